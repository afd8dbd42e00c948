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
    se3_q_block_into,
    so3_exp_into,
    so3_jacobian_into,
    so3_jacobian_inv_into,
    so3_log_into,
)
from .lie import so3_hat_into as _hat_into
from .spline import _segment


@jit
def _cum_basis(Mc, u, b):
    k = Mc.shape[0]
    for j in range(k):
        acc = 0.0
        un = 1.0
        for n in range(k):
            acc += Mc[j, n] * un
            un *= u
        b[j] = acc


@jit
def _basis(M, u, b):
    _cum_basis(M, u, b)


@jit
def _mm(A, B, C):
    """C = A @ B for square matrices of equal size."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            s = 0.0
            for m in range(n):
                s += A[i, m] * B[m, j]
            C[i, j] = s


@jit
def _mtm(A, B, C):
    """C = A^T @ B."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            s = 0.0
            for m in range(n):
                s += A[m, i] * B[m, j]
            C[i, j] = s


@jit
def position_normal_equations(s_all, w_all, P_meas, Mc_plain, nseg, H, rhs):
    """Split spline position: H (n, k) banded scalar blocks, rhs (n, 3); plain basis."""
    k = Mc_plain.shape[0]
    b = np.empty(k)
    for m in range(s_all.shape[0]):
        seg, u = _segment(s_all[m], nseg)
        _basis(Mc_plain, u, b)
        w = w_all[m]
        for a in range(k):
            wa = w * b[a]
            for c in range(k - a):
                H[seg + a, c] += wa * b[a + c]
            for d in range(3):
                rhs[seg + a, d] += wa * P_meas[m, d]


@jit
def position_residuals(s_all, P_meas, Pc, M_plain, nseg, out):
    k = M_plain.shape[0]
    b = np.empty(k)
    for m in range(s_all.shape[0]):
        seg, u = _segment(s_all[m], nseg)
        _basis(M_plain, u, b)
        for d in range(3):
            acc = 0.0
            for j in range(k):
                acc += b[j] * Pc[seg + j, d]
            out[m, d] = P_meas[m, d] - acc


@jit
def so3_normal_equations(s_all, w_all, R_meas, Rc, D, Mc, nseg, H, g, res):
    """Gauss-Newton blocks for rotation residuals. H (n, k, 3, 3), g (n, 3), res (M, 3) out.

    Returns the weighted cost sum w |r|^2.
    """
    k = Mc.shape[0]
    b = np.empty(k)
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
    for m in range(s_all.shape[0]):
        seg, u = _segment(s_all[m], nseg)
        _cum_basis(Mc, u, b)
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
        _mtm(R, R_meas[m], T)
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
            _mtm(P[j], Jr_b, X)
            for r0 in range(3):
                for c0 in range(3):
                    X[r0, c0] *= b[j]
            # + X Jr^-1(d_j) on delta_{s+j}
            so3_jacobian_inv_into(dj0, dj1, dj2, -1.0, Jinv)
            _mm(X, Jinv, E)
            for r0 in range(3):
                for c0 in range(3):
                    G[j, r0, c0] += E[r0, c0]
            # - X Jl^-1(d_j) on delta_{s+j-1}
            so3_jacobian_inv_into(dj0, dj1, dj2, 1.0, Jinv)
            _mm(X, Jinv, E)
            for r0 in range(3):
                for c0 in range(3):
                    G[j - 1, r0, c0] -= E[r0, c0]
        # Jm_i = -Jl^-1(r) G_i
        for i in range(k):
            _mm(Jl_inv_r, G[i], E)
            for r0 in range(3):
                for c0 in range(3):
                    Jm[i, r0, c0] = -E[r0, c0]
        for a in range(k):
            for c in range(k - a):
                for r0 in range(3):
                    for c0 in range(3):
                        s = 0.0
                        for z in range(3):
                            s += Jm[a, z, r0] * Jm[a + c, z, c0]
                        H[seg + a, c, r0, c0] += w * s
            for r0 in range(3):
                s = 0.0
                for z in range(3):
                    s += Jm[a, z, r0] * r[z]
                g[seg + a, r0] += w * s
    return cost


# --------------------------------------------------------------------------------- SE3
@jit
def _se3_exp_into(xi, R, t, Jscratch):
    so3_exp_into(xi[3], xi[4], xi[5], R)
    so3_jacobian_into(xi[3], xi[4], xi[5], 1.0, Jscratch)
    for r0 in range(3):
        t[r0] = Jscratch[r0, 0] * xi[0] + Jscratch[r0, 1] * xi[1] + Jscratch[r0, 2] * xi[2]


@jit
def _se3_jac_into(xi, sign, inverse, J, scratch, Q, S3):
    """6x6 SE3 Jacobian (sign=-1 right, +1 left), or its inverse."""
    for r0 in range(3):
        for c0 in range(3):
            J[3 + r0, c0] = 0.0
    if inverse:
        so3_jacobian_inv_into(xi[3], xi[4], xi[5], sign, S3)
    else:
        so3_jacobian_into(xi[3], xi[4], xi[5], sign, S3)
    for r0 in range(3):
        for c0 in range(3):
            J[r0, c0] = S3[r0, c0]
            J[3 + r0, 3 + c0] = S3[r0, c0]
    se3_q_block_into(xi[:3], xi[3:], sign, Q, scratch)
    if inverse:
        for r0 in range(3):
            for c0 in range(3):
                s = 0.0
                for m in range(3):
                    for n in range(3):
                        s += S3[r0, m] * Q[m, n] * S3[n, c0]
                J[r0, 3 + c0] = -s
    else:
        for r0 in range(3):
            for c0 in range(3):
                J[r0, 3 + c0] = Q[r0, c0]


