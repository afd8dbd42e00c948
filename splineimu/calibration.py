r"""Six-position accelerometer and rate-table gyro calibration (bias, scale, misalignment).

The sensor model (:mod:`splineimu.imu.noise`, DESIGN.md section 3) is, for either sensor,

.. math::  y_m = K x + b + n,\qquad K = M S,

with the true quantity ``x`` (specific force or body rate), the 3x3 scale-misalignment matrix
``K`` (misalignment ``M`` after scale ``S = I + diag(s)``), the bias ``b`` and white noise ``n``:
twelve unknowns per sensor. A calibration recording holds *steady phases* (at rest, or at a
constant table rate) whose reference ``x`` is known up to the orientation of the sensor:

- six-position test (:func:`calibrate_accel`): at rest with each axis up and down,
  ``x = g u`` with ``u`` the gravity direction in the sensor, nominally ``+-e_i``;
- rate table (:func:`calibrate_gyro`): each axis along the (vertical) table axis, spun at
  ``+rate`` and ``-rate`` (and at rest), ``x = +-rate u``, ``u`` nominally ``e_i``.

Procedure
---------
1. **Segmentation** (:func:`find_steady_phases`), from the data alone. For every channel
   ``c`` (the three axes of the calibrated sensor and, when given, of the other one) the
   moving standard deviation ``s_c(k)`` over a centred window of ``window_s`` seconds is
   compared with the channel's noise level ``sigma_c``: the 25th percentile of ``s_c`` over
   the recording divided by its value for white noise, ``sqrt(chi2_{w-1}(0.25) / w)`` (a
   robust white-noise level as long as a good part of the recording is steady). A sample is
   steady when ``s_c(k) <= threshold * sigma_c + floor_c`` on every channel (default
   ``threshold = 1.5``; a window of pure white noise has ``s / sigma`` within a few percent
   of 1, so this flags a window once its signal changes by about one noise standard
   deviation), and the means of the window's two halves must agree within
   ``drift_threshold = 5`` standard deviations of their difference (a slow ramp in heavy
   noise shows there first). ``floor_c``, added to both limits, is ``1e-9 max(1, median
   |y_c|)`` or half the smallest step of quantized data, whichever is larger.
   Runs of steady samples are shrunk by ``margin_s`` (default: two windows, 1 s) at each end
   that borders motion (not at the ends of the recording), so that the slow start and end of
   a move, whose signal is still below the noise, stays out of the averages (with one window,
   consumer-grade noise of 0.015 rad/s/sqrt(Hz) let ramps bias some phase means by up to 0.6
   of their standard deviation; with two, by less than 0.01); runs shorter than
   ``min_dwell_s`` are dropped.
2. **Averaging**: each phase gives its mean ``y_p`` and, per axis, the variance of that mean,
   ``sigma_p^2 / n_p`` with ``sigma_p`` the sample standard deviation in the phase (or
   ``noise_density / sqrt(dt)`` when a white-noise density is given).
3. **Reference assignment** from the measured direction: the dominant axis ``i`` and sign of
   ``y_p`` give the nominal ``u_p = +-e_i`` (within ``max_axis_angle_deg``, default 25
   degrees, and a magnitude within [0.8, 1.25] of ``g`` or of a table rate; gyro phases
   below half the smallest rate are at rest, ``x = 0``). Phases that fit nothing are
   reported and left out.
4. **Least squares** for ``vec(K)`` and ``b``: ``y_p = a_p K u_p + b`` (``a_p = g`` or
   ``+-rate`` or 0), weighted by the inverse variances of step 2 (the rows of ``K`` and
   ``b`` decouple; the system must have rank 12, else the error lists the references
   found). The predicted covariance is the inverse of the weighted normal matrix (white
   noise only: bias drift during the recording and g-sensitivity of the gyro are not
   modelled). With the reference exact, this is the classical method (``method="nominal"``).

Orientation error
-----------------
If a position is tilted by a small angle ``theta`` (a vector perpendicular to the nominal
``u``, components of standard deviation ``sigma``), the true reference is
``a (u + theta x u)`` and the nominal method reads ``a K (theta x u)`` as part of ``K`` and
``b``:

- six-position: a tilt of the ``+-e_i`` positions moves the other two axes' readings by
  ``g theta``, so the misalignment entries ``K_ji`` (j != i) are off by
  ``(theta_up - theta_down) / 2`` (first order; RMS ``sigma / sqrt(2)`` = 0.025 for tilt
  components of ``sigma`` = 2 degrees), the biases by about ``g sigma / 3`` (0.11 m/s^2: the
  bias of axis ``j`` is the average over all six positions, four of which are tilted across
  ``j``), and the scale factors by ``-|theta|^2 / 2`` (second order: on average
  ``-sigma^2`` = -1.2e-3);
- rate table: a tilted mount spins the sensor about ``u_i = e_i + theta x e_i``, so column
  ``i`` of ``K`` absorbs ``K (theta x e_i)``: misalignment off by ``theta`` (RMS ``sigma``),
  scale by ``-|theta|^2 / 2``; the biases are unaffected (the +rate and -rate phases cancel).

The misalignment error is fundamental: a common rotation of all positions is
indistinguishable from a rotation of ``K`` (``K u = (K Q)(Q^T u)``), and six positions
with fully unknown orientations leave 12 + 12 unknowns for 18 equations, so the norm
constraint ``|K^-1 (y - b)| = g`` alone cannot identify the 12 parameters either (it gives 6
equations for 9 identifiable parameters; multi-position methods use 9 or more positions).
What *can* be done with six positions is to treat the tilts as random, ``theta ~ N(0,
tilt_sigma^2 I_2)`` per position (per mount on the rate table), and marginalize them
(``tilt_sigma_deg`` > 0, ``method="tilt"``): with ``u = Exp(theta) u0``,
``E[y_p] = a_p c K u0_p + b`` with ``c = E[cos|theta|] ~ 1 - tilt_sigma^2``, and the tilt
adds the covariance ``a_p a_q K Sigma_u K^T`` between the phases of one position / mount,
``Sigma_u = Var(cos|theta|) u0 u0^T + E[sin^2|theta|]/2 (I - u0 u0^T)`` (about
``sigma^4`` along ``u0`` and ``sigma^2`` across it; :func:`tilt_moments`). ``K`` and ``b``
then follow by generalized least squares with that covariance (iterated, because it depends
on ``K``; only the estimated scale factors enter it, since the off-diagonal part of the
estimate carries the tilts themselves), the predicted covariance is the GLS one, and each
position's tilt is reported as its best linear prediction. This

- weights the accelerometer bias of axis ``j`` towards the positions where ``j`` is
  vertical, where a tilt acts only at second order, and removes the mean ``-sigma^2`` scale
  error (``c``);
- cannot resolve misalignment better than the tilts (the estimate stays the nominal one) but
  *states* that uncertainty: the predicted standard deviations of ``K_ji`` grow to about
  ``tilt_sigma / sqrt(2)`` (six-position) or ``tilt_sigma`` (rate table), so the 2-sigma
  intervals keep their coverage.

Measured over 100 seeds (``tests/test_calibration.py``; EuRoC ADIS16448 white noise, 10 s
phases at 200 Hz, tilt components of 2 degrees): six-position, nominal method: RMS errors
0.11 m/s^2 (bias), 0.024 (misalignment), 1.6e-3 (scale, mean -1.2e-3), 2-sigma coverage 2%;
tilt model: 0.0076 m/s^2, 0.024, 8.7e-4 (no mean error), coverage 96% (95.1% over 1000
seeds). Rate table, nominal: misalignment 0.034, scale 1.6e-3 (mean -1.1e-3), bias
unaffected (2e-5 rad/s), coverage 26%; tilt model: 0.034, 1.1e-3, coverage 97% (95.4% over
1000 seeds). Without tilt both methods are the same; 2-sigma coverage of the nominal method
95.6% (accelerometer) and 95.3% (gyro) over 100 seeds, 95.5% and 95.1% over 1000.

Results
-------
:class:`AccelCalibration` / :class:`GyroCalibration` hold ``K``, ``b``, their 12x12
covariance, the derived scale factors ``s = diag(K) - 1`` and misalignment ``M = K S^-1``
(unit diagonal, the sensor-model convention ``K = M S``) with their standard deviations, the
phases used and the fit statistics. :meth:`SensorCalibration.to_config_dict` gives the
sensor-model keys (``<sensor>_scale``, ``<sensor>_misalignment``, ``<sensor>_bias``) that
:func:`splineimu.imu.config.load_imu_config` reads, and :func:`apply_calibration` corrects
data: ``x = K^-1 (y_m - b)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import ConfigError, InputError
from .imu.noise import _as_samples

__all__ = [
    "SteadyPhase", "SensorCalibration", "AccelCalibration", "GyroCalibration",
    "find_steady_phases", "calibrate_accel", "calibrate_gyro", "apply_calibration",
    "intrinsics_from_config", "split_scale_misalignment", "calibration_yaml_dict",
    "write_calibration_yaml", "read_calibration_yaml", "tilt_moments", "PARAMETER_NAMES",
]

#: Names of the twelve estimated parameters, in the order of :attr:`SensorCalibration.covariance`.
PARAMETER_NAMES = tuple([f"K[{i},{j}]" for i in range(3) for j in range(3)] + [f"b[{i}]" for i in range(3)])

#: A phase's measured magnitude must be within this ratio range of its reference magnitude.
MAGNITUDE_RATIO_RANGE = (0.8, 1.25)

#: Relative floor of the noise level (noise-free data).
_FLOOR_REL = 1e-9

_AXES = "xyz"


# ------------------------------------------------------------------------------ segmentation


def _as_time(t_ns):
    t = np.asarray(t_ns)
    if t.ndim != 1 or t.size < 3:
        raise InputError(f"Expected `t_ns` to have shape (N,) with N >= 3, got {t.shape}")
    if not np.issubdtype(t.dtype, np.integer):
        raise InputError(f"Expected `t_ns` to be integer nanoseconds, got dtype {t.dtype}")
    t = t.astype(np.int64)
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0]) + 1
        raise InputError(f"`t_ns` must be strictly increasing: t_ns[{i}] = {int(t[i])} after {int(t[i - 1])}")
    return t


def _moving_std(x, half):
    """Moving standard deviation of every column over the centred window ``2 half + 1``.

    Windows are clamped inside the record. O(N) with running sums that stay accurate: the
    windows starting in block ``j`` (``w`` samples) are summed relative to the block's first
    sample, so the sums never grow beyond ``2 w`` deviations from a nearby value (constant data
    give exactly 0).
    """
    n, c = x.shape
    w = 2 * half + 1
    if n < w:
        return np.tile(x.std(axis=0), (n, 1))
    from numpy.lib.stride_tricks import sliding_window_view

    starts = n - w + 1
    nb = -(-starts // w)
    pad = np.empty(((nb + 1) * w, c))
    pad[:n] = x
    pad[n:] = x[-1]
    blocks = sliding_window_view(pad, 2 * w, axis=0)[::w][:nb]  # (nb, c, 2w)
    d = blocks - blocks[:, :, :1]
    cs1 = np.zeros((nb, c, 2 * w + 1))
    cs2 = np.zeros((nb, c, 2 * w + 1))
    np.cumsum(d, axis=2, out=cs1[:, :, 1:])
    np.cumsum(d * d, axis=2, out=cs2[:, :, 1:])
    s1 = cs1[:, :, w:2 * w] - cs1[:, :, :w]  # window sums for start offsets 0..w-1
    s2 = cs2[:, :, w:2 * w] - cs2[:, :, :w]
    var = np.maximum(s2 - s1 * s1 / w, 0.0) / w
    full = np.sqrt(var).transpose(0, 2, 1).reshape(nb * w, c)[:starts]
    idx = np.clip(np.arange(n) - half, 0, n - w)
    return full[idx]


def _moving_drift(x, half):
    """``|mean(x[k+1 .. k+half]) - mean(x[k-half .. k-1])|`` per column, clamped at the ends."""
    n, c = x.shape
    if n < 2 * half + 1:
        return np.zeros((n, c))
    cs = np.zeros((n + 1, c))
    np.cumsum(x - x[0], axis=0, out=cs[1:])
    k = np.arange(half, n - half)
    d = np.abs((cs[k + half + 1] - cs[k + 1]) - (cs[k] - cs[k - half])) / half
    idx = np.clip(np.arange(n) - half, 0, n - 2 * half - 1)
    return d[idx]


@dataclass
class SteadyPhase:
    """One steady phase (rest or constant rate) found in a recording.

    Attributes
    ----------
    start, stop : int
        Sample indices ``[start, stop)``.
    t_start_ns, t_end_ns : int
        Stamps of the first and last sample.
    samples : int
    mean : (3,) float64
        Mean of the calibrated sensor over the phase.
    std : (3,) float64
        Sample standard deviation per axis (ddof 1).
    var_mean : (3,) float64
        Variance of the mean used as its weight (``sigma^2 / n``).
    magnitude : float
        Reference magnitude ``a`` (``g``, ``+-rate`` or 0); NaN when unused.
    direction : (3,) float64
        Nominal unit direction ``u`` of the reference (zeros when unused or at rest).
    label : str
        ``"+x"``, ``"-z"`` (gravity or rate axis), ``"rest"``, or ``""``.
    group : int
        Orientation group (one tilt per group; -1 for none).
    used : bool
    note : str
        Why a phase was left out.
    tilt_rad : (2,) float64 or None
        Best linear prediction of the tilt of the phase's position / mount
        (``method="tilt"``) [rad], about the two axes other than the nominal one, in the order
        x, y, z (``u = Exp(theta) u0``).
    """

    start: int
    stop: int
    t_start_ns: int
    t_end_ns: int
    samples: int
    mean: np.ndarray
    std: np.ndarray
    var_mean: np.ndarray = field(default_factory=lambda: np.zeros(3))
    magnitude: float = float("nan")
    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    label: str = ""
    group: int = -1
    used: bool = False
    note: str = ""
    tilt_rad: np.ndarray | None = None

    def to_dict(self) -> dict:
        d = {
            "t_start_ns": int(self.t_start_ns), "t_end_ns": int(self.t_end_ns), "samples": int(self.samples),
            "mean": self.mean.tolist(), "std": self.std.tolist(), "reference": self.label or None,
            "used": bool(self.used),
        }
        if self.used:
            d["reference_value"] = (self.magnitude * self.direction).tolist()
        if self.tilt_rad is not None:
            d["tilt_deg"] = np.degrees(self.tilt_rad).tolist()
        if self.note:
            d["note"] = self.note
        return d


def find_steady_phases(t_ns, signals, *, window_s: float = 0.5, threshold: float = 1.5,
                       min_dwell_s: float = 2.0, margin_s: float | None = None, drift_threshold: float = 5.0):
    """Steady phases (rest or constant rate) of a recording, from the data alone.

    Parameters
    ----------
    t_ns : (N,) int64
        Strictly increasing stamps [ns].
    signals : (N, C) array_like
        The channels to watch (e.g. gyro and accelerometer side by side).
    window_s : float, default 0.5
        Length of the centred moving window [s].
    threshold : float, default 1.5
        A sample is steady when every channel's moving standard deviation is at most
        ``threshold`` times that channel's noise level (module docstring, step 1).
    min_dwell_s : float, default 2.0
        Shortest phase kept [s] (after shrinking).
    margin_s : float, optional
        Samples removed at each end of a phase that borders motion [s]; default ``2 window_s``.
    drift_threshold : float, default 5
        A sample is also unsteady when the means of the two halves of its window differ by
        more than ``drift_threshold`` standard deviations of that difference
        (``sigma_c sqrt(2 / half)``): a slow ramp shows up there long before it raises the
        moving standard deviation.

    Returns
    -------
    phases : list of (start, stop)
        Sample index ranges ``[start, stop)``, in time order.
    noise_level : (C,) float64
        The per-channel noise level ``sigma_c`` used.

    Raises
    ------
    InputError
        Bad shapes or stamps.
    ConfigError
        Non-positive window, threshold or dwell.

    Examples
    --------
    >>> t = np.arange(3000, dtype=np.int64) * 10_000_000          # 100 Hz, 30 s
    >>> x = np.zeros((3000, 1)); x[1000:1200, 0] = np.linspace(0, 1, 200); x[1200:, 0] = 1
    >>> x += np.random.default_rng(0).normal(0, 1e-3, x.shape)
    >>> phases, _ = find_steady_phases(t, x)
    >>> [(int(a), int(b)) for a, b in phases]
    [(0, 877), (1323, 3000)]
    """
    t = _as_time(t_ns)
    x = np.asarray(signals, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or x.shape[0] != t.size:
        raise InputError(f"Expected `signals` to have shape ({t.size}, C), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError("`signals` contains NaN or infinite values")
    for name, v in (("window_s", window_s), ("threshold", threshold), ("min_dwell_s", min_dwell_s),
                    ("drift_threshold", drift_threshold)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ConfigError(f"`{name}` must be a positive number, got {v!r}")
    if margin_s is None:
        margin_s = 2.0 * window_s
    if not (math.isfinite(margin_s) and margin_s >= 0):
        raise ConfigError(f"`margin_s` must be >= 0, got {margin_s!r}")
    dt = float(np.median(np.diff(t))) / 1e9
    half = max(2, int(round(0.5 * window_s / dt)))
    margin = int(round(margin_s / dt))
    min_len = max(2, int(round(min_dwell_s / dt)))

    s = _moving_std(np.ascontiguousarray(x), half)
    from scipy.stats import chi2

    w = 2 * half + 1
    # the 25th percentile of the moving std of white noise is sigma sqrt(chi2_{w-1}(0.25) / w)
    sigma = np.percentile(s, 25.0, axis=0) / math.sqrt(chi2.ppf(0.25, w - 1) / w)
    floor = _FLOOR_REL * np.maximum(1.0, np.median(np.abs(x), axis=0))
    dx = np.abs(np.diff(x, axis=0))
    for c in range(x.shape[1]):  # quantized data: half the smallest step (the LSB)
        nz = dx[:, c][dx[:, c] > floor[c]]
        if nz.size:
            floor[c] = max(floor[c], 0.5 * float(nz.min()))
    drift = _moving_drift(x, half)
    steady = np.all((s <= threshold * sigma + floor)
                    & (drift <= drift_threshold * sigma * math.sqrt(2.0 / half) + floor), axis=1)

    # runs of True
    edges = np.diff(np.concatenate([[0], steady.astype(np.int8), [0]]))
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1)
    n = t.size
    out = []
    for a, b in zip(starts, stops):
        a2 = a + margin if a > 0 else a
        b2 = b - margin if b < n else b
        if b2 - a2 >= min_len:
            out.append((int(a2), int(b2)))
    return out, sigma


# ------------------------------------------------------------------------------ model helpers


def split_scale_misalignment(K):
    """``K = M S`` with ``S = diag(1 + s)`` and a unit-diagonal ``M``.

    Returns
    -------
    scale : (3,) ``s = diag(K) - 1``
    misalignment : (3, 3) ``M = K S^-1``

    Examples
    --------
    >>> s, M = split_scale_misalignment([[1.01, 0.002, 0], [0, 0.99, 0], [0.001, 0, 1.0]])
    >>> s.round(6).tolist(), float(M[0, 1].round(9))
    ([0.01, -0.01, 0.0], 0.002020202)
    """
    K = np.asarray(K, dtype=np.float64)
    d = np.diag(K).copy()
    if np.any(np.abs(d) < 1e-12):
        raise ConfigError(f"scale-misalignment matrix has a zero diagonal entry: {d.tolist()}")
    return d - 1.0, K / d[None, :]


def intrinsics_from_config(config, sensor: str):
    """The ``(K, b)`` of one sensor of a sensor-model configuration.

    Parameters
    ----------
    config : ImuConfig, path, preset name or mapping (:func:`splineimu.imu.config.load_imu_config`)
    sensor : {"accelerometer", "gyroscope"}

    Returns
    -------
    K : (3, 3) ``M S`` (identity where the configuration sets neither)
    b : (3,) the fixed turn-on bias ``<sensor>_bias`` (zeros when absent; a random
        ``<sensor>_bias_sigma`` draw is not in the configuration)
    """
    from .imu.config import load_imu_config

    cfg = load_imu_config(config)
    if sensor not in ("accelerometer", "gyroscope"):
        raise ConfigError(f"sensor must be 'accelerometer' or 'gyroscope', got {sensor!r}")
    p = cfg.sensor(sensor)
    S = np.diag(1.0 + (p["scale"] if p["scale"] is not None else np.zeros(3)))
    M = p["misalignment"] if p["misalignment"] is not None else np.eye(3)
    b = np.array(p["bias"], dtype=np.float64) if p["bias"] is not None else np.zeros(3)
    return M @ S, b


def _tangent_basis(u0):
    """(3, 2): the two unit axes other than the dominant axis of ``u0`` (the tilt axes)."""
    i = int(np.argmax(np.abs(u0)))
    others = [k for k in range(3) if k != i]
    return np.eye(3)[:, others]


def tilt_moments(sigma: float):
    """Moments of a random tilt ``theta ~ N(0, sigma^2 I_2)`` of a unit vector ``u0``.

    ``u = Exp(theta) u0 = cos|theta| u0 + sin|theta| (theta / |theta|) x u0``.

    Returns
    -------
    c : float
        ``E[cos|theta|] = 1 - sigma^2 + sigma^4 / 3 - ...`` (so ``E[u] = c u0``).
    var_parallel : float
        ``Var(cos|theta|)`` (about ``sigma^4``): the variance of ``u`` along ``u0``.
    var_perpendicular : float
        ``E[sin^2|theta|] / 2`` (about ``sigma^2``): the variance of ``u`` along each direction
        perpendicular to ``u0``.

    Notes
    -----
    ``|theta|`` is Rayleigh distributed with ``E|theta|^(2k) = 2^k k! sigma^(2k)``, so
    ``E[cos(m |theta|)] = sum_k (-1)^k 2^k k! (m sigma)^(2k) / (2k)!`` (an entire series).

    Examples
    --------
    >>> c, vpar, vperp = tilt_moments(0.01)
    >>> round((1 - c) / 1e-4, 6), round(vpar / 1e-8, 3), round(vperp / 1e-4, 3)
    (0.999967, 1.0, 1.0)
    """
    def e_cos(m):
        x = (m * sigma) ** 2
        total, term = 1.0, 1.0
        for k in range(1, 200):
            term *= -2.0 * k * x / ((2 * k - 1) * (2 * k))
            total += term
            if abs(term) < 1e-18 * abs(total):
                break
        return total

    c1, c2 = e_cos(1.0), e_cos(2.0)
    return c1, max(0.0, 0.5 * (1.0 + c2) - c1 * c1), 0.25 * (1.0 - c2)


def _solve(m, var, a, u0, group, tilt_sigma):
    """Generalized least squares for ``K``, ``b`` with random orientation errors.

    Model: ``m_p = a_p K u_p + b + n_p``, ``n_p ~ N(0, diag(var_p))``; the phases of one
    group share ``u = Exp(theta_g) u0``, ``theta_g ~ N(0, tilt_sigma^2 I_2)``. Then
    ``E[m_p] = a_p c K u0_p + b`` and ``Cov(m_p, m_q) = a_p a_q K Sigma_u K^T`` within a group
    (:func:`tilt_moments`), which depends on ``K`` (iterated from the nominal estimate).

    Returns (K, b, cov12, tilts (G, 2) best linear predictions, chi2, ok).
    """
    P = m.shape[0]
    use_tilt = tilt_sigma > 0.0
    c, vpar, vperp = tilt_moments(tilt_sigma) if use_tilt else (1.0, 0.0, 0.0)
    A = np.zeros((3 * P, 12))
    for p in range(P):
        for r in range(3):
            A[3 * p + r, 3 * r:3 * r + 3] = a[p] * c * u0[p]
            A[3 * p + r, 9 + r] = 1.0
    y = m.reshape(-1)
    tilted = [p for p in range(P) if use_tilt and group[p] >= 0 and a[p] != 0.0]
    K = np.eye(3)
    x = None
    for _ in range(20):
        C = np.diag(var.reshape(-1))
        # the tilt covariance uses the estimated scale factors only: the off-diagonal part of
        # the estimate carries the common tilt of each axis pair, not misalignment
        Kc = np.diag(np.diag(K))
        for p in tilted:
            Su = vpar * np.outer(u0[p], u0[p]) + vperp * (np.eye(3) - np.outer(u0[p], u0[p]))
            KSK = Kc @ Su @ Kc.T
            for q in tilted:
                if group[q] == group[p]:
                    C[3 * p:3 * p + 3, 3 * q:3 * q + 3] += a[p] * a[q] * KSK
        L = np.linalg.cholesky(C)
        Aw = np.linalg.solve(L, A)
        yw = np.linalg.solve(L, y)
        sv = np.linalg.svd(Aw, compute_uv=False)
        if sv.size < 12 or sv[-1] <= 1e-10 * sv[0]:
            return None, None, None, None, None, False
        x_new, *_ = np.linalg.lstsq(Aw, yw, rcond=None)
        done = x is not None and np.max(np.abs(x_new - x)) <= 1e-13 * max(1.0, np.max(np.abs(x_new)))
        x = x_new
        K = x[:9].reshape(3, 3)
        if not tilted or done:
            break
    _, s, Vt = np.linalg.svd(Aw, full_matrices=False)
    cov = (Vt.T / s**2) @ Vt
    rw = yw - Aw @ x
    chi2 = float(rw @ rw)
    tilts = None
    if tilted:
        Cr = np.linalg.solve(L.T, rw).reshape(P, 3)  # C^-1 (y - A x)
        G = max(group[p] for p in tilted) + 1
        tilts = np.zeros((G, 2))
        for p in tilted:
            D = -a[p] * K @ _skew(u0[p]) @ _tangent_basis(u0[p])  # d m_p / d theta (3, 2)
            tilts[group[p]] += tilt_sigma**2 * (D.T @ Cr[p])
    return K.copy(), x[9:12].copy(), cov, tilts, chi2, True


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


# ------------------------------------------------------------------------------ results


@dataclass
class SensorCalibration:
    """Estimated scale-misalignment matrix and bias of one sensor, with predicted uncertainty.

    Attributes
    ----------
    sensor : {"accelerometer", "gyroscope"}
    K : (3, 3) float64
        Scale-misalignment matrix ``M S`` (model ``y_m = K x + b``).
    bias : (3,) float64
    covariance : (12, 12) float64
        Covariance of ``(K row-major, b)`` (order :data:`PARAMETER_NAMES`).
    method : {"nominal", "tilt"}
        Exact nominal references, or random tilts marginalized (module docstring).
    tilt_sigma_rad : float
        Standard deviation of each tilt component assumed (0 for ``"nominal"``).
    phases : list of SteadyPhase
        Every steady phase found, used or not.
    chi2 : float
        Weighted sum of squared residuals of the phase means.
    dof : int
        ``3 * (phases used) - 12``.
    noise_level : (3,) float64
        White-noise standard deviation per sample, pooled over the phases used.
    noise_density : (3,) float64
        The same as a continuous density ``noise_level * sqrt(dt)``.
    segmentation : dict
        The segmentation settings and the per-channel noise level it used.
    nominal : SensorCalibration or None
        The classical (nominal-reference) estimate when ``method == "tilt"``.
    """

    sensor: str
    K: np.ndarray
    bias: np.ndarray
    covariance: np.ndarray
    method: str
    tilt_sigma_rad: float
    phases: list
    chi2: float
    dof: int
    noise_level: np.ndarray
    noise_density: np.ndarray
    segmentation: dict = field(default_factory=dict)
    nominal: SensorCalibration | None = None

    # ---------------------------------------------------------------- derived values
    @property
    def parameters(self) -> np.ndarray:
        """``(K row-major, b)`` (12,)."""
        return np.concatenate([self.K.ravel(), self.bias])

    @property
    def std(self) -> np.ndarray:
        """Predicted standard deviations of :attr:`parameters` (12,)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    @property
    def K_std(self) -> np.ndarray:
        return self.std[:9].reshape(3, 3)

    @property
    def bias_std(self) -> np.ndarray:
        return self.std[9:]

    @property
    def scale(self) -> np.ndarray:
        """Scale-factor errors ``s = diag(K) - 1`` (3,)."""
        return split_scale_misalignment(self.K)[0]

    @property
    def misalignment(self) -> np.ndarray:
        """Unit-diagonal misalignment ``M = K diag(K)^-1`` (3, 3)."""
        return split_scale_misalignment(self.K)[1]

    def _derived_cov(self):
        """Covariance of ``(s (3), M row-major (9), b (3))`` by first-order propagation."""
        K = self.K
        d = np.diag(K)
        Jd = np.zeros((15, 12))
        for j in range(3):
            Jd[j, 4 * j] = 1.0
        for i in range(3):
            for j in range(3):
                r = 3 + 3 * i + j
                if i == j:
                    continue  # unit diagonal: no uncertainty
                Jd[r, 3 * i + j] = 1.0 / d[j]
                Jd[r, 4 * j] = -K[i, j] / d[j] ** 2
        Jd[12:, 9:] = np.eye(3)
        return Jd @ self.covariance @ Jd.T

    @property
    def scale_std(self) -> np.ndarray:
        return np.sqrt(np.diag(self._derived_cov())[:3])

    @property
    def misalignment_std(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self._derived_cov())[3:12], 0.0, None)).reshape(3, 3)

    # ---------------------------------------------------------------- use
    def correct(self, y) -> np.ndarray:
        """Corrected samples ``x = K^-1 (y - b)``, (N, 3) -> (N, 3)."""
        y = np.asarray(y, dtype=np.float64)
        return np.linalg.solve(self.K, (y - self.bias).T).T

    def to_config_dict(self) -> dict:
        """The sensor-model keys ``<sensor>_scale``, ``<sensor>_misalignment``, ``<sensor>_bias``."""
        s = self.sensor
        return {f"{s}_scale": self.scale.tolist(), f"{s}_misalignment": self.misalignment.tolist(),
                f"{s}_bias": self.bias.tolist()}

    def std_dict(self) -> dict:
        """Predicted standard deviations under the same keys as :meth:`to_config_dict`."""
        s = self.sensor
        return {f"{s}_scale": self.scale_std.tolist(), f"{s}_misalignment": self.misalignment_std.tolist(),
                f"{s}_bias": self.bias_std.tolist()}

    def to_imu_config(self):
        """An :class:`~splineimu.imu.config.ImuConfig` with the estimated intrinsics."""
        from .imu.config import ImuConfig

        return ImuConfig.from_dict(self.to_config_dict(), source=f"{self.sensor} calibration")

    def to_dict(self) -> dict:
        """Plain mapping (numbers and lists) of everything: estimates, standard deviations, phases."""
        d = {
            "sensor": self.sensor,
            "method": self.method,
            **self._reference_dict(),
            "estimates": self.to_config_dict(),
            "std": self.std_dict(),
            "K": self.K.tolist(),
            "K_std": self.K_std.tolist(),
            "bias": self.bias.tolist(),
            "bias_std": self.bias_std.tolist(),
            "covariance_order": list(PARAMETER_NAMES),
            "covariance": self.covariance.tolist(),
            "tilt_sigma_deg": math.degrees(self.tilt_sigma_rad),
            "chi2": float(self.chi2),
            "dof": int(self.dof),
            "noise_density_estimate": self.noise_density.tolist(),
            "segmentation": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.segmentation.items()},
            "phases": [p.to_dict() for p in self.phases],
        }
        if self.nominal is not None:
            n = self.nominal
            d["nominal_method"] = {"K": n.K.tolist(), "K_std": n.K_std.tolist(), "bias": n.bias.tolist(),
                                   "bias_std": n.bias_std.tolist(), "chi2": float(n.chi2), "dof": int(n.dof)}
        return d

    def _reference_dict(self) -> dict:  # pragma: no cover - overridden
        return {}


