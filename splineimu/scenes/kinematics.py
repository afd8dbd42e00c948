"""Closed-form rotation kinematics shared by the scenes: ZYX Euler angles, yaw rotations, sums of sines.

Examples
--------
>>> R, w, al = euler_zyx_kinematics([[0.0, 0.0, 0.3]], [[0.0, 0.0, 2.0]], [[0.0, 0.0, 0.0]])
>>> w.tolist(), bool(np.allclose(R[0], rotation_z(0.3)))
([[0.0, 0.0, 2.0]], True)
"""

from __future__ import annotations

import numpy as np

from ..exactfloat import turn

__all__ = ["euler_zyx_kinematics", "rotation_z", "sum_of_sines"]


def rotation_z(yaw):
    """``Rz(yaw)`` (..., 3, 3) for any shape of ``yaw`` [rad]."""
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.zeros(np.shape(yaw) + (3, 3))
    R[..., 0, 0] = c
    R[..., 0, 1] = -s
    R[..., 1, 0] = s
    R[..., 1, 1] = c
    R[..., 2, 2] = 1.0
    return R


def euler_zyx_kinematics(angles, rates, accels):
    """Rotation, body rate and body angular acceleration of ZYX Euler angles, exactly.

    Parameters
    ----------
    angles, rates, accels : (N, 3) array_like
        ``(roll, pitch, yaw)`` [rad] and their first [rad/s] and second [rad/s^2] time
        derivatives.

    Returns
    -------
    world_R_body : (N, 3, 3)
        ``Rz(yaw) Ry(pitch) Rx(roll)``.
    omega_body : (N, 3)
        ``E(r, p) (dr, dp, dy)``.
    alpha_body : (N, 3)
        ``dE/dt (dr, dp, dy) + E(r, p) (ddr, ddp, ddy)``.

    Notes
    -----
    With ``R = Rz(y) Ry(p) Rx(r)`` the body rate ``R^T dR/dt = [omega]x`` is
    ``omega = dr e_x + Rx^T (dp e_y) + Rx^T Ry^T (dy e_z) = E (dr, dp, dy)``::

        E = [[1,       0,        -sin p],
             [0,  cos r,   sin r cos p],
             [0, -sin r,   cos r cos p]]

    and, differentiating each entry,::

        dE/dt = [[0,            0,                         -cos p dp],
                 [0, -sin r dr,   cos r cos p dr - sin r sin p dp],
                 [0, -cos r dr,  -sin r cos p dr - cos r sin p dp]]

    The forward map has no singularity (only its inverse does at ``|p| = pi/2``), so
    angles may ramp through any number of full turns.
    """
    ang = np.asarray(angles, dtype=np.float64)
    rt = np.asarray(rates, dtype=np.float64)
    ac = np.asarray(accels, dtype=np.float64)
    r, p, y = ang[:, 0], ang[:, 1], ang[:, 2]
    dr, dp, dy = rt[:, 0], rt[:, 1], rt[:, 2]
    ddr, ddp, ddy = ac[:, 0], ac[:, 1], ac[:, 2]
    cr, sr = np.cos(r), np.sin(r)
    cp, sp = np.cos(p), np.sin(p)
    cy, sy = np.cos(y), np.sin(y)

    R = np.empty((ang.shape[0], 3, 3))
    R[:, 0, 0] = cy * cp
    R[:, 0, 1] = cy * sp * sr - sy * cr
    R[:, 0, 2] = cy * sp * cr + sy * sr
    R[:, 1, 0] = sy * cp
    R[:, 1, 1] = sy * sp * sr + cy * cr
    R[:, 1, 2] = sy * sp * cr - cy * sr
    R[:, 2, 0] = -sp
    R[:, 2, 1] = cp * sr
    R[:, 2, 2] = cp * cr

    w = np.empty((ang.shape[0], 3))
    w[:, 0] = dr - sp * dy
    w[:, 1] = cr * dp + sr * cp * dy
    w[:, 2] = -sr * dp + cr * cp * dy

    al = np.empty((ang.shape[0], 3))
    al[:, 0] = ddr - sp * ddy - cp * dp * dy
    al[:, 1] = (cr * ddp + sr * cp * ddy
                - sr * dr * dp + (cr * cp * dr - sr * sp * dp) * dy)
    al[:, 2] = (-sr * ddp + cr * cp * ddy
                - cr * dr * dp + (-sr * cp * dr - cr * sp * dp) * dy)
    return R, w, al


def sum_of_sines(t, table, scale=1.0):
    """``x = scale sum_j A_j sin(w_j t + phi_j)`` and its first two derivatives, (N,) each."""
    x = np.zeros_like(t)
    dx = np.zeros_like(t)
    ddx = np.zeros_like(t)
    for amp, om, ph in table:
        arg = turn(om, t, ph)
        s, c = np.sin(arg), np.cos(arg)
        x += amp * s
        dx += amp * om * c
        ddx -= amp * om * om * s
    return scale * x, scale * dx, scale * ddx
