"""Gauss-Newton passes of the rotation fit: one pass over the poses per iteration, straight into
the band of the normal matrix.

Notation as in :mod:`splineimu._kernels.fit`: control rotations ``R_i`` (here unit quaternions
``(w, x, y, z)``), increments ``d_i = Log(R_{i-1}^T R_i)``, a pose in segment ``s`` with cumulative
basis ``b_j`` sees ``R(t) = R_s A_1 .. A_{k-1}``, ``A_j = Exp(x_j)``, ``x_j = b_j d_{s+j}``, and the
residual ``r = Log(R(t)^T R_meas)``. With ``C_i = Jr^-1(d_i)`` (so ``Jl^-1(d_i) = C_i^T``) and
``P_j = A_{j+1} .. A_{k-1}``, the residual moves by ``-Jl^-1(r) G_i delta_{s+i}`` with

    G_i = [i = 0] P_0^T + Y_i C_{s+i} - Y_{i+1} C_{s+i+1}^T,    Y_j = b_j P_j^T Jr(x_j).

The gradient needs no matrix: ``Jl^-1(r)^T r = r``, so ``g_i = -w G_i^T r`` and
``Y_j^T r = b_j Jl(x_j) P_j r``, where ``y_j = P_j r`` follows from ``y_{k-1} = r``,
``y_{j-1} = A_j y_j`` (O(k) vector work per pose); the ``C`` factors are applied once per knot
after the pass. The normal matrix (only on request: the solver keeps it while the steps are small)
is ``sum w G^T G``; it leaves out ``Jl^-T(r) Jl^-1(r) = I + O(|r|^2)``, which changes the steps'
convergence rate at second order in the residuals and not the fixed point (the gradient is exact).

The band is the scalar upper band of :mod:`splineimu.spline.banded`: ``band[i, c]`` = entry
``(i, i + c)`` of the (3 n, 3 n) matrix, ``c < 3 k``.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import jit
from .lie import JAC_SMALL_ANGLE, _i_plus_bk_ck2_into, so3_jacobian_inv_into
from .spline import _segment_of


@jit(inline="always")
def _coeffs(t2):
    """For |x|^2 = t2: ``(a, b, c, qw, qs)`` with Exp(x) = I + a K + b K^2, Jl(x) = I + b K + c K^2,
    Jr(x) = I - b K + c K^2 (a = sin t/t, b = (1 - cos t)/t^2, c = (t - sin t)/t^3) and the unit
    quaternion (qw, qs x) of Exp(x). Series below JAC_SMALL_ANGLE (errors < 3e-18)."""
    if t2 < JAC_SMALL_ANGLE * JAC_SMALL_ANGLE:
        a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0)))
        b = 0.5 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0))))
        c = (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0 * (1.0 - t2 / 110.0)))) / 6.0
        qw = 1.0 - t2 / 8.0 * (1.0 - t2 / 48.0 * (1.0 - t2 / 120.0 * (1.0 - t2 / 224.0)))
        qs = 0.5 * (1.0 - t2 / 24.0 * (1.0 - t2 / 80.0 * (1.0 - t2 / 168.0 * (1.0 - t2 / 288.0))))
    else:
        t = math.sqrt(t2)
        sh = math.sin(0.5 * t)
        qw = math.cos(0.5 * t)
        qs = sh / t
        a = 2.0 * qs * qw
        b = 2.0 * qs * qs
        c = (1.0 - a) / t2
    return a, b, c, qw, qs


@jit(inline="always")
def _quat_log(w, x, y, z):
    """Log of a unit quaternion of either sign (as lie.quat_wxyz_log_into), as a tuple."""
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    n2 = x * x + y * y + z * z
    n = math.sqrt(n2)
    if n < 1e-6 * w:  # lie.LOG_SMALL_ANGLE
        scale = 2.0 / w * (1.0 - n2 / (w * w) / 3.0)
    else:
        scale = 2.0 * math.atan2(n, w) / n
    return scale * x, scale * y, scale * z


@jit(inline="always")
def _quat_mul(a0, a1, a2, a3, b0, b1, b2, b3):
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


@jit
def so3_knot_terms(qc, D, C):
    """Per knot: ``D[i] = Log(q_{i-1}^-1 q_i)`` and ``C[i] = Jr^-1(D[i])`` for i >= 1 (row 0 zero)."""
    n = qc.shape[0]
    D[0, :] = 0.0
    C[0] = 0.0
    for i in range(1, n):
        e0, e1, e2, e3 = _quat_mul(qc[i - 1, 0], -qc[i - 1, 1], -qc[i - 1, 2], -qc[i - 1, 3],
                                   qc[i, 0], qc[i, 1], qc[i, 2], qc[i, 3])
        d0, d1, d2 = _quat_log(e0, e1, e2, e3)
        D[i, 0] = d0
        D[i, 1] = d1
        D[i, 2] = d2
        so3_jacobian_inv_into(d0, d1, d2, -1.0, C[i])


@jit(inline="always")
def _store_unit(out, i, p0, p1, p2, p3):
    """``out[i] = p / |p|`` for a quaternion p (w, x, y, z)."""
    nrm = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2 + p3 * p3)
    out[i, 0] = p0 / nrm
    out[i, 1] = p1 / nrm
    out[i, 2] = p2 / nrm
    out[i, 3] = p3 / nrm


@jit
def so3_retract(qc, delta, out):
    """``out[i] = q_i Exp(delta_i)`` (unit quaternions, renormalized)."""
    for i in range(qc.shape[0]):
        x = delta[i, 0]
        y = delta[i, 1]
        z = delta[i, 2]
        _, _, _, qw, qs = _coeffs(x * x + y * y + z * z)
        p0, p1, p2, p3 = _quat_mul(qc[i, 0], qc[i, 1], qc[i, 2], qc[i, 3], qw, qs * x, qs * y, qs * z)
        _store_unit(out, i, p0, p1, p2, p3)


@jit
def quat_slerp(t, q, tq, out):
    """Slerp of unit quaternions ``q`` (N, 4) at times ``t`` (N,, increasing) to sorted ``tq``
    (clipped to [t[0], t[-1]]), along the shorter arc; ``out`` (len(tq), 4)."""
    N = t.shape[0]
    i = 0
    for m in range(tq.shape[0]):
        tm = min(max(tq[m], t[0]), t[N - 1])
        while i < N - 2 and t[i + 1] <= tm:
            i += 1
        if N == 1:
            out[m, :] = q[0]
            continue
        u = (tm - t[i]) / (t[i + 1] - t[i])
        e0, e1, e2, e3 = _quat_mul(q[i, 0], -q[i, 1], -q[i, 2], -q[i, 3], q[i + 1, 0], q[i + 1, 1], q[i + 1, 2],
                                   q[i + 1, 3])
        x, y, z = _quat_log(e0, e1, e2, e3)
        x *= u
        y *= u
        z *= u
        _, _, _, qw, qs = _coeffs(x * x + y * y + z * z)
        p0, p1, p2, p3 = _quat_mul(q[i, 0], q[i, 1], q[i, 2], q[i, 3], qw, qs * x, qs * y, qs * z)
        _store_unit(out, m, p0, p1, p2, p3)


@jit
def _flush(Hloc, seg, band):
    """band rows of segment ``seg``'s controls += the upper triangle of ``Hloc`` (3 k, 3 k); zeroes it."""
    m = Hloc.shape[0]
    for i in range(m):
        for j in range(i, m):
            band[3 * seg + i, j - i] += Hloc[i, j]
    Hloc[:] = 0.0