@dataclass
class AccelCalibration(SensorCalibration):
    """:class:`SensorCalibration` of the accelerometer; ``gravity_m_s2`` is the reference ``g``."""

    gravity_m_s2: float = 9.81

    def _reference_dict(self):
        return {"gravity_m_s2": float(self.gravity_m_s2)}


@dataclass
class GyroCalibration(SensorCalibration):
    """:class:`SensorCalibration` of the gyro; ``rates_rad_s`` are the table rate magnitudes."""

    rates_rad_s: tuple = ()

    def _reference_dict(self):
        return {"rates_rad_s": [float(r) for r in self.rates_rad_s]}


# ------------------------------------------------------------------------------ calibration


def _axis_label(i, sign):
    return ("+" if sign > 0 else "-") + _AXES[i]


def _phase_stats(t, y, ranges, noise_density):
    dt = float(np.median(np.diff(t))) / 1e9
    phases = []
    for a, b in ranges:
        seg = y[a:b]
        n = b - a
        mean = seg.mean(axis=0)
        std = seg.std(axis=0, ddof=1)
        if noise_density is not None:
            sig = noise_density / math.sqrt(dt)
        else:
            sig = std
        floor = _FLOOR_REL * max(1.0, float(np.max(np.abs(mean))))
        var = np.maximum(sig, floor) ** 2 / n
        phases.append(SteadyPhase(start=a, stop=b, t_start_ns=int(t[a]), t_end_ns=int(t[b - 1]), samples=n,
                                  mean=mean, std=std, var_mean=var))
    return phases, dt


