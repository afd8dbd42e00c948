"""Strapdown dead-reckoning kernels (private; see :mod:`splineimu.integrate`).

State: ``R`` (world_R_body, a 3x3 matrix inside the loop), ``v`` (velocity_world), ``p``
(position_world). Inputs are the measured body rate and specific force at the sample times
``t[k]``; the constant biases are subtracted here. The ODE is

    dR/dt = R [w(t) - b_g]x,   dv/dt = R (f(t) - b_a) + g,   dp/dt = v.

Outputs are written per sample: ``q_out`` (N, 4) as (w, x, y, z), ``v_out`` and ``p_out``
(N, 3). After each step the rotation is re-projected onto SO3 through its unit quaternion
(the quaternion written to ``q_out``), so round-off cannot make it drift off the group.

The rk4 kernel takes the rate and specific force at each interval's midpoint as separate
arrays (``gyro_mid``, ``accel_mid``): :func:`interp_mid_kernel` fills them from point samples
with a 4-point Lagrange cubic; another source (e.g. delta-angle / delta-velocity increments)
only has to produce the same stage values. The three methods share one driver
(:func:`_strapdown`); they differ only in their step function.
"""

from __future__ import annotations

import numpy as np

from .._jit import jit
from .lie import mat_to_quat_wxyz_into, quat_wxyz_to_mat_into, so3_exp_into, so3_jacobian_inv_into

METHOD_EULER = 0
METHOD_MIDPOINT = 1
METHOD_RK4 = 2


@jit(inline="always")
def _matmul33_into(A, B, C):
    for i in range(3):
        a0 = A[i, 0]
        a1 = A[i, 1]
        a2 = A[i, 2]
        for j in range(3):
            C[i, j] = a0 * B[0, j] + a1 * B[1, j] + a2 * B[2, j]


@jit(inline="always")
def _copy33(A, B):
    """B = A (explicitly: a slice assignment may allocate for an overlap check)."""
    for i in range(3):
        for j in range(3):
            B[i, j] = A[i, j]


@jit(inline="always")
def _store_and_reproject(R, q_tmp, q_out, k):
    """Write R's quaternion to q_out[k] and replace R by the exact rotation of that quaternion."""
    mat_to_quat_wxyz_into(R, q_tmp)
    q_out[k, 0] = q_tmp[0]
    q_out[k, 1] = q_tmp[1]
    q_out[k, 2] = q_tmp[2]
    q_out[k, 3] = q_tmp[3]
    quat_wxyz_to_mat_into(q_tmp[0], q_tmp[1], q_tmp[2], q_tmp[3], R)


@jit(inline="always")
def _rot_exp_into(R, x, y, z, E, out):
    """out = R Exp([x, y, z]) (E: 3x3 scratch)."""
    so3_exp_into(x, y, z, E)
    _matmul33_into(R, E, out)


@jit
def interp_mid_kernel(t, x, out):
    """out[k] = x at 0.5 (t[k] + t[k+1]) by the Lagrange polynomial through 4 neighbouring
    samples (k-1 .. k+2, shifted to one side at the ends); with fewer than 4 samples, through
    all of them. Error O(h^4) for smooth x."""
    n = t.shape[0]
    m = 4 if n >= 4 else n
    w = np.empty(4)
    for k in range(n - 1):
        j0 = k - 1
        if j0 < 0:
            j0 = 0
        if j0 > n - m:
            j0 = n - m
        tm = 0.5 * (t[k] + t[k + 1])
        for a in range(m):
            num = 1.0
            den = 1.0
            ta = t[j0 + a]
            for b in range(m):
                if b != a:
                    tb = t[j0 + b]
                    num *= tm - tb
                    den *= ta - tb
            w[a] = num / den
        for c in range(x.shape[1]):
            s = 0.0
            for a in range(m):
                s += w[a] * x[j0 + a, c]
            out[k, c] = s


@jit(inline="always")
def _euler_step(R, v, p, k, h, gyro, accel, bias_gyro, bias_accel, g, S, a):
    """Forward Euler (the lecture's form): a = R_k f_k + g, p += v h + a h^2 / 2, v += a h,
    R_{k+1} = R_k Exp(w_k h). First order. S: (>= 2, 3, 3), a: (3,) scratch."""
    E = S[0]
    Rn = S[1]
    fx = accel[k, 0] - bias_accel[0]
    fy = accel[k, 1] - bias_accel[1]
    fz = accel[k, 2] - bias_accel[2]
    for c in range(3):
        a[c] = R[c, 0] * fx + R[c, 1] * fy + R[c, 2] * fz + g[c]
    for c in range(3):
        p[c] += v[c] * h + 0.5 * a[c] * h * h
        v[c] += a[c] * h
    _rot_exp_into(
        R,
        (gyro[k, 0] - bias_gyro[0]) * h,
        (gyro[k, 1] - bias_gyro[1]) * h,
        (gyro[k, 2] - bias_gyro[2]) * h,
        E,
        Rn,
    )
    _copy33(Rn, R)


