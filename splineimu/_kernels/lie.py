"""SO3 / SE3 kernels on rotation matrices and (w, x, y, z) quaternions.

Conventions: right perturbation on the manifold, SE3 tangent order ``[rho, phi]``
(translation first). This module holds the one implementation of Exp, Log and their
Jacobians: single-element functions (``*_into``) that write into preallocated outputs so that
other kernels call them inside hot loops without allocating, and ``*_batch`` kernels that are
nothing but a loop of one element function over samples (tests check them bit for bit).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import jit

#: Below this angle Exp uses its Taylor series (terms to theta^4, error ~ theta^6 / 5040).
EXP_SMALL_ANGLE = 1e-4
#: Below this |v| / w Log uses its series (error ~ (n/w)^4).
LOG_SMALL_ANGLE = 1e-6
#: Below this angle the SO3 Jacobian coefficients use their Taylor series (terms to t^8,
#: error < 3e-18). The closed forms of (t - sin t)/t^3 and 1/t^2 - cot(t/2)/(2t) lose
#: ~ eps / t^2 relative to cancellation, so the switch is made late (1e-2 left 4e-12).
JAC_SMALL_ANGLE = 1e-1
#: Below this angle the SE3 Jacobian's Q-block coefficients use their Taylor series (terms to
#: t^12, error < 1e-18). Their closed forms lose ~ eps / t^4 to cancellation (in the Q block
#: ~ eps / t: 1.5e-14 at 0.1, 6e-16 at 0.5), so the switch is made late.
SE3_Q_SMALL_ANGLE = 0.5


@jit(inline="always")
def so3_exp_coeffs(t2):
    """The coefficients of Exp for t^2 = t2: (sin t/t, (1 - cos t)/t^2) of the matrix
    I + a K + b K^2 and (cos(t/2), sin(t/2)/t) of the quaternion. Below EXP_SMALL_ANGLE all by
    their series to t^4 (error < t^6 / 5040)."""
    if t2 < EXP_SMALL_ANGLE * EXP_SMALL_ANGLE:
        a = 1.0 - t2 / 6.0 + t2 * t2 / 120.0
        b = 0.5 - t2 / 24.0 + t2 * t2 / 720.0
        c = 1.0 - t2 / 8.0 + t2 * t2 / 384.0
        s = 0.5 - t2 / 48.0 + t2 * t2 / 3840.0
    else:
        t = math.sqrt(t2)
        a = math.sin(t) / t
        s = math.sin(0.5 * t) / t
        b = 2.0 * s * s
        c = math.cos(0.5 * t)
    return a, b, c, s


@jit
def so3_exp_into(x, y, z, R):
    """R = Exp([x, y, z]) = I + a K + b K^2 (Rodrigues; coefficients from so3_exp_coeffs)."""
    a, b, _, _ = so3_exp_coeffs(x * x + y * y + z * z)
    xx = x * x
    yy = y * y
    zz = z * z
    xy = x * y
    xz = x * z
    yz = y * z
    R[0, 0] = 1.0 - b * (yy + zz)
    R[0, 1] = b * xy - a * z
    R[0, 2] = b * xz + a * y
    R[1, 0] = b * xy + a * z
    R[1, 1] = 1.0 - b * (xx + zz)
    R[1, 2] = b * yz - a * x
    R[2, 0] = b * xz - a * y
    R[2, 1] = b * yz + a * x
    R[2, 2] = 1.0 - b * (xx + yy)


@jit
def mat_to_quat_wxyz_into(R, q):
    """Shepperd's method: the largest of (trace, diagonal) picks the stable branch; w >= 0."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr >= R[0, 0] and tr >= R[1, 1] and tr >= R[2, 2]:
        s = math.sqrt(1.0 + tr) * 2.0
        w = 0.25 * s
        x = (R[2, 1] - R[1, 2]) / s
        y = (R[0, 2] - R[2, 0]) / s
        z = (R[1, 0] - R[0, 1]) / s
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        s = math.sqrt(max(1.0 + R[0, 0] - R[1, 1] - R[2, 2], 0.0)) * 2.0
        w = (R[2, 1] - R[1, 2]) / s
        x = 0.25 * s
        y = (R[0, 1] + R[1, 0]) / s
        z = (R[0, 2] + R[2, 0]) / s
    elif R[1, 1] >= R[2, 2]:
        s = math.sqrt(max(1.0 + R[1, 1] - R[0, 0] - R[2, 2], 0.0)) * 2.0
        w = (R[0, 2] - R[2, 0]) / s
        x = (R[0, 1] + R[1, 0]) / s
        y = 0.25 * s
        z = (R[1, 2] + R[2, 1]) / s
    else:
        s = math.sqrt(max(1.0 + R[2, 2] - R[0, 0] - R[1, 1], 0.0)) * 2.0
        w = (R[1, 0] - R[0, 1]) / s
        x = (R[0, 2] + R[2, 0]) / s
        y = (R[1, 2] + R[2, 1]) / s
        z = 0.25 * s
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    quat_wxyz_normalize_into(w, x, y, z, q)


