"""Analytic inputs for the automatic fit: the lecture ellipse with white, coloured (AR(1), 30 ms)
and upsampled (100 Hz interpolated to 200 Hz) pose noise, and a tracking glitch; exact truth."""

from __future__ import annotations

import numpy as np

from splineimu import fit, lie
from splineimu.scenes import make_scene

POS_NOISE_M = 1e-3
ANGLE_NOISE_RAD = np.radians(0.1)
_SCENES = {}


def scene(duration_s):
    if duration_s not in _SCENES:
        _SCENES[duration_s] = make_scene("ellipse", duration_s=duration_s)
    return _SCENES[duration_s]


def scene_poses(name, kind, duration_s, rate_hz=200.0, seed=0, scale=1.0, angle_scale=None):
    """``(scene, t, positions, world_R_body)``: a named scene sampled at ``rate_hz`` with pose noise
    of ``kind`` (``scale`` x 1 mm / ``angle_scale`` (default ``scale``) x 0.1 deg; the positions'
    noise drawn first)."""
    sc = make_scene(name, duration_s=duration_s)
    t = np.arange(0.0, duration_s + 1e-9, 1.0 / rate_hz)
    k = sc.kinematics(t)
    rng = np.random.default_rng(seed)
    p = k.position_world + noise(kind, t.size, rate_hz, POS_NOISE_M * scale, rng)
    angle = ANGLE_NOISE_RAD * (scale if angle_scale is None else angle_scale)
    R = k.world_R_body @ lie.so3_exp(noise(kind, t.size, rate_hz, angle, rng))
    return sc, t, p, R


def noise(kind, n, rate_hz, sigma, rng):
    """(n, 3) pose noise of standard deviation ``sigma`` per axis."""
    if kind in ("white", "glitch"):
        return sigma * rng.normal(size=(n, 3))
    if kind == "ar1":  # correlation time 30 ms
        rho = np.exp(-1.0 / (rate_hz * 0.03))
        e = rng.normal(size=(n, 3)) * sigma * np.sqrt(1 - rho**2)
        x = np.empty((n, 3))
        x[0] = sigma * rng.normal(size=3)
        for i in range(1, n):
            x[i] = rho * x[i - 1] + e[i]
        return x
    if kind == "upsampled":  # noise drawn at half the rate, linearly interpolated
        m = n // 2 + 2
        c = sigma * rng.normal(size=(m, 3))
        ti = np.arange(n) / 2.0
        return np.column_stack([np.interp(ti, np.arange(m), c[:, j]) for j in range(3)])
    if kind == "clean":
        return np.zeros((n, 3))
    raise ValueError(kind)


def poses(kind, duration_s=60.0, rate_hz=200.0, seed=0):
    """``(t, positions, quat_xyzw)``; the glitch moves 40 ms of poses by 5 cm at t = duration / 2."""
    t = np.arange(0.0, duration_s + 1e-9, 1.0 / rate_hz)
    k = scene(duration_s).kinematics(t)
    rng = np.random.default_rng(seed)
    p = k.position_world + noise(kind, t.size, rate_hz, POS_NOISE_M, rng)
    R = k.world_R_body @ lie.so3_exp(noise(kind, t.size, rate_hz, ANGLE_NOISE_RAD, rng))
    if kind == "glitch":
        g = (t >= duration_s / 2) & (t < duration_s / 2 + 0.04)
        p[g] += np.array([0.05, 0.0, 0.0])
    return t, p, lie.matrix_to_quat_xyzw(R)


def imu_errors(spl, duration_s, margin=1.0, exclude=None):
    """RMS gyro [rad/s] and specific-force [m/s^2] errors on [margin, duration - margin] at 200 Hz,
    optionally without the samples within ``exclude = (t, half_width)``."""
    t = np.arange(margin, duration_s - margin, 0.005)
    if exclude is not None:
        t = t[np.abs(t - exclude[0]) > exclude[1]]
    g, f = spl.imu(t)
    g0, f0 = scene(duration_s).imu(t)

    def rms(e):
        return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))

    return rms(g - g0), rms(f - f0)


#: The fixed grid the automatic fit is compared with in the benchmarks (orders 4-6 x 19 spacings
#: 5 ms-2.56 s, one spacing for rotation and position).
FIXED_GRID = tuple((k, float(dt)) for k in (4, 5, 6) for dt in np.geomspace(0.005, 2.56, 19))


def scene_errors(sc, spl, duration_s, margin=1.0, exclude=None):
    """RMS gyro [rad/s] and specific-force [m/s^2] errors of ``spl`` against scene ``sc`` on
    [margin, duration - margin] at 200 Hz, optionally without the samples within ``exclude = (t,
    half_width)``."""
    te = np.arange(margin, duration_s - margin, 0.005)
    if exclude is not None:
        te = te[np.abs(te - exclude[0]) > exclude[1]]
    (g0, f0), (g, f) = sc.imu(te), spl.imu(te)
    return (float(np.sqrt(np.mean(np.sum((g - g0) ** 2, axis=1)))),
            float(np.sqrt(np.mean(np.sum((f - f0) ** 2, axis=1)))))


