"""The automatic knot choice on analytic input with exact truth: white, coloured (AR(1), 30 ms)
and upsampled pose noise, a tracking glitch, fast rotation, low-rate input, long input.

Acceptance (issue 13): auto <= 1.15x the best fixed setting per quantity on white noise,
<= 1.3x on coloured and upsampled noise; predicted / measured in [1/3, 3]; a 5 cm, 40 ms glitch
dropped or warned with its time range and the accel elsewhere <= 1.3x the best.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fit_scenes import (
    CAR_SINES,
    best_fixed,
    gyro_error,
    imu_errors,
    noise,
    poses,
    scene_errors,
    scene_poses,
    sine_positions,
)

from splineimu import fit, lie
from splineimu.errors import InputError
from splineimu.scenes import make_scene
from splineimu.spline import knots
from splineimu.spline.signals import MAX_CONTROL_TURN_RAD

RATIO = {"white": 1.15, "ar1": 1.3, "upsampled": 1.3}


def _around(rep, steps=(-2, -1, 0, 1, 2)):
    """Fixed settings around the automatic choice: both grids' spacings, every order."""
    out = set()
    for dt in (rep.knot_spacing_s, rep.position_knot_spacing_s):
        for k in (4, 5, 6):
            for j in steps:
                out.add((k, round(dt * 1.25**j, 6)))
    return sorted(out)


@pytest.mark.parametrize("kind", ["white", "ar1", "upsampled"])
def test_auto_matches_the_best_fixed_setting(kind):
    dur = 30.0
    t, p, q = poses(kind, dur, seed=1)
    spl, rep = fit(t, p, q, return_report=True)
    eg, ea = imu_errors(spl, dur)
    bg, ba = best_fixed(t, p, q, dur, _around(rep, (-1, 0, 1)))
    assert eg <= RATIO[kind] * bg and ea <= RATIO[kind] * ba, (kind, eg / bg, ea / ba, rep.summary())
    # predicted errors are credible: within a factor 3 of the measured ones
    assert 1 / 3 <= rep.predicted_gyro_rms_rad_s / eg <= 3, (rep.predicted_gyro_rms_rad_s, eg)
    assert 1 / 3 <= rep.predicted_accel_rms_m_s2 / ea <= 3, (rep.predicted_accel_rms_m_s2, ea)
    assert rep.warnings == [], [w.message for w in rep.warnings]
    assert rep.dropped_poses == []


def test_prediction_is_stable_across_noise_seeds():
    dur = 30.0
    preds, meas = [], []
    for seed in (2, 3, 4):
        t, p, q = poses("white", dur, seed=seed)
        spl, rep = fit(t, p, q, return_report=True)
        preds.append((rep.predicted_gyro_rms_rad_s, rep.predicted_accel_rms_m_s2))
        meas.append(imu_errors(spl, dur))
    ratio = np.array(preds) / np.array(meas)
    # measured: predicted / measured 0.85 .. 1.19 (gyro), 0.85 .. 0.99 (accel); predictions
    # within 1.3x of each other (the old spectral floor moved 800x between seeds)
    assert np.all((ratio > 1 / 3) & (ratio < 3)), ratio
    preds = np.array(preds)
    assert np.all(preds.max(axis=0) <= 2.0 * preds.min(axis=0)), preds


@pytest.mark.parametrize(("scene_name", "scale", "kind", "quantity", "before"), [
    ("ellipse", 0.01, "upsampled", 0, 0.22),
    ("ellipse", 0.1, "white", 0, 0.52),
    ("rate-table", 0.01, "white", 1, 3.35),
    ("six-position", 0.1, "white", 1, 3.08),
])
def test_predictions_of_slow_rotation_at_low_noise(scene_name, scale, kind, quantity, before):
    """Slow rotation about moving axes with little pose noise (scale x 1 mm / 0.1 deg), 60 s at
    200 Hz: the gyro's error is mostly the rotation spline's own bias, which the choice's R3
    proxy (the accumulated increments) underrates 2-11x; the accelerometer's is gravity tilted by
    the orientation error, whose noise part the sloped continuation of the noise spectrum
    overstated 3x. Predicted / measured before (``before``) and now (measured 1.01-1.97)."""
    dur = 60.0
    sc, t, p, R = scene_poses(scene_name, kind, dur, scale=scale)
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    te = np.arange(1.0, dur - 1.0, 0.005)
    err = spl.imu(te)[quantity] - sc.imu(te)[quantity]
    measured = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
    predicted = (rep.predicted_gyro_rms_rad_s, rep.predicted_accel_rms_m_s2)[quantity]
    assert 0.6 <= predicted / measured <= 2.2, (predicted / measured, before)


def test_slow_rotation_at_a_high_rate_checks_its_bias_on_one_window():
    """60 s of the circle scene at 500 Hz (30 001 poses, rotation knots 2 s): the rotation bias
    check wants 40 knots (40 000 poses) and takes at most the cross-validation's window
    (MAX_CV_POSES); it had asked for one window of 40 000 and stopped with a ValueError.
    Measured predicted / measured gyro 1.40."""
    dur = 60.0
    sc, t, p, R = scene_poses("circle", "white", dur, rate_hz=500.0)
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    te = np.arange(1.0, dur - 1.0, 0.005)
    measured = float(np.sqrt(np.mean(np.sum((spl.imu(te)[0] - sc.imu(te)[0]) ** 2, axis=1))))
    assert 0.6 <= rep.predicted_gyro_rms_rad_s / measured <= 2.2, (rep.predicted_gyro_rms_rad_s, measured)


def test_glitch_is_dropped_with_its_time_range():
    dur = 30.0
    t, p, q = poses("glitch", dur, seed=1)
    spl, rep = fit(t, p, q, return_report=True)
    glitch = np.flatnonzero((t >= 15.0) & (t < 15.04))
    assert sorted(rep.dropped_poses) == glitch.tolist()
    w = [w for w in rep.warnings if w.code == "outliers_dropped"]
    assert len(w) == 1 and w[0].t_start_s == t[glitch[0]] and w[0].t_end_s == t[glitch[-1]]
    assert rep.to_dict()["warnings"][0]["t_start_ns"] == int(round(t[glitch[0]] * 1e9))
    # elsewhere as good as the best fixed setting on the same noise without the glitch
    ea = imu_errors(spl, dur, exclude=(15.02, 1.0))[1]
    tw, pw, qw = poses("white", dur, seed=1)
    ba = best_fixed(tw, pw, qw, dur, _around(rep, (-1, 0, 1)), exclude=(15.02, 1.0))[1]
    assert ea <= 1.3 * ba, (ea, ba)


def test_glitch_in_fast_motion_is_dropped_and_leaves_the_choice_alone():
    """The same 5 cm, 40 ms glitch in the flips scene (17 rad/s, position knots ~118 ms): the
    first fit spreads its residual onto two valid neighbours each side, which join the run of
    outliers, so the jumps lie inside the run. Measured: before, not dropped (warned as a jump)
    and the choice, made with the glitch, took order 5 where order 6 is right: accel elsewhere
    0.237 against 0.152 without the glitch. Now the 8 poses are dropped, the choice is made again
    without them, and the spline equals the one from the clean poses."""
    dur = 60.0
    sc, t, p, R = scene_poses("flips", "white", dur)
    q = lie.matrix_to_quat_xyzw(R)
    glitch = (t >= 30.0) & (t < 30.04)
    pg = p.copy()
    pg[glitch] += [0.05, 0.0, 0.0]
    spl, rep = fit(t, pg, q, return_report=True)
    clean, rep0 = fit(t, p, q, return_report=True)
    assert sorted(rep.dropped_poses) == np.flatnonzero(glitch).tolist()
    assert (rep.position_order, rep.position_knot_spacing_s) == (rep0.position_order, rep0.position_knot_spacing_s)
    te = np.arange(1.0, dur - 1.0, 0.005)
    te = te[np.abs(te - 30.02) > 1.0]
    f0 = sc.imu(te)[1]

    def accel_err(s):
        return float(np.sqrt(np.mean(np.sum((s.imu(te)[1] - f0) ** 2, axis=1))))

    assert accel_err(spl) <= 1.02 * accel_err(clean), (accel_err(spl), accel_err(clean))


@pytest.mark.parametrize("deg", [60.0, 89.0])
def test_fast_yaw_is_followed(deg):
    t = np.arange(0, 5.0 + 1e-9, 0.01)
    rate = np.radians(deg) / 0.01
    q = np.c_[np.zeros((t.size, 2)), np.sin(rate * t / 2), np.cos(rate * t / 2)]
    spl, rep = fit(t, np.zeros((t.size, 3)), q, return_report=True)
    g = spl.imu(np.linspace(0.2, 4.8, 500))[0]
    # measured: 2e-13 relative
    np.testing.assert_allclose(g[:, 2], rate, rtol=1e-9)
    assert rep.knot_spacing_s * rate <= MAX_CONTROL_TURN_RAD * (1 + 1e-9), rep.knot_spacing_s


def test_turns_that_cannot_be_told_apart_are_refused():
    t = np.arange(0, 2.0 + 1e-9, 0.01)
    yaw = np.radians(120.0) / 0.01 * t
    q = np.c_[np.zeros((t.size, 2)), np.sin(yaw / 2), np.cos(yaw / 2)]
    with pytest.raises(InputError, match="rotate by 120.0 deg"):
        fit(t, np.zeros((t.size, 3)), q)