@jit(inline="always")
def quat_wxyz_normalize_into(w, x, y, z, q):
    """q = (w, x, y, z) / |(w, x, y, z)|."""
    n = math.sqrt(w * w + x * x + y * y + z * z)
    q[0] = w / n
    q[1] = x / n
    q[2] = y / n
    q[3] = z / n


@jit(inline="always")
def quat_wxyz_mul_into(a, b, q):
    """Hamilton product q = a * b of (w, x, y, z) quaternions (q must not alias a or b)."""
    q[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3]
    q[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2]
    q[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1]
    q[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]


@jit(inline="always")
def so3_exp_quat_wxyz_into(x, y, z, q):
    """q = Exp([x, y, z]) as a unit quaternion: (cos(t/2), sin(t/2)/t [x, y, z])."""
    _, _, c, s = so3_exp_coeffs(x * x + y * y + z * z)
    q[0] = c
    q[1] = s * x
    q[2] = s * y
    q[3] = s * z


@jit
def quat_wxyz_to_mat_into(w, x, y, z, R):
    """Rotation matrix of a (not necessarily unit) quaternion; it is normalized first."""
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w /= n
    x /= n
    y /= n
    z /= n
    R[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    R[0, 1] = 2.0 * (x * y - w * z)
    R[0, 2] = 2.0 * (x * z + w * y)
    R[1, 0] = 2.0 * (x * y + w * z)
    R[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    R[1, 2] = 2.0 * (y * z - w * x)
    R[2, 0] = 2.0 * (x * z - w * y)
    R[2, 1] = 2.0 * (y * z + w * x)
    R[2, 2] = 1.0 - 2.0 * (x * x + y * y)


@jit
def quat_wxyz_log_into(w, x, y, z, phi):
    """phi = Log(q) for a unit quaternion, either sign: 2 atan2(|v|, |w|) v/|v| sign(w)."""
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    n2 = x * x + y * y + z * z
    n = math.sqrt(n2)
    if n < LOG_SMALL_ANGLE * w:
        # 2 atan(n/w)/n = (2/w) (1 - (n/w)^2 / 3 + ...)
        r2 = n2 / (w * w)
        scale = 2.0 / w * (1.0 - r2 / 3.0)
    else:
        scale = 2.0 * math.atan2(n, w) / n
    phi[0] = scale * x
    phi[1] = scale * y
    phi[2] = scale * z


@jit
def so3_log_into(R, q_scratch, phi):
    """phi = Log(R), |phi| <= pi; stable near 0 and near pi (through the quaternion)."""
    mat_to_quat_wxyz_into(R, q_scratch)
    quat_wxyz_log_into(q_scratch[0], q_scratch[1], q_scratch[2], q_scratch[3], phi)


@jit
def so3_jac_coeffs(t2):
    """(a, b, c) with sin t/t, (1 - cos t)/t^2, (t - sin t)/t^3 for t^2 = t2."""
    if t2 < JAC_SMALL_ANGLE * JAC_SMALL_ANGLE:
        a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0)))
        b = 0.5 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0))))
        c = (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0 * (1.0 - t2 / 110.0)))) / 6.0
    else:
        t = math.sqrt(t2)
        st = math.sin(t)
        a = st / t
        s = math.sin(0.5 * t) / t
        b = 2.0 * s * s
        c = (t - st) / (t2 * t)
    return a, b, c