@jit
def _adj_inv_into(R, t, Ad, K):
    """Ad_{T^-1} for T = (R, t): [[R^T, -R^T [t]x], [0, R^T]]."""
    _hat_into(t[0], t[1], t[2], K)
    for r0 in range(3):
        for c0 in range(3):
            Ad[r0, c0] = R[c0, r0]
            Ad[3 + r0, 3 + c0] = R[c0, r0]
            Ad[3 + r0, c0] = 0.0
            s = 0.0
            for m in range(3):
                s += R[m, r0] * K[m, c0]
            Ad[r0, 3 + c0] = -s


@jit
def se3_normal_equations(s_all, w6, R_meas, p_meas, Rc, pc, D, Mc, nseg, H, g, res):
    """Gauss-Newton blocks for SE3 residuals ``Log(T(t)^-1 T_meas)`` = [rho, phi].

    w6 (M, 6) diagonal weights. H (n, k, 6, 6), g (n, 6), res (M, 6). Returns the cost.
    """
    k = Mc.shape[0]
    b = np.empty(k)
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
    scratch = np.empty((4, 3, 3))
    Q = np.empty((3, 3))
    S3 = np.empty((3, 3))
    K = np.empty((3, 3))
    Jl_inv_r = np.empty((6, 6))
    Jr_b = np.empty((6, 6))
    Jinv = np.empty((6, 6))
    Ad = np.empty((6, 6))
    X = np.empty((6, 6))
    E = np.empty((6, 6))
    G = np.empty((k, 6, 6))
    Jm = np.empty((k, 6, 6))
    cost = 0.0
    for m in range(s_all.shape[0]):
        seg, u = _segment(s_all[m], nseg)
        _cum_basis(Mc, u, b)
        for j in range(1, k):
            for z in range(6):
                xi[z] = b[j] * D[seg + j, z]
            _se3_exp_into(xi, AR[j], At[j], J3)
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
        _mtm(R, R_meas[m], TR)
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
        _se3_jac_into(r, 1.0, True, Jl_inv_r, scratch, Q, S3)
        # G_0 = Ad_{P_0^-1}
        _adj_inv_into(PR[0], Pt[0], G[0], K)
        for i in range(1, k):
            for r0 in range(6):
                for c0 in range(6):
                    G[i, r0, c0] = 0.0
        for j in range(1, k):
            for z in range(6):
                xi[z] = b[j] * D[seg + j, z]
            _se3_jac_into(xi, -1.0, False, Jr_b, scratch, Q, S3)
            _adj_inv_into(PR[j], Pt[j], Ad, K)
            _mm(Ad, Jr_b, X)
            for r0 in range(6):
                for c0 in range(6):
                    X[r0, c0] *= b[j]
            _se3_jac_into(D[seg + j], -1.0, True, Jinv, scratch, Q, S3)
            _mm(X, Jinv, E)
            for r0 in range(6):
                for c0 in range(6):
                    G[j, r0, c0] += E[r0, c0]
            _se3_jac_into(D[seg + j], 1.0, True, Jinv, scratch, Q, S3)
            _mm(X, Jinv, E)
            for r0 in range(6):
                for c0 in range(6):
                    G[j - 1, r0, c0] -= E[r0, c0]
        for i in range(k):
            _mm(Jl_inv_r, G[i], E)
            for r0 in range(6):
                for c0 in range(6):
                    Jm[i, r0, c0] = -E[r0, c0]
        for a in range(k):
            for c in range(k - a):
                for r0 in range(6):
                    for c0 in range(6):
                        s = 0.0
                        for z in range(6):
                            s += Jm[a, z, r0] * w6[m, z] * Jm[a + c, z, c0]
                        H[seg + a, c, r0, c0] += s
            for r0 in range(6):
                s = 0.0
                for z in range(6):
                    s += Jm[a, z, r0] * w6[m, z] * r[z]
                g[seg + a, r0] += s
    return cost


@jit
def blocks_to_lapack_upper(H, ab):
    """Block-banded (n, k, d, d) upper blocks -> LAPACK upper banded storage (u + 1, n d),
    ``ab[u + i - j, j] = A[i, j]`` for ``i <= j``, with ``u = k d - 1``."""
    n = H.shape[0]
    k = H.shape[1]
    d = H.shape[2]
    u = k * d - 1
    for bi in range(n):
        for c in range(k):
            bj = bi + c
            if bj >= n:
                break
            for r0 in range(d):
                i = bi * d + r0
                for c0 in range(d):
                    j = bj * d + c0
                    if c == 0 and c0 < r0:
                        continue
                    ab[u + i - j, j] = H[bi, c, r0, c0]
