"""Gyro + specific force of an SE3 cumulative B-spline: vectorized across samples, and one sample.

The body twist ``xi = (v_b, w_b) = T^-1 dT/dt`` and its derivative follow the O(k) recursion of
Sommer et al. (CVPR 2020) that :func:`splineimu._kernels.spline.eval_se3` implements, with
``A_j = Exp(b_j Omega_j) = (Q, tau)``, ``Omega_j = (r, d)`` (``[rho, phi]``), ``b`` the cumulative
basis value and primes time derivatives:

    v <- Q^T (v - tau x w) + b' r              w <- Q^T w + b' d
    v' <- Q^T (v' - tau x w') + b'' r + Q^T w x b' r + Q^T (v - tau x w) x b' d
    w' <- Q^T w' + b'' d + Q^T w x b' d

(``Ad_{A^-1}`` of a twist is ``[Q^T (v - tau x w), Q^T w]``, and ``ad(a) e`` is
``[a_w x e_v + a_v x e_w, a_w x e_w]``.) The specific force is
``f = R^T (a_w - g) = w x v + v' - R^T g``: the kernel carries ``v' - R^T g`` through the
recursion (``R^T g = Q_{k-1}^T .. Q_1^T R_i^T g`` rotates as ``v'`` does), which saves the
rotation matrix and a fifth vector. ``Q = Exp(b d)`` is applied as a 3x3 matrix built from the
half-angle polynomials of :mod:`splineimu._kernels.spline_imu`, and
``tau = J_l(b d) b r = b r + beta (d x r) + gamma d x (d x r)`` with the left Jacobian's
``beta = b^2 (1 - cos t) / t^2`` and ``gamma = b^3 (t - sin t) / t^3`` at ``t = b |d|``, gamma from
the same polynomials' ``sin t / t`` (:func:`_exp_gamma`; a 14-term polynomial of its own cost
order-6 splines 20% more per sample). The first step starts from ``v = w = w' = 0``.

Both kernels call the same inline step functions, so they give the same numbers; they agree
with ``eval_se3`` (libm sin/cos, Jacobian matrices, ``R^T g`` at the end) to rounding.
No ``fastmath`` (see :mod:`splineimu._kernels.spline_imu`).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import jit
from .spline_imu import (
    BLOCK,
    H_DT,
    H_HI,
    H_K,
    H_LO,
    H_MC,
    H_NSEG,
    H_ROWS,
    H_T0,
    _exp_coefficients,
    _exp_terms,
    _segment_one,
    _segments,
)

#: Columns of the per-knot table of :func:`se3_imu_knots`: ``Omega_m = Log(T_{m-1}^-1 T_m)``
#: as ``r`` (translation part), ``d`` (rotation part) and ``|d|``; one 64-byte row per knot.
KNOT_R = 0
KNOT_D = 3
KNOT_ANGLE = 6
KNOT_COLS = 8
#: The one-sample table's knot rows: the above, then the control rotation (row-major).
ROW_R = KNOT_COLS
ROW_COLS = KNOT_COLS + 9

# The first Taylor coefficients of (t - sin t) / t^3 = sum_m (-1)^m t^(2m) / (2m + 3)! in
# x = (t / 2)^2, i.e. (-4)^m / (2m + 3)! (used for small t, :func:`_exp_gamma`).
GM0, GM1, GM2 = tuple((-4.0) ** m / math.factorial(2 * m + 3) for m in range(3))

# scratch rows of se3_imu: carried vectors, the knot row of the current step, basis, powers
(_V0, _V1, _V2, _W0, _W1, _W2, _A0, _A1, _A2, _E0, _E1, _E2,
 _R0, _R1, _R2, _D0, _D1, _D2, _ANG, _B, _BD, _BDD) = range(22)
_PW = 21  # u^n is row _PW + n (n = 1 .. k-1)
_U = _PW + 1
_UK = np.uint64(KNOT_COLS)  # unsigned indices: numba checks signed ones for wraparound
_U9 = np.uint64(9)


def se3_imu_knots(increments):
    """Per-knot table (n, :data:`KNOT_COLS`) for :func:`se3_imu` from the increments (n, 6)
    ``[rho, phi]`` held by the spline (row 0 unused)."""
    n = increments.shape[0]
    K = np.zeros((n, KNOT_COLS))
    K[:, KNOT_R:KNOT_R + 3] = increments[:, :3]
    K[:, KNOT_D:KNOT_D + 3] = increments[:, 3:]
    K[:, KNOT_ANGLE] = np.sqrt(np.einsum("ni,ni->n", increments[:, 3:], increments[:, 3:]))
    return K


def se3_one_sample_table(t0, dt, nseg, Mc, K, Rc, t_lo, t_hi):
    """The array of :func:`se3_imu_one`: the header of
    :func:`splineimu._kernels.spline_imu.split_one_sample_table` (no position grid), then one row
    of :data:`ROW_COLS` per knot (136 bytes)."""
    k = Mc.shape[0]
    rows = H_MC + k * k
    head = np.array([t0, dt, nseg, 0.0, 0.0, 0.0, k, 0, rows, 0, t_lo, t_hi], dtype=np.float64)
    table = np.concatenate([head, Mc.ravel(), np.hstack([K, Rc.reshape(-1, 9)]).ravel()])
    return np.ascontiguousarray(table, dtype=np.float64)


@jit(inline="always")
def _exp_gamma(b, n):
    """:func:`splineimu._kernels.spline_imu._exp_coefficients` at ``t = b n`` and ``gamma = b^3
    (t - sin t) / t^3`` from the same half-angle polynomials, as ``(1 - sin t / t) / t^2``. Its
    cancellation for small ``t`` costs gamma relative precision (1e-12 at ``t = 0.02``) but not
    ``tau``, where gamma multiplies ``|d|^2 = t^2 / b^2``: the absolute error there stays ``~1e-16
    b |r|``. Below ``(t / 2)^2 = 1e-4``, the series' first three terms (the next is 2e-16 of it)."""
    ct, al, be, sinc, x = _exp_terms(b, n)
    g = (GM0 + GM1 * x) + GM2 * (x * x) if x < 1e-4 else (1.0 - sinc) / (4.0 * x)
    return ct, al, be, g * (b * (b * b))


