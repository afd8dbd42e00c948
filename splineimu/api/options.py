"""Typed, validated options of a synthesis job, shared by Python, command-line flags and scene files.

A :class:`SynthesisJob` holds one motion input (:class:`PosesInput` or :class:`SceneInput`),
the :class:`ImuOptions` and the :class:`OutputOptions`. Every value is checked when the object
is built, through :mod:`splineimu.validation`; the error names the value the way its author
wrote it: the argument (``rate_hz``), the command-line flag (``--rate``) or the scene-file key
with its file and line (``scene.yaml:4: `imu.rate_hz` must be positive``). Where the values came
from is the ``origin`` of each object (:class:`Origin`; plain Python names by default).

:meth:`SynthesisJob.to_argv` renders the equivalent ``splineimu`` command line; parsing it gives
an equal job (the flag of each field is in :data:`FLAGS`).

Examples
--------
>>> imu = ImuOptions(rate_hz=400, model="adis16448", seed=3)
>>> job = SynthesisJob(SceneInput("ellipse", duration_s=5), imu, OutputOptions("out"))
>>> job.to_argv()
['scene', 'ellipse', '--duration', '5', '--rate', '400', '--imu', 'adis16448', '--seed', '3', '-o', 'out']
>>> ImuOptions(rate_hz=-1)
Traceback (most recent call last):
...
splineimu.errors.ConfigError: `rate_hz` must be positive, got -1
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ConfigError, InputError
from ..validation import (
    as_rate_hz,
    as_seed,
    as_vector,
    finite_float,
    int_in_range,
    nonnegative_float,
    one_of,
    positive_float,
)
from .argv import FLAGS, SPLINE_FIELDS, job_argv

DEFAULT_GRAVITY = (0.0, 0.0, -9.81)


class Origin:
    """Where option values came from: names them in errors. The default is Python arguments."""

    def name(self, fld: str) -> str:
        return fld

    def where(self, fld: str):
        return None

    def relocate(self, fld: str, exc: ConfigError, keys=()) -> ConfigError:
        """An error raised while reading a nested value (an inline IMU model), re-placed here."""
        return ConfigError(f"`{self.name(fld)}`: {exc.problem}", option=self.name(fld))


class FlagOrigin(Origin):
    """Values from command-line flags: errors name the flag (``--rate``)."""

    def name(self, fld):
        return FLAGS.get(fld, fld)


class YamlOrigin(Origin):
    """Values from a scene file: errors name the key and its file and line.

    Parameters
    ----------
    doc : splineimu.io.yaml.YamlDoc
    keys : dict
        Field name -> key path in the document, e.g. ``{"rate_hz": ("imu", "rate_hz")}``.
    """

    def __init__(self, doc, keys: dict):
        self.doc = doc
        self.keys = keys

    def name(self, fld):
        return ".".join(map(str, self.keys.get(fld, (fld,))))

    def where(self, fld):
        return self.doc.where(*self.keys.get(fld, (fld,)))

    def relocate(self, fld, exc, keys=()):
        path = self.keys.get(fld, (fld,))
        line = self.doc.line(*path)
        for k in keys:  # the nested key the message names, if any
            if f"`{k}`" in exc.problem:
                line = self.doc.line(*path, k)
                break
        return ConfigError(f"`{self.name(fld)}`: {exc.problem}", path=self.doc.name, line=line,
                           option=self.name(fld))


_PLAIN = Origin()


def _origin_field():
    return field(default=None, compare=False, repr=False)


class _Checked:
    """Helpers shared by the options classes (validation in ``__post_init__``)."""

    origin: Origin | None

    def _o(self) -> Origin:
        return self.origin or _PLAIN

    def _kw(self, fld):
        o = self._o()
        return o.name(fld), {"where": o.where(fld)}

    def _err(self, fld, message) -> ConfigError:
        o = self._o()
        where = o.where(fld)
        path, line = where if isinstance(where, tuple) else (where, None)
        return ConfigError(f"`{o.name(fld)}` {message}", path=path, line=line, option=o.name(fld))

    def _bool(self, fld):
        v = getattr(self, fld)
        if not isinstance(v, bool):
            raise self._err(fld, f"must be true or false, got {v!r}")
        return v

    def _choice(self, fld, choices):
        name, kw = self._kw(fld)
        return one_of(getattr(self, fld), name, choices, **kw)

    def _path(self, fld, required=False):
        v = getattr(self, fld)
        if v is None:
            if required:
                raise self._err(fld, "is required")
            return None
        if not isinstance(v, (str, Path)) or not str(v):
            raise self._err(fld, f"must be a path, got {v!r}")
        return str(v)

    def _mapping_or_spec(self, fld):
        """A value that may be an inline mapping: text starting with ``{`` is read as YAML."""
        v = getattr(self, fld)
        if isinstance(v, Path):
            return str(v)
        if isinstance(v, str) and v.lstrip().startswith("{"):
            from ..io.yaml import parse_yaml

            v = parse_yaml(v, self._o().name(fld)).data
        return v


@dataclass
class ImuOptions(_Checked):
    """The IMU: sample stamps, sensor model, mounting, gravity and random seed.

    Parameters
    ----------
    rate_hz : float
        Sample rate of a uniform stamp grid over the motion's span.
    timestamps : str, optional
        A file whose first column gives the stamps instead (ns or decimal seconds).
    model : str, dict or ImuConfig, optional
        Preset name, Kalibr ``imu.yaml`` path, an inline mapping of its keys (also as YAML
        text ``"{gyroscope_noise_density: 0.01}"``) or an :class:`~splineimu.imu.config.ImuConfig`.
        Without it the data are noise-free.
    extrinsic : str, dict or Extrinsic, optional
        ``body_T_sensor``: a YAML file, a mapping (``translation`` + ``quat_xyzw``, or ``T_BS``)
        or an :class:`~splineimu.imu.ideal.Extrinsic`.
    gravity : (3,) float
        World gravity [m/s^2].
    sampling : {"point", "mean"}
        Value at the stamp, or mean over ``[previous stamp, stamp]``.
    increments : bool
        Also write delta-angle / delta-velocity per interval.
    seed : int, optional
        Seed of the run's random streams: the sensor model's, and (from their own child
        streams, so the sensor noise is the same with or without them) the timing's and the
        vibration's. A fresh one is drawn and reported when something random is modelled
        without a seed.
    timing : TimingModel or mapping, optional
        Clock offset and drift, stamp noise and dropped samples
        (:class:`~splineimu.imu.timing.TimingModel`; keys ``time_offset_s``,
        ``clock_drift_ppm``, ``stamp_noise_s``, ``drop_probability``, ``drop_burst_s``).
        Not with ``timestamps``. Without it (or with every key zero) the samples lie on the
        plain grid.
    vibration : VibrationModel, mapping, str, optional
        Sinusoidal and random vibration added before the sensor model
        (:class:`~splineimu.imu.vibration.VibrationModel`): a mapping with ``accel`` / ``gyro``
        lists, a YAML file holding one, or that mapping as YAML text.
    rostopic : str
        The IMU's ROS topic, written to ``imu.yaml`` / ``kalibr_imu_chain.yaml`` and used in bags.

    Raises
    ------
    ConfigError
        A value out of range, an unknown preset, a bad IMU model, extrinsic, timing or
        vibration.
    """

    rate_hz: float = 200.0
    timestamps: str | None = None
    model: object = None
    extrinsic: object = None
    gravity: tuple = DEFAULT_GRAVITY
    sampling: str = "point"
    increments: bool = False
    seed: int | None = None
    timing: object = None
    vibration: object = None
    rostopic: str = "/imu0"
    origin: Origin | None = _origin_field()

    def __post_init__(self):
        if not isinstance(self.rostopic, str) or not self.rostopic or any(c.isspace() for c in self.rostopic):
            raise self._err("rostopic", f"must be a ROS topic name like /imu0, got {self.rostopic!r}")
        name, kw = self._kw("rate_hz")
        self.rate_hz = as_rate_hz(self.rate_hz, name, **kw)
        self.timestamps = self._path("timestamps")
        name, kw = self._kw("gravity")
        try:
            self.gravity = tuple(float(x) for x in as_vector(self.gravity, name, **kw))
        except InputError as exc:  # a configuration value, not input data
            raise ConfigError(exc.problem, path=exc.path, line=exc.line, option=name) from None
        self.sampling = self._choice("sampling", ("point", "mean"))
        self.increments = self._bool("increments")
        name, kw = self._kw("seed")
        self.seed = as_seed(self.seed, name, **kw)
        self.model = self._mapping_or_spec("model")
        self.extrinsic = self._mapping_or_spec("extrinsic")
        self._config = self._load_model()
        self._body_T_sensor = self._load_extrinsic()
        from .effects import load_timing, load_vibration

        self.timing = load_timing(self._mapping_or_spec("timing"), self._o())
        self.vibration = load_vibration(self._mapping_or_spec("vibration"), self._o())
        if self.timing is not None and self.timestamps is not None:
            raise self._err("timing", "applies to the IMU's own clock grid (`rate_hz`), not to given `timestamps`")

    def _load_model(self):
        if self.model is None:
            return None
        from ..imu.config import ImuConfig, load_imu_config

        m = self.model
        if not isinstance(m, (str, dict, ImuConfig)):
            raise self._err("model", f"must be a preset name, a file or a mapping, got {type(m).__name__}")
        try:
            if isinstance(m, dict):
                base = None
                w = self._o().where("model")
                if isinstance(w, tuple) and w[0]:
                    base = Path(w[0]).parent
                return ImuConfig.from_dict(m, base_dir=base)
            return load_imu_config(m)
        except ConfigError as exc:
            if exc.path is not None:  # an IMU yaml file: its own file and line
                raise
            raise self._o().relocate("model", exc, list(m) if isinstance(m, dict) else ()) from None

    def _load_extrinsic(self):
        from ..imu.ideal import Extrinsic

        e = self.extrinsic
        if e is None or isinstance(e, Extrinsic):
            return e
        if isinstance(e, dict):
            try:
                return Extrinsic.from_dict(e)
            except ConfigError as exc:
                raise self._o().relocate("extrinsic", exc, list(e)) from None
        if isinstance(e, str):
            return Extrinsic.from_file(e)
        raise self._err("extrinsic", f"must be a file or a mapping, got {type(e).__name__}")

    @property
    def imu_config(self):
        """The :class:`~splineimu.imu.config.ImuConfig` of ``model`` (None: noise-free)."""
        return self._config

    @property
    def body_T_sensor(self):
        """The :class:`~splineimu.imu.ideal.Extrinsic` of ``extrinsic`` (None: identity)."""
        return self._body_T_sensor


def _auto_or(v, convert):
    if isinstance(v, str) and v.strip().lower() == "auto":
        return "auto"
    return convert(v)


@dataclass
class SplineOptions(_Checked):
    """How a pose file is fitted (see :func:`splineimu.fit`).

    Parameters
    ----------
    kind : {"split", "se3"}
    order : int or "auto"
        Spline order 3..8 (4 is cubic; 2 has no acceleration); ``"auto"``: the best predicted of 4, 5, 6.
    knot_spacing_s : float or "auto"
        Of the rotation, and of the position unless ``position_knot_spacing_s`` is given.
    position_order, position_knot_spacing_s : int / float or "auto", optional
        The position grid's own settings (``kind="split"`` only): e.g. a fixed position spacing
        where a ``motion_not_followed`` warning asks for a finer one, with the rotation's still
        chosen. None (default): as the rotation's.
    smoothness : float, optional
        Relative weight of the smoothness penalty (the fit's default when None).
    keep_outliers : bool
        Keep poses whose fit residual is beyond 8 robust sigmas.
    trim_ends_s : float or "auto"
        Time [s] at each end of the poses left out of the synthesized record (default 0);
        ``"auto"``: the fit's end zones (order x knot spacing of either grid: the fit sees
        one-sided data there, see the ``ends_less_accurate`` warning).
    rotation_source : {"auto", "estimate", "measurement"}
        ``"estimate"``: the rotations are an estimator's output that fused an IMU, their detail
        is motion and is kept (the fit's ``estimated_rotation``); ``"measurement"``: not;
        ``"auto"`` (default): an estimate when the pose file carries IMU biases (EuRoC's
        ground truth, vicon2gt), else measurements whose finest detail is read as motion where
        the positions' is (low-rate precise poses of fast rotation).
    """

    kind: str = "split"
    order: object = "auto"
    knot_spacing_s: object = "auto"
    position_order: object = None
    position_knot_spacing_s: object = None
    smoothness: float | None = None
    keep_outliers: bool = False
    trim_ends_s: object = 0.0
    rotation_source: str = "auto"
    origin: Origin | None = _origin_field()

    def __post_init__(self):
        self.kind = self._choice("kind", ("split", "se3"))
        for fld in ("order", "position_order"):
            if getattr(self, fld) is None:  # (position_order None: as the rotation's)
                continue
            name, kw = self._kw(fld)
            setattr(self, fld, _auto_or(getattr(self, fld), lambda v: int_in_range(v, name, 2, 8, **kw)))
            if getattr(self, fld) == 2:  # the fit takes it; the IMU read gravity alone (ellipse: a_x 0 for -1.48)
                raise self._err(fld, "2 (piecewise linear) has no acceleration: the specific force would be gravity "
                                     "alone; give 3..8 (4 is cubic) or auto")
        name, kw = self._kw("knot_spacing_s")
        self.knot_spacing_s = _auto_or(self.knot_spacing_s, lambda v: positive_float(v, name, **kw))
        if self.position_knot_spacing_s is not None:
            name, kw = self._kw("position_knot_spacing_s")
            self.position_knot_spacing_s = _auto_or(self.position_knot_spacing_s,
                                                    lambda v: positive_float(v, name, **kw))
        for fld in ("position_order", "position_knot_spacing_s"):
            if self.kind == "se3" and getattr(self, fld) is not None:
                raise self._err(fld, "needs the split spline: the se3 spline has one grid for rotation and position")
        if self.smoothness is not None:
            name, kw = self._kw("smoothness")
            self.smoothness = nonnegative_float(self.smoothness, name, **kw)
        self.keep_outliers = self._bool("keep_outliers")
        self.rotation_source = self._choice("rotation_source", ("auto", "estimate", "measurement"))
        name, kw = self._kw("trim_ends_s")
        self.trim_ends_s = _auto_or(self.trim_ends_s, lambda v: nonnegative_float(v, name, **kw))

    def fit_kwargs(self) -> dict:
        """The keyword arguments of :func:`splineimu.fit` these options give."""
        kw = {"kind": self.kind, "order": self.order, "knot_spacing_s": self.knot_spacing_s,
              "reject_outliers": not self.keep_outliers,
              # auto: a ground truth that carries IMU biases (EuRoC, vicon2gt) is an estimator's output
              # that fused that IMU, and its rotation's detail is motion (fit's estimated_rotation)
              "estimated_rotation": {"auto": "auto", "estimate": True, "measurement": False}[self.rotation_source]}
        for fld in ("position_order", "position_knot_spacing_s", "smoothness"):  # None: the fit's default
            if getattr(self, fld) is not None:
                kw[fld] = getattr(self, fld)
        return kw

    def trim_s(self, fit_report) -> float:
        """The time [s] left out at each end of a piece fitted as ``fit_report`` says."""
        if self.trim_ends_s != "auto":
            return float(self.trim_ends_s)
        r = fit_report
        return float(max(r.order * r.knot_spacing_s, (r.position_order or 0) * (r.position_knot_spacing_s or 0.0)))


@dataclass
class PosesInput(_Checked):
    """Motion from a pose file, through a fitted spline.

    Parameters
    ----------
    path : str
        TUM file (``t x y z qx qy qz qw``) or EuRoC ground-truth csv.
    format : {"tum", "euroc"}, optional
        Default: ``euroc`` for ``.csv`` files, else ``tum``.
    repeated_stamps : {"error", "first"}
    retime_stamps : bool
        The stamps are receive times: put the poses back on the capture clock fitted to them
        (:func:`splineimu.stamps.retime_stamps`) before the fit.
    max_gap_s : float, optional
        Longest gap bridged silently (default 0.5 s, or 5x the median spacing if larger).
    gaps : {"error", "bridge", "split"}
        Longer gaps: stop, fit through them, or write one folder per piece.
    spline : SplineOptions
    """

    path: str = None
    format: str | None = None
    repeated_stamps: str = "error"
    retime_stamps: bool = False
    max_gap_s: float | None = None
    gaps: str = "error"
    spline: SplineOptions = field(default_factory=SplineOptions)
    origin: Origin | None = _origin_field()

    def __post_init__(self):
        self.path = self._path("path", required=True)
        if self.format is None:
            self.format = "euroc" if self.path.lower().endswith(".csv") else "tum"
        self.format = self._choice("format", ("tum", "euroc"))
        self.repeated_stamps = self._choice("repeated_stamps", ("error", "first"))
        self.retime_stamps = self._bool("retime_stamps")
        if self.max_gap_s is not None:
            name, kw = self._kw("max_gap_s")
            self.max_gap_s = positive_float(self.max_gap_s, name, **kw)
        self.gaps = self._choice("gaps", ("error", "bridge", "split"))
        if not isinstance(self.spline, SplineOptions):
            raise self._err("spline", f"must be SplineOptions, got {type(self.spline).__name__}")


@dataclass
class SceneInput(_Checked):
    """Motion from an analytic scene (:func:`splineimu.scenes.make_scene`).

    Parameters
    ----------
    name : str
        A scene name (``splineimu scene --list``).
    duration_s : float, optional
        The scene's own duration when None.
    t0_ns : int
        Absolute stamp of the scene's start [ns].
    params : dict
        The scene's parameters; numbers, lists of numbers or their text (``"1,2,3"``).
    """

    name: str = None
    duration_s: float | None = None
    t0_ns: int = 0
    params: dict = field(default_factory=dict)
    origin: Origin | None = _origin_field()

    def __post_init__(self):
        from ..scenes import SCENES, scene_names

        self.name = self._choice("name", scene_names())
        if self.duration_s is not None:
            name, kw = self._kw("duration_s")
            self.duration_s = positive_float(self.duration_s, name, **kw)
        name, kw = self._kw("t0_ns")
        self.t0_ns = int_in_range(self.t0_ns, name, 0, 2**62 - 1, **kw)  # the scenes' range (scenes.base._origin_ns)
        if not isinstance(self.params, dict):
            raise self._err("params", f"must be a mapping, got {type(self.params).__name__}")
        known = list(getattr(SCENES[self.name], "PARAMS", {}))
        params = {}
        for k, v in self.params.items():
            name, kw = self._kw("params")
            one_of(k, f"{name} of scene {self.name}", known, **kw)
            params[k] = self._param(k, v)
        self.params = params

    def _param(self, key, v):
        name, kw = self._kw("params")
        label = f"{name}: {key}"
        if isinstance(v, str):
            parts = [p for p in v.replace(" ", "").split(",")]
            v = parts if len(parts) > 1 else parts[0]
        if isinstance(v, (list, tuple)):
            return [finite_float(x, label, **kw) for x in v]
        return finite_float(v, label, **kw)


@dataclass
class OutputOptions(_Checked):
    """Where the results go.

    Parameters
    ----------
    dir : str, optional
        The output folder (EuRoC-like layout; see :func:`splineimu.api.output.write_output`).
    force : bool
        Replace an existing non-empty folder.
    bag : {None, "ros1", "ros2"}
        Also write a ROS bag.
    plot : bool
        Also write PNG plots.
    tum : str, optional
        Scenes only: also write the scene's poses at the IMU rate as a TUM file.
    bag_version : {8, 9}, optional
        rosbag2 metadata version of a ROS 2 bag (default 8, read by Humble and newer).
    """

    dir: str | None = None
    force: bool = False
    bag: str | None = None
    plot: bool = False
    tum: str | None = None
    bag_version: int | None = None
    origin: Origin | None = _origin_field()

    def __post_init__(self):
        self.dir = self._path("dir")
        self.force = self._bool("force")
        if self.bag is not None:
            self.bag = self._choice("bag", ("ros1", "ros2"))
        self.plot = self._bool("plot")
        self.tum = self._path("tum")
        if self.bag_version is not None:
            self.bag_version = self._choice("bag_version", (8, 9))
            if self.bag != "ros2":
                raise self._err("bag_version", "is for ROS 2 bags (give the ROS 2 bag too)")


@dataclass
class SynthesisJob:
    """One synthesis: a motion input, the IMU and the outputs.

    Run it with :func:`splineimu.api.run_job` (or keep the data in memory with
    :func:`splineimu.api.synthesize_to_memory`).

    Parameters
    ----------
    motion : PosesInput or SceneInput
    imu : ImuOptions
    output : OutputOptions
    cameras : dict, optional
        Cameras observing landmarks on the same motion: name -> :class:`~splineimu.camera.Camera`,
        or a scene file's ``cameras:`` value (:func:`splineimu.camera.cameras_from_config`).
    landmarks : Landmarks or dict, optional
        Needed with cameras: ``{file: points.csv}`` or ``{random: {count: N, ...}}``
        (:func:`splineimu.camera.landmarks_from_config`; drawn from the run's seed).
    """

    motion: PosesInput | SceneInput
    imu: ImuOptions = field(default_factory=ImuOptions)
    output: OutputOptions = field(default_factory=OutputOptions)
    cameras: object = None
    landmarks: object = None
    origin: Origin | None = _origin_field()

    def __post_init__(self):
        if self.cameras is not None or self.landmarks is not None:
            from .cameras import check_cameras

            check_cameras(self)
        if not isinstance(self.motion, (PosesInput, SceneInput)):
            raise ConfigError(f"`motion` must be PosesInput or SceneInput, got {type(self.motion).__name__}")
        if not isinstance(self.imu, ImuOptions) or not isinstance(self.output, OutputOptions):
            raise ConfigError("`imu` must be ImuOptions and `output` OutputOptions")
        if self.output.tum is not None and isinstance(self.motion, PosesInput):
            raise ConfigError("`tum` output is for scenes (a pose file already is one)", option=FLAGS["tum"])

    @property
    def seed(self):
        return self.imu.seed

    def to_argv(self) -> list[str]:
        """The equivalent ``splineimu`` command line (without the program name).

        Only values that differ from the defaults are written; inline mappings (an IMU model
        or extrinsic given in a scene file) are written as YAML flow text.

        Raises
        ------
        ConfigError
            The job has cameras: they have no flags (scene files only).
        """
        return job_argv(self)


__all__ = ["ImuOptions", "SplineOptions", "PosesInput", "SceneInput", "OutputOptions", "SynthesisJob",
           "Origin", "FlagOrigin", "YamlOrigin", "FLAGS", "SPLINE_FIELDS"]
