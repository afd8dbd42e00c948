"""Analytic reference scenes: closed-form trajectories with exact derivatives.

A scene is a :class:`~splineimu.motion.MotionSource` whose pose, body rate, angular
acceleration, velocity and acceleration are all written out in closed form (no finite
differences), so it is the reference that splines, IMU synthesis, integrators and
preintegration are checked against.

Time base: a scene starts at the integer nanosecond stamp ``origin_ns`` (``t0_ns``), and every
query time is float seconds since then, in ``[0, duration_s]``. Epoch stamps such as
``1_403_636_579_758_555_392`` lose nothing because the large origin is never converted to
float.

Registry
--------
Scenes register themselves by name with :func:`register_scene`; any module can add one::

    from splineimu.scenes import Scene, Param, register_scene

    @register_scene("my-scene")
    class MyScene(Scene):
        '''Formulas, default duration, parameters with units.'''
        DEFAULT_DURATION_S = 10.0
        PARAMS = {"speed_m_s": Param(1.0, "m/s", "forward speed")}

        def _evaluate(self, t):
            ...  # return p, v, a, R, omega, alpha

:func:`scene_names` lists the registered names, after importing the modules in
``EXTRA_SCENE_MODULES`` that exist (the calibration scenes live there), and
:func:`make_scene` builds one by name.

Built-in scenes: ``ellipse`` (the lecture's scene, DESIGN.md section 4), ``static``,
``circle``, ``screw`` (constant body twist) and ``flips`` (aggressive hand-held-like
tumbling).
"""

from __future__ import annotations

import difflib
import importlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ConfigError
from .motion import Kinematics, MotionSource

__all__ = [
    "SCENES", "EXTRA_SCENE_MODULES", "Param", "Scene", "register_scene", "scene_names",
    "make_scene", "write_scene_tum", "euler_zyx_kinematics",
    "EllipseScene", "StaticScene", "CircleScene", "ScrewScene", "FlipsScene",
]

#: name -> Scene subclass; filled by :func:`register_scene`.
SCENES: dict[str, type] = {}

#: Modules that register more scenes; :func:`scene_names` imports those that exist.
EXTRA_SCENE_MODULES: tuple[str, ...] = ("splineimu.calibration_scenes",)


# ------------------------------------------------------------------------------ registry


def register_scene(name: str):
    """Class decorator: register a :class:`Scene` subclass under ``name``.

    Parameters
    ----------
    name : str
        The scene's name as used by :func:`make_scene` and the command line.

    Raises
    ------
    ConfigError
        If ``name`` is taken by a different class, or the class is not a :class:`Scene`.

    Examples
    --------
    >>> @register_scene("doc-example")
    ... class _Still(StaticScene):
    ...     '''Like ``static``, under another name.'''
    >>> make_scene("doc-example", position_m="1,2,3").kinematics([0.5]).position_world
    array([[1., 2., 3.]])
    >>> del SCENES["doc-example"]
    """
    if not isinstance(name, str) or not name:
        raise ConfigError(f"Expected a non-empty scene name, got {name!r}")

    def deco(cls):
        if not (isinstance(cls, type) and issubclass(cls, Scene)):
            raise ConfigError(f"scene {name!r}: {cls!r} is not a subclass of splineimu.scenes.Scene")
        old = SCENES.get(name)
        if old is not None and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
            raise ConfigError(
                f"scene name {name!r} is already registered by {old.__module__}.{old.__qualname__}"
            )
        cls.name = name
        SCENES[name] = cls
        return cls

    return deco


def _load_extra_modules() -> None:
    for mod in EXTRA_SCENE_MODULES:
        try:
            importlib.import_module(mod)
        except ModuleNotFoundError as e:
            # Only "this optional module does not exist" is ignored; a missing import
            # *inside* it is a real error and propagates.
            if e.name != mod:
                raise


def scene_names() -> list[str]:
    """Sorted names of all registered scenes (built-in and from ``EXTRA_SCENE_MODULES``)."""
    _load_extra_modules()
    return sorted(SCENES)