@jit(inline="always")
def _midpoint_step(R, v, p, k, h, gyro, accel, bias_gyro, bias_accel, g, S, a):
    """Midpoint (the lecture's form): R_{k+1} = R_k Exp((w_k + w_{k+1}) h / 2),
    a = ((R_k f_k + g) + (R_{k+1} f_{k+1} + g)) / 2, p += v h + a h^2 / 2, v += a h.
    Second order. S: (>= 2, 3, 3), a: (3,) scratch."""
    E = S[0]
    Rn = S[1]
    hh = 0.5 * h
    _rot_exp_into(
        R,
        (gyro[k, 0] + gyro[k + 1, 0] - 2.0 * bias_gyro[0]) * hh,
        (gyro[k, 1] + gyro[k + 1, 1] - 2.0 * bias_gyro[1]) * hh,
        (gyro[k, 2] + gyro[k + 1, 2] - 2.0 * bias_gyro[2]) * hh,
        E,
        Rn,
    )
    f0x = accel[k, 0] - bias_accel[0]
    f0y = accel[k, 1] - bias_accel[1]
    f0z = accel[k, 2] - bias_accel[2]
    f1x = accel[k + 1, 0] - bias_accel[0]
    f1y = accel[k + 1, 1] - bias_accel[1]
    f1z = accel[k + 1, 2] - bias_accel[2]
    for c in range(3):
        a0 = R[c, 0] * f0x + R[c, 1] * f0y + R[c, 2] * f0z
        a1 = Rn[c, 0] * f1x + Rn[c, 1] * f1y + Rn[c, 2] * f1z
        a[c] = 0.5 * (a0 + a1) + g[c]
    for c in range(3):
        p[c] += v[c] * h + 0.5 * a[c] * h * h
        v[c] += a[c] * h
    _copy33(Rn, R)


@jit(inline="always")
def _stage(R, theta, w, f, bias_gyro, bias_accel, g, E, Rs, J, k_th, k_v):
    """One Munthe-Kaas stage at the chart point theta (rotation R Exp(theta)):
    k_th = dexp^-1_theta(w - b_g) = J_r^-1(theta) (w - b_g),  k_v = R Exp(theta) (f - b_a) + g."""
    _rot_exp_into(R, theta[0], theta[1], theta[2], E, Rs)
    so3_jacobian_inv_into(theta[0], theta[1], theta[2], -1.0, J)
    wx = w[0] - bias_gyro[0]
    wy = w[1] - bias_gyro[1]
    wz = w[2] - bias_gyro[2]
    fx = f[0] - bias_accel[0]
    fy = f[1] - bias_accel[1]
    fz = f[2] - bias_accel[2]
    for c in range(3):
        k_th[c] = J[c, 0] * wx + J[c, 1] * wy + J[c, 2] * wz
        k_v[c] = Rs[c, 0] * fx + Rs[c, 1] * fy + Rs[c, 2] * fz + g[c]


@jit(inline="always")
def _rk4_step(R, v, p, k, h, gyro, accel, gyro_mid, accel_mid, bias_gyro, bias_accel, g, S, kv):
    """Munthe-Kaas RK4 on SO3 x R3 x R3: classical RK4 in the chart R = R_k Exp(theta), whose
    ODE is theta' = J_r^-1(theta) w, with the stage values at t_k, t_k + h/2 (twice) and
    t_{k+1}. Fourth order when the midpoint values are fourth-order accurate.
    S: (4, 3, 3), kv: (9, 3) scratch."""
    E = S[0]
    Rn = S[1]
    Rs = S[2]
    J = S[3]
    th = kv[0]
    k1t = kv[1]
    k2t = kv[2]
    k3t = kv[3]
    k4t = kv[4]
    k1v = kv[5]
    k2v = kv[6]
    k3v = kv[7]
    k4v = kv[8]
    hh = 0.5 * h
    # stage 1: theta = 0
    th[0] = 0.0
    th[1] = 0.0
    th[2] = 0.0
    _stage(R, th, gyro[k], accel[k], bias_gyro, bias_accel, g, E, Rs, J, k1t, k1v)
    # stage 2
    for c in range(3):
        th[c] = hh * k1t[c]
    _stage(R, th, gyro_mid[k], accel_mid[k], bias_gyro, bias_accel, g, E, Rs, J, k2t, k2v)
    # stage 3
    for c in range(3):
        th[c] = hh * k2t[c]
    _stage(R, th, gyro_mid[k], accel_mid[k], bias_gyro, bias_accel, g, E, Rs, J, k3t, k3v)
    # stage 4
    for c in range(3):
        th[c] = h * k3t[c]
    _stage(R, th, gyro[k + 1], accel[k + 1], bias_gyro, bias_accel, g, E, Rs, J, k4t, k4v)
    h6 = h / 6.0
    for c in range(3):
        th[c] = h6 * (k1t[c] + 2.0 * k2t[c] + 2.0 * k3t[c] + k4t[c])
    # p stages: k1p = v, k2p = v + h/2 k1v, k3p = v + h/2 k2v, k4p = v + h k3v
    for c in range(3):
        p[c] += h * v[c] + h6 * h * (k1v[c] + k2v[c] + k3v[c])
        v[c] += h6 * (k1v[c] + 2.0 * k2v[c] + 2.0 * k3v[c] + k4v[c])
    _rot_exp_into(R, th[0], th[1], th[2], E, Rn)
    _copy33(Rn, R)