def _check_direction(mean, max_angle_deg):
    norm = float(np.linalg.norm(mean))
    i = int(np.argmax(np.abs(mean)))
    sign = 1 if mean[i] >= 0 else -1
    ang = math.degrees(math.acos(min(1.0, abs(mean[i]) / norm))) if norm > 0 else 90.0
    return i, sign, norm, ang <= max_angle_deg, ang


def _noise_density_arg(v):
    if v is None:
        return None
    arr = np.broadcast_to(np.asarray(v, dtype=np.float64), (3,)).copy()
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ConfigError(f"`noise_density` must be positive, got {v!r}")
    return arr


def _finish(cls, sensor, phases, dt, tilt_sigma_deg, seg_info, extra, what):
    used = [p for p in phases if p.used]
    if not used:
        raise InputError(f"no usable steady phases for the {sensor} calibration ({what})")
    m = np.array([p.mean for p in used])
    var = np.array([p.var_mean for p in used])
    a = np.array([p.magnitude for p in used])
    u0 = np.array([p.direction for p in used])
    groups = np.array([p.group for p in used])
    # renumber the groups that carry a tilt (a != 0)
    keys = sorted({int(g) for g, ai in zip(groups, a) if g >= 0 and ai != 0.0})
    remap = {g: k for k, g in enumerate(keys)}
    groups = np.array([remap.get(int(g), -1) if ai != 0.0 else -1 for g, ai in zip(groups, a)])
    found = ", ".join(sorted({p.label for p in used}))

    def result(method, tilt_sigma):
        K, b, cov, tilts, chi2, ok = _solve(m, var, a, u0, groups, tilt_sigma)
        if not ok:
            raise InputError(f"the {sensor} calibration is underdetermined: the steady phases found give the "
                             f"references {found or 'none'} ({len(used)} phases); {what}")
        pooled = np.sqrt(np.sum([(p.samples - 1) * p.std**2 for p in used], axis=0)
                         / max(1, sum(p.samples - 1 for p in used)))
        return cls(sensor=sensor, K=K, bias=b, covariance=cov, method=method, tilt_sigma_rad=tilt_sigma,
                   phases=phases, chi2=chi2, dof=3 * len(used) - 12, noise_level=pooled,
                   noise_density=pooled * math.sqrt(dt), segmentation=seg_info, **extra), tilts

    nominal, _ = result("nominal", 0.0)
    if not (tilt_sigma_deg and tilt_sigma_deg > 0):
        return nominal
    out, tilts = result("tilt", math.radians(tilt_sigma_deg))
    if tilts is not None:
        for p, g in zip(used, groups):
            if g >= 0:
                p.tilt_rad = tilts[g].copy()
    out.nominal = nominal
    return out


