"""Group-axiom suite for :mod:`splineimu.lie` (STYLE.md 13-18).

One suite runs over {SO3, SE3} x {identity, 1e-8, random, pi - 1e-6, pi - 1e-9, pi}; then
threshold continuity, quaternion helpers, scipy cross-checks and hypothesis properties.

Tolerances (measured values in brackets, jit and NUMBA_DISABLE_JIT=1 alike)
-------------------------------------------------------------------------
- Round trips ``log(exp(x)) = x``, ``exp(log(X)) = X``: 1e-12 relative  [<= 5e-16]
- ``J J^-1 = I``, ``J_l = Ad J_r``, adjoint, associativity, inverse: 1e-12  [<= 1e-15]
- Jacobians against :mod:`numdiff` (Richardson, h = 1e-3, order 6): 1e-9 relative
  [<= 7e-12, near pi and in the hypothesis ranges included]. Near pi, Log is not continuous
  (it wraps at pi), so the Jacobians of Log are differenced through a Log continued past pi
  (the representative nearest the base point); Exp needs no care.
- Continuity across each small-angle threshold (inputs 1e-15 relative below / above, the branch
  checked by recomputing the kernel's own comparison): 1e-14 relative, normwise and on the
  off-diagonal entries / coupling block alone, which carry the small-angle terms [<= 2.3e-15,
  of which 2e-15 is the true change of the input].
- Scalar Jacobian coefficients and the SE3 Q block against 60-digit references: 4 eps on the
  Taylor side; closed forms above JAC_SMALL_ANGLE within 4 eps + 16 eps / t^2; Q block 2e-15.
- scipy ``Rotation``: 1e-14 absolute on matrices, rotation vectors and quaternions [<= 9e-16].
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from decimal import Decimal, localcontext

import numpy as np
import pytest
import scipy.linalg
from hypothesis import given
from hypothesis import strategies as st
from numdiff import (
    assert_derivative_close,
    assert_jacobian_close,
    decimal_sin_cos,
    numeric_jacobian,
    time_derivative,
)
from scipy.spatial.transform import Rotation

from splineimu import lie
from splineimu._kernels import lie as K
from splineimu.errors import SplineImuError

PI = math.pi
ROUND_TRIP_RTOL = 1e-12
IDENTITY_TOL = 1e-12
NUMDIFF_RTOL = 1e-9
THRESHOLD_RTOL = 4e-14  # a few ulp: compiled callers may order the arithmetic differently
SCIPY_ATOL = 1e-14


# --------------------------------------------------------------------------- helpers


def _unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def _maxabs(a):
    return float(np.max(np.abs(a))) if np.size(a) else 0.0


def assert_close_rel(actual, expected, rtol, label="", scale=None):
    """max|actual - expected| <= rtol * scale (default: max|expected|, at least tiny)."""
    actual = np.asarray(actual, dtype=np.float64)
    expected = np.asarray(expected, dtype=np.float64)
    assert actual.shape == expected.shape, f"{label}: shape {actual.shape} vs {expected.shape}"
    s = _maxabs(expected) if scale is None else scale
    err = _maxabs(actual - expected)
    assert err <= rtol * s, (
        f"{label}: max error {err:.3e} > {rtol:g} * {s:.3e}\nactual:\n{actual!r}\nexpected:\n{expected!r}"
    )


def so3_log_near(R, ref):
    """Log continued past pi: of ``phi`` and ``phi (1 - 2 pi / |phi|)`` (same rotation, angle
    ``2 pi - |phi|`` the other way round), the one nearest ``ref``. Smooth around ``ref`` for
    ``|ref| < 2 pi``, including rotations near pi."""
    phi = lie.so3_log(R)
    n = np.linalg.norm(phi)
    if n > 0.0:
        alt = phi * (1.0 - 2.0 * PI / n)
        if np.linalg.norm(alt - ref) < np.linalg.norm(phi - ref):
            return alt
    return phi


def se3_log_near(T, ref):
    """SE3 Log with the rotation part continued past pi (``rho = J_l(phi)^-1 t``)."""
    phi = so3_log_near(T[:3, :3], ref[3:])
    rho = np.linalg.solve(lie.so3_left_jacobian(phi), T[:3, 3])
    return np.concatenate([rho, phi])


@dataclass(frozen=True)
class Group:
    name: str  # numdiff group name
    dim: int
    n: int  # matrix size
    exp: Callable
    log: Callable
    hat: Callable
    vee: Callable
    inverse: Callable
    compose: Callable
    adjoint: Callable
    jr: Callable
    jl: Callable
    jr_inv: Callable
    jl_inv: Callable
    log_near: Callable

    def phi(self, x):
        return x[..., -3:]


SO3 = Group("so3", 3, 3, lie.so3_exp, lie.so3_log, lie.so3_hat, lie.so3_vee, lie.so3_inverse,
            lie.so3_compose, lie.so3_adjoint, lie.so3_right_jacobian, lie.so3_left_jacobian,
            lie.so3_right_jacobian_inv, lie.so3_left_jacobian_inv, so3_log_near)
SE3 = Group("se3", 6, 4, lie.se3_exp, lie.se3_log, lie.se3_hat, lie.se3_vee, lie.se3_inverse,
            lie.se3_compose, lie.se3_adjoint, lie.se3_right_jacobian, lie.se3_left_jacobian,
            lie.se3_right_jacobian_inv, lie.se3_left_jacobian_inv, se3_log_near)
GROUPS = {"SO3": SO3, "SE3": SE3}

#: rotation angle of each case (None: random in [0.5, 2.5])
CASES = {
    "identity": 0.0,
    "1e-8": 1e-8,
    "random": None,
    "pi-1e-6": PI - 1e-6,
    "pi-1e-9": PI - 1e-9,
    "pi": PI,
}


def _rng(*key):
    return np.random.default_rng(zlib.crc32("/".join(map(str, key)).encode()))


def tangent(gname, case):
    """Deterministic tangent vector of group ``gname`` for ``case`` (SE3: ``[rho, phi]``)."""
    rng = _rng(gname, case)
    angle = rng.uniform(0.5, 2.5) if CASES[case] is None else CASES[case]
    phi = _unit(rng) * angle
    if gname == "SO3":
        return phi
    if case == "identity":
        rho = np.zeros(3)
    elif case == "1e-8":
        rho = 1e-8 * _unit(rng)
    else:
        rho = 2.0 * rng.normal(size=3)
    return np.concatenate([rho, phi])


def random_tangent(gname, rng, angle=None):
    phi = _unit(rng) * (rng.uniform(0.2, 2.8) if angle is None else angle)
    return phi if gname == "SO3" else np.concatenate([rng.normal(size=3), phi])


@pytest.fixture(params=list(GROUPS), ids=list(GROUPS))
def gname(request):
    return request.param


@pytest.fixture(params=list(CASES), ids=list(CASES))
def case(request):
    return request.param


# ---------------------------------------------------------------- group-axiom suite


def test_log_of_exp(gname, case):
    G = GROUPS[gname]
    x = tangent(gname, case)
    X = G.exp(x)
    y = G.log(X)
    if case != "pi":
        assert_close_rel(y, x, ROUND_TRIP_RTOL, f"{gname} log(exp(x)), {case}")
        return
    # exactly pi: Log may return phi or -phi (same rotation); its angle is pi either way
    assert abs(np.linalg.norm(G.phi(y)) - PI) <= 4e-16 * PI
    s = 1.0 if np.dot(G.phi(y), G.phi(x)) > 0 else -1.0
    assert_close_rel(G.phi(y), s * G.phi(x), ROUND_TRIP_RTOL, "pi: phi = +-x")
    assert_close_rel(G.exp(y), X, ROUND_TRIP_RTOL, "pi: exp(log(X))", scale=max(1.0, _maxabs(X)))


def test_exp_of_log(gname, case):
    G = GROUPS[gname]
    X = G.exp(tangent(gname, case))
    assert_close_rel(G.exp(G.log(X)), X, ROUND_TRIP_RTOL, f"{gname} exp(log(X)), {case}",
                     scale=max(1.0, _maxabs(X)))


def test_exp_is_a_group_element_and_matrix_exponential(gname, case):
    G = GROUPS[gname]
    x = tangent(gname, case)
    X = G.exp(x)
    R = X[:3, :3]
    assert_close_rel(R.T @ R, np.eye(3), 4e-15, "R^T R = I", scale=1.0)
    assert abs(np.linalg.det(R) - 1.0) <= 4e-15  # a few eps (det has its own rounding)
    if gname == "SE3":
        np.testing.assert_array_equal(X[3], [0.0, 0.0, 0.0, 1.0])
    # independent reference: the matrix exponential of the hat matrix
    assert_close_rel(X, scipy.linalg.expm(G.hat(x)), 1e-14, "Exp = expm(hat)",
                     scale=max(1.0, _maxabs(X)))


def test_inverse(gname, case):
    G = GROUPS[gname]
    x = tangent(gname, case)
    X = G.exp(x)
    Xi = G.inverse(X)
    scale = max(1.0, _maxabs(X))
    eye = np.eye(G.n)
    assert_close_rel(G.compose(X, Xi), eye, IDENTITY_TOL, "X X^-1", scale=scale)
    assert_close_rel(G.compose(Xi, X), eye, IDENTITY_TOL, "X^-1 X", scale=scale)
    assert_close_rel(G.exp(-x), Xi, IDENTITY_TOL, "Exp(-x) = Exp(x)^-1", scale=scale)
    assert_close_rel(np.linalg.inv(X), Xi, IDENTITY_TOL, "inverse vs np.linalg.inv", scale=scale)


def test_compose_associative_and_closed(gname, case):
    G = GROUPS[gname]
    rng = _rng("compose", gname, case)
    A = G.exp(tangent(gname, case))
    B = G.exp(random_tangent(gname, rng))
    C = G.exp(random_tangent(gname, rng))
    left = G.compose(G.compose(A, B), C)
    right = G.compose(A, G.compose(B, C))
    assert_close_rel(left, right, IDENTITY_TOL, "(AB)C = A(BC)", scale=max(1.0, _maxabs(left)))
    # closure: the product is again an element (its Log round-trips)
    assert_close_rel(G.exp(G.log(left)), left, ROUND_TRIP_RTOL, "AB in G", scale=max(1.0, _maxabs(left)))
    # the action composes like the matrices
    if gname == "SO3":
        v = rng.normal(size=3)
        assert_close_rel(lie.so3_act(left, v), A @ (B @ (C @ v)), IDENTITY_TOL, "act")
    else:
        p = rng.normal(size=3)
        ph = np.append(p, 1.0)
        assert_close_rel(lie.se3_act(left, p), (A @ (B @ (C @ ph)))[:3], IDENTITY_TOL, "act")


def test_hat_vee(gname, case):
    G = GROUPS[gname]
    x = tangent(gname, case)
    H = G.hat(x)
    np.testing.assert_array_equal(G.vee(H), x)
    W = H[:3, :3]
    np.testing.assert_array_equal(W, -W.T)
    v = _rng("hat", gname, case).normal(size=3)
    phi = G.phi(x)
    assert_close_rel(W @ v, np.cross(phi, v), 1e-15, "hat(phi) v = phi x v", scale=max(1e-300, _maxabs(phi)))
    if gname == "SE3":
        np.testing.assert_array_equal(H[:3, 3], x[:3])
        np.testing.assert_array_equal(H[3], np.zeros(4))


def test_adjoint(gname, case):
    G = GROUPS[gname]
    rng = _rng("adjoint", gname, case)
    X = G.exp(tangent(gname, case))
    Xi = G.inverse(X)
    Ad = G.adjoint(X)
    xi = random_tangent(gname, rng, angle=0.7)
    # linear identity: X hat(xi) X^-1 = hat(Ad xi)
    assert_close_rel(Ad @ xi, G.vee(X @ G.hat(xi) @ Xi), IDENTITY_TOL, "Ad xi = vee(X hat X^-1)",
                     scale=max(1.0, _maxabs(Ad @ xi)))
    # group identity: X Exp(xi) X^-1 = Exp(Ad_X xi)
    lhs = X @ G.exp(xi) @ Xi
    assert_close_rel(lhs, G.exp(Ad @ xi), IDENTITY_TOL, "X Exp(xi) X^-1 = Exp(Ad xi)",
                     scale=max(1.0, _maxabs(lhs)))
    # Ad is a homomorphism: Ad_{X^-1} = Ad_X^-1
    assert_close_rel(G.adjoint(Xi) @ Ad, np.eye(G.dim), IDENTITY_TOL, "Ad_{X^-1} Ad_X",
                     scale=max(1.0, _maxabs(Ad)))


def test_jacobian_identities(gname, case):
    G = GROUPS[gname]
    x = tangent(gname, case)
    Jr, Jl, Jri, Jli = G.jr(x), G.jl(x), G.jr_inv(x), G.jl_inv(x)
    eye = np.eye(G.dim)
    s = max(1.0, _maxabs(Jr)) * max(1.0, _maxabs(Jri))
    assert_close_rel(Jr @ Jri, eye, IDENTITY_TOL, "J_r J_r^-1", scale=s)
    assert_close_rel(Jri @ Jr, eye, IDENTITY_TOL, "J_r^-1 J_r", scale=s)
    assert_close_rel(Jl @ Jli, eye, IDENTITY_TOL, "J_l J_l^-1", scale=s)
    assert_close_rel(Jli @ Jl, eye, IDENTITY_TOL, "J_l^-1 J_l", scale=s)
    assert_close_rel(Jl, G.jr(-x), 1e-15, "J_l(x) = J_r(-x)", scale=max(1.0, _maxabs(Jl)))
    assert_close_rel(Jli, G.jr_inv(-x), 1e-15, "J_l^-1(x) = J_r^-1(-x)", scale=max(1.0, _maxabs(Jli)))
    assert_close_rel(Jl, G.adjoint(G.exp(x)) @ Jr, IDENTITY_TOL, "J_l = Ad_Exp(x) J_r",
                     scale=max(1.0, _maxabs(Jl)))
    if np.linalg.norm(G.phi(x)) == 0.0 and np.all(x == 0.0):
        np.testing.assert_array_equal(Jr, eye)
        np.testing.assert_array_equal(Jri, eye)


def test_jacobians_of_exp_numeric(gname, case):
    """Exp(x + d) = Exp(x) Exp(J_r d) = Exp(J_l d) Exp(x) to first order."""
    G = GROUPS[gname]
    x = tangent(gname, case)
    Nr = numeric_jacobian(G.exp, x, "vec", G.name)
    assert_jacobian_close(G.jr(x), Nr, NUMDIFF_RTOL, 0.0, f"{gname} J_r, {case}")
    Nl = numeric_jacobian(G.exp, x, "vec", G.name, side="left")
    assert_jacobian_close(G.jl(x), Nl, NUMDIFF_RTOL, 0.0, f"{gname} J_l, {case}")


def test_jacobians_of_log_numeric(gname, case):
    """Log(X Exp(d)) = x + J_r^-1 d and Log(Exp(d) X) = x + J_l^-1 d to first order (Log
    continued past pi, see the module notes)."""
    G = GROUPS[gname]
    x = tangent(gname, case)
    X = G.exp(x)
    Nr = numeric_jacobian(lambda Y: G.log_near(Y, x), X, G.name, "vec")
    assert_jacobian_close(G.jr_inv(x), Nr, NUMDIFF_RTOL, 0.0, f"{gname} J_r^-1, {case}")
    Nl = numeric_jacobian(lambda Y: G.log_near(Y, x), X, G.name, "vec", side="left")
    assert_jacobian_close(G.jl_inv(x), Nl, NUMDIFF_RTOL, 0.0, f"{gname} J_l^-1, {case}")


@pytest.mark.parametrize("angle", [3.5, 5.0, 6.0])
def test_jacobians_beyond_pi(gname, angle):
    """Exp and its Jacobians are defined for any angle, J^-1 up to 2 pi (splines may evaluate
    Exp(u d) with |d| near pi): numeric checks as in the suite, Log continued past pi."""
    G = GROUPS[gname]
    x = random_tangent(gname, _rng("beyond", gname, angle), angle=angle)
    assert_jacobian_close(G.jr(x), numeric_jacobian(G.exp, x, "vec", G.name), NUMDIFF_RTOL, 0.0, "J_r")
    Nl = numeric_jacobian(G.exp, x, "vec", G.name, side="left")
    assert_jacobian_close(G.jl(x), Nl, NUMDIFF_RTOL, 0.0, "J_l")
    X = G.exp(x)
    Nri = numeric_jacobian(lambda Y: G.log_near(Y, x), X, G.name, "vec")
    assert_jacobian_close(G.jr_inv(x), Nri, NUMDIFF_RTOL, 0.0, "J_r^-1")
    s = max(1.0, _maxabs(G.jr(x))) * max(1.0, _maxabs(G.jr_inv(x)))
    assert_close_rel(G.jr(x) @ G.jr_inv(x), np.eye(G.dim), IDENTITY_TOL, "J_r J_r^-1", scale=s)


def test_exact_pi_matrices():
    """Rotations by exactly pi, built without Exp: log has norm pi, points along the axis, and
    Exp(Log(R)) = R (every Shepperd branch: x, y, z, and a generic axis)."""
    rng = _rng("exact-pi")
    axes = [np.eye(3)[i] for i in range(3)] + [_unit(rng) for _ in range(4)]
    for a in axes:
        R = 2.0 * np.outer(a, a) - np.eye(3)
        phi = lie.so3_log(R)
        assert abs(np.linalg.norm(phi) - PI) <= 1e-15 * PI
        assert abs(abs(np.dot(phi, a)) - PI) <= 1e-14
        assert_close_rel(lie.so3_exp(phi), R, ROUND_TRIP_RTOL, "Exp(Log(R)) at pi", scale=1.0)
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = rng.normal(size=3)
        assert_close_rel(lie.se3_exp(lie.se3_log(T)), T, ROUND_TRIP_RTOL, "SE3 at pi", scale=_maxabs(T))


# ---------------------------------------------------------- small-angle thresholds


def _t2(x):
    """|x|^2 exactly as the kernels compute it."""
    return x[0] * x[0] + x[1] * x[1] + x[2] * x[2]


def _sides(threshold, key):
    """Angles 1e-15 relative below / above ``threshold`` along a random axis, with the branch
    of each checked against the kernels' comparison ``t2 < threshold**2``."""
    axis = _unit(_rng("threshold", key))
    lo = axis * (threshold * (1.0 - 1e-15))
    hi = axis * (threshold * (1.0 + 1e-15))
    assert _t2(lo) < threshold * threshold <= _t2(hi)
    return lo, hi


