"""Kernels of the rotation fit's Gauss-Newton solve against the reference kernel, finite
differences and scipy."""

from __future__ import annotations

import numpy as np
import pytest
from numdiff import assert_jacobian_close, numeric_jacobian

from splineimu import lie
from splineimu._kernels import fit as _kf
from splineimu._kernels import gauss_newton as _gn
from splineimu.spline import banded
from splineimu.spline.banded import segments
from splineimu.spline.basis import blending_matrix
from splineimu.spline.controls import _increments_so3
from splineimu.spline.problem import _quasi_interpolant


def _wxyz(R):
    return np.ascontiguousarray(lie.matrix_to_quat_xyzw(R)[..., [3, 0, 1, 2]])


def _problem(k, n=11, n_poses=150, spread=1.0, seed=0):
    rng = np.random.default_rng(seed)
    Rc = lie.so3_exp(rng.normal(size=(n, 3)) * 0.7)
    nseg = n - k + 1
    s = np.sort(rng.uniform(0, nseg, n_poses))
    Rm = lie.so3_exp(rng.normal(size=(n_poses, 3)) * spread)
    w = rng.uniform(0.5, 2.0, n_poses)
    w[::17] = 0.0
    return Rc, s, Rm, w, nseg


def _new(Rc, s, Rm, w, k, nseg, want_h=True):
    n = Rc.shape[0]
    qc = _wxyz(Rc)
    D = np.empty((n, 3))
    C = np.empty((n, 3, 3))
    _gn.so3_knot_terms(qc, D, C)
    band = np.zeros((3 * n, 3 * k))
    g = np.zeros((n, 3))
    res = np.empty((s.size, 3))
    cost = _gn.so3_pass(*segments(s, 0.0, 1.0), w, _wxyz(Rm), qc, D, C, blending_matrix(k, True), nseg, want_h,
                        band, g, res)
    return cost, band, g, res, D, C


def _old(Rc, s, Rm, w, k, nseg):
    n = Rc.shape[0]
    H = np.zeros((n, k, 3, 3))
    g = np.zeros((n, 3))
    res = np.empty((s.size, 3))
    cost = _kf.so3_normal_equations(*segments(s, 0.0, 1.0), w, Rm, Rc, _increments_so3(Rc), blending_matrix(k, True),
                                    nseg, H, g, res)
    band = np.zeros((3 * n, 3 * k))
    _kf.blocks_to_band(H, band)
    return cost, band, g, res


