"""Preintegration of a recording over windows, compared with its ground truth.

:func:`splineimu.api.evaluate_recording` is what ``splineimu preintegrate`` runs: it reads an output folder
(``mav0/imu0/data.csv``, ``mav0/state_groundtruth_estimate0/data.csv``, optionally ``imu.yaml``), cuts the
IMU stream into windows (:func:`make_windows`) and calls :func:`evaluate_windows`, which
preintegrates each window linearized at the ground-truth biases at its start and compares the
deltas with the exact ones of the ground truth (errors ``truth (-) estimate``, 9-dof NEES).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError, InputError, SplineImuError
from ..groundtruth import GroundTruth
from ..integrate import SAMPLINGS, points_from_means
from ..motion import DEFAULT_GRAVITY
from ..validation import as_stamps_ns, as_vector, as_vectors, one_of
from .deltas import Deltas, delta_error, deltas_from_states, nees
from .preintegrator import Preintegrator

__all__ = ["WindowResult", "NeesTest", "evaluate_windows", "make_windows",
           "noise_densities", "KALIBR_KEYS"]

#: The four noise densities of an IMU yaml, in the order :class:`Preintegrator` takes them.
KALIBR_KEYS = ("gyroscope_noise_density", "accelerometer_noise_density",
               "gyroscope_random_walk", "accelerometer_random_walk")


@dataclass
class NeesTest:
    """Mean NEES of ``n_windows`` windows and the 95 % interval of that mean for a consistent
    covariance (``chi2(9 n) / n``)."""

    n_windows: int
    mean: float
    low: float
    high: float

    @property
    def inside(self) -> bool:
        return bool(self.low <= self.mean <= self.high)


@dataclass
class WindowResult:
    """Preintegrated windows of a recording compared with ground truth.

    Attributes
    ----------
    t_i_ns, t_j_ns : (W,) int64 window bounds
    n_samples : (W,) int, IMU samples used (including interpolated end samples)
    error_p_m, error_v_m_s, error_theta_rad : (W,) norms of ``truth (-) estimate``
    error : (W, 9) the errors ``(p, theta, v)``
    nees : (W,) 9-dof NEES; NaN without noise parameters or for a singular covariance (one-step
        windows: there ``p`` and ``v`` are driven by the same noise)
    delta_p, delta_v : (W, 3); delta_q_xyzw : (W, 4), the preintegrated deltas
    truth : list of :class:`Deltas`, ground-truth deltas
    method, covariance_model : str
    noise : dict or None
        The four Kalibr densities used for the covariance (None: no NEES).
    noise_source : str
        Where they came from (a file or preset name; "" without noise).
    notes : list of str
        What the errors depend on that the table does not say (windows across gaps of the IMU stamps).
    """

    t_i_ns: np.ndarray
    t_j_ns: np.ndarray
    n_samples: np.ndarray
    error: np.ndarray
    nees: np.ndarray
    delta_p: np.ndarray
    delta_v: np.ndarray
    delta_q_xyzw: np.ndarray
    truth: list
    method: str = "midpoint"
    covariance_model: str = "consistent"
    noise: dict | None = None
    noise_source: str = ""
    notes: list = field(default_factory=list)

    def __len__(self) -> int:
        return int(self.t_i_ns.shape[0])

    @property
    def error_p_m(self):
        """(W,) position error norms [m]."""
        return np.linalg.norm(self.error[:, 0:3], axis=1)

    @property
    def error_theta_rad(self):
        """(W,) rotation error angles [rad]."""
        return np.linalg.norm(self.error[:, 3:6], axis=1)

    @property
    def error_v_m_s(self):
        """(W,) velocity error norms [m/s]."""
        return np.linalg.norm(self.error[:, 6:9], axis=1)

    def to_dataframe(self):
        """One row per window: bounds, length, samples, error norms (theta in degrees), NEES."""
        import pandas as pd

        return pd.DataFrame({
            "t_i_ns": self.t_i_ns,
            "t_j_ns": self.t_j_ns,
            "dt_s": (self.t_j_ns - self.t_i_ns) * 1e-9,
            "samples": self.n_samples,
            "err_p_m": self.error_p_m,
            "err_v_m_s": self.error_v_m_s,
            "err_theta_deg": np.degrees(self.error_theta_rad),
            "nees9": self.nees,
        })

    @property
    def n_nees(self) -> int:
        """Number of windows with a NEES."""
        return int(np.isfinite(self.nees).sum())

    @property
    def noise_free(self) -> bool:
        """The noise densities are all zero (a noise-free recording's imu.yaml): the covariance
        is zero and no window has a NEES."""
        return self.noise is not None and all(not np.any(np.asarray(self.noise[k])) for k in KALIBR_KEYS)

    def nees_test(self) -> NeesTest | None:
        """Mean 9-dof NEES of the windows that have one, against its 95 % chi-square interval.

        None without noise parameters or when no window has a NEES.
        """
        if self.noise is None:
            return None
        ok = np.isfinite(self.nees)
        n = int(ok.sum())
        if n == 0:
            return None
        from scipy import stats

        lo, hi = stats.chi2.ppf([0.025, 0.975], 9 * n) / n
        return NeesTest(n, float(np.mean(self.nees[ok])), float(lo), float(hi))

    def format_table(self, limit: int | None = 40) -> str:
        """The windows as text (times relative to the first window's start); at most ``limit``
        rows, the middle ones elided."""
        show = self.to_dataframe()
        show.insert(0, "t_i_s", (show["t_i_ns"] - int(self.t_i_ns[0])) * 1e-9)
        show = show.drop(columns=["t_i_ns", "t_j_ns"])
        if self.noise is None:
            show = show.drop(columns=["nees9"])
        fmt = {"t_i_s": "{:.3f}".format, "dt_s": "{:.4f}".format, "err_p_m": "{:.3e}".format,
               "err_v_m_s": "{:.3e}".format, "err_theta_deg": "{:.3e}".format, "nees9": "{:.2f}".format}
        lines = show.to_string(index=False, formatters=fmt).splitlines()
        if limit is not None and len(lines) - 1 > limit:
            half = limit // 2
            skipped = f"... {len(lines) - 1 - limit} windows not shown (--all) ..."
            lines = lines[: 1 + half] + [skipped] + lines[-half:]
        return "\n".join(lines)



def _sample_at(t_ns, y, stamp):
    """Linear interpolation of the rows of ``y`` at an integer stamp inside ``t_ns``."""
    j = int(np.searchsorted(t_ns, stamp, side="right")) - 1
    if t_ns[j] == stamp:
        return y[j]
    u = float(stamp - t_ns[j]) / float(t_ns[j + 1] - t_ns[j])
    return (1.0 - u) * y[j] + u * y[j + 1]


def _window_samples(t_ns, gyro, accel, a_ns, b_ns):
    """Samples in ``[a_ns, b_ns]``, with linearly interpolated end samples when no sample falls
    exactly on a bound."""
    if a_ns < t_ns[0] or b_ns > t_ns[-1]:
        raise InputError(f"window [{a_ns}, {b_ns}] ns is outside the IMU data [{t_ns[0]}, {t_ns[-1]}] ns")
    lo = int(np.searchsorted(t_ns, a_ns, side="left"))
    hi = int(np.searchsorted(t_ns, b_ns, side="right"))
    tt, gg, aa = t_ns[lo:hi], gyro[lo:hi], accel[lo:hi]
    if tt.size == 0 or tt[0] != a_ns:
        tt = np.concatenate([[a_ns], tt])
        gg = np.vstack([_sample_at(t_ns, gyro, a_ns), gg])
        aa = np.vstack([_sample_at(t_ns, accel, a_ns), aa])
    if tt[-1] != b_ns:
        tt = np.concatenate([tt, [b_ns]])
        gg = np.vstack([gg, _sample_at(t_ns, gyro, b_ns)])
        aa = np.vstack([aa, _sample_at(t_ns, accel, b_ns)])
    return tt.astype(np.int64), gg, aa


def evaluate_windows(imu_t_ns, gyro, accel, groundtruth: GroundTruth, windows_ns, noise=None,
                     method="midpoint", covariance="consistent", gravity=DEFAULT_GRAVITY,
                     noise_source: str = "", sampling: str = "point") -> WindowResult:
    """Preintegrate a recording's IMU over windows and compare with its ground truth.

    Parameters
    ----------
    imu_t_ns : (N,) int64; gyro, accel : (N, 3)
        IMU samples (EuRoC ``imu0/data.csv``).
    groundtruth : splineimu.groundtruth.GroundTruth
        Ground truth (EuRoC ``state_groundtruth_estimate0``); the states and biases at window
        bounds that fall between stamps are interpolated (:meth:`GroundTruth.state_at`).
    windows_ns : (W, 2) int64
        ``[t_i, t_j]`` per window. IMU samples at the bounds are interpolated linearly when
        no sample falls exactly on them.
    noise : dict, optional
        Kalibr keys ``gyroscope_noise_density``, ``accelerometer_noise_density``,
        ``gyroscope_random_walk``, ``accelerometer_random_walk``; gives the NEES.
    method, covariance : str
        As in :class:`Preintegrator`.
    gravity : (3,)
        ``g_w`` the data were made with.
    noise_source : str
        Where ``noise`` came from (kept in the result).
    sampling : {"point", "mean"}
        The samples are values at the stamps, or means over ``[t_{k-1}, t_k]`` (turned into
        point values first, :func:`splineimu.integrate.points_from_means`).

    Returns
    -------
    WindowResult
        Errors ``truth (-) estimate`` with the deltas linearized at the ground-truth biases at
        ``t_i``, i.e. the first nine rows of :meth:`Preintegrator.residual` with true states.
    """
    imu_t_ns = as_stamps_ns(imu_t_ns, "imu_t_ns")
    gyro = as_vectors(gyro, "gyro", imu_t_ns.shape[0])
    accel = as_vectors(accel, "accel", imu_t_ns.shape[0])
    gravity = as_vector(gravity, "gravity")  # NaN gave NaN errors for every window, exit code 0
    if one_of(sampling, "sampling", SAMPLINGS) == "mean":
        both = points_from_means((imu_t_ns - imu_t_ns[0]).astype(np.float64) * 1e-9, np.hstack([gyro, accel]))
        gyro, accel = both[:, :3], both[:, 3:]
    windows = np.asarray(windows_ns, dtype=np.int64).reshape(-1, 2)
    if noise is None:
        dens = (0.0, 0.0, 0.0, 0.0)
    else:
        dens = (noise["gyroscope_noise_density"], noise["accelerometer_noise_density"],
                noise["gyroscope_random_walk"], noise["accelerometer_random_walk"])
    W = len(windows)
    err = np.zeros((W, 9))
    ne = np.full(W, np.nan)
    dps, dvs, dqs, nsamp, truths = np.zeros((W, 3)), np.zeros((W, 3)), np.zeros((W, 4)), np.zeros(W, int), []
    for w, (a_ns, b_ns) in enumerate(windows):
        if b_ns <= a_ns:
            raise InputError(f"window {w}: end {b_ns} ns is not after start {a_ns} ns")
        ts, gs, as_ = _window_samples(imu_t_ns, gyro, accel, a_ns, b_ns)
        s_i, s_j = groundtruth.state_at(a_ns), groundtruth.state_at(b_ns)
        pre = Preintegrator(*dens, bias_gyro=s_i.bias_gyro, bias_accel=s_i.bias_accel, method=method,
                            covariance=covariance, compute_covariance=noise is not None)
        pre.integrate((ts - a_ns).astype(np.float64) * 1e-9, gs, as_)
        dt = pre.delta_t_s
        dp, dv, dq = deltas_from_states(s_i.position_world, s_i.world_R_body, s_i.velocity_world,
                                        s_j.position_world, s_j.world_R_body, s_j.velocity_world, dt, gravity)
        truth = Deltas(dp, dv, dq, dt)
        est = pre.deltas()
        err[w] = delta_error(est, truth)
        if noise is not None and len(ts) >= 3:  # one step: p and v share one noise, singular
            try:
                ne[w] = nees(err[w], pre.covariance[:9, :9])
            except SplineImuError:
                pass  # singular (too few samples): NaN
        dps[w], dvs[w], dqs[w], nsamp[w] = est.delta_p, est.delta_v, est.delta_q_xyzw, len(ts)
        truths.append(truth)
    return WindowResult(windows[:, 0].copy(), windows[:, 1].copy(), nsamp, err, ne, dps, dvs, dqs, truths,
                        method, covariance, noise, noise_source if noise is not None else "",
                        notes=_gap_notes(imu_t_ns, windows))


def _gap_notes(t_ns, windows) -> list:
    """A note on gaps of the IMU stamps (> 1.5 median intervals) inside windows: a window's deltas
    integrate the motion in a gap from its two end samples alone (1 s cut out of the ellipse:
    3 m of position error in that window, 6e-5 m in the others)."""
    d = np.diff(t_ns)
    gaps = np.flatnonzero(d > 1.5 * float(np.median(d)))
    hit = [g for g in gaps if np.any((windows[:, 0] < t_ns[g + 1]) & (windows[:, 1] > t_ns[g]))]
    if not hit:
        return []
    k = max(hit, key=lambda g: d[g])
    return [f"{len(hit)} gap(s) in the IMU stamps longer than 1.5 sample intervals lie inside windows (longest "
            f"{d[k] / 1e9:.6g} s, {(t_ns[k] - windows[0, 0]) / 1e9:.6g} s after the first window's start): "
            "a window's deltas across a gap come from the gap's two end samples alone"]


def noise_densities(spec) -> dict:
    """The four Kalibr densities ((3,) arrays) of an IMU yaml or preset, via
    :func:`splineimu.imu.config.load_imu_config` (Kalibr chains and OpenCV headers included)."""
    from ..imu.config import load_imu_config

    cfg = load_imu_config(spec)
    return {k: getattr(cfg, k).copy() for k in KALIBR_KEYS}


def make_windows(imu_t_ns, gt_t_ns, every=None, stamps_ns=None) -> np.ndarray:
    """(W, 2) int64 windows inside both the IMU and the ground-truth spans.

    Parameters
    ----------
    imu_t_ns, gt_t_ns : (N,), (M,) int64
        IMU and ground-truth stamps.
    every : int, optional
        Window length in IMU samples (default: about 1 s of samples).
    stamps_ns : (S,) int64, optional
        Window bounds instead (consecutive stamps inside both spans).

    Examples
    --------
    >>> t = np.arange(0, 1000, 100)
    >>> make_windows(t, t[1:], every=3).tolist()
    [[100, 400], [400, 700]]
    """
    lo = max(int(imu_t_ns[0]), int(gt_t_ns[0]))
    hi = min(int(imu_t_ns[-1]), int(gt_t_ns[-1]))
    if stamps_ns is not None:
        given = np.asarray(stamps_ns, dtype=np.int64)
        s = given[(given >= lo) & (given <= hi)]
        if s.size < 2:
            got = f"the {given.size} given span [{given.min()}, {given.max()}] ns" if given.size else "none given"
            raise ConfigError(f"fewer than 2 stamps inside the IMU and ground-truth span [{lo}, {hi}] ns ({got})")
        return np.stack([s[:-1], s[1:]], axis=1)
    t = imu_t_ns[(imu_t_ns >= lo) & (imu_t_ns <= hi)]
    if t.size < 2:
        raise ConfigError("fewer than 2 IMU samples inside the ground truth's span")
    if every is None:
        every = max(1, int(round(1e9 / float(np.median(np.diff(t))))))
    if every < 1:
        raise ConfigError(f"--every must be >= 1, got {every}")
    idx = np.arange(0, t.size, every)
    if idx.size < 2:
        raise ConfigError(f"--every {every} is longer than the {t.size} usable IMU samples")
    return np.stack([t[idx[:-1]], t[idx[1:]]], axis=1)