def test_low_rate_input_gets_spacing_at_or_below_the_pose_spacing():
    """20 Hz poses of smooth fast motion (as a re-estimated ground truth): the best spacing is at
    or below the pose spacing, where the old 2x floor forbade it."""
    dur = 30.0
    t, p, q = poses("clean", dur, rate_hz=20.0)
    spl, rep = fit(t, p, q, return_report=True)
    assert rep.position_knot_spacing_s <= 0.05 and rep.knot_spacing_s <= 0.05, rep.summary()
    eg, ea = imu_errors(spl, dur)
    bg, ba = best_fixed(t, p, q, dur, [(k, dt) for k in (4, 6) for dt in (0.035, 0.05, 0.07, 0.1)])
    # exact poses: both sit at 1e-8..1e-7 (measured gyro 7.3e-8 against 4.9e-8), far below any
    # noise; the real 20 Hz pair (test_fit_real.py) checks the ratio where it matters
    assert eg <= 1.15 * bg + 1e-6 and ea <= 1.15 * ba + 1e-5, (eg, bg, ea, ba)


@pytest.mark.parametrize("rate_hz", [2.0, 5.0, 20.0])
def test_ends_of_exact_low_rate_input_are_predicted(rate_hz):
    """Exact ellipse poses at 2-20 Hz: the one-sided fit over the first and last k spacings
    misses motion the interior's fit follows (accel 0.2-2.4 m/s^2 there against 3e-2-4e-4
    inside). The ends' prediction counts it (measured by truncation); with the noise part alone
    it predicted 0.1, 3e-4 and 1e-6 m/s^2 for measured 2.36, 0.80 and 0.21, and from 2 and 5 Hz
    nothing was warned."""
    dur = 60.0
    sc = make_scene("ellipse", duration_s=dur)
    t = np.arange(0.0, dur + 1e-9, 1.0 / rate_hz)
    k = sc.kinematics(t)
    spl, rep = fit(t, k.position_world, lie.matrix_to_quat_xyzw(k.world_R_body), return_report=True)
    c = rep.knot_choice["position"]
    te = np.arange(0.0, dur, 0.005)
    e = np.sum((spl.imu(te)[1] - sc.imu(te)[1]) ** 2, axis=1)
    z = c["end_zone_s"]
    ends = np.sqrt(max(np.mean(e[te <= z]), np.mean(e[te >= dur - z])))
    assert 1 / 3 <= c["end_predicted_rms"] / ends <= 3, (c["end_predicted_rms"], ends)
    warned = [w for w in rep.warnings if w.code == "ends_less_accurate"]
    # warned where the ends' accel is off by more than 1 m/s^2 (and the prediction says so)
    assert bool(warned) == (c["end_predicted_rms"] > 1.0), [w.message for w in rep.warnings]
    assert warned or ends < 1.0
    if rate_hz == 20.0:  # its top octave is rounding: blocks of 0.1 s, not of 4 poses (ends 11 m/s^2)
        assert ends < 0.5, ends  # 0.21


def test_separate_grids_are_reported():
    t, p, q = poses("white", 20.0, seed=5)
    spl, rep = fit(t, p, q, return_report=True)
    d = rep.to_dict()
    for key in ("order", "knot_spacing_s", "position_order", "position_knot_spacing_s", "predicted_gyro_rms_rad_s",
                "predicted_accel_rms_m_s2", "warnings"):
        assert key in d
    # rotation is smoother than position on this scene
    assert rep.knot_spacing_s > 1.5 * rep.position_knot_spacing_s, rep.summary()
    assert spl.dt_s == rep.knot_spacing_s and spl.position_dt_s == rep.position_knot_spacing_s
    # fixed settings for each grid
    spl2 = fit(t, p, q, order=5, knot_spacing_s=0.5, position_order=6, position_knot_spacing_s=0.3)
    assert (spl2.order, spl2.position_order) == (5, 6)
    assert abs(spl2.dt_s - 0.5) < 0.01 and abs(spl2.position_dt_s - 0.3) < 0.01


def test_no_warning_on_the_bundled_example():
    path = Path(__file__).resolve().parent.parent / "examples" / "ellipse_mocap.tum"
    a = np.loadtxt(path)
    rep = fit(a[:, 0] - a[0, 0], a[:, 1:4], a[:, 4:8], return_report=True)[1]
    assert rep.warnings == [], [w.message for w in rep.warnings]
    assert rep.predicted_accel_rms_m_s2 < 0.1 and rep.predicted_gyro_rms_rad_s < 0.01


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["white", "ar1", "upsampled"])
def test_auto_against_the_full_grid(kind):
    dur = 60.0
    t, p, q = poses(kind, dur)
    spl, rep = fit(t, p, q, return_report=True)
    eg, ea = imu_errors(spl, dur)
    grid = [(k, float(dt)) for k in (4, 5, 6) for dt in np.geomspace(0.02, 2.0, 21)]
    bg, ba = best_fixed(t, p, q, dur, grid)
    assert eg <= RATIO[kind] * bg and ea <= RATIO[kind] * ba, (kind, eg / bg, ea / ba)
    assert 1 / 3 <= rep.predicted_gyro_rms_rad_s / eg <= 3
    assert 1 / 3 <= rep.predicted_accel_rms_m_s2 / ea <= 3


@pytest.mark.slow
def test_one_hour_is_as_good_as_one_minute():
    """1 mm / 0.1 deg white pose noise on the ellipse at 200 Hz: the hour's IMU errors equal the
    minute's (measured 0.97x gyro, 1.00x accel; same orders and spacings within 0.5%)."""
    errs = {dur: imu_errors(fit(*poses("white", dur)), dur) for dur in (60.0, 3600.0)}
    assert errs[3600.0][0] <= 1.1 * errs[60.0][0] and errs[3600.0][1] <= 1.1 * errs[60.0][1], errs


@pytest.mark.slow
def test_one_hour_of_exact_poses_is_as_good_as_one_minute():
    """Exact ellipse poses: the hour's IMU errors are the minute's (issue 13, item 5: within 2x).
    Measured gyro 1.14e-8 against 1.14e-8 rad/s, accel 3.2e-9 against 3.7e-9 m/s^2. Two float
    roundings that grow with time held the hour at 9.6e-8 m/s^2 (26x): the spline parameter ``s
    = (t - t0) / dt`` in one float (steps of 1.2e-10 at 6.5e5 segments: each pose moved by 6e-13
    s; now the segment and the fraction, :func:`splineimu.spline.banded.segments`) and the
    scene's own ``sin(K t)`` (``K t`` rounded by 2e-13 rad at 3600 s: 1e-12 m of noise on the
    positions; now reduced exactly, :mod:`splineimu.exactfloat`). Earlier, the rotation signal
    summed over the hour read its rounding as noise (21 ms knots, gyro 4.9e-8); it is summed
    from zero in each cross-validated window."""
    errs = {dur: imu_errors(fit(*poses("clean", dur)), dur) for dur in (60.0, 3600.0)}
    assert errs[3600.0][0] <= 2.0 * errs[60.0][0] and errs[3600.0][1] <= 2.0 * errs[60.0][1], errs
    assert errs[60.0][0] <= 3e-8 and errs[60.0][1] <= 1e-8, errs


def test_long_rotation_signal_is_summed_per_window(monkeypatch):
    """Inputs longer than the cross-validated length are windowed; each window's rotation
    signal is the sum of its own increments from zero, not a stretch of a sum over all poses
    (whose rounding grows with the turn accumulated before it)."""
    from splineimu.spline import crossval

    monkeypatch.setattr(crossval, "MAX_CV_POSES", 600)
    monkeypatch.setattr(crossval, "MIN_WINDOW_S", 0.1)
    n = 3000
    t = np.arange(n) * 0.005
    inc = np.random.default_rng(1).normal(size=(n - 1, 3))
    inc[:, 2] += 100.0  # 1e4 rad of accumulated turn a minute
    wins = crossval._windows(t, inc, np.ones(n), increments=True)
    assert len(wins) == crossval._N_WINDOWS
    last = wins[-1]
    a = n - last.t.size
    assert last.X[0].tolist() == [0.0, 0.0, 0.0]
    np.testing.assert_array_equal(last.X[1], inc[a])
    np.testing.assert_allclose(last.X[-1], inc[a:].sum(axis=0), rtol=1e-13)
    whole = crossval._windows(t[:500], inc[:499], np.ones(500), increments=True)
    assert len(whole) == 1
    np.testing.assert_array_equal(whole[0].X, np.vstack([np.zeros(3), np.cumsum(inc[:499], axis=0)]))


def test_quaternion_noise_ignores_sign():
    t, p, q = poses("white", 10.0, seed=6)
    flips = np.where(np.random.default_rng(0).random(t.size) < 0.5, -1.0, 1.0)
    a = fit(t, p, q)
    b = fit(t, p, q * flips[:, None])
    assert (a.dt_s, a.position_dt_s) == (b.dt_s, b.position_dt_s)
    ti = np.linspace(1, 9, 200)
    np.testing.assert_allclose(a.imu(ti)[0], b.imu(ti)[0], atol=1e-12)
    assert lie is not None


