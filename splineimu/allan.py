"""Overlapping Allan deviation of IMU data and identification of its noise parameters.

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

from ._kernels import allan as _k
from .errors import InputError

__all__ = [
    "AllanResult", "NoiseFit", "allan_deviation", "fit_noise_parameters", "default_cluster_factors",
    "edf_oadev", "FLICKER_FLOOR", "imu_noise_dict", "plot_allan",
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
    m_max = max(1, int(n_samples * max_fraction))
    m_max = min(m_max, max(1, (n_samples - 1) // 2))
    if m_max == 1:
        return np.array([1], dtype=np.int64)
    decades = math.log10(m_max)
    num = max(2, int(math.ceil(points_per_decade * decades)) + 1)
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


def _nnls(A, b):
    """Non-negative least squares ``min |A x - b|, x >= 0`` for a few columns, exactly: the
    optimum is the unconstrained solution on its support, so every support is tried (2^3
    for the noise model) and the best feasible one kept. (``scipy.optimize.nnls`` gives the
    same; importing ``scipy.optimize`` costs 0.34 s, measured.)"""
    n = A.shape[1]
    best_x = np.zeros(n)
    best_r = float(b @ b)
    live = [j for j in range(n) if np.any(A[:, j] != 0.0)]
    for mask in range(1, 1 << len(live)):
        cols = [live[i] for i in range(len(live)) if mask >> i & 1]
        xs = np.linalg.lstsq(A[:, cols], b, rcond=None)[0]
        if np.any(xs < 0.0):
            continue
        r = b - A[:, cols] @ xs
        rr = float(r @ r)
        if rr < best_r:
            best_r = rr
            best_x = np.zeros(n)
            best_x[cols] = xs
    return best_x


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


@dataclass
class NoiseFit:
    """Noise parameters per axis read off an Allan-deviation curve (K axes).

    Units follow the data: for a gyro in rad/s, ``white_noise_density`` is rad/s/sqrt(Hz)
    (Kalibr's ``gyroscope_noise_density``), ``random_walk`` rad/s^2/sqrt(Hz)
    (``gyroscope_random_walk``) and ``bias_instability`` rad/s.

    Attributes
    ----------
    white_noise_density, random_walk, bias_instability : (K,) float64
        N (the -1/2 line at tau = 1 s), K (the +1/2 line at tau = 3 s), B (floor / 0.664).
    white_noise_density_ci95, random_walk_ci95, bias_instability_ci95 : (K, 2) float64
        95 % intervals ``[low, high]`` (``high`` may be ``inf``: not bounded by the data).
    random_walk_resolved : (K,) bool
        False when the random walk is not significant (its 95 % interval includes 0, or the
        +1/2 slope never dominates the curve): ``random_walk`` is then the 95 % upper bound
        and its interval ``[0, bound]``.
    bias_instability_resolved : (K,) bool
        False when the curve's minimum is explained by the white and random-walk terms alone
        (no flat region): ``bias_instability`` is then only an upper bound on B.
    bias_instability_tau_s : (K,) float64
        Cluster time of the minimum.
    white_fit_tau_range_s, random_walk_fit_tau_range_s : (K, 2) float64
        Cluster times used for each line (``nan`` when unresolved).
    model_coefficients : (K, 3) float64
        ``(N^2, c, K^2)`` of the weighted least-squares model ``N^2/tau + c + K^2 tau/3`` used to
        decide which term dominates where (``c`` = flat floor's variance).
    labels : list of str
    """

    white_noise_density: np.ndarray
    white_noise_density_ci95: np.ndarray
    random_walk: np.ndarray
    random_walk_ci95: np.ndarray
    random_walk_resolved: np.ndarray
    bias_instability: np.ndarray
    bias_instability_ci95: np.ndarray
    bias_instability_resolved: np.ndarray
    bias_instability_tau_s: np.ndarray
    white_fit_tau_range_s: np.ndarray
    random_walk_fit_tau_range_s: np.ndarray
    model_coefficients: np.ndarray
    labels: list = field(default_factory=list)

    def white_line(self, taus_s) -> np.ndarray:
        """The fitted -1/2 slope lines ``N / sqrt(tau)``, (T, K)."""
        t = np.asarray(taus_s, dtype=np.float64)[:, None]
        return self.white_noise_density[None, :] / np.sqrt(t)

    def random_walk_line(self, taus_s) -> np.ndarray:
        """The fitted +1/2 slope lines ``K sqrt(tau / 3)``, (T, K)."""
        t = np.asarray(taus_s, dtype=np.float64)[:, None]
        return self.random_walk[None, :] * np.sqrt(t / 3.0)

    def model_adev(self, taus_s) -> np.ndarray:
        """The least-squares model ``sqrt(N^2/tau + c + K^2 tau/3)``, (T, K)."""
        t = np.asarray(taus_s, dtype=np.float64)[:, None]
        c = self.model_coefficients
        return np.sqrt(c[None, :, 0] / t + c[None, :, 1] + c[None, :, 2] * t / 3.0)


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


# ------------------------------------------------------------------------------ fit


def _wls_model(taus, s2, edf_of_alpha, flat=True, n_iter=12):
    """Non-negative weighted least squares of ``s2 ~ a/tau + c + b tau/3`` (``c = 0`` unless
    ``flat``).

    The weight of a point is ``edf / (2 model^2)`` (the variance of a chi-square estimate),
    recomputed from the current model, with the EDF of the term that dominates there.
    """
    A = np.column_stack([1.0 / taus, np.ones_like(taus) if flat else np.zeros_like(taus), taus / 3.0])
    model = s2.copy()
    x = np.zeros(3)
    for _ in range(n_iter):
        terms = A * x[None, :] if np.any(x > 0) else None
        if terms is None:
            alpha = np.full(taus.shape, WHITE_FM)
        else:
            alpha = np.array([WHITE_FM, FLICKER_FM, RANDOM_WALK_FM])[np.argmax(terms, axis=1)]
        nu = edf_of_alpha(alpha)
        w = np.sqrt(nu / 2.0) / np.maximum(model, 1e-300)
        Aw = A * w[:, None]
        scale = np.linalg.norm(Aw, axis=0)
        scale[scale == 0] = 1.0
        xs = _nnls(Aw / scale, s2 * w)
        x_new = xs / scale
        new_model = A @ x_new
        if np.all(new_model > 0):
            converged = np.allclose(x_new, x, rtol=1e-9, atol=0.0)
            x, model = x_new, new_model
            if converged:
                break
        else:
            x = x_new
            break
    return x, A


def _combine(s2, other, g, nu, frac):
    """Combine per-point estimates of one coefficient ``p`` of the model ``s2 = other + p g``.

    Point j gives ``p_j = (s2_j - other_j) / g_j`` (the other model terms subtracted); its
    relative standard deviation is ``r_j = sqrt(2 / nu_j) / frac_j`` (``frac_j``: share of
    the point's variance due to this term), and the points are averaged with weights
    ``1 / r_j^2``. Overlapping Allan estimates at neighbouring taus are strongly correlated,
    so the interval assumes them fully (rank-)correlated: each point's exact chi-square
    interval of the total variance, ``[s2 nu / chi2_0.975(nu), s2 nu / chi2_0.025(nu)]``, is
    mapped to ``p`` and the bounds are averaged with the same weights. For one point this is
    the exact interval; for several it is conservative. Returns ``(estimate, low, high)``.
    """
    r = np.sqrt(2.0 / nu) / np.maximum(frac, 1e-12)
    w = 1.0 / r**2
    w /= w.sum()
    est = float(w @ ((s2 - other) / g))
    lo = float(w @ ((s2 * nu / _chi2_ppf(0.975, nu) - other) / g))
    hi = float(w @ ((s2 * nu / _chi2_ppf(0.025, nu) - other) / g))
    return max(est, 0.0), max(lo, 0.0), max(hi, 0.0)


def fit_noise_parameters(result: AllanResult, *, min_white_tau_s: float | None = None,
                         white_fraction: float = 0.9, random_walk_fraction: float = 0.5,
                         flat_fraction: float = 0.5, max_bias_tau_fraction: float = 0.1) -> NoiseFit:
    """Read white-noise density N, random walk K and bias instability B off each axis.

    Parameters
    ----------
    result : AllanResult
        From :func:`allan_deviation` (the default cluster times suit this fit).
    min_white_tau_s : float, optional
        Shortest cluster time for the white-noise line (default ``10 / rate``: the first few
        samples are shaped by the sensor's internal filters and by quantization).
    white_fraction : float
        The -1/2 line is fitted where the white term explains at least this share of the
        model variance.
    random_walk_fraction : float
        The +1/2 line is fitted where the random-walk term explains at least this share.
    flat_fraction : float
        The model keeps its flat (bias-instability) term only if that term explains at least
        this share of the variance at some tau with 10 or more degrees of freedom; otherwise
        it is refitted without it.
    max_bias_tau_fraction : float
        The minimum for B is searched up to this fraction of the record (at least 10
        independent clusters).

    Returns
    -------
    NoiseFit

    Notes
    -----
    1. A non-negative weighted least-squares fit of ``sigma^2 = N^2/tau + c + K^2 tau/3`` to
       all points (weights: inverse chi-square variance of each point from its EDF,
       iterated on the model) decides which term dominates at each tau. The flat term is
       dropped (refit with ``c = 0``) when it never reaches ``flat_fraction`` of the variance
       where the curve is known to 10 degrees of freedom or better.
    2. **N**: on the points where white noise dominates, the other two model terms are
       subtracted and ``N^2 = tau sigma^2`` (the -1/2 line, equal to N at tau = 1 s) is
       averaged with inverse-variance weights.
    3. **K**: likewise ``K^2 = 3 sigma^2 / tau`` (the +1/2 line, equal to K at tau = 3 s) on
       the points where the random walk dominates. If its interval includes 0 the walk is
       "not resolved" and K is reported as the interval's upper end.
    4. **B**: the minimum of the curve up to ``max_bias_tau_fraction`` of the record,
       divided by 0.664, with the chi-square interval of that point (flicker-FM EDF). The
       selection of a minimum biases it slightly low.

    Intervals: each point's chi-square interval of the total variance (EDF of the dominant
    noise type) is mapped to the coefficient with the other terms subtracted, and the bounds
    are averaged with the estimate's weights, i.e. the points of a line are assumed fully
    correlated (see ``_combine``): exact for one point, conservative for several. They hold
    only for the model above (no drift, no temperature trend, no flicker component other
    than a flat floor) and ignore the small uncertainty of the subtracted terms.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> y = 0.01 * np.sqrt(100.0) * rng.standard_normal(200_000)  # N = 0.01 at 100 Hz
    >>> f = fit_noise_parameters(allan_deviation(y, 100.0))
    >>> bool(abs(f.white_noise_density[0] / 0.01 - 1) < 0.02)
    True
    """
    taus = result.taus_s
    T, K = result.adev.shape
    n_phase = result.n_samples + 1
    rate = result.rate_hz
    if min_white_tau_s is None:
        min_white_tau_s = 10.0 / rate
    def edf_of_alpha(alpha):
        return edf_oadev(n_phase, result.m, alpha)

    nan2 = np.full((K, 2), np.nan)
    nu_white = edf_of_alpha(WHITE_FM)
    nu_rw = edf_of_alpha(RANDOM_WALK_FM)
    nu_ff = edf_of_alpha(FLICKER_FM)
    out = {
        "white_noise_density": np.zeros(K), "white_noise_density_ci95": np.zeros((K, 2)),
        "random_walk": np.zeros(K), "random_walk_ci95": np.zeros((K, 2)),
        "random_walk_resolved": np.zeros(K, dtype=bool),
        "bias_instability": np.zeros(K), "bias_instability_ci95": np.zeros((K, 2)),
        "bias_instability_resolved": np.zeros(K, dtype=bool), "bias_instability_tau_s": np.zeros(K),
        "white_fit_tau_range_s": nan2.copy(), "random_walk_fit_tau_range_s": nan2.copy(),
        "model_coefficients": np.zeros((K, 3)),
    }
    for k in range(K):
        s2 = result.adev[:, k] ** 2
        if not np.any(s2 > 0):  # a constant signal: every term is zero
            out["bias_instability_tau_s"][k] = taus[0]
            continue
        x, A = _wls_model(taus, s2, edf_of_alpha)
        terms = A * x[None, :]
        model = np.maximum(terms.sum(axis=1), 1e-300)
        frac = terms / model[:, None]
        informative = nu_ff >= 10.0  # a floor seen only in the last few clusters is noise
        if not informative.any() or frac[informative, 1].max() < flat_fraction:
            # no visible floor: a small constant soaked up by the fit would only bias the
            # white and random-walk coefficients that it is subtracted from
            x, A = _wls_model(taus, s2, edf_of_alpha, flat=False)
            terms = A * x[None, :]
            model = np.maximum(terms.sum(axis=1), 1e-300)
            frac = terms / model[:, None]
        out["model_coefficients"][k] = x

        # --- white noise: -1/2 line
        sel = (frac[:, 0] >= white_fraction) & (taus >= min_white_tau_s - 1e-12)
        if not sel.any():
            sel = frac[:, 0] >= 0.5
        if not sel.any():
            sel = np.zeros(T, dtype=bool)
            sel[0] = True
        est, lo, hi = _combine(s2[sel], terms[sel, 1] + terms[sel, 2], 1.0 / taus[sel], nu_white[sel],
                               frac[sel, 0])
        out["white_noise_density"][k] = math.sqrt(est)
        out["white_noise_density_ci95"][k] = (math.sqrt(lo), math.sqrt(hi))
        out["white_fit_tau_range_s"][k] = (taus[sel].min(), taus[sel].max())

        # --- random walk: +1/2 line
        sel = frac[:, 2] >= random_walk_fraction
        est = lo = hi = 0.0
        if sel.any():
            est, lo, hi = _combine(s2[sel], terms[sel, 0] + terms[sel, 1], taus[sel] / 3.0, nu_rw[sel],
                                   frac[sel, 2])
            out["random_walk_fit_tau_range_s"][k] = (taus[sel].min(), taus[sel].max())
        if lo > 0.0:
            out["random_walk"][k] = math.sqrt(est)
            out["random_walk_ci95"][k] = (math.sqrt(lo), math.sqrt(hi))
            out["random_walk_resolved"][k] = True
        else:
            # not significant: report the 95 % upper bound. Without a +1/2 region, attribute
            # all of a point's variance to the random walk, at the point (chosen on the model)
            # where that bound is tightest.
            if not sel.any():
                q_lo = _chi2_ppf(0.025, nu_rw)
                j = int(np.argmin(3.0 * model * nu_rw / (q_lo * taus)))
                hi = 3.0 * s2[j] * nu_rw[j] / (q_lo[j] * taus[j])
            out["random_walk"][k] = math.sqrt(hi)
            out["random_walk_ci95"][k] = (0.0, math.sqrt(hi))

        # --- bias instability: minimum of the curve
        cand = np.flatnonzero(taus <= max_bias_tau_fraction * result.duration_s + 1e-12)
        if cand.size == 0:
            cand = np.arange(T)
        j = int(cand[np.argmin(result.adev[cand, k])])
        lo_f, hi_f = _chi2_interval_factors(nu_ff[j])
        a = result.adev[j, k]
        out["bias_instability"][k] = a / FLICKER_FLOOR
        out["bias_instability_ci95"][k] = (a * math.sqrt(lo_f) / FLICKER_FLOOR,
                                           a * math.sqrt(hi_f) / FLICKER_FLOOR)
        out["bias_instability_tau_s"][k] = taus[j]
        out["bias_instability_resolved"][k] = bool(frac[j, 1] >= 0.5)
    return NoiseFit(labels=list(result.labels), **out)


# ------------------------------------------------------------------------------ output

_SENSOR_UNITS = {
    "gyroscope": ("rad/s/sqrt(Hz)", "rad/s^2/sqrt(Hz)", "rad/s", "rad/s"),
    "accelerometer": ("m/s^2/sqrt(Hz)", "m/s^3/sqrt(Hz)", "m/s^2", "m/s^2"),
}


def _r6(v) -> float:
    """Round to 6 significant digits (the estimates are not better than 1e-3 anyway)."""
    return float(f"{float(v):.6g}")


def _floats(a):
    return [_r6(v) for v in np.asarray(a, dtype=np.float64).ravel()]


def _pairs(a):
    return [[_r6(lo), _r6(hi)] for lo, hi in np.asarray(a, dtype=np.float64).reshape(-1, 2)]


def imu_noise_dict(result: AllanResult, fit: NoiseFit, source: str = "") -> dict:
    """Kalibr-keyed mapping of a six-axis fit (gyro x y z, accel x y z), as ``allan.yaml`` holds it.

    Each Kalibr key holds the three per-axis values, ``<key>_avg`` their mean and
    ``<key>_ci95`` one ``[low, high]`` pair per axis; ``update_rate`` is the data's rate. The
    ``allan`` section (bias instability, resolution flags, record length) is informational:
    :class:`splineimu.imu.config.ImuConfig` reads the file and ignores it.

    Raises
    ------
    InputError
        If the fit does not have six axes.
    """
    if fit.white_noise_density.shape != (6,):
        raise InputError("expected a six-axis fit (gyro xyz, accel xyz), "
                         f"got {fit.white_noise_density.shape[0]} axes")
    d: dict = {}
    sl = {"gyroscope": slice(0, 3), "accelerometer": slice(3, 6)}
    for sensor in ("gyroscope", "accelerometer"):
        for key, val, ci in (("noise_density", fit.white_noise_density, fit.white_noise_density_ci95),
                             ("random_walk", fit.random_walk, fit.random_walk_ci95)):
            v = val[sl[sensor]]
            d[f"{sensor}_{key}"] = _floats(v)
            d[f"{sensor}_{key}_avg"] = _r6(np.mean(v))
            d[f"{sensor}_{key}_ci95"] = _pairs(ci[sl[sensor]])
    d["update_rate"] = float(result.rate_hz)
    info: dict = {
        "source": str(source),
        "n_samples": int(result.n_samples),
        "duration_s": float(result.duration_s),
        "cluster_times": int(result.taus_s.size),
        "method": "overlapping Allan deviation; N on the -1/2 line at 1 s, K on the +1/2 line at 3 s, "
                  "B = curve minimum / 0.664; 95% chi-square intervals (NIST SP 1065 EDF)",
    }
    for sensor in ("gyroscope", "accelerometer"):
        s = sl[sensor]
        info[f"{sensor}_random_walk_resolved"] = [bool(v) for v in fit.random_walk_resolved[s]]
        info[f"{sensor}_bias_instability"] = _floats(fit.bias_instability[s])
        info[f"{sensor}_bias_instability_ci95"] = _pairs(fit.bias_instability_ci95[s])
        info[f"{sensor}_bias_instability_tau_s"] = _floats(fit.bias_instability_tau_s[s])
        info[f"{sensor}_bias_instability_resolved"] = [bool(v) for v in fit.bias_instability_resolved[s]]
    d["allan"] = info
    return d


def plot_allan(result: AllanResult, fit: NoiseFit | None, path, title: str = "") -> None:
    """Log-log plot of the curves with their 95 % bands and the fitted lines, saved atomically.

    Six columns are drawn as two panels (gyro, accelerometer); other counts in one panel.
    Uses matplotlib's Agg backend (imported here).
    """
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    K = result.adev.shape[1]
    groups = [(range(0, 3), "gyroscope", "rad/s"), (range(3, 6), "accelerometer", "m/s$^2$")] if K == 6 \
        else [(range(K), "", "")]
    fig, axes = plt.subplots(1, len(groups), figsize=(6.4 * len(groups), 5.0), squeeze=False)
    colors = ["tab:red", "tab:green", "tab:blue"]
    taus = result.taus_s
    for ax, (cols, name, unit) in zip(axes[0], groups):
        for i, k in enumerate(cols):
            c = colors[i % 3] if K == 6 else f"C{i}"
            lab = result.labels[k] if result.labels else str(k)
            ax.fill_between(taus, result.adev_ci95[:, k, 0], result.adev_ci95[:, k, 1], color=c,
                            alpha=0.18, lw=0)
            ax.loglog(taus, result.adev[:, k], color=c, lw=1.6, label=lab)
            if fit is None:
                continue
            ax.loglog(taus, fit.white_line(taus)[:, k], color=c, lw=0.9, ls="--")
            ax.loglog(taus, fit.random_walk_line(taus)[:, k], color=c, lw=0.9, ls="-.")
            tb = fit.bias_instability_tau_s[k]
            ax.loglog([tb / 10.0, tb * 10.0], [FLICKER_FLOOR * fit.bias_instability[k]] * 2, color=c,
                      lw=0.9, ls=":")
            ax.plot([1.0], [fit.white_noise_density[k]], "o", color=c, ms=5)
            ax.plot([3.0], [fit.random_walk[k]], "s", color=c, ms=5,
                    mfc=c if fit.random_walk_resolved[k] else "white")
        lo = np.nanmin(result.adev_ci95[:, list(cols), 0])
        if fit is not None:
            marks = np.r_[fit.white_noise_density[list(cols)], fit.random_walk[list(cols)]]
            marks = marks[marks > 0]
            if marks.size:
                lo = min(lo, marks.min())
        hi = np.nanmax(result.adev_ci95[:, list(cols), 1][np.isfinite(result.adev_ci95[:, list(cols), 1])])
        ax.set_ylim(lo / 2.0, hi * 2.0)
        ax.set_xlim(taus[0] / 1.3, taus[-1] * 1.3)
        ax.grid(True, which="major", alpha=0.5)
        ax.grid(True, which="minor", alpha=0.15)
        ax.set_xlabel(r"cluster time $\tau$ [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]" if unit else "Allan deviation")
        if name:
            ax.set_title(name)
        handles, labels = ax.get_legend_handles_labels()
        if fit is not None:
            from matplotlib.lines import Line2D

            handles += [Line2D([], [], color="k", ls="--", lw=0.9),
                        Line2D([], [], color="k", ls="-.", lw=0.9),
                        Line2D([], [], color="k", ls=":", lw=0.8),
                        Line2D([], [], color="k", marker="o", ls=""),
                        Line2D([], [], color="k", marker="s", ls="")]
            labels += ["white noise $N/\\sqrt{\\tau}$", "random walk $K\\sqrt{\\tau/3}$",
                       "0.664 B (at the minimum)", "N (at 1 s)", "K (at 3 s; open: bound)"]
        ax.legend(handles, labels, fontsize=8, loc="best")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    import io

    from .io.output import atomic_write_bytes

    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=110)
    finally:
        plt.close(fig)
    atomic_write_bytes(Path(path), buf.getbuffer())