def fixed_grid_errors(sc, t, p, q, duration_s, path=None):
    """(len(FIXED_GRID), 2) array of :func:`scene_errors` of each fixed setting's fit (without
    outlier rejection); kept in the .npy file ``path`` if given (they do not depend on the
    automatic choice, so a change to it is measured again in a minute)."""
    from pathlib import Path

    path = None if path is None else Path(path)
    if path is not None and path.exists():
        return np.load(path)
    grid = np.array([scene_errors(sc, fit(t, p, q, order=k, knot_spacing_s=dt, reject_outliers=False), duration_s)
                     for k, dt in FIXED_GRID])
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.save(path, grid)
    return grid


def best_fixed(t, p, q, duration_s, settings, exclude=None):
    """Best gyro and best accel error over fixed (order, spacing) settings (one spacing for both)."""
    errs = [imu_errors(fit(t, p, q, order=k, knot_spacing_s=dt, reject_outliers=exclude is None), duration_s,
                       exclude=exclude) for k, dt in settings]
    return min(e[0] for e in errs), min(e[1] for e in errs)


def gyro_error(sc, duration_s, margin=1.0):
    """A function of a spline: its RMS gyro error [rad/s] against scene ``sc`` on [margin,
    duration - margin] at 200 Hz."""
    te = np.arange(margin, duration_s - margin, 0.005)
    g0 = sc.imu(te)[0]
    return lambda spl: float(np.sqrt(np.mean(np.sum((spl.imu(te)[0] - g0) ** 2, axis=1))))


#: Hand-held positions (three sines per axis: amplitude [m], rate [rad/s], phase), 0.4-1.3 Hz.
HAND_SINES = (
    ((0.1181, 2.4644, 1.3290), (0.2846, 6.8342, 1.5501), (0.2170, 4.0027, 0.8443)),
    ((0.2470, 3.0625, 2.5929), (0.2084, 3.4788, 2.9361), (0.2321, 8.2203, 2.9064)),
    ((0.1207, 4.0617, 4.4562), (0.0938, 2.6852, 0.8968), (0.1801, 6.1128, 2.2058)),
)
#: A car's positions: loops of 50-100 m at 0.008-0.04 Hz, 4 cm of bumps at 0.4-0.9 Hz.
CAR_SINES = (
    ((31.9739, 0.2456, 0.1372), (42.9665, 0.0526, 0.1493), (23.6169, 0.0981, 1.3290)),
    ((56.9275, 0.2338, 1.5501), (43.3916, 0.1459, 0.8443), (49.3930, 0.1167, 2.5929)),
    ((0.0347, 2.5926, 2.9361), (0.0387, 5.5356, 2.9064)),
)


def sine_positions(t, table=HAND_SINES, r=0):
    """The r-th derivative (0 or 2) of positions given as sums of sines per axis, (N, 3)."""
    sign = 1.0 if r == 0 else -1.0
    return np.column_stack([sum(sign * a * w**r * np.sin(w * t + ph) for a, w, ph in axis) for axis in table])


def received(name, seed, duration=30.0, stalls=True, jitter=True, delays=(0.001, 0.010), rate=50.0):
    """``(scene, capture times, receive times, positions, quat_xyzw)`` of mocap at ``rate`` logged
    on arrival (splineimu.stamps): 7% of the frames dropped, 1-10 ms delivery delays, and
    (``stalls``) one frame in 150 held 100-270 ms with the frames queued behind it, delivered 0.1
    ms apart; 0.3 mm / 0.05 deg pose noise."""
    sc = make_scene(name, duration_s=duration)
    rng = np.random.default_rng(seed)
    tc = np.arange(0.0, duration, 1.0 / rate)
    tc = tc[rng.random(tc.size) > 0.07]
    k = sc.kinematics(tc)
    p = k.position_world + 3e-4 * rng.normal(size=(tc.size, 3))
    q = lie.matrix_to_quat_xyzw(k.world_R_body @ lie.so3_exp(np.radians(0.05) * rng.normal(size=(tc.size, 3))))
    tr = tc + (rng.uniform(*delays, tc.size) if jitter else 0.001)
    i = 0
    while stalls and i < tc.size:
        if rng.random() < 1.0 / 150.0:
            end = tc[i] + rng.uniform(0.1, 0.27)
            j = int(np.searchsorted(tc, end))
            tr[i:j] = end + 1e-4 * np.arange(j - i)
            i = j
        else:
            i += 1
    for i in range(1, tr.size):  # delivered in order, 0.1 ms apart at least
        tr[i] = max(tr[i], tr[i - 1] + 1e-4)
    return sc, tc, tr, p, q
