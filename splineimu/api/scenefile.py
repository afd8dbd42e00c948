"""Scene files: one YAML that names the motion source, the IMU and the outputs.

::

    motion:                       # exactly one of `scene` or `poses`
      scene: ellipse              # an analytic scene (splineimu scene --list) ...
      duration_s: 60
      t0_ns: 0
      params: {}                  # the scene's own parameters
      # poses: mocap.tum          # ... or a pose file (TUM, or EuRoC csv with format: euroc)
      # format: tum
      # spline: {kind: split, order: auto, knot_spacing_s: auto, smoothness: 1e-10, keep_outliers: false,
      #          trim_ends_s: 0, rotation_source: auto,   # auto | estimate | measurement
      #          position_order: auto, position_knot_spacing_s: auto}  # (default: as the rotation's)
      # gaps: error               # error | bridge | split
      # max_gap_s: 0.5
      # repeated_stamps: error    # error | first
      # retime_stamps: false      # true: receive-time stamps, put back on the capture clock
    imu:
      rate_hz: 200
      timestamps: real_imu0.csv   # optional: synthesize at these stamps
      model: adis16448            # preset, Kalibr yaml path, or an inline mapping of its keys
      extrinsic: T_bs.yaml        # optional: file or {translation: [...], quat_xyzw: [...]}
      gravity: [0, 0, -9.81]
      sampling: point             # point | mean
      increments: false
      timing: {time_offset_s: 0.0123, clock_drift_ppm: 50, stamp_noise_s: 1.0e-4, drop_probability: 0.01}
      vibration:                  # or a YAML file holding this block
        accel: [{freq_hz: 37, amplitude: [0.5, 0, 0]}, {band_hz: [20, 80], psd: [1.0e-4, 1.0e-4, 0]}]
    seed: 42
    output:
      dir: out                    # relative paths are relative to the scene file
      bag: ros2                   # optional
      plot: true
      force: false
      tum: poses.tum              # scenes only: their poses at the IMU rate
    cameras: {cam0: {...}}        # optional: Kalibr camchain keys per camera, or {file: camchain.yaml}
    landmarks: {random: {count: 1500, shape: shell}}   # with cameras; or {file: points.csv}
                                  # (keys and files: splineimu.camera.config)
    vary:                         # optional: Monte-Carlo batches (see SceneFile)
      imu.model.gyroscope_noise_density: {normal: [1.8e-4, 2.0e-5]}

The file builds a :class:`~splineimu.api.options.SynthesisJob`, the same object the command-line
flags build; every value is checked with the file and line it stands on. Only what the file
names is modelled: without ``imu.model`` the data are noise-free.

Examples
--------
>>> import pathlib, tempfile
>>> f = pathlib.Path(tempfile.mkdtemp()) / "s.yaml"
>>> _ = f.write_text("motion: {scene: static, duration_s: 2}\\nimu: {rate_hz: 100}\\noutput: {dir: out}\\n")
>>> load_scene_file(f).to_argv()[:4]
['scene', 'static', '--duration', '2']
>>> _ = f.write_text("motion: {scene: static}\\nimu:\\n  rate: 100\\noutput: {dir: out}\\n")
>>> load_scene_file(f)
Traceback (most recent call last):
...
splineimu.errors.ConfigError: ...s.yaml:3: unknown key `imu.rate`; did you mean `rate_hz`?
"""

from __future__ import annotations

import copy
import difflib
from dataclasses import dataclass
from pathlib import Path

from ..batch.vary import draws_for_run, nominal_values, parse_vary, run_seed, set_dotted
from ..errors import ConfigError, SplineImuError
from .options import (
    SPLINE_FIELDS,
    ImuOptions,
    OutputOptions,
    PosesInput,
    SceneInput,
    SplineOptions,
    SynthesisJob,
    YamlOrigin,
)

#: Keys of each section (the file's structure).
KEYS = {
    (): ("motion", "imu", "seed", "output", "cameras", "landmarks", "vary"),
    ("motion",): ("scene", "duration_s", "t0_ns", "params", "poses", "format", "spline", "gaps", "max_gap_s",
                  "repeated_stamps", "retime_stamps"),
    ("motion", "spline"): SPLINE_FIELDS,
    ("imu",): ("rate_hz", "timestamps", "model", "extrinsic", "gravity", "sampling", "increments", "timing",
               "vibration", "rostopic"),
    ("output",): ("dir", "bag", "plot", "force", "tum", "bag_version"),
}

#: Option field -> key in the file, where the two differ.
_RENAMED = {"name": "scene", "path": "poses"}