SO3_MATRIX_FUNCS = {
    "so3_exp": lie.so3_exp,
    "so3_right_jacobian": lie.so3_right_jacobian,
    "so3_left_jacobian": lie.so3_left_jacobian,
    "so3_right_jacobian_inv": lie.so3_right_jacobian_inv,
    "so3_left_jacobian_inv": lie.so3_left_jacobian_inv,
}
SE3_MATRIX_FUNCS = {
    "se3_exp": lie.se3_exp,
    "se3_right_jacobian": lie.se3_right_jacobian,
    "se3_left_jacobian": lie.se3_left_jacobian,
    "se3_right_jacobian_inv": lie.se3_right_jacobian_inv,
    "se3_left_jacobian_inv": lie.se3_left_jacobian_inv,
}
THRESHOLDS = ["EXP_SMALL_ANGLE", "JAC_SMALL_ANGLE", "SE3_Q_SMALL_ANGLE"]
_OFFDIAG = ~np.eye(3, dtype=bool)


@pytest.mark.parametrize("threshold", THRESHOLDS)
@pytest.mark.parametrize("fname", list(SO3_MATRIX_FUNCS))
def test_so3_continuity_across_threshold(threshold, fname):
    lo, hi = _sides(getattr(K, threshold), threshold)
    f = SO3_MATRIX_FUNCS[fname]
    a, b = f(lo), f(hi)
    assert_close_rel(b, a, THRESHOLD_RTOL, f"{fname} across {threshold}")
    # the small-angle terms sit in the off-diagonal entries; compare them on their own scale
    assert_close_rel(b[_OFFDIAG], a[_OFFDIAG], THRESHOLD_RTOL, f"{fname} off-diagonal across {threshold}")


