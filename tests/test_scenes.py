"""Analytic scenes: exact derivatives against central differences, closed-form values,
registry and parameter validation, time base and TUM output."""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import pytest
from numdiff import assert_derivative_close, time_derivative
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from splineimu import scenes
from splineimu.errors import ConfigError, RangeError
from splineimu.io.tum import write_scene_tum
from splineimu.lie import quat_xyzw_to_matrix, se3_hat, so3_exp
from splineimu.scenes import (
    SCENES,
    Scene,
    StaticScene,
    euler_zyx_kinematics,
    make_scene,
    register_scene,
    scene_names,
)

BUILTIN = ["ellipse", "static", "circle", "screw", "flips"]

#: Outer difference step per scene: ~1e-2 / (fastest frequency in rad/s) (tests/numdiff.py notes).
STEP_S = {"ellipse": 2e-3, "static": 1e-2, "circle": 1e-2, "screw": 1e-2, "flips": 5e-4}

#: Non-default parameters exercised as well (every axis and branch moving).
VARIANTS = {
    "static": {"position_m": (1.0, -2.0, 3.0), "yaw_rad": 0.7},
    "circle": {"radius_m": 3.0, "speed_m_s": -2.5, "center_m": (1, 2, 3), "phase_rad": 0.4},
    "screw": {"v_body_m_s": (0.5, -1.0, 0.3), "omega_body_rad_s": (1.2, -0.7, 2.0),
              "initial_position_m": (1, 2, 3), "initial_rotvec_rad": (0.3, -2.0, 1.0)},
    "flips": {"turn_rate_rad_s": (-7.0, 6.0, 4.0), "wobble_scale": 1.5},
    "ellipse": {"k_rad_s": 0.5, "k1": 4.0},
}

RTOL = 1e-7
EPOCH_NS = 1_403_636_579_758_555_392


def _times(sc, n=31):
    """Interior times (stencils of width +-h stay inside the valid range), incl. odd ones."""
    T = sc.t_max_s
    t = np.linspace(0.02 * T, 0.98 * T, n)
    return np.concatenate([t, [0.3333333 * T, 0.7071 * T]])


def _check_derivatives(sc, h):
    """Every exact derivative against Richardson-extrapolated central differences (order 6)."""
    t = _times(sc)
    k = sc.kinematics(t)
    pos = lambda s: sc.kinematics(s).position_world  # noqa: E731
    vel = lambda s: sc.kinematics(s).velocity_world  # noqa: E731
    rot = lambda s: sc.kinematics(s).world_R_body  # noqa: E731
    omg = lambda s: sc.kinematics(s).omega_body  # noqa: E731
    # Per-sample relative, with an absolute floor of 1e-7 of the largest value along the path
    # for samples where the quantity passes near zero.
    pairs = [
        ("velocity_world", k.velocity_world, time_derivative(pos, t, h)),
        ("accel_world", k.accel_world, time_derivative(vel, t, h)),
        ("omega_body", k.omega_body, time_derivative(rot, t, h, group="so3")),
        ("alpha_body", k.alpha_body, time_derivative(omg, t, h)),
    ]
    worst = {}
    for label, exact, num in pairs:
        floor = RTOL * max(float(np.max(np.abs(exact))), 1e-3)
        assert_derivative_close(exact, num, rtol=RTOL, atol=floor, label=f"{sc.name} {label}", t=t)
        worst[label] = float(np.max(np.abs(exact - num)))
    return worst


@pytest.mark.parametrize("name", BUILTIN)
@pytest.mark.parametrize("variant", ["default", "variant"])
def test_exact_derivatives_match_central_differences(name, variant):
    params = VARIANTS[name] if variant == "variant" else {}
    sc = make_scene(name, **params)
    _check_derivatives(sc, STEP_S[name])
    # Rotations are proper and orthonormal to rounding.
    R = sc.kinematics(_times(sc)).world_R_body
    assert np.max(np.abs(np.matmul(np.swapaxes(R, 1, 2), R) - np.eye(3))) < 1e-14
    assert np.allclose(np.linalg.det(R), 1.0, atol=1e-14, rtol=0)