@jit
def control_grid_init(t, q, tc, a1, a2, out):
    """Initial control rotations (n, 4) at the control times ``tc`` (sorted): the poses' slerp ``F``,
    continued along the end geodesics outside their span, then the quasi-interpolant
    ``F_i Exp(a1 (L_-1 + L_1) + a2 (L_-2 - 4 L_-1 - 4 L_1 + L_2))``, ``L_j = Log(F_i^-1 F_{i+j})``:
    the first two terms of the inverse of the spline's smoothing of its control points in powers
    of the second difference (only ``a1`` within two controls of the ends)."""
    n = tc.shape[0]
    N = t.shape[0]
    F = np.empty((n, 4))
    quat_slerp(t, q, tc, F)
    a = 0
    while a < n and tc[a] < t[0]:
        a += 1
    b = n - 1
    while b >= 0 and tc[b] > t[N - 1]:
        b -= 1
    if b - a >= 1:
        for i in range(a - 1, -1, -1):
            _extrapolate(F, i, i + 1, i + 2)
        for i in range(b + 1, n):
            _extrapolate(F, i, i - 1, i - 2)
    out[0] = F[0]
    out[n - 1] = F[n - 1]
    for i in range(1, n - 1):
        x0, x1, x2 = _rel_log(F, i, i - 1)
        y0, y1, y2 = _rel_log(F, i, i + 1)
        c1 = a1
        c2 = 0.0
        z0 = z1 = z2 = 0.0
        if 2 <= i < n - 2:
            c1 = a1 - 4.0 * a2
            c2 = a2
            u0, u1, u2 = _two_step_log(F, i, -1)
            v0, v1, v2 = _two_step_log(F, i, 1)
            z0 = u0 + v0
            z1 = u1 + v1
            z2 = u2 + v2
        x0 = c1 * (x0 + y0) + c2 * z0
        x1 = c1 * (x1 + y1) + c2 * z1
        x2 = c1 * (x2 + y2) + c2 * z2
        _, _, _, qw, qs = _coeffs(x0 * x0 + x1 * x1 + x2 * x2)
        p0, p1, p2, p3 = _quat_mul(F[i, 0], F[i, 1], F[i, 2], F[i, 3], qw, qs * x0, qs * x1, qs * x2)
        _store_unit(out, i, p0, p1, p2, p3)


