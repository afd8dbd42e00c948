"""Steps 2 and 3 of a calibration and the two entry points: six-position accelerometer and rate-table gyro.

Each steady phase gives its mean and the variance of that mean (step 2); its nominal reference
comes from its dominant axis (step 3); :func:`~splineimu.calibration.solve.solve_intrinsics`
then gives ``K``, ``b`` and their covariance (step 4). See :mod:`splineimu.calibration`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..errors import ConfigError, InputError
from ..validation import as_vectors, positive_float
from .drift import estimate_random_walk, phase_drift_covariance
from .options import CalibrationOptions
from .result import AccelCalibration, GyroCalibration, SteadyPhase
from .segmentation import FLOOR_REL, as_stamps_ns_checked, find_steady_phases
from .solve import solve_intrinsics

__all__ = ["calibrate_accel", "calibrate_gyro", "MAGNITUDE_RATIO_RANGE"]

#: A phase's measured magnitude must be within this ratio range of its reference magnitude.
MAGNITUDE_RATIO_RANGE = (0.8, 1.25)

_AXES = "xyz"


class _Record(NamedTuple):
    t: np.ndarray          # stamps [ns]
    y: np.ndarray          # the calibrated sensor (N, 3)
    other: np.ndarray | None  # the other sensor, when given
    phases: list
    dt: float
    seg: dict


def _axis_label(i, sign):
    return ("+" if sign > 0 else "-") + _AXES[i]


def _phase_stats(t, y, ranges, noise_density):
    dt = float(np.median(np.diff(t))) / 1e9
    nd = None if noise_density is None else np.array(noise_density, dtype=np.float64)
    phases = []
    for a, b in ranges:
        seg = y[a:b]
        n = b - a
        mean = seg.mean(axis=0)
        std = seg.std(axis=0, ddof=1)
        sig = std if nd is None else nd / math.sqrt(dt)
        floor = FLOOR_REL * max(1.0, float(np.max(np.abs(mean))))
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


def _phases(t_ns, y, other, name, other_name, opts):
    """Validated stamps and samples, and the steady phases with their statistics (steps 1 and 2)."""
    t = as_stamps_ns_checked(t_ns)
    y = as_vectors(y, name, t.size)
    other = None if other is None else as_vectors(other, other_name, t.size)
    watch = y if other is None else np.hstack([y, other])
    ranges, noise_level = find_steady_phases(t, watch, **opts.segmentation())
    phases, dt = _phase_stats(t, y, ranges, opts.noise_density)
    seg = {"window_s": opts.window_s, "threshold": opts.threshold, "min_dwell_s": opts.min_dwell_s,
           "margin_s": opts.effective_margin_s, "noise_level": noise_level, "phases_found": len(phases)}
    return _Record(t, y, other, phases, dt, seg)


def _drift(rec, used, a, u0, groups, opts):
    """``(density (3,), source, likelihood ratio, covariance (3P, 3P) or None)`` of the bias drift."""
    if opts.random_walk is not None:
        density, source, lr = np.array(opts.random_walk), "given", math.inf
    else:
        # structure below 1e-6 of the signal (round-off, the smooth ends of noise-free moves) is no drift
        floor = 1e-6 * max(1.0, float(np.max(np.abs([p.mean for p in used]))))
        fit = estimate_random_walk(rec.t, rec.y, used, a, u0, groups, opts.tilt_sigma_rad, floor=floor)
        density, source, lr = np.full(3, fit.density), "estimated", fit.lr_statistic
    if not np.any(density > 0):
        return np.zeros(3), "none" if source == "given" else source, 0.0, None
    return density, source, lr, np.kron(phase_drift_covariance(rec.t, used), np.diag(density**2))


def _finish(cls, sensor, rec, opts, extra, what):
    phases, dt = rec.phases, rec.dt
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
    if not solve_intrinsics(m, var, a, u0, groups, 0.0)[-1]:
        raise InputError(f"the {sensor} calibration is underdetermined: the steady phases found give the "
                         f"references {found or 'none'} ({len(used)} phases); {what}")
    density, source, lr, drift_cov = _drift(rec, used, a, u0, groups, opts)

    def result(method, tilt_sigma):
        K, b, white_cov, tilts, chi2, _ = solve_intrinsics(m, var, a, u0, groups, tilt_sigma)
        cov = white_cov
        if drift_cov is not None:
            K, b, cov, tilts, chi2, _ = solve_intrinsics(m, var, a, u0, groups, tilt_sigma, drift_cov)
        pooled = np.sqrt(np.sum([(p.samples - 1) * p.std**2 for p in used], axis=0)
                         / max(1, sum(p.samples - 1 for p in used)))
        return cls(sensor=sensor, K=K, bias=b, covariance=cov, method=method, tilt_sigma_rad=tilt_sigma,
                   phases=phases, chi2=chi2, dof=3 * len(used) - 12, noise_level=pooled,
                   noise_density=pooled * math.sqrt(dt), segmentation=rec.seg, random_walk=density,
                   random_walk_source=source, random_walk_lr=lr, white_covariance=white_cov, **extra), tilts

    nominal, _ = result("nominal", 0.0)
    if not opts.tilt_sigma_deg > 0:
        return nominal
    out, tilts = result("tilt", opts.tilt_sigma_rad)
    if tilts is not None:
        for p, g in zip(used, groups):
            if g >= 0:
                p.tilt_rad = tilts[g].copy()
    out.nominal = nominal
    return out


def calibrate_accel(t_ns, accel, gravity: float = 9.81, *, gyro=None, options: CalibrationOptions | None = None,
                    **settings) -> AccelCalibration:
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
    options : CalibrationOptions, optional
        Segmentation, weighting and orientation-error settings (defaults when omitted).
    **settings
        Fields of :class:`CalibrationOptions` that replace those of ``options``, e.g.
        ``tilt_sigma_deg=2`` (> 0: the positions' tilts are marginalized with this prior and
        the result's ``nominal`` holds the nominal estimate) or ``noise_density`` (white-noise
        density [m/s^2/sqrt(Hz)] for the weights instead of each phase's scatter).

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
    opts = CalibrationOptions.merged(options, settings, "calibrate_accel")
    gravity = positive_float(gravity, "gravity")
    rec = _phases(t_ns, accel, gyro, "accel", "gyro", opts)
    max_axis_angle_deg = opts.max_axis_angle_deg
    lo, hi = MAGNITUDE_RATIO_RANGE
    for k, p in enumerate(rec.phases):
        i, sign, norm, ok_dir, ang = _check_direction(p.mean, max_axis_angle_deg)
        if not (lo * gravity <= norm <= hi * gravity):
            p.note = f"|mean| = {norm:.4g} m/s^2 is not within [{lo:g}, {hi:g}] g"
            continue
        if not ok_dir:
            p.note = f"{ang:.1f} deg from the nearest axis (> {max_axis_angle_deg:g})"
            continue
        p.used, p.magnitude, p.label, p.group = True, float(gravity), _axis_label(i, sign), k
        p.direction = sign * np.eye(3)[i]
    return _finish(AccelCalibration, "accelerometer", rec, opts,
                   {"gravity_m_s2": float(gravity)},
                   "the six-position test needs each axis up and down (static phases with the "
                   "gravity along +x, -x, +y, -y, +z, -z)")


def calibrate_gyro(t_ns, gyro, rate=None, *, accel=None, shared_mount: bool = True,
                   options: CalibrationOptions | None = None, **settings) -> GyroCalibration:
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
    shared_mount : bool, default True
        The +rate and -rate phases about one axis share a mount (one tilt); with ``accel``,
        phases with a different gravity axis are different mounts. False: one tilt per phase.
    options : CalibrationOptions, optional
        Segmentation, weighting and orientation-error settings (defaults when omitted).
    **settings
        Fields of :class:`CalibrationOptions` that replace those of ``options``, e.g.
        ``tilt_sigma_deg=2`` (> 0: one tilt per mount is marginalized with this prior) or
        ``noise_density`` [rad/s/sqrt(Hz)].

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
    opts = CalibrationOptions.merged(options, settings, "calibrate_gyro")
    if rate is None:
        raise ConfigError("give the table rate magnitude(s) `rate` [rad/s]: the gyro scale factors are "
                          "relative to it", option="rate")
    rates = np.array([positive_float(r, "rate") for r in np.atleast_1d(rate)], dtype=np.float64)
    if rates.size == 0:
        raise ConfigError("`rate` must be one or more positive rates [rad/s], got none", option="rate")
    rec = _phases(t_ns, gyro, accel, "gyro", "accel", opts)
    acc = rec.other
    max_axis_angle_deg = opts.max_axis_angle_deg
    lo, hi = MAGNITUDE_RATIO_RANGE
    mounts: dict = {}
    for k, p in enumerate(rec.phases):
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
    return _finish(GyroCalibration, "gyroscope", rec, opts,
                   {"rates_rad_s": tuple(float(r) for r in rates)},
                   f"the rate table needs constant-rate phases about each axis at +-{rates[0]:g} rad/s "
                   "(and/or at rest)")