def test_whole_input_warnings():
    """A given spacing far too coarse for the motion is warned about (residual against the
    noise read off third differences); 20 Hz poses of fast motion are warned as rate-limited,
    the same motion at 200 Hz with white noise is not. The exact flips' ends are less accurate
    than the interior at both rates (measured over the first and last k spacings: 20 Hz gyro
    0.34 rad/s, 200 Hz accel 1.8 m/s^2, against 0.004 and 1e-4 inside) and are warned."""
    t, p, q = poses("white", 20.0)
    _, rep = fit(t, p, q, order=4, knot_spacing_s=1.0, return_report=True)
    msg = [w.message for w in rep.warnings if w.code == "residual_above_noise"]
    assert len(msg) == 1 and "position" in msg[0], [w.message for w in rep.warnings]
    _, rep = fit(t, p, q, return_report=True)
    assert [w.code for w in rep.warnings] == [], [w.message for w in rep.warnings]
    sc = make_scene("flips", duration_s=20.0)
    for rate, codes in ((20.0, ["ends_less_accurate", "input_rate_low"]), (200.0, ["ends_less_accurate"])):
        ts = np.arange(0.0, 20.0, 1.0 / rate)
        k = sc.kinematics(ts)
        _, rep = fit(ts, k.position_world, lie.matrix_to_quat_xyzw(k.world_R_body), return_report=True)
        assert [w.code for w in rep.warnings] == codes, [w.message for w in rep.warnings]


def test_residual_warning_on_exact_poses_at_rest():
    """Exact poses resting most of the time (six-position scene): the third-difference noise is
    exactly zero; a given spacing too coarse for its turns is warned about (it divided by zero)."""
    sc = make_scene("six-position", duration_s=60.0)
    t = np.arange(0.0, 60.0, 0.005)
    k = sc.kinematics(t)
    _, rep = fit(t, k.position_world, lie.matrix_to_quat_xyzw(k.world_R_body), order=4, knot_spacing_s=0.5,
                 return_report=True)
    msg = [w.message for w in rep.warnings if w.code == "residual_above_noise"]
    assert msg and "far above the third-difference pose noise (0 rad)" in msg[-1], msg


def test_predicted_accel_counts_gravity_tilted_by_the_orientation_error():
    """Slow motion (the circle scene: 0.4 rad/s, 1 mm / 0.1 deg white pose noise): the
    accelerometer's error is mostly gravity tilted by the orientation error, which the
    prediction includes (measured: predicted / measured 0.98 at 60 s; 0.18 with the position's
    error alone)."""
    from splineimu.scenes import make_scene

    dur = 30.0
    sc = make_scene("circle", duration_s=dur)
    t = np.arange(0.0, dur + 1e-9, 0.005)
    k = sc.kinematics(t)
    rng = np.random.default_rng(3)
    p = k.position_world + 1e-3 * rng.normal(size=(t.size, 3))
    R = k.world_R_body @ lie.so3_exp(np.radians(0.1) * rng.normal(size=(t.size, 3)))
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    te = np.arange(1.0, dur - 1.0, 0.005)
    f = spl.imu(te)[1] - sc.imu(te)[1]
    measured = float(np.sqrt(np.mean(np.sum(f**2, axis=1))))
    ratio = rep.predicted_accel_rms_m_s2 / measured
    assert 0.6 <= ratio <= 1.6, (rep.predicted_accel_rms_m_s2, measured)


def test_fast_smooth_rotation_walks_to_its_turn_limit():
    """The flips scene turns at up to 17.6 rad/s; with AR(1) 30 ms pose noise its gyro is best
    at 70-80 ms knots, beyond a 60-degree turn limit (55 ms), within the 90-degree one (84 ms).
    The rotation's walk is not held at WALK_MAX_S (50 ms, a limit for the position), and the fit
    converges with its control rotations turning 70-80 degrees (the prior on those beyond the
    data). Measured: 43.5 ms (walk held) -> 54.2 ms (60-degree limit) -> 80 ms (order 5); gyro
    1.6x -> 1.35x -> 1.11x the best fixed setting (order 6 at 55, 70, 80 ms)."""
    from splineimu.spline.knots import WALK_MAX_S
    from splineimu.spline.signals import max_rotation_spacing

    dur = 20.0
    sc, t, p, R = scene_poses("flips", "ar1", dur)
    q = lie.matrix_to_quat_xyzw(R)
    gyro_err = gyro_error(sc, dur)

    spl, rep = fit(t, p, q, return_report=True)
    best = min(gyro_err(fit(t, p, q, order=6, knot_spacing_s=dt, reject_outliers=False)) for dt in (0.055, 0.07, 0.08))
    assert max(WALK_MAX_S, 0.06) < rep.knot_spacing_s <= max_rotation_spacing(t, R) * (1 + 1e-9), rep.knot_spacing_s
    assert rep.converged and rep.iterations <= 8, rep.iterations
    assert gyro_err(spl) <= 1.25 * best, (gyro_err(spl), best)


def test_noisy_low_rate_poses_get_the_noise_under_their_motion():
    """Flips at 20 Hz (50 degrees per pose) with 0.1 deg white noise: the top octave holds motion,
    so the choice follows it with knots finer than the poses, and the prediction (a tenth of the
    noise surrogate there) said gyro ~0.009 rad/s for 0.098 measured (told "up to 0.15"). The
    held-out errors at three gap lengths, read as noise plus motion growing as a power of the gap,
    give the noise under the motion (0.1 deg): predicted 0.087. With a fifth of the noise (held-out
    errors grow 8x with twice the gap, noise and motion mixed): 0.0017 for 0.020 before, 0.017 now;
    the accelerometer's 0.078 for 0.54 before, 0.71 now. Exact poses of the same motion (growth
    24-29x) keep their prediction."""
    from splineimu.scenes import make_scene

    dur = 60.0
    sc = make_scene("flips", duration_s=dur)
    t = np.arange(0.0, dur + 1e-9, 0.05)
    k = sc.kinematics(t)
    te = np.arange(4.0, dur - 4.0, 0.005)
    g0, f0 = sc.imu(te)
    for scale in (1.0, 0.2):
        rng = np.random.default_rng(0)
        R = k.world_R_body @ lie.so3_exp(noise("white", t.size, 20.0, np.radians(0.1) * scale, rng))
        p = k.position_world + noise("white", t.size, 20.0, 1e-3 * scale, rng)
        spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
        g, f = spl.imu(te)
        sigma = rep.knot_choice["rotation"]["noise_under_motion"]
        assert 0.7 < sigma / np.radians(0.1 * scale) < 1.4, (scale, sigma)
        for key, e in (("rotation", g - g0), ("position", f - f0)):
            measured = float(np.sqrt(np.mean(np.sum(e**2, axis=1))))
            pred = rep.knot_choice[key]["predicted_rms"]
            assert 1 / 2 < pred / measured < 2, (scale, key, pred, measured)  # 0.86-1.5
    _, rep = fit(t, k.position_world, lie.matrix_to_quat_xyzw(k.world_R_body), return_report=True)
    assert "prediction_assumes_motion" not in [w.code for w in rep.warnings]
    assert all("noise_under_motion" not in rep.knot_choice[key] for key in ("rotation", "position"))


def test_low_rate_noise_under_slow_motion_is_smoothed():
    """Hand-held positions at 20 Hz with 0.2 mm white noise were taken for motion-limited (the
    slow motion's leakage in the plain periodogram, see test_knots_surrogate): knots of 18 ms
    followed the noise (accel 7.1x the best fixed setting in the benchmark). Read on the tapered
    periodogram as noise: 1.00x the best of the grid below (k6 136 ms; before 9.3x, 18 ms)."""
    t = np.arange(0.0, 60.0 + 1e-9, 0.05)
    rng = np.random.default_rng(1)
    p = sine_positions(t) + 2e-4 * rng.normal(size=(t.size, 3))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1))  # level and still: body = world
    te = np.arange(1.0, 59.0, 0.005)
    f0 = sine_positions(te, r=2) + [0.0, 0.0, 9.81]  # specific force: acceleration less gravity

    def accel_error(spl):
        return float(np.sqrt(np.mean(np.sum((spl.imu(te)[1] - f0) ** 2, axis=1))))

    spl, rep = fit(t, p, q, return_report=True)
    best = min(accel_error(fit(t, p, q, order=k, knot_spacing_s=dt, reject_outliers=False))
               for k in (4, 5, 6) for dt in (0.05, 0.07, 0.1, 0.136, 0.2, 0.28))
    assert not rep.knot_choice["position"]["motion_limited"]
    assert best < 0.2, best
    assert accel_error(spl) < 1.3 * best, (accel_error(spl), best, rep.summary())