def _check_common(tilt_sigma_deg, max_axis_angle_deg):
    if not (math.isfinite(tilt_sigma_deg) and tilt_sigma_deg >= 0):
        raise ConfigError(f"`tilt_sigma_deg` must be >= 0, got {tilt_sigma_deg!r}")
    if not (math.isfinite(max_axis_angle_deg) and 0 < max_axis_angle_deg < 45):
        raise ConfigError(f"`max_axis_angle_deg` must be in (0, 45), got {max_axis_angle_deg!r}")


def calibrate_accel(t_ns, accel, gravity: float = 9.81, *, gyro=None, tilt_sigma_deg: float = 0.0,
                    noise_density=None, window_s: float = 0.5, threshold: float = 1.5,
                    min_dwell_s: float = 2.0, margin_s: float | None = None,
                    max_axis_angle_deg: float = 25.0) -> AccelCalibration:
    """Six-position accelerometer calibration: ``K`` (3x3) and ``b`` (3) from static phases.

    Parameters
    ----------
    t_ns : (N,) int64
        Stamps [ns].
    accel : (N, 3) array_like
        Measured specific force [m/s^2].
    gravity : float, default 9.81
        Local gravity magnitude ``g`` [m/s^2] (the reference of every static phase).
    gyro : (N, 3) array_like, optional
        Gyro samples; when given they must be steady too (a better segmentation).
    tilt_sigma_deg : float, default 0
        Standard deviation of each component of the positions' orientation error [deg]. 0:
        the nominal method (references exactly ``+-g e_i``). > 0: the tilts are estimated with
        this prior (module docstring, "Orientation error"); the result's ``nominal`` holds the
        nominal estimate for comparison.
    noise_density : float or (3,), optional
        White-noise density [m/s^2/sqrt(Hz)] for the weights and the predicted covariance;
        default: each phase's sample standard deviation.
    window_s, threshold, min_dwell_s, margin_s
        Segmentation (:func:`find_steady_phases`).
    max_axis_angle_deg : float, default 25
        Largest angle between a phase's mean and the nearest axis for it to be used.

    Returns
    -------
    AccelCalibration

    Raises
    ------
    InputError
        Bad arrays; too few distinct positions found (the message lists those found).
    ConfigError
        Bad settings.

    Notes
    -----
    Each static phase ``p`` gives ``y_p = g K u_p + b`` with ``u_p = +-e_i`` from the
    dominant axis of ``y_p`` (module docstring). Needs positions whose references span an
    affine basis (e.g. the six of the six-position test; four well-chosen ones suffice
    algebraically). Every phase is its own orientation (one tilt each).

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> from splineimu.imu.noise import SensorModel
    >>> sc = make_scene("six-position", dwell_s=6, transition_s=1)
    >>> t_ns = sc.sample_times_ns(100)
    >>> w, f = sc.imu(sc.t_s_from_ns(t_ns))
    >>> cfg = {"accelerometer_scale": [1e-3, -2e-3, 5e-4], "accelerometer_bias": [0.05, -0.02, 0.1]}
    >>> m = SensorModel(cfg).apply(sc.t_s_from_ns(t_ns), w, f)
    >>> cal = calibrate_accel(t_ns, m.accel, gyro=m.gyro)
    >>> np.round(cal.scale, 9).tolist(), np.round(cal.bias, 9).tolist()
    ([0.001, -0.002, 0.0005], [0.05, -0.02, 0.1])
    """
    t = _as_time(t_ns)
    y = _as_samples(accel, t.size, "accel")
    if not (isinstance(gravity, (int, float)) and math.isfinite(gravity) and gravity > 0):
        raise ConfigError(f"`gravity` must be a positive magnitude [m/s^2], got {gravity!r}")
    _check_common(tilt_sigma_deg, max_axis_angle_deg)
    nd = _noise_density_arg(noise_density)
    watch = y if gyro is None else np.hstack([y, _as_samples(gyro, t.size, "gyro")])
    ranges, noise_level = find_steady_phases(t, watch, window_s=window_s, threshold=threshold,
                                             min_dwell_s=min_dwell_s, margin_s=margin_s)
    phases, dt = _phase_stats(t, y, ranges, nd)
    lo, hi = MAGNITUDE_RATIO_RANGE
    for k, p in enumerate(phases):
        i, sign, norm, ok_dir, ang = _check_direction(p.mean, max_axis_angle_deg)
        if not (lo * gravity <= norm <= hi * gravity):
            p.note = f"|mean| = {norm:.4g} m/s^2 is not within [{lo:g}, {hi:g}] g"
            continue
        if not ok_dir:
            p.note = f"{ang:.1f} deg from the nearest axis (> {max_axis_angle_deg:g})"
            continue
        p.used, p.magnitude, p.label, p.group = True, float(gravity), _axis_label(i, sign), k
        p.direction = sign * np.eye(3)[i]
    seg = {"window_s": window_s, "threshold": threshold, "min_dwell_s": min_dwell_s,
           "margin_s": 2.0 * window_s if margin_s is None else margin_s, "noise_level": noise_level,
           "phases_found": len(phases)}
    return _finish(AccelCalibration, "accelerometer", phases, dt, tilt_sigma_deg, seg,
                   {"gravity_m_s2": float(gravity)},
                   "the six-position test needs each axis up and down (static phases with the "
                   "gravity along +x, -x, +y, -y, +z, -z)")