def test_derivative_check_is_sensitive():
    """A scene whose acceleration is off by 1e-6 relative must fail the same check."""

    class Wrong(scenes.EllipseScene):
        def _evaluate(self, t):
            p, v, a, R, w, al = super()._evaluate(t)
            return p, v, a * (1 + 1e-6), R, w, al

    Wrong.name = "ellipse-wrong"
    with pytest.raises(AssertionError, match="accel_world"):
        _check_derivatives(Wrong(), STEP_S["ellipse"])


def test_euler_zyx_matches_scipy_and_derivatives():
    rng = np.random.default_rng(3)
    ang = rng.uniform(-4, 4, (50, 3))
    R, _, _ = euler_zyx_kinematics(ang, np.zeros((50, 3)), np.zeros((50, 3)))
    ref = Rotation.from_euler("ZYX", ang[:, ::-1]).as_matrix()  # intrinsic Rz Ry Rx
    assert np.max(np.abs(R - ref)) < 1e-15


# --------------------------------------------------------------------------- ellipse


def test_ellipse_matches_design_formulas():
    K, K1 = math.pi / 10, 10.0
    sc = make_scene("ellipse")
    assert sc.duration_s == 20.0
    t = np.array([0.0, 5.0, 7.25, 20.0])
    k = sc.kinematics(t)
    p_ref = np.stack([15 * np.cos(K * t) + 5, 20 * np.sin(K * t) + 5, np.sin(K1 * K * t) + 5], axis=1)
    assert np.max(np.abs(k.position_world - p_ref)) < 1e-13
    np.testing.assert_allclose(k.position_world[0], [20.0, 5.0, 5.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(k.position_world[1], [5.0, 25.0, 5.0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(k.position_world[3], k.position_world[0], rtol=0, atol=1e-12)  # one lap
    np.testing.assert_allclose(k.velocity_world[0], [0.0, 20 * K, K1 * K], rtol=0, atol=1e-15)
    roll, pitch, yaw = 0.1 * np.cos(t), 0.2 * np.sin(t), K * t
    R_ref = Rotation.from_euler("ZYX", np.stack([yaw, pitch, roll], axis=1)).as_matrix()
    assert np.max(np.abs(k.world_R_body - R_ref)) < 1e-15
    # w_b = E(r, p) (dr, dp, dy), written out by hand at t = 0: r = 0.1, p = 0, dr = 0, dp = 0.2.
    r = 0.1
    np.testing.assert_allclose(
        k.omega_body[0], [0.0, np.cos(r) * 0.2 + np.sin(r) * K, -np.sin(r) * 0.2 + np.cos(r) * K],
        rtol=0, atol=1e-16,
    )
    # Accelerometer at t = 0: R^T (a - g) with a = (-15 K^2, 0, 0).
    f = sc.specific_force_body([0.0])[0]
    np.testing.assert_allclose(f, R_ref[0].T @ np.array([-15 * K * K, 0.0, 9.81]), rtol=0, atol=1e-14)


# --------------------------------------------------------------------------- static


def test_static_reads_gravity_and_zero_rate():
    sc = make_scene("static", duration_s=60.0, **VARIANTS["static"])
    t = np.linspace(0, 60, 7)
    gyro, f = sc.imu(t)
    assert np.array_equal(gyro, np.zeros((7, 3)))
    np.testing.assert_allclose(f, np.tile([0.0, 0.0, 9.81], (7, 1)), rtol=0, atol=1e-15)
    k = sc.kinematics(t)
    np.testing.assert_array_equal(k.position_world, np.tile([1.0, -2.0, 3.0], (7, 1)))
    assert np.array_equal(k.velocity_world, np.zeros((7, 3)))
    assert np.array_equal(k.accel_world, np.zeros((7, 3)))
    np.testing.assert_allclose(k.world_R_body[0], so3_exp([0, 0, 0.7]), rtol=0, atol=1e-15)


def test_static_three_hours_at_200hz_is_vectorized():
    # Vectorized arrays for 2.16e6 samples (its speed is measured in benchmarks/bench_allan.py).
    sc = make_scene("static", duration_s=3 * 3600.0)
    t = np.arange(2_160_000) / 200.0
    k = sc.kinematics(t)
    assert k.world_R_body.shape == (2_160_000, 3, 3) and k.world_R_body.flags.c_contiguous
    assert k.omega_body.flags.writeable
    assert np.array_equal(k.world_R_body[-1], np.eye(3))


# --------------------------------------------------------------------------- circle


@pytest.mark.parametrize("speed", [2.0, -2.5])
def test_circle_reads_centripetal_force_on_body_y(speed):
    r = 3.0
    sc = make_scene("circle", radius_m=r, speed_m_s=speed, center_m=(1, 2, 3))
    t = np.linspace(0, 20, 11)
    gyro, f = sc.imu(t)
    k = sc.kinematics(t)
    np.testing.assert_allclose(gyro, np.tile([0, 0, speed / r], (11, 1)), rtol=0, atol=1e-15)
    # body x along the velocity, body z up, centripetal force towards the centre
    vdir = k.velocity_world / np.linalg.norm(k.velocity_world, axis=1, keepdims=True)
    np.testing.assert_allclose(k.world_R_body[:, :, 0], vdir, rtol=0, atol=1e-14)
    np.testing.assert_allclose(k.world_R_body[:, :, 2], np.tile([0, 0, 1.0], (11, 1)), atol=1e-15)
    side = speed * speed / r * np.sign(speed)
    np.testing.assert_allclose(f, np.tile([0.0, side, 9.81], (11, 1)), rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.linalg.norm(k.position_world - [1, 2, 3], axis=1), r, rtol=1e-15)


# --------------------------------------------------------------------------- screw


def test_screw_pose_is_T0_exp_t_xi_with_constant_body_twist():
    params = VARIANTS["screw"]
    sc = make_scene("screw", **params)
    xi = np.concatenate([params["v_body_m_s"], params["omega_body_rad_s"]])
    T0 = np.eye(4)
    T0[:3, :3] = Rotation.from_rotvec(params["initial_rotvec_rad"]).as_matrix()
    T0[:3, 3] = params["initial_position_m"]
    np.testing.assert_allclose(sc.world_T_body0, T0, rtol=0, atol=1e-15)
    t = np.array([0.0, 0.37, 3.0, 11.1, 20.0])
    k = sc.kinematics(t)
    for i, ti in enumerate(t):
        T = T0 @ expm(ti * se3_hat(xi))  # independent: matrix exponential of the twist
        np.testing.assert_allclose(k.world_R_body[i], T[:3, :3], rtol=0, atol=1e-12)
        np.testing.assert_allclose(k.position_world[i], T[:3, 3], rtol=0, atol=1e-11)
    # R^T dR/dt (numerically) is the constant w_b, and R^T dp/dt the constant v_b.
    tt = np.linspace(0.5, 19.5, 9)
    w_num = time_derivative(lambda s: sc.kinematics(s).world_R_body, tt, 1e-2, group="so3")
    np.testing.assert_allclose(w_num, np.tile(xi[3:], (9, 1)), rtol=0, atol=1e-9)
    v_num = time_derivative(lambda s: sc.kinematics(s).position_world, tt, 1e-2)
    vb = np.einsum("nji,nj->ni", sc.kinematics(tt).world_R_body, v_num)
    np.testing.assert_allclose(vb, np.tile(xi[:3], (9, 1)), rtol=0, atol=1e-9)
    assert np.array_equal(k.alpha_body, np.zeros((5, 3)))


# --------------------------------------------------------------------------- flips


def test_flips_is_fast_and_tumbles_through_full_turns():
    sc = make_scene("flips")
    t = np.linspace(0.0, sc.t_max_s, 20_001)  # 1 kHz
    k = sc.kinematics(t)
    rate = np.linalg.norm(k.omega_body, axis=1)
    assert rate.max() > scenes.FlipsScene.PEAK_OMEGA_RAD_S  # documented: > 15 (measured 17.8)
    assert rate.max() < 25.0
    # Total rotation traversed, and the body really turns upside down again and again.
    traversed = np.sum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))
    assert traversed > 20 * 2 * np.pi
    up = k.world_R_body[:, 2, 2]  # cosine between body z and world z
    assert up.min() < -0.99 and up.max() > 0.99
    assert np.count_nonzero(np.diff(np.sign(up)) != 0) >= 40  # measured 60
    # Shaky translation: a few m/s^2 peak.
    acc = np.linalg.norm(k.accel_world, axis=1).max()
    assert 2.0 < acc < 10.0


def test_flips_scales():
    still = make_scene("flips", shake_scale=0.0, position_m=(1, 2, 3))
    k = still.kinematics(np.linspace(0, 20, 5))
    np.testing.assert_array_equal(k.position_world, np.tile([1.0, 2.0, 3.0], (5, 1)))
    ramps = make_scene("flips", wobble_scale=0.0, turn_rate_rad_s=(0.0, 0.0, 2.0))
    np.testing.assert_allclose(ramps.kinematics([0.0, 7.0]).omega_body, [[0, 0, 2.0], [0, 0, 2.0]],
                               rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- time base


@pytest.mark.parametrize("name", BUILTIN)
def test_queries_outside_range_raise(name):
    sc = make_scene(name, duration_s=4.0)
    sc.kinematics([0.0, 4.0])  # both ends are valid
    for bad in ([-1e-3], [4.0 + 1e-3], [1.0, np.nan], [[1.0, 2.0]]):
        with pytest.raises(RangeError):
            sc.kinematics(bad)


def test_epoch_origin_ns():
    a = make_scene("flips", t0_ns=EPOCH_NS)
    b = make_scene("flips")
    assert a.origin_ns == EPOCH_NS and a.t_min_s == 0.0 and a.t_max_s == 20.0
    t_ns = np.array([EPOCH_NS, EPOCH_NS + 5_000_000_000, EPOCH_NS + 12_345_678_901])
    t_s = a.t_s_from_ns(t_ns)
    np.testing.assert_array_equal(t_s, [0.0, 5.0, 12.345678901])
    ka, kb = a.kinematics(t_s), b.kinematics([0.0, 5.0, 12.345678901])
    np.testing.assert_array_equal(ka.omega_body, kb.omega_body)
    np.testing.assert_array_equal(ka.position_world, kb.position_world)
    stamps = a.sample_times_ns(200)
    assert stamps.dtype == np.int64 and len(stamps) == 4001
    assert stamps[0] == EPOCH_NS and stamps[-1] == EPOCH_NS + 20_000_000_000
    assert np.all(np.diff(stamps) == 5_000_000)
    assert make_scene("static", t0_ns=str(EPOCH_NS)).origin_ns == EPOCH_NS


def test_sample_times_at_a_rate_that_does_not_divide_a_second():
    sc = make_scene("circle", duration_s=1.0, t0_ns=7)
    st = sc.sample_times_ns(300)
    assert len(st) == 301 and st[-1] == 1_000_000_007
    np.testing.assert_array_equal(st - 7, [round(k * 1e9 / 300) for k in range(301)])
    sc.kinematics(sc.t_s_from_ns(st))  # all valid


# --------------------------------------------------------------------------- TUM output


def _read_tum(path):
    rows = [ln.split() for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    stamps = [r[0] for r in rows]
    vals = np.array([[float(x) for x in r[1:]] for r in rows])
    return stamps, vals


def test_write_scene_tum_epoch_exact_stamps_and_poses(tmp_path):
    sc = make_scene("screw", duration_s=2.0, t0_ns=EPOCH_NS, **VARIANTS["screw"])
    out = tmp_path / "sub" / "gt.tum"
    write_scene_tum(sc, out, 50.0)
    stamps, vals = _read_tum(out)
    assert len(stamps) == 101
    assert stamps[0] == "1403636579.758555392"
    assert stamps[1] == "1403636579.778555392"
    assert stamps[-1] == "1403636581.758555392"
    t_s = np.arange(101) / 50.0
    k = sc.kinematics(t_s)
    np.testing.assert_allclose(vals[:, :3], k.position_world, rtol=0, atol=1e-8)
    R = quat_xyzw_to_matrix(vals[:, 3:7])  # qx qy qz qw
    assert np.max(np.abs(R - k.world_R_body)) < 1e-9
    q = vals[:, 3:7]
    assert np.all(np.einsum("ij,ij->i", q[1:], q[:-1]) > 0)  # sign-continuous
    # overwrite in place, no temporary files left behind
    write_scene_tum(make_scene("static", duration_s=1.0), out, 10)
    assert len(_read_tum(out)[0]) == 11
    assert sorted(p.name for p in out.parent.iterdir()) == ["gt.tum"]


# --------------------------------------------------------------------------- registry and config


def test_builtin_names_registered():
    names = scene_names()
    assert set(BUILTIN) <= set(names) and names == sorted(names)
    for n in BUILTIN:
        assert SCENES[n].name == n and isinstance(make_scene(n), Scene)


def test_unknown_scene_did_you_mean():
    with pytest.raises(ConfigError, match=r"unknown scene 'elipse'\. Did you mean 'ellipse'\?"):
        make_scene("elipse")
    with pytest.raises(ConfigError, match="Known scenes:.*flips"):
        make_scene("zzzz")


@pytest.mark.parametrize(
    ("name", "kwargs", "match"),
    [
        ("circle", {"radius": 2.0}, r"no parameter 'radius'\. Did you mean 'radius_m'\?"),
        ("circle", {"radius_m": -1.0}, "must be > 0"),
        ("circle", {"radius_m": float("nan")}, "must be finite"),
        ("circle", {"center_m": (1.0, 2.0)}, "expected 3 values"),
        ("circle", {"speed_m_s": "fast"}, "cannot read 'fast'"),
        ("circle", {"speed_m_s": True}, "expected a number"),
        ("flips", {"wobble_scale": -0.5}, "must be >= 0"),
        ("static", {"duration_s": 0.0}, "duration_s"),
        ("static", {"duration_s": "abc"}, "duration_s"),
        ("static", {"duration_s": float("inf")}, "duration_s"),
        ("static", {"t0_ns": 1.5}, "t0_ns"),
        ("static", {"t0_ns": -1}, "t0_ns"),
        ("static", {"t0_ns": "1e9"}, "t0_ns"),
    ],
)
def test_bad_parameters_raise_config_error(name, kwargs, match):
    with pytest.raises(ConfigError, match=match):
        make_scene(name, **kwargs)


def test_string_parameters_as_from_a_command_line():
    sc = make_scene("screw", v_body_m_s="1, 2,3", omega_body_rad_s="0 0 0.5", duration_s="5")
    np.testing.assert_array_equal(sc.params["v_body_m_s"], [1.0, 2.0, 3.0])
    assert sc.duration_s == 5.0
    assert make_scene("circle", radius_m="2.5").params["radius_m"] == 2.5
    with pytest.raises(ValueError):
        sc.params["v_body_m_s"][0] = 9.0  # read-only: a scene is immutable


def test_describe_round_trips_and_is_json():
    for n in BUILTIN:
        sc = make_scene(n, duration_s=3.0, t0_ns=EPOCH_NS, **VARIANTS[n])
        d = json.loads(json.dumps(sc.describe()))
        assert d["name"] == n and d["duration_s"] == 3.0 and d["t0_ns"] == EPOCH_NS
        assert set(d["units"]) == set(d["params"])
        again = make_scene(d["name"], d["duration_s"], d["t0_ns"], **d["params"])
        t = np.linspace(0, 3, 5)
        np.testing.assert_array_equal(again.kinematics(t).accel_world, sc.kinematics(t).accel_world)


def test_docstrings_document_formulas_duration_and_parameters():
    for n in BUILTIN:
        cls = SCENES[n]
        doc = cls.__doc__
        assert f"Default duration: {cls.DEFAULT_DURATION_S:g} s" in doc, n
        assert "Formulas" in doc, n
        for pname, spec in cls.PARAMS.items():
            assert f"{pname} :" in doc, (n, pname)
            unit = spec.unit if spec.unit != "1" else "[1]"
            assert unit in doc, (n, pname, spec.unit)


def test_register_from_another_module_and_duplicates():
    @register_scene("test-still")
    class Still(StaticScene):
        """Static under another name."""

    try:
        assert "test-still" in scene_names()
        sc = make_scene("test-still", position_m=(0, 0, 2))
        assert sc.describe()["name"] == "test-still"
        np.testing.assert_array_equal(sc.imu([0.0])[1], [[0, 0, 9.81]])
        register_scene("test-still")(Still)  # the same class again (module reload) is fine

        class Other(StaticScene):
            pass

        with pytest.raises(ConfigError, match="already registered"):
            register_scene("test-still")(Other)
        with pytest.raises(ConfigError, match="not a subclass"):
            register_scene("test-bad")(dict)
    finally:
        SCENES.pop("test-still", None)
    assert "test-still" not in SCENES


def test_extra_scene_modules_are_optional_but_not_their_imports(tmp_path, monkeypatch):
    monkeypatch.setattr(scenes.base, "EXTRA_SCENE_MODULES", ("splineimu._no_such_scene_module",))
    assert set(BUILTIN) <= set(scene_names())

    (tmp_path / "_extra_scenes_ok.py").write_text(
        "from splineimu.scenes import StaticScene, register_scene\n"
        "@register_scene('test-extra')\n"
        "class Extra(StaticScene):\n"
        "    '''Extra.'''\n"
    )
    (tmp_path / "_extra_scenes_broken.py").write_text("import _no_such_dependency_xyz\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        monkeypatch.setattr(scenes.base, "EXTRA_SCENE_MODULES", ("_extra_scenes_ok",))
        assert isinstance(make_scene("test-extra"), StaticScene)  # loaded lazily by make_scene
        monkeypatch.setattr(scenes.base, "EXTRA_SCENE_MODULES", ("_extra_scenes_broken",))
        with pytest.raises(ModuleNotFoundError, match="_no_such_dependency_xyz"):
            scene_names()
    finally:
        SCENES.pop("test-extra", None)
        sys.modules.pop("_extra_scenes_ok", None)
        sys.modules.pop("_extra_scenes_broken", None)


def test_parameters_without_finite_motion_are_refused():
    """A circle at 1e300 m/s overflows: refused naming the scene and its parameters (it reached
    the table writer as 'Expected finite values, got nan at row 0, column 3', no scene named)."""
    from splineimu.errors import ConfigError

    sc = make_scene("circle", speed_m_s=1e300)
    with pytest.raises(ConfigError, match=r"scene 'circle' with .*'speed_m_s': 1e\+300.* no finite motion at t = 0 s"):
        sc.kinematics([0.0, 1.0])
    assert np.isfinite(make_scene("circle", speed_m_s=50.0).kinematics([0.0, 1.0]).accel_world).all()
