"""Evaluation kernels of cumulative uniform B-splines (split R3 x SO3 and SE3).

Derivatives follow the O(k) recursion of Sommer et al. (CVPR 2020): with
``A_j = Exp(Btilde_j(u) d_j)`` and ``T(t) = T_i A_1 ... A_{k-1}``,

    w_{j+1}    = A_j^-1 . w_j + Btilde_j' d_j
    wdot_{j+1} = A_j^-1 . wdot_j + Btilde_j'' d_j + ad(A_j^-1 . w_j) (Btilde_j' d_j)

where ``.`` is the adjoint action (``R^T w`` on SO3), primes are time derivatives and
``ad(a) b = a x b`` on SO3, ``[phi_a x rho_b + rho_a x phi_b, phi_a x phi_b]`` on SE3.

Inputs are prepared by :mod:`splineimu.spline.core`: ``s`` = (t - t_min) / dt per sample,
control rotations ``Rc`` (n, 3, 3), per-knot increments ``D`` (n, 3) or (n, 6) with
``D[m] = Log(T_{m-1}^-1 T_m)`` (``D[0]`` unused), cumulative blending matrix ``Mc``.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import jit
from .lie import mat_to_quat_wxyz_into, so3_exp_into, so3_jacobian_into

WANT_ROT = 1
WANT_POS = 2
WANT_OMEGA = 4
WANT_ALPHA = 8
WANT_VEL = 16
WANT_ACC = 32
WANT_FORCE = 64
WANT_QUAT = 128


@jit
def _segment(s, nseg):
    seg = int(math.floor(s))
    if seg < 0:
        seg = 0
    elif seg > nseg - 1:
        seg = nseg - 1
    return seg, s - seg


@jit
def _segment_of(seg, u, nseg):
    """:func:`_segment` of a parameter given as its segment and the fraction within it (from
    :func:`splineimu.spline.banded.segments`): clamped to [0, nseg - 1], u continued past."""
    if seg < 0:
        return 0, u + seg
    if seg > nseg - 1:
        return nseg - 1, u + (seg - (nseg - 1))
    return seg, u


@jit
def basis_into(M, u, inv_dt, b, bd, bdd):
    """The one basis evaluation of every kernel: ``b = M [1, u, .., u^(k-1)]`` and its first and
    second time derivatives (``d/du`` scaled by ``inv_dt`` per order) into ``b, bd, bdd`` (k,).

    ``M`` is the plain or the cumulative blending matrix of :mod:`splineimu.spline.basis`.
    The power sums run in a fixed order (``n = 0 .. k-1``), so all kernels round alike.
    """
    k = M.shape[0]
    for j in range(k):
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        un = 1.0  # u^n
        un1 = 0.0  # n u^(n-1)
        un2 = 0.0  # n (n-1) u^(n-2)
        um1 = 0.0  # u^(n-1)
        um2 = 0.0  # u^(n-2)
        for n in range(k):
            if n >= 1:
                um2 = um1
                um1 = un
                un = un * u
                un1 = n * um1
                un2 = n * (n - 1) * um2 if n >= 2 else 0.0
            s0 += M[j, n] * un
            s1 += M[j, n] * un1
            s2 += M[j, n] * un2
        b[j] = s0
        bd[j] = s1 * inv_dt
        bdd[j] = s2 * inv_dt * inv_dt


@jit
def basis_table(M, u_all, inv_dt, out):
    """Basis rows at every ``u_all`` (N,): ``out`` (3, N, k) = values, first, second time derivative."""
    for i in range(u_all.shape[0]):
        basis_into(M, u_all[i], inv_dt, out[0, i], out[1, i], out[2, i])


@jit(inline="always")
def _transpose_times(A, x0, x1, x2):
    """``A^T x`` for a 3x3 matrix and a vector given by its components."""
    return (A[0, 0] * x0 + A[1, 0] * x1 + A[2, 0] * x2,
            A[0, 1] * x0 + A[1, 1] * x1 + A[2, 1] * x2,
            A[0, 2] * x0 + A[1, 2] * x1 + A[2, 2] * x2)


@jit(inline="always")
def _times(A, x0, x1, x2):
    """``A x`` for a 3x3 matrix and a vector given by its components."""
    return (A[0, 0] * x0 + A[0, 1] * x1 + A[0, 2] * x2,
            A[1, 0] * x0 + A[1, 1] * x1 + A[1, 2] * x2,
            A[2, 0] * x0 + A[2, 1] * x1 + A[2, 2] * x2)


@jit(inline="always")
def _times_right(R, A, T):
    """``R <- R A`` for 3x3 matrices (``T`` scratch)."""
    for r in range(3):
        x0 = R[r, 0]
        x1 = R[r, 1]
        x2 = R[r, 2]
        T[r, 0] = x0 * A[0, 0] + x1 * A[1, 0] + x2 * A[2, 0]
        T[r, 1] = x0 * A[0, 1] + x1 * A[1, 1] + x2 * A[2, 1]
        T[r, 2] = x0 * A[0, 2] + x1 * A[1, 2] + x2 * A[2, 2]
    for r in range(3):
        R[r, 0] = T[r, 0]
        R[r, 1] = T[r, 1]
        R[r, 2] = T[r, 2]


@jit(inline="always")
def _write_vector(i, x0, x1, x2, out):
    out[i, 0] = x0
    out[i, 1] = x1
    out[i, 2] = x2


@jit(inline="always")
def _write_outputs(i, want, R, q, p0, p1, p2, w0, w1, w2, a0, a1, a2, out_R, out_q, out_p, out_w, out_wd):
    """Rotation, quaternion (x, y, z, w), position, body rate and its derivative of sample ``i``."""
    if want & WANT_ROT:
        for r in range(3):
            for c in range(3):
                out_R[i, r, c] = R[r, c]
    if want & WANT_QUAT:
        mat_to_quat_wxyz_into(R, q)
        out_q[i, 0] = q[1]
        out_q[i, 1] = q[2]
        out_q[i, 2] = q[3]
        out_q[i, 3] = q[0]
    if want & WANT_POS:
        _write_vector(i, p0, p1, p2, out_p)
    if want & WANT_OMEGA:
        _write_vector(i, w0, w1, w2, out_w)
    if want & WANT_ALPHA:
        _write_vector(i, a0, a1, a2, out_wd)


@jit
def eval_split(s_all, nseg, dt, Rc, D, Mc, sp_all, nseg_p, dt_p, Pc, M, g, want,
               out_R, out_q, out_p, out_w, out_wd, out_v, out_a, out_f):
    """Split spline: cumulative SO3 rotation on its grid (``s_all``, ``nseg``, ``dt``, ``Mc``),
    ordinary R3 position on its own (``sp_all``, ``nseg_p``, ``dt_p``, ``M``). Writes the wanted
    outputs."""
    k = Mc.shape[0]
    kp = M.shape[0]
    inv_dt = 1.0 / dt
    inv_dtp = 1.0 / dt_p
    b = np.empty(k)
    bd = np.empty(k)
    bdd = np.empty(k)
    pb = np.empty(kp)
    pbd = np.empty(kp)
    pbdd = np.empty(kp)
    R = np.empty((3, 3))
    A = np.empty((3, 3))
    T = np.empty((3, 3))
    q = np.empty(4)
    # the rotation matrix is built only when it is an output; the specific force alone is
    # carried through the product as a vector (R^T f = A_{k-1}^T .. A_1^T R_i^T f)
    need_rot = (want & (WANT_ROT | WANT_QUAT)) != 0
    need_fvec = (want & WANT_FORCE) != 0 and not need_rot
    need_w = (want & (WANT_OMEGA | WANT_ALPHA)) != 0
    need_wd = (want & WANT_ALPHA) != 0
    for i in range(s_all.shape[0]):
        seg, u = _segment(s_all[i], nseg)
        basis_into(Mc, u, inv_dt, b, bd, bdd)
        segp, up = _segment(sp_all[i], nseg_p)
        basis_into(M, up, inv_dtp, pb, pbd, pbdd)
        # position and its derivatives
        p0 = 0.0
        p1 = 0.0
        p2 = 0.0
        v0 = 0.0
        v1 = 0.0
        v2 = 0.0
        c0 = 0.0
        c1 = 0.0
        c2 = 0.0
        for j in range(kp):
            x0 = Pc[segp + j, 0]
            x1 = Pc[segp + j, 1]
            x2 = Pc[segp + j, 2]
            p0 += pb[j] * x0
            p1 += pb[j] * x1
            p2 += pb[j] * x2
            v0 += pbd[j] * x0
            v1 += pbd[j] * x1
            v2 += pbd[j] * x2
            c0 += pbdd[j] * x0
            c1 += pbdd[j] * x1
            c2 += pbdd[j] * x2
        if need_rot:
            for r in range(3):
                for c in range(3):
                    R[r, c] = Rc[seg, r, c]
        h0 = c0 - g[0]
        h1 = c1 - g[1]
        h2 = c2 - g[2]
        if need_fvec:
            f0 = Rc[seg, 0, 0] * h0 + Rc[seg, 1, 0] * h1 + Rc[seg, 2, 0] * h2
            f1 = Rc[seg, 0, 1] * h0 + Rc[seg, 1, 1] * h1 + Rc[seg, 2, 1] * h2
            f2 = Rc[seg, 0, 2] * h0 + Rc[seg, 1, 2] * h1 + Rc[seg, 2, 2] * h2
        else:
            f0 = f1 = f2 = 0.0
        w0 = 0.0
        w1 = 0.0
        w2 = 0.0
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        for j in range(1, k):
            d0 = D[seg + j, 0]
            d1 = D[seg + j, 1]
            d2 = D[seg + j, 2]
            if not (need_rot or need_w or need_fvec):
                continue
            so3_exp_into(b[j] * d0, b[j] * d1, b[j] * d2, A)
            if need_fvec:
                f0, f1, f2 = _transpose_times(A, f0, f1, f2)
            if need_rot:
                _times_right(R, A, T)
            if need_w:
                # A^T w
                r0, r1, r2 = _transpose_times(A, w0, w1, w2)
                e0 = bd[j] * d0
                e1 = bd[j] * d1
                e2 = bd[j] * d2
                if need_wd:
                    y0, y1, y2 = _transpose_times(A, a0, a1, a2)
                    a0 = y0 + bdd[j] * d0 + (r1 * e2 - r2 * e1)
                    a1 = y1 + bdd[j] * d1 + (r2 * e0 - r0 * e2)
                    a2 = y2 + bdd[j] * d2 + (r0 * e1 - r1 * e0)
                w0 = r0 + e0
                w1 = r1 + e1
                w2 = r2 + e2
        _write_outputs(i, want, R, q, p0, p1, p2, w0, w1, w2, a0, a1, a2, out_R, out_q, out_p, out_w, out_wd)
        if want & WANT_VEL:
            _write_vector(i, v0, v1, v2, out_v)
        if want & WANT_ACC:
            _write_vector(i, c0, c1, c2, out_a)
        if want & WANT_FORCE:
            if need_rot:
                f0, f1, f2 = _transpose_times(R, h0, h1, h2)
            _write_vector(i, f0, f1, f2, out_f)


@jit
def eval_se3(s_all, nseg, dt, Rc, D, Pc, Mc, M, g, want,
             out_R, out_q, out_p, out_w, out_wd, out_v, out_a, out_f):
    """SE3 spline (Lovegrove et al.): cumulative products of SE3 exponentials.

    ``D[m] = [rho, phi]`` increments; the body twist ``xi = (v_b, w_b)``.
    """
    k = Mc.shape[0]
    inv_dt = 1.0 / dt
    b = np.empty(k)
    bd = np.empty(k)
    bdd = np.empty(k)
    R = np.empty((3, 3))
    A = np.empty((3, 3))
    J = np.empty((3, 3))
    T = np.empty((3, 3))
    q = np.empty(4)
    need_alpha = (want & (WANT_ALPHA | WANT_ACC | WANT_FORCE)) != 0
    for i in range(s_all.shape[0]):
        seg, u = _segment(s_all[i], nseg)
        basis_into(Mc, u, inv_dt, b, bd, bdd)
        for r in range(3):
            for c in range(3):
                R[r, c] = Rc[seg, r, c]
        p0 = Pc[seg, 0]
        p1 = Pc[seg, 1]
        p2 = Pc[seg, 2]
        # twist (v: translational, w: rotational) and its derivative
        v0 = v1 = v2 = 0.0
        w0 = w1 = w2 = 0.0
        dv0 = dv1 = dv2 = 0.0
        dw0 = dw1 = dw2 = 0.0
        for j in range(1, k):
            bj = b[j]
            rho0 = bj * D[seg + j, 0]
            rho1 = bj * D[seg + j, 1]
            rho2 = bj * D[seg + j, 2]
            ph0 = bj * D[seg + j, 3]
            ph1 = bj * D[seg + j, 4]
            ph2 = bj * D[seg + j, 5]
            so3_exp_into(ph0, ph1, ph2, A)
            so3_jacobian_into(ph0, ph1, ph2, 1.0, J)
            t0 = J[0, 0] * rho0 + J[0, 1] * rho1 + J[0, 2] * rho2
            t1 = J[1, 0] * rho0 + J[1, 1] * rho1 + J[1, 2] * rho2
            t2 = J[2, 0] * rho0 + J[2, 1] * rho1 + J[2, 2] * rho2
            # pose: p += R t ; R = R A
            p0 += R[0, 0] * t0 + R[0, 1] * t1 + R[0, 2] * t2
            p1 += R[1, 0] * t0 + R[1, 1] * t1 + R[1, 2] * t2
            p2 += R[2, 0] * t0 + R[2, 1] * t1 + R[2, 2] * t2
            _times_right(R, A, T)
            # Ad_{A^-1} xi = [A^T (v - t x w), A^T w]
            x0 = v0 - (t1 * w2 - t2 * w1)
            x1 = v1 - (t2 * w0 - t0 * w2)
            x2 = v2 - (t0 * w1 - t1 * w0)
            zv0, zv1, zv2 = _transpose_times(A, x0, x1, x2)
            zw0, zw1, zw2 = _transpose_times(A, w0, w1, w2)
            bdj = bd[j]
            er0 = bdj * D[seg + j, 0]
            er1 = bdj * D[seg + j, 1]
            er2 = bdj * D[seg + j, 2]
            ew0 = bdj * D[seg + j, 3]
            ew1 = bdj * D[seg + j, 4]
            ew2 = bdj * D[seg + j, 5]
            if need_alpha:
                x0 = dv0 - (t1 * dw2 - t2 * dw1)
                x1 = dv1 - (t2 * dw0 - t0 * dw2)
                x2 = dv2 - (t0 * dw1 - t1 * dw0)
                yv0, yv1, yv2 = _transpose_times(A, x0, x1, x2)
                yw0, yw1, yw2 = _transpose_times(A, dw0, dw1, dw2)
                bddj = bdd[j]
                # ad(z) e = [zw x er + zv x ew, zw x ew]
                dv0 = yv0 + bddj * D[seg + j, 0] + (zw1 * er2 - zw2 * er1) + (zv1 * ew2 - zv2 * ew1)
                dv1 = yv1 + bddj * D[seg + j, 1] + (zw2 * er0 - zw0 * er2) + (zv2 * ew0 - zv0 * ew2)
                dv2 = yv2 + bddj * D[seg + j, 2] + (zw0 * er1 - zw1 * er0) + (zv0 * ew1 - zv1 * ew0)
                dw0 = yw0 + bddj * D[seg + j, 3] + (zw1 * ew2 - zw2 * ew1)
                dw1 = yw1 + bddj * D[seg + j, 4] + (zw2 * ew0 - zw0 * ew2)
                dw2 = yw2 + bddj * D[seg + j, 5] + (zw0 * ew1 - zw1 * ew0)
            v0 = zv0 + er0
            v1 = zv1 + er1
            v2 = zv2 + er2
            w0 = zw0 + ew0
            w1 = zw1 + ew1
            w2 = zw2 + ew2
        # world velocity R v_b; world acceleration R (w x v + dv)
        _write_outputs(i, want, R, q, p0, p1, p2, w0, w1, w2, dw0, dw1, dw2, out_R, out_q, out_p, out_w, out_wd)
        if want & WANT_VEL:
            x0, x1, x2 = _times(R, v0, v1, v2)
            _write_vector(i, x0, x1, x2, out_v)
        if want & (WANT_ACC | WANT_FORCE):
            ab0 = (w1 * v2 - w2 * v1) + dv0
            ab1 = (w2 * v0 - w0 * v2) + dv1
            ab2 = (w0 * v1 - w1 * v0) + dv2
            if want & WANT_ACC:
                x0, x1, x2 = _times(R, ab0, ab1, ab2)
                _write_vector(i, x0, x1, x2, out_a)
            if want & WANT_FORCE:
                # f_b = R^T (a_w - g) = a_b - R^T g
                y0, y1, y2 = _transpose_times(R, g[0], g[1], g[2])
                _write_vector(i, ab0 - y0, ab1 - y1, ab2 - y2, out_f)