def calibrate_gyro(t_ns, gyro, rate=None, *, accel=None, tilt_sigma_deg: float = 0.0, shared_mount: bool = True,
                   noise_density=None, window_s: float = 0.5, threshold: float = 1.5,
                   min_dwell_s: float = 2.0, margin_s: float | None = None,
                   max_axis_angle_deg: float = 25.0) -> GyroCalibration:
    """Rate-table gyro calibration: ``K`` (3x3) and ``b`` (3) from constant-rate phases.

    Parameters
    ----------
    t_ns : (N,) int64
        Stamps [ns].
    gyro : (N, 3) array_like
        Measured body rate [rad/s].
    rate : float or sequence of float
        Table rate magnitude(s) [rad/s] (required: the scale factor is relative to it).
    accel : (N, 3) array_like, optional
        Accelerometer samples: used for the segmentation, and to tell mounts apart.
    tilt_sigma_deg : float, default 0
        Standard deviation of each component of the mount error [deg]; 0: nominal references
        ``+-rate e_i``; > 0: one tilt per mount is estimated with this prior.
    shared_mount : bool, default True
        The +rate and -rate phases about one axis share a mount (one tilt); with ``accel``,
        phases with a different gravity axis are different mounts. False: one tilt per phase.
    noise_density : float or (3,), optional
        White-noise density [rad/s/sqrt(Hz)]; default: each phase's sample standard deviation.
    window_s, threshold, min_dwell_s, margin_s
        Segmentation (:func:`find_steady_phases`).
    max_axis_angle_deg : float, default 25
        Largest angle between a phase's mean rate and the nearest axis.

    Returns
    -------
    GyroCalibration

    Raises
    ------
    ConfigError
        ``rate`` missing or not positive, bad settings.
    InputError
        Bad arrays; too few distinct rates found (the message lists those found).

    Notes
    -----
    Phases with ``|mean| < rate_min / 2`` are at rest (``x = 0``: they measure the bias);
    the others must be within [0.8, 1.25] of one of the rates and within
    ``max_axis_angle_deg`` of an axis: ``x = +-rate e_i``. Needs +rate and -rate (or rest)
    phases about all three axes. The gyro's g-sensitivity is not modelled: on a rate table
    it adds ``G g u_i`` per mount, which biases ``b`` (and inflates ``chi2``).

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> from splineimu.imu.noise import SensorModel
    >>> sc = make_scene("rate-table", dwell_s=6, rest_s=5, ramp_s=1, transition_s=1)
    >>> t_ns = sc.sample_times_ns(100)
    >>> w, f = sc.imu(sc.t_s_from_ns(t_ns))
    >>> m = SensorModel({"gyroscope_scale": [2e-3, 0, -1e-3], "gyroscope_bias": 1e-3}).apply(
    ...     sc.t_s_from_ns(t_ns), w, f)
    >>> cal = calibrate_gyro(t_ns, m.gyro, rate=1.0, accel=m.accel)
    >>> (np.round(cal.scale, 9) + 0.0).tolist(), np.round(cal.bias, 9).tolist()
    ([0.002, 0.0, -0.001], [0.001, 0.001, 0.001])
    """
    t = _as_time(t_ns)
    y = _as_samples(gyro, t.size, "gyro")
    if rate is None:
        raise ConfigError("give the table rate magnitude(s) `rate` [rad/s]: the gyro scale factors are "
                          "relative to it")
    rates = np.atleast_1d(np.asarray(rate, dtype=np.float64))
    if rates.ndim != 1 or rates.size == 0 or not np.all(np.isfinite(rates)) or np.any(rates <= 0):
        raise ConfigError(f"`rate` must be one or more positive rates [rad/s], got {rate!r}")
    _check_common(tilt_sigma_deg, max_axis_angle_deg)
    nd = _noise_density_arg(noise_density)
    acc = None if accel is None else _as_samples(accel, t.size, "accel")
    watch = y if acc is None else np.hstack([y, acc])
    ranges, noise_level = find_steady_phases(t, watch, window_s=window_s, threshold=threshold,
                                             min_dwell_s=min_dwell_s, margin_s=margin_s)
    phases, dt = _phase_stats(t, y, ranges, nd)
    lo, hi = MAGNITUDE_RATIO_RANGE
    mounts: dict = {}
    for k, p in enumerate(phases):
        i, sign, norm, ok_dir, ang = _check_direction(p.mean, max_axis_angle_deg)
        if norm < 0.5 * rates.min():
            p.used, p.magnitude, p.label, p.group = True, 0.0, "rest", -1
            continue
        j = int(np.argmin(np.abs(np.log(norm / rates))))
        if not (lo * rates[j] <= norm <= hi * rates[j]):
            p.note = f"|mean| = {norm:.4g} rad/s matches no table rate ({', '.join(f'{r:g}' for r in rates)})"
            continue
        if not ok_dir:
            p.note = f"{ang:.1f} deg from the nearest axis (> {max_axis_angle_deg:g})"
            continue
        if shared_mount:
            key = (i,)
            if acc is not None:
                ga = acc[p.start:p.stop].mean(axis=0)
                gi = int(np.argmax(np.abs(ga)))
                key = (i, gi, 1 if ga[gi] >= 0 else -1)
            group = mounts.setdefault(key, len(mounts))
        else:
            group = 1000 + k
        p.used, p.magnitude, p.group = True, float(sign * rates[j]), group
        p.label = _axis_label(i, sign) + (f" {rates[j]:g} rad/s" if rates.size > 1 else "")
        p.direction = np.eye(3)[i]
    seg = {"window_s": window_s, "threshold": threshold, "min_dwell_s": min_dwell_s,
           "margin_s": 2.0 * window_s if margin_s is None else margin_s, "noise_level": noise_level,
           "phases_found": len(phases)}
    return _finish(GyroCalibration, "gyroscope", phases, dt, tilt_sigma_deg, seg,
                   {"rates_rad_s": tuple(float(r) for r in rates)},
                   f"the rate table needs constant-rate phases about each axis at +-{rates[0]:g} rad/s "
                   "(and/or at rest)")