@jit(inline="always")
def _rel_log(F, i, j):
    """Log(F_i^-1 F_j) as a tuple."""
    e0, e1, e2, e3 = _quat_mul(F[i, 0], -F[i, 1], -F[i, 2], -F[i, 3], F[j, 0], F[j, 1], F[j, 2], F[j, 3])
    return _quat_log(e0, e1, e2, e3)


@jit(inline="always")
def _two_step_log(F, i, s):
    """``Log(F_i^-1 F_{i+2s})`` unwrapped: where either step turns by more than 60 degrees, the two
    steps' Logs added in frame i (exact for turns about one axis), since together they may
    turn beyond pi, where the Log wraps to the opposite turn (knots 90-135 degrees apart)."""
    x0, x1, x2 = _rel_log(F, i, i + s)
    y0, y1, y2 = _rel_log(F, i + s, i + 2 * s)
    lim = (math.pi / 3.0) ** 2
    if x0 * x0 + x1 * x1 + x2 * x2 <= lim and y0 * y0 + y1 * y1 + y2 * y2 <= lim:
        return _rel_log(F, i, i + 2 * s)
    # y turned into frame i by e = F_i^-1 F_{i+s}: y + 2 w (v x y) + 2 v x (v x y)
    e0, e1, e2, e3 = _quat_mul(F[i, 0], -F[i, 1], -F[i, 2], -F[i, 3], F[i + s, 0], F[i + s, 1], F[i + s, 2],
                               F[i + s, 3])
    c0 = 2.0 * (e2 * y2 - e3 * y1)
    c1 = 2.0 * (e3 * y0 - e1 * y2)
    c2 = 2.0 * (e1 * y1 - e2 * y0)
    return (x0 + y0 + e0 * c0 + e2 * c2 - e3 * c1, x1 + y1 + e0 * c1 + e3 * c0 - e1 * c2,
            x2 + y2 + e0 * c2 + e1 * c1 - e2 * c0)


@jit
def _extrapolate(F, i, i1, i2):
    """``F[i] = F[i1] Exp(-Log(F[i1]^-1 F[i2]))``: one more step along the geodesic through i2, i1."""
    e0, e1, e2, e3 = _quat_mul(F[i1, 0], -F[i1, 1], -F[i1, 2], -F[i1, 3], F[i2, 0], F[i2, 1], F[i2, 2], F[i2, 3])
    x0, x1, x2 = _quat_log(e0, e1, e2, e3)
    _, _, _, qw, qs = _coeffs(x0 * x0 + x1 * x1 + x2 * x2)
    p0, p1, p2, p3 = _quat_mul(F[i1, 0], F[i1, 1], F[i1, 2], F[i1, 3], qw, -qs * x0, -qs * x1, -qs * x2)
    F[i, 0] = p0
    F[i, 1] = p1
    F[i, 2] = p2
    F[i, 3] = p3