@pytest.mark.parametrize("threshold", THRESHOLDS)
@pytest.mark.parametrize("fname", list(SE3_MATRIX_FUNCS))
def test_se3_continuity_across_threshold(threshold, fname):
    lo, hi = _sides(getattr(K, threshold), threshold)
    rho = _rng("rho", threshold).normal(size=3)
    f = SE3_MATRIX_FUNCS[fname]
    a, b = f(np.concatenate([rho, lo])), f(np.concatenate([rho, hi]))
    tol = THRESHOLD_RTOL
    assert_close_rel(b, a, tol, f"{fname} across {threshold}")
    # the translation column / Q block on its own scale
    blk = (slice(0, 3), slice(3, 4)) if a.shape == (4, 4) else (slice(0, 3), slice(3, 6))
    assert_close_rel(b[blk], a[blk], tol, f"{fname} coupling block across {threshold}")


@pytest.mark.parametrize("threshold", THRESHOLDS)
def test_log_round_trip_at_threshold(threshold):
    for x in _sides(getattr(K, threshold), threshold):
        assert_close_rel(lie.so3_log(lie.so3_exp(x)), x, THRESHOLD_RTOL, f"log(exp) at {threshold}")


def test_log_continuity_across_log_threshold():
    """LOG_SMALL_ANGLE bounds |v| / w of the quaternion: the series and atan2 branches must
    agree with 2 atan(r) to 1e-14 relative on both sides (quaternion and matrix paths)."""
    th = K.LOG_SMALL_ANGLE
    axis = _unit(_rng("log-threshold"))
    outs = []
    for f in (1.0 - 1e-15, 1.0 + 1e-15):
        q_xyz = axis * (th * f)
        n = math.sqrt(_t2(q_xyz))
        assert (n < th) == (f < 1.0)  # the kernel's branch test with w = 1
        phi = lie.so3_log(np.append(q_xyz, 1.0))
        expected = q_xyz / n * (2.0 * math.atan(n))
        assert_close_rel(phi, expected, THRESHOLD_RTOL, f"quaternion log at LOG_SMALL_ANGLE * {f}")
        outs.append(phi)
    assert_close_rel(outs[1], outs[0], THRESHOLD_RTOL, "log across LOG_SMALL_ANGLE")
    # matrix path: angles 1e-9 relative on either side of 2 atan(threshold)
    for f in (1.0 - 1e-9, 1.0 + 1e-9):
        x = axis * (2.0 * math.atan(th) * f)
        q = lie.matrix_to_quat_xyzw(lie.so3_exp(x))
        assert (np.linalg.norm(q[:3]) < th * q[3]) == (f < 1.0)
        assert_close_rel(lie.so3_log(lie.so3_exp(x)), x, THRESHOLD_RTOL, "matrix log at LOG_SMALL_ANGLE")


