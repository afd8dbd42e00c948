"""Normal-equation assembly for least-squares spline fits (block-banded, one pass over poses).

Notation: control points ``i = s .. s+k-1`` support segment ``s``; the normal matrix is kept
as blocks ``H[i, c]`` = block (i, i + c), ``c = 0 .. k-1`` (upper band), shape (n, k, d, d).

Rotation residual (right perturbation ``R_i <- R_i Exp(delta_i)``):
``r = Log(R(t)^T R_meas)``, ``R(t) = R_s A_1 .. A_{k-1}``, ``A_j = Exp(b_j d_j)``,
``d_j = Log(R_{s+j-1}^T R_{s+j})``. To first order
``d_j <- d_j + Jr^-1(d_j) delta_{s+j} - Jl^-1(d_j) delta_{s+j-1}``,
``A_j <- A_j Exp(b_j Jr(b_j d_j) eps_j)``, and a perturbation moved to the right end of the
product picks up the inverse adjoint of what it passes, so ``R(t) <- R(t) Exp(Delta)`` with
``Delta = P_0^T delta_s + sum_j P_j^T b_j Jr(b_j d_j) eps_j``, ``P_j = A_{j+1} .. A_{k-1}``,
and ``r <- r - Jl^-1(r) Delta``. The SE3 kernel is the same with SE3 exponentials, 6x6
Jacobians and adjoints.
"""

from __future__ import annotations

import numpy as np

from .._jit import jit
from .lie import (
    se3_adjoint_into,
    se3_exp_into,
    se3_jacobian_into,
    se3_jacobian_inv_into,
    so3_exp_into,
    so3_jacobian_into,
    so3_jacobian_inv_into,
    so3_log_into,
)
from .spline import _segment_of, basis_into


@jit
def _accumulate(Jm, r, z0, z1, w, seg, H, g):
    """Add ``w J^T J`` and ``w J^T r`` over residual rows ``z0 .. z1-1`` to the banded blocks
    (``Jm`` (k, d, d): the residual's Jacobian blocks on control points ``seg .. seg+k-1``)."""
    k = Jm.shape[0]
    d = Jm.shape[2]
    for a in range(k):
        for c in range(k - a):
            for r0 in range(d):
                for c0 in range(d):
                    s = 0.0
                    for z in range(z0, z1):
                        s += Jm[a, z, r0] * Jm[a + c, z, c0]
                    H[seg + a, c, r0, c0] += w * s
        for r0 in range(d):
            s = 0.0
            for z in range(z0, z1):
                s += Jm[a, z, r0] * r[z]
            g[seg + a, r0] += w * s


