"""Numba kernels of the IMU preintegrator (see :mod:`splineimu.preintegration` for the math).

State layout (all float64, owned by the public class, updated in place):

- ``nav`` (10,): ``alpha`` (delta p, 3), ``beta`` (delta v, 3), ``q`` (delta rotation, w x y z).
- ``P`` (15, 15): error-state covariance in the *start-frame* chart ``(p, phi, v, b_a, b_g)``
  with ``phi = R_k dtheta`` (the rotation error rotated into frame i). In the consistent
  model it is the covariance of ``y_k = dx_k - V1_{k-1} n_k``, the part of the error that is
  independent of the last sample's noise (see the public module).
- ``J`` (15, 9): the columns ``(theta, b_a, b_g)`` of the Jacobian of the error state at k
  with respect to the error state at i, same chart (the ``p`` and ``v`` columns are trivial:
  ``d p_k / d p_i = I``, ``d p_k / d v_i = (t_k - t_i) I``, ``d v_k / d v_i = I``).
- ``V1`` (15, 6): noise Jacobian of the last step with respect to the last sample's
  ``(n_a, n_g)`` (consistent model only; zero rows for the biases).
- ``qlast`` (6,): discrete variances of the last sample's ``(n_a, n_g)``.
- ``prev`` (7,): the last sample consumed: ``t, gyro xyz, accel xyz``.
- ``params`` (18,): ``b_g (3), b_a (3), sigma_a^2 (3), sigma_g^2 (3), sigma_ba^2 (3),
  sigma_bg^2 (3)`` (continuous densities squared).

Error-state Jacobians are the exact linearization of the discrete step actually computed
(rotation advanced with the exact SO3 exponential), so bias Jacobians agree with finite
differences of the discrete map to rounding.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import jit
from .lie import EXP_SMALL_ANGLE, quat_wxyz_to_mat_into, so3_jacobian_into

METHOD_EULER = 0
METHOD_MIDPOINT = 1

COV_CONSISTENT = 0
COV_VINS = 1

# error-state offsets
O_P = 0
O_R = 3
O_V = 6
O_BA = 9
O_BG = 12


@jit
def _quat_mul_exp(q, x, y, z, out):
    """out = q * Exp([x, y, z]) for q = (w, x, y, z), renormalized."""
    t2 = x * x + y * y + z * z
    if t2 < EXP_SMALL_ANGLE * EXP_SMALL_ANGLE:
        # cos(t/2), sin(t/2)/t to t^4
        c = 1.0 - t2 / 8.0 + t2 * t2 / 384.0
        s = 0.5 - t2 / 48.0 + t2 * t2 / 3840.0
    else:
        t = math.sqrt(t2)
        c = math.cos(0.5 * t)
        s = math.sin(0.5 * t) / t
    bw = c
    bx = s * x
    by = s * y
    bz = s * z
    aw = q[0]
    ax = q[1]
    ay = q[2]
    az = q[3]
    w = aw * bw - ax * bx - ay * by - az * bz
    xx = aw * bx + ax * bw + ay * bz - az * by
    yy = aw * by - ax * bz + ay * bw + az * bx
    zz = aw * bz + ax * by - ay * bx + az * bw
    n = math.sqrt(w * w + xx * xx + yy * yy + zz * zz)
    out[0] = w / n
    out[1] = xx / n
    out[2] = yy / n
    out[3] = zz / n


@jit
def _rows_F(X, ncol, dt, ab, M, Cba, Cbg):
    """X <- F X for the 15 rows of X (15, ncol), in place.

    F = I except: rows p += dt v + dt^2/2 W, rows v += dt W, rows phi -= M bg, with
    W = -[ab]x phi + Cba ba + Cbg bg (all from the *old* rows).
    """
    h2 = 0.5 * dt * dt
    for c in range(ncol):
        f0 = X[3, c]
        f1 = X[4, c]
        f2 = X[5, c]
        a0 = X[9, c]
        a1 = X[10, c]
        a2 = X[11, c]
        g0 = X[12, c]
        g1 = X[13, c]
        g2 = X[14, c]
        # -[ab]x phi = phi x ab
        w0 = f1 * ab[2] - f2 * ab[1] + Cba[0, 0] * a0 + Cba[0, 1] * a1 + Cba[0, 2] * a2
        w1 = f2 * ab[0] - f0 * ab[2] + Cba[1, 0] * a0 + Cba[1, 1] * a1 + Cba[1, 2] * a2
        w2 = f0 * ab[1] - f1 * ab[0] + Cba[2, 0] * a0 + Cba[2, 1] * a1 + Cba[2, 2] * a2
        w0 += Cbg[0, 0] * g0 + Cbg[0, 1] * g1 + Cbg[0, 2] * g2
        w1 += Cbg[1, 0] * g0 + Cbg[1, 1] * g1 + Cbg[1, 2] * g2
        w2 += Cbg[2, 0] * g0 + Cbg[2, 1] * g1 + Cbg[2, 2] * g2
        X[0, c] += dt * X[6, c] + h2 * w0
        X[1, c] += dt * X[7, c] + h2 * w1
        X[2, c] += dt * X[8, c] + h2 * w2
        X[6, c] += dt * w0
        X[7, c] += dt * w1
        X[8, c] += dt * w2
        X[3, c] = f0 - (M[0, 0] * g0 + M[0, 1] * g1 + M[0, 2] * g2)
        X[4, c] = f1 - (M[1, 0] * g0 + M[1, 1] * g1 + M[1, 2] * g2)
        X[5, c] = f2 - (M[2, 0] * g0 + M[2, 1] * g1 + M[2, 2] * g2)


@jit
def _cols_F_sym(X, dt, ab, M, Cba, Cbg):
    """X <- X F^T for X = F P with P symmetric, so that the result is symmetric.

    F's bias rows are the identity, so ``(X F^T)[nav, bias] = X[nav, bias]``; only the nav
    rows need the column operation, the bias rows are copied by symmetry.
    """
    h2 = 0.5 * dt * dt
    for r in range(9):
        f0 = X[r, 3]
        f1 = X[r, 4]
        f2 = X[r, 5]
        a0 = X[r, 9]
        a1 = X[r, 10]
        a2 = X[r, 11]
        g0 = X[r, 12]
        g1 = X[r, 13]
        g2 = X[r, 14]
        w0 = f1 * ab[2] - f2 * ab[1] + Cba[0, 0] * a0 + Cba[0, 1] * a1 + Cba[0, 2] * a2
        w1 = f2 * ab[0] - f0 * ab[2] + Cba[1, 0] * a0 + Cba[1, 1] * a1 + Cba[1, 2] * a2
        w2 = f0 * ab[1] - f1 * ab[0] + Cba[2, 0] * a0 + Cba[2, 1] * a1 + Cba[2, 2] * a2
        w0 += Cbg[0, 0] * g0 + Cbg[0, 1] * g1 + Cbg[0, 2] * g2
        w1 += Cbg[1, 0] * g0 + Cbg[1, 1] * g1 + Cbg[1, 2] * g2
        w2 += Cbg[2, 0] * g0 + Cbg[2, 1] * g1 + Cbg[2, 2] * g2
        X[r, 0] += dt * X[r, 6] + h2 * w0
        X[r, 1] += dt * X[r, 7] + h2 * w1
        X[r, 2] += dt * X[r, 8] + h2 * w2
        X[r, 6] += dt * w0
        X[r, 7] += dt * w1
        X[r, 8] += dt * w2
        X[r, 3] = f0 - (M[0, 0] * g0 + M[0, 1] * g1 + M[0, 2] * g2)
        X[r, 4] = f1 - (M[1, 0] * g0 + M[1, 1] * g1 + M[1, 2] * g2)
        X[r, 5] = f2 - (M[2, 0] * g0 + M[2, 1] * g1 + M[2, 2] * g2)
    for r in range(9, 15):
        for c in range(9):
            X[r, c] = X[c, r]


@jit
def _add_noise(P, G, qd):
    """P[:9, :9] += G[:9] diag(qd) G[:9]^T (G has zero bias rows)."""
    for i in range(9):
        for j in range(i, 9):
            s = 0.0
            for m in range(6):
                s += G[i, m] * qd[m] * G[j, m]
            P[i, j] += s
            if j != i:
                P[j, i] += s


@jit
def _fill_noise_jac(V, dt, R, M, K1, wa, wg):
    """Noise Jacobian of one sample in one step (nav rows; bias rows untouched = 0).

    The sample's accel noise enters u with weight ``wa R`` and its gyro noise enters
    phi with ``wg M`` and u with ``-wg K1 / 2`` (K1 = 0 for Euler); p gets dt^2/2 u, v gets dt u.
    """
    h2 = 0.5 * dt * dt
    for r in range(3):
        for c in range(3):
            ua = wa * R[r, c]
            ug = -0.5 * wg * K1[r, c]
            V[O_P + r, c] = h2 * ua
            V[O_V + r, c] = dt * ua
            V[O_R + r, c] = 0.0
            V[O_P + r, 3 + c] = h2 * ug
            V[O_V + r, 3 + c] = dt * ug
            V[O_R + r, 3 + c] = wg * M[r, c]


@jit
def preintegrate_kernel(t, gyro, accel, has_prev, params, method, cov_model, with_cov,
                        nav, P, J, V1, qlast, prev, sum_dt):
    """Consume samples ``t (N,), gyro (N, 3), accel (N, 3)``; update the state in place.

    If ``has_prev`` the first step goes from ``prev`` to sample 0. Returns the new
    ``delta_t`` (``sum_dt[0]`` is updated too).
    """
    n = t.shape[0]
    bg0 = params[0]
    bg1 = params[1]
    bg2 = params[2]
    ba0 = params[3]
    ba1 = params[4]
    ba2 = params[5]

    R0 = np.empty((3, 3))
    R1 = np.empty((3, 3))
    Jr = np.empty((3, 3))
    M = np.empty((3, 3))
    K1 = np.zeros((3, 3))
    Cba = np.empty((3, 3))
    Cbg = np.zeros((3, 3))
    ab = np.empty(3)
    qn = np.empty(4)
    V0 = np.zeros((15, 6))
    Vn = np.zeros((15, 6))
    G = np.zeros((15, 6))
    qd = np.empty(6)

    quat_wxyz_to_mat_into(nav[6], nav[7], nav[8], nav[9], R0)
    midpoint = method == METHOD_MIDPOINT
    first_sample = 0 if has_prev else 1
    total = sum_dt[0]

    for k in range(first_sample, n):
        if k == 0:
            t0 = prev[0]
            gx0 = prev[1]
            gy0 = prev[2]
            gz0 = prev[3]
            ax0 = prev[4]
            ay0 = prev[5]
            az0 = prev[6]
        else:
            t0 = t[k - 1]
            gx0 = gyro[k - 1, 0]
            gy0 = gyro[k - 1, 1]
            gz0 = gyro[k - 1, 2]
            ax0 = accel[k - 1, 0]
            ay0 = accel[k - 1, 1]
            az0 = accel[k - 1, 2]
        t1 = t[k]
        gx1 = gyro[k, 0]
        gy1 = gyro[k, 1]
        gz1 = gyro[k, 2]
        ax1 = accel[k, 0]
        ay1 = accel[k, 1]
        az1 = accel[k, 2]
        dt = t1 - t0

        if midpoint:
            wx = 0.5 * (gx0 + gx1) - bg0
            wy = 0.5 * (gy0 + gy1) - bg1
            wz = 0.5 * (gz0 + gz1) - bg2
        else:
            wx = gx0 - bg0
            wy = gy0 - bg1
            wz = gz0 - bg2
        fx0 = ax0 - ba0
        fy0 = ay0 - ba1
        fz0 = az0 - ba2
        fx1 = ax1 - ba0
        fy1 = ay1 - ba1
        fz1 = az1 - ba2

        # rotation: R1 = R0 Exp(w dt)
        _quat_mul_exp(nav[6:10], wx * dt, wy * dt, wz * dt, qn)
        quat_wxyz_to_mat_into(qn[0], qn[1], qn[2], qn[3], R1)

        # start-frame accelerations
        a0x = R0[0, 0] * fx0 + R0[0, 1] * fy0 + R0[0, 2] * fz0
        a0y = R0[1, 0] * fx0 + R0[1, 1] * fy0 + R0[1, 2] * fz0
        a0z = R0[2, 0] * fx0 + R0[2, 1] * fy0 + R0[2, 2] * fz0
        if midpoint:
            a1x = R1[0, 0] * fx1 + R1[0, 1] * fy1 + R1[0, 2] * fz1
            a1y = R1[1, 0] * fx1 + R1[1, 1] * fy1 + R1[1, 2] * fz1
            a1z = R1[2, 0] * fx1 + R1[2, 1] * fy1 + R1[2, 2] * fz1
            ab[0] = 0.5 * (a0x + a1x)
            ab[1] = 0.5 * (a0y + a1y)
            ab[2] = 0.5 * (a0z + a1z)
        else:
            a1x = 0.0
            a1y = 0.0
            a1z = 0.0
            ab[0] = a0x
            ab[1] = a0y
            ab[2] = a0z

        # ---------------------------------------------------------- linearization
        so3_jacobian_into(wx * dt, wy * dt, wz * dt, -1.0, Jr)
        for r in range(3):
            for c in range(3):
                M[r, c] = dt * (R1[r, 0] * Jr[0, c] + R1[r, 1] * Jr[1, c] + R1[r, 2] * Jr[2, c])
        if midpoint:
            # K1 = [a1]x M
            for c in range(3):
                K1[0, c] = -a1z * M[1, c] + a1y * M[2, c]
                K1[1, c] = a1z * M[0, c] - a1x * M[2, c]
                K1[2, c] = -a1y * M[0, c] + a1x * M[1, c]
            for r in range(3):
                for c in range(3):
                    Cba[r, c] = -0.5 * (R0[r, c] + R1[r, c])
                    Cbg[r, c] = 0.5 * K1[r, c]
        else:
            for r in range(3):
                for c in range(3):
                    Cba[r, c] = -R0[r, c]

        # Jacobian w.r.t. the start error state (its columns for theta, b_a, b_g)
        _rows_F(J, 9, dt, ab, M, Cba, Cbg)

        if with_cov:
            if midpoint:
                _fill_noise_jac(V0, dt, R0, M, K1, 0.5, 0.5)
                _fill_noise_jac(Vn, dt, R1, M, K1, 0.5, 0.5)
            else:
                _fill_noise_jac(V0, dt, R0, M, K1, 1.0, 1.0)
            # covariance: P <- F P F^T
            _rows_F(P, 15, dt, ab, M, Cba, Cbg)
            _cols_F_sym(P, dt, ab, M, Cba, Cbg)
            inv_dt = 1.0 / dt
            for m in range(3):
                qd[m] = params[6 + m] * inv_dt
                qd[3 + m] = params[9 + m] * inv_dt
            if (not midpoint) or cov_model == COV_VINS:
                _add_noise(P, V0, qd)
                if midpoint:
                    _add_noise(P, Vn, qd)
            else:
                # each sample's noise once, with the combined Jacobian
                if total == 0.0:  # first step: sample 0's variance from its forward interval
                    for m in range(6):
                        qlast[m] = qd[m]
                for r in range(15):
                    for c in range(6):
                        G[r, c] = V1[r, c]
                _rows_F(G, 6, dt, ab, M, Cba, Cbg)
                for r in range(9):
                    for c in range(6):
                        G[r, c] += V0[r, c]
                _add_noise(P, G, qlast)
                for r in range(15):
                    for c in range(6):
                        V1[r, c] = Vn[r, c]
                for m in range(6):
                    qlast[m] = qd[m]
            for m in range(3):
                P[O_BA + m, O_BA + m] += params[12 + m] * dt
                P[O_BG + m, O_BG + m] += params[15 + m] * dt

        # ---------------------------------------------------------- nominal state
        h2 = 0.5 * dt * dt
        nav[0] += nav[3] * dt + h2 * ab[0]
        nav[1] += nav[4] * dt + h2 * ab[1]
        nav[2] += nav[5] * dt + h2 * ab[2]
        nav[3] += dt * ab[0]
        nav[4] += dt * ab[1]
        nav[5] += dt * ab[2]
        for m in range(4):
            nav[6 + m] = qn[m]
        for r in range(3):
            for c in range(3):
                R0[r, c] = R1[r, c]
        total += dt

    if n > 0:
        prev[0] = t[n - 1]
        prev[1] = gyro[n - 1, 0]
        prev[2] = gyro[n - 1, 1]
        prev[3] = gyro[n - 1, 2]
        prev[4] = accel[n - 1, 0]
        prev[5] = accel[n - 1, 1]
        prev[6] = accel[n - 1, 2]
    sum_dt[0] = total
    return total
