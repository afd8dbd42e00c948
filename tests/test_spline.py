"""Spline core: analytic derivatives against central differences, continuity, closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from numdiff import assert_derivative_close, time_derivative
from scipy.interpolate import BSpline
from scipy.spatial.transform import Rotation

from splineimu import RangeError, Spline, SplineImuError, lie
from splineimu.spline.basis import basis_values, blending_matrix

KINDS = ["split", "se3"]
ORDERS = [4, 5, 6]
RTOL = 1e-7


def random_spline(kind, order, n=12, dt=0.2, seed=0, step_angle=0.6, origin_ns=0, t0=0.3):
    rng = np.random.default_rng(seed)
    pos = np.cumsum(rng.normal(size=(n, 3)), axis=0)
    steps = rng.normal(size=(n, 3))
    steps *= step_angle / np.linalg.norm(steps, axis=1, keepdims=True)
    R = [Rotation.from_rotvec(rng.normal(size=3))]
    for s in steps[1:]:
        R.append(R[-1] * Rotation.from_rotvec(s))
    quat = np.array([r.as_quat() for r in R])
    return Spline.from_control_points(t0, dt, pos, quat, kind=kind, order=order, origin_ns=origin_ns)


def interior_times(spl, n=40, margin=None, seed=1):
    """Sample times at least ``margin`` from every knot (finite differences need smoothness)."""
    margin = 0.05 * spl.dt_s if margin is None else margin
    rng = np.random.default_rng(seed)
    seg = rng.integers(0, spl.n_segments, n)
    u = rng.uniform(margin / spl.dt_s, 1 - margin / spl.dt_s, n)
    return spl.t_min_s + (seg + u) * spl.dt_s


def check(analytic, numeric, label, rtol=RTOL, t=None):
    scale = np.abs(analytic).max()
    assert_derivative_close(analytic, numeric, rtol=rtol, atol=rtol * scale, label=label, t=t)


# ------------------------------------------------------------------------------- basis
@pytest.mark.parametrize("order", [2, 3, 4, 5, 6, 7, 8])
def test_basis_matches_scipy_cardinal_bspline(order):
    u = np.linspace(0, 1, 11)
    ref = np.stack([BSpline.basis_element(np.arange(order + 1), extrapolate=False)(u + order - 1 - j)
                    for j in range(order)], axis=1)
    ref[-1] = basis_values(order, [1.0])[0]  # basis_element is open on the right end
    np.testing.assert_allclose(basis_values(order, u), ref, atol=1e-14)
    np.testing.assert_allclose(basis_values(order, u).sum(axis=1), 1.0, atol=1e-14)
    Mc = blending_matrix(order, cumulative=True)
    np.testing.assert_allclose(Mc[0], np.eye(order)[0], atol=1e-15)  # Btilde_0 = 1


def test_basis_derivatives_match_differences():
    u = np.linspace(0.1, 0.9, 9)
    h = 1e-6
    for order in ORDERS:
        d1 = basis_values(order, u, derivative=1)
        fd = (basis_values(order, u + h) - basis_values(order, u - h)) / (2 * h)
        np.testing.assert_allclose(d1, fd, atol=1e-8)


# -------------------------------------------------------------------------- derivatives
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("order", ORDERS)
def test_derivatives_against_central_differences(kind, order):
    spl = random_spline(kind, order)
    t = interior_times(spl)
    h = 0.02 * spl.dt_s  # stencil [t - h, t + h] stays inside one segment (margin 0.05 dt)
    K = spl.kinematics(t)
    check(K.velocity_world, time_derivative(lambda s: spl.pose(s)[0], t, h), f"{kind}{order} velocity", t=t)
    check(K.accel_world, time_derivative(spl.velocity_world, t, h), f"{kind}{order} accel", t=t)
    check(K.omega_body, time_derivative(spl.rotation_matrix, t, h, group="so3"), f"{kind}{order} omega", t=t)
    check(K.alpha_body, time_derivative(spl.angular_velocity_body, t, h), f"{kind}{order} alpha", t=t)


@pytest.mark.parametrize("kind", KINDS)
def test_single_quantity_methods_agree_with_kinematics(kind):
    spl = random_spline(kind, 4)
    t = interior_times(spl)
    K = spl.kinematics(t)
    g = np.array([0.1, -0.2, -9.7])
    np.testing.assert_array_equal(spl.angular_velocity_body(t), K.omega_body)
    np.testing.assert_array_equal(spl.angular_acceleration_body(t), K.alpha_body)
    np.testing.assert_array_equal(spl.velocity_world(t), K.velocity_world)
    np.testing.assert_allclose(spl.acceleration_world(t), K.accel_world, rtol=0, atol=1e-12)
    f_ref = np.einsum("nji,nj->ni", K.world_R_body, K.accel_world - g)
    np.testing.assert_allclose(spl.specific_force_body(t, gravity=g), f_ref, atol=1e-11)
    gyro, f = spl.imu(t, gravity=g)
    # the vectorized kernels rotate with polynomials instead of libm sin / cos
    err = np.linalg.norm(gyro - K.omega_body, axis=1) / np.linalg.norm(K.omega_body, axis=1)
    assert err.max() < 1e-14
    np.testing.assert_allclose(f, f_ref, atol=1e-11)
    p, q = spl.pose(t)
    np.testing.assert_array_equal(p, K.position_world)
    np.testing.assert_allclose(lie.quat_xyzw_to_matrix(q), K.world_R_body, atol=1e-15)


@pytest.mark.parametrize("order", ORDERS)
def test_continuity_across_knots(order):
    """C^(k-2): position..(k-2)-th derivative continuous; for k = 4 omega and alpha too."""
    for kind in KINDS:
        spl = random_spline(kind, order)
        knots = spl.t_min_s + spl.dt_s * np.arange(1, spl.n_segments)
        e = 1e-9
        a = spl.kinematics(knots - e)
        b = spl.kinematics(knots + e)
        for name in ("position_world", "velocity_world", "accel_world", "omega_body", "alpha_body"):
            x, y = getattr(a, name), getattr(b, name)
            # one derivative beyond the quantity changes by at most ~ (jerk) * 2e
            assert np.abs(x - y).max() < 1e-6 * max(1.0, np.abs(x).max()), (kind, order, name)
        assert np.abs(a.world_R_body - b.world_R_body).max() < 1e-7


def test_split_and_se3_share_rotation_and_gyro():
    for order in ORDERS:
        a = random_spline("split", order)
        b = random_spline("se3", order)
        t = np.linspace(a.t_min_s, a.t_max_s, 301)
        np.testing.assert_array_equal(a.rotation_matrix(t), b.rotation_matrix(t))
        np.testing.assert_array_equal(a.angular_velocity_body(t), b.angular_velocity_body(t))
        np.testing.assert_array_equal(a.angular_acceleration_body(t), b.angular_acceleration_body(t))


def test_split_position_is_scipy_bspline():
    """The split spline's position is the ordinary uniform B-spline of the control points."""
    for order in ORDERS:
        spl = random_spline("split", order, n=15)
        n, k, dt = spl.n_control, order, spl.dt_s
        knots = spl.t_min_s + dt * (np.arange(n + k) - (k - 1))
        ref = BSpline(knots, spl.control_positions, k - 1, extrapolate=False)
        t = np.linspace(spl.t_min_s, spl.t_max_s, 500)
        t[-1] = np.nextafter(t[-1], -np.inf)
        np.testing.assert_allclose(spl.pose(t)[0], ref(t), atol=1e-12)
        np.testing.assert_allclose(spl.acceleration_world(t), ref.derivative(2)(t), atol=1e-9)


