"""The lecture's scenes: ``ellipse`` (DESIGN.md section 4), ``static`` and ``circle``.

Examples
--------
>>> from splineimu.scenes import make_scene
>>> (make_scene("circle").imu([0.0])[1].round(6) + 0.0).tolist()     # centripetal 2^2 / 5 on body y
[[0.0, 0.8, 9.81]]
"""

from __future__ import annotations

import math

import numpy as np

from ..exactfloat import turn
from .base import Param, Scene, register_scene
from .kinematics import euler_zyx_kinematics, rotation_z

__all__ = ["EllipseScene", "StaticScene", "CircleScene"]


@register_scene("ellipse")
class EllipseScene(Scene):
    r"""The lecture's reference scene (DESIGN.md section 4): an ellipse with a vertical wobble.

    Formulas (t in seconds, ``K = k_rad_s``, ``K1 = k1``)::

        p(t)  = (15 cos(K t) + 5,  20 sin(K t) + 5,  sin(K1 K t) + 5)          [m]
        roll  = 0.1 cos t,   pitch = 0.2 sin t,   yaw = K t                     [rad]
        world_R_body = Rz(yaw) Ry(pitch) Rx(roll)
        omega_body   = E(roll, pitch) (d roll, d pitch, d yaw)
        alpha_body   = dE/dt (d roll, d pitch, d yaw) + E (dd roll, dd pitch, dd yaw)

    with ``E`` as in :func:`euler_zyx_kinematics`. Velocity and acceleration are the exact
    first and second derivatives of ``p``. At t = 0: ``p = (20, 5, 5)``.

    Default duration: 20 s (one lap, ``2 pi / K``).

    Parameters
    ----------
    k_rad_s : float, default pi/10
        ``K`` [rad/s], angular frequency of the lap (and the yaw rate).
    k1 : float, default 10
        ``K1`` [1], ratio of the vertical wobble's frequency to ``K``.
    """

    DEFAULT_DURATION_S = 20.0
    PARAMS = {
        "k_rad_s": Param(math.pi / 10.0, "rad/s", "lap frequency K (also the yaw rate)"),
        "k1": Param(10.0, "1", "vertical wobble frequency as a multiple of K"),
    }

    def _evaluate(self, t):
        K = self.params["k_rad_s"]
        K1 = self.params["k1"]
        n = t.shape[0]
        lap = turn(K, t)  # K t, reduced without its rounding (exactfloat)
        c, s = np.cos(lap), np.sin(lap)
        w1 = K1 * K
        wob = turn(w1, t)
        cz, sz = np.cos(wob), np.sin(wob)
        p = np.empty((n, 3))
        v = np.empty((n, 3))
        a = np.empty((n, 3))
        p[:, 0] = 15.0 * c + 5.0
        p[:, 1] = 20.0 * s + 5.0
        p[:, 2] = sz + 5.0
        v[:, 0] = -15.0 * K * s
        v[:, 1] = 20.0 * K * c
        v[:, 2] = w1 * cz
        a[:, 0] = -15.0 * K * K * c
        a[:, 1] = -20.0 * K * K * s
        a[:, 2] = -w1 * w1 * sz

        ct, st = np.cos(t), np.sin(t)
        ang = np.stack([0.1 * ct, 0.2 * st, lap], axis=1)
        rates = np.stack([-0.1 * st, 0.2 * ct, np.full(n, K)], axis=1)
        accs = np.stack([-0.1 * ct, -0.2 * st, np.zeros(n)], axis=1)
        R, w, al = euler_zyx_kinematics(ang, rates, accs)
        return p, v, a, R, w, al


@register_scene("static")
class StaticScene(Scene):
    """Level body at rest: the accelerometer reads ``(0, 0, +9.81)`` with default gravity.

    Formulas::

        p(t) = position_m,  v = a = 0
        world_R_body = Rz(yaw_rad)   (level: body z is world z)
        omega_body = alpha_body = 0

    Constants are broadcast into the output arrays (no per-sample work), so hours of
    samples are cheap (2.16e6 samples, 3 h at 200 Hz, in well under a second).

    Default duration: 10 s.

    Parameters
    ----------
    position_m : (3,) float, default (0, 0, 0)
        Body position in the world [m].
    yaw_rad : float, default 0
        Heading [rad] (rotation about world z; the body stays level).
    """

    DEFAULT_DURATION_S = 10.0
    PARAMS = {
        "position_m": Param((0.0, 0.0, 0.0), "m", "body position in the world"),
        "yaw_rad": Param(0.0, "rad", "heading about world z"),
    }

    def _setup(self):
        self._R = rotation_z(np.float64(self.params["yaw_rad"]))

    def _evaluate(self, t):
        n = t.shape[0]
        p = np.empty((n, 3))
        p[:] = self.params["position_m"]
        R = np.empty((n, 3, 3))
        R[:] = self._R
        z = np.zeros((n, 3))
        return p, z, z.copy(), R, z.copy(), z.copy()


@register_scene("circle")
class CircleScene(Scene):
    """Horizontal circle at constant speed with the body x axis along the velocity.

    Formulas (``w = speed_m_s / radius_m``, ``th = phase_rad + w t``, c = center_m)::

        p(t) = c + radius_m (cos th, sin th, 0)
        v(t) = radius_m w (-sin th, cos th, 0)
        a(t) = -radius_m w^2 (cos th, sin th, 0)
        world_R_body = Rz(th + pi/2)    if speed_m_s >= 0 (counter-clockwise)
                       Rz(th - pi/2)    if speed_m_s <  0 (clockwise)
        omega_body = (0, 0, w),  alpha_body = 0

    The body is level (z up), x points along the velocity, so the accelerometer reads
    the centripetal ``speed^2 / radius`` on body y (towards the centre) plus 9.81 on z.

    Default duration: 20 s.

    Parameters
    ----------
    radius_m : float, default 5
        Circle radius [m], > 0.
    speed_m_s : float, default 2
        Signed tangential speed [m/s] (negative: clockwise).
    center_m : (3,) float, default (0, 0, 1)
        Circle centre [m].
    phase_rad : float, default 0
        Angle ``th`` of the position at t = 0 [rad].
    """

    DEFAULT_DURATION_S = 20.0
    PARAMS = {
        "radius_m": Param(5.0, "m", "circle radius", "positive"),
        "speed_m_s": Param(2.0, "m/s", "signed tangential speed (negative = clockwise)"),
        "center_m": Param((0.0, 0.0, 1.0), "m", "circle centre"),
        "phase_rad": Param(0.0, "rad", "angle of the start point"),
    }

    def _evaluate(self, t):
        r = self.params["radius_m"]
        w = self.params["speed_m_s"] / r
        th = turn(w, t, self.params["phase_rad"])
        c, s = np.cos(th), np.sin(th)
        n = t.shape[0]
        p = np.empty((n, 3))
        v = np.zeros((n, 3))
        a = np.zeros((n, 3))
        p[:, 0] = r * c
        p[:, 1] = r * s
        p[:, 2] = 0.0
        p += self.params["center_m"]
        v[:, 0] = -r * w * s
        v[:, 1] = r * w * c
        a[:, 0] = -r * w * w * c
        a[:, 1] = -r * w * w * s
        yaw = th + (0.5 * math.pi if self.params["speed_m_s"] >= 0.0 else -0.5 * math.pi)
        R = rotation_z(yaw)
        om = np.zeros((n, 3))
        om[:, 2] = w
        return p, v, a, R, om, np.zeros((n, 3))