@jit(inline="always")
def _transpose_of_exp(d0, d1, d2, ct, al, be):
    """``Q^T = Exp(b d)^T = ct I - al [d]x + be d d^T`` (row-major, 9 values)."""
    s01 = be * (d0 * d1)
    s02 = be * (d0 * d2)
    s12 = be * (d1 * d2)
    a0 = al * d0
    a1 = al * d1
    a2 = al * d2
    return (ct + be * (d0 * d0), s01 + a2, s02 - a1,
            s01 - a2, ct + be * (d1 * d1), s12 + a0,
            s02 + a1, s12 - a0, ct + be * (d2 * d2))


@jit(inline="always")
def _first_step(b, bd, bdd, r0, r1, r2, d0, d1, d2, n, e0, e1, e2):
    """Step j = 1 from ``v = w = w' = 0``: ``(v, w, v' - R^T g, w')`` with ``e = v' - R^T g``
    before the step (``-R_i^T g``)."""
    ct, al, be = _exp_coefficients(b, n)
    q00, q01, q02, q10, q11, q12, q20, q21, q22 = _transpose_of_exp(d0, d1, d2, ct, al, be)
    return (bd * r0, bd * r1, bd * r2, bd * d0, bd * d1, bd * d2,
            (q00 * e0 + q01 * e1 + q02 * e2) + bdd * r0,
            (q10 * e0 + q11 * e1 + q12 * e2) + bdd * r1,
            (q20 * e0 + q21 * e1 + q22 * e2) + bdd * r2,
            bdd * d0, bdd * d1, bdd * d2)