# ------------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("order", ORDERS)
def test_constant_twist_screw_is_exact_on_se3(order):
    """Control poses T0 Exp(i dt xi) give T(t) = T0 Exp((t - c) xi): constant body twist."""
    xi = np.array([1.0, -0.5, 0.3, 0.4, -0.7, 1.1])  # [v_b, w_b]
    T0 = lie.se3_exp([2.0, -1.0, 3.0, 0.2, 0.3, -0.1])
    dt, n = 0.1, 14
    T = T0 @ lie.se3_exp(np.outer(np.arange(n) * dt, xi))
    quat = lie.matrix_to_quat_xyzw(T[:, :3, :3])
    spl = Spline.from_control_points(0.0, dt, T[:, :3, 3], quat, kind="se3", order=order)
    t = np.linspace(spl.t_min_s, spl.t_max_s, 200)
    K = spl.kinematics(t)
    np.testing.assert_allclose(K.omega_body, np.tile(xi[3:], (t.size, 1)), atol=1e-12)
    np.testing.assert_allclose(K.alpha_body, 0.0, atol=1e-10)
    v_b = np.einsum("nji,nj->ni", K.world_R_body, K.velocity_world)
    np.testing.assert_allclose(v_b, np.tile(xi[:3], (t.size, 1)), atol=1e-12)
    # the spline passes through T0 Exp((t + c) xi) with c = (k - 2)/2 * dt (linear precision)
    c = (order - 2) / 2 * dt
    Tref = T0 @ lie.se3_exp(np.outer(t + c, xi))
    np.testing.assert_allclose(K.world_R_body, Tref[:, :3, :3], atol=1e-12)
    np.testing.assert_allclose(K.position_world, Tref[:, :3, 3], atol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_static_spline_reads_minus_gravity(kind):
    n = 6
    spl = Spline.from_control_points(0.0, 0.5, np.tile([1.0, 2.0, 3.0], (n, 1)),
                                     np.tile([0, 0, 0, 1.0], (n, 1)), kind=kind)
    gyro, f = spl.imu(np.linspace(spl.t_min_s, spl.t_max_s, 50))
    np.testing.assert_allclose(gyro, 0.0, atol=0)
    np.testing.assert_allclose(f, np.tile([0, 0, 9.81], (50, 1)), atol=1e-15)


# ----------------------------------------------------------------------------- extremes
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("angle", [0.3, 1.0, 2.0, 3.0, np.pi - 1e-3, np.pi - 1e-6])
def test_large_rotation_steps(kind, angle):
    """Relative rotations between control points up to pi - 1e-6 (the shortest path is taken)."""
    spl = random_spline(kind, 4, dt=1.0, step_angle=angle, seed=3)
    np.testing.assert_allclose(np.linalg.norm(spl._D[1:, -3:], axis=1), angle, rtol=1e-9)
    t = interior_times(spl, n=30)
    rtol = 1e-6 if angle > np.pi - 1e-5 else RTOL
    h = 0.01
    check(spl.angular_velocity_body(t), time_derivative(spl.rotation_matrix, t, h, group="so3"),
          f"omega at step {angle}", rtol=rtol, t=t)
    check(spl.angular_acceleration_body(t), time_derivative(spl.angular_velocity_body, t, h),
          f"alpha at step {angle}", rtol=rtol, t=t)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("angle", [1e-12, 1e-9, 1e-6, 1e-4])
def test_tiny_rotation_steps_follow_the_linearized_spline(kind, angle):
    """For tiny steps d_j, omega = sum_j Btilde_j' d_j up to O(|d|^2) (finite differences are
    useless at 1e-12 rad); relative tolerance 1e-9 + |d|."""
    spl = random_spline(kind, 4, dt=0.5, step_angle=angle, seed=4)
    t = interior_times(spl, n=25)
    s = (t - spl.t_min_s) / spl.dt_s
    seg = np.minimum(np.floor(s).astype(int), spl.n_segments - 1)
    u = s - seg
    bd = basis_values(4, u, derivative=1, cumulative=True) / spl.dt_s
    D = spl._D[:, -3:]
    ref = sum(bd[:, j, None] * D[seg + j] for j in range(1, 4))
    w = spl.angular_velocity_body(t)
    scale = np.abs(ref).max()
    assert scale > 0.1 * angle
    assert np.abs(w - ref).max() <= (1e-9 + 10 * angle) * scale


@pytest.mark.parametrize("kind", KINDS)
def test_quaternion_signs_do_not_matter(kind):
    rng = np.random.default_rng(7)
    spl = random_spline(kind, 4)
    q = spl.control_quat_xyzw * rng.choice([-1.0, 1.0], size=(spl.n_control, 1))
    flipped = Spline.from_control_points(spl.t0_s, spl.dt_s, spl.control_positions, q, kind=kind)
    t = np.linspace(spl.t_min_s, spl.t_max_s, 100)
    a, b = spl.kinematics(t), flipped.kinematics(t)
    for name in ("world_R_body", "position_world", "omega_body", "alpha_body", "accel_world"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), atol=1e-12)