def test_so3_jacobian_coefficients_against_60_digits():
    """The scalar coefficients sin t/t, (1-cos t)/t^2, (t-sin t)/t^3, 1/t^2 - cot(t/2)/2t against a
    60-digit reference: 4 eps on the Taylor side of JAC_SMALL_ANGLE; above it the last two lose
    ~ eps/t^2 to cancellation (that is why the switch is at 0.1), bounded by 4 eps + 16 eps/t^2."""
    eps = np.finfo(float).eps
    th = K.JAC_SMALL_ANGLE
    ts = np.concatenate([np.geomspace(1e-8, 3.1, 40), [th * (1 - 1e-15), th * (1 + 1e-15), 0.5 * th, 2 * th]])
    with localcontext() as ctx:
        ctx.prec = 60
        for t in ts:
            T = Decimal(float(t))
            st_, ct_ = decimal_sin_cos(T)
            sh, ch = decimal_sin_cos(T / 2)
            ref = [st_ / T, (1 - ct_) / T**2, (T - st_) / T**3, 1 / T**2 - ch / (2 * T * sh)]
            got = list(K.so3_jac_coeffs(t * t)) + [K.so3_jac_inv_coeff(t * t)]
            for name, g, r in zip("abcd", got, ref):
                rel = abs(g / float(r) - 1.0)
                bound = 4 * eps if (name in "ab" or t * t < th * th) else 4 * eps + 16 * eps / (t * t)
                assert rel <= bound, f"coefficient {name} at t={t!r}: relative error {rel:.2e} > {bound:.2e}"


