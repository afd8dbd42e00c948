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

import numpy as np

from .._jit import jit
from .lie import (
    quat_wxyz_mul_into,
    quat_wxyz_normalize_into,
    quat_wxyz_to_mat_into,
    so3_exp_quat_wxyz_into,
    so3_jacobian_into,
)

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

# the step's linearization blocks, lin (5, 3, 3): J_r(w dt), M = dt R1 J_r(w dt), K1 = [a1]x M
# (midpoint; 0 for Euler), and the bias columns Cba, Cbg of the start-frame acceleration
L_JR = 0
L_M = 1
L_K1 = 2
L_CBA = 3
L_CBG = 4


@jit(nrt=False)
def _rows_F(X, ncol, dt, ab, lin):
    """X <- F X for the 15 rows of X (15, ncol), in place.

    F = I except: rows p += dt v + dt^2/2 W, rows v += dt W, rows phi -= M bg, with
    W = -[ab]x phi + Cba ba + Cbg bg (all from the *old* rows).
    """
    M = lin[L_M]
    Cba = lin[L_CBA]
    Cbg = lin[L_CBG]
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


@jit(nrt=False)
def _cols_F_sym(X, dt, ab, lin):
    """X <- X F^T for X = F P with P symmetric, so that the result is symmetric.

    ``X F^T = (F X^T)^T``: the row operation on the transpose. F's bias rows are the identity,
    so ``(X F^T)[nav, bias] = X[nav, bias]``; only the nav rows need it, the bias rows are
    copied by symmetry.
    """
    _rows_F(X.T, 9, dt, ab, lin)
    for r in range(9, 15):
        for c in range(9):
            X[r, c] = X[c, r]


@jit(nrt=False)
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


@jit(nrt=False)
def _fill_noise_jac(V, dt, R, lin, wa, wg):
    """Noise Jacobian of one sample in one step (nav rows; bias rows untouched = 0).

    The sample's accel noise enters u with weight ``wa R`` and its gyro noise enters
    phi with ``wg M`` and u with ``-wg K1 / 2`` (K1 = 0 for Euler); p gets dt^2/2 u, v gets dt u.
    """
    M = lin[L_M]
    K1 = lin[L_K1]
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


@jit(nrt=False)
def _load_sample(t, gyro, accel, k, s):
    """s (7,) = (t[k], gyro[k], accel[k])."""
    s[0] = t[k]
    for c in range(3):
        s[1 + c] = gyro[k, c]
        s[4 + c] = accel[k, c]


@jit(nrt=False)
def _step_inputs(ends, params, midpoint, u):
    """Bias-corrected inputs of a step from its samples ``ends`` (2, 7) at start and end:
    ``u[0]``, ``u[1]`` the specific force at both ends, ``u[2]`` the body rate over the step
    (the mean of both ends for midpoint, the start for Euler)."""
    for c in range(3):
        if midpoint:
            u[2, c] = 0.5 * (ends[0, 1 + c] + ends[1, 1 + c]) - params[c]
        else:
            u[2, c] = ends[0, 1 + c] - params[c]
        for e in range(2):
            u[e, c] = ends[e, 4 + c] - params[3 + c]


@jit(nrt=False)
def _rotate_into(R, v, out):
    """out = R v."""
    for r in range(3):
        out[r] = R[r, 0] * v[0] + R[r, 1] * v[1] + R[r, 2] * v[2]


@jit(nrt=False)
def _linearize(rot, w, dt, a1, midpoint, lin):
    """The blocks of lin (see L_*) for a step from rot[0] to rot[1] at rate w, end acceleration a1."""
    R0 = rot[0]
    R1 = rot[1]
    Jr = lin[L_JR]
    M = lin[L_M]
    so3_jacobian_into(w[0] * dt, w[1] * dt, w[2] * dt, -1.0, Jr)
    for r in range(3):
        for c in range(3):
            M[r, c] = dt * (R1[r, 0] * Jr[0, c] + R1[r, 1] * Jr[1, c] + R1[r, 2] * Jr[2, c])
    if midpoint:
        K1 = lin[L_K1]
        for c in range(3):
            K1[0, c] = -a1[2] * M[1, c] + a1[1] * M[2, c]
            K1[1, c] = a1[2] * M[0, c] - a1[0] * M[2, c]
            K1[2, c] = -a1[1] * M[0, c] + a1[0] * M[1, c]
        for r in range(3):
            for c in range(3):
                lin[L_CBA, r, c] = -0.5 * (R0[r, c] + R1[r, c])
                lin[L_CBG, r, c] = 0.5 * K1[r, c]
    else:
        for r in range(3):
            for c in range(3):
                lin[L_CBA, r, c] = -R0[r, c]


