"""Rotations from an estimator that fused an IMU (EuRoC's ground truth, vicon2gt): their detail
up to the Nyquist frequency is the vehicle's motion (vibration included), which no test on the
poses alone tells from pose noise; ``fit(..., estimated_rotation=True)`` keeps it (from-euroc sets
it for files that carry IMU biases)."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu import fit, lie
from splineimu.scenes.kinematics import euler_zyx_kinematics, sum_of_sines

RATE_HZ = 200.0
TWO_PI = 2.0 * np.pi


def _vibrating(t, vib=1e-4):
    """Rotation and body rate: slow turns (0.2-2.3 Hz, 0.05-0.5 rad) and vibration at 19-71 Hz
    (``vib`` rad, rate ~0.03 rad/s) on each Euler angle."""
    slow = [((0.3, 0.3, 0.1), (0.1, 1.1, 1.0)), ((0.2, 0.5, 2.0), (0.1, 1.7, 0.3)), ((0.5, 0.2, 0.7), (0.05, 2.3, 1.9))]
    fast = [((23.0, 0.4), (41.0, 1.3), (67.0, 2.2)), ((29.0, 0.9), (47.0, 0.2), (71.0, 1.7)),
            ((19.0, 2.4), (37.0, 0.6), (59.0, 0.8))]
    cols = []
    for s_axis, f_axis in zip(slow, fast):
        table = [(a, TWO_PI * f, ph) for a, f, ph in s_axis] + [
            (vib * w, TWO_PI * f, ph) for w, (f, ph) in zip((1.0, 0.6, 0.3), f_axis)]
        cols.append(sum_of_sines(t, table))
    R, w, _ = euler_zyx_kinematics(*(np.column_stack([c[i] for c in cols]) for i in range(3)))
    return R, w


def test_vibration_in_an_estimated_rotation_is_kept():
    dur = 30.0
    t = np.arange(0.0, dur + 1e-9, 1.0 / RATE_HZ)
    R, _ = _vibrating(t)
    rng = np.random.default_rng(0)
    q = lie.matrix_to_quat_xyzw(R @ lie.so3_exp(2e-5 * rng.normal(size=(t.size, 3))))
    p = 1e-5 * rng.normal(size=(t.size, 3))
    te = np.arange(1.0, dur - 1.0, 0.0025)  # at the poses and between them
    w0 = _vibrating(te)[1]

    def gyro_error(spl):
        return float(np.sqrt(np.mean(np.sum((spl.imu(te)[0] - w0) ** 2, axis=1))))

    best = gyro_error(fit(t, p, q, order=6, knot_spacing_s=0.005, reject_outliers=False))
    spl, rep = fit(t, p, q, return_report=True)
    # read as pose noise: 68 ms knots, 3.3x the 5 ms fit's error, predicted 0.04x the measured;
    # told: the residual's spectral lines (19-71 Hz) hold 0.029 rad/s of gyro, 23x the prediction
    assert gyro_error(spl) > 2.5 * best, (gyro_error(spl), best, rep.knot_spacing_s)
    told = [w.message for w in rep.warnings if w.code == "residual_periodic"]
    assert len(told) == 1 and "lines at 23, 19, 29" in told[0] and "--rotation-source estimate" in told[0], told
    assert 0.5 * gyro_error(spl) < float(told[0].split("(")[2].split()[0]) < 1.5 * gyro_error(spl), told
    spl, rep = fit(t, p, q, return_report=True, estimated_rotation=True)
    e = gyro_error(spl)
    # measured: 1.8 ms knots, 1.19x, predicted 1.28x the measured
    assert rep.knot_choice["rotation"]["estimated"] and rep.knot_choice["rotation"]["motion_limited"]
    assert e < 1.3 * best, (e, best, rep.knot_spacing_s)
    assert 1 / 3 < rep.predicted_gyro_rms_rad_s / e < 3, (rep.predicted_gyro_rms_rad_s, e)
    assert "residual_periodic" not in {w.code for w in rep.warnings}


def test_periodic_residual_of_exact_periodic_motion_is_not_told():
    """Exact poses of the screw scene (periodic turning): the residual's lines are rounding
    (1e-13 rad/s of gyro at 3.2 s knots), below LINE_GYRO_FLOOR; white pose noise has no lines."""
    from splineimu.scenes import make_scene

    sc = make_scene("screw", duration_s=60.0)
    t = np.arange(0.0, 60.0 + 1e-9, 1.0 / RATE_HZ)
    k = sc.kinematics(t)
    q = lie.matrix_to_quat_xyzw(k.world_R_body)
    _, rep = fit(t, k.position_world, q, return_report=True)
    assert "residual_periodic" not in {w.code for w in rep.warnings}
    noisy = lie.matrix_to_quat_xyzw(k.world_R_body @ lie.so3_exp(np.radians(0.1) * np.random.default_rng(2).normal(
        size=(t.size, 3))))
    _, rep = fit(t, k.position_world, noisy, return_report=True)
    assert "residual_periodic" not in {w.code for w in rep.warnings}


def test_a_track_from_a_file_with_imu_biases_is_fitted_as_an_estimate():
    """fit(track): the file says what arrays cannot. A track carrying IMU biases (EuRoC's ground
    truth) is fitted as an estimator's output by default, the same poses as arrays are not; the
    track's first stamp is the origin."""
    from splineimu.errors import SplineImuError
    from splineimu.io import PoseTrack

    t = np.arange(0.0, 20.0 + 1e-9, 1.0 / RATE_HZ)
    R, _ = _vibrating(t)
    rng = np.random.default_rng(1)
    q = lie.matrix_to_quat_xyzw(R @ lie.so3_exp(2e-5 * rng.normal(size=(t.size, 3))))
    p = 1e-5 * rng.normal(size=(t.size, 3))
    t_ns = 1_403_715_273_262_142_976 + np.round(t * 1e9).astype(np.int64)
    plain = PoseTrack(t_ns, p, q)
    biased = PoseTrack(t_ns, p, q, velocity_world=np.zeros_like(p), bias_gyro=np.zeros_like(p),
                       bias_accel=np.zeros_like(p))
    runs = {"arrays": fit(t, p, q, return_report=True), "plain track": fit(plain, return_report=True),
            "track with biases": fit(biased, return_report=True),
            "told": fit(t, p, q, return_report=True, estimated_rotation=True),
            "track told not": fit(biased, return_report=True, estimated_rotation=False)}
    est = {name: rep.knot_choice["rotation"]["estimated"] for name, (_, rep) in runs.items()}
    assert est == {"arrays": False, "plain track": False, "track with biases": True, "told": True,
                   "track told not": False}
    # the same poses and choice as the arrays told so, on the track's own origin
    (a, ra), (b, rb) = runs["told"], runs["track with biases"]
    assert rb.knot_spacing_s == ra.knot_spacing_s < 0.01 < runs["arrays"][1].knot_spacing_s
    assert b.origin_ns == t_ns[0] and a.origin_ns == 0
    np.testing.assert_allclose(b.imu(t[100:110])[0], a.imu(t[100:110])[0], atol=1e-12)
    with pytest.raises(SplineImuError, match="do not pass positions"):
        fit(biased, p, q)
    with pytest.raises(SplineImuError, match="do not pass positions"):
        fit(biased, origin_ns=5)
    with pytest.raises(SplineImuError, match="track read from a pose file"):
        fit(t, p)
    with pytest.raises(SplineImuError, match="estimated_rotation must be"):
        fit(t, p, q, estimated_rotation="yes")


