"""Preintegrated quantities (deltas) between two instants: exact ones from states or a motion
source, their error ``truth (-) estimate`` and its normalized squared size (NEES).

With ``g_w`` world gravity and ``dt = t_j - t_i``::

    Delta q = q_i^{-1} q_j,
    Delta v = R_i^T (v_j - v_i - g_w dt),
    Delta p = R_i^T (p_j - p_i - v_i dt - g_w dt^2 / 2).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import SplineImuError
from ..lie import matrix_to_quat_xyzw, quat_xyzw_to_matrix, so3_log
from ..motion import DEFAULT_GRAVITY

__all__ = ["Deltas", "ExactDeltas", "deltas_from_states", "exact_deltas", "delta_error", "nees"]


@dataclass
class Deltas:
    """Preintegrated quantities between two instants, in the body frame of the first.

    Attributes
    ----------
    delta_p : (3,) ``R_i^T (p_j - p_i - v_i dt - g dt^2 / 2)`` [m]
    delta_v : (3,) ``R_i^T (v_j - v_i - g dt)`` [m/s]
    delta_q_xyzw : (4,) ``q_i^{-1} q_j`` (Hamilton, ``w >= 0``)
    delta_t_s : float, ``t_j - t_i`` [s]
    """

    delta_p: np.ndarray
    delta_v: np.ndarray
    delta_q_xyzw: np.ndarray
    delta_t_s: float

    @property
    def delta_R(self) -> np.ndarray:
        """(3, 3) rotation matrix of :attr:`delta_q_xyzw`."""
        return quat_xyzw_to_matrix(self.delta_q_xyzw)


@dataclass
class ExactDeltas(Deltas):
    """:class:`Deltas` computed from a motion source, with the states at both ends.

    Extra attributes
    ----------------
    t_i_s, t_j_s : float
    position_i, velocity_i, position_j, velocity_j : (3,) world frame
    quat_i_xyzw, quat_j_xyzw : (4,) ``world_R_body``
    relative_position : (3,) ``R_i^T (p_j - p_i)``, the body-frame displacement [m]
    """

    t_i_s: float = 0.0
    t_j_s: float = 0.0
    position_i: np.ndarray = field(default_factory=lambda: np.zeros(3))
    quat_i_xyzw: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.0, 1.0]))
    velocity_i: np.ndarray = field(default_factory=lambda: np.zeros(3))
    position_j: np.ndarray = field(default_factory=lambda: np.zeros(3))
    quat_j_xyzw: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.0, 1.0]))
    velocity_j: np.ndarray = field(default_factory=lambda: np.zeros(3))
    relative_position: np.ndarray = field(default_factory=lambda: np.zeros(3))


def deltas_from_states(p_i, R_i, v_i, p_j, R_j, v_j, dt, gravity=DEFAULT_GRAVITY):
    """``(Delta p, Delta v, Delta q_xyzw)`` of two states ``dt`` seconds apart (see the module notes).

    Examples
    --------
    >>> I = np.eye(3)
    >>> dp, dv, dq = deltas_from_states(np.zeros(3), I, np.zeros(3), np.zeros(3), I, np.zeros(3), 1.0)
    >>> dp.tolist(), dv.tolist(), dq.tolist()
    ([0.0, 0.0, 4.905], [0.0, 0.0, 9.81], [0.0, 0.0, 0.0, 1.0])
    """
    g = np.asarray(gravity, dtype=np.float64)
    dR = R_i.T @ R_j
    dp = R_i.T @ (p_j - p_i - v_i * dt - 0.5 * g * dt * dt)
    dv = R_i.T @ (v_j - v_i - g * dt)
    return dp, dv, matrix_to_quat_xyzw(dR)


def exact_deltas(source, t_i_s, t_j_s, gravity=DEFAULT_GRAVITY) -> ExactDeltas:
    """Exact, bias-free preintegrated quantities of a motion source between two times.

    Parameters
    ----------
    source : splineimu.motion.MotionSource
        A fitted spline or an analytic scene.
    t_i_s, t_j_s : float
        Start and end, seconds in the source's time base.
    gravity : (3,) array_like, default (0, 0, -9.81)
        World gravity ``g_w``; must be the value the IMU samples were made with.

    Returns
    -------
    ExactDeltas
        ``delta_q = q_i^{-1} q_j``, ``delta_v = R_i^T (v_j - v_i - g dt)``,
        ``delta_p = R_i^T (p_j - p_i - v_i dt - g dt^2 / 2)``, plus both states.

    Raises
    ------
    RangeError
        A time outside the source's valid range.

    Notes
    -----
    These are what a preintegrator fed with the source's ideal IMU
    (``source.imu(t, gravity)``) converges to as the sample interval goes to zero.

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> d = exact_deltas(make_scene("static"), 0.0, 1.0)
    >>> d.delta_v.round(12) + 0.0, d.delta_p.round(12) + 0.0
    (array([0.  , 0.  , 9.81]), array([0.   , 0.   , 4.905]))
    """
    t = source.check_times([t_i_s, t_j_s], "t_i_s, t_j_s")
    kin = source.kinematics(t)
    dt = float(t[1] - t[0])
    R_i, R_j = kin.world_R_body[0], kin.world_R_body[1]
    p_i, p_j = kin.position_world[0], kin.position_world[1]
    v_i, v_j = kin.velocity_world[0], kin.velocity_world[1]
    dp, dv, dq = deltas_from_states(p_i, R_i, v_i, p_j, R_j, v_j, dt, gravity)
    q = matrix_to_quat_xyzw(kin.world_R_body)
    return ExactDeltas(
        delta_p=dp, delta_v=dv, delta_q_xyzw=dq, delta_t_s=dt,
        t_i_s=float(t[0]), t_j_s=float(t[1]),
        position_i=p_i.copy(), quat_i_xyzw=q[0], velocity_i=v_i.copy(),
        position_j=p_j.copy(), quat_j_xyzw=q[1], velocity_j=v_j.copy(),
        relative_position=R_i.T @ (p_j - p_i),
    )


def delta_error(estimate, truth) -> np.ndarray:
    """``truth (-) estimate`` of two :class:`Deltas` as a (9,) vector ``(dp, dtheta, dv)``.

    ``dtheta = Log(Delta R_est^T Delta R_true)`` (right perturbation), the sense and order of
    the first nine rows of :meth:`Preintegrator.residual` and :attr:`Preintegrator.covariance`.
    """
    e = np.empty(9)
    e[0:3] = np.asarray(truth.delta_p) - np.asarray(estimate.delta_p)
    e[3:6] = so3_log(estimate.delta_R.T @ truth.delta_R)
    e[6:9] = np.asarray(truth.delta_v) - np.asarray(estimate.delta_v)
    return e


def nees(error, covariance) -> float:
    """Normalized estimation error squared ``e^T C^{-1} e`` (via a Cholesky solve).

    Raises
    ------
    SplineImuError
        ``covariance`` is not positive definite (e.g. the 9x9 block of a one-step window, where
        p and v are driven by the same noise).
    """
    e = np.asarray(error, dtype=np.float64)
    C = np.asarray(covariance, dtype=np.float64)
    try:
        L = np.linalg.cholesky(C)
    except np.linalg.LinAlgError:
        raise SplineImuError("the covariance is not positive definite: no NEES") from None
    z = np.linalg.solve(L, e)
    return float(z @ z)