def test_se3_q_block_against_60_digits():
    """Barfoot's Q(rho, phi) block evaluated in 60-digit arithmetic, on both sides of
    SE3_Q_SMALL_ANGLE and up to pi: 2e-15 relative [<= 7e-16]."""
    rng = _rng("q-block")
    th = K.SE3_Q_SMALL_ANGLE
    for angle in [1e-6, 0.05, th * (1 - 1e-15), th * (1 + 1e-15), 1.0, 2.5, PI - 1e-6, PI]:
        rho = rng.normal(size=3)
        phi = _unit(rng) * angle
        with localcontext() as ctx:
            ctx.prec = 60
            r = [Decimal(float(v)) for v in rho]
            p = [Decimal(float(v)) for v in phi]

            def hat(v):
                z = Decimal(0)
                return [[z, -v[2], v[1]], [v[2], z, -v[0]], [-v[1], v[0], z]]

            def mm(A, B):
                return [[sum(A[i][m] * B[m][j] for m in range(3)) for j in range(3)] for i in range(3)]

            t2 = sum(v * v for v in p)
            t = t2.sqrt()
            st_, ct_ = decimal_sin_cos(t)
            c1 = (t - st_) / t**3
            c2 = (t2 / 2 + ct_ - 1) / t2**2
            c4 = (2 * t - 3 * st_ + t * ct_) / (2 * t**5)
            P, R = hat(p), hat(r)
            PR, RP = mm(P, R), mm(R, P)
            PRP, PPR, RPP = mm(PR, P), mm(P, PR), mm(RP, P)
            PRPP, PPRP = mm(PRP, P), mm(P, PRP)
            ref = np.array([[float(R[i][j] / 2 + c1 * (PR[i][j] + RP[i][j] + PRP[i][j])
                                   + c2 * (PPR[i][j] + RPP[i][j] - 3 * PRP[i][j])
                                   + c4 * (PRPP[i][j] + PPRP[i][j])) for j in range(3)] for i in range(3)])
        Q = lie.se3_left_jacobian(np.concatenate([rho, phi]))[:3, 3:]
        assert_close_rel(Q, ref, 2e-15, f"Q block at |phi| = {angle!r}")
        # the right Jacobian's block is Q(-rho, -phi)
        Qr = lie.se3_right_jacobian(np.concatenate([-rho, -phi]))[:3, 3:]
        assert_close_rel(Qr, ref, 2e-15, f"right Q block at |phi| = {angle!r}")


# ----------------------------------------------------------------------- quaternions


def _quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _near_pi_rotvecs(rng):
    out = []
    for d in (0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3):
        for _ in range(3):
            out.append(_unit(rng) * (PI - d))
    for i in range(3):  # coordinate axes: each Shepperd diagonal branch
        for d in (1e-9, 1e-6):
            out.append(np.eye(3)[i] * (PI - d))
    return np.array(out)


def test_so3_log_quaternion_sign_indifference():
    rng = _rng("quat-sign")
    rotvecs = np.concatenate([rng.normal(size=(20, 3)), _near_pi_rotvecs(rng), [[0.0, 0.0, 0.0]],
                              _unit(rng)[None] * 1e-8])
    q = Rotation.from_rotvec(rotvecs).as_quat()  # xyzw
    a = lie.so3_log(q)
    b = lie.so3_log(-q)
    assert_close_rel(b, a, 0.0, "so3_log(-q) = so3_log(q)", scale=1.0)
    # and the quaternion path agrees with the matrix path
    assert_close_rel(lie.so3_log(lie.quat_xyzw_to_matrix(q)), a, 1e-14, "quat vs matrix log", scale=PI)
    # non-unit quaternions are normalized first
    assert_close_rel(lie.so3_log(3.7 * q), a, 1e-15, "non-unit q", scale=PI)
    # exactly pi (w = 0): +q and -q give +-phi, the same rotation
    for axis in [np.eye(3)[0], _unit(rng)]:
        qpi = np.append(axis, 0.0)
        p, m = lie.so3_log(qpi), lie.so3_log(-qpi)
        assert abs(np.linalg.norm(p) - PI) <= 2e-15 and abs(np.linalg.norm(m) - PI) <= 2e-15
        assert_close_rel(lie.so3_exp(m), lie.so3_exp(p), 1e-15, "pi: same rotation", scale=1.0)