def _section(doc, keys) -> dict:
    d = doc.data
    for k in keys:
        d = d.get(k) if isinstance(d, dict) else None
    if d is None:
        return {}
    label = ".".join(keys) or "the top level"
    if not isinstance(d, dict):
        raise doc.error(f"`{label}` must be a mapping of keys, got {type(d).__name__}", *keys)
    allowed = KEYS[keys]
    for k in d:
        if k not in allowed:
            near = difflib.get_close_matches(str(k), allowed, n=1)
            hint = f"; did you mean `{near[0]}`?" if near else f"; known keys: {', '.join(allowed)}"
            raise doc.error(f"unknown key `{'.'.join(map(str, (*keys, k)))}`{hint}", *keys, k)
    return d


def _build(cls, doc, section: dict, keys: tuple, fields, extra=None, **kw):
    """``cls`` from the ``fields`` of ``section`` (only those present: the others keep their defaults)."""
    place = {f: (*keys, _RENAMED.get(f, f)) for f in fields}
    place.update(extra or {})
    values = {f: section[place[f][-1]] for f in fields if place[f][-1] in section}
    return cls(**values, **kw, origin=YamlOrigin(doc, place))


def _scene_input(doc, motion: dict):
    """The :class:`SceneInput` of ``motion``, with each parameter's errors at the line of its key.

    The parameters are also checked against the scene's own specification (vector length,
    sign) here: that check ran only when the scene was made, without the file and line.
    """
    from ..scenes import SCENES

    params = motion.get("params")
    try:
        source = _build(SceneInput, doc, motion, ("motion",), ("name", "duration_s", "t0_ns", "params"))
    except ConfigError as exc:
        named = [k for k in (params if isinstance(params, dict) else ())
                 if f"`motion.params: {k}`" in exc.problem or f"got {k!r}" in exc.problem]
        if not named or exc.line != doc.line("motion", "params"):
            raise
        raise ConfigError(exc.problem, path=doc.name, line=doc.line("motion", "params", named[0]),
                          option=f"motion.params.{named[0]}") from None
    spec = getattr(SCENES[source.name], "PARAMS", {})
    for k, v in source.params.items():
        try:
            spec[k].coerce(source.name, k, v)
        except ConfigError as exc:
            raise doc.error(exc.problem, "motion", "params", k) from None
    return source


def load_scene_file(path, run_index: int | None = None) -> SynthesisJob:
    """Read a scene file into a :class:`~splineimu.api.options.SynthesisJob`.

    Parameters
    ----------
    path : str or os.PathLike
        The YAML file (format in the module docstring). Relative paths in it are relative to
        its folder.
    run_index : int, optional
        Run ``k`` of a Monte-Carlo batch over the file's ``vary:`` block: its draws and seed
        (:class:`SceneFile`); without it the nominal values.

    Returns
    -------
    SynthesisJob

    Raises
    ------
    ConfigError
        Unreadable or invalid YAML, an unknown key (with a did-you-mean), a missing or invalid
        value: each with the file and line.
    """
    if run_index is None:
        return SceneFile.read(path).job()
    return SceneFile.read(Path(path).resolve()).job(run_index)


def job_from_document(doc, base) -> SynthesisJob:
    """The job of a parsed scene file (:class:`~splineimu.io.yaml.YamlDoc`) whose relative paths start at ``base``."""
    base = Path(base)
    if not isinstance(doc.data, dict):
        raise doc.error(f"a scene file is a mapping with motion, imu, seed, output; got {type(doc.data).__name__}")
    top = _section(doc, ())
    motion = _section(doc, ("motion",))
    imu = dict(_section(doc, ("imu",)))
    out = dict(_section(doc, ("output",)))

    def rel(section, key):
        v = section.get(key)
        if isinstance(v, str) and v:
            q = Path(v).expanduser()
            section[key] = str(q if q.is_absolute() else base / q)

    for key in ("timestamps", "extrinsic", "vibration"):
        rel(imu, key)
    model = imu.get("model")
    if isinstance(model, str) and ((base / model).exists() or model.endswith((".yaml", ".yml"))):
        rel(imu, "model")
    for key in ("dir", "tum"):
        rel(out, key)
    if ("scene" in motion) == ("poses" in motion):
        raise doc.error("`motion` needs exactly one of `scene` or `poses`", "motion")
    if out.get("dir") is None:
        what = "`output.dir` is required" if "dir" not in out else "`output.dir` is empty (null)"
        raise ConfigError(what, path=doc.name, line=doc.line("output", "dir") or 1, option="output.dir")

    if "scene" in motion:
        source = _scene_input(doc, motion)
    else:
        m = dict(motion)
        rel(m, "poses")
        spline = _build(SplineOptions, doc, _section(doc, ("motion", "spline")), ("motion", "spline"),
                        SPLINE_FIELDS)
        source = _build(PosesInput, doc, m, ("motion",),
                        ("path", "format", "repeated_stamps", "retime_stamps", "max_gap_s", "gaps"), spline=spline)
    if imu.get("timestamps") is not None and imu.get("rate_hz") is not None:  # the rate was ignored in silence
        raise doc.error("`imu.rate_hz` and `imu.timestamps` are both given: the samples are at the file's "
                        "stamps; remove rate_hz", "imu", "rate_hz")
    if "seed" in top:
        imu["seed"] = top["seed"]
    imu_opts = _build(ImuOptions, doc, imu, ("imu",), ("rate_hz", "timestamps", "model", "extrinsic", "gravity",
                                                      "sampling", "increments", "seed", "timing", "vibration",
                                                      "rostopic"),
                      extra={"seed": ("seed",)})
    output = _build(OutputOptions, doc, out, ("output",), ("dir", "force", "bag", "plot", "tum", "bag_version"))
    try:
        return SynthesisJob(source, imu_opts, output, cameras=top.get("cameras"), landmarks=top.get("landmarks"),
                            origin=YamlOrigin(doc, {"cameras": ("cameras",), "landmarks": ("landmarks",)}))
    except ConfigError as exc:
        if exc.path is not None:  # cameras and landmarks: at their file and line already
            raise
        raise ConfigError(exc.problem, path=doc.name, option=exc.option) from None


