r"""VINS-style IMU preintegration with a covariance that matches the actual sample noise.

Between two instants ``i`` and ``j`` the IMU samples are integrated in the body frame of
``i``, independently of the (unknown) state at ``i``:

.. math::

    \alpha_{ij} = \Delta p, \quad \beta_{ij} = \Delta v, \quad \gamma_{ij} = \Delta q,

which relate to the states by (``g_w`` is gravity in the world frame, ``(0, 0, -9.81)`` by
default, ``dt = t_j - t_i``)

.. math::

    \Delta q = q_i^{-1} q_j, \quad
    \Delta v = R_i^T (v_j - v_i - g_w\,dt), \quad
    \Delta p = R_i^T (p_j - p_i - v_i\,dt - \tfrac12 g_w\,dt^2).

VINS-Mono writes the same with ``G = (0, 0, +9.81)`` and ``a_w = R (a_m - b_a) - G``, so its
``+ 0.5 G dt^2`` and ``+ G dt`` are our ``- 0.5 g_w dt^2`` and ``- g_w dt``: the numbers agree.

Discrete step (``"midpoint"``, VINS-Mono)
-----------------------------------------
Samples ``k`` and ``k+1`` (``h = t_{k+1} - t_k``, biases ``b_a, b_g`` held at the
linearization point):

.. math::

    \omega = \tfrac12 (\omega_k + \omega_{k+1}) - b_g, \qquad
    R_{k+1} = R_k \operatorname{Exp}(\omega h),

    \bar a = \tfrac12 \big(R_k (a_k - b_a) + R_{k+1} (a_{k+1} - b_a)\big), \qquad
    \alpha_{k+1} = \alpha_k + \beta_k h + \tfrac12 \bar a h^2, \qquad
    \beta_{k+1} = \beta_k + \bar a h.

``"euler"`` uses sample ``k`` alone over ``[t_k, t_{k+1}]`` (``omega = omega_k - b_g``,
``a_bar = R_k (a_k - b_a)``); that is the discretization of GTSAM's
``PreintegratedImuMeasurements``. The rotation is advanced with the exact SO3 exponential
(VINS-Mono uses the first-order quaternion ``(1, omega h / 2)`` and renormalizes; the two
differ by ``O(|omega h|^3)`` per step).

Error state and its Jacobians
-----------------------------
The error state is ``dx = (dp, dtheta, dv, db_a, db_g)`` (VINS-Mono's order), with the truth
written ``R_true = R Exp(dtheta)`` (right perturbation), ``p_true = p + dp`` and so on: the
sense of the residual, ``r = truth (-) estimate``. Internally the rotation error is carried
in the start frame, ``phi = R_k dtheta``; then the step's transition is

.. math::

    \phi' = \phi - M\, db_g, \qquad
    W = -[\bar a]_\times \phi + C_a\, db_a + C_g\, db_g,

    dv' = dv + h W, \qquad dp' = dp + h\, dv + \tfrac12 h^2 W,

with ``M = R_{k+1} J_r(omega h) h``, ``C_a = -(R_k + R_{k+1}) / 2`` and
``C_g = [R_{k+1} (a_{k+1} - b_a)]_x M / 2`` (Euler: ``C_a = -R_k``, ``C_g = 0``). These are
the exact derivatives of the discrete step above (not the first-order ``I - [omega]_x h`` of
VINS-Mono), so the bias Jacobians in :attr:`Preintegrator.jacobian` equal finite differences
of :meth:`Preintegrator.repropagate` to rounding. The outputs :attr:`~Preintegrator.covariance`
and :attr:`~Preintegrator.jacobian` are converted back to ``dtheta = R_j^T phi``.

Noise model and a consistent covariance
---------------------------------------
Measurements follow the shared sensor model: ``omega_k = omega_true + b_g,k + n_g,k`` with
white ``n_g,k ~ N(0, sigma_g^2 / tau)`` (continuous density ``sigma_g``, sample interval
``tau``), and the bias walks ``b_{k+1} = b_k + N(0, sigma_bg^2 h)``; likewise for the
accelerometer. Writing ``n_k = (n_a,k, n_g,k)``, one midpoint step is

.. math::

    dx_{k+1} = F_k\, dx_k + V^0_k n_k + V^1_k n_{k+1} + (\text{bias walk}),

with ``V^0`` and ``V^1`` the derivatives of the step with respect to its first and second
sample. The noise of sample ``k`` therefore enters **two** steps, ``k-1 -> k`` through
``V^1_{k-1}`` and ``k -> k+1`` through ``V^0_k``, so ``dx_k`` is correlated with ``n_k``.

*VINS-Mono* (``covariance="vins"``) propagates
``P' = F P F^T + V^0 Q V^{0T} + V^1 Q V^{1T}`` as if ``n_k`` and ``n_{k+1}`` were fresh in
every step: the cross terms ``F V^1_{k-1} Q V^{0T}_k`` are lost. Because ``V^0 ~ V^1`` (each
is half of the sample's effect), the white-noise part of the covariance comes out about
**half** of the truth (measured below).

*Consistent* (``covariance="consistent"``, the default) propagates the part of the error that
is independent of the last sample's noise, ``y_k = dx_k - V^1_{k-1} n_k``:

.. math::

    y_{k+1} = F_k y_k + G_k n_k, \qquad G_k = F_k V^1_{k-1} + V^0_k, \qquad
    P^y_{k+1} = F_k P^y_k F_k^T + G_k Q_k G_k^T + Q_{walk},

so every sample's noise is added exactly once, through its combined Jacobian, and
``Cov(dx_k) = P^y_k + V^1_{k-1} Q_k V^{1T}_{k-1}`` (the last sample has so far entered only
one step). This is exact to first order for the discrete estimator that is actually run
(``euler`` has ``V^1 = 0`` and both models coincide).

Discretization: sample ``k``'s white-noise variance is ``sigma^2 / tau_k`` with ``tau_k`` its
*backward* interval ``t_k - t_{k-1}`` (the first sample uses its forward interval; with a
uniform rate every ``tau`` is ``1 / rate``). The VINS model uses the step's ``h`` for both
samples, Euler the step's ``h``. Bias walk per step: ``sigma_b^2 h`` on the bias diagonal.
(VINS-Mono itself uses its yaml values directly as discrete standard deviations, i.e. without
the ``1/tau`` and with ``h^2`` for the walk; here both models use the continuous densities as
above, so that the two differ only in the correlation structure.)

The walk of step ``k`` is applied to the bias states at the end of the step, while the shared
model's sample ``k+1`` already carries ``b_{k+1}``; the difference is ``O(h)`` relative to the
walk's own (small) contribution and is neglected.

Measured (tests/test_preintegration.py, shared sensor model, ellipse scene, 200 Hz, nested
windows of 0.1 / 1 / 5 s, each realization's NEES with its own covariance):

========================  ==============  ==========================  ===========================
noise, realizations       model           mean 9-dof NEES             block variance / MC (p, th, v)
========================  ==============  ==========================  ===========================
ADIS16448, 500            consistent      9.23 / 9.09 / 9.17          0.92 .. 1.07
ADIS16448, 20000          consistent      9.11 / 8.96 / 8.96          0.99 .. 1.01
ADIS16448, 4000           vins            17.5 / 15.6 / 12.7          theta 0.51 / 0.51 / 0.54
lecture, 2000             consistent      9.11 / 8.97 / 10.1          0.99 .. 1.02
lecture, 2000             vins            17.4 / 17.9 / 20.2          0.50 .. 0.52
========================  ==============  ==========================  ===========================

(ADIS16448: EuRoC's Kalibr values; lecture: DESIGN.md's 0.015 / 0.019 / 5e-5 / 5e-4. 95 %
interval of the mean for 500 realizations: 8.63 .. 9.38; the 0.1 s ADIS16448 window
carries a deterministic midpoint discretization term of 0.13 in the expected NEES.) The VINS
form gives about half of every white-noise-driven variance; where the accelerometer bias walk
dominates (ADIS16448 p and v at 5 s) the ratio is 0.85 - 0.88. With the lecture's large gyro
noise the 5 s window exceeds the NEES interval (about 2 deg of rotation error: the first-order
model's limit, the block variances still agree to 1 %).

Bias correction
---------------
First order, as VINS-Mono: with ``d b = b_new - b_lin``,
``Delta p' = Delta p + J_{p,b_a} d b_a + J_{p,b_g} d b_g`` (same for ``v``) and
``Delta q' = Delta q Exp(J_{theta,b_g} d b_g)``; :meth:`Preintegrator.repropagate` integrates
the stored samples again instead.

References
----------
T. Qin, P. Li, S. Shen, "VINS-Mono: A Robust and Versatile Monocular Visual-Inertial State
Estimator", IEEE T-RO 34(4), 2018 (``IntegrationBase``, midpoint integration).
C. Forster, L. Carlone, F. Dellaert, D. Scaramuzza, "On-Manifold Preintegration for Real-Time
Visual-Inertial Odometry", IEEE T-RO 33(1), 2017.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._kernels import preintegration as _k
from .errors import ConfigError, InputError, SplineImuError
from .lie import matrix_to_quat_xyzw, quat_xyzw_to_matrix, so3_exp, so3_log
from .motion import DEFAULT_GRAVITY

__all__ = [
    "Preintegrator", "Deltas", "ExactDeltas", "exact_deltas", "delta_error", "nees",
    "METHODS", "COVARIANCE_MODELS", "STATE_ORDER", "WindowResult", "evaluate_windows",
]

METHODS = ("midpoint", "euler")
COVARIANCE_MODELS = ("consistent", "vins")
#: Error-state blocks of :attr:`Preintegrator.covariance` and :attr:`Preintegrator.jacobian`.
STATE_ORDER = ("p", "theta", "v", "b_a", "b_g")

O_P, O_R, O_V, O_BA, O_BG = 0, 3, 6, 9, 12


# ----------------------------------------------------------------------------- helpers


def _density(x, name):
    a = np.asarray(x, dtype=np.float64)
    if a.shape == ():
        a = np.full(3, float(a))
    if a.shape != (3,):
        raise ConfigError(f"Expected `{name}` to be a scalar or have shape (3,), got {np.shape(x)}")
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ConfigError(f"`{name}` must be finite and >= 0, got {x!r}")
    return a


def _vec3(x, name):
    a = np.asarray(x, dtype=np.float64)
    if a.shape != (3,):
        raise InputError(f"Expected `{name}` to have shape (3,), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"`{name}` contains NaN or inf")
    return np.ascontiguousarray(a)


def _quat(x, name):
    q = np.asarray(x, dtype=np.float64)
    if q.shape != (4,):
        raise InputError(f"Expected `{name}` to have shape (4,), got {q.shape}")
    n = float(np.linalg.norm(q))
    if not np.isfinite(n) or n < 1e-12:
        raise InputError(f"`{name}` is not a valid quaternion (norm {n:g})")
    return q / n


def _quat_mul_xyzw(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ])


def _quat_inv_xyzw(q):
    return np.array([-q[0], -q[1], -q[2], q[3]])


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


def _deltas_from_states(p_i, R_i, v_i, p_j, R_j, v_j, dt, gravity):
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
    dp, dv, dq = _deltas_from_states(p_i, R_i, v_i, p_j, R_j, v_j, dt, gravity)
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


# ----------------------------------------------------------------------------- class


class Preintegrator:
    """IMU preintegration between two keyframes, VINS-Mono style, with bias Jacobians.

    Parameters
    ----------
    gyro_noise_density : float or (3,)
        White gyro noise, rad/s/sqrt(Hz) (Kalibr ``gyroscope_noise_density``).
    accel_noise_density : float or (3,)
        White accelerometer noise, m/s^2/sqrt(Hz).
    gyro_random_walk : float or (3,)
        Gyro bias random walk, rad/s^2/sqrt(Hz).
    accel_random_walk : float or (3,)
        Accelerometer bias random walk, m/s^3/sqrt(Hz).
    bias_gyro, bias_accel : (3,) array_like, default zeros
        Linearization point of the biases (subtracted from every sample).
    method : {"midpoint", "euler"}, default "midpoint"
        Discretization (see the module notes).
    covariance : {"consistent", "vins"}, default "consistent"
        Noise model of the covariance: each sample's noise once (consistent with the actual
        noise) or VINS-Mono's (each sample's noise independently in both steps it enters).
        Irrelevant for ``method="euler"``.
    compute_covariance : bool, default True
        ``False`` skips the covariance (the Jacobian is always computed).

    Attributes
    ----------
    delta_p, delta_v : (3,) ndarray
    delta_q_xyzw : (4,) ndarray
    delta_t_s : float
    covariance : (15, 15) ndarray, error-state order (p, theta, v, b_a, b_g)
    jacobian : (15, 15) ndarray, ``d dx_j / d dx_i``; its bias columns are the bias Jacobians
    bias_gyro, bias_accel : (3,) ndarray, linearization point
    n_samples : int, samples consumed so far

    Notes
    -----
    :meth:`integrate` may be called repeatedly: the last sample of one call and the first of
    the next form a step. The samples are stored for :meth:`repropagate`. The error state is
    ``truth (-) estimate`` with the rotation perturbed on the right; see the module docstring
    for the discrete model and the derivation of both covariance models.

    Examples
    --------
    >>> import numpy as np
    >>> pre = Preintegrator(0.015, 0.019, 5e-5, 5e-4, np.zeros(3), np.zeros(3))
    >>> t = np.arange(201) * 0.005
    >>> gyro = np.tile([0.0, 0.0, 0.5], (201, 1)); accel = np.tile([0.0, 0.0, 9.81], (201, 1))
    >>> _ = pre.integrate(t, gyro, accel)
    >>> pre.delta_t_s, pre.delta_v.round(9) + 0.0
    (1.0, array([0.  , 0.  , 9.81]))
    >>> pre.covariance.shape
    (15, 15)
    """

    def __init__(self, gyro_noise_density, accel_noise_density, gyro_random_walk, accel_random_walk,
                 bias_gyro=(0.0, 0.0, 0.0), bias_accel=(0.0, 0.0, 0.0), method: str = "midpoint",
                 covariance: str = "consistent", compute_covariance: bool = True):
        if method not in METHODS:
            raise ConfigError(f"Expected `method` to be one of {METHODS}, got {method!r}")
        if covariance not in COVARIANCE_MODELS:
            raise ConfigError(f"Expected `covariance` to be one of {COVARIANCE_MODELS}, got {covariance!r}")
        self.method = method
        self.covariance_model = covariance
        self.compute_covariance = bool(compute_covariance)
        self.gyro_noise_density = _density(gyro_noise_density, "gyro_noise_density")
        self.accel_noise_density = _density(accel_noise_density, "accel_noise_density")
        self.gyro_random_walk = _density(gyro_random_walk, "gyro_random_walk")
        self.accel_random_walk = _density(accel_random_walk, "accel_random_walk")
        try:
            bg = _vec3(bias_gyro, "bias_gyro")
            ba = _vec3(bias_accel, "bias_accel")
        except InputError as e:
            raise ConfigError(str(e)) from None
        self._chunks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self._reset(bg, ba)

    # ------------------------------------------------------------------ state
    def _reset(self, bias_gyro, bias_accel):
        self._params = np.concatenate([
            bias_gyro, bias_accel,
            self.accel_noise_density ** 2, self.gyro_noise_density ** 2,
            self.accel_random_walk ** 2, self.gyro_random_walk ** 2,
        ])
        self._nav = np.zeros(10)
        self._nav[6] = 1.0
        self._P = np.zeros((15, 15))
        self._J = np.zeros((15, 9))  # columns (theta, b_a, b_g) of d dx_k / d dx_i
        self._J[3:6, 0:3] = np.eye(3)
        self._J[9:15, 3:9] = np.eye(6)
        self._V1 = np.zeros((15, 6))
        self._qlast = np.zeros(6)
        self._prev = np.zeros(7)
        self._sum_dt = np.zeros(1)
        self._n = 0

    @property
    def bias_gyro(self) -> np.ndarray:
        return self._params[0:3].copy()

    @property
    def bias_accel(self) -> np.ndarray:
        return self._params[3:6].copy()

    @property
    def n_samples(self) -> int:
        return self._n

    @property
    def delta_p(self) -> np.ndarray:
        return self._nav[0:3].copy()

    @property
    def delta_v(self) -> np.ndarray:
        return self._nav[3:6].copy()

    @property
    def delta_q_xyzw(self) -> np.ndarray:
        w, x, y, z = self._nav[6:10]
        q = np.array([x, y, z, w])
        return q if w >= 0 else -q

    @property
    def delta_R(self) -> np.ndarray:
        return quat_xyzw_to_matrix(self.delta_q_xyzw)

    @property
    def delta_t_s(self) -> float:
        return float(self._sum_dt[0])

    def deltas(self) -> Deltas:
        """The current deltas as a :class:`Deltas` object."""
        return Deltas(self.delta_p, self.delta_v, self.delta_q_xyzw, self.delta_t_s)

    def _to_theta(self):
        T = np.eye(15)
        T[3:6, 3:6] = self.delta_R.T
        return T

    @property
    def covariance(self) -> np.ndarray:
        """(15, 15) covariance of ``truth (-) estimate``, order (p, theta, v, b_a, b_g)."""
        if not self.compute_covariance:
            raise SplineImuError("this Preintegrator was made with compute_covariance=False")
        P = self._P.copy()
        if self.method == "midpoint" and self.covariance_model == "consistent":
            P += (self._V1 * self._qlast) @ self._V1.T
        T = self._to_theta()
        P = T @ P @ T.T
        return 0.5 * (P + P.T)

    @property
    def jacobian(self) -> np.ndarray:
        """(15, 15) ``d dx_j / d dx_i``; blocks ``[0:3, 9:12]`` = ``d Delta p / d b_a`` etc."""
        J = np.eye(15)
        J[O_P:O_P + 3, O_V:O_V + 3] = self.delta_t_s * np.eye(3)
        J[:, O_R:O_R + 3] = self._J[:, 0:3]
        J[:, O_BA:O_BA + 6] = self._J[:, 3:9]
        return self._to_theta() @ J

    # ------------------------------------------------------------------ integration
    def integrate(self, t_s, gyro, accel) -> Preintegrator:
        """Consume consecutive samples (appending to what was integrated before).

        Parameters
        ----------
        t_s : (N,) array_like
            Strictly increasing sample times [s]; the first must come after the last sample
            of the previous call.
        gyro : (N, 3) array_like
            Measured body rate [rad/s].
        accel : (N, 3) array_like
            Measured specific force [m/s^2].

        Returns
        -------
        Preintegrator
            ``self``, for chaining.

        Raises
        ------
        InputError
            Wrong shapes, non-finite values or non-increasing times.
        """
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(t_s, dtype=np.float64)))
        if t.ndim != 1:
            raise InputError(f"Expected `t_s` to have shape (N,), got {np.shape(t_s)}")
        n = t.shape[0]
        g = np.asarray(gyro, dtype=np.float64)
        a = np.asarray(accel, dtype=np.float64)
        for arr, name in ((g, "gyro"), (a, "accel")):
            if arr.shape != (n, 3) and not (n == 0 and arr.size == 0):
                raise InputError(f"Expected `{name}` to have shape ({n}, 3), got {arr.shape}")
        if n == 0:
            return self
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(g)) and np.all(np.isfinite(a))):
            raise InputError("`t_s`, `gyro` and `accel` must be finite")
        d = np.diff(t)
        if np.any(d <= 0):
            i = int(np.flatnonzero(d <= 0)[0])
            raise InputError(f"`t_s` must be strictly increasing: t_s[{i + 1}] = {t[i + 1]!r} <= {t[i]!r}")
        if self._n and t[0] <= self._prev[0]:
            raise InputError(
                f"`t_s[0]` = {t[0]!r} must come after the last sample integrated ({self._prev[0]!r})"
            )
        g = np.ascontiguousarray(g)
        a = np.ascontiguousarray(a)
        self._run(t, g, a)
        self._chunks.append((t.copy(), g.copy(), a.copy()))
        return self

    def _run(self, t, g, a):
        _k.preintegrate_kernel(
            t, g, a, self._n > 0, self._params,
            _k.METHOD_MIDPOINT if self.method == "midpoint" else _k.METHOD_EULER,
            _k.COV_CONSISTENT if self.covariance_model == "consistent" else _k.COV_VINS,
            self.compute_covariance,
            self._nav, self._P, self._J, self._V1, self._qlast, self._prev, self._sum_dt,
        )
        self._n += t.shape[0]

    def samples(self):
        """All stored samples ``(t_s (N,), gyro (N, 3), accel (N, 3))``."""
        if not self._chunks:
            return np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3))
        return tuple(np.concatenate([c[i] for c in self._chunks]) for i in range(3))

    def repropagate(self, bias_gyro, bias_accel) -> Preintegrator:
        """Integrate the stored samples again about new bias linearization points (in place).

        Parameters
        ----------
        bias_gyro, bias_accel : (3,) array_like

        Returns
        -------
        Preintegrator
            ``self``.
        """
        bg = _vec3(bias_gyro, "bias_gyro")
        ba = _vec3(bias_accel, "bias_accel")
        self._reset(bg, ba)
        if self._chunks:
            t, g, a = self.samples()
            self._chunks = [(t, g, a)]
            self._run(np.ascontiguousarray(t), np.ascontiguousarray(g), np.ascontiguousarray(a))
        return self

    def copy(self) -> Preintegrator:
        """An independent copy (stored samples are shared read-only)."""
        new = object.__new__(Preintegrator)
        new.__dict__.update(self.__dict__)
        for name in ("_params", "_nav", "_P", "_J", "_V1", "_qlast", "_prev", "_sum_dt"):
            setattr(new, name, getattr(self, name).copy())
        new._chunks = list(self._chunks)
        return new

    # ------------------------------------------------------------------ correction, residual
    def corrected(self, bias_gyro, bias_accel) -> Deltas:
        """First-order bias correction of the deltas (VINS-Mono's ``evaluate``).

        Parameters
        ----------
        bias_gyro, bias_accel : (3,) array_like
            New bias estimates.

        Returns
        -------
        Deltas
            ``Delta p + J_{p,b_a} d b_a + J_{p,b_g} d b_g``, likewise ``v``, and
            ``Delta q Exp(J_{theta,b_g} d b_g)`` with ``d b = b - b_lin``.
        """
        dbg = _vec3(bias_gyro, "bias_gyro") - self._params[0:3]
        dba = _vec3(bias_accel, "bias_accel") - self._params[3:6]
        Jm = self.jacobian
        dp = self.delta_p + Jm[O_P:O_P + 3, O_BA:O_BA + 3] @ dba + Jm[O_P:O_P + 3, O_BG:O_BG + 3] @ dbg
        dv = self.delta_v + Jm[O_V:O_V + 3, O_BA:O_BA + 3] @ dba + Jm[O_V:O_V + 3, O_BG:O_BG + 3] @ dbg
        dR = self.delta_R @ so3_exp(Jm[O_R:O_R + 3, O_BG:O_BG + 3] @ dbg)
        return Deltas(dp, dv, matrix_to_quat_xyzw(dR), self.delta_t_s)

    def residual(self, p_i, q_i_xyzw, v_i, ba_i, bg_i, p_j, q_j_xyzw, v_j, ba_j, bg_j,
                 gravity=DEFAULT_GRAVITY) -> np.ndarray:
        """15-dim residual between two states, VINS-Mono's ``IntegrationBase::evaluate``.

        Parameters
        ----------
        p_i, v_i, p_j, v_j : (3,) world position [m] and velocity [m/s]
        q_i_xyzw, q_j_xyzw : (4,) ``world_R_body``
        ba_i, bg_i, ba_j, bg_j : (3,) accelerometer and gyro biases
        gravity : (3,), default (0, 0, -9.81)
            World gravity ``g_w`` (VINS-Mono's ``G`` is ``-g_w``).

        Returns
        -------
        (15,) ndarray
            ``r_p = R_i^T (p_j - p_i - v_i dt - g dt^2/2) - Delta p_c``,
            ``r_theta = 2 vec(Delta q_c^{-1} q_i^{-1} q_j)`` (sign chosen with ``w >= 0``),
            ``r_v = R_i^T (v_j - v_i - g dt) - Delta v_c``, ``r_ba = ba_j - ba_i``,
            ``r_bg = bg_j - bg_i``; ``_c`` are the deltas bias-corrected to ``(bg_i, ba_i)``
            by :meth:`corrected`. Order (p, theta, v, b_a, b_g), covariance
            :attr:`covariance`.
        """
        p_i = _vec3(p_i, "p_i")
        v_i = _vec3(v_i, "v_i")
        p_j = _vec3(p_j, "p_j")
        v_j = _vec3(v_j, "v_j")
        qi = _quat(q_i_xyzw, "q_i_xyzw")
        qj = _quat(q_j_xyzw, "q_j_xyzw")
        ba_i = _vec3(ba_i, "ba_i")
        bg_i = _vec3(bg_i, "bg_i")
        ba_j = _vec3(ba_j, "ba_j")
        bg_j = _vec3(bg_j, "bg_j")
        g = _vec3(gravity, "gravity")
        c = self.corrected(bg_i, ba_i)
        dt = self.delta_t_s
        R_i = quat_xyzw_to_matrix(qi)
        r = np.empty(15)
        r[O_P:O_P + 3] = R_i.T @ (p_j - p_i - v_i * dt - 0.5 * g * dt * dt) - c.delta_p
        qe = _quat_mul_xyzw(_quat_inv_xyzw(c.delta_q_xyzw), _quat_mul_xyzw(_quat_inv_xyzw(qi), qj))
        if qe[3] < 0:
            qe = -qe
        r[O_R:O_R + 3] = 2.0 * qe[:3]
        r[O_V:O_V + 3] = R_i.T @ (v_j - v_i - g * dt) - c.delta_v
        r[O_BA:O_BA + 3] = ba_j - ba_i
        r[O_BG:O_BG + 3] = bg_j - bg_i
        return r

    def predict(self, p_i, q_i_xyzw, v_i, gravity=DEFAULT_GRAVITY):
        """State at j from the state at i and the deltas: ``(p_j (3,), q_j_xyzw (4,), v_j (3,))``."""
        p_i = _vec3(p_i, "p_i")
        v_i = _vec3(v_i, "v_i")
        qi = _quat(q_i_xyzw, "q_i_xyzw")
        g = _vec3(gravity, "gravity")
        dt = self.delta_t_s
        R_i = quat_xyzw_to_matrix(qi)
        p_j = p_i + v_i * dt + 0.5 * g * dt * dt + R_i @ self.delta_p
        v_j = v_i + g * dt + R_i @ self.delta_v
        q_j = _quat_mul_xyzw(qi, self.delta_q_xyzw)
        return p_j, (q_j if q_j[3] >= 0 else -q_j), v_j

    def __repr__(self) -> str:
        return (
            f"Preintegrator(method={self.method!r}, covariance={self.covariance_model!r}, "
            f"n_samples={self._n}, delta_t_s={self.delta_t_s:.6f})"
        )


# ----------------------------------------------------------------------------- windows


@dataclass
class WindowResult:
    """Preintegrated windows of a recording compared with ground truth.

    Attributes
    ----------
    t_i_ns, t_j_ns : (W,) int64 window bounds
    n_samples : (W,) int, IMU samples used (including interpolated end samples)
    error_p_m, error_v_m_s, error_theta_rad : (W,) norms of ``truth (-) estimate``
    error : (W, 9) the errors ``(p, theta, v)``
    nees : (W,) 9-dof NEES; NaN without noise parameters or for a singular covariance (one-step
        windows: there ``p`` and ``v`` are driven by the same noise)
    delta_p, delta_v : (W, 3); delta_q_xyzw : (W, 4), the preintegrated deltas
    truth : list of :class:`Deltas`, ground-truth deltas
    method, covariance_model : str
    """

    t_i_ns: np.ndarray
    t_j_ns: np.ndarray
    n_samples: np.ndarray
    error: np.ndarray
    nees: np.ndarray
    delta_p: np.ndarray
    delta_v: np.ndarray
    delta_q_xyzw: np.ndarray
    truth: list
    method: str = "midpoint"
    covariance_model: str = "consistent"

    @property
    def error_p_m(self):
        return np.linalg.norm(self.error[:, 0:3], axis=1)

    @property
    def error_theta_rad(self):
        return np.linalg.norm(self.error[:, 3:6], axis=1)

    @property
    def error_v_m_s(self):
        return np.linalg.norm(self.error[:, 6:9], axis=1)

    def to_dataframe(self):
        import pandas as pd

        return pd.DataFrame({
            "t_i_ns": self.t_i_ns,
            "t_j_ns": self.t_j_ns,
            "dt_s": (self.t_j_ns - self.t_i_ns) * 1e-9,
            "samples": self.n_samples,
            "err_p_m": self.error_p_m,
            "err_v_m_s": self.error_v_m_s,
            "err_theta_deg": np.degrees(self.error_theta_rad),
            "nees9": self.nees,
        })


def _gt_state_at(t_ns, gt_t_ns, gt_p, gt_R, gt_v, gt_bg, gt_ba):
    """Ground-truth state at ``t_ns`` (exact stamp or linear/geodesic interpolation)."""
    idx = int(np.searchsorted(gt_t_ns, t_ns))
    if idx < len(gt_t_ns) and gt_t_ns[idx] == t_ns:
        return gt_p[idx], gt_R[idx], gt_v[idx], gt_bg[idx], gt_ba[idx]
    if idx == 0 or idx >= len(gt_t_ns):
        raise InputError(f"time {t_ns} ns is outside the ground truth [{gt_t_ns[0]}, {gt_t_ns[-1]}] ns")
    a, b = idx - 1, idx
    u = float(t_ns - gt_t_ns[a]) / float(gt_t_ns[b] - gt_t_ns[a])
    lerp = lambda x: (1 - u) * x[a] + u * x[b]  # noqa: E731
    R = gt_R[a] @ so3_exp(u * so3_log(gt_R[a].T @ gt_R[b]))
    return lerp(gt_p), R, lerp(gt_v), lerp(gt_bg), lerp(gt_ba)


def _sample_at(t_ns, y, stamp):
    """Linear interpolation of the rows of ``y`` at an integer stamp inside ``t_ns``."""
    j = int(np.searchsorted(t_ns, stamp, side="right")) - 1
    if t_ns[j] == stamp:
        return y[j]
    u = float(stamp - t_ns[j]) / float(t_ns[j + 1] - t_ns[j])
    return (1.0 - u) * y[j] + u * y[j + 1]


def _window_samples(t_ns, gyro, accel, a_ns, b_ns):
    """Samples in ``[a_ns, b_ns]``, with linearly interpolated end samples when no sample falls
    exactly on a bound."""
    if a_ns < t_ns[0] or b_ns > t_ns[-1]:
        raise InputError(f"window [{a_ns}, {b_ns}] ns is outside the IMU data [{t_ns[0]}, {t_ns[-1]}] ns")
    lo = int(np.searchsorted(t_ns, a_ns, side="left"))
    hi = int(np.searchsorted(t_ns, b_ns, side="right"))
    tt, gg, aa = t_ns[lo:hi], gyro[lo:hi], accel[lo:hi]
    if tt.size == 0 or tt[0] != a_ns:
        tt = np.concatenate([[a_ns], tt])
        gg = np.vstack([_sample_at(t_ns, gyro, a_ns), gg])
        aa = np.vstack([_sample_at(t_ns, accel, a_ns), aa])
    if tt[-1] != b_ns:
        tt = np.concatenate([tt, [b_ns]])
        gg = np.vstack([gg, _sample_at(t_ns, gyro, b_ns)])
        aa = np.vstack([aa, _sample_at(t_ns, accel, b_ns)])
    return tt.astype(np.int64), gg, aa


def evaluate_windows(imu_t_ns, gyro, accel, gt_t_ns, gt_position, gt_quat_xyzw, gt_velocity,
                     gt_bias_gyro, gt_bias_accel, windows_ns, noise=None, method="midpoint",
                     covariance="consistent", gravity=DEFAULT_GRAVITY) -> WindowResult:
    """Preintegrate a recording's IMU over windows and compare with its ground truth.

    Parameters
    ----------
    imu_t_ns : (N,) int64; gyro, accel : (N, 3)
        IMU samples (EuRoC ``imu0/data.csv``).
    gt_t_ns : (M,) int64; gt_position, gt_velocity, gt_bias_gyro, gt_bias_accel : (M, 3);
    gt_quat_xyzw : (M, 4)
        Ground truth (EuRoC ``state_groundtruth_estimate0``); the state and biases at a window
        start that falls between stamps are interpolated.
    windows_ns : (W, 2) int64
        ``[t_i, t_j]`` per window. IMU samples at the bounds are interpolated linearly when
        no sample falls exactly on them.
    noise : dict, optional
        Kalibr keys ``gyroscope_noise_density``, ``accelerometer_noise_density``,
        ``gyroscope_random_walk``, ``accelerometer_random_walk``; gives the NEES.
    method, covariance : str
        As in :class:`Preintegrator`.
    gravity : (3,)
        ``g_w`` the data were made with.

    Returns
    -------
    WindowResult
        Errors ``truth (-) estimate`` with the deltas linearized at the ground-truth biases at
        ``t_i``, i.e. the first nine rows of :meth:`Preintegrator.residual` with true states.
    """
    imu_t_ns = np.asarray(imu_t_ns, dtype=np.int64)
    gt_t_ns = np.asarray(gt_t_ns, dtype=np.int64)
    gyro = np.asarray(gyro, dtype=np.float64)
    accel = np.asarray(accel, dtype=np.float64)
    gt_R = quat_xyzw_to_matrix(gt_quat_xyzw)
    gt_p = np.asarray(gt_position, dtype=np.float64)
    gt_v = np.asarray(gt_velocity, dtype=np.float64)
    gt_bg = np.asarray(gt_bias_gyro, dtype=np.float64)
    gt_ba = np.asarray(gt_bias_accel, dtype=np.float64)
    windows = np.asarray(windows_ns, dtype=np.int64).reshape(-1, 2)
    if noise is None:
        dens = (0.0, 0.0, 0.0, 0.0)
    else:
        dens = (noise["gyroscope_noise_density"], noise["accelerometer_noise_density"],
                noise["gyroscope_random_walk"], noise["accelerometer_random_walk"])
    W = len(windows)
    err = np.zeros((W, 9))
    ne = np.full(W, np.nan)
    dps, dvs, dqs, nsamp, truths = np.zeros((W, 3)), np.zeros((W, 3)), np.zeros((W, 4)), np.zeros(W, int), []
    for w, (a_ns, b_ns) in enumerate(windows):
        if b_ns <= a_ns:
            raise InputError(f"window {w}: end {b_ns} ns is not after start {a_ns} ns")
        ts, gs, as_ = _window_samples(imu_t_ns, gyro, accel, a_ns, b_ns)
        p_i, R_i, v_i, bg_i, ba_i = _gt_state_at(a_ns, gt_t_ns, gt_p, gt_R, gt_v, gt_bg, gt_ba)
        p_j, R_j, v_j, _, _ = _gt_state_at(b_ns, gt_t_ns, gt_p, gt_R, gt_v, gt_bg, gt_ba)
        pre = Preintegrator(*dens, bias_gyro=bg_i, bias_accel=ba_i, method=method, covariance=covariance,
                            compute_covariance=noise is not None)
        pre.integrate((ts - a_ns).astype(np.float64) * 1e-9, gs, as_)
        dt = pre.delta_t_s
        dp, dv, dq = _deltas_from_states(p_i, R_i, v_i, p_j, R_j, v_j, dt, gravity)
        truth = Deltas(dp, dv, dq, dt)
        est = pre.deltas()
        err[w] = delta_error(est, truth)
        if noise is not None and len(ts) >= 3:  # one step: p and v share one noise, singular
            try:
                ne[w] = nees(err[w], pre.covariance[:9, :9])
            except SplineImuError:
                pass  # singular (too few samples): NaN
        dps[w], dvs[w], dqs[w], nsamp[w] = est.delta_p, est.delta_v, est.delta_q_xyzw, len(ts)
        truths.append(truth)
    return WindowResult(windows[:, 0].copy(), windows[:, 1].copy(), nsamp, err, ne, dps, dvs, dqs, truths,
                        method, covariance)
