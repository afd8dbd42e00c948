"""The Lie kernels as building blocks (:mod:`splineimu._kernels.lie`).

- Every ``*_batch`` kernel is its element function in a loop: equal bit for bit (signed zeros
  included) on random rows, exactly 0, tiny angles, both sides of every small-angle threshold,
  near and at pi and beyond pi. A new batch kernel without an entry here fails the test.
- The element functions that other kernels compose (quaternion Exp and product, SE3 Exp / Log /
  Jacobians / adjoint on (R, t) parts) agree with the matrix forms the group-axiom suite checks.

Tolerances (measured in brackets over 20000 random cases): Exp coefficients against 60 digits
4 eps [<= 1.5 eps]; quaternion Exp against the matrix Exp, and the quaternion product against
the matrix product, 1e-14 absolute [<= 1.3e-15 and 1.7e-15].
"""

from __future__ import annotations

import math
import zlib
from decimal import Decimal, localcontext

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numdiff import decimal_sin_cos

from splineimu import lie
from splineimu._kernels import lie as K

PI = math.pi
EPS = np.finfo(float).eps
QUAT_ATOL = 1e-14
THRESHOLDS = [K.EXP_SMALL_ANGLE, K.JAC_SMALL_ANGLE, K.SE3_Q_SMALL_ANGLE, 2.0 * math.atan(K.LOG_SMALL_ANGLE)]


def _rng(key):
    return np.random.default_rng(zlib.crc32(key.encode()))


def _angles(rng):
    """Exactly 0, tiny, 1e-15 relative either side of each threshold, random, near pi, pi, beyond."""
    sides = [th * f for th in THRESHOLDS for f in (1.0 - 1e-15, 1.0 + 1e-15)]
    near_pi = [PI - d for d in (1e-3, 1e-6, 1e-9, 1e-12, 1e-15)] + [PI, PI + 1e-9]
    return np.concatenate([[0.0, 1e-300, 1e-12, 1e-8], sides, rng.uniform(0.0, PI, 24), near_pi, [4.0, 6.0]])


def _rotvecs(key):
    rng = _rng(key)
    a = _angles(rng)
    d = rng.normal(size=(a.size, 3))
    phi = d / np.linalg.norm(d, axis=1, keepdims=True) * a[:, None]
    phi[-6:-3] = np.eye(3) * (PI - 1e-9)  # coordinate axes: each of Shepperd's diagonal branches
    return np.ascontiguousarray(phi)


def _twists(key):
    phi = _rotvecs(key)
    rho = _rng(key + "/rho").normal(size=phi.shape) * 3.0
    rho[:2] = 0.0
    return np.ascontiguousarray(np.concatenate([rho, phi], axis=1))


def _rotations(key):
    R = lie.so3_exp(_rotvecs(key))
    axis = np.array([1.0, -2.0, 0.5]) / math.sqrt(5.25)
    exact_pi = [2.0 * np.outer(a, a) - np.eye(3) for a in (np.eye(3)[0], np.eye(3)[2], axis)]
    return np.ascontiguousarray(np.concatenate([R, exact_pi]))


def _poses(key):
    return np.ascontiguousarray(lie.se3_exp(_twists(key)))


def _quats_wxyz(key):
    rng = _rng(key)
    q = rng.normal(size=(30, 4)) * rng.uniform(0.1, 10.0, size=(30, 1))
    q[:3, 0] = 0.0  # w = 0: exactly pi
    q[3:6, 0] = [1e-300, -1e-12, 1e-8]
    q[6:9, 1:] *= 1e-9  # tiny angles, either sign of w
    q[7, 0] = -abs(q[7, 0])
    return np.ascontiguousarray(q)


def _normalized_log(x, o):
    u = np.empty(4)
    K.quat_wxyz_normalize_into(x[0], x[1], x[2], x[3], u)
    K.quat_wxyz_log_into(u[0], u[1], u[2], u[3], o)


#: batch kernel -> (inputs, output tail, element call on one row, takes a sign)
ELEMENTS = {
    "so3_hat_batch": (_rotvecs, (3, 3), lambda x, o: K.so3_hat_into(x[0], x[1], x[2], o), False),
    "so3_exp_batch": (_rotvecs, (3, 3), lambda x, o: K.so3_exp_into(x[0], x[1], x[2], o), False),
    "so3_log_batch": (_rotations, (3,), lambda x, o: K.so3_log_into(x, np.empty(4), o), False),
    "quat_wxyz_log_batch": (_quats_wxyz, (3,), _normalized_log, False),
    "mat_to_quat_wxyz_batch": (_rotations, (4,), lambda x, o: K.mat_to_quat_wxyz_into(x, o), False),
    "quat_wxyz_to_mat_batch": (_quats_wxyz, (3, 3), lambda x, o: K.quat_wxyz_to_mat_into(*x, o), False),
    "so3_jacobian_batch": (_rotvecs, (3, 3), lambda x, s, o: K.so3_jacobian_into(*x, s, o), True),
    "so3_jacobian_inv_batch": (_rotvecs, (3, 3), lambda x, s, o: K.so3_jacobian_inv_into(*x, s, o), True),
    "se3_exp_batch": (_twists, (4, 4), None, False),  # element: se3_exp_into on the (R, t) parts
    "se3_log_batch": (_poses, (6,), lambda x, o: K.se3_log_into(x[:3, :3], x[:3, 3], np.empty(4),
                                                                 np.empty((3, 3)), o), False),
    "se3_jacobian_batch": (_twists, (6, 6), lambda x, s, o: K.se3_jacobian_into(x, s, o, np.empty((4, 3, 3))),
                           True),
    "se3_jacobian_inv_batch": (_twists, (6, 6),
                               lambda x, s, o: K.se3_jacobian_inv_into(x, s, o, np.empty((5, 3, 3))), True),
    "se3_adjoint_batch": (_poses, (6, 6), lambda x, o: K.se3_adjoint_into(x[:3, :3], x[:3, 3], o), False),
}


