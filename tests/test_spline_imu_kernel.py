"""The ``imu()`` kernels: the vectorized ones of split splines (``_kernels/spline_imu.py``) and
of se3 splines (``_kernels/se3_imu.py``) against the general kernels ``eval_split`` and
``eval_se3`` (gyro and specific force of ``angular_velocity_body`` and
``specific_force_body``), against closed forms and differenced poses; the one-sample path
(a float time) and the few-sample one (short float64 arrays) against the vectorized one, bit
for bit."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu import RangeError, Spline, lie
from splineimu._kernels import se3_imu as _ks
from splineimu._kernels import spline as _k
from splineimu._kernels.spline_imu import BLOCK, KNOT_ANGLE, KNOT_COLS, KNOT_D, split_imu_knots
from splineimu.spline.core import FEW_SAMPLES

# Both kernels share the rounding of the basis and of the acceleration (the same power sums in
# the same order); they differ in how they rotate (Taylor polynomials and Rodrigues on the
# vectors vs libm sin/cos and a rotation matrix), a few ulps per rotation: measured <= 3e-15
# relative over these tests. 1e-14 relative to each vector's norm, plus 1e-15 absolute for
# vectors near zero.
RTOL = 1e-14
ATOL = 1e-15
ORDERS = [2, 3, 4, 5, 6, 7, 8]


def general_kernel(spl, t, g):
    o = spl._evaluate(t, _k.WANT_OMEGA | _k.WANT_FORCE, g)
    return o["w"], o["f"]


def random_split_spline(order, seed, n=None, angles=None):
    """Split spline with random positions and rotation steps of the given (or random) angles.

    Random angles are log-uniform in [1e-12, pi - 1e-6], with some steps of exactly 0 and of
    pi - 1e-6 (the largest the shortest-path increments allow with margin).
    """
    rng = np.random.default_rng(seed)
    n = order + 5 if n is None else n
    if angles is None:
        angles = np.exp(rng.uniform(np.log(1e-12), np.log(np.pi - 1e-6), n))
        angles[rng.random(n) < 0.15] = np.pi - 1e-6
        angles[rng.random(n) < 0.1] = 0.0
    steps = rng.normal(size=(n, 3))
    steps *= (np.broadcast_to(angles, (n,)) / np.linalg.norm(steps, axis=1))[:, None]
    R = [lie.so3_exp(rng.normal(size=3))]
    for s in steps[1:]:
        R.append(R[-1] @ lie.so3_exp(s))
    pos = np.cumsum(rng.normal(size=(n, 3)), axis=0)
    dt = float(np.exp(rng.uniform(np.log(0.01), np.log(2.0))))
    return Spline(rng.normal(), dt, pos, np.array(R), kind="split", order=order)


def sample_times(spl, rng, n_random=100):
    """Random times, every knot, the float just below every knot, and both range ends with
    the excess that the range check tolerates (there u leaves [0, 1] slightly)."""
    knots = spl.t_min_s + spl.dt_s * np.arange(spl.n_segments + 1)
    tol = 1e-9 * max(1.0, spl.t_max_s - spl.t_min_s)
    ends = [spl.t_min_s, spl.t_max_s, spl.t_min_s - 0.5 * tol, spl.t_max_s + 0.5 * tol]
    return np.concatenate([rng.uniform(spl.t_min_s, spl.t_max_s, n_random), knots,
                           np.nextafter(knots, -np.inf)[1:], ends])


def assert_vectors_close(actual, desired, label, rtol=RTOL, atol=ATOL):
    err = np.linalg.norm(actual - desired, axis=1)
    tol = rtol * np.linalg.norm(desired, axis=1) + atol
    i = int(np.argmax(err / tol))
    assert err[i] <= tol[i], (f"{label}: sample {i}: |error| {err[i]:.3g} > {tol[i]:.3g} "
                              f"(|v| = {np.linalg.norm(desired[i]):.3g})")


@pytest.mark.parametrize("order", ORDERS)
def test_agrees_with_general_kernel(order):
    for seed in range(6):
        spl = random_split_spline(order, seed)
        rng = np.random.default_rng(100 + seed)
        t = sample_times(spl, rng)
        g = rng.normal(size=3) * 10.0
        gyro, f = spl.imu(t, gravity=g)
        w_ref, f_ref = general_kernel(spl, t, g)
        assert_vectors_close(gyro, w_ref, f"order {order} seed {seed} gyro")
        assert_vectors_close(f, f_ref, f"order {order} seed {seed} specific force")


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-8, 1e-4, 0.3, 2.0, 3.0, np.pi - 1e-6])
def test_agrees_with_general_kernel_at_fixed_step_angles(angle):
    for order in (4, 7):
        spl = random_split_spline(order, 7, n=order + 8, angles=angle)
        np.testing.assert_allclose(np.linalg.norm(spl._D[1:], axis=1), angle, rtol=1e-9, atol=1e-15)
        t = sample_times(spl, np.random.default_rng(8))
        g = np.array([0.3, -0.2, -9.81])
        gyro, f = spl.imu(t, gravity=g)
        w_ref, f_ref = general_kernel(spl, t, g)
        assert_vectors_close(gyro, w_ref, f"step {angle} order {order} gyro")
        assert_vectors_close(f, f_ref, f"step {angle} order {order} specific force")


@pytest.mark.parametrize("angle", [1e-9, 0.5, 3.0, np.pi - 1e-6])
def test_constant_rate_rotation_has_constant_gyro(angle):
    """Equal increments D about one axis: R(t) = R_0 Exp(s(t) D) with s' = 1/dt (the basis
    reproduces lines), so the gyro is D/dt exactly; an independent check of the kernel."""
    order, n, dt = 5, 12, 0.05
    axis = np.array([2.0, -1.0, 0.5]) / np.linalg.norm([2.0, -1.0, 0.5])
    D = angle * axis
    R = lie.so3_exp([0.3, 0.2, -0.1]) @ lie.so3_exp(np.outer(np.arange(n), D))
    spl = Spline(0.0, dt, np.zeros((n, 3)), R, kind="split", order=order)
    t = sample_times(spl, np.random.default_rng(1))
    gyro, f = spl.imu(t, gravity=[0.0, 0.0, -9.81])
    assert_vectors_close(gyro, np.tile(D / dt, (t.size, 1)), f"gyro at step {angle}", rtol=2e-14)
    # at rest in position: f = R(t)^T (0, 0, 9.81), |f| = 9.81
    np.testing.assert_allclose(np.linalg.norm(f, axis=1), 9.81, rtol=1e-14)
    f_ref = np.einsum("nji,j->ni", spl.rotation_matrix(t), [0.0, 0.0, 9.81])
    assert_vectors_close(f, f_ref, f"specific force at step {angle}")


def test_result_does_not_depend_on_position_or_batch():
    """Blocks, vector bodies and scalar remainder loops all round alike: a sample's result
    is bit-identical wherever it sits in the input."""
    spl = random_split_spline(6, 3, n=40)
    rng = np.random.default_rng(4)
    t = rng.uniform(spl.t_min_s, spl.t_max_s, 3 * BLOCK + 5)
    gyro, f = spl.imu(t)
    perm = rng.permutation(t.size)
    g2, f2 = spl.imu(t[perm])
    np.testing.assert_array_equal(g2, gyro[perm])
    np.testing.assert_array_equal(f2, f[perm])
    for i in (0, 1, 7, 8, BLOCK - 1, BLOCK, 2 * BLOCK + 3, t.size - 1):
        g1, f1 = spl.imu(t[i])
        np.testing.assert_array_equal(g1[0], gyro[i])
        np.testing.assert_array_equal(f1[0], f[i])


def test_output_arrays():
    spl = random_split_spline(4, 0)
    gyro, f = spl.imu(np.linspace(spl.t_min_s, spl.t_max_s, 11))
    for a in (gyro, f):
        assert a.shape == (11, 3) and a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable
    assert not np.shares_memory(gyro, f)
    f_before = f.copy()
    gyro[:] = np.nan  # writing one leaves the other alone
    np.testing.assert_array_equal(f, f_before)
    g0, f0 = spl.imu(np.array([]))
    assert g0.shape == (0, 3) and f0.shape == (0, 3)


def test_se3_imu_matches_differenced_poses():
    """se3 splines: gyro and specific force against central differences of the spline's own
    poses (an independent path: rotations and positions only, no derivative recursion)."""
    rng = np.random.default_rng(2)
    n = 10
    pos = np.cumsum(rng.normal(size=(n, 3)), axis=0)
    spl = Spline(0.0, 0.1, pos, lie.so3_exp(rng.normal(size=(n, 3))), kind="se3", order=5)
    t = np.linspace(spl.t_min_s + 0.01, spl.t_max_s - 0.01, 50)
    gravity = np.array([0.0, 0.0, -9.81])
    gyro, f = spl.imu(t, gravity=gravity)
    h = 1e-5
    R_m, R_p = spl.rotation_matrix(t - h), spl.rotation_matrix(t + h)
    w_num = lie.so3_log(np.matmul(np.swapaxes(R_m, 1, 2), R_p)) / (2 * h)
    # the body rate at t is the rate of R(t-h)^T R(t+h) up to O(h^2)
    h = 2e-4
    p_m, p_0, p_p = (spl.pose(t + d)[0] for d in (-h, 0.0, h))
    a_num = (p_p - 2 * p_0 + p_m) / h**2
    f_num = np.einsum("nji,nj->ni", spl.rotation_matrix(t), a_num - gravity)
    scale_w = np.abs(gyro).max()
    scale_f = np.abs(f).max()
    # measured 1.0e-8 and 4.3e-6 relative (O(h^2) truncation of the differences)
    assert np.abs(gyro - w_num).max() <= 1e-7 * scale_w, np.abs(gyro - w_num).max() / scale_w
    assert np.abs(f - f_num).max() <= 4e-5 * scale_f, np.abs(f - f_num).max() / scale_f


def test_knot_table():
    spl = random_split_spline(4, 5)
    K = split_imu_knots(spl._D)
    assert K.shape == (spl.n_control, KNOT_COLS) and K.flags.c_contiguous
    np.testing.assert_array_equal(K[:, KNOT_D:KNOT_D + 3], spl._D)
    np.testing.assert_allclose(K[:, KNOT_ANGLE], np.linalg.norm(spl._D, axis=1), rtol=1e-15)
    assert K[0, KNOT_ANGLE] == 0.0


@pytest.mark.parametrize("orders", [(4, 6), (6, 4), (5, 5)])
def test_separate_position_grid(orders):
    """Rotation and position on their own grids: the vectorized kernel agrees with the general
    one, and the position part is the ordinary B-spline of its own control points (scipy)."""
    from scipy.interpolate import BSpline

    k_rot, k_pos = orders
    rng = np.random.default_rng(11)
    n_rot, dt_rot = 12, 0.3
    rot = random_split_spline(k_rot, 3, n=n_rot)
    t0 = 0.1
    span = (n_rot - k_rot + 1) * dt_rot
    dt_pos = span / 23
    n_pos = 23 + k_pos - 1
    pos = np.cumsum(rng.normal(size=(n_pos, 3)), axis=0)
    spl = Spline(t0, dt_rot, pos, rot.control_rotations, kind="split", order=k_rot, position_t0_s=t0,
                 position_dt_s=dt_pos, position_order=k_pos)
    assert abs(spl.t_max_s - (t0 + span)) < 1e-12
    t = np.r_[rng.uniform(spl.t_min_s, spl.t_max_s, 300), spl.t_min_s, spl.t_max_s]
    g = np.array([0.2, -0.1, -9.81])
    gyro, f = spl.imu(t, gravity=g)
    w_ref, f_ref = general_kernel(spl, t, g)
    assert_vectors_close(gyro, w_ref, "gyro")
    assert_vectors_close(f, f_ref, "specific force")
    # position: scipy's B-spline on the uniform knot vector of the position grid
    knots = t0 + dt_pos * (np.arange(n_pos + k_pos) - (k_pos - 1))
    ref = BSpline(knots, pos, k_pos - 1)
    np.testing.assert_allclose(spl.pose(t)[0], ref(t), rtol=0, atol=1e-11 * np.abs(pos).max())
    np.testing.assert_allclose(spl.acceleration_world(t), ref.derivative(2)(t), rtol=0,
                               atol=1e-9 * np.abs(pos).max() / dt_pos**2)
    # the rotation is that of the rotation grid alone
    alone = Spline(t0, dt_rot, np.zeros((n_rot, 3)), rot.control_rotations, kind="split", order=k_rot)
    np.testing.assert_array_equal(spl.rotation_matrix(t), alone.rotation_matrix(t))


# ------------------------------------------------------------------------------ se3 kernel
def random_se3_spline(order, seed, n=None, angles=None):
    """An se3 spline on the control poses of :func:`random_split_spline`."""
    spl = random_split_spline(order, seed, n, angles)
    return Spline(spl.t0_s, spl.dt_s, spl.control_positions, spl.control_rotations, kind="se3", order=order)


@pytest.mark.parametrize("order", ORDERS)
def test_se3_agrees_with_general_kernel(order):
    """Same recursion as eval_se3, different rounding (half-angle polynomials and Rodrigues'
    matrix vs libm and Jacobian matrices, R^T g carried through): measured <= 2.4e-15 relative."""
    for seed in range(6):
        spl = random_se3_spline(order, seed)
        rng = np.random.default_rng(200 + seed)
        t = sample_times(spl, rng)
        g = rng.normal(size=3) * 10.0
        gyro, f = spl.imu(t, gravity=g)
        w_ref, f_ref = general_kernel(spl, t, g)
        assert_vectors_close(gyro, w_ref, f"se3 order {order} seed {seed} gyro")
        assert_vectors_close(f, f_ref, f"se3 order {order} seed {seed} specific force")


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-8, 1e-4, 0.3, 2.0, 3.0, np.pi - 1e-6])
def test_se3_agrees_with_general_kernel_at_fixed_step_angles(angle):
    for order in (4, 7):
        spl = random_se3_spline(order, 7, n=order + 8, angles=angle)
        np.testing.assert_allclose(np.linalg.norm(spl._D[1:, 3:], axis=1), angle, rtol=1e-9, atol=1e-15)
        t = sample_times(spl, np.random.default_rng(8))
        g = np.array([0.3, -0.2, -9.81])
        gyro, f = spl.imu(t, gravity=g)
        w_ref, f_ref = general_kernel(spl, t, g)
        assert_vectors_close(gyro, w_ref, f"se3 step {angle} order {order} gyro")
        assert_vectors_close(f, f_ref, f"se3 step {angle} order {order} specific force")


@pytest.mark.parametrize("order", [4, 6])
def test_se3_screw_reads_constant_twist(order):
    """Control poses T0 Exp(i dt xi): the body twist is xi at all times, so the gyro reads
    w = xi[3:] and the specific force w x v - R^T g (closed form, independent of the kernel)."""
    xi = np.array([1.0, -0.5, 0.3, 0.4, -0.7, 1.1])  # [v_b, w_b]
    T0 = lie.se3_exp([2.0, -1.0, 3.0, 0.2, 0.3, -0.1])
    dt, n = 0.1, 14
    T = T0 @ lie.se3_exp(np.outer(np.arange(n) * dt, xi))
    spl = Spline(0.0, dt, T[:, :3, 3], T[:, :3, :3], kind="se3", order=order)
    t = sample_times(spl, np.random.default_rng(3))
    g = np.array([0.0, 0.0, -9.81])
    gyro, f = spl.imu(t, gravity=g)
    assert_vectors_close(gyro, np.tile(xi[3:], (t.size, 1)), "screw gyro", rtol=1e-13)
    f_ref = np.cross(xi[3:], xi[:3]) - np.einsum("nji,j->ni", spl.rotation_matrix(t), g)
    assert_vectors_close(f, f_ref, "screw specific force", rtol=1e-13)


@pytest.mark.parametrize("order", [4, 6])
def test_se3_matches_richardson_differences_of_poses(order):
    """Gyro: the body rate of the spline's rotations; specific force: R^T (p'' - g) with p''
    from nested central differences of its positions (Richardson; numdiff.time_derivative).
    An independent path: poses only, no derivative recursion."""
    from numdiff import assert_derivative_close, time_derivative

    spl = random_se3_spline(order, 4, n=order + 6, angles=0.5)
    rng = np.random.default_rng(5)
    seg = rng.integers(0, spl.n_segments, 30)
    t = spl.t_min_s + (seg + rng.uniform(0.1, 0.9, seg.size)) * spl.dt_s  # clear of knots
    h = 0.02 * spl.dt_s
    g = np.array([0.1, 0.2, -9.81])
    gyro, f = spl._imu_vectorized(t, gravity=g)
    w_num = time_derivative(spl.rotation_matrix, t, h, group="so3")
    a_num = time_derivative(lambda s: time_derivative(lambda q: spl.pose(q)[0], s, h), t, h)
    f_num = np.einsum("nji,nj->ni", spl.rotation_matrix(t), a_num - g)
    # measured 1.4e-13 and 1.5e-11 relative to the largest value (truncation and rounding of
    # the differences)
    assert_derivative_close(gyro, w_num, rtol=1e-11, atol=1e-11 * np.abs(gyro).max(), label="gyro", t=t)
    assert_derivative_close(f, f_num, rtol=2e-10, atol=2e-10 * np.abs(f).max(), label="specific force", t=t)


def test_se3_result_does_not_depend_on_position_or_batch():
    spl = random_se3_spline(5, 3, n=40)
    rng = np.random.default_rng(4)
    t = rng.uniform(spl.t_min_s, spl.t_max_s, 2 * BLOCK + 7)
    gyro, f = spl.imu(t)
    perm = rng.permutation(t.size)
    g2, f2 = spl.imu(t[perm])
    np.testing.assert_array_equal(g2, gyro[perm])
    np.testing.assert_array_equal(f2, f[perm])


def test_se3_knot_table():
    spl = random_se3_spline(4, 5)
    K = _ks.se3_imu_knots(spl._D)
    assert K.shape == (spl.n_control, _ks.KNOT_COLS) and K.flags.c_contiguous
    np.testing.assert_array_equal(K[:, _ks.KNOT_R:_ks.KNOT_R + 3], spl._D[:, :3])
    np.testing.assert_array_equal(K[:, _ks.KNOT_D:_ks.KNOT_D + 3], spl._D[:, 3:])
    np.testing.assert_allclose(K[:, _ks.KNOT_ANGLE], np.linalg.norm(spl._D[:, 3:], axis=1), rtol=1e-15)


# ------------------------------------------------------------------------ one sample
def assert_one_sample_path_equal(spl, t, g=None):
    """``imu(float)`` for every time, and ``imu(array)`` of a few of them, equal the vectorized
    kernel bit for bit."""
    kw = {} if g is None else {"gravity": g}
    gyro, f = spl._imu_vectorized(t, **kw)
    for n in (0, 1, 2, FEW_SAMPLES):  # few-sample path: up to FEW_SAMPLES times in one array
        g_few, f_few = spl.imu(t[:n], **kw)
        np.testing.assert_array_equal(g_few, gyro[:n])
        np.testing.assert_array_equal(f_few, f[:n])
    g_few, f_few = spl.imu(t[:2 * FEW_SAMPLES:2], **kw)  # a strided array
    np.testing.assert_array_equal(g_few, gyro[:2 * FEW_SAMPLES:2])
    np.testing.assert_array_equal(f_few, f[:2 * FEW_SAMPLES:2])
    for i, ti in enumerate(t):
        for scalar in (float(ti), np.float64(ti)):
            g1, f1 = spl.imu(scalar, **kw)
            assert g1.shape == (1, 3) and f1.shape == (1, 3)
            np.testing.assert_array_equal(g1[0], gyro[i], err_msg=f"gyro at t = {ti!r}")
            np.testing.assert_array_equal(f1[0], f[i], err_msg=f"specific force at t = {ti!r}")


@pytest.mark.parametrize("kind", ["split", "se3"])
@pytest.mark.parametrize("order", ORDERS)
def test_one_sample_equals_vectorized(kind, order):
    make = random_split_spline if kind == "split" else random_se3_spline
    for seed in range(3):
        spl = make(order, seed)
        rng = np.random.default_rng(300 + seed)
        t = sample_times(spl, rng, n_random=30)
        assert_one_sample_path_equal(spl, t)
        assert_one_sample_path_equal(spl, t[:20], g=rng.normal(size=3) * 10.0)
        assert_one_sample_path_equal(spl, t[:5], g=(0.0, 0.0, -9.81))


def test_one_sample_equals_vectorized_on_separate_position_grid():
    rot = random_split_spline(5, 3, n=12)
    rng = np.random.default_rng(12)
    pos = np.cumsum(rng.normal(size=(30, 3)), axis=0)
    spl = Spline(rot.t0_s, rot.dt_s, pos, rot.control_rotations, kind="split", order=5,
                 position_t0_s=rot.t0_s, position_dt_s=rot.dt_s * 8 / 27, position_order=4)
    assert_one_sample_path_equal(spl, sample_times(spl, rng, n_random=50))


@pytest.mark.parametrize("kind", ["split", "se3"])
def test_one_sample_range_and_other_scalars(kind):
    spl = (random_split_spline if kind == "split" else random_se3_spline)(4, 1)
    tol = 1e-9 * max(1.0, spl.t_max_s - spl.t_min_s)
    t = 0.5 * (spl.t_min_s + spl.t_max_s)
    for bad in (spl.t_min_s - 2 * tol, spl.t_max_s + 2 * tol, np.nan, np.inf, -np.inf):
        with pytest.raises(RangeError):
            spl.imu(float(bad))
        with pytest.raises(RangeError):
            spl.imu(np.array([t, bad, t]))  # the few-sample path
    gyro, f = spl._imu_vectorized(np.array([t]))
    for scalar in (t, np.array(t), [t], np.array([t])):  # float, 0-d array, list, array: the same numbers
        g1, f1 = spl.imu(scalar)
        np.testing.assert_array_equal(g1, gyro)
        np.testing.assert_array_equal(f1, f)
    t32 = np.array([t, t], dtype=np.float32)  # not float64: the vectorized path
    for a, b in zip(spl.imu(t32), spl._imu_vectorized(t32)):
        np.testing.assert_array_equal(a, b)
    a, b = spl.imu(t)
    c, d = spl.imu(t)
    for x in (a, b):
        assert x.dtype == np.float64 and x.flags.c_contiguous and x.flags.writeable
    assert not (np.shares_memory(a, b) or np.shares_memory(a, c) or np.shares_memory(b, d))
    with pytest.raises(ValueError):
        spl.imu(t, gravity=[1.0, 2.0])


def test_one_sample_spline_pickles():
    import copy
    import pickle

    spl = random_split_spline(4, 2)
    t = 0.5 * (spl.t_min_s + spl.t_max_s)
    gyro, f = spl.imu(t)  # builds the one-sample path
    for other in (pickle.loads(pickle.dumps(spl)), copy.deepcopy(spl)):
        g1, f1 = other.imu(t)
        np.testing.assert_array_equal(g1, gyro)
        np.testing.assert_array_equal(f1, f)
