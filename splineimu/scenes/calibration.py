"""Calibration scenes: the six-position test and a single-axis rate table, with exact kinematics.

Both scenes keep the body origin fixed at the world origin (``p = v = a_world = 0``), so the
specific force is gravity alone, ``f_b = R^T (0, 0, +g)``, and every change of orientation is a
smooth rotation about a fixed axis whose angle follows the minimum-jerk polynomial::

    s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5,    tau = (t - t_start) / T in [0, 1]
    s'     = 30 tau^2 - 60 tau^3 + 30 tau^4            (per unit tau; divide by T)
    s''    = 60 tau - 180 tau^2 + 120 tau^3            (divide by T^2)

``s`` goes from 0 to 1 with zero first and second derivatives at both ends, so the body rate
and the angular acceleration are continuous and exact everywhere (the dwell phases join the
moves without jumps):

- a *turn* from ``R0`` by the rotation vector ``rho`` (body frame): ``R(t) = R0 Exp(s rho)``,
  ``omega_body = (s'/T) rho``, ``alpha_body = (s''/T^2) rho`` (``Exp(s rho)`` commutes with
  its derivative);
- a *spin* of the table about the world vertical by the table angle ``Phi(t)``:
  ``R(t) = Rz(Phi(t)) R_m`` with the mount ``R_m``, ``omega_body = Phi' u``,
  ``alpha_body = Phi'' u``, ``u = R_m^T e_z``; a rate change from ``r_a`` to ``r_b`` has
  ``Phi' = r_a + (r_b - r_a) s``, ``Phi = Phi_0 + r_a (t - t_start) + (r_b - r_a) T S(tau)``
  with ``S(tau) = 2.5 tau^4 - 3 tau^5 + tau^6`` (the integral of ``s``).

Orientation error: each position (six-position) or mount (rate table) is
``R = Exp(eps) R_nominal`` with a world-frame rotation vector ``eps`` whose three components
are independent ``N(0, tilt_sigma_deg^2)`` draws from ``numpy.random.default_rng(tilt_seed)``
(positions in order). The gravity direction in the body is then
``u = R^T e_z = Exp(-R_nominal^T eps) u_nominal``: tilted by the two components of
``R_nominal^T eps`` perpendicular to ``u_nominal`` (each ``N(0, sigma^2)``; the RMS tilt angle
is ``sigma sqrt(2)``). :attr:`CalibrationScene.tilts_rad` and
:meth:`CalibrationScene.steady_phases` give the truth.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from .base import Param, Scene, register_scene
from .kinematics import rotation_z

__all__ = ["CalibrationScene", "SixPositionScene", "RateTableScene", "min_jerk", "nominal_up_rotation"]

_EZ = np.array([0.0, 0.0, 1.0])


def min_jerk(tau):
    """Minimum-jerk profile ``s(tau)`` and its first two derivatives in ``tau`` (clipped to [0, 1]).

    Examples
    --------
    >>> [float(v) for v in min_jerk(np.array([0.5]))[0]] == [0.5]
    True
    """
    x = np.clip(np.asarray(tau, dtype=np.float64), 0.0, 1.0)
    x2 = x * x
    s = x2 * x * (10.0 + x * (-15.0 + 6.0 * x))
    ds = 30.0 * x2 * (1.0 + x * (-2.0 + x))
    dds = x * (60.0 + x * (-180.0 + 120.0 * x))
    return s, ds, dds


def _min_jerk_integral(tau):
    x = np.clip(np.asarray(tau, dtype=np.float64), 0.0, 1.0)
    return x ** 4 * (2.5 + x * (-3.0 + x))


def nominal_up_rotation(axis: int, sign: int) -> np.ndarray:
    """``world_R_body`` (3, 3) that points body axis ``axis`` (0, 1, 2) with ``sign`` (+1/-1) up.

    Then ``R^T e_z = sign e_axis`` and a body at rest reads ``f = sign g e_axis``.

    Examples
    --------
    >>> R = nominal_up_rotation(0, +1)
    >>> (R.T @ [0, 0, 1]).round(12).tolist()
    [1.0, 0.0, 0.0]
    """
    if axis not in (0, 1, 2) or sign not in (1, -1):
        raise ConfigError(f"nominal orientation needs axis in 0..2 and sign +-1, got {axis}, {sign}")
    h = 0.5 * math.pi
    c = lambda a: (math.cos(a), math.sin(a))  # noqa: E731
    if axis == 2:
        return np.eye(3) if sign > 0 else np.diag([1.0, -1.0, -1.0])  # Rx(pi)
    if axis == 0:
        co, si = c(-h * sign)  # Ry(-pi/2) maps e_x to e_z
        return np.array([[co, 0.0, si], [0.0, 1.0, 0.0], [-si, 0.0, co]])
    co, si = c(h * sign)  # Rx(pi/2) maps e_y to e_z
    return np.array([[1.0, 0.0, 0.0], [0.0, co, -si], [0.0, si, co]])


def _rotvec_between(Ra, Rb):
    """Rotation vector ``rho`` with ``Ra Exp(rho) = Rb`` (body frame of ``Ra``)."""
    from ..lie import so3_log

    return np.asarray(so3_log(Ra.T @ Rb), dtype=np.float64)


def _seed(value, label) -> int:
    if value != int(value):
        raise ConfigError(f"scene {label!r} parameter `tilt_seed` must be a whole number, got {value!r}")
    return int(value)


class CalibrationScene(Scene):
    """Base of the calibration scenes: a schedule of *turn* and *spin* segments (module docstring).

    Subclasses build ``self._segments`` in :meth:`_build`; each segment is a dict with
    ``kind`` ("turn" or "spin"), ``t0``, ``T`` and its constants. Before the first segment and
    after the last one the body holds the first / last orientation. The natural length of the
    schedule is the default duration; a longer ``duration_s`` holds the last orientation (the
    last spin's rate is zero), a shorter one ends the scene early.

    Attributes
    ----------
    tilts_rad : (P, 3) float64
        World-frame orientation errors ``eps`` of the positions / mounts [rad].
    natural_duration_s : float
        Length of the schedule [s].
    """

    def __init_subclass__(cls, **kwargs):
        # the orientation-error parameters are shared: document them once, in every subclass
        super().__init_subclass__(**kwargs)
        if cls.__doc__ and "tilt_sigma_deg" in cls.PARAMS and "tilt_seed :" not in cls.__doc__:
            cls.__doc__ = cls.__doc__.rstrip() + "\n" + _TILT_DOC + "    "

    def __init__(self, duration_s=None, t0_ns: int = 0, **params):
        self._duration_given = duration_s is not None
        super().__init__(duration_s=duration_s, t0_ns=t0_ns, **params)

    def _setup(self):
        label = type(self).name or type(self).__name__
        n = self._n_orientations()
        rng = np.random.default_rng(_seed(self.params["tilt_seed"], label))
        sigma = math.radians(self.params["tilt_sigma_deg"])
        self.tilts_rad = rng.standard_normal((n, 3)) * sigma
        self.tilts_rad.setflags(write=False)
        self._segments: list[dict] = []
        self._phases: list[dict] = []
        self.natural_duration_s = float(self._build())
        if not self._duration_given:
            self.t_max_s = self.natural_duration_s
        self._t_starts = np.array([s["t0"] for s in self._segments])

    # ---------------------------------------------------------------- schedule building
    def _n_orientations(self) -> int:  # pragma: no cover - abstract
        raise NotImplementedError

    def _build(self) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def _mount(self, k: int, axis: int, sign: int) -> np.ndarray:
        from ..lie import so3_exp

        return np.asarray(so3_exp(self.tilts_rad[k]), dtype=np.float64) @ nominal_up_rotation(axis, sign)

    def _add_turn(self, t0, T, R0, R1):
        rho = _rotvec_between(R0, R1)
        self._segments.append({"kind": "turn", "t0": float(t0), "T": float(T), "R0": R0, "rho": rho})
        return float(t0) + float(T)

    def _add_spin(self, t0, T, Rm, phi0, rate_a, rate_b):
        """A spin segment; returns (end time, table angle at the end)."""
        self._segments.append({"kind": "spin", "t0": float(t0), "T": float(T), "Rm": Rm, "phi0": float(phi0),
                               "ra": float(rate_a), "rb": float(rate_b)})
        if rate_a == rate_b:
            phi1 = phi0 + rate_a * T
        else:
            phi1 = phi0 + rate_a * T + (rate_b - rate_a) * T * float(_min_jerk_integral(1.0))
        return float(t0) + float(T), phi1

    def _add_phase(self, t0, T, Rm, rate):
        u = Rm.T @ _EZ
        self._phases.append({"t_start_s": float(t0), "t_end_s": float(t0) + float(T),
                             "gravity_direction_body": u, "omega_body": rate * u})

    # ---------------------------------------------------------------- queries
    def steady_phases(self) -> list[dict]:
        """The scene's steady phases (rest or constant rate), in time order.

        Returns
        -------
        list of dict
            ``t_start_s``, ``t_end_s`` [s], ``gravity_direction_body`` (3,) unit vector
            ``R^T e_z`` (the specific force is ``g`` times it) and ``omega_body`` (3,) [rad/s].
            Truth for tests and reports; the calibration never reads it.
        """
        out = []
        for ph in self._phases:
            if ph["t_start_s"] >= self.t_max_s:
                break
            d = dict(ph)
            d["t_end_s"] = min(d["t_end_s"], self.t_max_s)
            d["gravity_direction_body"] = ph["gravity_direction_body"].copy()
            d["omega_body"] = ph["omega_body"].copy()
            out.append(d)
        return out

    # ---------------------------------------------------------------- evaluation
    def _evaluate(self, t):
        from ..lie import so3_exp

        n = t.shape[0]
        R = np.empty((n, 3, 3))
        w = np.zeros((n, 3))
        al = np.zeros((n, 3))
        idx = np.searchsorted(self._t_starts, t, side="right") - 1
        idx = np.clip(idx, 0, len(self._segments) - 1)
        for k, seg in enumerate(self._segments):
            m = idx == k
            if not np.any(m):
                continue
            T = seg["T"]
            tau = (t[m] - seg["t0"]) / T
            s, ds, dds = min_jerk(tau)
            if seg["kind"] == "turn":
                rho = seg["rho"]
                R[m] = seg["R0"] @ so3_exp(s[:, None] * rho[None, :])
                inside = (tau > 0.0) & (tau < 1.0)
                w[m] = np.where(inside[:, None], (ds / T)[:, None] * rho[None, :], 0.0)
                al[m] = np.where(inside[:, None], (dds / (T * T))[:, None] * rho[None, :], 0.0)
            else:
                ra, rb = seg["ra"], seg["rb"]
                u = seg["Rm"].T @ _EZ
                tt = np.clip(t[m] - seg["t0"], 0.0, T)
                if ra == rb:
                    phi = seg["phi0"] + ra * tt
                    rate = np.full(tt.shape, ra)
                    acc = np.zeros(tt.shape)
                else:
                    phi = seg["phi0"] + ra * tt + (rb - ra) * T * _min_jerk_integral(tau)
                    rate = ra + (rb - ra) * s
                    acc = (rb - ra) * ds / T
                # past the end of the last segment the body holds still
                after = t[m] > seg["t0"] + T
                rate = np.where(after, 0.0, rate)
                acc = np.where(after, 0.0, acc)
                R[m] = rotation_z(phi) @ seg["Rm"]
                w[m] = rate[:, None] * u[None, :]
                al[m] = acc[:, None] * u[None, :]
        z = np.zeros((n, 3))
        return z, z.copy(), z.copy(), R, w, al


_TILT_DOC = """\
    tilt_sigma_deg : float, default 0
        Orientation error [deg]: std of each component of the random world-frame rotation
        vector ``eps`` of every position / mount.
    tilt_seed : float, default 0
        Seed [1] (a whole number) of ``numpy.random.default_rng`` for ``eps``.
"""

_TILT_PARAMS = {
    "tilt_sigma_deg": Param(0.0, "deg", "orientation error: std of each world-frame rotation-vector "
                            "component of every position / mount", "nonnegative"),
    "tilt_seed": Param(0.0, "1", "seed of the orientation errors (a whole number)", "nonnegative"),
}

#: Order of the six positions: (axis, sign) up; consecutive positions are 90 degrees apart.
SIX_POSITION_ORDER = ((2, 1), (0, 1), (1, 1), (2, -1), (0, -1), (1, -1))


@register_scene("six-position")
class SixPositionScene(CalibrationScene):
    """Six-position accelerometer test: each body axis up and down, at rest, with turns between.

    Formulas (``D = dwell_s``, ``T = transition_s``; positions k = 0..5 in the order
    z up, x up, y up, z down, x down, y down, each 90 degrees from the previous one)::

        R_k = Exp(eps_k) R_nominal(k)     R_nominal(k)^T e_z = +-e_axis (that axis up)
        dwell k:  t in [k (D + T), k (D + T) + D]:   R = R_k,  omega = alpha = 0
        turn k:   t in [k (D + T) + D, (k + 1)(D + T)]:
                  R = R_k Exp(s(tau) rho_k),  rho_k = Log(R_k^T R_{k+1}),
                  omega_body = s'(tau)/T rho_k,  alpha_body = s''(tau)/T^2 rho_k
        p = v = accel_world = 0                   (so f_b = R^T (0, 0, g))

    with the minimum-jerk ``s`` of :mod:`splineimu.scenes.calibration` and ``eps_k`` the
    orientation errors (``tilt_sigma_deg``, ``tilt_seed``; zero by default). At rest in
    position k the accelerometer reads ``g R_k^T e_z``: ``+-g`` on the axis that is up.

    Default duration: 70 s (``6 D + 5 T`` with the default parameters; without
    ``duration_s`` the scene lasts exactly ``6 D + 5 T``; a longer one holds the last position).

    Parameters
    ----------
    dwell_s : float, default 10
        Time at rest in each position [s], > 0.
    transition_s : float, default 2
        Duration of each turn [s], > 0.
    """

    DEFAULT_DURATION_S = 70.0
    PARAMS = {
        "dwell_s": Param(10.0, "s", "time at rest in each position", "positive"),
        "transition_s": Param(2.0, "s", "duration of each turn between positions", "positive"),
        **_TILT_PARAMS,
    }

    def _n_orientations(self):
        return len(SIX_POSITION_ORDER)

    def _build(self):
        D, T = self.params["dwell_s"], self.params["transition_s"]
        mounts = [self._mount(k, a, s) for k, (a, s) in enumerate(SIX_POSITION_ORDER)]
        self.positions_world_R_body = np.array(mounts)
        t = 0.0
        for k, Rk in enumerate(mounts):
            self._add_phase(t, D, Rk, 0.0)
            t, _ = self._add_spin(t, D, Rk, 0.0, 0.0, 0.0)
            if k + 1 < len(mounts):
                t = self._add_turn(t, T, Rk, mounts[k + 1])
        return t


@register_scene("rate-table")
class RateTableScene(CalibrationScene):
    """Single-axis rate table: each body axis up in turn, spun at +rate and at -rate.

    Formulas (``r = rate_rad_s``, ``Dr = rest_s``, ``D = dwell_s``, ``Tr = ramp_s``,
    ``T = transition_s``; mounts i = x, y, z with that axis up)::

        mount i:  R_m,i = Exp(eps_i) R_nominal(i)      R_nominal(i)^T e_z = e_i
        on mount i (table angle Phi, about the world vertical):
          rest Dr | ramp 0 -> +r (Tr) | +r for D | ramp +r -> -r (Tr) | -r for D | ramp -r -> 0 (Tr)
          R = Rz(Phi(t)) R_m,i,   omega_body = Phi' u_i,   alpha_body = Phi'' u_i,  u_i = R_m,i^T e_z
          ramp a -> b:  Phi' = a + (b - a) s(tau),  Phi'' = (b - a) s'(tau) / Tr
        between mounts: a turn R = R_end Exp(s(tau) rho) over T (R_end = Rz(Phi_end) R_m,i,
          rho = Log(R_m,i^T R_m,i+1)); after the last mount a final rest Dr
        p = v = accel_world = 0                          (so f_b = g u_i on mount i)

    The table's axis is vertical, so on mount i the gyro reads ``Phi' u_i`` and the
    accelerometer the constant ``g u_i``; a mount error (``tilt_sigma_deg``) tilts ``u_i``
    away from ``e_i``.

    Default duration: 104 s (``4 Dr + 3 (2 D + 3 Tr) + 2 T`` with the default parameters;
    without ``duration_s`` the scene lasts exactly that long).

    Parameters
    ----------
    rate_rad_s : float, default 1
        Table rate magnitude [rad/s], > 0.
    dwell_s : float, default 10
        Time at each constant rate [s], > 0.
    rest_s : float, default 5
        Time at rest on each mount before spinning (and at the end) [s], > 0.
    ramp_s : float, default 2
        Duration of each rate change [s], > 0.
    transition_s : float, default 3
        Duration of the turn to the next mount [s], > 0.
    """

    DEFAULT_DURATION_S = 104.0
    PARAMS = {
        "rate_rad_s": Param(1.0, "rad/s", "table rate magnitude", "positive"),
        "dwell_s": Param(10.0, "s", "time at each constant rate", "positive"),
        "rest_s": Param(5.0, "s", "time at rest on each mount before spinning, and at the end", "positive"),
        "ramp_s": Param(2.0, "s", "duration of each rate change", "positive"),
        "transition_s": Param(3.0, "s", "duration of the turn to the next mount", "positive"),
        **_TILT_PARAMS,
    }

    def _n_orientations(self):
        return 3

    def _build(self):
        r = self.params["rate_rad_s"]
        D, Dr = self.params["dwell_s"], self.params["rest_s"]
        Tr, T = self.params["ramp_s"], self.params["transition_s"]
        mounts = [self._mount(i, i, 1) for i in range(3)]
        self.mounts_world_R_body = np.array(mounts)
        t, phi = 0.0, 0.0
        for i, Rm in enumerate(mounts):
            self._add_phase(t, Dr, Rm, 0.0)
            t, phi = self._add_spin(t, Dr, Rm, phi, 0.0, 0.0)
            t, phi = self._add_spin(t, Tr, Rm, phi, 0.0, r)
            self._add_phase(t, D, Rm, r)
            t, phi = self._add_spin(t, D, Rm, phi, r, r)
            t, phi = self._add_spin(t, Tr, Rm, phi, r, -r)
            self._add_phase(t, D, Rm, -r)
            t, phi = self._add_spin(t, D, Rm, phi, -r, -r)
            t, phi = self._add_spin(t, Tr, Rm, phi, -r, 0.0)
            if i + 1 < len(mounts):
                R_end = rotation_z(phi) @ Rm
                nxt = rotation_z(phi) @ mounts[i + 1]
                t = self._add_turn(t, T, R_end, nxt)  # the next mount at the table angle reached
        Rl = mounts[-1]
        self._add_phase(t, Dr, Rl, 0.0)
        t, phi = self._add_spin(t, Dr, Rl, phi, 0.0, 0.0)
        return t