def test_knots_finer_than_noisy_poses_are_told(monkeypatch):
    """A car's positions at 20 Hz with 0.2 mm noise drawn at 10 Hz and interpolated: the top of
    the band reads as noise, yet the held-out fits interpolate it (knots 35 ms for poses every
    50 ms; accel ~0.15 m/s^2, ~9x the fixed fits at 0.2-0.6 s) and the prediction said 0.008,
    nothing told. The noise is read as for motion-limited input (in blocks as long as the first
    pass's): predicted 0.07-0.08, up to 0.69-0.72 if noise, told (prediction_assumes_motion).
    That is the path where the half-rate interpolation is not seen (fast motion hides it, as
    here with checks.noise_interpolated turned off); found, the knots are chosen on the poses
    carrying the noise: 278 ms, accel 0.015 m/s^2 (predicted 0.014; fixed fits at 0.2 / 0.3 s
    0.024 / 0.017)."""
    import splineimu.spline.fit as fit_module

    t = np.arange(0.0, 60.0 + 1e-9, 0.05)
    te = np.arange(1.0, 59.0, 0.005)
    f0 = sine_positions(te, CAR_SINES, r=2) + [0.0, 0.0, 9.81]
    rng = np.random.default_rng(1)
    p = sine_positions(t, CAR_SINES) + noise("upsampled", t.size, 20.0, 2e-4, rng)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1))
    spl, rep = fit(t, p, q, return_report=True)
    measured = float(np.sqrt(np.mean(np.sum((spl.imu(te)[1] - f0) ** 2, axis=1))))
    assert [w.code for w in rep.warnings] == ["noise_interpolated"] and rep.position_knot_spacing_s > 0.2
    assert measured < 0.02 and 1.0 / 3.0 < rep.predicted_accel_rms_m_s2 / measured < 3.0, (measured, rep.summary())
    monkeypatch.setattr(fit_module, "noise_interpolated", lambda *a: None)
    spl, rep = fit(t, p, q, return_report=True)
    measured = float(np.sqrt(np.mean(np.sum((spl.imu(te)[1] - f0) ** 2, axis=1))))
    c = rep.knot_choice["position"]
    assert not c["motion_limited"] and c["knot_spacing_s"] < 0.05, rep.summary()
    assert c["predicted_rms"] / 3 < measured < c["predicted_rms_if_noise"], (measured, c["predicted_rms"])
    told = [w.message for w in rep.warnings if w.code == "prediction_assumes_motion"]
    assert len(told) == 1 and "finer than the poses (every 50 ms)" in told[0], told


def test_position_beyond_the_walk_limit_walks_on():
    """A car's positions at 10 Hz with 1 mm noise, linearly interpolated to 20 Hz (as exported
    re-estimated trajectories are): value-optimal at 135 ms, the ladder ended at 211 ms with the
    predicted error still falling (accel 0.11 m/s^2, 2.1x the best fixed setting, predicted
    alike). A position whose value-optimal spacing is beyond WALK_MAX_S walks on: 329 ms, 0.89x
    the best of the grid below (k6 300 ms)."""
    t = np.arange(0.0, 60.0 + 1e-9, 0.05)
    coarse = t[::2]
    rng = np.random.default_rng(1)
    pc = sine_positions(coarse, CAR_SINES) + 1e-3 * rng.normal(size=(coarse.size, 3))
    p = np.column_stack([np.interp(t, coarse, pc[:, j]) for j in range(3)])
    q = np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1))
    te = np.arange(1.0, 59.0, 0.005)
    f0 = sine_positions(te, CAR_SINES, r=2) + [0.0, 0.0, 9.81]

    def accel_error(spl):
        return float(np.sqrt(np.mean(np.sum((spl.imu(te)[1] - f0) ** 2, axis=1))))

    spl, rep = fit(t, p, q, return_report=True)
    best = min(accel_error(fit(t, p, q, order=6, knot_spacing_s=dt, reject_outliers=False))
               for dt in (0.15, 0.2, 0.3, 0.4, 0.6))
    c = rep.knot_choice["position"]
    assert c["cv_knot_spacing_s"] > knots.WALK_MAX_S
    assert accel_error(spl) < 1.3 * best, (accel_error(spl), best, rep.summary())
    assert 1 / 2 < c["predicted_rms"] / accel_error(spl) < 2, c["predicted_rms"]


def test_a_fit_that_does_not_converge_says_so():
    t, p, q = poses("white", 10.0)
    _, rep = fit(t, p, q, order=6, knot_spacing_s=0.05, max_iter=1, return_report=True)
    assert not rep.converged
    assert [w.code for w in rep.warnings] == ["fit_not_converged"], [w.message for w in rep.warnings]
    _, rep = fit(t, p, q, order=6, knot_spacing_s=0.05, return_report=True)
    assert rep.converged and not rep.warnings


def test_exact_static_poses_fit_without_numpy_warnings():
    """A static pose sampled exactly (5 s at 10 kHz) leaves no residual: the noise spectrum's
    slope was read from log(0) and numpy printed 'divide by zero encountered in log'."""
    import warnings

    from splineimu.scenes import make_scene

    sc = make_scene("static", duration_s=5.0)
    t = np.arange(0.0, 5.0 + 1e-9, 1e-4)
    k = sc.kinematics(t)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        spl, rep = fit(t, k.position_world, lie.matrix_to_quat_xyzw(k.world_R_body), return_report=True)
    assert np.abs(spl.imu(np.linspace(0.5, 4.5, 100))[0]).max() < 1e-9


def test_jittered_stamps_are_warned():
    """Poses of the flips scene taken every 10 ms but stamped with up to 9 ms of delay (receive
    times): 2-3% of the intervals are under 3 ms long yet hold a whole step of motion. Warned
    with the share and time range; the same poses at their true (irregular, exact) times, and
    the true stamps themselves, are not."""
    sc = make_scene("flips", duration_s=20.0)
    t = np.arange(0.0, 20.0, 0.01)
    stamps = t + 0.009 * np.random.default_rng(4).random(t.size)
    k = sc.kinematics(t)
    q = lie.matrix_to_quat_xyzw(k.world_R_body)
    _, rep = fit(stamps, k.position_world, q, return_report=True)
    (w,) = [w for w in rep.warnings if w.code == "timestamps_jittered"]
    short = int(np.count_nonzero(np.diff(stamps) < 0.003))
    n = int(w.message.split(" of ")[0])
    assert 0.8 * short <= n <= short and 0.01 * t.size < n, (n, short, w.message)
    assert w.t_start_s < 2.0 and w.t_end_s > 18.0
    ks = sc.kinematics(stamps)
    for tt, kk in ((stamps, ks), (t, k)):
        _, rep = fit(tt, kk.position_world, lie.matrix_to_quat_xyzw(kk.world_R_body), return_report=True)
        assert "timestamps_jittered" not in [w.code for w in rep.warnings], [w.message for w in rep.warnings]


def test_slow_motion_gets_knots_beyond_two_seconds():
    """The circle scene turns at 0.4 rad/s: its best fixed rotation spacing is 2.5 s or more. The
    grid goes on past 2 s (to 10 s or a quarter of the span); held at 2 s the gyro was 1.59x the
    fixed fit at 2.56 s (measured now 0.72x; order 5 at 3.75 s)."""
    sc, t, p, R = scene_poses("circle", "white", 60.0, seed=7)
    q = lie.matrix_to_quat_xyzw(R)
    te = np.arange(1.0, 59.0, 0.005)
    g0, f0 = sc.imu(te)

    def errs(spl):
        g, f = spl.imu(te)
        return [float(np.sqrt(np.mean(np.sum(e**2, axis=1)))) for e in (g - g0, f - f0)]

    spl, rep = fit(t, p, q, return_report=True)
    assert rep.knot_spacing_s > 2.5 and rep.position_knot_spacing_s > 1.0
    auto = errs(spl)
    fixed = errs(fit(t, p, q, order=5, knot_spacing_s=2.56, reject_outliers=False))
    assert auto[0] <= 0.9 * fixed[0] and auto[1] <= 1.15 * fixed[1], (auto, fixed)
    assert 0.5 <= rep.predicted_gyro_rms_rad_s / auto[0] <= 2.0


def test_high_rate_input_is_cross_validated_on_windows_of_seconds():
    """Long inputs are cross-validated on windows, whose span bounds the spacing at a quarter of
    it: 4000 poses each were 4 s at 1 kHz and 0.4 s at 10 kHz. Slow turning at 1 kHz (circle,
    60 s) got 1 s knots, gyro 4.2x the fixed fit at 2.56 s (10 kHz ellipse: 0.1 s, 14x the best
    fixed setting). Windows now span MIN_WINDOW_S at least (measured: 5.5 s knots, 0.48x)."""
    from splineimu.spline import crossval

    for rate, n, count, span in ((200.0, 720_001, 6, 20.0), (1000.0, 60_001, 1, 60.0), (10_000.0, 1_000_001, 6, 12.0)):
        t = np.arange(n) / rate
        wins = crossval._windows(t, np.zeros((n, 3)), np.ones(n))
        assert len(wins) == count and min(wd.t[-1] - wd.t[0] for wd in wins) >= span - 0.01, (rate, len(wins))
    sc, t, p, R = scene_poses("circle", "white", 60.0, rate_hz=1000.0, seed=1)
    q = lie.matrix_to_quat_xyzw(R)
    gyro_err = gyro_error(sc, 60.0)

    spl, rep = fit(t, p, q, return_report=True)
    fixed = gyro_err(fit(t, p, q, order=4, knot_spacing_s=2.56, reject_outliers=False))
    assert rep.knot_spacing_s > 2.5 and gyro_err(spl) <= 0.8 * fixed, (rep.knot_spacing_s, gyro_err(spl), fixed)