def test_quaternion_matrix_conversions_against_scipy():
    rng = _rng("quat-conv")
    q = np.concatenate([
        _quats(rng, 50),
        Rotation.from_rotvec(_near_pi_rotvecs(rng)).as_quat(),
        [[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]],
    ])
    R = lie.quat_xyzw_to_matrix(q)
    assert_close_rel(R, Rotation.from_quat(q).as_matrix(), SCIPY_ATOL, "quat -> matrix", scale=1.0)
    q2 = lie.matrix_to_quat_xyzw(R)
    assert np.all(q2[:, 3] >= 0.0)
    assert_close_rel(np.linalg.norm(q2, axis=1), np.ones(len(q)), 1e-15, "unit", scale=1.0)
    # q2 = +-q (canonical w >= 0; the sign is free when w = 0)
    sign = np.where(np.einsum("ij,ij->i", q2, q) < 0.0, -1.0, 1.0)
    assert_close_rel(q2, sign[:, None] * q, SCIPY_ATOL, "matrix -> quat = +-q", scale=1.0)
    ref = Rotation.from_matrix(R).as_quat(canonical=True)
    sref = np.where(np.einsum("ij,ij->i", q2, ref) < 0.0, -1.0, 1.0)
    assert np.all(sref[q2[:, 3] > 1e-12] == 1.0)  # same canonical sign wherever w != 0
    assert_close_rel(q2, sref[:, None] * ref, SCIPY_ATOL, "matrix -> quat vs scipy", scale=1.0)
    assert_close_rel(lie.quat_xyzw_to_matrix(q2), R, SCIPY_ATOL, "matrix -> quat -> matrix", scale=1.0)
    # non-unit input is normalized
    assert_close_rel(lie.quat_xyzw_to_matrix(0.25 * q), R, 1e-15, "non-unit q", scale=1.0)


def test_scipy_rotation_cross_check():
    rng = _rng("scipy")
    rotvecs = np.concatenate([
        rng.normal(size=(50, 3)) * 1.2,
        _unit(rng)[None] * 1e-8,
        _near_pi_rotvecs(rng),
    ])
    rotvecs = rotvecs[np.linalg.norm(rotvecs, axis=1) < PI]
    R = lie.so3_exp(rotvecs)
    assert_close_rel(R, Rotation.from_rotvec(rotvecs).as_matrix(), SCIPY_ATOL, "so3_exp vs scipy", scale=1.0)
    phi = lie.so3_log(R)
    ref = Rotation.from_matrix(R).as_rotvec()
    far = np.linalg.norm(rotvecs, axis=1) < PI - 1e-12  # below this the axis sign is determined
    assert_close_rel(phi[far], ref[far], SCIPY_ATOL, "so3_log vs scipy", scale=1.0)
    assert_close_rel(phi[far], rotvecs[far], 1e-13, "so3_log(so3_exp(x))", scale=1.0)
    # within 1e-12 of pi: same rotation, angle pi
    assert_close_rel(lie.so3_exp(phi[~far]), R[~far], SCIPY_ATOL, "near pi", scale=1.0)
    # quaternion route
    q = Rotation.from_rotvec(rotvecs).as_quat()
    assert_close_rel(lie.so3_log(q)[far], rotvecs[far], 1e-13, "so3_log(quat)", scale=1.0)


def test_quat_make_continuous():
    rng = _rng("continuous")
    t = np.linspace(0.0, 4.0, 200)
    rotvecs = np.outer(t, [0.3, -1.1, 2.0])  # several full turns: the scipy sign wanders
    smooth = Rotation.from_rotvec(rotvecs).as_quat()
    # build the reference by hand: flip whenever the step dot product is negative
    ref = smooth.copy()
    for i in range(1, len(ref)):
        if np.dot(ref[i], ref[i - 1]) < 0:
            ref[i] = -ref[i]
    flips = rng.choice([-1.0, 1.0], size=len(t))
    flips[0] = 1.0
    messy = ref * flips[:, None]
    out = lie.quat_make_continuous(messy)
    np.testing.assert_array_equal(out, ref)
    assert np.all(np.einsum("ij,ij->i", out[1:], out[:-1]) >= 0.0)
    assert np.min(np.einsum("ij,ij->i", out[1:], out[:-1])) > 0.99  # smooth, not just non-negative
    # batches of sequences along axis -2, a single quaternion and an empty sequence
    both = lie.quat_make_continuous(np.stack([messy, -messy]))
    np.testing.assert_array_equal(both[0], ref)
    np.testing.assert_array_equal(both[1], -ref)
    np.testing.assert_array_equal(lie.quat_make_continuous(-ref[3]), -ref[3])
    assert lie.quat_make_continuous(np.zeros((0, 4))).shape == (0, 4)
    with pytest.raises(SplineImuError, match="quat_xyzw"):
        lie.quat_make_continuous(np.zeros((5, 3)))


def test_quat_normalize():
    q = np.array([[0.0, 0.0, 0.0, 2.0], [1.0, 1.0, 1.0, 1.0]])
    expected = [[0, 0, 0, 1], [0.5, 0.5, 0.5, 0.5]]
    np.testing.assert_allclose(lie.quat_normalize(q), expected, rtol=0, atol=1e-16)
    with pytest.raises(SplineImuError, match="quat_xyzw"):
        lie.quat_normalize([0.0, 0.0, 0.0, 0.0])
    with pytest.raises(SplineImuError, match="quat_xyzw"):
        lie.quat_xyzw_to_matrix([np.nan, 0.0, 0.0, 1.0])


# --------------------------------------------------------------- array API contract


