"""Scene base class, parameter declarations and the registry of scenes by name.

Time base: a scene starts at the integer nanosecond stamp ``origin_ns`` (``t0_ns``), and every
query time is float seconds since then, in ``[0, duration_s]``. Epoch stamps such as
``1_403_636_579_758_555_392`` lose nothing because the large origin is never converted to
float.

Scenes register themselves by name with :func:`register_scene` (see :mod:`splineimu.scenes`);
:func:`scene_names` lists the registered names, after importing the modules in
``EXTRA_SCENE_MODULES`` that exist, and :func:`make_scene` builds one by name.
"""

from __future__ import annotations

import difflib
import importlib
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..motion import Kinematics, MotionSource
from ..validation import int_in_range, positive_float

__all__ = ["SCENES", "EXTRA_SCENE_MODULES", "Param", "Scene", "register_scene", "scene_names", "make_scene"]

#: name -> Scene subclass; filled by :func:`register_scene`.
SCENES: dict[str, type] = {}

#: Modules that register more scenes; :func:`scene_names` imports those that exist (set
#: ``splineimu.scenes.base.EXTRA_SCENE_MODULES`` to add plug-in modules).
EXTRA_SCENE_MODULES: tuple[str, ...] = ()


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
    >>> from splineimu.scenes import StaticScene
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
        dur = positive_float(duration_s, "duration_s")
        self.origin_ns = _origin_ns(t0_ns)
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
        ConfigError
            Parameters whose motion is not finite (``speed_m_s=1e300`` overflows).
        """
        t = self.check_times(t_s)
        with np.errstate(all="ignore"):
            p, v, a, R, w, al = self._evaluate(t)
        if not all(np.isfinite(x).all() for x in (p, v, a, R, w, al)):
            first = min(int(np.argmin(np.isfinite(np.reshape(x, (t.size, -1))).all(axis=1)))
                        for x in (p, v, a, R, w, al) if not np.isfinite(x).all())
            label = type(self).name or type(self).__name__
            raise ConfigError(f"scene {label!r} with {self.describe()['params']} has no finite motion at t = "
                              f"{t[first]:g} s: a parameter too large?")
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
        from ..timegrid import uniform_stamps_ns

        return uniform_stamps_ns(self.origin_ns, self.origin_ns + int(round(self.duration_s * 1e9)), rate_hz)

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


def _origin_ns(t0_ns) -> int:
    """``t0_ns`` as an int in ``[0, 2^62)``; a float holding a whole number (from a yaml file) is accepted."""
    if isinstance(t0_ns, (float, np.floating)) and float(t0_ns).is_integer() and abs(t0_ns) < 2**53:
        t0_ns = int(t0_ns)
    return int_in_range(t0_ns, "t0_ns", 0, 2**62 - 1)