def test_rotation_signal_of_high_rate_poses_does_not_random_walk():
    """Summed body-frame increments of noisy rotations random-walk (each step's second-order
    noise term does not telescope): at 10 kHz with 0.1 deg noise the sum's 1 s means spread
    13x as far as the white noise's (measured here; 22x over 20 s), which slow fits took for
    motion (screw scene, 20 s: 0.6-0.95 s rotation knots, gyro 4-7.6x the best fixed setting,
    now 0.93-0.96x). Above 666 Hz the signal's low band comes from block-mean anchors, 3 ms long
    (measured 0.64x), 20 ms where the noise is large for the rate, as here (0.62x); exact poses
    give the plain sum's rate to 1e-10 rad/s."""
    from splineimu.spline.signals import accumulate, anchor_block, rotation_increments

    sc, t, p, R = scene_poses("screw", "white", 12.0, rate_hz=10_000.0, seed=1)
    exact = sc.kinematics(t).world_R_body
    noise = lie.so3_log(np.swapaxes(exact, 1, 2) @ R)
    block = anchor_block(t, rotation_increments(R))
    assert anchor_block(t) == 30 and block == 200
    assert anchor_block(t[::50], rotation_increments(R[::50])) == 1  # 0.1 deg at 200 Hz: none

    def wander(inc):  # per-axis spread of the 1 s means of the summed noise
        d = accumulate(inc) - accumulate(rotation_increments(exact, block)) - noise
        return float(d[: 120_000].reshape(12, 10_000, 3).mean(axis=1).std(axis=0).mean())

    white = float(noise[: 120_000].reshape(12, 10_000, 3).mean(axis=1).std(axis=0).mean())
    assert wander(rotation_increments(R)) > 5 * white
    assert wander(rotation_increments(R, 30)) < white and wander(rotation_increments(R, block)) < white
    rate_diff = np.diff(accumulate(rotation_increments(exact, block)) - accumulate(rotation_increments(exact)), axis=0)
    assert np.abs(rate_diff).max() * 10_000 < 1e-10
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    gyro_err = gyro_error(sc, 12.0)
    fixed = gyro_err(fit(t, p, lie.matrix_to_quat_xyzw(R), order=4, knot_spacing_s=2.56, reject_outliers=False))
    assert rep.knot_spacing_s > 2.0 and gyro_err(spl) <= 1.15 * fixed, (rep.knot_spacing_s, gyro_err(spl) / fixed)


def test_rotation_signal_of_very_noisy_poses_at_200_hz_does_not_random_walk():
    """The summed increments' walk grows as (noise / pose spacing)^2: at 200 Hz with 1 deg white
    noise the sum's 1 s means spread 7.9x as far as the white noise's (circle scene), which the
    choice read as the rotation's bias (1.3-2e-3 rad/s at 2-4 s knots, for a turn the spline
    follows exactly): predicted gyro 3.6x the measured. From 0.5 rad/s of noise per pose spacing
    the low band comes from 20 ms anchors (2.1x): predicted 1.01x. The noise is read within 1%."""
    from splineimu.spline.signals import accumulate, anchor_block, rotation_increments, rotation_noise

    sc, t, p, R = scene_poses("circle", "white", 60.0, rate_hz=200.0, seed=2, angle_scale=10.0)  # 1 mm / 1 deg
    exact = sc.kinematics(t).world_R_body
    noise = lie.so3_log(np.swapaxes(exact, 1, 2) @ R)
    assert rotation_noise(rotation_increments(R)) == pytest.approx(np.radians(1.0), rel=0.02)
    block = anchor_block(t, rotation_increments(R))
    assert block == 4 and anchor_block(t) == 1
    assert anchor_block(t[::2], rotation_increments(R[::2])) == 2  # 100 Hz: 0.5 deg and up

    def wander(inc):  # per-axis spread of the 1 s means of the summed noise
        d = accumulate(inc) - accumulate(rotation_increments(exact, block)) - noise
        return float(d[:12_000].reshape(60, 200, 3).mean(axis=1).std(axis=0).mean())

    white = float(noise[:12_000].reshape(60, 200, 3).mean(axis=1).std(axis=0).mean())
    assert wander(rotation_increments(R)) > 6 * white
    assert wander(rotation_increments(R, block)) < 2.5 * white
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    ratio = rep.predicted_gyro_rms_rad_s / gyro_error(sc, 60.0)(spl)
    assert 0.67 <= ratio <= 1.5, (rep.knot_spacing_s, ratio)


@pytest.mark.parametrize("size", [2, 3, 8, 40, 400])
def test_anchor_moving_mean_is_scipys_uniform_filter(size):
    """The anchors' triangular smoothing (two moving means) is scipy.ndimage's uniform_filter1d
    with the ends continued ("nearest"), to rounding, including windows longer than the data."""
    from scipy.ndimage import uniform_filter1d

    from splineimu.spline.signals import moving_mean

    x = np.cumsum(np.random.default_rng(size).normal(size=(300, 3)), axis=0)
    np.testing.assert_allclose(moving_mean(x, size), uniform_filter1d(x, size, axis=0, mode="nearest"),
                               rtol=0, atol=1e-11)


def test_very_noisy_rotation_at_1_khz_is_anchored_over_20_ms():
    """At 1 kHz the 3 ms anchors are two poses: with 1 deg of white noise the walk left was read
    as motion (screw scene, 30 s: order 5 at 1.58 s, gyro 1.84x the best fixed setting, k5 at 2.56
    s; predicted 1.79x the measured). Anchored over 20 ms: 3.33 s knots, 0.69x, predicted 1.01x."""
    from splineimu.spline.signals import anchor_block, rotation_increments

    sc, t, p, R = scene_poses("screw", "white", 30.0, rate_hz=1000.0, seed=0, angle_scale=10.0)
    q = lie.matrix_to_quat_xyzw(R)
    assert anchor_block(t) == 2 and anchor_block(t, rotation_increments(R)) == 20
    gyro_err = gyro_error(sc, 30.0)
    spl, rep = fit(t, p, q, return_report=True)
    fixed = gyro_err(fit(t, p, q, order=5, knot_spacing_s=2.56, reject_outliers=False))
    assert gyro_err(spl) <= 0.9 * fixed, (rep.order, rep.knot_spacing_s, gyro_err(spl) / fixed)
    assert 0.67 <= rep.predicted_gyro_rms_rad_s / gyro_err(spl) <= 1.5


@pytest.mark.parametrize("scene_name, spacings", [("six-position", (0.2263, 0.283)),
                                                   ("rate-table", (0.326, 0.4075, 0.4525, 0.5095))])
def test_gyro_bias_estimate_is_corrected_for_white_noise(scene_name, spacings):
    """The gyro's bias estimate (the change from the rung below) lags the bias; with white pose
    noise (drawn flat) it is multiplied by 1.4. Without it the choice landed a rung coarse:
    six-position order 5 at 283 ms, gyro 1.23x the best fixed setting (order 4 at 226 ms);
    rate-table 509 ms, 1.24x (with the doubling of a surrogate read high, 1.02x and 1.04x)."""
    sc, t, p, R = scene_poses(scene_name, "white", 60.0, seed=1)
    q = lie.matrix_to_quat_xyzw(R)
    gyro_err = gyro_error(sc, 60.0)

    spl, rep = fit(t, p, q, return_report=True)
    best = min(gyro_err(fit(t, p, q, order=k, knot_spacing_s=dt, reject_outliers=False))
               for k in (4, 5, 6) for dt in spacings)
    assert rep.knot_choice["rotation"]["bias_correction"] == knots.FLAT_WHITE_BIAS_LAG
    assert gyro_err(spl) <= 1.15 * best, (rep.order, rep.knot_spacing_s, gyro_err(spl) / best)
    assert 1 / 3 <= rep.predicted_gyro_rms_rad_s / gyro_err(spl) <= 3


def test_slow_steady_turning_gets_knots_up_to_135_degrees():
    """The screw scene turns steadily at 0.65 rad/s about one axis: knots far apart lose nothing
    but noise. Held at 90 degrees per spacing (2.4 s) its gyro was 1.11-1.28x the fixed fit at
    2.56 s; the limit is 135 degrees now (measured 0.52x the best order at 2.4 s, 3.5 s knots).
    The turn limit is found without the angle's wrap beyond pi (a steady spin: 135 deg / rate)."""
    from splineimu.spline.signals import max_rotation_spacing

    sc, t, p, R = scene_poses("screw", "white", 60.0, seed=1)
    q = lie.matrix_to_quat_xyzw(R)
    gyro_err = gyro_error(sc, 60.0)

    spl, rep = fit(t, p, q, return_report=True)
    at_90 = min(gyro_err(fit(t, p, q, order=k, knot_spacing_s=2.4, reject_outliers=False)) for k in (4, 5, 6))
    assert rep.knot_spacing_s > 3.0 and gyro_err(spl) <= 0.8 * at_90, (rep.knot_spacing_s, gyro_err(spl), at_90)
    for rate in (0.3, 0.654, 5.0, 40.0):
        ts = np.arange(0.0, 60.0, 0.005)
        Rz = lie.so3_exp(np.c_[np.zeros((ts.size, 2)), rate * ts])
        dt = max_rotation_spacing(ts, Rz)
        assert 0.85 * MAX_CONTROL_TURN_RAD <= rate * dt <= MAX_CONTROL_TURN_RAD + 1e-9, (rate, dt)