@jit(inline="always")
def _step(b, bd, bdd, r0, r1, r2, d0, d1, d2, n, v0, v1, v2, w0, w1, w2, e0, e1, e2, a0, a1, a2):
    """One step j >= 2 of the recursion: ``(v, w, e, w')`` after it, ``e = v' - R^T g``."""
    ct, al, be, ga = _exp_gamma(b, n)
    q00, q01, q02, q10, q11, q12, q20, q21, q22 = _transpose_of_exp(d0, d1, d2, ct, al, be)
    # tau = b r + beta d x r + gamma d x (d x r)
    c0 = d1 * r2 - d2 * r1
    c1 = d2 * r0 - d0 * r2
    c2 = d0 * r1 - d1 * r0
    t0 = (b * r0 + be * c0) + ga * (d1 * c2 - d2 * c1)
    t1 = (b * r1 + be * c1) + ga * (d2 * c0 - d0 * c2)
    t2 = (b * r2 + be * c2) + ga * (d0 * c1 - d1 * c0)
    # Q^T (v - tau x w), Q^T w
    x0 = v0 - (t1 * w2 - t2 * w1)
    x1 = v1 - (t2 * w0 - t0 * w2)
    x2 = v2 - (t0 * w1 - t1 * w0)
    zv0 = q00 * x0 + q01 * x1 + q02 * x2
    zv1 = q10 * x0 + q11 * x1 + q12 * x2
    zv2 = q20 * x0 + q21 * x1 + q22 * x2
    zw0 = q00 * w0 + q01 * w1 + q02 * w2
    zw1 = q10 * w0 + q11 * w1 + q12 * w2
    zw2 = q20 * w0 + q21 * w1 + q22 * w2
    # Q^T (e - tau x w'), Q^T w'
    x0 = e0 - (t1 * a2 - t2 * a1)
    x1 = e1 - (t2 * a0 - t0 * a2)
    x2 = e2 - (t0 * a1 - t1 * a0)
    y0 = q00 * x0 + q01 * x1 + q02 * x2
    y1 = q10 * x0 + q11 * x1 + q12 * x2
    y2 = q20 * x0 + q21 * x1 + q22 * x2
    yw0 = q00 * a0 + q01 * a1 + q02 * a2
    yw1 = q10 * a0 + q11 * a1 + q12 * a2
    yw2 = q20 * a0 + q21 * a1 + q22 * a2
    # ad(z) (b' Omega) = b' [zw x r + zv x d, zw x d]
    k0 = zw1 * d2 - zw2 * d1
    k1 = zw2 * d0 - zw0 * d2
    k2 = zw0 * d1 - zw1 * d0
    return (zv0 + bd * r0, zv1 + bd * r1, zv2 + bd * r2,
            zw0 + bd * d0, zw1 + bd * d1, zw2 + bd * d2,
            (y0 + bdd * r0) + bd * ((zw1 * r2 - zw2 * r1) + (zv1 * d2 - zv2 * d1)),
            (y1 + bdd * r1) + bd * ((zw2 * r0 - zw0 * r2) + (zv2 * d0 - zv0 * d2)),
            (y2 + bdd * r2) + bd * ((zw0 * r1 - zw1 * r0) + (zv0 * d1 - zv1 * d0)),
            (yw0 + bdd * d0) + bd * k0, (yw1 + bdd * d1) + bd * k1, (yw2 + bdd * d2) + bd * k2)


@jit(inline="always")
def _specific_force(v0, v1, v2, w0, w1, w2, e0, e1, e2):
    """``f = w x v + (v' - R^T g)``."""
    return (w1 * v2 - w2 * v1) + e0, (w2 * v0 - w0 * v2) + e1, (w0 * v1 - w1 * v0) + e2


