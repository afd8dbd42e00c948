"""Fast whole-body motions: ``screw`` (constant body twist) and ``flips`` (hand-held tumbling).

Examples
--------
>>> from splineimu.scenes import make_scene
>>> make_scene("screw").kinematics([0.0, 5.0]).omega_body.tolist()
[[0.1, -0.2, 0.6], [0.1, -0.2, 0.6]]
"""

from __future__ import annotations

import numpy as np

from ..exactfloat import turn
from .base import Param, Scene, register_scene
from .kinematics import euler_zyx_kinematics, sum_of_sines

__all__ = ["ScrewScene", "FlipsScene"]


@register_scene("screw")
class ScrewScene(Scene):
    """Constant body twist: ``world_T_body(t) = T0 Exp(t xi)``, a screw (helix) motion.

    Formulas (``xi = [v_b, w_b]``, SE3 tangent order translation first;
    ``T0 = (Exp(initial_rotvec_rad), initial_position_m)``)::

        world_T_body(t) = T0 Exp(t xi)             (splineimu.lie.se3_exp)
        omega_body      = w_b,        alpha_body = 0
        velocity_world  = R(t) v_b
        accel_world     = R(t) (w_b x v_b)

    since ``T^-1 dT/dt = xi^`` is constant. This is the motion an SE3 spline reproduces
    exactly from its control points.

    Default duration: 20 s.

    Parameters
    ----------
    v_body_m_s : (3,) float, default (1.0, 0.0, 0.2)
        Linear part ``v_b`` of the body twist [m/s].
    omega_body_rad_s : (3,) float, default (0.1, -0.2, 0.6)
        Angular part ``w_b`` of the body twist [rad/s].
    initial_position_m : (3,) float, default (0, 0, 1)
        Position at t = 0 [m].
    initial_rotvec_rad : (3,) float, default (0, 0, 0)
        Orientation at t = 0 as a rotation vector ``Log(R0)`` [rad].
    """

    DEFAULT_DURATION_S = 20.0
    PARAMS = {
        "v_body_m_s": Param((1.0, 0.0, 0.2), "m/s", "linear part of the body twist"),
        "omega_body_rad_s": Param((0.1, -0.2, 0.6), "rad/s", "angular part of the body twist"),
        "initial_position_m": Param((0.0, 0.0, 1.0), "m", "position at t = 0"),
        "initial_rotvec_rad": Param((0.0, 0.0, 0.0), "rad", "orientation at t = 0 (rotation vector)"),
    }

    def _setup(self):
        from ..lie import so3_exp

        self._R0 = so3_exp(self.params["initial_rotvec_rad"])
        self._p0 = np.array(self.params["initial_position_m"])
        self._xi = np.concatenate([self.params["v_body_m_s"], self.params["omega_body_rad_s"]])

    @property
    def world_T_body0(self) -> np.ndarray:
        """``T0`` (4, 4)."""
        return np.vstack([np.column_stack([self._R0, self._p0]), [0.0, 0.0, 0.0, 1.0]])

    @property
    def twist_body(self) -> np.ndarray:
        """``xi = [v_b, w_b]`` (6,)."""
        return self._xi.copy()

    def _evaluate(self, t):
        from ..lie import se3_exp

        n = t.shape[0]
        E = se3_exp(t[:, None] * self._xi[None, :])
        Rrel = E[:, :3, :3]
        R = np.matmul(self._R0, Rrel)
        p = E[:, :3, 3] @ self._R0.T + self._p0
        vb = self._xi[:3]
        wb = self._xi[3:]
        v = R @ vb
        a = R @ np.cross(wb, vb)
        om = np.empty((n, 3))
        om[:] = wb
        return p, v, a, R, om, np.zeros((n, 3))


# Coefficient tables of the flips scene: (amplitude, angular frequency [rad/s], phase [rad]).
_FLIPS_ANGLE_SINES = (
    ((0.90, 6.0, 0.0), (0.12, 17.0, 1.1)),   # roll   [rad]
    ((0.70, 4.5, 0.7), (0.10, 13.0, 2.3)),   # pitch  [rad]
    ((0.80, 3.2, 1.9), (0.08, 11.0, 0.4)),   # yaw    [rad]
)
_FLIPS_POSITION_SINES = (
    ((0.35, 1.1, 0.0), (0.040, 6.3, 0.5), (0.010, 15.0, 1.3)),   # x [m]
    ((0.30, 0.9, 1.2), (0.035, 7.4, 2.0), (0.008, 13.0, 0.2)),   # y [m]
    ((0.20, 1.4, 2.5), (0.030, 5.6, 0.9), (0.008, 17.0, 2.8)),   # z [m]
)