@jit(inline="always")
def _store(R, v, p, q, k, q_out, v_out, p_out):
    """Row k of the outputs; R is re-projected through its quaternion (q: (4,) scratch)."""
    _store_and_reproject(R, q, q_out, k)
    for c in range(3):
        v_out[k, c] = v[c]
        p_out[k, c] = p[c]


@jit
def _strapdown(method, t, gyro, accel, gyro_mid, accel_mid, bias_gyro, bias_accel, g, R0, v0, p0,
               q_out, v_out, p_out):
    """The one integration: state from (R0, v0, p0), one step of ``method`` per interval."""
    _strapdown_loop(method, t, gyro, accel, gyro_mid, accel_mid, bias_gyro, bias_accel, g,
                    R0.copy(), v0.copy(), p0.copy(), np.empty(4), np.empty((4, 3, 3)), np.empty((9, 3)),
                    q_out, v_out, p_out)


@jit(nrt=False)
def _strapdown_loop(method, t, gyro, accel, gyro_mid, accel_mid, bias_gyro, bias_accel, g, R, v, p, q, S, kv,
                    q_out, v_out, p_out):
    """The loop of :func:`_strapdown` on the state (R, v, p), in place and without reference
    counting (q, S, kv: scratch)."""
    _store(R, v, p, q, 0, q_out, v_out, p_out)
    for k in range(t.shape[0] - 1):
        h = t[k + 1] - t[k]
        if method == METHOD_EULER:
            _euler_step(R, v, p, k, h, gyro, accel, bias_gyro, bias_accel, g, S, kv[0])
        elif method == METHOD_MIDPOINT:
            _midpoint_step(R, v, p, k, h, gyro, accel, bias_gyro, bias_accel, g, S, kv[0])
        else:
            _rk4_step(R, v, p, k, h, gyro, accel, gyro_mid, accel_mid, bias_gyro, bias_accel, g, S, kv)
        _store(R, v, p, q, k + 1, q_out, v_out, p_out)


@jit
def euler_kernel(t, gyro, accel, bias_gyro, bias_accel, g, R0, v0, p0, q_out, v_out, p_out):
    """Forward Euler, first order (see :func:`_euler_step`)."""
    _strapdown(METHOD_EULER, t, gyro, accel, gyro, accel, bias_gyro, bias_accel, g, R0, v0, p0, q_out, v_out, p_out)


@jit
def midpoint_kernel(t, gyro, accel, bias_gyro, bias_accel, g, R0, v0, p0, q_out, v_out, p_out):
    """Midpoint, second order (see :func:`_midpoint_step`)."""
    _strapdown(METHOD_MIDPOINT, t, gyro, accel, gyro, accel, bias_gyro, bias_accel, g, R0, v0, p0,
               q_out, v_out, p_out)


@jit
def rk4_kernel(
    t, gyro, accel, gyro_mid, accel_mid, bias_gyro, bias_accel, g, R0, v0, p0, q_out, v_out, p_out
):
    """Munthe-Kaas RK4, fourth order (see :func:`_rk4_step`); ``gyro_mid``, ``accel_mid``
    (N - 1, 3) are the values at the interval midpoints."""
    _strapdown(METHOD_RK4, t, gyro, accel, gyro_mid, accel_mid, bias_gyro, bias_accel, g, R0, v0, p0,
               q_out, v_out, p_out)