# ------------------------------------------------------------------------------ applying


def _intrinsics(cal, sensor):
    if isinstance(cal, SensorCalibration):
        if cal.sensor != sensor:
            return None
        return cal.K, cal.bias, None
    K, b = intrinsics_from_config(cal, sensor)
    G = None
    if sensor == "gyroscope":
        from .imu.config import load_imu_config

        G = load_imu_config(cal).gyroscope_g_sensitivity
    return K, b, G


def apply_calibration(calibration, gyro=None, accel=None):
    """Correct measurements with a calibration: ``x = K^-1 (y_m - b)`` per sensor.

    Parameters
    ----------
    calibration : SensorCalibration, sequence of them, or anything
        :func:`~splineimu.imu.config.load_imu_config` reads (e.g. ``CAL/calibration.yaml``).
        A sensor without intrinsics in it is returned unchanged (``K = I``, ``b = 0``).
    gyro, accel : (N, 3) array_like, optional

    Returns
    -------
    (gyro, accel) : corrected arrays (None where not given)

    Notes
    -----
    With a configuration that has ``gyroscope_g_sensitivity`` ``G`` and with ``accel``
    given, the gyro is corrected as ``K_g^-1 (w_m - b_g - G f)`` with ``f`` the corrected
    specific force.

    Examples
    --------
    >>> cfg = {"accelerometer_scale": [0.01, 0, 0], "accelerometer_bias": [0.1, 0, 0]}
    >>> _, f = apply_calibration(cfg, accel=[[1.11, 0, 9.81]])
    >>> f.round(12).tolist()
    [[1.0, 0.0, 9.81]]
    """
    cals = list(calibration) if isinstance(calibration, (list, tuple)) else [calibration]
    out = {}
    for sensor, y in (("accelerometer", accel), ("gyroscope", gyro)):
        if y is None:
            out[sensor] = None
            continue
        y = np.asarray(y, dtype=np.float64)
        if y.ndim != 2 or y.shape[1] != 3:
            raise InputError(f"Expected `{'gyro' if sensor == 'gyroscope' else 'accel'}` to have shape (N, 3), "
                             f"got {y.shape}")
        K, b, G = np.eye(3), np.zeros(3), None
        for c in cals:
            got = _intrinsics(c, sensor)
            if got is not None:
                K, b, G = got
        z = y - b
        if G is not None and out.get("accelerometer") is not None:
            z = z - out["accelerometer"] @ G.T
        out[sensor] = np.linalg.solve(K, z.T).T
    return out["gyroscope"], out["accelerometer"]