#: Top-level keys a ``vary:`` block may not touch (each run has its own seed and folder).
NOT_VARIED = ("seed", "output", "vary")


def _resolve(base: Path, value: str) -> Path:
    q = Path(value).expanduser()
    return q if q.is_absolute() else base / q


def _expander(base: Path):
    """``expand(path, value)`` for :func:`~splineimu.batch.vary.set_dotted`: blocks given by name or file, or absent."""

    def expand(path, value):
        if path == "imu.model" and (value is None or isinstance(value, str)):
            if value is None:
                return {}
            from ..imu.config import load_imu_config

            file = _resolve(base, value)
            return load_imu_config(str(file) if file.exists() or value.endswith((".yaml", ".yml")) else value).to_dict()
        if path == "imu.extrinsic" and (value is None or isinstance(value, str)):
            from ..imu.ideal import Extrinsic
            from ..lie import matrix_to_quat_xyzw

            e = Extrinsic() if value is None else Extrinsic.from_file(str(_resolve(base, value)))
            return {"translation": e.body_t_sensor.tolist(), "quat_xyzw": matrix_to_quat_xyzw(e.body_R_sensor).tolist()}
        if value is None and (path in ("motion.params", "imu.timing") or tuple(path.split(".")) in KEYS):
            return {}  # an absent optional block of the format
        if value is None and path == "imu.gravity":
            from .options import DEFAULT_GRAVITY

            return list(DEFAULT_GRAVITY)
        return None

    return expand


def _index(run_index) -> int:
    from ..validation import int_in_range

    return int_in_range(run_index, "run index", 0, 2**63 - 1)


