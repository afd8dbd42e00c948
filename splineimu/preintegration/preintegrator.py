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

import numpy as np

from .._kernels import preintegration as _k
from ..errors import ConfigError, InputError, SplineImuError
from ..lie import matrix_to_quat_xyzw, quat_xyzw_to_matrix, so3_exp
from ..motion import DEFAULT_GRAVITY
from ..validation import as_quat_xyzw, as_times_s, as_vector, as_vectors, finite_float, one_of
from .deltas import Deltas

__all__ = ["Preintegrator", "METHODS", "COVARIANCE_MODELS", "STATE_ORDER"]

METHODS = ("midpoint", "euler")
COVARIANCE_MODELS = ("consistent", "vins")
#: Error-state blocks of :attr:`Preintegrator.covariance` and :attr:`Preintegrator.jacobian`.
STATE_ORDER = ("p", "theta", "v", "b_a", "b_g")

O_P, O_R, O_V, O_BA, O_BG = 0, 3, 6, 9, 12


def _noise_density(value, name) -> np.ndarray:
    """A density given as one number or per axis, as a (3,) array >= 0."""
    a = as_vector(np.full(3, finite_float(value, name)) if np.ndim(value) == 0 else value, name)
    if np.any(a < 0):
        raise ConfigError(f"`{name}` must be zero or positive, got {value!r}", option=name)
    return a


def _rotation(quat_xyzw, name) -> np.ndarray:
    """(3, 3) rotation of one quaternion argument (checked: shape (4,), finite, non-zero)."""
    q = as_quat_xyzw(np.reshape(as_vector(quat_xyzw, name, 4), (1, 4)), name)
    return quat_xyzw_to_matrix(q[0])


def _part(array_name: str, lo: int, hi: int, doc: str) -> property:
    """A read-only property returning a copy of ``self.<array_name>[lo:hi]``."""
    return property(lambda self: getattr(self, array_name)[lo:hi].copy(), doc=doc)


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
        self.method = one_of(method, "method", METHODS)
        self.covariance_model = one_of(covariance, "covariance", COVARIANCE_MODELS)
        self.compute_covariance = bool(compute_covariance)
        self.gyro_noise_density = _noise_density(gyro_noise_density, "gyro_noise_density")
        self.accel_noise_density = _noise_density(accel_noise_density, "accel_noise_density")
        self.gyro_random_walk = _noise_density(gyro_random_walk, "gyro_random_walk")
        self.accel_random_walk = _noise_density(accel_random_walk, "accel_random_walk")
        bg = as_vector(bias_gyro, "bias_gyro")
        ba = as_vector(bias_accel, "bias_accel")
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

    bias_gyro = _part("_params", 0, 3, "(3,) gyro bias linearization point [rad/s].")
    bias_accel = _part("_params", 3, 6, "(3,) accelerometer bias linearization point [m/s^2].")
    delta_p = _part("_nav", 0, 3, "(3,) preintegrated position delta [m].")
    delta_v = _part("_nav", 3, 6, "(3,) preintegrated velocity delta [m/s].")

    @property
    def n_samples(self) -> int:
        return self._n

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
        t = as_times_s(np.atleast_1d(t_s), "t_s", increasing=True)
        n = t.shape[0]
        if n == 0 and np.size(gyro) == 0 and np.size(accel) == 0:
            return self
        g = as_vectors(gyro, "gyro", n)
        a = as_vectors(accel, "accel", n)
        if self._n and t[0] <= self._prev[0]:
            raise InputError(
                f"`t_s[0]` = {t[0]!r} must come after the last sample integrated ({self._prev[0]!r})"
            )
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
        self._reset(as_vector(bias_gyro, "bias_gyro"), as_vector(bias_accel, "bias_accel"))
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
        dbg = as_vector(bias_gyro, "bias_gyro") - self._params[0:3]
        dba = as_vector(bias_accel, "bias_accel") - self._params[3:6]
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
        p_i, v_i, p_j, v_j, ba_i, bg_i, ba_j, bg_j, g = (
            as_vector(x, name) for x, name in ((p_i, "p_i"), (v_i, "v_i"), (p_j, "p_j"), (v_j, "v_j"),
                                               (ba_i, "ba_i"), (bg_i, "bg_i"), (ba_j, "ba_j"), (bg_j, "bg_j"),
                                               (gravity, "gravity")))
        R_i = _rotation(q_i_xyzw, "q_i_xyzw")
        R_j = _rotation(q_j_xyzw, "q_j_xyzw")
        c = self.corrected(bg_i, ba_i)
        dt = self.delta_t_s
        r = np.empty(15)
        r[O_P:O_P + 3] = R_i.T @ (p_j - p_i - v_i * dt - 0.5 * g * dt * dt) - c.delta_p
        qe = matrix_to_quat_xyzw(c.delta_R.T @ R_i.T @ R_j)  # w >= 0
        r[O_R:O_R + 3] = 2.0 * qe[:3]
        r[O_V:O_V + 3] = R_i.T @ (v_j - v_i - g * dt) - c.delta_v
        r[O_BA:O_BA + 3] = ba_j - ba_i
        r[O_BG:O_BG + 3] = bg_j - bg_i
        return r

    def predict(self, p_i, q_i_xyzw, v_i, gravity=DEFAULT_GRAVITY):
        """State at j from the state at i and the deltas: ``(p_j (3,), q_j_xyzw (4,), v_j (3,))``."""
        p_i = as_vector(p_i, "p_i")
        v_i = as_vector(v_i, "v_i")
        g = as_vector(gravity, "gravity")
        R_i = _rotation(q_i_xyzw, "q_i_xyzw")
        dt = self.delta_t_s
        p_j = p_i + v_i * dt + 0.5 * g * dt * dt + R_i @ self.delta_p
        v_j = v_i + g * dt + R_i @ self.delta_v
        return p_j, matrix_to_quat_xyzw(R_i @ self.delta_R), v_j

    def __repr__(self) -> str:
        return (
            f"Preintegrator(method={self.method!r}, covariance={self.covariance_model!r}, "
            f"n_samples={self._n}, delta_t_s={self.delta_t_s:.6f})"
        )