@register_scene("flips")
class FlipsScene(Scene):
    """Aggressive hand-held-like motion: the body tumbles through many full flips.

    Formulas (ZYX Euler angles, each a ramp plus two sinusoids; ``s = wobble_scale``,
    ``W = turn_rate_rad_s``, ``S = shake_scale``)::

        roll (t) = W_x t + s (0.90 sin(6.0 t)       + 0.12 sin(17.0 t + 1.1))
        pitch(t) = W_y t + s (0.70 sin(4.5 t + 0.7) + 0.10 sin(13.0 t + 2.3))
        yaw  (t) = W_z t + s (0.80 sin(3.2 t + 1.9) + 0.08 sin(11.0 t + 0.4))
        world_R_body = Rz(yaw) Ry(pitch) Rx(roll)
        omega_body = E(roll, pitch) (d roll, d pitch, d yaw)
        alpha_body = dE/dt (d roll, d pitch, d yaw) + E (dd roll, dd pitch, dd yaw)

        p(t) = position_m + S (x(t), y(t), z(t))   [m], a shaky hand:
        x = 0.35 sin(1.1 t)       + 0.040 sin(6.3 t + 0.5) + 0.010 sin(15.0 t + 1.3)
        y = 0.30 sin(0.9 t + 1.2) + 0.035 sin(7.4 t + 2.0) + 0.008 sin(13.0 t + 0.2)
        z = 0.20 sin(1.4 t + 2.5) + 0.030 sin(5.6 t + 0.9) + 0.008 sin(17.0 t + 2.8)

    with ``E`` as in :func:`euler_zyx_kinematics` (its forward map has no gimbal problem,
    so pitch may ramp through +-pi/2). Velocity and acceleration are the exact derivatives
    of the sums of sines.

    With the defaults over the default 20 s the body turns about 16 times in roll and 11
    in pitch (it is upside down about 30 times); peak ``|omega_body|`` exceeds 15 rad/s
    (about 17.8), peak ``|alpha_body|`` is about 115 rad/s^2, and peak ``|accel_world|``
    is about 6 m/s^2 (speed below 1 m/s).

    Default duration: 20 s.

    Parameters
    ----------
    turn_rate_rad_s : (3,) float, default (5.0, 3.5, 2.5)
        Ramp rates ``W`` of roll, pitch and yaw [rad/s].
    wobble_scale : float, default 1
        Factor ``s`` [1] on the sinusoidal parts of the Euler angles.
    shake_scale : float, default 1
        Factor ``S`` [1] on the translation sinusoids (0: no translation).
    position_m : (3,) float, default (0, 0, 1.5)
        Mean position [m].
    """

    DEFAULT_DURATION_S = 20.0
    #: Documented lower bound on the peak |omega_body| [rad/s] with the default parameters.
    PEAK_OMEGA_RAD_S = 15.0
    PARAMS = {
        "turn_rate_rad_s": Param((5.0, 3.5, 2.5), "rad/s", "ramp rates of roll, pitch, yaw"),
        "wobble_scale": Param(1.0, "1", "factor on the angle sinusoids", "nonnegative"),
        "shake_scale": Param(1.0, "1", "factor on the translation sinusoids", "nonnegative"),
        "position_m": Param((0.0, 0.0, 1.5), "m", "mean position"),
    }

    def _evaluate(self, t):
        n = t.shape[0]
        W = self.params["turn_rate_rad_s"]
        sw = self.params["wobble_scale"]
        ss = self.params["shake_scale"]
        ang = np.empty((n, 3))
        rates = np.empty((n, 3))
        accs = np.empty((n, 3))
        p = np.empty((n, 3))
        v = np.empty((n, 3))
        a = np.empty((n, 3))
        for i in range(3):
            x, dx, ddx = sum_of_sines(t, _FLIPS_ANGLE_SINES[i], sw)
            ang[:, i] = turn(W[i], t) + x
            rates[:, i] = W[i] + dx
            accs[:, i] = ddx
            x, dx, ddx = sum_of_sines(t, _FLIPS_POSITION_SINES[i], ss)
            p[:, i] = self.params["position_m"][i] + x
            v[:, i] = dx
            a[:, i] = ddx
        R, w, al = euler_zyx_kinematics(ang, rates, accs)
        return p, v, a, R, w, al