def test_orientation_flips_are_dropped():
    """Mocap orientation flips (the body's markers matched the wrong way round): one pose turned
    by 180 degrees and a run of three by 150 degrees, each back afterwards. No spline can follow
    a turn that large between poses; they are dropped before the fit (listed and warned about),
    and the rest gives the clean fit's IMU. Without outlier rejection the input is refused,
    naming the flip."""
    t, p, q = poses("white", 60.0, seed=2)
    R = lie.quat_xyzw_to_matrix(q)
    Rf = R.copy()
    one, run = 6000, np.arange(8000, 8003)
    Rf[one] = R[one] @ lie.so3_exp(np.array([np.pi, 0.0, 0.0]))
    Rf[run] = R[run] @ lie.so3_exp(np.radians([0.0, 150.0, 0.0]))
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(Rf), return_report=True)
    # the clean poses at the same settings (the choice itself may land elsewhere by a rung's
    # share: its bias estimates scatter with the data)
    clean = fit(t, p, q, order=rep.order, knot_spacing_s=rep.knot_spacing_s, position_order=rep.position_order,
                position_knot_spacing_s=rep.position_knot_spacing_s)
    assert rep.dropped_poses == [one, *run.tolist()] and rep.n_poses == t.size
    flips = [w for w in rep.warnings if w.code == "outliers_dropped"]
    assert [w.t_start_s for w in flips] == [t[one], t[run[0]]] and "orientation flip" in flips[0].message
    got, ref = imu_errors(spl, 60.0), imu_errors(clean, 60.0)
    assert got[0] <= 1.02 * ref[0] and got[1] <= 1.02 * ref[1], (got, ref)
    with pytest.raises(InputError, match=f"pose {one} .* orientation flip"):
        fit(t, p, lie.matrix_to_quat_xyzw(Rf), reject_outliers=False)


def test_stalled_wide_rotation_knots_are_chosen_again_within_90_degrees():
    """Six-position scene with 8 mm / 0.8 deg pose noise: the choice takes 669 ms rotation knots
    (113 degrees of its fastest turn), where Gauss-Newton stalls on the control rotations beyond
    the data (62 iterations, unconverged, gyro 0.039 rad/s). The rotation is then chosen again
    within 90 degrees (522 ms): converged in 4, gyro 0.016 rad/s."""
    from splineimu.spline.signals import max_rotation_spacing

    sc, t, p, R = scene_poses("six-position", "white", 60.0, seed=2, scale=8.0)
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    # (the layout fits a whole number of spacings in the span: 115 of 522 ms for 520)
    assert rep.converged and rep.knot_spacing_s <= max_rotation_spacing(t, R, np.pi / 2) * 1.01
    assert "fit_not_converged" not in [w.code for w in rep.warnings]
    te = np.arange(1.0, 59.0, 0.005)
    err = float(np.sqrt(np.mean(np.sum((spl.imu(te)[0] - sc.imu(te)[0]) ** 2, axis=1))))
    assert err < 0.03 and 1 / 3 <= rep.predicted_gyro_rms_rad_s / err <= 3, (err, rep.predicted_gyro_rms_rad_s)


def test_given_spacing_with_automatic_order_is_kept():
    """A given knot spacing with the order left automatic: the spacing is used as given (the
    grid's range and refinement replaced it: 0.05 s became 0.063 s; outside the range the choice
    crashed), and a spacing too long to choose an order over is refused with a clear error."""
    from splineimu.errors import SplineImuError

    sc, t, p, R = scene_poses("circle", "white", 20.0, rate_hz=100.0, seed=0)
    q = lie.matrix_to_quat_xyzw(R)
    for dt in (0.003, 0.05, 4.9):
        _, rep = fit(t, p, q, knot_spacing_s=dt, return_report=True)
        n = round((t[-1] - t[0]) / dt)
        assert rep.knot_spacing_s == pytest.approx((t[-1] - t[0]) / n, rel=1e-9), (dt, rep.knot_spacing_s)
        assert rep.position_knot_spacing_s == rep.knot_spacing_s
    with pytest.raises(SplineImuError, match="give the order too"):
        fit(t, p, q, knot_spacing_s=11.0)