@pytest.mark.parametrize("amplitude", [1.5e-3, 3e-3])
def test_motion_between_low_rate_estimated_poses_is_kept(amplitude):
    """An estimate at 20 Hz whose rotation holds motion at 6-9 Hz (1.5-3 mrad), which the poses
    sample too sparsely to predict: the value-optimal spacing is 2-3 pose spacings and the
    ladder's errors between there and the poses are rough. Every rung down to the finest is
    predicted against the finest (splineimu.spline.knots, method step 4)."""
    rate, dur = 20.0, 60.0
    slow = [((0.3, 0.3, 0.1), (0.1, 1.1, 1.0)), ((0.2, 0.5, 2.0), (0.1, 1.7, 0.3)), ((0.5, 0.2, 0.7), (0.05, 2.3, 1.9))]
    fast = [((6.3, 0.4), (7.9, 1.3)), ((6.8, 0.9), (8.6, 0.2)), ((7.4, 2.4), (8.9, 0.6))]

    def motion(t):
        cols = [sum_of_sines(t, [(a, TWO_PI * f, ph) for a, f, ph in s] + [(amplitude, TWO_PI * f, ph) for f, ph in fa])
                for s, fa in zip(slow, fast)]
        return euler_zyx_kinematics(*(np.column_stack([c[i] for c in cols]) for i in range(3)))[:2]

    t = np.arange(0.0, dur + 1e-9, 1.0 / rate)
    q = lie.matrix_to_quat_xyzw(motion(t)[0])
    p = np.zeros((t.size, 3))
    te = np.arange(2.0, dur - 2.0, 0.005)
    w0 = motion(te)[1]

    def gyro_error(spl):
        return float(np.sqrt(np.mean(np.sum((spl.imu(te)[0] - w0) ** 2, axis=1))))

    interp = gyro_error(fit(t, p, q, order=4, knot_spacing_s=0.7 / rate, reject_outliers=False))
    spl, rep = fit(t, p, q, return_report=True, estimated_rotation=True)
    e = gyro_error(spl)
    # measured: k4 18 ms, 1.25x the interpolating fit (4.2x before, 108 ms knots)
    assert rep.knot_spacing_s < 1.0 / rate, rep.knot_spacing_s
    assert e < 1.4 * interp, (e, interp, rep.knot_spacing_s)
    # what the poses cannot resolve is not in the prediction (0.28x and 2.9x the measured for
    # the two amplitudes): that is told
    assert "input_rate_low" in {w.code for w in rep.warnings}