@jit
def se3_imu(t, t0, dt, nseg, Rc, K, Mc, g, out):
    """Gyro ``out[0]`` (N, 3) and specific force ``out[1]`` (N, 3) of an SE3 spline at ``t`` (N,).

    ``t`` in seconds, already range-checked; ``s = (t - t0) / dt`` picks segment
    ``clamp(floor(s), 0, nseg - 1)`` as ``eval_se3``. ``Rc`` (n, 3, 3) control rotations, ``K``
    from :func:`se3_imu_knots`, ``Mc`` the cumulative blending matrix (k, k), ``g`` gravity (3,),
    ``out`` (2, N, 3) C-contiguous. Blocks of samples in structure-of-arrays scratch, as
    :func:`splineimu._kernels.spline_imu.imu_split` (gathers in loops of their own).
    """
    k = Mc.shape[0]
    N = t.shape[0]
    inv_dt = 1.0 / dt
    g0 = g[0]
    g1 = g[1]
    g2 = g[2]
    B = BLOCK
    seg = np.empty(B, dtype=np.uint64)
    Kf = K.reshape(K.size)
    Rf = Rc.reshape(Rc.size)
    of = out.reshape(out.size)
    S = np.empty((_PW + k, B))
    for start in range(0, N, B):
        m = min(B, N - start)
        _segments(t, start, m, t0, dt, nseg - 1, seg, S, _U)
        for n in range(2, k):
            for i in range(m):
                S[_PW + n, i] = S[_PW + n - 1, i] * S[_U, i]
        # e = -R_seg^T g
        for i in range(m):
            r9 = seg[i] * _U9
            S[_E0, i] = -(Rf[r9] * g0 + Rf[r9 + np.uint64(3)] * g1 + Rf[r9 + np.uint64(6)] * g2)
            S[_E1, i] = -(Rf[r9 + np.uint64(1)] * g0 + Rf[r9 + np.uint64(4)] * g1 + Rf[r9 + np.uint64(7)] * g2)
            S[_E2, i] = -(Rf[r9 + np.uint64(2)] * g0 + Rf[r9 + np.uint64(5)] * g1 + Rf[r9 + np.uint64(8)] * g2)
        for j in range(1, k):
            off = np.uint64(KNOT_COLS * j)
            for i in range(m):
                r = seg[i] * _UK + off
                S[_R0, i] = Kf[r]
                S[_R1, i] = Kf[r + np.uint64(1)]
                S[_R2, i] = Kf[r + np.uint64(2)]
                S[_D0, i] = Kf[r + np.uint64(3)]
                S[_D1, i] = Kf[r + np.uint64(4)]
                S[_D2, i] = Kf[r + np.uint64(5)]
                S[_ANG, i] = Kf[r + np.uint64(6)]
            # cumulative basis and its time derivatives: the power sums of _basis_one, in its order
            c0 = Mc[j, 0]
            c1 = Mc[j, 1]
            c2 = 2.0 * Mc[j, 2] if k > 2 else 0.0
            for i in range(m):
                S[_B, i] = (0.0 + c0) + c1 * S[_U, i]
                S[_BD, i] = 0.0 + c1
                S[_BDD, i] = 0.0 + c2
            for n in range(2, k):
                cn = Mc[j, n]
                fn = float(n)
                fnn = float(n * (n - 1))
                for i in range(m):
                    S[_B, i] += cn * S[_PW + n, i]
                    S[_BD, i] += cn * (fn * S[_PW + n - 1, i])
                if n >= 3:
                    for i in range(m):
                        S[_BDD, i] += cn * (fnn * S[_PW + n - 2, i])
            if j == 1:
                for i in range(m):
                    (S[_V0, i], S[_V1, i], S[_V2, i], S[_W0, i], S[_W1, i], S[_W2, i],
                     S[_E0, i], S[_E1, i], S[_E2, i], S[_A0, i], S[_A1, i], S[_A2, i]) = _first_step(
                        S[_B, i], S[_BD, i] * inv_dt, (S[_BDD, i] * inv_dt) * inv_dt,
                        S[_R0, i], S[_R1, i], S[_R2, i], S[_D0, i], S[_D1, i], S[_D2, i], S[_ANG, i],
                        S[_E0, i], S[_E1, i], S[_E2, i])
            else:
                for i in range(m):
                    (S[_V0, i], S[_V1, i], S[_V2, i], S[_W0, i], S[_W1, i], S[_W2, i],
                     S[_E0, i], S[_E1, i], S[_E2, i], S[_A0, i], S[_A1, i], S[_A2, i]) = _step(
                        S[_B, i], S[_BD, i] * inv_dt, (S[_BDD, i] * inv_dt) * inv_dt,
                        S[_R0, i], S[_R1, i], S[_R2, i], S[_D0, i], S[_D1, i], S[_D2, i], S[_ANG, i],
                        S[_V0, i], S[_V1, i], S[_V2, i], S[_W0, i], S[_W1, i], S[_W2, i],
                        S[_E0, i], S[_E1, i], S[_E2, i], S[_A0, i], S[_A1, i], S[_A2, i])
        for i in range(m):
            o = np.uint64(3 * (start + i))
            of[o] = S[_W0, i]
            of[o + np.uint64(1)] = S[_W1, i]
            of[o + np.uint64(2)] = S[_W2, i]
        for i in range(m):
            o = np.uint64(3 * (N + start + i))
            of[o], of[o + np.uint64(1)], of[o + np.uint64(2)] = _specific_force(
                S[_V0, i], S[_V1, i], S[_V2, i], S[_W0, i], S[_W1, i], S[_W2, i], S[_E0, i], S[_E1, i], S[_E2, i])


