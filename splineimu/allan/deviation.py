"""Overlapping Allan deviation with a 95 % interval per point (the curve; the fit is in :mod:`.fit`).

:func:`allan_deviation` computes the overlapping Allan deviation (OADEV) of one or more rate
signals, exactly as ``allantools.oadev(y, rate=rate_hz, data_type="freq", taus=...)`` defines
it, with a 95 % confidence interval per point. :func:`fit_noise_parameters` reads the IMU noise
terms off the curve in Kalibr's continuous units.

Definitions
-----------
For samples ``y_i`` (i = 0..N-1) at rate ``1/tau0``, the "phase" is the integral
``x_0 = 0``, ``x_{i+1} = tau0 * sum_{j<=i} (y_j - mean(y))``; for an averaging factor ``m``
(cluster time ``tau = m tau0``)::

    sigma^2(tau) = 1 / (2 tau^2 (N + 1 - 2m)) * sum_{i=0}^{N-2m} (x_{i+2m} - 2 x_{i+m} + x_i)^2

using all ``N + 1 - 2m`` overlapping second differences (:attr:`AllanResult.n_clusters`).
Each tau costs one O(N) pass over the cumulative sum; the kernel
(:func:`splineimu._kernels.allan.oadev_sums`) fuses the pass and runs over (tau, axis) pairs
in parallel threads.

Noise model of an IMU axis (IEEE Std 952-1997, annex C)::

    sigma^2(tau) = N^2 / tau  +  (2 ln 2 / pi) B^2  +  K^2 tau / 3

- ``N`` white noise density (angle / velocity random walk) [unit / s / sqrt(Hz)]: the
  -1/2 slope line, read at tau = 1 s;
- ``K`` rate random walk (bias random walk) [unit / s^2 / sqrt(Hz)]: the +1/2 slope line,
  read at tau = 3 s;
- ``B`` bias instability [unit / s]: the flat floor ``sqrt(2 ln 2 / pi) B = 0.664 B``.

Confidence intervals
--------------------
The 95 % interval of one point is the chi-square interval of the Allan variance with the
equivalent degrees of freedom (EDF) of the overlapping estimator from the simple
approximations of NIST SP 1065 (W. Riley, "Handbook of Frequency Stability Analysis", 2008),
table 5 (after Howe, Allan and Barnes 1981), for the power-law noise that dominates at that
tau::

    white FM (alpha = 0):   edf = (3 (M - 1) / (2m) - 2 (M - 2) / M) * 4 m^2 / (4 m^2 + 5)
    flicker FM (alpha = -1): edf = 2 (M - 2) / (2.3 M - 4.9)  (m = 1),  5 M^2 / (4 m (M + 3m))
    random-walk FM (alpha = -2):
                            edf = (M - 2) / m * ((M - 1)^2 - 3 m (M - 1) + 4 m^2) / (M - 3)^2
    white PM (alpha = 2):    edf = (M + 1) (M - 2m) / (2 (M - m))

with ``M = N + 1`` phase points. "FM" is in the frequency-stability sense: a gyro's white rate
noise is white FM, its bias random walk is random-walk FM, and quantization is white PM.
:func:`allan_deviation` picks the type from the local log-log slope of the curve;
:func:`fit_noise_parameters` from the fitted model.

References
----------
IEEE Std 952-1997, "IEEE Standard Specification Format Guide and Test Procedure for
Single-Axis Interferometric Fiber Optic Gyros", annex C.
W. J. Riley, "Handbook of Frequency Stability Analysis", NIST SP 1065, 2008.
N. El-Sheimy, H. Hou, X. Niu, "Analysis and Modeling of Inertial Sensors Using Allan
Variance", IEEE TIM 57(1), 2008.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from .._kernels import allan as _k
from ..errors import InputError

__all__ = [
    "AllanResult", "allan_deviation", "default_cluster_factors", "edf_oadev", "FLICKER_FLOOR",
    "WHITE_PM", "WHITE_FM", "FLICKER_FM", "RANDOM_WALK_FM",
]

#: Height of the flicker (bias-instability) floor in units of B: sqrt(2 ln 2 / pi) = 0.6643.
FLICKER_FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)

#: Below this many second differences in total, one thread is used (starting threads costs
#: more than it saves; benchmarks/bench_allan.py).
PARALLEL_MIN_WORK = 5e6

#: Power-law exponents alpha (PSD of the rate ~ f^alpha) by name.
WHITE_PM, WHITE_FM, FLICKER_FM, RANDOM_WALK_FM = 2, 0, -1, -2


# ------------------------------------------------------------------------------ helpers


def default_cluster_factors(n_samples: int, points_per_decade: float = 10.0,
                            max_fraction: float = 0.25) -> np.ndarray:
    """Log-spaced integer averaging factors ``m`` from 1 to ``max_fraction * n_samples``.

    Parameters
    ----------
    n_samples : int
        Number of rate samples N.
    points_per_decade : float
        Density of the log spacing before rounding to integers (duplicates are removed, so
        the first decade has fewer points).
    max_fraction : float
        Largest ``m`` as a fraction of N (0.25: the longest cluster time is a quarter of the
        record, the "stop ratio" 4 that Stable32 uses for OADEV).

    Returns
    -------
    m : (T,) int64, strictly increasing.

    Examples
    --------
    >>> default_cluster_factors(1000, 5)[:6].tolist()
    [1, 2, 3, 4, 6, 10]
    """
    from ..validation import positive_float

    positive_float(points_per_decade, "points_per_decade")
    m_max = max(1, int(n_samples * max_fraction))
    m_max = min(m_max, max(1, (n_samples - 1) // 2))
    if m_max == 1:
        return np.array([1], dtype=np.int64)
    decades = math.log10(m_max)
    num = max(2, int(math.ceil(min(points_per_decade * decades, 1e9))) + 1)
    # from 2 m_max ln(m_max) points on, neighbours are < 1 apart even at the top: every integer
    # 1..m_max is taken, and a denser grid (e.g. 1e9 per decade) only costs memory
    num = min(num, int(math.ceil(2.0 * m_max * math.log(m_max))) + 2)
    m = np.unique(np.round(np.logspace(0.0, decades, num)).astype(np.int64))
    return m[(m >= 1) & (m <= m_max)]


def edf_oadev(n_phase, m, alpha):
    """Equivalent degrees of freedom of the overlapping Allan variance (NIST SP 1065 table 5).

    Parameters
    ----------
    n_phase : int
        Number of phase points M (rate samples + 1).
    m : array_like of int
        Averaging factors.
    alpha : array_like of int
        Power-law exponent per point: 2 (white PM), 1 (flicker PM), 0 (white FM),
        -1 (flicker FM), -2 (random-walk FM). Broadcast against ``m``.

    Returns
    -------
    edf : ndarray of float, at least 1e-3 (the approximations can reach 0 at the largest m).

    Examples
    --------
    >>> round(float(edf_oadev(1001, 10, 0)), 3)
    146.177
    """
    M = float(n_phase)
    m_arr = np.asarray(m, dtype=np.float64)
    a = np.asarray(alpha)
    if not np.isin(a, (2, 1, 0, -1, -2)).all():
        raise ValueError(f"`alpha` must be one of 2, 1, 0, -1, -2, got {np.unique(a).tolist()}")
    m_b, a_b = np.broadcast_arrays(m_arr, a)
    out = np.empty(m_b.shape, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        wpm = (M + 1.0) * (M - 2.0 * m_b) / (2.0 * (M - m_b))
        fpm = np.exp(np.sqrt(np.abs(np.log((M - 1.0) / (2.0 * m_b))
                                    * np.log((2.0 * m_b + 1.0) * (M - 1.0) / 4.0))))
        wfm = (3.0 * (M - 1.0) / (2.0 * m_b) - 2.0 * (M - 2.0) / M) * (4.0 * m_b**2 / (4.0 * m_b**2 + 5.0))
        ffm = np.where(m_b == 1, 2.0 * (M - 2.0) / (2.3 * M - 4.9),
                       5.0 * M**2 / (4.0 * m_b * (M + 3.0 * m_b)))
        rfm = (M - 2.0) / (m_b * (M - 3.0) ** 2) * ((M - 1.0) ** 2 - 3.0 * m_b * (M - 1.0) + 4.0 * m_b**2)
    out[...] = np.select([a_b == 2, a_b == 1, a_b == 0, a_b == -1, a_b == -2], [wpm, fpm, wfm, ffm, rfm],
                         default=np.nan)
    return np.maximum(out, 1e-3)


def _chi2_ppf(q, nu):
    """Quantile ``q`` of chi2(nu) (``scipy.stats.chi2.ppf``; through ``scipy.special``, whose
    import costs a third of ``scipy.stats``'s: 0.17 s against 0.56 s, measured)."""
    from scipy.special import chdtri

    return chdtri(nu, 1.0 - q)


def _chi2_interval_factors(edf):
    """Return ``(lo, hi)`` with ``var * lo <= true var <= var * hi`` at 95 % for chi2(edf)."""
    edf = np.asarray(edf, dtype=np.float64)
    return edf / _chi2_ppf(0.975, edf), edf / _chi2_ppf(0.025, edf)


def _alpha_from_slope(slope):
    """Map a local log-log ADEV slope to the nearest identifiable power-law alpha."""
    return np.select([slope < -0.75, slope < -0.25, slope < 0.25], [WHITE_PM, WHITE_FM, FLICKER_FM],
                     default=RANDOM_WALK_FM)


def _local_slopes(taus, adev, half_width_decades=0.5):
    """Least-squares slope of log10 adev vs log10 tau within +-half_width around each point."""
    lt = np.log10(taus)
    la = np.log10(np.maximum(adev, 1e-300))
    T, K = adev.shape
    out = np.zeros((T, K))
    for j in range(T):
        sel = np.abs(lt - lt[j]) <= half_width_decades + 1e-12
        if sel.sum() < 3:
            # widen to the three nearest points
            sel = np.zeros(T, dtype=bool)
            sel[np.argsort(np.abs(lt - lt[j]))[: min(3, T)]] = True
        x = lt[sel] - lt[sel].mean()
        den = float(x @ x)
        if den == 0.0:
            continue
        out[j] = x @ (la[sel] - la[sel].mean(axis=0)) / den
    return out


# ------------------------------------------------------------------------------ results


@dataclass
class AllanResult:
    """Overlapping Allan deviation of K signals at T cluster times.

    Attributes
    ----------
    taus_s : (T,) float64
        Cluster times ``m / rate_hz`` [s].
    m : (T,) int64
        Averaging factors.
    adev : (T, K) float64
        Overlapping Allan deviation, in the unit of the data.
    n_clusters : (T,) int64
        Number of overlapping second differences per tau, ``N + 1 - 2m`` (allantools' ``ns``).
    edf : (T, K) float64
        Equivalent degrees of freedom used for the interval.
    noise_alpha : (T, K) int64
        Power-law exponent assumed for the EDF (from the local slope; see module notes).
    adev_ci95 : (T, K, 2) float64
        95 % chi-square interval ``[low, high]`` of each point.
    rate_hz : float
    n_samples : int
    labels : list of str
        One name per column (``"x"``, ``"gyro_x"``, ...).
    """

    taus_s: np.ndarray
    m: np.ndarray
    adev: np.ndarray
    n_clusters: np.ndarray
    edf: np.ndarray
    noise_alpha: np.ndarray
    adev_ci95: np.ndarray
    rate_hz: float
    n_samples: int
    labels: list = field(default_factory=list)

    @property
    def duration_s(self) -> float:
        """Length of the record, ``n_samples / rate_hz`` [s]."""
        return self.n_samples / self.rate_hz

    def to_dataframe(self):
        """Long-format :class:`pandas.DataFrame`: one row per (tau, axis)."""
        import pandas as pd

        T, K = self.adev.shape
        return pd.DataFrame({
            "tau_s": np.repeat(self.taus_s, K),
            "axis": np.tile(np.asarray(self.labels, dtype=object), T),
            "adev": self.adev.ravel(),
            "adev_ci95_low": self.adev_ci95[:, :, 0].ravel(),
            "adev_ci95_high": self.adev_ci95[:, :, 1].ravel(),
            "edf": self.edf.ravel(),
            "n_clusters": np.repeat(self.n_clusters, K),
        })


# ------------------------------------------------------------------------------ OADEV


def _cluster_factors_from_taus(taus, rate_hz, n):
    t = np.asarray(taus, dtype=np.float64).ravel()
    if t.size == 0 or not np.all(np.isfinite(t)):
        raise InputError(f"`taus` must be a non-empty array of finite cluster times, got {taus!r}")
    m = np.round(t * rate_hz)
    # allantools keeps 0 < m < len(phase) and then drops points with a single difference
    m = m[(m > 0) & (m < n + 1)]
    m = np.unique(m).astype(np.int64)
    m = m[(n + 1 - 2 * m) > 1]
    if m.size == 0:
        raise InputError(f"no valid cluster time in `taus` for {n} samples at {rate_hz} Hz")
    return m


def allan_deviation(data, rate_hz: float, taus=None, *, points_per_decade: float = 10.0,
                    labels=None, threads: int | None = None) -> AllanResult:
    """Overlapping Allan deviation of one or more evenly sampled signals.

    Parameters
    ----------
    data : (N,) or (N, K) array_like
        Rate samples (gyro [rad/s], accelerometer [m/s^2], ...), one column per axis.
    rate_hz : float
        Sample rate [Hz]; ``tau0 = 1 / rate_hz``.
    taus : array_like, optional
        Cluster times [s]. Rounded to integer multiples ``m`` of ``tau0``; duplicates and
        values with fewer than two differences are dropped, exactly as allantools does.
        Default: :func:`default_cluster_factors` (log-spaced from ``tau0`` to a quarter of the
        record).
    points_per_decade : float
        Density of the default cluster times.
    labels : list of str, optional
        Column names (default ``"0", "1", ...``).
    threads : int, optional
        Threads for long records (default: the number of CPUs, at most 8).

    Returns
    -------
    AllanResult

    Raises
    ------
    InputError
        Data not finite, fewer than 3 samples, bad rate or taus.

    Notes
    -----
    Equal to ``allantools.oadev(data[:, k], rate=rate_hz, data_type="freq", taus=taus)`` to
    rounding (the mean is removed before integration as allantools does, and the integration
    is the same sequential cumulative sum); about 3x faster on one thread and 5x on two for
    six axes of 2e6 samples (``benchmarks/bench_allan.py``).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> r = allan_deviation(rng.standard_normal(100_000), 100.0, taus=[0.01, 1.0])
    >>> r.taus_s.tolist(), np.round(r.adev[:, 0] * np.sqrt(r.taus_s * 100.0), 1).tolist()
    ([0.01, 1.0], [1.0, 1.0])
    """
    rate_hz = float(rate_hz)
    if not (math.isfinite(rate_hz) and rate_hz > 0.0):
        raise InputError(f"`rate_hz` must be a positive number, got {rate_hz!r}")
    y = np.asarray(data, dtype=np.float64)
    if y.ndim == 1:
        y = y[:, None]
    if y.ndim != 2:
        raise InputError(f"Expected `data` to have shape (N,) or (N, K), got {np.shape(data)}")
    n, K = y.shape
    if n < 3 or K < 1:
        raise InputError(f"Expected `data` to have at least 3 samples and 1 column, got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise InputError("`data` contains NaN or infinite values")
    if labels is None:
        labels = [str(k) for k in range(K)]
    labels = [str(s) for s in labels]
    if len(labels) != K:
        raise InputError(f"Expected {K} `labels`, got {len(labels)}")

    if taus is None:
        m = default_cluster_factors(n, points_per_decade)
    else:
        m = _cluster_factors_from_taus(taus, rate_hz, n)

    y = np.ascontiguousarray(y)
    phase = np.empty((K, n + 1))
    _k.freq_to_phase_into(y, np.ascontiguousarray(y.mean(axis=0)), 1.0 / rate_hz, phase)
    sums = np.empty((m.size, K))
    work = float(np.sum(n + 1 - 2 * m)) * K
    if threads is None:
        threads = os.cpu_count() or 1
    threads = max(1, min(int(threads), 8, K * m.size)) if work >= PARALLEL_MIN_WORK else 1
    if threads > 1:
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=threads) as pool:
            for f in [pool.submit(_k.oadev_sums, phase, m, sums, i, threads) for i in range(threads)]:
                f.result()
    else:
        _k.oadev_sums(phase, m, sums, 0, 1)
    del phase
    n_clusters = (n + 1 - 2 * m).astype(np.int64)
    adev = np.sqrt(sums / (2.0 * n_clusters[:, None])) / m[:, None] * rate_hz
    taus_s = m / rate_hz

    alpha = _alpha_from_slope(_local_slopes(taus_s, adev)) if m.size > 1 else np.zeros((1, K), np.int64)
    edf = edf_oadev(n + 1, m[:, None], alpha)
    lo, hi = _chi2_interval_factors(edf)
    ci = np.stack([adev * np.sqrt(lo), adev * np.sqrt(hi)], axis=-1)
    return AllanResult(taus_s=taus_s, m=m, adev=adev, n_clusters=n_clusters, edf=edf,
                       noise_alpha=alpha.astype(np.int64), adev_ci95=ci, rate_hz=rate_hz,
                       n_samples=n, labels=labels)