def make_scene(name: str, duration_s: float | None = None, t0_ns: int = 0, **params) -> Scene:
    """Build a registered scene by name.

    Parameters
    ----------
    name : str
        A name from :func:`scene_names`.
    duration_s : float, optional
        Length of the valid range ``[0, duration_s]`` in seconds; the scene's
        ``DEFAULT_DURATION_S`` when omitted.
    t0_ns : int, default 0
        Integer nanosecond stamp of ``t = 0`` (``origin_ns``), e.g. a Unix-epoch stamp.
    **params
        Scene parameters (see each scene's docstring). Values may be numbers, sequences, or
        strings such as ``"2.5"`` or ``"1,2,3"`` (as given on a command line).

    Returns
    -------
    Scene

    Raises
    ------
    ConfigError
        Unknown scene name (with a did-you-mean), unknown or invalid parameter, bad
        ``duration_s`` or ``t0_ns``.

    Examples
    --------
    >>> sc = make_scene("ellipse")
    >>> sc.kinematics([0.0]).position_world
    array([[20.,  5.,  5.]])
    """
    if name not in SCENES:
        _load_extra_modules()
    cls = SCENES.get(name)
    if cls is None:
        known = sorted(SCENES)
        close = difflib.get_close_matches(str(name), known, n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise ConfigError(f"unknown scene {name!r}.{hint} Known scenes: {', '.join(known)}")
    return cls(duration_s=duration_s, t0_ns=t0_ns, **params)


# ------------------------------------------------------------------------------ parameters


@dataclass(frozen=True)
class Param:
    """Declaration of one scene parameter.

    Attributes
    ----------
    default : float or tuple of float
        Default value; a tuple makes it a vector parameter of that length.
    unit : str
        Unit, e.g. ``"m"``, ``"rad/s"``, ``"1"`` for dimensionless.
    doc : str
        One-line description.
    check : {None, "positive", "nonnegative"}
        Constraint on every component.
    """

    default: float | tuple
    unit: str
    doc: str
    check: str | None = None

    @property
    def size(self) -> int:
        """0 for a scalar, else the vector length."""
        return len(self.default) if isinstance(self.default, tuple) else 0

    def coerce(self, scene: str, name: str, value):
        """Validated float (scalar) or read-only float64 array (vector)."""
        where = f"scene {scene!r} parameter `{name}`"
        if isinstance(value, str):
            parts = [s for s in value.replace(",", " ").split() if s]
            try:
                vals = [float(s) for s in parts]
            except ValueError:
                raise ConfigError(f"{where}: cannot read {value!r} as numbers") from None
            value = vals[0] if (self.size == 0 and len(vals) == 1) else vals
        if isinstance(value, bool):
            raise ConfigError(f"{where}: expected a number, got {value!r}")
        try:
            arr = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise ConfigError(f"{where}: expected a number or numbers, got {value!r}") from None
        want = () if self.size == 0 else (self.size,)
        if arr.shape != want:
            exp = "a scalar" if self.size == 0 else f"{self.size} values"
            raise ConfigError(f"{where}: expected {exp}, got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ConfigError(f"{where}: must be finite, got {value!r}")
        if self.check == "positive" and np.any(arr <= 0.0):
            raise ConfigError(f"{where}: must be > 0, got {value!r}")
        if self.check == "nonnegative" and np.any(arr < 0.0):
            raise ConfigError(f"{where}: must be >= 0, got {value!r}")
        if self.size == 0:
            return float(arr)
        arr = arr.copy()
        arr.setflags(write=False)
        return arr


# ------------------------------------------------------------------------------ base class


class Scene(MotionSource):
    """Base class of the analytic scenes.

    Subclasses set ``DEFAULT_DURATION_S`` and ``PARAMS`` (name -> :class:`Param`), may
    override :meth:`_setup` to precompute constants from ``self.params``, and implement
    :meth:`_evaluate`, which returns exact closed-form values at valid times.

    Parameters
    ----------
    duration_s : float, optional
        Valid range is ``[0, duration_s]`` seconds; default ``DEFAULT_DURATION_S``.
    t0_ns : int, default 0
        Integer nanosecond stamp of ``t = 0``; must be >= 0.
    **params
        The scene's parameters; missing ones take their defaults.

    Attributes
    ----------
    name : str
        Registered name.
    origin_ns : int
        ``t0_ns``.
    t_min_s, t_max_s : float
        ``0.0`` and ``duration_s``.
    params : dict
        Validated parameters (floats, or read-only (n,) float64 arrays).
    """

    name: str = ""
    DEFAULT_DURATION_S: float = 10.0
    PARAMS: dict[str, Param] = {}

    def __init__(self, duration_s: float | None = None, t0_ns: int = 0, **params):
        cls = type(self)
        label = cls.name or cls.__name__
        if duration_s is None:
            duration_s = cls.DEFAULT_DURATION_S
        if isinstance(duration_s, bool):
            raise ConfigError(f"scene {label!r}: expected `duration_s` to be a number, got {duration_s!r}")
        try:
            dur = float(duration_s)
        except (TypeError, ValueError):
            raise ConfigError(
                f"scene {label!r}: expected `duration_s` to be a number, got {duration_s!r}"
            ) from None
        if not (math.isfinite(dur) and dur > 0.0):
            raise ConfigError(f"scene {label!r}: `duration_s` must be finite and > 0, got {duration_s!r}")
        self.origin_ns = _as_origin_ns(t0_ns, label)
        self.t_min_s = 0.0
        self.t_max_s = dur

        unknown = [k for k in params if k not in cls.PARAMS]
        if unknown:
            k = unknown[0]
            close = difflib.get_close_matches(k, list(cls.PARAMS), n=1)
            hint = f" Did you mean {close[0]!r}?" if close else ""
            names = ", ".join(cls.PARAMS) or "(none)"
            raise ConfigError(f"scene {label!r} has no parameter {k!r}.{hint} Parameters: {names}")
        self.params = {}
        for k, spec in cls.PARAMS.items():
            self.params[k] = spec.coerce(label, k, params.get(k, spec.default))
        self._setup()

    # -------------------------------------------------------------- subclass hooks
    def _setup(self) -> None:
        """Precompute constants from ``self.params`` (optional)."""

    def _evaluate(self, t: np.ndarray):  # pragma: no cover - abstract
        """Return ``(p, v, a, R, omega, alpha)`` at valid times ``t`` (N,)."""
        raise NotImplementedError

    # -------------------------------------------------------------- public
    @property
    def duration_s(self) -> float:
        return self.t_max_s - self.t_min_s

    def kinematics(self, t_s) -> Kinematics:
        """Exact pose and derivatives at ``t_s`` (N,) seconds since ``origin_ns``.

        Returns
        -------
        Kinematics
            ``position_world``, ``velocity_world``, ``accel_world``, ``omega_body``,
            ``alpha_body`` (N, 3) and ``world_R_body`` (N, 3, 3), float64, C-contiguous.

        Raises
        ------
        RangeError
            A time outside ``[t_min_s, t_max_s]``, NaN, or a non-1-D input.
        """
        t = self.check_times(t_s)
        p, v, a, R, w, al = self._evaluate(t)
        c = np.ascontiguousarray
        return Kinematics(
            t_s=t,
            position_world=c(p, dtype=np.float64),
            world_R_body=c(R, dtype=np.float64),
            omega_body=c(w, dtype=np.float64),
            alpha_body=c(al, dtype=np.float64),
            velocity_world=c(v, dtype=np.float64),
            accel_world=c(a, dtype=np.float64),
        )

    def sample_times_ns(self, rate_hz: float) -> np.ndarray:
        """Absolute int64 stamps ``origin_ns + round(k 1e9 / rate_hz)`` inside the valid range.

        ``k = 0, 1, ...`` while the stamp is within ``duration_s`` (both ends included when the
        duration is a whole number of periods). Integer rates use exact integer arithmetic.
        """
        from .timegrid import uniform_stamps_ns

        return uniform_stamps_ns(self.origin_ns, self.origin_ns + int(round(self.duration_s * 1e9)), _as_rate(rate_hz))

    def describe(self) -> dict:
        """JSON-friendly summary: name, duration, origin and parameters (with units)."""
        params = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.params.items()}
        return {
            "name": type(self).name,
            "duration_s": self.duration_s,
            "t0_ns": int(self.origin_ns),
            "params": params,
            "units": {k: spec.unit for k, spec in type(self).PARAMS.items()},
        }

    def __repr__(self) -> str:
        ps = ", ".join(
            f"{k}={v.tolist() if isinstance(v, np.ndarray) else v!r}" for k, v in self.params.items()
        )
        sep = ", " if ps else ""
        return (f"{type(self).__name__}(duration_s={self.duration_s!r}, "
                f"t0_ns={self.origin_ns}{sep}{ps})")


def _as_origin_ns(t0_ns, label: str) -> int:
    if isinstance(t0_ns, bool):
        raise ConfigError(f"scene {label!r}: expected `t0_ns` to be an integer, got {t0_ns!r}")
    if isinstance(t0_ns, str):
        try:
            t0_ns = int(t0_ns.strip())
        except ValueError:
            raise ConfigError(f"scene {label!r}: expected `t0_ns` to be an integer, got {t0_ns!r}") from None
    if isinstance(t0_ns, (int, np.integer)):
        v = int(t0_ns)
    elif isinstance(t0_ns, (float, np.floating)) and float(t0_ns).is_integer() and abs(t0_ns) < 2**53:
        v = int(t0_ns)
    else:
        raise ConfigError(
            f"scene {label!r}: expected `t0_ns` to be an integer number of nanoseconds, got {t0_ns!r}"
        )
    if not (0 <= v < 2**62):
        raise ConfigError(f"scene {label!r}: `t0_ns` must be in [0, 2^62), got {v}")
    return v


def _as_rate(rate_hz) -> float:
    if isinstance(rate_hz, bool):
        raise ConfigError(f"Expected `rate_hz` to be a number, got {rate_hz!r}")
    try:
        r = float(rate_hz)
    except (TypeError, ValueError):
        raise ConfigError(f"Expected `rate_hz` to be a number, got {rate_hz!r}") from None
    if not (math.isfinite(r) and 0.0 < r <= 1e9):
        raise ConfigError(f"Expected `rate_hz` in (0, 1e9], got {rate_hz!r}")
    return r


# ------------------------------------------------------------------------------ helpers


def _rz(yaw):
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


def _sum_of_sines(t, table, scale=1.0):
    """``x = scale sum_j A_j sin(w_j t + phi_j)`` and its first two derivatives, (N,) each."""
    x = np.zeros_like(t)
    dx = np.zeros_like(t)
    ddx = np.zeros_like(t)
    for amp, om, ph in table:
        arg = om * t + ph
        s, c = np.sin(arg), np.cos(arg)
        x += amp * s
        dx += amp * om * c
        ddx -= amp * om * om * s
    return scale * x, scale * dx, scale * ddx


# ------------------------------------------------------------------------------ scenes


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
        c, s = np.cos(K * t), np.sin(K * t)
        w1 = K1 * K
        cz, sz = np.cos(w1 * t), np.sin(w1 * t)
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
        ang = np.stack([0.1 * ct, 0.2 * st, K * t], axis=1)
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
        self._R = _rz(np.float64(self.params["yaw_rad"]))

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
        th = self.params["phase_rad"] + w * t
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
        R = _rz(yaw)
        om = np.zeros((n, 3))
        om[:, 2] = w
        return p, v, a, R, om, np.zeros((n, 3))


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
        from .lie import so3_exp

        self._R0 = so3_exp(self.params["initial_rotvec_rad"])
        self._p0 = np.array(self.params["initial_position_m"])
        self._xi = np.concatenate([self.params["v_body_m_s"], self.params["omega_body_rad_s"]])

    @property
    def world_T_body0(self) -> np.ndarray:
        """``T0`` (4, 4)."""
        T = np.eye(4)
        T[:3, :3] = self._R0
        T[:3, 3] = self._p0
        return T

    @property
    def twist_body(self) -> np.ndarray:
        """``xi = [v_b, w_b]`` (6,)."""
        return self._xi.copy()

    def _evaluate(self, t):
        from .lie import se3_exp

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
            x, dx, ddx = _sum_of_sines(t, _FLIPS_ANGLE_SINES[i], sw)
            ang[:, i] = W[i] * t + x
            rates[:, i] = W[i] + dx
            accs[:, i] = ddx
            x, dx, ddx = _sum_of_sines(t, _FLIPS_POSITION_SINES[i], ss)
            p[:, i] = self.params["position_m"][i] + x
            v[:, i] = dx
            a[:, i] = ddx
        R, w, al = euler_zyx_kinematics(ang, rates, accs)
        return p, v, a, R, w, al


# ------------------------------------------------------------------------------ TUM output


def write_scene_tum(scene: Scene, path, rate_hz: float) -> Path:
    """Write a scene's poses at a uniform rate as a TUM trajectory file, atomically.

    Parameters
    ----------
    scene : Scene
        Any motion source with ``origin_ns``, ``t_min_s``, ``t_max_s`` (a :class:`Scene`
        gives its :meth:`Scene.sample_times_ns`).
    path : str or os.PathLike
        Output file; replaced if it exists (written to a temporary file in the same
        directory, then ``os.replace``).
    rate_hz : float
        Sample rate [Hz]. Stamps are ``origin_ns + round(k 1e9 / rate_hz)``.

    Returns
    -------
    pathlib.Path
        The written path.

    Notes
    -----
    Lines are ``timestamp tx ty tz qx qy qz qw`` with the absolute timestamp printed
    exactly from integer nanoseconds as ``"%d.%09d"`` (seconds.nanoseconds) and
    quaternions made sign-continuous along time, through :func:`splineimu.io.tum.write_tum`.
    """
    if isinstance(scene, Scene):
        t_ns = scene.sample_times_ns(rate_hz)
    else:
        rate = _as_rate(rate_hz)
        n = int(math.floor((scene.t_max_s - scene.t_min_s) * rate + 1e-9)) + 1
        start = int(scene.origin_ns) + int(round(scene.t_min_s * 1e9))
        t_ns = start + np.rint(np.arange(n) * (1e9 / rate)).astype(np.int64)
    t_s = scene.t_s_from_ns(t_ns)
    t_s = np.clip(t_s, scene.t_min_s, scene.t_max_s)
    pos, quat = scene.pose(t_s)
    from .lie import quat_make_continuous

    quat = quat_make_continuous(quat)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    from .io.tum import write_tum

    write_tum(path, t_ns, pos, quat)
    return path