# ------------------------------------------------------------------------------ yaml


def calibration_yaml_dict(*calibrations, previous: dict | None = None, source: str = "") -> dict:
    """The mapping written to ``calibration.yaml``.

    Layout: ``imu0`` holds the estimates under the sensor-model keys (so that
    :func:`~splineimu.imu.config.load_imu_config` reads the file as a Kalibr-style chain),
    ``std`` the predicted standard deviations under the same keys, and ``calibration`` one
    informational section per sensor (:meth:`SensorCalibration.to_dict`, plus ``source``).
    Entries of ``previous`` (an earlier file's mapping) for other sensors are kept.
    """
    d = {"imu0": {}, "std": {}, "calibration": {}}
    if previous:
        for key in ("imu0", "std", "calibration"):
            if isinstance(previous.get(key), dict):
                d[key].update(previous[key])
    for cal in calibrations:
        s = cal.sensor
        for key in ("imu0", "std"):
            d[key] = {k: v for k, v in d[key].items() if not k.startswith(s + "_")}
        d["imu0"].update(cal.to_config_dict())
        d["std"].update(cal.std_dict())
        info = {"source": source} if source else {}
        info.update(cal.to_dict())
        info.pop("estimates")
        info.pop("std")
        d["calibration"][s] = info
    return d