@jit
def so3_pass(seg_all, u_all, w_all, q_meas, qc, D, C, Mc, nseg, want_h, band, g, res):
    """One pass over the poses: residuals into ``res`` (N, 3), ``g`` (n, 3) += gradient
    ``sum w J^T r`` and, if ``want_h``, ``band`` (3 n, 3 k) += ``sum w G^T G``. Returns the cost
    ``sum w |r|^2``. ``q_meas`` (N, 4) and ``qc`` (n, 4) unit quaternions (w, x, y, z); ``D``, ``C``
    from :func:`so3_knot_terms`."""
    k = Mc.shape[0]
    n = qc.shape[0]
    b = np.empty(k)
    X = np.empty((k, 3))
    cf = np.empty((k, 3))
    V = np.zeros((n, 3))
    Z = np.zeros((n, 3))
    P = np.empty((k, 3, 3))
    Y = np.empty((k, 3, 3))
    Gf = np.empty((3, 3 * k))
    Hloc = np.zeros((3 * k, 3 * k))
    hseg = -1
    A = np.empty((3, 3))
    J = np.empty((3, 3))
    cost = 0.0
    for m in range(seg_all.shape[0]):
        seg, u = _segment_of(seg_all[m], u_all[m], nseg)
        for j in range(k):
            acc = Mc[j, k - 1]
            for p in range(k - 2, -1, -1):
                acc = acc * u + Mc[j, p]
            b[j] = acc
        # q(t) = q_s Exp(x_1) .. Exp(x_{k-1})
        w0 = qc[seg, 0]
        w1 = qc[seg, 1]
        w2 = qc[seg, 2]
        w3 = qc[seg, 3]
        for j in range(1, k):
            x0 = b[j] * D[seg + j, 0]
            x1 = b[j] * D[seg + j, 1]
            x2 = b[j] * D[seg + j, 2]
            X[j, 0] = x0
            X[j, 1] = x1
            X[j, 2] = x2
            ca, cb, cc, qw, qs = _coeffs(x0 * x0 + x1 * x1 + x2 * x2)
            cf[j, 0] = ca
            cf[j, 1] = cb
            cf[j, 2] = cc
            w0, w1, w2, w3 = _quat_mul(w0, w1, w2, w3, qw, qs * x0, qs * x1, qs * x2)
        e0, e1, e2, e3 = _quat_mul(w0, -w1, -w2, -w3, q_meas[m, 0], q_meas[m, 1], q_meas[m, 2], q_meas[m, 3])
        r0, r1, r2 = _quat_log(e0, e1, e2, e3)
        res[m, 0] = r0
        res[m, 1] = r1
        res[m, 2] = r2
        ww = w_all[m]
        cost += ww * (r0 * r0 + r1 * r1 + r2 * r2)
        if ww == 0.0:
            continue
        # gradient: z_j = b_j Jl(x_j) y_j, y_{j-1} = Exp(x_j) y_j, y_{k-1} = r
        y0 = r0
        y1 = r1
        y2 = r2
        for j in range(k - 1, 0, -1):
            x0 = X[j, 0]
            x1 = X[j, 1]
            x2 = X[j, 2]
            c0 = x1 * y2 - x2 * y1
            c1 = x2 * y0 - x0 * y2
            c2 = x0 * y1 - x1 * y0
            cc0 = x1 * c2 - x2 * c1
            cc1 = x2 * c0 - x0 * c2
            cc2 = x0 * c1 - x1 * c0
            bw = ww * b[j]
            Z[seg + j, 0] += bw * (y0 + cf[j, 1] * c0 + cf[j, 2] * cc0)
            Z[seg + j, 1] += bw * (y1 + cf[j, 1] * c1 + cf[j, 2] * cc1)
            Z[seg + j, 2] += bw * (y2 + cf[j, 1] * c2 + cf[j, 2] * cc2)
            y0 += cf[j, 0] * c0 + cf[j, 1] * cc0
            y1 += cf[j, 0] * c1 + cf[j, 1] * cc1
            y2 += cf[j, 0] * c2 + cf[j, 1] * cc2
        V[seg, 0] += ww * y0
        V[seg, 1] += ww * y1
        V[seg, 2] += ww * y2
        if not want_h:
            continue
        # suffix products P_j = A_{j+1} .. A_{k-1}
        for r in range(3):
            for c in range(3):
                P[k - 1, r, c] = 1.0 if r == c else 0.0
        for j in range(k - 1, 0, -1):
            _i_plus_bk_ck2_into(X[j, 0], X[j, 1], X[j, 2], cf[j, 0], cf[j, 1], A)
            for r in range(3):
                for c in range(3):
                    P[j - 1, r, c] = A[r, 0] * P[j, 0, c] + A[r, 1] * P[j, 1, c] + A[r, 2] * P[j, 2, c]
        # Y_j = b_j P_j^T Jr(x_j)
        for j in range(1, k):
            _i_plus_bk_ck2_into(X[j, 0], X[j, 1], X[j, 2], -cf[j, 1], cf[j, 2], J)
            for r in range(3):
                for c in range(3):
                    Y[j, r, c] = b[j] * (P[j, 0, r] * J[0, c] + P[j, 1, r] * J[1, c] + P[j, 2, r] * J[2, c])
        # G_i (as Gf[z, 3 i + r] = G_i[z, r])
        for r in range(3):
            for c in range(3):
                Gf[r, c] = P[0, c, r]
            for c in range(3, 3 * k):
                Gf[r, c] = 0.0
        for j in range(1, k):
            cj = seg + j
            for r in range(3):
                for c in range(3):
                    Gf[r, 3 * j + c] += (Y[j, r, 0] * C[cj, 0, c] + Y[j, r, 1] * C[cj, 1, c]
                                         + Y[j, r, 2] * C[cj, 2, c])
                    Gf[r, 3 * j - 3 + c] -= (Y[j, r, 0] * C[cj, c, 0] + Y[j, r, 1] * C[cj, c, 1]
                                             + Y[j, r, 2] * C[cj, c, 2])
        # the segment's block of the normal matrix += w G^T G (upper triangle), into the band when the
        # segment changes
        if seg != hseg:
            if hseg >= 0:
                _flush(Hloc, hseg, band)
            hseg = seg
        for i in range(3 * k):
            a0 = ww * Gf[0, i]
            a1 = ww * Gf[1, i]
            a2 = ww * Gf[2, i]
            for j in range(3 * k):  # the whole square: a loop of fixed length vectorizes, 1.7x faster
                Hloc[i, j] += a0 * Gf[0, j] + a1 * Gf[1, j] + a2 * Gf[2, j]
    if hseg >= 0:
        _flush(Hloc, hseg, band)
    # g_i = -(V_i + C_i^T Z_i - C_{i+1} Z_{i+1})
    for i in range(n):
        for r in range(3):
            s = V[i, r]
            if i >= 1:
                s += C[i, 0, r] * Z[i, 0] + C[i, 1, r] * Z[i, 1] + C[i, 2, r] * Z[i, 2]
            if i + 1 < n:
                s -= C[i + 1, r, 0] * Z[i + 1, 0] + C[i + 1, r, 1] * Z[i + 1, 1] + C[i + 1, r, 2] * Z[i + 1, 2]
            g[i, r] -= s
    return cost