def test_epoch_nanosecond_origin():
    origin = 1_403_636_579_758_555_392  # an EuRoC stamp; does not fit a float64 exactly
    a = random_spline("split", 4, origin_ns=origin)
    b = random_spline("split", 4, origin_ns=0)
    t_ns = origin + np.array([300_000_000, 512_345_678, 1_999_999_999], dtype=np.int64)
    t_s = a.t_s_from_ns(t_ns)
    np.testing.assert_array_equal(t_s, [0.3, 0.512345678, 1.999999999])
    np.testing.assert_array_equal(a.imu(t_s)[1], b.imu(t_s)[1])


def test_unsorted_times_and_valid_range():
    spl = random_spline("split", 4)
    t = np.linspace(spl.t_min_s, spl.t_max_s, 50)
    perm = np.random.default_rng(0).permutation(50)
    np.testing.assert_array_equal(spl.imu(t[perm])[0], spl.imu(t)[0][perm])
    spl.imu([spl.t_min_s, spl.t_max_s])  # both ends are valid
    with pytest.raises(RangeError, match="outside the valid range"):
        spl.imu([spl.t_max_s + 1e-3])
    with pytest.raises(RangeError):
        spl.pose([spl.t_min_s - 1e-3])
    with pytest.raises(RangeError, match="NaN"):
        spl.pose([np.nan])


def test_bad_construction_is_a_clear_error():
    q = np.tile([0, 0, 0, 1.0], (5, 1))
    p = np.zeros((5, 3))
    with pytest.raises(SplineImuError, match="at least 6 control points"):
        Spline.from_control_points(0, 0.1, p, q, order=6)
    with pytest.raises(SplineImuError, match="kind"):
        Spline.from_control_points(0, 0.1, p, q, kind="bezier")
    with pytest.raises(SplineImuError, match="not a valid quaternion"):
        Spline.from_control_points(0, 0.1, p, np.zeros((5, 4)))
    with pytest.raises(SplineImuError, match="positive"):
        Spline.from_control_points(0, 0.0, p, q)
