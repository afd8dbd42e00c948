"""Stretches of motion the knots do not follow (a landing, a knock) are told with their time range
and the IMU error they make there (``motion_not_followed``), and noise is not taken for them."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu import fit, lie
from splineimu.spline.surrogate import residual_bursts

RATE_HZ = 200.0
BURST_S = (30.0, 31.0)


def _motion(t, amp_m, amp_rad, f_hz=5.0):
    """Slow motion (an ellipse, yaw, roll) and, over BURST_S, a burst at ``f_hz`` of ``amp_m``
    along z and ``amp_rad`` of roll under a raised-cosine envelope."""
    a, b = BURST_S
    env = np.where((t >= a) & (t <= b), 0.5 * (1.0 - np.cos(2.0 * np.pi * (t - a) / (b - a))), 0.0)
    burst = env * np.sin(2.0 * np.pi * f_hz * (t - a))
    p = np.stack([np.cos(2 * np.pi * t / 10), 0.6 * np.sin(2 * np.pi * t / 10),
                  1.0 + 0.1 * np.sin(2 * np.pi * t / 7) + amp_m * burst], axis=1)
    zero = np.zeros_like(t)
    yaw = 2 * np.pi * t / 10 + 0.3 * np.sin(2 * np.pi * t / 4)
    roll = 0.2 * np.sin(2 * np.pi * t / 6) + amp_rad * burst
    R = lie.so3_exp(np.stack([zero, zero, yaw], axis=1)) @ lie.so3_exp(np.stack([roll, zero, zero], axis=1))
    return p, R


def _truth(t, *args):
    """Acceleration (world) and body rate by central differences of :func:`_motion` (h = 1e-4 s)."""
    h = 1e-4
    (pm, Rm), (p0, _), (pp, Rp) = (_motion(t + d, *args) for d in (-h, 0.0, h))
    return (pp - 2.0 * p0 + pm) / h**2, lie.so3_log(np.swapaxes(Rm, 1, 2) @ Rp) / (2.0 * h)


def _fit(amp_m, amp_rad, seed=1):
    t = np.arange(0.0, 60.0, 1.0 / RATE_HZ)
    p, R = _motion(t, amp_m, amp_rad)
    rng = np.random.default_rng(seed)
    P = p + 1e-3 * rng.normal(size=p.shape)
    Rn = R @ lie.so3_exp(np.radians(0.1) * rng.normal(size=p.shape))
    return fit(t, P, lie.matrix_to_quat_xyzw(Rn), return_report=True)


@pytest.fixture(scope="module")
def burst_fit():
    return _fit(5e-3, 0.02)


def test_a_burst_of_motion_is_told_with_its_time_range_and_error(burst_fit):
    """5 mm / 0.02 rad at 5 Hz over 1 s under 1 mm / 0.1 deg noise: the knots (0.6-1.4 s, set by
    the slow motion elsewhere) miss it, accel 2.2 m/s^2 and gyro 0.27 rad/s off there (the
    predicted errors elsewhere are 0.002-0.006 and 0.001-0.003). Both are told over the burst,
    each with its error within 1.5x of the measured one (2.25 and 0.27 told for 2.22 and 0.27)."""
    spl, rep = burst_fit
    told = {w.message.split(" poses ")[0].split()[-1]: w for w in rep.warnings if w.code == "motion_not_followed"}
    assert set(told) == {"position", "rotation"}, [w.message for w in rep.warnings]
    te = np.arange(*BURST_S, 1.0 / 400.0)
    acc, omega = _truth(te, 5e-3, 0.02)
    measured = {"position": np.sqrt(np.mean(np.sum((spl.acceleration_world(te) - acc) ** 2, axis=1))),
                "rotation": np.sqrt(np.mean(np.sum((spl.angular_velocity_body(te) - omega) ** 2, axis=1)))}
    assert measured["position"] > 1.0 and measured["rotation"] > 0.1  # (the case is what it says)
    for key, w in told.items():
        assert w.t_start_s <= BURST_S[0] + 0.5 and w.t_end_s >= BURST_S[1] - 0.5 and w.t_end_s - w.t_start_s <= 2.5
        value = float(w.message.split("is off by ~")[1].split()[0])
        assert measured[key] / 1.5 <= value <= 1.5 * measured[key], (key, value, measured[key])
        d = w.to_dict(origin_ns=10**18)
        assert d["t_start_ns"] == 10**18 + round(w.t_start_s * 1e9) and d["t_end_ns"] > d["t_start_ns"]


def test_the_same_motion_without_the_burst_is_not_told():
    _, rep = _fit(0.0, 0.0)
    assert "motion_not_followed" not in {w.code for w in rep.warnings}, [w.message for w in rep.warnings]


def test_bursts_of_noise_are_not_taken_for_motion():
    """White noise whose level rises 5x for 1 s (broadband: its top octave rises too), and AR(1)
    noise of 30 ms: no window is read as motion; a 5 Hz burst of 3 mm in the same noise is, with
    the second derivative of its part of the residual (1.32 m/s^2 RMS over the window, 1.56
    read: the noise under it adds to its peak)."""
    t = np.arange(0.0, 60.0, 1.0 / RATE_HZ)
    rng = np.random.default_rng(3)
    keep = np.ones(t.size, dtype=bool)
    white = 1e-3 * rng.normal(size=(t.size, 3))
    louder = white * np.where((t >= 30.0) & (t < 31.0), 5.0, 1.0)[:, None]
    assert residual_bursts(t, louder, keep, 2) == []
    ar = np.zeros_like(white)
    phi = np.exp(-1.0 / (RATE_HZ * 0.03))
    for i in range(1, t.size):
        ar[i] = phi * ar[i - 1] + np.sqrt(1.0 - phi**2) * white[i]
    assert residual_bursts(t, ar, keep, 2) == []
    a, b = 30.0, 31.0
    env = np.where((t >= a) & (t <= b), 0.5 * (1.0 - np.cos(2.0 * np.pi * (t - a))), 0.0)
    burst = np.zeros_like(white)
    burst[:, 2] = 3e-3 * env * np.sin(2.0 * np.pi * 5.0 * (t - a))
    found = residual_bursts(t, white + burst, keep, 2)
    assert found and all(a - 1.0 <= w[0] and w[1] <= b + 1.0 for w in found)
    inside = (t >= a) & (t <= b)
    accel = np.sqrt(np.mean(np.gradient(np.gradient(burst[:, 2], t), t)[inside] ** 2))  # 1.32 m/s^2
    best = max(found, key=lambda w: w[2])
    assert best[0] == pytest.approx(a, abs=0.01) and 4.0 <= best[3] <= 6.0
    assert accel <= best[2] <= 1.3 * accel, (best, accel)


def test_dropped_poses_and_gaps_leave_their_windows_out():
    """A window holding a pose the fit did not follow, or a gap, is not read: a burst there is the
    glitch's or the gap's, told by their own checks."""
    t = np.arange(0.0, 60.0, 1.0 / RATE_HZ)
    rng = np.random.default_rng(4)
    res = 1e-3 * rng.normal(size=(t.size, 3))
    burst = (t >= 30.0) & (t <= 31.0)
    res[burst, 2] += 3e-3 * np.sin(2.0 * np.pi * 5.0 * (t[burst] - 30.0)) * np.sin(np.pi * (t[burst] - 30.0))
    keep = np.ones(t.size, dtype=bool)
    assert residual_bursts(t, res, keep, 2)  # read where every pose is followed
    dropped = keep & ~((t >= 30.2) & (t <= 30.6))
    assert residual_bursts(t, res, dropped, 2) == []
    assert residual_bursts(t[dropped], res[dropped], keep[dropped], 2) == []


def test_burst_taper_is_scipys_tukey_window():
    """The windows' taper equals scipy.signal.windows.tukey (surrogate._tukey avoids importing
    scipy.signal into every fit)."""
    from scipy.signal.windows import tukey

    from splineimu.spline.surrogate import _tukey

    for m in (32, 200, 201):
        np.testing.assert_allclose(_tukey(m), tukey(m, 0.5), rtol=0, atol=1e-12)