def _se3_exp_element(x, o):
    K.se3_exp_into(x, o[:3, :3], o[:3, 3], np.empty((3, 3)))
    o[3] = [0.0, 0.0, 0.0, 1.0]


def assert_bitwise_equal(a, b, label):
    """Equal bit patterns (so -0.0 != 0.0); on failure the first differing entry."""
    a = np.ascontiguousarray(a)
    b = np.ascontiguousarray(b)
    assert a.shape == b.shape, f"{label}: shape {a.shape} vs {b.shape}"
    diff = np.flatnonzero(a.view(np.int64) != b.view(np.int64))
    if diff.size:
        i = np.unravel_index(diff[0], a.shape)
        pytest.fail(f"{label}: {diff.size} entries differ, first at {i}: batch {a[i]!r} vs element {b[i]!r}")


def test_every_batch_kernel_is_listed():
    batches = {n for n in dir(K) if n.endswith("_batch") and callable(getattr(K, n))}
    assert batches == set(ELEMENTS)


@pytest.mark.parametrize("name", sorted(ELEMENTS))
def test_batch_kernel_equals_its_element_function(name):
    make, tail, element, signed = ELEMENTS[name]
    if name == "se3_exp_batch":
        element = _se3_exp_element
    x = make(name)
    for sign in ((1.0, -1.0) if signed else (None,)):
        args = () if sign is None else (sign,)
        batch = np.full((x.shape[0],) + tail, np.nan)
        getattr(K, name)(x, *args, batch)
        each = np.full_like(batch, np.nan)
        for i in range(x.shape[0]):
            element(x[i], *args, each[i])
        assert_bitwise_equal(batch, each, f"{name} sign={sign}")


# ------------------------------------------------------------ element functions


def test_exp_coefficients_against_60_digits():
    """sin t/t, (1 - cos t)/t^2, cos(t/2), sin(t/2)/t on both sides of EXP_SMALL_ANGLE: 4 eps."""
    th = K.EXP_SMALL_ANGLE
    ts = np.concatenate([np.geomspace(1e-10, 3.1, 40), [th * (1 - 1e-15), th * (1 + 1e-15), 0.5 * th, 2 * th]])
    worst = 0.0
    with localcontext() as ctx:
        ctx.prec = 60
        for t in ts:
            T = Decimal(float(t))
            st_, ct_ = decimal_sin_cos(T)
            sh, ch = decimal_sin_cos(T / 2)
            ref = [st_ / T, (1 - ct_) / T**2, ch, sh / T]
            for name, g, r in zip("abcs", K.so3_exp_coeffs(t * t), ref):
                rel = abs(g / float(r) - 1.0)
                worst = max(worst, rel)
                assert rel <= 4 * EPS, f"coefficient {name} at t={t!r}: relative error {rel:.2e}"
    assert worst > 0.0  # the reference is finer than float64: some rounding must show


@given(st.tuples(*[st.floats(-1.0, 1.0)] * 3), st.one_of(
    st.just(0.0), st.floats(1e-12, 1e-3), st.sampled_from(THRESHOLDS).flatmap(
        lambda th: st.floats(th * (1 - 1e-9), th * (1 + 1e-9))), st.floats(1e-3, 6.0)))
def test_property_quaternion_exp_is_the_matrix_exp(direction, angle):
    d = np.array(direction)
    n = np.linalg.norm(d)
    phi = (np.array([0.0, 0.0, 1.0]) if n < 1e-3 else d / n) * angle
    q = np.empty(4)
    K.so3_exp_quat_wxyz_into(phi[0], phi[1], phi[2], q)
    assert abs(np.linalg.norm(q) - 1.0) <= 2 * EPS
    R = np.empty((3, 3))
    K.quat_wxyz_to_mat_into(q[0], q[1], q[2], q[3], R)
    assert np.abs(R - lie.so3_exp(phi)).max() <= QUAT_ATOL


@given(st.tuples(*[st.floats(-3.0, 3.0)] * 3), st.tuples(*[st.floats(-3.0, 3.0)] * 3))
def test_property_quaternion_product_is_the_matrix_product(a, b):
    qa, qb, q = np.empty(4), np.empty(4), np.empty(4)
    K.so3_exp_quat_wxyz_into(*a, qa)
    K.so3_exp_quat_wxyz_into(*b, qb)
    K.quat_wxyz_mul_into(qa, qb, q)
    R = np.empty((3, 3))
    K.quat_wxyz_to_mat_into(q[0], q[1], q[2], q[3], R)
    assert np.abs(R - lie.so3_exp(a) @ lie.so3_exp(b)).max() <= QUAT_ATOL


def test_se3_elements_on_parts_match_the_matrix_forms():
    """se3_exp_into / se3_log_into work on (R, t) views, as the fit kernels hold poses."""
    xi = _twists("se3-parts")[:-2]  # |phi| <= pi + 1e-9
    R, t, J = np.empty((3, 3)), np.empty(3), np.empty((3, 3))
    for x in xi:
        K.se3_exp_into(x, R, t, J)
        T = lie.se3_exp(x)
        np.testing.assert_array_equal(R, T[:3, :3])
        np.testing.assert_array_equal(t, T[:3, 3])
        out = np.empty(6)
        K.se3_log_into(R, t, np.empty(4), J, out)
        np.testing.assert_array_equal(out, lie.se3_log(T))