def read_calibration_yaml(path):
    """Read ``calibration.yaml`` (layout: :func:`calibration_yaml_dict`).

    Returns
    -------
    config : ImuConfig
        The estimates (as :func:`~splineimu.imu.config.load_imu_config` reads them).
    std : dict
        Predicted standard deviations under the same keys.
    raw : dict
        The whole mapping (with the ``calibration`` details).

    Raises
    ------
    ConfigError
        Missing or unreadable file, yaml error, no ``imu0`` section, invalid keys.
    """
    from pathlib import Path

    import yaml

    from .imu.config import ImuConfig

    path = Path(path)
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(f"cannot read calibration file {path}: {exc}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: invalid yaml: {exc}") from None
    if not isinstance(raw, dict) or not isinstance(raw.get("imu0"), dict):
        raise ConfigError(f"{path}: not a splineimu calibration file (no `imu0` section)")
    cfg = ImuConfig.from_dict(raw["imu0"], source=str(path), base_dir=path.parent)
    return cfg, dict(raw.get("std") or {}), raw


def write_calibration_yaml(path, *calibrations, source: str = "", force: bool = False):
    """Write (or update) ``calibration.yaml`` atomically (layout: :func:`calibration_yaml_dict`).

    An existing file's entries for *other* sensors are kept; replacing a sensor that is
    already in it needs ``force``. ``source`` (one line, e.g. the input file and method) is
    stored with each sensor written and listed in the file's header comment.

    Raises
    ------
    OutputExistsError
        The file already holds one of these sensors and ``force`` is False.
    """
    from pathlib import Path

    import yaml

    from .errors import OutputExistsError
    from .io.files import atomic_write_text

    path = Path(path)
    previous = None
    if path.exists():
        try:
            previous = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        except yaml.YAMLError:
            previous = None
        if not isinstance(previous, dict) or not isinstance(previous.get("imu0", {}), dict):
            if not force:
                raise OutputExistsError(f"{path} exists and is not a calibration file; use --force to replace it")
            previous = None
        else:
            have = set((previous.get("calibration") or {}).keys())
            clash = sorted(have & {c.sensor for c in calibrations})
            if clash and not force:
                raise OutputExistsError(f"{path} already holds a {' and '.join(clash)} calibration; "
                                        "use --force to replace it")
    d = calibration_yaml_dict(*calibrations, previous=previous, source=source)
    lines = [
        "# splineimu calibration. `imu0`: estimated intrinsics under the sensor-model keys",
        "# (K = M S, S = I + diag(scale), unit-diagonal M; read with load_imu_config / --imu);",
        "# `std`: predicted standard deviations under the same keys; `calibration`: details.",
    ]
    for sensor, info in d["calibration"].items():
        if isinstance(info, dict) and info.get("source"):
            lines.append(f"# {sensor}: {' '.join(str(info['source']).split())}")
    text = "\n".join(lines) + "\n" + _dump_yaml(d)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, text)
    return path


def _dump_yaml(d) -> str:
    import yaml

    class _Dumper(yaml.SafeDumper):
        pass

    def _repr_list(dumper, value):
        flat = all(not isinstance(v, (list, dict)) for v in value)
        return dumper.represent_sequence("tag:yaml.org,2002:seq", value, flow_style=flat)

    def _repr_float(dumper, value):
        if math.isnan(value):
            return dumper.represent_scalar("tag:yaml.org,2002:float", ".nan")
        if math.isinf(value):
            return dumper.represent_scalar("tag:yaml.org,2002:float", ".inf" if value > 0 else "-.inf")
        return dumper.represent_scalar("tag:yaml.org,2002:float", repr(float(value)))

    _Dumper.add_representer(list, _repr_list)
    _Dumper.add_representer(tuple, _repr_list)
    _Dumper.add_representer(float, _repr_float)
    return yaml.dump(d, Dumper=_Dumper, sort_keys=False, default_flow_style=False, width=120)