@jit
def so3_jac_inv_coeff(t2):
    """1/t^2 - cot(t/2) / (2 t): the K^2 coefficient of the inverse Jacobians."""
    if t2 < JAC_SMALL_ANGLE * JAC_SMALL_ANGLE:
        # sum_n |B_2n| t^(2n-2) / (2n)!
        return 1.0 / 12.0 + t2 * (1.0 / 720.0 + t2 * (1.0 / 30240.0 + t2 * (
            1.0 / 1209600.0 + t2 / 47900160.0)))
    t = math.sqrt(t2)
    h = 0.5 * t
    return 1.0 / t2 - math.cos(h) / (2.0 * t * math.sin(h))


@jit
def _i_plus_bk_ck2_into(x, y, z, b, c, J):
    """J = I + b K + c K^2 for K = [x, y, z]x (the form of every SO3 Jacobian and inverse)."""
    xx = x * x
    yy = y * y
    zz = z * z
    J[0, 0] = 1.0 - c * (yy + zz)
    J[0, 1] = -b * z + c * x * y
    J[0, 2] = b * y + c * x * z
    J[1, 0] = b * z + c * x * y
    J[1, 1] = 1.0 - c * (xx + zz)
    J[1, 2] = -b * x + c * y * z
    J[2, 0] = -b * y + c * x * z
    J[2, 1] = b * x + c * y * z
    J[2, 2] = 1.0 - c * (xx + yy)


@jit
def so3_jacobian_into(x, y, z, sign, J):
    """Right (sign = -1) or left (sign = +1) Jacobian: I + sign b K + c K^2."""
    _, b, c = so3_jac_coeffs(x * x + y * y + z * z)
    _i_plus_bk_ck2_into(x, y, z, sign * b, c, J)


@jit
def so3_jacobian_inv_into(x, y, z, sign, J):
    """Inverse right (sign = -1) or left (sign = +1) Jacobian: I - sign K/2 + d K^2."""
    d = so3_jac_inv_coeff(x * x + y * y + z * z)
    _i_plus_bk_ck2_into(x, y, z, -0.5 * sign, d, J)


@jit
def so3_hat_into(x, y, z, K):
    """K = [x, y, z]x, the skew-symmetric matrix with K v = [x, y, z] x v."""
    K[0, 0] = 0.0
    K[0, 1] = -z
    K[0, 2] = y
    K[1, 0] = z
    K[1, 1] = 0.0
    K[1, 2] = -x
    K[2, 0] = -y
    K[2, 1] = x
    K[2, 2] = 0.0