@jit
def _mm(A, B, C, transpose_a=False):
    """C = A @ B (or A^T @ B) for square matrices of equal size."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            s = 0.0
            for m in range(n):
                s += (A[m, i] if transpose_a else A[i, m]) * B[m, j]
            C[i, j] = s


@jit
def _add_product(X, B, E, out, sign):
    """``out += sign * X @ B`` for square matrices (``E`` scratch)."""
    _mm(X, B, E)
    d = E.shape[0]
    for r0 in range(d):
        for c0 in range(d):
            out[r0, c0] += sign * E[r0, c0]


@jit
def position_residuals(seg_all, u_all, P_meas, Pc, M_plain, nseg, out):
    k = M_plain.shape[0]
    b = np.empty(k)
    bd = np.empty(k)
    for m in range(seg_all.shape[0]):
        seg, u = _segment_of(seg_all[m], u_all[m], nseg)
        basis_into(M_plain, u, 1.0, b, bd, bd)
        for d in range(3):
            acc = 0.0
            for j in range(k):
                acc += b[j] * Pc[seg + j, d]
            out[m, d] = P_meas[m, d] - acc


@jit
def so3_normal_equations(seg_all, u_all, w_all, R_meas, Rc, D, Mc, nseg, H, g, res):
    """Gauss-Newton blocks for rotation residuals. H (n, k, 3, 3), g (n, 3), res (M, 3) out.

    Returns the weighted cost sum w |r|^2. The reference implementation (matrices, the exact
    ``Jl^-1(r)`` in H); the fit runs :func:`splineimu._kernels.gauss_newton.so3_pass`, which the
    tests check against this.
    """
    k = Mc.shape[0]
    b = np.empty(k)
    bd = np.empty(k)
    A = np.empty((k, 3, 3))
    P = np.empty((k, 3, 3))  # suffix products P_j = A_{j+1} .. A_{k-1}
    R = np.empty((3, 3))
    T = np.empty((3, 3))
    E = np.empty((3, 3))
    q = np.empty(4)
    r = np.empty(3)
    Jl_inv_r = np.empty((3, 3))
    Jr_b = np.empty((3, 3))
    Jinv = np.empty((3, 3))
    G = np.empty((k, 3, 3))  # dDelta / d delta_{s+i}
    Jm = np.empty((k, 3, 3))
    X = np.empty((3, 3))
    cost = 0.0
    for m in range(seg_all.shape[0]):
        seg, u = _segment_of(seg_all[m], u_all[m], nseg)
        basis_into(Mc, u, 1.0, b, bd, bd)
        for j in range(1, k):
            so3_exp_into(b[j] * D[seg + j, 0], b[j] * D[seg + j, 1], b[j] * D[seg + j, 2], A[j])
        # suffix products
        for r0 in range(3):
            for c0 in range(3):
                P[k - 1, r0, c0] = 1.0 if r0 == c0 else 0.0
        for j in range(k - 2, -1, -1):
            _mm(A[j + 1], P[j + 1], P[j])
        # R(t) = R_s P_0
        _mm(Rc[seg], P[0], R)
        # residual r = Log(R^T R_meas)
        _mm(R, R_meas[m], T, True)
        so3_log_into(T, q, r)
        for d in range(3):
            res[m, d] = r[d]
        w = w_all[m]
        cost += w * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
        so3_jacobian_inv_into(r[0], r[1], r[2], 1.0, Jl_inv_r)
        # G_0 = P_0^T ; the rest from the increments
        for i in range(k):
            for r0 in range(3):
                for c0 in range(3):
                    G[i, r0, c0] = P[0, c0, r0] if i == 0 else 0.0
        for j in range(1, k):
            dj0 = D[seg + j, 0]
            dj1 = D[seg + j, 1]
            dj2 = D[seg + j, 2]
            so3_jacobian_into(b[j] * dj0, b[j] * dj1, b[j] * dj2, -1.0, Jr_b)
            # X = P_j^T b_j Jr(b_j d_j)
            _mm(P[j], Jr_b, X, True)
            for r0 in range(3):
                for c0 in range(3):
                    X[r0, c0] *= b[j]
            # + X Jr^-1(d_j) on delta_{s+j}
            so3_jacobian_inv_into(dj0, dj1, dj2, -1.0, Jinv)
            _add_product(X, Jinv, E, G[j], 1.0)
            # - X Jl^-1(d_j) on delta_{s+j-1}
            so3_jacobian_inv_into(dj0, dj1, dj2, 1.0, Jinv)
            _add_product(X, Jinv, E, G[j - 1], -1.0)
        # Jm_i = -Jl^-1(r) G_i
        Jm[:] = 0.0
        for i in range(k):
            _add_product(Jl_inv_r, G[i], E, Jm[i], -1.0)
        _accumulate(Jm, r, 0, 3, w, seg, H, g)
    return cost


# --------------------------------------------------------------------------------- SE3
@jit
def _adj_inv_into(R, t, Ad, RT, tt):
    """Ad_{T^-1} for T = (R, t): the adjoint of (R^T, -R^T t). RT (3, 3), tt (3,) scratch."""
    for r0 in range(3):
        tt[r0] = -(R[0, r0] * t[0] + R[1, r0] * t[1] + R[2, r0] * t[2])
        for c0 in range(3):
            RT[r0, c0] = R[c0, r0]
    se3_adjoint_into(RT, tt, Ad)


@jit
def se3_normal_equations(seg_all, u_all, w6, R_meas, p_meas, Rc, pc, D, Mc, nseg, H, g, res):
    """Gauss-Newton blocks for SE3 residuals ``Log(T(t)^-1 T_meas)`` = [rho, phi].

    w6 (M, 6) diagonal weights, equal within the translation rows and within the rotation rows.
    H (n, k, 6, 6), g (n, 6), res (M, 6). Returns the cost.
    """
    k = Mc.shape[0]
    b = np.empty(k)
    bd = np.empty(k)
    AR = np.empty((k, 3, 3))
    At = np.empty((k, 3))
    PR = np.empty((k, 3, 3))
    Pt = np.empty((k, 3))
    J3 = np.empty((3, 3))
    R = np.empty((3, 3))
    t = np.empty(3)
    TR = np.empty((3, 3))
    tt = np.empty(3)
    q = np.empty(4)
    r = np.empty(6)
    xi = np.empty(6)
    scratch = np.empty((5, 3, 3))
    RT = np.empty((3, 3))
    tt = np.empty(3)
    Jl_inv_r = np.empty((6, 6))
    Jr_b = np.empty((6, 6))
    Jinv = np.empty((6, 6))
    Ad = np.empty((6, 6))
    X = np.empty((6, 6))
    E = np.empty((6, 6))
    G = np.empty((k, 6, 6))
    Jm = np.empty((k, 6, 6))
    cost = 0.0
    for m in range(seg_all.shape[0]):
        seg, u = _segment_of(seg_all[m], u_all[m], nseg)
        basis_into(Mc, u, 1.0, b, bd, bd)
        for j in range(1, k):
            for z in range(6):
                xi[z] = b[j] * D[seg + j, z]
            se3_exp_into(xi, AR[j], At[j], J3)
        # suffix products P_j = A_{j+1} .. A_{k-1} (as R, t)
        for r0 in range(3):
            Pt[k - 1, r0] = 0.0
            for c0 in range(3):
                PR[k - 1, r0, c0] = 1.0 if r0 == c0 else 0.0
        for j in range(k - 2, -1, -1):
            _mm(AR[j + 1], PR[j + 1], PR[j])
            for r0 in range(3):
                Pt[j, r0] = At[j + 1, r0] + (AR[j + 1, r0, 0] * Pt[j + 1, 0] + AR[j + 1, r0, 1] * Pt[j + 1, 1]
                                             + AR[j + 1, r0, 2] * Pt[j + 1, 2])
        # T(t) = T_s P_0
        _mm(Rc[seg], PR[0], R)
        for r0 in range(3):
            t[r0] = pc[seg, r0] + Rc[seg, r0, 0] * Pt[0, 0] + Rc[seg, r0, 1] * Pt[0, 1] + Rc[seg, r0, 2] * Pt[0, 2]
        # residual: Log(T^-1 T_meas) = Log(R^T R_m, R^T (p_m - t))
        _mm(R, R_meas[m], TR, True)
        for r0 in range(3):
            tt[r0] = (R[0, r0] * (p_meas[m, 0] - t[0]) + R[1, r0] * (p_meas[m, 1] - t[1])
                      + R[2, r0] * (p_meas[m, 2] - t[2]))
        so3_log_into(TR, q, r[3:])
        so3_jacobian_inv_into(r[3], r[4], r[5], 1.0, J3)
        for r0 in range(3):
            r[r0] = J3[r0, 0] * tt[0] + J3[r0, 1] * tt[1] + J3[r0, 2] * tt[2]
        for z in range(6):
            res[m, z] = r[z]
            cost += w6[m, z] * r[z] * r[z]
        se3_jacobian_inv_into(r, 1.0, Jl_inv_r, scratch)
        # G_0 = Ad_{P_0^-1}
        _adj_inv_into(PR[0], Pt[0], G[0], RT, tt)
        for i in range(1, k):
            for r0 in range(6):
                for c0 in range(6):
                    G[i, r0, c0] = 0.0
        for j in range(1, k):
            for z in range(6):
                xi[z] = b[j] * D[seg + j, z]
            se3_jacobian_into(xi, -1.0, Jr_b, scratch)
            _adj_inv_into(PR[j], Pt[j], Ad, RT, tt)
            _mm(Ad, Jr_b, X)
            for r0 in range(6):
                for c0 in range(6):
                    X[r0, c0] *= b[j]
            se3_jacobian_inv_into(D[seg + j], -1.0, Jinv, scratch)
            _add_product(X, Jinv, E, G[j], 1.0)
            se3_jacobian_inv_into(D[seg + j], 1.0, Jinv, scratch)
            _add_product(X, Jinv, E, G[j - 1], -1.0)
        Jm[:] = 0.0
        for i in range(k):
            _add_product(Jl_inv_r, G[i], E, Jm[i], -1.0)
        # translation and rotation rows carry one weight each
        _accumulate(Jm, r, 0, 3, w6[m, 0], seg, H, g)
        _accumulate(Jm, r, 3, 6, w6[m, 3], seg, H, g)
    return cost


# ------------------------------------------------------------------- cross-validation
@jit
def fold_normal_equations(seg_all, u_all, w_all, fold, X, M, nseg, H, rhs):
    """Per-fold contributions of an ordinary B-spline fit of ``X`` (N, d).

    ``fold`` (N,) int in [0, F); H (F, n, k) banded scalar blocks and rhs (F, n, d) receive the
    poses of each fold; the training system of fold f is the sum over the others.
    """
    k = M.shape[0]
    d = X.shape[1]
    b = np.empty(k)
    bd = np.empty(k)
    for m in range(seg_all.shape[0]):
        seg, u = _segment_of(seg_all[m], u_all[m], nseg)
        basis_into(M, u, 1.0, b, bd, bd)
        f = fold[m]
        w = w_all[m]
        for a in range(k):
            wa = w * b[a]
            for c in range(k - a):
                H[f, seg + a, c] += wa * b[a + c]
            for z in range(d):
                rhs[f, seg + a, z] += wa * X[m, z]


# ------------------------------------------------------------------- banded solves
@jit
def blocks_to_band(H, out):
    """Block-banded (n, k, d, d) upper blocks -> scalar upper band ``out`` (n d, k d),
    ``out[i, c] = A[i, i + c]``."""
    n = H.shape[0]
    k = H.shape[1]
    d = H.shape[2]
    for bi in range(n):
        for c in range(k):
            if bi + c >= n:
                break
            for r0 in range(d):
                for c0 in range(d):
                    off = c * d + c0 - r0
                    if off >= 0:
                        out[bi * d + r0, off] = H[bi, c, r0, c0]


@jit
def band_factored_solve(U, B):
    """Solve ``U^T U X = B`` in place of ``B`` (n, m) with the upper band factor ``U`` (n, w) that
    :func:`band_cholesky_solve` leaves in its matrix argument."""
    n = U.shape[0]
    w = U.shape[1]
    m = B.shape[1]
    # U^T y = b
    for i in range(n):
        for z in range(m):
            s = B[i, z]
            for q in range(1, w):
                if i - q < 0:
                    break
                s -= U[i - q, q] * B[i - q, z]
            B[i, z] = s / U[i, 0]
    # U x = y
    for i in range(n - 1, -1, -1):
        for z in range(m):
            s = B[i, z]
            for c in range(1, w):
                if i + c >= n:
                    break
                s -= U[i, c] * B[i + c, z]
            B[i, z] = s / U[i, 0]


@jit
def band_cholesky_solve(A, B):
    """Solve ``A X = B`` in place of ``B`` (n, m) for the symmetric positive definite band
    matrix with upper diagonals ``A`` (n, w) (``A[i, c]`` = entry (i, i + c)); ``A`` is
    overwritten by its factor ``U`` (A = U^T U). Returns False if A is not positive definite."""
    n = A.shape[0]
    w = A.shape[1]
    for i in range(n):
        for c in range(w):
            if i + c >= n:
                break
            s = A[i, c]
            for q in range(1, w - c):
                if i - q < 0:
                    break
                s -= A[i - q, q] * A[i - q, q + c]
            if c == 0:
                if not s > 0.0:
                    return False
                A[i, 0] = np.sqrt(s)
            else:
                A[i, c] = s / A[i, 0]
    band_factored_solve(A, B)
    return True