@dataclass
class SceneFile:
    """A scene file read once, from which the job of any run is built (``vary:`` block below).

    Scene files with a ``vary:`` block: the job of every run of a Monte-Carlo batch.

    ::

        seed: 42
        vary:
          imu.model.gyroscope_noise_density: {normal: [1.8e-4, 2.0e-5]}
          imu.model.accelerometer_noise_density: {uniform: [1.0e-3, 3.0e-3]}
          imu.extrinsic.translation.0: {normal: [0.10, 0.005]}

    Each key is a dotted path of the scene format (a number indexes a list); distributions are
    described in :mod:`splineimu.batch.vary`. An IMU model given as a preset name or a file, and an
    extrinsic given as a file (or not at all), are expanded to their keys so that one of them can
    be varied. The block is checked when the file is read, before any work: each key is applied
    with its nominal value and the job built, so that a key which is not part of the format, or a
    value the format refuses, is an error naming the file, the line and the key.

    Run ``k`` (:meth:`SceneFile.job`) takes the draws of ``k`` and its own seed, both from the
    file's ``seed`` and ``k`` alone; without a run index the nominal values (mean, midpoint, first
    choice) are used. ``splineimu run SCENE.yaml --run-index k`` and ``splineimu batch`` build their
    jobs through this one method, so they write the same bytes.

    Attributes
    ----------
    doc : splineimu.io.yaml.YamlDoc
        The file as written (for the lines of its keys).
    base : pathlib.Path
        The folder relative paths in the file start from.
    vary : dict
        ``{dotted key: Distribution}`` of the ``vary:`` block (empty without one).
    data : dict
        The document with the varied blocks expanded and the nominal values set.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "s.yaml"
    >>> _ = f.write_text('''motion: {scene: static, duration_s: 1}
    ... imu: {rate_hz: 100, model: {gyroscope_noise_density: 0.01}}
    ... seed: 1
    ... output: {dir: out}
    ... vary:
    ...   imu.model.gyroscope_noise_density: {uniform: [0.01, 0.02]}
    ... ''')
    >>> scene = SceneFile.read(f)
    >>> scene.job().imu.imu_config.gyroscope_noise_density.tolist()
    [0.015, 0.015, 0.015]
    >>> scene.values(3) == scene.values(3), 0.01 <= scene.values(3)["imu.model.gyroscope_noise_density"] < 0.02
    (True, True)
    >>> _ = f.write_text(f.read_text().replace("gyroscope_noise_density: {", "gyro_noise: {"))
    >>> SceneFile.read(f)
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: ...s.yaml:6: `vary.imu.model.gyro_noise`: `imu.model`: unknown IMU key ...
    """

    doc: object
    base: Path
    vary: dict
    data: dict

    @classmethod
    def read(cls, path) -> SceneFile:
        """Read and check a scene file and its ``vary:`` block (see the module docstring).

        Raises
        ------
        ConfigError
            As :func:`~splineimu.api.scenefile.load_scene_file`; for the ``vary:`` block with the
            line of the key at fault.
        """
        from ..io.yaml import YamlDoc, read_yaml

        doc = read_yaml(path, "scene file")
        base = Path(path).parent
        job_from_document(doc, base)  # the file without its draws: errors at their own lines
        vary = parse_vary(doc.data.get("vary"), doc)
        expand = _expander(base)
        data = copy.deepcopy(doc.data)
        for key, dist in vary.items():
            if key.split(".")[0] in NOT_VARIED:
                raise doc.error(f"`vary`: `{key}` cannot be varied (each run has its own seed and output folder)",
                                "vary", key)
            values = dist.params if dist.kind == "choice" else (dist.nominal(),)
            for value in values:
                trial = copy.deepcopy(doc.data)
                try:
                    set_dotted(trial, key, value, expand)
                    job_from_document(YamlDoc(trial, doc.name, doc.lines), base)
                except KeyError as exc:
                    raise doc.error(f"`vary`: `{key}` is not a key of the scene format (no `{exc.args[0]}`)",
                                    "vary", key) from None
                except SplineImuError as exc:
                    raise ConfigError(f"`vary.{key}`: {exc.problem}", path=doc.name, line=doc.line("vary", key),
                                      option=f"vary.{key}") from None
            set_dotted(data, key, dist.nominal(), expand)
        return cls(doc, base, vary, data)

    @property
    def seed(self) -> int | None:
        """The file's ``seed`` (the root of every run's draws and seed)."""
        return self.doc.data.get("seed")

    @property
    def varies_motion(self) -> bool:
        """Whether a varied key is under ``motion`` (then each run reads and fits its own motion)."""
        return any(key.split(".")[0] == "motion" for key in self.vary)

    def values(self, run_index: int | None = None) -> dict:
        """The varied values of run ``run_index`` (``{dotted key: value}``), or the nominal ones."""
        if run_index is None:
            return nominal_values(self.vary)
        return draws_for_run(self.vary, self._seed(), _index(run_index))

    def run_seed(self, run_index: int) -> int:
        """The seed of run ``run_index`` (it replaces the file's ``seed``)."""
        return run_seed(self._seed(), _index(run_index))

    def _seed(self) -> int:
        if self.seed is None:
            raise self.doc.error("runs of a batch need the scene's `seed` (their draws and seeds derive from it)")
        return int(self.seed)

    def job(self, run_index: int | None = None, out_dir=None):
        """The :class:`~splineimu.api.options.SynthesisJob` of run ``run_index`` (None: the nominal values).

        Parameters
        ----------
        run_index : int, optional
            With it the run's draws and seed are used and the file's ``output.tum`` is not
            written (it would be one file for all runs).
        out_dir : str or os.PathLike, optional
            The output folder instead of the file's ``output.dir``.

        Raises
        ------
        ConfigError
            A drawn value the format refuses (with the line of its key), a run index without
            the file's ``seed``.
        """
        import dataclasses

        from ..io.yaml import YamlDoc

        data = self.data
        if run_index is not None:
            data = copy.deepcopy(data)
            for key, value in self.values(run_index).items():
                set_dotted(data, key, value)
            data["seed"] = self.run_seed(run_index)
        job = job_from_document(YamlDoc(data, self.doc.name, self.doc.lines), self.base)
        if run_index is not None and job.output.tum is not None:
            job.output = dataclasses.replace(job.output, tum=None)
        if out_dir is not None:
            job.output = dataclasses.replace(job.output, dir=str(out_dir))
        return job


__all__ = ["load_scene_file", "job_from_document", "SceneFile", "KEYS", "NOT_VARIED"]