@jit
def se3_q_block_into(rho, phi, sign, Q, scratch):
    """Barfoot's Q(rho, phi) block of the left (sign = +1) SE3 Jacobian; sign = -1 gives
    Q(-rho, -phi), the block of the right Jacobian.

    scratch: (4, 3, 3) work array.
    """
    px = sign * phi[0]
    py = sign * phi[1]
    pz = sign * phi[2]
    P = scratch[0]
    Rh = scratch[1]
    A = scratch[2]
    B = scratch[3]
    so3_hat_into(px, py, pz, P)
    so3_hat_into(sign * rho[0], sign * rho[1], sign * rho[2], Rh)
    t2 = px * px + py * py + pz * pz
    if t2 < SE3_Q_SMALL_ANGLE * SE3_Q_SMALL_ANGLE:
        # c1 = sum (-t2)^k / (2k+3)!, c2 = sum (-t2)^k / (2k+4)!, c4 = sum (-t2)^k (k+1) / (2k+5)!
        c1 = (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0 * (1.0 - t2 / 110.0 * (
            1.0 - t2 / 156.0 * (1.0 - t2 / 210.0)))))) / 6.0
        c2 = (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0 * (1.0 - t2 / 132.0 * (
            1.0 - t2 / 182.0 * (1.0 - t2 / 240.0)))))) / 24.0
        c4 = (1.0 - t2 / 21.0 * (1.0 - t2 / 48.0 * (1.0 - t2 * (2.0 / 165.0) * (1.0 - t2 * (5.0 / 624.0) * (
            1.0 - t2 / 175.0 * (1.0 - t2 * (7.0 / 1632.0))))))) / 120.0
    else:
        t = math.sqrt(t2)
        st = math.sin(t)
        ct = math.cos(t)
        c1 = (t - st) / (t2 * t)
        c2 = (0.5 * t2 + ct - 1.0) / (t2 * t2)
        c4 = (2.0 * t - 3.0 * st + t * ct) / (2.0 * t2 * t2 * t)
    # A = P Rh, B = Rh P
    for i in range(3):
        for j in range(3):
            s1 = 0.0
            s2 = 0.0
            for m in range(3):
                s1 += P[i, m] * Rh[m, j]
                s2 += Rh[i, m] * P[m, j]
            A[i, j] = s1
            B[i, j] = s2
    for i in range(3):
        for j in range(3):
            prp = 0.0  # P Rh P
            pprh = 0.0  # P P Rh
            rhpp = 0.0  # Rh P P
            for m in range(3):
                prp += A[i, m] * P[m, j]
                pprh += P[i, m] * A[m, j]
                rhpp += B[i, m] * P[m, j]
            # P Rh P P and P P Rh P
            prpp = 0.0
            pprp = 0.0
            for m in range(3):
                for l in range(3):
                    prpp += A[i, m] * P[m, l] * P[l, j]
                    pprp += P[i, m] * A[m, l] * P[l, j]
            Q[i, j] = (
                0.5 * Rh[i, j]
                + c1 * (A[i, j] + B[i, j] + prp)
                + c2 * (pprh + rhpp - 3.0 * prp)
                + c4 * (prpp + pprp)
            )


@jit
def se3_exp_into(xi, R, t, J):
    """(R, t) = Exp(xi) for xi = [rho, phi]: R = Exp(phi), t = J_l(phi) rho. J: (3, 3) scratch."""
    so3_exp_into(xi[3], xi[4], xi[5], R)
    so3_jacobian_into(xi[3], xi[4], xi[5], 1.0, J)
    for r in range(3):
        t[r] = J[r, 0] * xi[0] + J[r, 1] * xi[1] + J[r, 2] * xi[2]


@jit
def se3_log_into(R, t, q, J, xi):
    """xi = Log((R, t)) = [J_l(phi)^-1 t, phi] with phi = Log(R). q: (4,), J: (3, 3) scratch."""
    so3_log_into(R, q, xi[3:])
    so3_jacobian_inv_into(xi[3], xi[4], xi[5], 1.0, J)
    for r in range(3):
        xi[r] = J[r, 0] * t[0] + J[r, 1] * t[1] + J[r, 2] * t[2]


@jit
def _zero_lower_left_into(J):
    for r in range(3):
        for c in range(3):
            J[3 + r, c] = 0.0


@jit
def se3_jacobian_into(xi, sign, J, scratch):
    """Left (sign = +1) or right (sign = -1) SE3 Jacobian (6, 6): [[J(phi), Q], [0, J(phi)]].

    scratch: (4, 3, 3) work array.
    """
    so3_jacobian_into(xi[3], xi[4], xi[5], sign, J[:3, :3])
    so3_jacobian_into(xi[3], xi[4], xi[5], sign, J[3:, 3:])
    se3_q_block_into(xi[:3], xi[3:], sign, J[:3, 3:], scratch)
    _zero_lower_left_into(J)


@jit
def se3_jacobian_inv_into(xi, sign, J, scratch):
    """Inverse left (sign = +1) or right (sign = -1) SE3 Jacobian: [[Ji, -Ji Q Ji], [0, Ji]].

    scratch: (5, 3, 3) work array (the Q block goes to scratch[4]).
    """
    so3_jacobian_inv_into(xi[3], xi[4], xi[5], sign, J[:3, :3])
    so3_jacobian_inv_into(xi[3], xi[4], xi[5], sign, J[3:, 3:])
    Q = scratch[4]
    se3_q_block_into(xi[:3], xi[3:], sign, Q, scratch)
    for r in range(3):
        for c in range(3):
            s = 0.0
            for m in range(3):
                for n in range(3):
                    s += J[r, m] * Q[m, n] * J[n, c]
            J[r, 3 + c] = -s
    _zero_lower_left_into(J)