def test_a_gap_far_longer_than_the_data_is_scored_by_its_poses():
    """20 s of poses, an hour without, 1 s more: 5% of the span from each end held almost every
    pose, so nothing was scored (numpy warned about empty means) and the choice read noise."""
    import warnings

    t = np.r_[np.arange(0.0, 20.0, 0.01), 3620.0 + np.arange(0.0, 1.0, 0.01)]
    k = make_scene("circle", duration_s=3700.0).kinematics(t)
    rng = np.random.default_rng(1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, rep = fit(t, k.position_world + 1e-3 * rng.normal(size=(t.size, 3)),
                     lie.matrix_to_quat_xyzw(k.world_R_body), return_report=True)
    assert rep.knot_spacing_s > 1.0 and rep.position_knot_spacing_s > 0.5, rep.knot_spacing_s


def test_given_knots_that_follow_the_pose_noise_are_warned():
    """Given settings get no predicted error; where the noise alone (third differences of the
    poses, through the spline's noise gain) makes it large, it is warned about. Ellipse at 100
    Hz, 1 mm / 0.1 deg: order 4 at 1, 10, 20 ms estimates 0.6-0.9x the measured accel (67, 71, 15
    m/s^2: the knots follow the noise); at 200 ms (0.12 m/s^2) nothing is said."""
    sc, t, p, R = scene_poses("ellipse", "white", 20.0, rate_hz=100.0)
    q = lie.matrix_to_quat_xyzw(R)
    te = np.arange(1.0, 19.0, 0.005)
    f0 = sc.imu(te)[1]
    for dt in (0.001, 0.01, 0.02, 0.2):
        spl, rep = fit(t, p, q, order=4, knot_spacing_s=dt, return_report=True)
        accel = float(np.sqrt(np.mean(np.sum((spl.imu(te)[1] - f0) ** 2, axis=1))))
        said = [w.message for w in rep.warnings if w.code == "knots_follow_noise" and "position" in w.message]
        if dt < 0.1:
            est = float(said[0].split("alone is ~")[1].split(" ")[0])
            assert 0.4 * accel <= est <= accel, (dt, est, accel)
        else:
            assert not said and accel < 1.0, (said, accel)


def test_rotation_stops_at_a_step_far_below_the_pose_noise(monkeypatch):
    """With the noise measured by the automatic choice, Gauss-Newton stops at a step below 1e-4
    of it instead of 1e-9 rad (flips, 0.1 deg: 3 iterations instead of 4-5): the spline moves by
    far less than its error to the truth (measured 2e-6 of it)."""
    from splineimu.spline import problem

    sc, t, p, R = scene_poses("flips", "white", 20.0, seed=2)
    q = lie.matrix_to_quat_xyzw(R)
    te = np.arange(1.0, 19.0, 0.005)
    g0 = sc.imu(te)[0]
    loose, rl = fit(t, p, q, return_report=True)
    monkeypatch.setattr(problem, "GN_STEP_REL", 0.0)
    tight, rt = fit(t, p, q, return_report=True)
    assert rl.iterations < rt.iterations, (rl.iterations, rt.iterations)
    g_loose, g_tight = loose.imu(te)[0], tight.imu(te)[0]
    err = np.sqrt(np.mean(np.sum((g_tight - g0) ** 2, axis=1)))
    assert np.sqrt(np.mean(np.sum((g_loose - g_tight) ** 2, axis=1))) < 1e-4 * err


@pytest.mark.parametrize("scene_name, warned", [("flips", True), ("ellipse", False)])
def test_gaps_are_told_with_their_error(scene_name, warned):
    """Poses missing for 0.4 s: the IMU there is the fit's guess. Fast motion (flips) gets a
    gap_bridged warning with the time range and the error inside (measured by opening gaps that
    long where there are poses): gyro 1.0 rad/s and accel 1.6 m/s^2 predicted for 2.0 and 1.5
    measured, against 0.026 and 0.15 elsewhere (it was bridged without a word); the ellipse's
    gap costs little (accel 0.050 predicted, 0.017 measured) and is not warned about."""
    sc, t, p, R = scene_poses(scene_name, "white", 30.0, seed=1)
    keep = ~((t > 10.0) & (t < 10.4))
    spl, rep = fit(t[keep], p[keep], lie.matrix_to_quat_xyzw(R[keep]), return_report=True)
    te = np.arange(10.0, 10.4, 0.002)
    g, f = spl.imu(te)
    g0, f0 = sc.imu(te)
    measured = {"rotation": float(np.sqrt(np.mean(np.sum((g - g0) ** 2, axis=1)))),
                "position": float(np.sqrt(np.mean(np.sum((f - f0) ** 2, axis=1))))}
    gaps = [w for w in rep.warnings if w.code == "gap_bridged"]
    assert bool(gaps) == warned, [w.message for w in rep.warnings]
    if warned:
        assert len(gaps) == 1 and abs(gaps[0].t_start_s - 10.0) < 0.01 and abs(gaps[0].t_end_s - 10.4) < 0.01
    for key in ("rotation", "position") if warned else ("position",):
        (gap,) = rep.knot_choice[key]["gaps"]
        # (a harmless gap's prediction is the noise of gaps opened elsewhere: 2.9x high there)
        assert 1 / 3 <= gap["predicted_rms"] / measured[key] <= (3 if warned else 4), (key, gap, measured)


def test_a_gap_too_long_to_measure_is_told():
    """12 s without poses in 30 s: no stretch of poses is long enough to open such a gap and
    measure the error inside, and the gap was bridged without a gap_bridged warning (the
    ellipse's gyro there is off by 0.62 rad/s, 0.0014 predicted elsewhere). Now told, its error
    marked as not measured."""
    sc, t, p, R = scene_poses("ellipse", "white", 30.0, seed=1)
    keep = ~((t > 10.0) & (t < 22.0))
    spl, rep = fit(t[keep], p[keep], lie.matrix_to_quat_xyzw(R[keep]), return_report=True)
    te = np.arange(10.0, 22.0, 0.01)
    assert np.sqrt(np.mean(np.sum((spl.imu(te)[0] - sc.imu(te)[0]) ** 2, axis=1))) > 0.3
    gaps = [w for w in rep.warnings if w.code == "gap_bridged"]
    assert len(gaps) == 1 and abs(gaps[0].t_start_s - 10.0) < 0.01 and abs(gaps[0].t_end_s - 22.0) < 0.01
    assert "not measured" in gaps[0].message, gaps[0].message
    (gap,) = rep.knot_choice["rotation"]["gaps"]
    assert gap["predicted_rms"] is None, gap



def test_a_fit_unsettled_by_a_long_gap_says_so():
    """16 s without poses under 68 ms rotation knots (flips): some 230 knot spacings whose
    controls only the smoothness penalty holds, too weakly conditioned for Gauss-Newton to settle
    (fit_not_converged). The warning names the gap and says to split the input there, not to
    raise the iteration count (which does not help) or coarsen the knots."""
    sc, t, p, R = scene_poses("flips", "white", 30.0, seed=1)
    keep = ~((t > 8.0) & (t < 24.0))
    _, rep = fit(t[keep], p[keep], lie.matrix_to_quat_xyzw(R[keep]), return_report=True)
    (msg,) = [w.message for w in rep.warnings if w.code == "fit_not_converged"]
    assert "without poses from 8.000 s to 24.000 s" in msg and "split the input there" in msg, msg
    assert "more iterations" not in msg, msg
    assert any(w.code == "gap_bridged" and abs(w.t_start_s - 8.0) < 0.01 for w in rep.warnings)

def test_unclear_gyro_bias_estimates_take_the_power_law_of_a_clear_one():
    """Ellipse, white noise, 1 kHz: the order-6 rotation rungs at 794 and 992 ms read a bias of
    1.3e-4 and 1.6e-4 rad/s (below their noise part: within its scatter, and lagging a true 1e-4
    and 2.7e-4), the choice was 992 ms at 1.24-1.30x the best fixed setting on seeds 1, 4 and 5.
    The clear reading at 1240 ms scaled down as dt^5 floors them: 794 ms, 0.91-0.94x the best
    of a 1.41x grid on seeds 1-6."""
    sc, t, p, R = scene_poses("ellipse", "white", 60.0, rate_hz=1000.0, seed=4)
    q = lie.matrix_to_quat_xyzw(R)
    gyro_err = gyro_error(sc, 60.0)
    spl, rep = fit(t, p, q, return_report=True)
    best = min(gyro_err(fit(t, p, q, order=6, knot_spacing_s=dt, reject_outliers=False)) for dt in (0.8, 0.905))
    assert gyro_err(spl) <= 1.1 * best, (rep.order, rep.knot_spacing_s, gyro_err(spl) / best)  # was 1.28
    # the floor: unclear rungs only, never lowered, the power law of the nearest clear rung above
    # (dt^5, or steeper as the bias grows to the next clear rung: dt^7 here)
    dts = 0.5 * 1.25 ** np.arange(6)
    var = 1e-6 * (dts / 0.5) ** -3.0
    for grow, q in ((1.25**8, 5.0), (1.25**14, 7.0)):
        bias2 = np.array([0.0, 2e-8, 1e-7, 5e-6, 5e-6 * grow, 1e-5])
        out = knots._extrapolate_bias(dts, var, bias2, 5)
        clear = bias2 > var
        assert np.array_equal(out[clear], bias2[clear]) and np.all(out >= bias2)
        floor = bias2[3] * (dts[:3] / dts[3]) ** (2 * q)
        np.testing.assert_allclose(out[:3], np.maximum(bias2[:3], floor), rtol=1e-9)
    # a rung that read inf (a singular fit) floors nothing
    bias2 = np.array([1e-8, np.inf, 1e-7, 5e-6, 4e-5, 1e-5])
    out = knots._extrapolate_bias(dts, var, bias2, 5)
    assert np.isfinite(out[0]) and out[0] == max(1e-8, 5e-6 * (dts[0] / dts[3]) ** 10)


def test_a_best_rung_without_bias_is_refined_between_rungs():
    """Ellipse, white noise, 200 Hz: the rotation's best rung (1017 ms) read no bias for a true
    4e-4 rad/s on every seed, and the best fixed spacing (905 ms) lies between rungs: gyro
    1.154x the best of a 1.41x grid on seed 1. Such a rung moves to the vertex of the parabola
    through its and its neighbours' predictions (952 ms): 1.05x (seeds 1-10: 0.94-1.08x)."""
    sc, t, p, R = scene_poses("ellipse", "white", 60.0, seed=1)
    q = lie.matrix_to_quat_xyzw(R)
    gyro_err = gyro_error(sc, 60.0)
    spl, rep = fit(t, p, q, return_report=True)
    best = min(gyro_err(fit(t, p, q, order=6, knot_spacing_s=dt, reject_outliers=False))
               for dt in (0.81, 0.86, 0.905, 0.95, 1.0, 1.05))
    assert 0.93 <= rep.knot_spacing_s <= 1.0, rep.knot_spacing_s  # off the rungs (817, 1017 ms)
    assert gyro_err(spl) <= 1.1 * best, (rep.order, rep.knot_spacing_s, gyro_err(spl) / best)


@pytest.mark.parametrize("seed", [0, 3])
def test_white_noise_under_missed_motion_is_read_as_white(seed):
    """White pose noise at 100 Hz on the six-position scene: motion the coarse fit misses made
    the octave above its cut-off read f^-2.1 to f^-2.25 and the noise level there 2x its RMS, so
    the noise was taken as coloured: k6 373 ms, gyro 1.62x / 1.65x the best fixed setting (k4
    226 ms). The residual is uncorrelated and flat from twice the cut-off up: white, drawn at
    that band's level (measured 1.05x / 1.02x, k5 235 ms / k6 238 ms)."""
    sc, t, p, R = scene_poses("six-position", "white", 60.0, rate_hz=100.0, seed=seed)
    q = lie.matrix_to_quat_xyzw(R)
    gyro_err = gyro_error(sc, 60.0)
    spl, rep = fit(t, p, q, return_report=True)
    best = min(gyro_err(fit(t, p, q, order=k, knot_spacing_s=dt, reject_outliers=False))
               for k in (4, 5, 6) for dt in (0.16, 0.2263, 0.32))
    rot = rep.knot_choice["rotation"]
    assert rot["noise_slope"] == 0.0 and rot["bias_correction"] == knots.FLAT_WHITE_BIAS_LAG, rot["noise_slope"]
    assert gyro_err(spl) <= 1.3 * best, (rep.order, rep.knot_spacing_s, gyro_err(spl) / best)
    assert 1 / 3 <= rep.predicted_gyro_rms_rad_s / gyro_err(spl) <= 3


def test_white_noise_ties_between_rungs_take_the_coarser():
    """Fast hand-held motion (benchmarks/heldout_motions.py, draw 3), white 1 mm / 0.1 deg at
    200 Hz. Drawn flat, the rotation noise's gyro part is predicted within 3%; the bias at 55 ms
    read 1.5x high (0.030 rad/s for 0.020), so 44 and 55 ms predicted within 0.2% for a measured
    0.043 and 0.036: 1.16-1.19x the best fixed setting at 44 ms. Of rungs of the best order within
    1% of the best prediction the coarsest is taken (knots.WHITE_TIE): 55 ms."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    from heldout_motions import SumOfSines, _tables

    sc = SumOfSines(duration_s=60.0)
    sc.tables = _tables("fasthand", 3)
    t = np.arange(0.0, 60.0 + 1e-9, 1 / 200.0)
    rng = np.random.default_rng(1)
    k = sc.kinematics(t)
    p = k.position_world + noise("white", t.size, 200.0, 1e-3, rng)
    q = lie.matrix_to_quat_xyzw(k.world_R_body @ lie.so3_exp(noise("white", t.size, 200.0, np.radians(0.1), rng)))
    gyro_err = gyro_error(sc, 60.0)
    spl, rep = fit(t, p, q, return_report=True)
    best = min(gyro_err(fit(t, p, q, order=6, knot_spacing_s=dt, reject_outliers=False))
               for dt in (0.044, 0.055, 0.069))
    assert rep.knot_choice["rotation"]["bias_correction"] == knots.FLAT_WHITE_BIAS_LAG
    assert rep.knot_spacing_s > 0.05 and gyro_err(spl) <= 1.1 * best, (rep.knot_spacing_s, gyro_err(spl) / best)
    assert 1 / 3 <= rep.predicted_gyro_rms_rad_s / gyro_err(spl) <= 3


#: Hand-held rotation (ZYX Euler angles as sums of sines, 0.2-1.9 Hz; benchmarks/heldout_motions.py,
#: hand-held draw 2): (amplitude [rad], angular frequency [rad/s], phase) per angle.
HAND_ANGLES = (((0.1295, 6.371, 4.6974), (0.1237, 6.5017, 3.4865), (0.1668, 3.4515, 5.2801)),
               ((0.2127, 6.7009, 2.186), (0.2423, 6.1468, 1.7786), (0.4074, 1.1119, 5.1341)),
               ((0.2185, 2.8015, 1.585), (0.0663, 12.0493, 0.1372), (0.6108, 1.7587, 0.1493)))


def test_low_rate_noise_under_motion_moves_the_choice_coarser():
    """Hand-held rotation at 20 Hz with 0.02 deg white noise: the top octave reads as motion, the
    candidates' predictions carry a tenth of the noise surrogate, and 18 ms knots won (gyro 2.6x
    the best fixed setting, predicted 0.0018 rad/s before the noise under the motion was added at
    the choice). That noise (0.02 deg, read as 0.017) added to every candidate's prediction takes
    108 ms: 1.02x."""
    from splineimu.scenes.kinematics import euler_zyx_kinematics, sum_of_sines

    def rotation(t):
        cols = [sum_of_sines(t, table) for table in HAND_ANGLES]
        return euler_zyx_kinematics(*(np.column_stack([c[i] for c in cols]) for i in range(3)))[:2]

    t = np.arange(0.0, 60.0 + 1e-9, 0.05)
    rng = np.random.default_rng(1)
    R = rotation(t)[0] @ lie.so3_exp(np.radians(0.02) * rng.normal(size=(t.size, 3)))
    p = 2e-4 * rng.normal(size=(t.size, 3))
    q = lie.matrix_to_quat_xyzw(R)
    te = np.arange(1.0, 59.0, 0.005)
    w0 = rotation(te)[1]

    def gyro_err(spl):
        return float(np.sqrt(np.mean(np.sum((spl.angular_velocity_body(te) - w0) ** 2, axis=1))))

    spl, rep = fit(t, p, q, return_report=True)
    c = rep.knot_choice["rotation"]
    best = min(gyro_err(fit(t, p, q, order=k, knot_spacing_s=dt, reject_outliers=False))
               for k, dt in ((5, 0.113), (6, 0.08), (6, 0.113), (6, 0.16)))
    assert c["motion_limited"] and c["moved_by_noise_under_motion_from_s"] < 0.05, c
    assert 0.5 < c["noise_under_motion"] / np.radians(0.02) < 2.0, c["noise_under_motion"]
    assert gyro_err(spl) < 1.15 * best, (gyro_err(spl), best)  # 1.02 (2.6 before)
    assert 1 / 3 < c["predicted_rms"] / gyro_err(spl) < 3, (c["predicted_rms"], gyro_err(spl))


def test_position_walks_on_where_any_order_is_value_optimal_beyond_the_limit():
    """Flips, AR(1) pose noise, 30 s (seed 4): order 4's value-optimal position spacing is 53 ms,
    order 6's 34 ms; order 6 stopped at the walk limit (WALK_MAX_S, 50 ms), order 4 walked on and
    won at 104 ms: accel 1.57x the fixed fit at order 6 and 113 ms. With the limit lifted for
    every order: order 6 at 128 ms, 0.89x."""
    sc, t, p, R = scene_poses("flips", "ar1", 30.0, 200.0, 4)
    q = lie.matrix_to_quat_xyzw(R)
    te = np.arange(1.0, 29.0, 0.005)
    f0 = sc.imu(te)[1]

    def accel_err(spl):
        return float(np.sqrt(np.mean(np.sum((spl.imu(te)[1] - f0) ** 2, axis=1))))

    spl, rep = fit(t, p, q, return_report=True)
    fixed = accel_err(fit(t, p, q, order=6, knot_spacing_s=0.113, reject_outliers=False))
    assert rep.position_knot_spacing_s > knots.WALK_MAX_S, rep.summary()
    assert accel_err(spl) < 1.3 * fixed, (accel_err(spl), fixed)  # 0.89 (1.57 before)


@pytest.mark.parametrize("name, kind", [("circle", "white"), ("ellipse", "ar1")])
def test_long_glitch_is_dropped_whole(name, kind):
    """A 5 cm glitch for 200 ms (40 poses): on the circle the choice followed it partly (position
    knots 129 ms), its residual split in two runs, each warned as a step, nothing dropped, accel
    elsewhere 73x the best fixed setting; under AR(1) noise the ellipse's 326 ms knots smeared it
    over 0.6 s, nowhere above the local residual level: nothing told, accel 2x. Found in the
    poses themselves (a step by d and one by -d within MAX_GLITCH_S), all 40 poses are dropped,
    and the rest is as without the glitch."""
    sc, t, p, R = scene_poses(name, kind, 60.0, 200.0, 0)
    q = lie.matrix_to_quat_xyzw(R)
    inside = (t >= 33.337) & (t < 33.537)
    pg = p.copy()
    pg[inside] += 0.05 * np.array([0.6, -0.64, 0.48])
    te = np.arange(1.0, 59.0, 0.005)
    te = te[np.abs(te - 33.437) > 0.5]
    f0 = sc.imu(te)[1]

    def accel_err(spl):
        return float(np.sqrt(np.mean(np.sum((spl.imu(te)[1] - f0) ** 2, axis=1))))

    spl, rep = fit(t, pg, q, return_report=True)
    assert sorted(rep.dropped_poses) == np.flatnonzero(inside).tolist(), rep.summary()
    assert [w.code for w in rep.warnings if w.code in ("unexplained_jump", "residual_burst")] == [], rep.summary()
    clean = accel_err(fit(t, p, q))
    assert accel_err(spl) < 1.1 * clean, (accel_err(spl), clean)


@pytest.mark.parametrize("scene_name, seed, size", [("circle", 2, 0.015), ("circle", 2, 0.01),
                                                    ("ellipse", 2, 0.01), ("flips", 0, 0.01)])
def test_weaker_long_glitch_is_found_by_its_offset(scene_name, seed, size):
    """Long glitches (200 ms) under 1 mm white noise, benchmarks/glitch_sweep.py's draws. 1.5 cm:
    its steps (about 6.7 robust sigmas, with the noise under 6 at one end) went unfound, accel
    elsewhere 19x the best fixed setting on the circle; steps from 4 sigmas count where the
    poses between sit off a cubic through the poses around them by one offset. 1 cm: its single
    steps (about 4.5 sigmas) went unfound on every scene with seed 2, the knots following it
    (circle: accel elsewhere 12x, screw 9.9x); the steps of 8-pose box means stand 7-15 sigmas
    out, and on the flips scene a quintic through the poses around follows its motion (a cubic
    left 3.9 mm of residual there). All 40 poses dropped."""
    sc, t, p, R = scene_poses(scene_name, "white", 60.0, 200.0, seed)
    rng = np.random.default_rng(500 + seed)
    t0 = rng.uniform(5.0, 55.0)
    d = rng.normal(size=3)
    inside = (t >= t0) & (t < t0 + 0.2)
    pg = p.copy()
    pg[inside] += size * d / np.linalg.norm(d)
    spl, rep = fit(t, pg, lie.matrix_to_quat_xyzw(R), return_report=True)
    assert set(np.flatnonzero(inside).tolist()) <= set(rep.dropped_poses), rep.summary()
    assert len(rep.dropped_poses) <= 42, rep.dropped_poses


@pytest.mark.parametrize("seed", [4, 6])
def test_position_bias_floor_under_white_noise(seed):
    """The flips scene over 20 s with white noise: the position's order-5 rung at its value-optimal
    106 ms read no bias and won, accel 1.39x (seed 4) and 1.36x (seed 6) the best fixed setting;
    floored by the rungs above (uncorrelated noise), order 6 at 118 ms, 1.01-1.02x."""
    dur = 20.0
    sc, t, p, R = scene_poses("flips", "white", dur, seed=seed)
    q = lie.matrix_to_quat_xyzw(R)
    spl, rep = fit(t, p, q, return_report=True)
    accel = scene_errors(sc, spl, dur)[1]
    best = min(scene_errors(sc, fit(t, p, q, order=6, knot_spacing_s=dt, reject_outliers=False), dur)[1]
               for dt in (0.0905, 0.113, 0.1414))
    assert accel <= 1.15 * best, (rep.position_order, rep.position_knot_spacing_s, accel / best)
    assert 1 / 3 <= rep.predicted_accel_rms_m_s2 / accel <= 3
