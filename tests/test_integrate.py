"""Dead reckoning: closed-form cases, round trips from exact IMU data, convergence orders, CLI."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import require_shared

from splineimu import cli
from splineimu._kernels.integrate import interp_mid_kernel
from splineimu.api.integrate import dead_reckon, default_groundtruth_path
from splineimu.errors import ConfigError, InputError, RangeError
from splineimu.groundtruth import GroundTruth
from splineimu.integrate import (
    METHOD_ORDER,
    METHODS,
    NavState,
    Trajectory,
    integrate,
)
from splineimu.lie import quat_xyzw_to_matrix, so3_exp, so3_log
from splineimu.scenes import make_scene

G = np.array([0.0, 0.0, -9.81])


def rot_err(R_a, R_b):
    """Angle [rad] of R_a^T R_b per row."""
    return np.linalg.norm(so3_log(np.einsum("nji,njk->nik", R_a, R_b)), axis=1)


def round_trip(scene, rate_hz, method, duration_s):
    t = np.arange(int(round(duration_s * rate_hz)) + 1) / rate_hz
    gyro, accel = scene.imu(t)
    tr = integrate(t, gyro, accel, NavState.from_motion(scene, 0.0), method=method)
    k = scene.kinematics(t)
    e_p = np.linalg.norm(tr.position_world - k.position_world, axis=1)
    e_r = rot_err(tr.world_R_body, k.world_R_body)
    return e_p, e_r


# ------------------------------------------------------------------------- closed form


@pytest.mark.parametrize("method", METHODS)
def test_level_body_at_rest_stays(method):
    n = 201
    t = np.arange(n) * 0.005
    f = np.tile([0.0, 0.0, 9.81], (n, 1))
    init = NavState(0.0, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0])
    tr = integrate(t, np.zeros((n, 3)), f, init, method=method)
    assert np.abs(tr.position_world - [1.0, 2.0, 3.0]).max() < 1e-12
    assert np.abs(tr.velocity_world).max() < 1e-12
    assert np.abs(tr.quat_xyzw - [0, 0, 0, 1]).max() < 1e-15


@pytest.mark.parametrize("method", METHODS)
def test_constant_rate_rotation_is_exact_exponential(method):
    # w constant: R(t) = R0 Exp(w t) exactly for every method (the update is an exact Exp)
    w = np.array([0.7, -1.3, 2.1])
    t = np.arange(1001) * 0.01
    R0 = so3_exp(np.array([0.3, 0.2, -0.1]))
    init = NavState.from_world_R_body(0.0, np.zeros(3), R0)
    f = np.tile([0.0, 0.0, 9.81], (t.size, 1))  # irrelevant for the rotation
    tr = integrate(t, np.tile(w, (t.size, 1)), f, init, method=method)
    R_true = R0 @ so3_exp(t[:, None] * w)
    assert rot_err(tr.world_R_body, R_true).max() < 1e-12
    assert np.all(np.abs(np.linalg.norm(tr.quat_xyzw, axis=1) - 1.0) < 1e-15)


@pytest.mark.parametrize("method", METHODS)
def test_constant_acceleration_is_exact(method):
    # fixed attitude, constant world acceleration: p = p0 + v0 t + a t^2 / 2 for every method
    R = so3_exp(np.array([0.4, -0.5, 1.0]))
    a_w = np.array([0.3, -0.2, 0.5])
    f_b = R.T @ (a_w - G)
    t = np.cumsum(np.r_[0.0, np.full(300, 0.01) + 0.004 * np.sin(np.arange(300))])  # non-uniform
    init = NavState.from_world_R_body(0.0, [1.0, -1.0, 2.0], R, velocity_world=[0.5, 0.1, -0.2])
    tr = integrate(t, np.zeros((t.size, 3)), np.tile(f_b, (t.size, 1)), init, method=method)
    p = [1.0, -1.0, 2.0] + np.outer(t, [0.5, 0.1, -0.2]) + 0.5 * np.outer(t * t, a_w)
    assert np.abs(tr.position_world - p).max() < 1e-12
    assert np.abs(tr.velocity_world - ([0.5, 0.1, -0.2] + np.outer(t, a_w))).max() < 1e-12


def test_biases_are_subtracted():
    scene = make_scene("ellipse", duration_s=5.0)
    t = np.arange(1001) / 200.0
    gyro, accel = scene.imu(t)
    bg, ba = np.array([0.01, -0.02, 0.03]), np.array([-0.1, 0.2, 0.05])
    for method in METHODS:
        clean = integrate(t, gyro, accel, NavState.from_motion(scene, 0.0), method=method)
        biased = integrate(t, gyro + bg, accel + ba,
                           NavState.from_motion(scene, 0.0, bias_gyro=bg, bias_accel=ba), method=method)
        assert np.abs(biased.position_world - clean.position_world).max() < 1e-9
        # and ignoring the bias is visibly wrong
        wrong = integrate(t, gyro + bg, accel + ba, NavState.from_motion(scene, 0.0), method=method)
        assert np.abs(wrong.position_world - clean.position_world).max() > 0.1


def test_midpoint_interpolation_is_exact_for_cubics():
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.5, 1.5, 12))
    coef = rng.normal(size=(4, 2))
    poly = lambda s: np.stack([np.polyval(coef[:, j], s) for j in range(2)], axis=1)  # noqa: E731
    out = np.empty((11, 2))
    interp_mid_kernel(t, np.ascontiguousarray(poly(t)), out)
    assert np.abs(out - poly(0.5 * (t[1:] + t[:-1]))).max() < 1e-9 * np.abs(poly(t)).max()
    for n, deg in ((2, 1), (3, 2)):  # fewer samples: exact for degree n - 1
        c = coef[4 - deg - 1:]
        pol = lambda s, c=c: np.stack([np.polyval(c[:, j], s) for j in range(2)], axis=1)  # noqa: E731
        o = np.empty((n - 1, 2))
        interp_mid_kernel(t[:n], np.ascontiguousarray(pol(t[:n])), o)
        assert np.abs(o - pol(0.5 * (t[1:n] + t[: n - 1]))).max() < 1e-12


# ------------------------------------------------------------- round trip and convergence


def test_round_trip_60s_200hz_ellipse():
    """Acceptance figure (point sampling): noise-free 60 s ellipse at 200 Hz integrated back.

    Measured: euler 8.6 m, midpoint 4.0e-3 m, rk4 1.7e-7 m (final position error).
    """
    scene = make_scene("ellipse", duration_s=60.0)
    bounds = {"euler": (5.0, 15.0), "midpoint": (2e-3, 8e-3), "rk4": (1e-8, 1e-6)}
    for method, (lo, hi) in bounds.items():
        e_p, e_r = round_trip(scene, 200.0, method, 60.0)
        assert lo < e_p.max() < hi, (method, e_p.max())
    assert e_p.max() < 1e-3  # rk4: the issue's < 1 mm
    assert e_r.max() < 1e-8


def test_convergence_orders_on_ellipse():
    """Log-log slope of the position error vs rate (100 -> 800 Hz, 20 s) matches the order.

    Measured slopes (final error): euler 1.00, midpoint 2.00, rk4 3.99.
    """
    scene = make_scene("ellipse", duration_s=20.0)
    rates = np.array([100.0, 200.0, 400.0, 800.0])
    for method in METHODS:
        finals, rmss = [], []
        for r in rates:
            e_p, _ = round_trip(scene, r, method, 20.0)
            finals.append(e_p[-1])
            rmss.append(np.sqrt(np.mean(e_p**2)))
        for err in (finals, rmss):
            slope = -np.polyfit(np.log(rates), np.log(err), 1)[0]
            assert abs(slope - METHOD_ORDER[method]) < 0.3, (method, slope, err)
            steps = -np.diff(np.log(err)) / np.log(2.0)  # every doubling, not only the fit
            assert np.all(np.abs(steps - METHOD_ORDER[method]) < 0.3), (method, steps)
        assert min(finals) > 1e-11  # round-off here is ~1e-13 m: the slopes are not noise


def test_rk4_fourth_order_on_non_uniform_times():
    # the same jitter pattern (relative to the step) at two rates; error ratio ~ 2^4
    scene = make_scene("ellipse", duration_s=10.0)
    jitter = 0.3 * np.sin(1.7 * np.arange(4001))
    errs = []
    for r in (200.0, 400.0):
        n = int(10.0 * r)
        t = (np.arange(n + 1) + jitter[: n + 1] * (np.arange(n + 1) % n != 0)) / r
        gyro, accel = scene.imu(t)
        tr = integrate(t, gyro, accel, NavState.from_motion(scene, 0.0), method="rk4")
        errs.append(np.linalg.norm(tr.position_world[-1] - scene.kinematics(t[-1:]).position_world[0]))
    assert 2 ** 3.7 < errs[0] / errs[1] < 2 ** 4.3, errs


def test_screw_and_flips_scenes_rk4():
    # other motion: fast rotation (flips) and coupled screw motion, 10 s at 200 Hz
    for name, tol in (("screw", 1e-9), ("flips", 3e-4)):  # measured 2.8e-10, 1.2e-4
        scene = make_scene(name, duration_s=10.0)
        e_p, e_r = round_trip(scene, 200.0, "rk4", 10.0)
        e_p2, _ = round_trip(scene, 400.0, "rk4", 10.0)
        assert e_p.max() < tol, (name, e_p.max())
        assert e_p[-1] / e_p2[-1] > 2**3.5, (name, e_p[-1], e_p2[-1])


# ------------------------------------------------------------------------ API behaviour


def test_trajectory_object_and_dataframe():
    scene = make_scene("ellipse", duration_s=2.0)
    t = np.arange(101) / 50.0
    gyro, accel = scene.imu(t)
    tr = integrate(t, gyro, accel, NavState.from_motion(scene, 0.0))
    assert isinstance(tr, Trajectory) and tr.method == "rk4" and len(tr) == 101
    assert tr.position_world.shape == (101, 3) and tr.quat_xyzw.shape == (101, 4)
    assert np.all(np.einsum("ij,ij->i", tr.quat_xyzw[1:], tr.quat_xyzw[:-1]) > 0)  # continuous
    df = tr.to_dataframe()
    assert list(df.columns) == ["t_s", "px", "py", "pz", "qx", "qy", "qz", "qw", "vx", "vy", "vz"]
    np.testing.assert_array_equal(df[["vx", "vy", "vz"]].to_numpy(), tr.velocity_world)
    # state at t[0] is the initial state itself
    k0 = scene.kinematics(t[:1])
    np.testing.assert_allclose(tr.position_world[0], k0.position_world[0], atol=0)
    assert rot_err(quat_xyzw_to_matrix(tr.quat_xyzw[:1]), k0.world_R_body)[0] < 1e-15


def test_bad_inputs():
    t = np.arange(5) * 0.01
    z = np.zeros((5, 3))
    init = NavState(None, [0, 0, 0], [0, 0, 0, 1])
    with pytest.raises(ConfigError, match="`method` must be one of euler, midpoint, rk4, got 'heun'"):
        integrate(t, z, z, init, method="heun")
    with pytest.raises(InputError, match="strictly increasing"):
        integrate(t[[0, 1, 1, 3, 4]], z, z, init)
    with pytest.raises(InputError, match=r"Expected `accel` to have shape \(5, 3\), got \(5, 2\)"):
        integrate(t, z, z[:, :2], init)
    with pytest.raises(InputError, match="at least 2 samples"):
        integrate(t[:1], z[:1], z[:1], init)
    bad = z.copy()
    bad[3, 1] = np.nan
    with pytest.raises(InputError, match=r"`gyro` contains NaN or inf \(first at index \(3, 1\)\)"):
        integrate(t, bad, z, init)
    with pytest.raises(ConfigError, match="must coincide"):
        integrate(t + 1.0, z, z, NavState(0.0, [0, 0, 0], [0, 0, 0, 1]))
    with pytest.raises(InputError, match="`quat_xyzw` row 0 is a zero quaternion"):
        NavState(0.0, [0, 0, 0], [0, 0, 0, 0])
    with pytest.raises(InputError, match=r"`velocity_world` to have shape \(3,\)"):
        NavState(0.0, [0, 0, 0], [0, 0, 0, 1], velocity_world=[1, 2])


# --------------------------------------------------------------------------------- CLI


def _write_dataset(folder, scene, rate_hz, gt_every=1, gt_shift_ns=0, gt_start=0):
    """EuRoC-like folder: imu0/data.csv and state_groundtruth_estimate0/data.csv (ground truth
    every `gt_every` IMU samples, stamps shifted by `gt_shift_ns`, from IMU sample `gt_start`)."""
    t_ns = scene.sample_times_ns(rate_hz)
    t = scene.t_s_from_ns(t_ns)
    gyro, accel = scene.imu(t)
    (folder / "imu0").mkdir(parents=True)
    with open(folder / "imu0" / "data.csv", "w") as fh:
        fh.write("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                 "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n")
        for i in range(t.size):
            fh.write(f"{t_ns[i]}," + ",".join(repr(float(x)) for x in (*gyro[i], *accel[i])) + "\n")
    gt_ns = t_ns[gt_start::gt_every] + gt_shift_ns
    k = scene.kinematics(scene.t_s_from_ns(gt_ns))
    q = k.quat_xyzw
    (folder / "state_groundtruth_estimate0").mkdir()
    with open(folder / "state_groundtruth_estimate0" / "data.csv", "w") as fh:
        fh.write("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
                 "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
                 "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
                 "b_a_RS_S_z [m s^-2]\n")
        for i in range(gt_ns.size):
            row = (*k.position_world[i], q[i, 3], *q[i, :3], *k.velocity_world[i], *np.zeros(6))
            fh.write(f"{gt_ns[i]}," + ",".join(repr(float(x)) for x in row) + "\n")
    return t_ns


def _read_tum_exact(path):
    stamps, vals = [], []
    for line in open(path):
        if line.startswith("#"):
            continue
        parts = line.split()
        s, ns = parts[0].split(".")
        stamps.append(int(s) * 10**9 + int(ns))
        vals.append([float(x) for x in parts[1:]])
    return np.array(stamps, dtype=np.int64), np.array(vals)


def test_cli_integrate_round_trip(tmp_path, capsys):
    scene = make_scene("ellipse", duration_s=20.0, t0_ns=1_403_715_523_912_140_001)
    t_ns = _write_dataset(tmp_path / "out", scene, 200.0)
    out = tmp_path / "rk4.tum"
    assert cli.main(["integrate", str(tmp_path / "out" / "imu0" / "data.csv"), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "integrated 4001 point samples (20.000 s) with rk4" in text
    stamps, vals = _read_tum_exact(out)
    np.testing.assert_array_equal(stamps, t_ns)  # exact, not through float seconds
    assert open(out).read().splitlines()[1].startswith("1403715523.912140001 ")
    k = scene.kinematics(scene.t_s_from_ns(t_ns))
    assert np.abs(vals[:, :3] - k.position_world).max() < 1e-7
    assert rot_err(quat_xyzw_to_matrix(vals[:, 3:]), k.world_R_body).max() < 1e-8
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "rk4.tum"]  # no temp file left


def test_cli_integrate_interpolates_initial_state(tmp_path, capsys):
    # ground truth at 100 Hz, shifted 2.5 ms and starting 10 samples late: the first IMU stamp
    # inside it (IMU sample 10) is 2.5 ms after a ground-truth row; its state is interpolated.
    scene = make_scene("ellipse", duration_s=10.0, t0_ns=5_000_000_000)
    t_ns = _write_dataset(tmp_path / "d", scene, 200.0, gt_every=2, gt_shift_ns=-2_500_000, gt_start=10)
    out = tmp_path / "mid.tum"
    rc = cli.main(["integrate", str(tmp_path / "d" / "imu0" / "data.csv"), "--method", "midpoint",
                   "--init", str(tmp_path / "d" / "state_groundtruth_estimate0" / "data.csv"),
                   "-o", str(out)])
    assert rc == 0
    assert "skipping 10 IMU samples" in capsys.readouterr().out
    stamps, vals = _read_tum_exact(out)
    np.testing.assert_array_equal(stamps, t_ns[10:])
    k = scene.kinematics(scene.t_s_from_ns(stamps[:1]))
    # linear interpolation over 10 ms of the ellipse: error ~ a h^2 / 8 ~ 1e-4 m
    assert np.linalg.norm(vals[0, :3] - k.position_world[0]) < 2e-4
    assert rot_err(quat_xyzw_to_matrix(vals[:1, 3:]), k.world_R_body)[0] < 1e-4


def test_cli_integrate_errors(tmp_path, capsys):
    (tmp_path / "imu0").mkdir()
    imu = tmp_path / "imu0" / "data.csv"
    imu.write_text("#timestamp [ns],wx,wy,wz,ax,ay,az\n1000,0,0,0,0,0,9.81\n2000,0,0,0,0,0,9.81\n")
    assert cli.main(["integrate", str(imu), "-o", str(tmp_path / "x.tum")]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "initial-state file not found" in err and "--init" in err
    imu.write_text("#timestamp [ns],wx,wy,wz,ax,ay,az\n1000,0,0,0,0,0,9.81\n2000,0,0,0,zero,0,9.81\n")
    gt = tmp_path / "gt.csv"
    gt.write_text("1000" + ",0" * 4 + ",1" + ",0" * 12 + "\n")
    assert cli.main(["integrate", str(imu), "--init", str(gt), "-o", str(tmp_path / "x.tum")]) == 1
    assert f"{imu}:3: non-numeric value" in capsys.readouterr().err
    assert not (tmp_path / "x.tum").exists()


def test_cli_integrate_euroc_real_data(tmp_path, capsys):
    """EuRoC V1_02_medium (ETH ASL): 2 s of the real ADIS16448 data from the ground-truth state.

    Measured drift at 2 s: 0.09 m for every method (sensor noise and ground-truth
    bias/velocity errors dominate the method error). With the gravity sign flipped, ~40 m.
    """
    imu = require_shared("euroc_V1_02_medium", "imu0_first40s.csv")
    gt = require_shared("euroc_V1_02_medium", "groundtruth.csv")
    lines = open(imu).read().splitlines()
    short = tmp_path / "imu.csv"
    short.write_text("\n".join(lines[:1 + 200 + 401]) + "\n")  # 1 s before the ground truth + 2 s
    for method in METHODS:
        out = tmp_path / f"{method}.tum"
        assert cli.main(["integrate", str(short), "--init", str(gt), "--method", method, "-o", str(out)]) == 0
        text = capsys.readouterr().out
        drift = float(text.split("differs from the ground truth by ")[1].split()[0])
        assert drift < 0.2, (method, drift)
    assert cli.main(["integrate", str(short), "--init", str(gt), "--gravity", "0", "0", "9.81",
                     "-o", str(tmp_path / "g.tum")]) == 0
    drift = float(capsys.readouterr().out.split("differs from the ground truth by ")[1].split()[0])
    assert drift > 10.0


# --------------------------------------------------------------------------------- library


def test_dead_reckon_library_equals_cli(tmp_path, capsys):
    scene = make_scene("ellipse", duration_s=5.0, t0_ns=5_000_000_000)
    t_ns = _write_dataset(tmp_path / "d", scene, 200.0, gt_every=2, gt_shift_ns=-2_500_000, gt_start=10)
    imu = tmp_path / "d" / "imu0" / "data.csv"
    res = dead_reckon(imu, method="midpoint")
    assert res.skipped_samples == 10 and res.method == "midpoint"
    np.testing.assert_array_equal(res.t_ns, t_ns[10:])
    assert res.groundtruth_path == default_groundtruth_path(imu)
    df = res.to_dataframe()
    assert list(df.columns[:3]) == ["t_ns", "t_s", "px"] and len(df) == t_ns.size - 10
    assert res.final_position_error_m is None  # the last IMU stamp is 2.5 ms after the ground truth
    lib = res.write_tum(tmp_path / "lib.tum")
    assert cli.main(["integrate", str(imu), "--method", "midpoint", "-o", str(tmp_path / "cli.tum")]) == 0
    assert "differs from the ground truth" not in capsys.readouterr().out
    assert lib.read_bytes() == (tmp_path / "cli.tum").read_bytes()
    assert res.write_tum(tmp_path / "new" / "sub" / "x.tum").read_bytes() == lib.read_bytes()  # folders made
    with pytest.raises(ConfigError, match="`method` must be one of"):
        dead_reckon(imu, method="rk5")


def test_groundtruth_interpolation():
    angle = 0.8
    q = np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)]])
    p = np.array([[0.0, 0.0, 0.0], [2.0, 4.0, -6.0]])
    gt = GroundTruth([100, 300], p, q, p * 10, p * 0.1, p * 0.01, path="gt.csv")
    s = gt.state_at(150)  # u = 1/4
    np.testing.assert_allclose(s.position_world, [0.5, 1.0, -1.5], rtol=0, atol=1e-15)
    np.testing.assert_allclose(s.velocity_world, [5.0, 10.0, -15.0], rtol=0, atol=1e-14)
    np.testing.assert_allclose(s.bias_accel, [0.005, 0.01, -0.015], rtol=0, atol=1e-17)
    np.testing.assert_allclose(so3_log(s.world_R_body), [0.0, 0.0, angle / 4], atol=1e-15)
    np.testing.assert_allclose(quat_xyzw_to_matrix(s.quat_xyzw), s.world_R_body, atol=1e-15)
    end = gt.state_at(300)  # a stamp: the stored row itself
    np.testing.assert_array_equal(end.quat_xyzw, q[1])
    np.testing.assert_array_equal(end.position_world, p[1])
    assert gt.covers(100) and not gt.covers(301)
    with pytest.raises(RangeError, match=r"gt\.csv: time 99 ns is outside the ground truth \[100, 300\] ns"):
        gt.state_at(99)
    from splineimu.io.poses import PoseTrack

    with pytest.raises(InputError, match="17-column"):
        GroundTruth.from_track(PoseTrack(np.array([0, 1]), p, q))
    with pytest.raises(InputError, match="strictly increasing"):
        GroundTruth([5, 5], p, q, p, p, p)


def test_a_gap_in_the_imu_stamps_is_noted(tmp_path):
    """1 s cut out of 20 s of the ellipse at 200 Hz ended 17 m off (6e-8 m without the gap),
    with nothing said; the result now carries a note naming the gap."""
    imu = "".join(f"{i * 5_000_000},0,0,0,0,0,9.81\n" for i in range(400) if not 100 < i < 300)
    (tmp_path / "imu.csv").write_text(imu)
    (tmp_path / "gt.csv").write_text("".join(f"{i * 1_000_000_000},0,0,0,1" + ",0" * 12 + "\n" for i in range(3)))
    r = dead_reckon(tmp_path / "imu.csv", init=tmp_path / "gt.csv")
    assert r.notes == ["1 gap(s) in the IMU stamps longer than 1.5 sample intervals (longest 1 s after 0.5 s): "
                       "the motion across a gap is integrated from its two end samples alone"]
    assert r.final_position_error_m < 1e-9  # at rest the gap costs nothing
    (tmp_path / "even.csv").write_text("".join(f"{i * 5_000_000},0,0,0,0,0,9.81\n" for i in range(400)))
    assert dead_reckon(tmp_path / "even.csv", init=tmp_path / "gt.csv").notes == []


def test_a_broken_report_json_is_not_taken_for_point_samples(tmp_path):
    """report.json records --sampling mean; a truncated one was read as 'point' in silence (the
    ellipse, 10 s: 0.24 m off instead of 3e-8 m). It is refused unless --sampling is given."""
    imu = tmp_path / "mav0" / "imu0" / "data.csv"
    imu.parent.mkdir(parents=True)
    imu.write_text("".join(f"{i * 5_000_000},0,0,0,0,0,9.81\n" for i in range(50)))
    gt = tmp_path / "gt.csv"
    gt.write_text("".join(f"{i * 100_000_000},0,0,0,1" + ",0" * 12 + "\n" for i in range(3)))
    (tmp_path / "report.json").write_text('{"imu": {"sampling": "me')
    with pytest.raises(InputError) as e:
        dead_reckon(imu, init=gt)
    assert str(e.value).startswith(f"{tmp_path / 'report.json'}:1: not valid JSON (")
    assert "give --sampling point|mean" in str(e.value)
    with pytest.raises(InputError, match="records the IMU clock's offset and drift: repair it, or give --time-offset"):
        dead_reckon(imu, init=gt, sampling="mean")  # nor for an IMU clock without offset
    assert dead_reckon(imu, init=gt, sampling="mean", time_offset_s=0, clock_drift_ppm=0).sampling == "mean"
    (tmp_path / "report.json").write_text('{"imu": {"sampling": "mean"}}')
    assert dead_reckon(imu, init=gt).sampling == "mean"


def test_a_tum_file_as_initial_state_gets_the_right_advice(tmp_path):
    """groundtruth.tum (which scene and from-tum write) given to --init was answered with 'use
    `splineimu from-tum`', the advice for synthesis; integrate needs the 17-column ground truth."""
    imu = tmp_path / "imu.csv"
    imu.write_text("".join(f"{i * 5_000_000},0,0,0,0,0,9.81\n" for i in range(10)))
    tum = tmp_path / "groundtruth.tum"
    tum.write_text("# timestamp tx ty tz qx qy qz qw\n" + "".join(f"{i * 0.005:.9f} 0 0 0 0 0 0 1\n" for i in range(5)))
    with pytest.raises(InputError) as e:
        dead_reckon(imu, init=tum)
    msg = str(e.value)
    assert msg.endswith("the file looks like a TUM trajectory (t x y z qx qy qz qw, seconds): this needs the "
                        "17-column EuRoC ground truth, e.g. OUT/mav0/state_groundtruth_estimate0/data.csv")
    assert "from-tum" not in msg


def test_a_folder_given_as_initial_state_is_named_a_folder(tmp_path):
    """--init FOLDER was reported as 'initial-state file not found'."""
    imu = tmp_path / "imu.csv"
    imu.write_text("".join(f"{i * 5_000_000},0,0,0,0,0,9.81\n" for i in range(10)))
    with pytest.raises(ConfigError) as e:
        dead_reckon(imu, init=tmp_path)
    assert str(e.value) == f"initial-state file is a folder, expected the ground-truth csv: {tmp_path}"
