"""Strapdown dead reckoning: integrate body rate and specific force back into a trajectory.

The measured body rate ``gyro`` and specific force ``accel`` (``f_b = R_wb^T (a_w - g_w)``)
at the sample times drive

.. math::

    \\dot R = R [\\omega - b_g]_\\times, \\qquad
    \\dot v = R (f - b_a) + g, \\qquad
    \\dot p = v

from an initial :class:`NavState`. The rotation is always advanced with the exact SO3
exponential (never a first-order quaternion update) and re-projected onto SO3 after each
step. Three methods:

``"euler"``
    First order. ``a = R_k f_k + g``, ``p += v h + a h^2/2``, ``v += a h``,
    ``R_{k+1} = R_k Exp(w_k h)`` (the form of the lecture exercise).
``"midpoint"``
    Second order. ``R_{k+1} = R_k Exp((w_k + w_{k+1}) h / 2)``; ``a`` is the mean of
    ``R_k f_k + g`` and ``R_{k+1} f_{k+1} + g``; ``p``, ``v`` as above.
``"rk4"``
    Fourth order. Munthe-Kaas RK4 on SO3 x R3 x R3: classical RK4 in the chart
    ``R = R_k Exp(theta)``, whose ODE is ``theta' = J_r^{-1}(theta) w`` (the dexpinv
    correction of the stage increments), coupled with velocity and position. The rate and
    specific force at each interval's midpoint come from the Lagrange cubic through the 4
    neighbouring samples (one-sided at the ends), which keeps the fourth order. Composing
    stage rotations by exponentials without the ``J_r^{-1}`` correction is only third order.

Orders are in the sample interval ``h`` for smooth motion sampled at points (instantaneous
values). Non-uniform sample times are allowed.

Mean samples (``sampling="mean"``: each value the average over ``[t_{k-1}, t_k]``, as
``splineimu --sampling mean`` and integrating IMU front ends give) are first turned into
point values by :func:`points_from_means`, so every method keeps its order for them too.

Extension to delta-angle / delta-velocity increments: the rk4 kernel consumes stage values
(rate and specific force at ``t_k``, ``t_k + h/2``, ``t_{k+1}``). From increments
``dtheta_k = int w``, ``dv_k = int f`` over each interval, the cumulative sums are samples of
the antiderivatives ``W(t)``, ``V(t)``; differentiating their local Lagrange interpolant
(5 points) gives those stage values to the same order, so a future
``integrate_increments(t_s, delta_angle, delta_velocity, init, ...)`` only prepares the
inputs and calls the same kernels (euler/midpoint would use ``w_k ~ dtheta_k / h`` directly).

References
----------
H. Munthe-Kaas, "High order Runge-Kutta methods on manifolds", Appl. Numer. Math. 29, 1999.
E. Hairer, C. Lubich, G. Wanner, "Geometric Numerical Integration", 2nd ed., ch. IV.8.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._kernels import integrate as _k
from .errors import ConfigError, InputError
from .lie import matrix_to_quat_xyzw, quat_make_continuous, quat_normalize, quat_xyzw_to_matrix
from .motion import DEFAULT_GRAVITY
from .validation import as_float_array, as_quat_xyzw, as_times_s, as_vector, as_vectors, finite_float, one_of

__all__ = ["NavState", "Trajectory", "integrate", "points_from_means", "METHODS", "METHOD_ORDER", "SAMPLINGS"]

#: Sampling modes of IMU data: the value at the stamp, or the mean over [previous stamp, stamp].
SAMPLINGS = ("point", "mean")

#: Nodes of the local interpolant of the integral in :func:`points_from_means`.
_MEAN_NODES = 7


def points_from_means(t_s, means) -> np.ndarray:
    """Point values at ``t_s`` of a smooth signal given its means over ``[t_{k-1}, t_k]``.

    The running integral ``A(t_k) = sum_{j<=k} means_j (t_j - t_{j-1})`` (``A(t_0) = 0``) is
    known exactly at the stamps; the derivative of its Lagrange interpolant through the 7
    nearest stamps (one-sided at the ends) gives the value at each stamp to sixth order in
    the sample interval, so that the conversion adds nothing visible to a fourth-order
    integration (uniform stamps:
    ``(m_{k-2} - 8 m_{k-1} + 37 m_k + 37 m_{k+1} - 8 m_{k+2} + m_{k+3}) / 60``; white noise
    comes out with 0.80 times its variance). The first mean (whose interval starts before
    ``t_0``) is not used.

    Parameters
    ----------
    t_s : (N,) array_like
        Strictly increasing stamps [s], N >= 2.
    means : (N, D) array_like
        ``means[k]``: the mean over ``[t_{k-1}, t_k]``.

    Returns
    -------
    (N, D) ndarray

    Examples
    --------
    Means of ``t^5`` over unit intervals give back ``t^5`` at the stamps:

    >>> t = np.arange(8.0)
    >>> m = (t**6 - (t - 1) ** 6) / 6
    >>> points_from_means(t, m[:, None]).ravel().round(6).tolist() == (t**5).tolist()
    True
    """
    t = as_times_s(t_s, "t_s", increasing=True)
    n = t.shape[0]
    m = as_float_array(means, "means")
    if m.ndim != 2 or m.shape[0] != n or n < 2:
        raise InputError(f"Expected `means` of shape ({n}, D) with N >= 2, got {m.shape}")
    A = np.zeros_like(m)
    A[1:] = np.cumsum(m[1:] * np.diff(t)[:, None], axis=0)
    k = min(_MEAN_NODES, n)
    first = np.clip(np.arange(n) - k // 2, 0, n - k)
    idx = first[:, None] + np.arange(k)[None, :]  # (N, k) node indices, each row holds its own stamp
    pos = np.arange(n) - first
    x = t[idx] - t[:, None]  # nodes relative to the target (the target node is 0)
    w = np.zeros((n, k))
    rows = np.arange(n)
    for j in range(k):
        others = [i for i in range(k) if i != j]
        not_target = j != pos
        # derivative at the target node x_p = 0 of the Lagrange basis l_j
        num = np.ones(n)
        for i in others:
            num = num * np.where(i == pos, 1.0, -x[:, i])
        den = np.ones(n)
        for i in others:
            den = den * (x[:, j] - x[:, i])
        w[:, j] = np.where(not_target, num / den, 0.0)
    w[rows, pos] = -w.sum(axis=1)  # the weights of a derivative sum to zero
    return np.einsum("nk,nkd->nd", w, A[idx] - A[:, None, :])


#: Integration methods and their order of accuracy in the sample interval.
METHOD_ORDER = {"euler": 1, "midpoint": 2, "rk4": 4}
METHODS = tuple(METHOD_ORDER)


@dataclass
class NavState:
    """Navigation state of the body at one instant.

    Attributes
    ----------
    t_s : float or None
        Time [s] in the caller's time base; ``None`` means "at the first sample".
    position_world : (3,) float64
        Body origin in the world frame [m].
    quat_xyzw : (4,) float64
        ``world_R_body`` as a Hamilton quaternion (x, y, z, w); normalized on creation.
    velocity_world : (3,) float64
        [m/s], zero by default.
    bias_gyro : (3,) float64
        Gyro bias [rad/s], subtracted from every gyro sample; zero by default.
    bias_accel : (3,) float64
        Accelerometer bias [m/s^2], subtracted from every specific-force sample; zero by default.

    Examples
    --------
    >>> s = NavState(0.0, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0])
    >>> s.world_R_body.tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """

    t_s: float | None
    position_world: np.ndarray
    quat_xyzw: np.ndarray
    velocity_world: np.ndarray = field(default_factory=lambda: np.zeros(3))
    bias_gyro: np.ndarray = field(default_factory=lambda: np.zeros(3))
    bias_accel: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        if self.t_s is not None:
            self.t_s = finite_float(self.t_s, "t_s")
        self.position_world = as_vector(self.position_world, "position_world")
        q = as_quat_xyzw(np.reshape(as_vector(self.quat_xyzw, "quat_xyzw", 4), (1, 4)), "quat_xyzw")
        self.quat_xyzw = quat_normalize(q[0])
        self.velocity_world = as_vector(self.velocity_world, "velocity_world")
        self.bias_gyro = as_vector(self.bias_gyro, "bias_gyro")
        self.bias_accel = as_vector(self.bias_accel, "bias_accel")

    @property
    def world_R_body(self) -> np.ndarray:
        """(3, 3) rotation of :attr:`quat_xyzw`."""
        return quat_xyzw_to_matrix(self.quat_xyzw)

    @classmethod
    def from_world_R_body(cls, t_s, position_world, world_R_body, velocity_world=(0.0, 0.0, 0.0),
                          bias_gyro=(0.0, 0.0, 0.0), bias_accel=(0.0, 0.0, 0.0)) -> NavState:
        """Build a state from a rotation matrix instead of a quaternion."""
        R = np.asarray(world_R_body, dtype=np.float64)
        if R.shape != (3, 3):
            raise ConfigError(f"Expected `world_R_body` to have shape (3, 3), got {R.shape}")
        return cls(t_s, position_world, matrix_to_quat_xyzw(R), velocity_world, bias_gyro, bias_accel)

    @classmethod
    def from_motion(cls, source, t_s: float, bias_gyro=(0.0, 0.0, 0.0),
                    bias_accel=(0.0, 0.0, 0.0)) -> NavState:
        """The exact state of a :class:`~splineimu.motion.MotionSource` at ``t_s``."""
        k = source.kinematics(np.array([float(t_s)]))
        return cls.from_world_R_body(t_s, k.position_world[0], k.world_R_body[0],
                                     k.velocity_world[0], bias_gyro, bias_accel)


@dataclass
class Trajectory:
    """Dead-reckoned trajectory, one row per input sample.

    Attributes
    ----------
    t_s : (N,) float64
        Sample times [s] (the input times).
    position_world : (N, 3) float64
        [m]
    quat_xyzw : (N, 4) float64
        ``world_R_body``, unit, sign-continuous along time.
    velocity_world : (N, 3) float64
        [m/s]
    method : str
        Integration method that produced it.
    """

    t_s: np.ndarray
    position_world: np.ndarray
    quat_xyzw: np.ndarray
    velocity_world: np.ndarray
    method: str = ""

    def __len__(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def world_R_body(self) -> np.ndarray:
        """(N, 3, 3) rotations."""
        return quat_xyzw_to_matrix(self.quat_xyzw)

    def to_dataframe(self):
        """``pandas.DataFrame`` with columns t_s, px, py, pz, qx, qy, qz, qw, vx, vy, vz."""
        import pandas as pd

        cols = {"t_s": self.t_s}
        for i, c in enumerate("xyz"):
            cols["p" + c] = self.position_world[:, i]
        for i, c in enumerate("xyzw"):
            cols["q" + c] = self.quat_xyzw[:, i]
        for i, c in enumerate("xyz"):
            cols["v" + c] = self.velocity_world[:, i]
        return pd.DataFrame(cols)


def integrate(t_s, gyro, accel, init: NavState, method: str = "rk4",
              gravity=DEFAULT_GRAVITY, sampling: str = "point") -> Trajectory:
    """Dead-reckon body rate and specific force from an initial state.

    Parameters
    ----------
    t_s : (N,) array_like
        Strictly increasing sample times [s], N >= 2. The state ``init`` is taken at ``t_s[0]``.
    gyro : (N, 3) array_like
        Measured body rate [rad/s] (``R^T dR/dt = [w]x``).
    accel : (N, 3) array_like
        Measured specific force [m/s^2], ``f_b = R_wb^T (a_w - g_w)``.
    init : NavState
        Pose, velocity and (constant) biases at ``t_s[0]``; ``init.t_s`` must be ``None``
        or equal ``t_s[0]`` (to 1 ns).
    method : {"euler", "midpoint", "rk4"}
        First, second or fourth order in the sample interval; see the module notes.
    gravity : (3,) array_like
        ``g_w`` [m/s^2], default (0, 0, -9.81).
    sampling : {"point", "mean"}
        ``gyro`` and ``accel`` are values at ``t_s``, or means over ``[t_{k-1}, t_k]``
        (turned into point values by :func:`points_from_means` first).

    Returns
    -------
    Trajectory
        Position, quaternion and velocity at every ``t_s``.

    Raises
    ------
    InputError
        Wrong shapes, NaN/inf (also in ``gravity``), fewer than 2 samples or times not strictly
        increasing.
    ConfigError
        Unknown method, or ``init.t_s`` not at the first sample.

    Notes
    -----
    Rotations are advanced with ``Exp`` and re-projected through their unit quaternion after
    every step. For rk4 the midpoint values are interpolated from the samples (Lagrange cubic
    through 4 neighbours), so the result is fourth order only for point samples of smooth
    motion; averaged samples need ``sampling="mean"``.

    Examples
    --------
    A level body at rest reads +9.81 up and stays put:

    >>> import numpy as np
    >>> t = np.arange(5) * 0.01
    >>> f = np.tile([0.0, 0.0, 9.81], (5, 1))
    >>> tr = integrate(t, np.zeros((5, 3)), f, NavState(None, [0, 0, 0], [0, 0, 0, 1]))
    >>> bool(np.abs(tr.position_world).max() < 1e-15)
    True
    """
    one_of(method, "method", METHODS)
    if not isinstance(init, NavState):
        raise ConfigError(f"Expected `init` to be a NavState, got {type(init).__name__}")
    t = as_times_s(t_s, "t_s", increasing=True)
    n = t.shape[0]
    if n < 2:
        raise InputError(f"Need at least 2 samples to integrate, got {n}")
    w = as_vectors(gyro, "gyro", n)
    f = as_vectors(accel, "accel", n)
    g = as_vector(gravity, "gravity")
    if one_of(sampling, "sampling", SAMPLINGS) == "mean":
        both = points_from_means(t, np.hstack([w, f]))
        w, f = np.ascontiguousarray(both[:, :3]), np.ascontiguousarray(both[:, 3:])
    if init.t_s is not None and abs(init.t_s - t[0]) > 1e-9 * max(1.0, abs(t[0])):
        raise ConfigError(f"The initial state is at t = {init.t_s!r} s but the first sample is at "
                          f"t = {t[0]!r} s; they must coincide")

    R0 = np.ascontiguousarray(init.world_R_body)
    q = np.empty((n, 4))
    v = np.empty((n, 3))
    p = np.empty((n, 3))
    args = (init.bias_gyro, init.bias_accel, g, R0, init.velocity_world, init.position_world, q, v, p)
    if method == "euler":
        _k.euler_kernel(t, w, f, *args)
    elif method == "midpoint":
        _k.midpoint_kernel(t, w, f, *args)
    else:
        w_mid = np.empty((n - 1, 3))
        f_mid = np.empty((n - 1, 3))
        _k.interp_mid_kernel(t, w, w_mid)
        _k.interp_mid_kernel(t, f, f_mid)
        _k.rk4_kernel(t, w, f, w_mid, f_mid, *args)
    quat = quat_make_continuous(np.ascontiguousarray(q[:, [1, 2, 3, 0]]))
    return Trajectory(t_s=t.copy(), position_world=p, quat_xyzw=quat, velocity_world=v, method=method)