@pytest.mark.parametrize("k", [2, 4, 5, 6])
def test_pass_matches_reference_kernel(k):
    """Cost, residuals and gradient equal the reference kernel's (the fixed point is today's)."""
    Rc, s, Rm, w, nseg = _problem(k)
    c1, _, g1, r1, D, C = _new(Rc, s, Rm, w, k, nseg)
    c0, _, g0, r0 = _old(Rc, s, Rm, w, k, nseg)
    assert abs(c1 - c0) <= 1e-13 * c0
    np.testing.assert_allclose(r1, r0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(g1, g0, rtol=0, atol=1e-13 * np.abs(g0).max())
    np.testing.assert_allclose(D, _increments_so3(Rc), rtol=0, atol=1e-15)
    np.testing.assert_allclose(C[1:], lie.so3_right_jacobian_inv(D[1:]), rtol=0, atol=1e-15)
    # without the normal matrix: the same gradient
    c2, band2, g2, _, _, _ = _new(Rc, s, Rm, w, k, nseg, want_h=False)
    assert c2 == c1 and np.array_equal(g2, g1) and not band2.any()


@pytest.mark.parametrize("k", [4, 6])
def test_normal_matrix_equals_reference_at_zero_residual(k):
    """The normal matrix leaves out Jl^-T(r) Jl^-1(r) = I + O(|r|^2): exact at r = 0, and off by
    O(|r|^2) relative for small residuals."""
    Rc, s, _, w, nseg = _problem(k)
    R_fit = np.empty((s.size, 3, 3))
    _, _, _, r_any = _old(Rc, s, lie.so3_exp(np.zeros((s.size, 3))), w, k, nseg)
    R_fit = lie.so3_exp(np.zeros((s.size, 3))) @ lie.so3_exp(-r_any)  # R(t_m): residual 0 against it
    _, band1, _, res1, _, _ = _new(Rc, s, R_fit, w, k, nseg)
    _, band0, _, _ = _old(Rc, s, R_fit, w, k, nseg)
    assert np.abs(res1).max() < 1e-14
    np.testing.assert_allclose(band1, band0, rtol=0, atol=1e-13 * np.abs(band0).max())
    eps = 1e-3
    rng = np.random.default_rng(1)
    R_near = R_fit @ lie.so3_exp(eps * rng.normal(size=(s.size, 3)))
    _, band1, _, _, _, _ = _new(Rc, s, R_near, w, k, nseg)
    _, band0, _, _ = _old(Rc, s, R_near, w, k, nseg)
    assert np.abs(band1 - band0).max() <= 10 * eps**2 * np.abs(band0).max()


def test_gradient_matches_finite_differences():
    """g = sum w J^T r is half the gradient of the cost under R_i <- R_i Exp(d) (spread-out data)."""
    k = 5
    Rc, s, Rm, w, nseg = _problem(k, n=9, n_poses=60, spread=0.4, seed=3)

    def cost_of(d):
        R = Rc @ lie.so3_exp(d.reshape(-1, 3))
        return np.array([_new(R, s, Rm, w, k, nseg, want_h=False)[0]])

    _, _, g, _, _, _ = _new(Rc, s, Rm, w, k, nseg)
    num = numeric_jacobian(cost_of, np.zeros(Rc.shape[0] * 3), eps=1e-3)[0] / 2
    assert_jacobian_close(g.reshape(1, -1), num.reshape(1, -1), rtol=1e-7, atol=1e-9 * np.abs(num).max(),
                          label="so3_pass gradient")


def _penalty_numpy(D, Jr, Jl, mu):
    """The penalty's blocks as the reference formula: e_j = d_{j+1} - d_j, j = 1 .. n-2."""
    n, d = D.shape
    H = np.zeros((n * d, n * d))
    g = np.zeros(n * d)
    cost = 0.0
    for j in range(1, n - 1):
        e = D[j + 1] - D[j]
        B = {j - 1: Jl[j], j: -Jl[j + 1] - Jr[j], j + 1: Jr[j + 1]}
        Jrow = np.zeros((d, n * d))
        for i, blk in B.items():
            Jrow[:, i * d:(i + 1) * d] = blk
        H += mu[j - 1] * Jrow.T @ Jrow
        g += mu[j - 1] * Jrow.T @ e
        cost += mu[j - 1] * e @ e
    return cost, H, g


def _band_to_dense(band):
    m, w = band.shape
    A = np.zeros((m, m))
    for i in range(m):
        for c in range(w):
            if i + c < m:
                A[i, i + c] = A[i + c, i] = band[i, c]
    return A


@pytest.mark.parametrize("d", [3, 6])
def test_increment_penalty_matches_dense_formula(d):
    rng = np.random.default_rng(d)
    n, k = 8, 4
    D = rng.normal(size=(n, d))
    Jr = rng.normal(size=(n, d, d))
    Jl = rng.normal(size=(n, d, d))
    mu = rng.uniform(0.0, 2.0, n - 2)
    mu[2] = 0.0
    band = np.zeros((n * d, k * d))
    g = np.zeros((n, d))
    cost = _gn.increment_penalty(D, Jr, Jl, mu, True, band, g)
    c0, H0, g0 = _penalty_numpy(D, Jr, Jl, mu)
    assert abs(cost - c0) <= 1e-13 * c0
    np.testing.assert_allclose(g.reshape(-1), g0, rtol=0, atol=1e-13 * np.abs(g0).max())
    np.testing.assert_allclose(_band_to_dense(band), H0, rtol=0, atol=1e-13 * np.abs(H0).max())


def test_slerp_matches_scipy():
    from scipy.spatial.transform import Rotation, Slerp

    rng = np.random.default_rng(4)
    t = np.cumsum(rng.uniform(0.01, 0.1, 40))
    R = lie.so3_exp(np.cumsum(rng.normal(size=(40, 3)) * 0.3, axis=0))
    tq = np.sort(np.r_[rng.uniform(t[0] - 0.2, t[-1] + 0.2, 100), t[:3], t[-1]])
    out = np.empty((tq.size, 4))
    q = _wxyz(R)
    q[::3] *= -1  # either sign
    _gn.quat_slerp(t, q, tq, out)
    ref = Slerp(t, Rotation.from_matrix(R))(np.clip(tq, t[0], t[-1])).as_matrix()
    got = lie.quat_xyzw_to_matrix(out[:, [1, 2, 3, 0]])
    assert np.abs(got - ref).max() < 1e-14


def _spline_rotations(Rc, order, t0, dt, t):
    from splineimu import Spline

    spl = Spline(t0, dt, np.zeros((Rc.shape[0], 3)), Rc, "split", order)
    return lie.quat_xyzw_to_matrix(spl.pose(t)[1])


_INIT_N = 24


def _init_error(Rc, order, dt=0.1):
    """Largest angle between the control rotations Rc (_INIT_N, 3, 3) and the quasi-interpolant
    of their spline's poses at the control times, away from the ends."""
    n = _INIT_N
    tc = (np.arange(n) - (order - 2) / 2.0) * dt
    nseg = n - order + 1
    inside = (tc >= 0.0) & (tc <= nseg * dt)
    t = np.unique(np.r_[0.0, tc[inside], nseg * dt])
    q = _wxyz(_spline_rotations(Rc, order, 0.0, dt, t))
    out = np.empty((n, 4))
    _gn.control_grid_init(t, q, tc, *_quasi_interpolant(order), out)
    e = np.linalg.norm(lie.so3_log(np.swapaxes(Rc, 1, 2) @ lie.quat_xyzw_to_matrix(out[:, [1, 2, 3, 0]])), axis=1)
    first, last = np.flatnonzero(inside)[[0, -1]]
    return float(e[first + 2: last - 1].max())


@pytest.mark.parametrize("order", [3, 4, 5, 6])
def test_control_grid_init_inverts_the_smoothing(order):
    """About a fixed axis the spline is an ordinary B-spline of the angle: for control angles
    that are a polynomial of degree 5 in the index, poses at the control times give back the
    control rotations exactly (the quasi-interpolant's error is a sixth difference); turning
    about all axes, the error is second order in the turn per knot."""
    i = np.arange(_INIT_N) / _INIT_N
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    errs = [_init_error(Rc, order) for Rc in (lie.so3_exp(np.outer(3.0 * i - 2.0 * i**3 + 4.0 * i**5, axis)),
                                              lie.so3_exp(np.c_[np.sin(3 * i), np.cos(5 * i), 4 * i] * 0.5))]
    assert errs[0] < 1e-13 and errs[1] < 2e-4, errs  # measured < 1.5e-15, < 6.2e-5


@pytest.mark.parametrize("order", [4, 6])
def test_control_grid_init_unwraps_turns_beyond_pi(order):
    """Knots 60-133 degrees apart (the knot choice allows 135): two steps turn beyond pi, where
    a Log wraps to the opposite turn; the quasi-interpolant adds the two steps' Logs instead and
    stays exact about a fixed axis (it was off by radians, and Gauss-Newton stalled from there:
    the flips scene with 1 cm / 1 deg AR(1) noise at 125 ms knots, 137 iterations unconverged,
    now 7)."""
    j = np.arange(_INIT_N)
    # steps from 60 to 133 degrees: two steps cross pi on one side of a control, not the other
    Rc = lie.so3_exp(np.outer(1.05 * j + 0.0276 * j**2, np.array([1.0, 2.0, 2.0]) / 3.0))
    assert _init_error(Rc, order) < 1e-12  # measured < 1e-14


def test_band_factored_solve_reuses_the_factor():
    rng = np.random.default_rng(5)
    n, w = 30, 6
    A = rng.normal(size=(n, n + w))
    dense = np.zeros((n, n))
    for i in range(n):
        for c in range(w):
            if i + c < n:
                dense[i, i + c] = dense[i + c, i] = A[i, c] * 0.3
    dense += np.eye(n) * 5.0
    band = np.zeros((n, w))
    for i in range(n):
        for c in range(w):
            if i + c < n:
                band[i, c] = dense[i, i + c]
    solver = banded.BandSolver(band)
    for lam in (0.0, 0.0, 1e-2, 1e-2, 0.0):
        b = rng.normal(size=n)
        x = solver.solve(b, lam)
        M = dense + lam * np.diag(np.maximum(np.diag(dense), 1e-12))
        np.testing.assert_allclose(M @ x, b, rtol=0, atol=1e-12)
    assert np.array_equal(solver.band, band)  # the matrix itself is kept


def test_quat_increments_match_rotation_signal():
    from splineimu.spline.signals import rotation_signal

    rng = np.random.default_rng(6)
    R = lie.so3_exp(np.cumsum(rng.normal(size=(200, 3)) * 0.2, axis=0))
    q = _wxyz(R)
    q[1::2] *= -1
    inc = np.empty((199, 3))
    _gn.quat_increments(q, inc)
    ref = np.diff(rotation_signal(R), axis=0)
    np.testing.assert_allclose(inc, ref, rtol=0, atol=1e-14)