@jit
def increment_penalty(D, Jr_inv, Jl_inv, mu, want_h, band, g):
    """Linearized penalty ``sum_j mu_{j-1} |d_{j+1} - d_j|^2`` (j = 1 .. n-2) on the increments D (n, d):
    ``g`` += its gradient half ``sum mu B^T e``, ``band`` (d n, d k) += ``sum mu B^T B`` if ``want_h``.
    ``d_j`` moves by ``Jr^-1(d_j) delta_j - Jl^-1(d_j) delta_{j-1}`` (blocks ``Jr_inv``, ``Jl_inv``
    (n, d, d)). Returns the penalty."""
    n = D.shape[0]
    d = D.shape[1]
    B = np.empty((3, d, d))
    e = np.empty(d)
    cost = 0.0
    for j in range(1, n - 1):
        mj = mu[j - 1]
        if mj == 0.0:
            continue
        for r in range(d):
            e[r] = D[j + 1, r] - D[j, r]
            cost += mj * e[r] * e[r]
            for c in range(d):
                B[0, r, c] = Jl_inv[j, r, c]
                B[1, r, c] = -Jl_inv[j + 1, r, c] - Jr_inv[j, r, c]
                B[2, r, c] = Jr_inv[j + 1, r, c]
        for a in range(3):
            row = d * (j - 1 + a)
            for r in range(d):
                s = 0.0
                for z in range(d):
                    s += B[a, z, r] * e[z]
                g[j - 1 + a, r] += mj * s
            if not want_h:
                continue
            for bb in range(a, 3):
                for r in range(d):
                    for c in range(d):
                        off = d * (bb - a) + c - r
                        if off >= 0:
                            s = 0.0
                            for z in range(d):
                                s += B[a, z, r] * B[bb, z, c]
                            band[row + r, off] += mj * s
    return cost


@jit
def add_difference_penalty(Hs, mu, c):
    """``Hs`` (n, k) upper band += ``D^T diag(mu) D`` for the difference operator with coefficients
    ``c`` (r + 1,): row ``j`` of D touches ``j .. j + r``, ``mu`` (n - r,)."""
    L = c.shape[0]
    for a in range(L):  # in this order, the sums round as numpy's slice by slice
        for b in range(a, L):
            for j in range(mu.shape[0]):
                Hs[j + a, b - a] += mu[j] * c[a] * c[b]


@jit
def quat_increments(q, out):
    """``out[i] = Log(q_i^-1 q_{i+1})`` (N - 1, 3) of unit quaternions q (N, 4)."""
    for i in range(q.shape[0] - 1):
        e0, e1, e2, e3 = _quat_mul(q[i, 0], -q[i, 1], -q[i, 2], -q[i, 3], q[i + 1, 0], q[i + 1, 1], q[i + 1, 2],
                                   q[i + 1, 3])
        out[i, 0], out[i, 1], out[i, 2] = _quat_log(e0, e1, e2, e3)