@jit(inline="always")
def _basis_one(H, row, k, u, inv_dt):
    """Cumulative basis value and its first and second time derivatives at ``u`` of the blending
    matrix row from ``H[row]``: :func:`se3_imu`'s power sums, in its order."""
    b = (0.0 + H[row]) + H[row + 1] * u
    bd = 0.0 + H[row + 1]
    bdd = 0.0 + (2.0 * H[row + 2] if k > 2 else 0.0)
    um2 = 1.0  # u^(n-2)
    um1 = u  # u^(n-1)
    for n in range(2, k):
        cn = H[row + n]
        un = um1 * u
        b += cn * un
        bd += cn * (float(n) * um1)
        if n >= 3:
            bdd += cn * (float(n * (n - 1)) * um2)
        um2 = um1
        um1 = un
    return b, bd * inv_dt, (bdd * inv_dt) * inv_dt


@jit(inline="always")
def _se3_at(t, H, g0, g1, g2):
    """Gyro and specific force at one time (in the table's range): :func:`se3_imu`'s operations."""
    k = int(H[H_K])
    dt = H[H_DT]
    inv_dt = 1.0 / dt
    seg, u = _segment_one(t, H[H_T0], dt, int(H[H_NSEG]) - 1)
    rows = int(H[H_ROWS])
    r = rows + ROW_COLS * seg + ROW_R
    e0 = -(H[r] * g0 + H[r + 3] * g1 + H[r + 6] * g2)
    e1 = -(H[r + 1] * g0 + H[r + 4] * g1 + H[r + 7] * g2)
    e2 = -(H[r + 2] * g0 + H[r + 5] * g1 + H[r + 8] * g2)
    v0 = v1 = v2 = w0 = w1 = w2 = a0 = a1 = a2 = 0.0
    for j in range(1, k):
        r = rows + ROW_COLS * (seg + j)
        b, bd, bdd = _basis_one(H, H_MC + j * k, k, u, inv_dt)
        if j == 1:
            v0, v1, v2, w0, w1, w2, e0, e1, e2, a0, a1, a2 = _first_step(
                b, bd, bdd, H[r], H[r + 1], H[r + 2], H[r + 3], H[r + 4], H[r + 5], H[r + 6], e0, e1, e2)
        else:
            v0, v1, v2, w0, w1, w2, e0, e1, e2, a0, a1, a2 = _step(
                b, bd, bdd, H[r], H[r + 1], H[r + 2], H[r + 3], H[r + 4], H[r + 5], H[r + 6],
                v0, v1, v2, w0, w1, w2, e0, e1, e2, a0, a1, a2)
    f0, f1, f2 = _specific_force(v0, v1, v2, w0, w1, w2, e0, e1, e2)
    return w0, w1, w2, f0, f1, f2


@jit(nrt=False)
def se3_imu_one(t, H, g, gyro, force):
    """:func:`se3_imu` at one time ``t`` (the same operations, so the same numbers). ``H`` from
    :func:`se3_one_sample_table`, gravity ``g`` (3,); writes ``gyro`` (1, 3) and ``force`` (1, 3)
    and returns True, or returns False (writing nothing) outside the table's time range or for
    NaN."""
    if not (H[H_LO] <= t <= H[H_HI]):
        return False
    gyro[0, 0], gyro[0, 1], gyro[0, 2], force[0, 0], force[0, 1], force[0, 2] = _se3_at(t, H, g[0], g[1], g[2])
    return True


@jit(nrt=False)
def se3_imu_few(t, H, g, out):
    """:func:`se3_imu_one` at each of a few times ``t`` (N,) into ``out`` (2, N, 3); returns False
    (writing nothing) if any time is outside the range or NaN."""
    lo = H[H_LO]
    hi = H[H_HI]
    for i in range(t.shape[0]):
        if not (lo <= t[i] <= hi):
            return False
    for i in range(t.shape[0]):
        out[0, i, 0], out[0, i, 1], out[0, i, 2], out[1, i, 0], out[1, i, 1], out[1, i, 2] = _se3_at(
            t[i], H, g[0], g[1], g[2])
    return True