def test_batch_shapes_match_single_calls():
    rng = _rng("batch")
    phi = rng.normal(size=(2, 3, 3))
    xi = rng.normal(size=(2, 3, 6))
    for f, x, tail in [
        (lie.so3_exp, phi, (3, 3)), (lie.so3_right_jacobian, phi, (3, 3)),
        (lie.so3_left_jacobian_inv, phi, (3, 3)), (lie.so3_hat, phi, (3, 3)),
        (lie.se3_exp, xi, (4, 4)), (lie.se3_right_jacobian, xi, (6, 6)),
        (lie.se3_left_jacobian_inv, xi, (6, 6)), (lie.se3_hat, xi, (4, 4)),
    ]:
        out = f(x)
        assert out.shape == (2, 3) + tail
        for i in range(2):
            for j in range(3):
                np.testing.assert_array_equal(out[i, j], f(x[i, j]))
    R = lie.so3_exp(phi)
    assert lie.so3_log(R).shape == (2, 3, 3)
    T = lie.se3_exp(xi)
    assert lie.se3_log(T).shape == (2, 3, 6)
    assert lie.se3_adjoint(T).shape == (2, 3, 6, 6)
    assert lie.matrix_to_quat_xyzw(R).shape == (2, 3, 4)
    assert lie.so3_exp(np.zeros((0, 3))).shape == (0, 3, 3)
    assert lie.se3_log(np.zeros((0, 4, 4))).shape == (0, 6)
    # inputs need not be contiguous or float64
    Rt = np.swapaxes(R, -1, -2)
    np.testing.assert_array_equal(lie.so3_log(Rt), lie.so3_log(np.ascontiguousarray(Rt)))
    np.testing.assert_array_equal(lie.so3_exp(np.array([1, 0, 0])), lie.so3_exp([1.0, 0.0, 0.0]))


@pytest.mark.parametrize(
    "func, arg, name",
    [
        (lie.so3_exp, np.zeros(4), "phi"),
        (lie.so3_right_jacobian, np.zeros((2, 2)), "phi"),
        (lie.se3_exp, np.zeros(3), "xi"),
        (lie.se3_log, np.eye(3), "T"),
        (lie.so3_log, np.zeros((3, 2)), "rot"),
        (lie.matrix_to_quat_xyzw, np.zeros(3), "R"),
        (lie.quat_xyzw_to_matrix, np.zeros(3), "quat_xyzw"),
    ],
)
def test_shape_errors_name_the_argument(func, arg, name):
    with pytest.raises(SplineImuError, match=rf"`{name}`.*got {re_shape(np.shape(arg))}"):
        func(arg)


def re_shape(shape):
    return str(tuple(shape)).replace("(", r"\(").replace(")", r"\)")


# ------------------------------------------------------------------------ hypothesis

#: rotation angles: exactly 0, tiny, around every threshold, ordinary, up to pi - 1e-9
ANGLES = st.one_of(
    st.just(0.0),
    st.floats(1e-300, 1e-9),
    st.floats(1e-9, 1e-3),
    st.sampled_from([getattr(K, n) for n in THRESHOLDS] + [2.0 * math.atan(K.LOG_SMALL_ANGLE)]).flatmap(
        lambda th: st.floats(th * (1 - 1e-9), th * (1 + 1e-9))),
    st.floats(1e-3, PI - 1e-3),
    st.floats(PI - 1e-3, PI - 1e-9),
)
#: beyond pi (Exp and the Jacobians are defined there; J^-1 up to 2 pi)
ANGLES_WIDE = st.one_of(ANGLES, st.floats(PI - 1e-9, PI), st.floats(PI, 6.0))
_DIRS = st.tuples(*[st.floats(-1.0, 1.0)] * 3)


def _rotvec(direction, angle):
    d = np.array(direction)
    n = np.linalg.norm(d)
    d = np.array([1.0, 0.0, 0.0]) if n < 1e-3 else d / n
    return d * angle


def rotvecs(angles=ANGLES):
    return st.builds(_rotvec, _DIRS, angles)


_RHO = st.builds(lambda d, s: _rotvec(d, s), _DIRS,
                 st.one_of(st.just(0.0), st.floats(1e-9, 1e-3), st.floats(1e-3, 20.0)))


def twists(angles=ANGLES):
    return st.builds(lambda r, p: np.concatenate([r, p]), _RHO, rotvecs(angles))


@given(rotvecs())
def test_property_so3_round_trips(x):
    R = lie.so3_exp(x)
    assert_close_rel(lie.so3_log(R), x, ROUND_TRIP_RTOL, "log(exp(x))")
    assert_close_rel(lie.so3_exp(lie.so3_log(R)), R, ROUND_TRIP_RTOL, "exp(log(X))", scale=1.0)
    assert_close_rel(R, Rotation.from_rotvec(x).as_matrix(), SCIPY_ATOL, "vs scipy", scale=1.0)
    q = lie.matrix_to_quat_xyzw(R)
    assert_close_rel(lie.so3_log(-q), x, ROUND_TRIP_RTOL, "log(-q)", scale=max(_maxabs(x), 1e-300))


@given(twists())
def test_property_se3_round_trips(xi):
    T = lie.se3_exp(xi)
    assert_close_rel(lie.se3_log(T), xi, ROUND_TRIP_RTOL, "log(exp(xi))")
    s = max(1.0, _maxabs(T))
    assert_close_rel(lie.se3_exp(lie.se3_log(T)), T, ROUND_TRIP_RTOL, "exp(log(T))", scale=s)


@pytest.mark.parametrize("gname", list(GROUPS))
@given(data=st.data())
def test_property_jacobian_identities(gname, data):
    G = GROUPS[gname]
    x = data.draw(rotvecs(ANGLES_WIDE) if gname == "SO3" else twists(ANGLES_WIDE))
    Jr, Jri, Jl = G.jr(x), G.jr_inv(x), G.jl(x)
    s = max(1.0, _maxabs(Jr)) * max(1.0, _maxabs(Jri))
    # cond(J) grows towards |phi| = 2 pi (at 6: ~ 20)
    assert_close_rel(Jr @ Jri, np.eye(G.dim), IDENTITY_TOL, "J_r J_r^-1", scale=s)
    assert_close_rel(Jl @ G.jl_inv(x), np.eye(G.dim), IDENTITY_TOL, "J_l J_l^-1", scale=s)
    assert_close_rel(Jl, G.jr(-x), 1e-15, "J_l(x) = J_r(-x)", scale=max(1.0, _maxabs(Jl)))
    assert_close_rel(Jl, G.adjoint(G.exp(x)) @ Jr, IDENTITY_TOL, "J_l = Ad J_r", scale=max(1.0, _maxabs(Jl)))