@jit(nrt=False)
def _propagate_covariance(P, V1, qlast, params, dt, first_step, midpoint, cov_model, rot, ab, lin, V, qd):
    """P <- F P F^T + the step's noise (+ bias random walks), in place.

    ``V`` (3, 15, 6) scratch: the noise Jacobians of the start and end samples and, for the
    consistent midpoint model, their combination; ``qd`` (6,) scratch.
    """
    V0 = V[0]
    Vn = V[1]
    if midpoint:
        _fill_noise_jac(V0, dt, rot[0], lin, 0.5, 0.5)
        _fill_noise_jac(Vn, dt, rot[1], lin, 0.5, 0.5)
    else:
        _fill_noise_jac(V0, dt, rot[0], lin, 1.0, 1.0)
    _rows_F(P, 15, dt, ab, lin)
    _cols_F_sym(P, dt, ab, lin)
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
        if first_step:  # sample 0's variance from its forward interval
            for m in range(6):
                qlast[m] = qd[m]
        G = V[2]
        for r in range(15):
            for c in range(6):
                G[r, c] = V1[r, c]
        _rows_F(G, 6, dt, ab, lin)
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


@jit
def preintegrate_kernel(t, gyro, accel, has_prev, params, method, cov_model, with_cov,
                        nav, P, J, V1, qlast, prev, sum_dt):
    """Consume samples ``t (N,), gyro (N, 3), accel (N, 3)``; update the state in place.

    If ``has_prev`` the first step goes from ``prev`` to sample 0. Returns the new
    ``delta_t`` (``sum_dt[0]`` is updated too).
    """
    return _preintegrate(t, gyro, accel, has_prev, params, method == METHOD_MIDPOINT, cov_model, with_cov,
                         nav, P, J, V1, qlast, prev, sum_dt,
                         np.empty((2, 7)), np.empty((3, 3)), np.zeros((3, 3)), np.empty((2, 3, 3)),
                         np.empty((2, 4)), np.zeros((5, 3, 3)), np.zeros((3, 15, 6)), np.empty(6))


@jit(nrt=False)
def _preintegrate(t, gyro, accel, has_prev, params, midpoint, cov_model, with_cov,
                  nav, P, J, V1, qlast, prev, sum_dt, ends, u, a, rot, dq, lin, V, qd):
    """The loop of :func:`preintegrate_kernel`, without reference counting (so no allocation).

    Scratch: ``ends`` (2, 7) the samples (t, gyro, accel) at the start and end of a step;
    ``u`` (3, 3) its bias-corrected inputs (specific force at both ends, body rate over the
    step); ``a`` (3, 3) zeros: the specific force at both ends in the start frame (``a[1]``
    stays 0 for Euler) and ``ab = a[2]`` the step's; ``rot`` (2, 3, 3) the delta rotation at
    both ends; ``dq`` (2, 4) Exp(w dt) and the new delta rotation as quaternions; ``lin``
    (5, 3, 3) zeros, the step's linearization; ``V`` (3, 15, 6) zeros and ``qd`` (6,) for
    :func:`_propagate_covariance`.
    """
    n = t.shape[0]
    w = u[2]
    ab = a[2]
    quat_wxyz_to_mat_into(nav[6], nav[7], nav[8], nav[9], rot[0])
    total = sum_dt[0]
    for k in range(0 if has_prev else 1, n):
        if k == 0:
            for m in range(7):
                ends[0, m] = prev[m]
        else:
            _load_sample(t, gyro, accel, k - 1, ends[0])
        _load_sample(t, gyro, accel, k, ends[1])
        dt = ends[1, 0] - ends[0, 0]
        _step_inputs(ends, params, midpoint, u)

        # rotation: R1 = R0 Exp(w dt)
        so3_exp_quat_wxyz_into(w[0] * dt, w[1] * dt, w[2] * dt, dq[0])
        quat_wxyz_mul_into(nav[6:10], dq[0], dq[1])
        quat_wxyz_normalize_into(dq[1, 0], dq[1, 1], dq[1, 2], dq[1, 3], dq[1])
        quat_wxyz_to_mat_into(dq[1, 0], dq[1, 1], dq[1, 2], dq[1, 3], rot[1])

        # start-frame accelerations, ab over the step
        _rotate_into(rot[0], u[0], a[0])
        if midpoint:
            _rotate_into(rot[1], u[1], a[1])
            for c in range(3):
                ab[c] = 0.5 * (a[0, c] + a[1, c])
        else:
            for c in range(3):
                ab[c] = a[0, c]

        # linearization; the Jacobian w.r.t. the start error state (its columns for theta, b_a, b_g)
        _linearize(rot, w, dt, a[1], midpoint, lin)
        _rows_F(J, 9, dt, ab, lin)
        if with_cov:
            _propagate_covariance(P, V1, qlast, params, dt, total == 0.0, midpoint, cov_model, rot, ab, lin, V, qd)

        # nominal state
        h2 = 0.5 * dt * dt
        for c in range(3):
            nav[c] += nav[3 + c] * dt + h2 * ab[c]
            nav[3 + c] += dt * ab[c]
        for m in range(4):
            nav[6 + m] = dq[1, m]
        for r in range(3):
            for c in range(3):
                rot[0, r, c] = rot[1, r, c]
        total += dt

    if n > 0:
        _load_sample(t, gyro, accel, n - 1, prev)
    sum_dt[0] = total
    return total
