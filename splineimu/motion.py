"""The motion-source protocol shared by fitted splines and analytic scenes.

A motion source describes the body pose ``world_T_body(t)`` over a valid time range and its
exact time derivatives. Times are float seconds in the source's own time base: seconds since
the integer nanosecond origin ``origin_ns`` (so Unix-epoch stamps lose nothing).

Every source provides :meth:`kinematics`, which computes all quantities in one pass; the
single-quantity methods are conveniences built on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import RangeError

DEFAULT_GRAVITY = (0.0, 0.0, -9.81)


@dataclass
class Kinematics:
    """Body motion sampled at ``t_s`` (N,).

    Attributes
    ----------
    t_s : (N,) float64, seconds in the source's time base
    position_world : (N, 3) body origin in the world frame [m]
    world_R_body : (N, 3, 3)
    omega_body : (N, 3) body angular rate, ``R^T dR/dt = [omega]x`` [rad/s]
    alpha_body : (N, 3) its time derivative [rad/s^2]
    velocity_world : (N, 3) [m/s]
    accel_world : (N, 3) [m/s^2]
    """

    t_s: np.ndarray
    position_world: np.ndarray
    world_R_body: np.ndarray
    omega_body: np.ndarray
    alpha_body: np.ndarray
    velocity_world: np.ndarray
    accel_world: np.ndarray

    @property
    def quat_xyzw(self) -> np.ndarray:
        from .lie import matrix_to_quat_xyzw

        return matrix_to_quat_xyzw(self.world_R_body)

    def specific_force_body(self, gravity=DEFAULT_GRAVITY) -> np.ndarray:
        """``f_b = R^T (a_w - g_w)``: a level body at rest reads (0, 0, +9.81)."""
        g = np.asarray(gravity, dtype=np.float64)
        return np.einsum("nji,nj->ni", self.world_R_body, self.accel_world - g)


class MotionSource:
    """Base class: subclasses set ``t_min_s``, ``t_max_s``, ``origin_ns`` and implement
    :meth:`kinematics`."""

    t_min_s: float
    t_max_s: float
    origin_ns: int = 0

    def kinematics(self, t_s) -> Kinematics:  # pragma: no cover - abstract
        raise NotImplementedError

    # ------------------------------------------------------------------ conveniences
    def t_s_from_ns(self, t_ns) -> np.ndarray:
        """Seconds in this source's time base from integer nanoseconds (exact subtraction)."""
        t = np.asarray(t_ns, dtype=np.int64) - np.int64(self.origin_ns)
        return t.astype(np.float64) / 1e9

    def check_times(self, t_s, name: str = "t_s") -> np.ndarray:
        """Return ``t_s`` as a 1-D float64 array; raise :class:`RangeError` outside the range."""
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(t_s, dtype=np.float64)))
        if t.ndim != 1:
            raise RangeError(f"Expected `{name}` to have shape (N,), got {np.shape(t_s)}")
        if t.size:
            if not np.all(np.isfinite(t)):
                raise RangeError(f"`{name}` contains NaN or inf")
            tol = 1e-9 * max(1.0, abs(self.t_max_s - self.t_min_s))
            lo, hi = float(t.min()), float(t.max())
            if lo < self.t_min_s - tol or hi > self.t_max_s + tol:
                raise RangeError(
                    f"time {lo if lo < self.t_min_s - tol else hi:.9f} s is outside the valid range "
                    f"[{self.t_min_s:.9f}, {self.t_max_s:.9f}] s"
                )
        return t

    def pose(self, t_s):
        """``(positions (N, 3), quat_xyzw (N, 4))`` of ``world_T_body`` at ``t_s``."""
        k = self.kinematics(t_s)
        return k.position_world, k.quat_xyzw

    def angular_velocity_body(self, t_s) -> np.ndarray:
        return self.kinematics(t_s).omega_body

    def angular_acceleration_body(self, t_s) -> np.ndarray:
        return self.kinematics(t_s).alpha_body

    def velocity_world(self, t_s) -> np.ndarray:
        return self.kinematics(t_s).velocity_world

    def acceleration_world(self, t_s) -> np.ndarray:
        return self.kinematics(t_s).accel_world

    def specific_force_body(self, t_s, gravity=DEFAULT_GRAVITY) -> np.ndarray:
        return self.kinematics(t_s).specific_force_body(gravity)

    def imu(self, t_s, gravity=DEFAULT_GRAVITY):
        """Ideal ``(gyro (N, 3), specific_force (N, 3))`` of a sensor at the body origin."""
        k = self.kinematics(t_s)
        return k.omega_body, k.specific_force_body(gravity)