@jit
def se3_adjoint_into(R, t, Ad):
    """Ad = [[R, [t]x R], [0, R]], so that T Exp(xi) T^-1 = Exp(Ad xi) for T = (R, t)."""
    for r in range(3):
        for c in range(3):
            Ad[r, c] = R[r, c]
            Ad[3 + r, 3 + c] = R[r, c]
            Ad[3 + r, c] = 0.0
    # [t]x R, column by column: t x R[:, c]
    for c in range(3):
        Ad[0, 3 + c] = t[1] * R[2, c] - t[2] * R[1, c]
        Ad[1, 3 + c] = t[2] * R[0, c] - t[0] * R[2, c]
        Ad[2, 3 + c] = t[0] * R[1, c] - t[1] * R[0, c]


# ----------------------------------------------------------------------------- batches
# Each is one element function in a loop (scratch allocated once); no arithmetic of its own.


@jit
def so3_hat_batch(phi, out):
    for i in range(phi.shape[0]):
        so3_hat_into(phi[i, 0], phi[i, 1], phi[i, 2], out[i])


@jit
def so3_exp_batch(phi, out):
    for i in range(phi.shape[0]):
        so3_exp_into(phi[i, 0], phi[i, 1], phi[i, 2], out[i])


@jit
def so3_log_batch(R, out):
    q = np.empty(4)
    for i in range(R.shape[0]):
        so3_log_into(R[i], q, out[i])


@jit
def quat_wxyz_log_batch(q, out):
    """Log of (w, x, y, z) quaternions of any norm and sign: normalized, then quat_wxyz_log_into."""
    u = np.empty(4)
    for i in range(q.shape[0]):
        quat_wxyz_normalize_into(q[i, 0], q[i, 1], q[i, 2], q[i, 3], u)
        quat_wxyz_log_into(u[0], u[1], u[2], u[3], out[i])


@jit
def mat_to_quat_wxyz_batch(R, out):
    for i in range(R.shape[0]):
        mat_to_quat_wxyz_into(R[i], out[i])


@jit
def quat_wxyz_to_mat_batch(q, out):
    for i in range(q.shape[0]):
        quat_wxyz_to_mat_into(q[i, 0], q[i, 1], q[i, 2], q[i, 3], out[i])


@jit
def so3_jacobian_batch(phi, sign, out):
    for i in range(phi.shape[0]):
        so3_jacobian_into(phi[i, 0], phi[i, 1], phi[i, 2], sign, out[i])


@jit
def so3_jacobian_inv_batch(phi, sign, out):
    for i in range(phi.shape[0]):
        so3_jacobian_inv_into(phi[i, 0], phi[i, 1], phi[i, 2], sign, out[i])


@jit
def se3_exp_batch(xi, out):
    """xi (N, 6) = [rho, phi] -> (N, 4, 4)."""
    J = np.empty((3, 3))
    for i in range(xi.shape[0]):
        T = out[i]
        se3_exp_into(xi[i], T[:3, :3], T[:3, 3], J)
        T[3, :3] = 0.0
        T[3, 3] = 1.0


@jit
def se3_log_batch(T, out):
    q = np.empty(4)
    J = np.empty((3, 3))
    for i in range(T.shape[0]):
        se3_log_into(T[i, :3, :3], T[i, :3, 3], q, J, out[i])


@jit
def se3_jacobian_batch(xi, sign, out):
    scratch = np.empty((4, 3, 3))
    for i in range(xi.shape[0]):
        se3_jacobian_into(xi[i], sign, out[i], scratch)


@jit
def se3_jacobian_inv_batch(xi, sign, out):
    scratch = np.empty((5, 3, 3))
    for i in range(xi.shape[0]):
        se3_jacobian_inv_into(xi[i], sign, out[i], scratch)


@jit
def se3_adjoint_batch(T, out):
    for i in range(T.shape[0]):
        se3_adjoint_into(T[i, :3, :3], T[i, :3, 3], out[i])