def test_positions_finer_than_their_poses_bridge_them_only_where_that_predicts_better():
    """Positions fitted finer than their poses (motion-limited, 20 Hz): the segments between the
    poses are set by the penalty alone. Bending least there (second differences, as a cubic
    interpolating spline) is taken only where it predicts every 4th pose from the others better
    than jerking least: not for exact fast motion, which it would smooth (11x the accel error of
    this motion). The controls it would bridge are those between the poses, not a gap's."""
    from splineimu.spline.banded import BRIDGE_SMOOTHNESS, layout
    from splineimu.spline.core import Spline
    from splineimu.spline.problem import _Problem

    rate, dur = 20.0, 40.0
    t = np.arange(0.0, dur + 1e-9, 1.0 / rate)
    t = t[(t < 20.0) | (t > 21.0)]  # a 1 s gap (20 poses)
    tables = [[(0.4, TWO_PI * f, ph) for f, ph in ((0.3, 0.1), (1.1, 1.0), (2.9, 0.4))],
              [(0.3, TWO_PI * f, ph) for f, ph in ((0.5, 2.0), (1.7, 0.3), (3.7, 1.3))],
              [(0.2, TWO_PI * f, ph) for f, ph in ((0.2, 0.7), (2.3, 1.9), (4.3, 0.6))]]
    p = np.column_stack([sum_of_sines(t, tab)[0] for tab in tables])
    q = lie.matrix_to_quat_xyzw(np.repeat(np.eye(3)[None], t.size, axis=0))
    _, rep = fit(t, p, q, return_report=True, estimated_rotation=True)
    pos = rep.knot_choice["position"]
    assert pos["motion_limited"] and rep.position_knot_spacing_s < 1.0 / rate, rep.summary()
    assert pos["bridge_smoothness"] == 0.0 and pos["bridge_heldout_ratio"] > 1.0 and rep.notes == []
    k = rep.position_order
    t0, dt, nseg, _ = layout(t[0], t[-1], rep.position_knot_spacing_s, k)
    prob = _Problem(t, p, None, None, np.ones(t.size), k, t0, dt, nseg, 1e-10, 1.0, 1.0, bridge=BRIDGE_SMOOTHNESS)
    tc = t0 + (np.arange(prob.n) - (k - 2) / 2.0) * dt  # the controls' centres
    in_gap = (tc > 20.0 + k * dt) & (tc < 21.0 - k * dt)
    assert in_gap.any() and prob.sparse[in_gap].all() and not prob.bridge[in_gap].any()
    away = np.abs(tc - 20.5) > 0.5 + k * dt
    assert prob.bridge[away].mean() > 0.9 and not prob.sparse[away].any()
    # bridged so, this exact motion's accel would be 4.7 m/s^2 RMS off, not 0.41 (2-18 s)
    te = np.arange(2.0, 18.0, 0.005)
    a0 = np.column_stack([sum_of_sines(te, tab)[2] for tab in tables])
    errs = []
    for weight in (0.0, BRIDGE_SMOOTHNESS):
        fold = _Problem(t, p, None, None, np.ones(t.size), k, t0, dt, nseg, 1e-10, 1.0, 1.0, bridge=weight)
        spl = Spline.from_control_points(t0, dt, fold.solve_positions(), np.tile([0.0, 0.0, 0.0, 1.0], (fold.n, 1)),
                                         order=k)
        errs.append(float(np.sqrt(np.mean(np.sum((spl.acceleration_world(te) - a0) ** 2, axis=1)))))
    assert 5.0 * errs[0] < errs[1], errs