@pytest.mark.parametrize("gname", list(GROUPS))
@given(data=st.data())
def test_property_jacobians_numeric(gname, data):
    G = GROUPS[gname]
    x = data.draw(rotvecs(ANGLES_WIDE) if gname == "SO3" else twists(ANGLES_WIDE))
    assert_jacobian_close(G.jr(x), numeric_jacobian(G.exp, x, "vec", G.name), NUMDIFF_RTOL, 0.0, "J_r")
    if np.linalg.norm(G.phi(x)) < 6.0:
        X = G.exp(x)
        Nri = numeric_jacobian(lambda Y: G.log_near(Y, x), X, G.name, "vec")
        assert_jacobian_close(G.jr_inv(x), Nri, NUMDIFF_RTOL, 0.0, "J_r^-1")


# ------------------------------------------------------------------ numdiff self-checks


def test_numdiff_time_derivative_orders():
    """Richardson (order 6) reaches ~1e-13 where central2 is at 1e-6: the helper is good enough
    for the 1e-7 checks of the spline and scene derivatives (module notes of numdiff)."""
    w = 10.0
    t = np.linspace(0.1, 2.0, 40)

    def f(t):
        return np.stack([np.sin(w * t), np.cos(3 * t) * np.exp(t)], axis=1)

    df = np.stack([w * np.cos(w * t), (np.cos(3 * t) - 3 * np.sin(3 * t)) * np.exp(t)], axis=1)
    h = 0.02 / w
    err = {m: np.abs(time_derivative(f, t, h, method=m, levels=3) - df).max() / np.abs(df).max()
           for m in ("central2", "central4", "richardson")}
    assert 1e-6 < err["central2"] < 1e-4
    assert err["central4"] < 1e-8
    assert err["richardson"] < 1e-11
    # large time origins: the rounding of t + s is accounted for
    t0 = 1.0e6
    g = time_derivative(lambda tt: np.sin(w * (tt - t0))[:, None], t0 + t, h)
    assert np.abs(g[:, 0] - w * np.cos(w * ((t0 + t) - t0))).max() < 1e-9 * w


def test_numdiff_body_rates_on_groups():
    """``group="so3"`` gives vee(R^T dR/dt) = J_r(a) a' for R = Exp(a(t)), and ``"se3"`` the body
    twist J_r(xi) xi' for T = Exp(xi(t)) (a cross-check of both right Jacobians as well)."""
    t = np.linspace(-1.0, 1.0, 25)

    def xi(t):
        return np.stack([np.sin(t), t**2, 0.5 * t, 2.5 * np.sin(1.3 * t) + 0.4, t**3 - 1.0, np.cos(2 * t)],
                        axis=1)

    def dxi(t):
        return np.stack([np.cos(t), 2 * t, 0.5 + 0 * t, 3.25 * np.cos(1.3 * t), 3 * t**2, -2 * np.sin(2 * t)],
                        axis=1)

    omega = np.einsum("nij,nj->ni", lie.so3_right_jacobian(xi(t)[:, 3:]), dxi(t)[:, 3:])
    num = time_derivative(lambda s: lie.so3_exp(xi(s)[:, 3:]), t, 1e-2, group="so3")
    assert_derivative_close(omega, num, 1e-11, 0.0, "so3 body rate", t=t)
    twist = np.einsum("nij,nj->ni", lie.se3_right_jacobian(xi(t)), dxi(t))
    num = time_derivative(lambda s: lie.se3_exp(xi(s)), t, 1e-2, group="se3")
    assert_derivative_close(twist, num, 1e-11, 0.0, "se3 body twist", t=t)


def test_numdiff_jacobian_of_linear_maps():
    A = _rng("linear").normal(size=(4, 3))
    x = np.array([1e6, -2.0, 3e-3])
    # f is exactly linear in the step that x + s really applies; dividing by the nominal 2 s
    # instead would be off by eps * 1e6 / 1e-3 ~ 1e-7
    assert_jacobian_close(A, numeric_jacobian(lambda v: A @ (v - x), x), 1e-12, 0.0, "linear")
    # the action of a rotation, differentiated on SO3 (right): d(R Exp(d) v)/dd = -R [v]x
    R = lie.so3_exp([0.3, -2.0, 1.0])
    v = np.array([1.0, 2.0, -0.5])
    N = numeric_jacobian(lambda Y: Y @ v, R, "so3", "vec")
    assert_jacobian_close(-R @ lie.so3_hat(v), N, 1e-11, 0.0, "d(Rv)/dR")


def test_numdiff_failure_messages_show_both_jacobians():
    A = np.arange(6.0).reshape(2, 3)
    with pytest.raises(AssertionError) as err:
        assert_jacobian_close(A, A + 1e-6, 1e-9, 0.0, "demo-label")
    msg = str(err.value)
    for part in ("demo-label", "analytic:", "numeric:", "analytic - numeric:", "relative"):
        assert part in msg
    assert_jacobian_close(A, A + 1e-10, 1e-9, 0.0, "within tolerance")
    with pytest.raises(AssertionError) as err:
        bumped = np.ones((5, 3))
        bumped[4, 1] += 1e-3
        assert_derivative_close(np.ones((5, 3)), bumped, 1e-7, 0.0, "rates", t=np.arange(5.0))
    msg = str(err.value)
    assert "sample 4 t=" in msg and "analytic" in msg and "numeric" in msg and "diff" in msg
