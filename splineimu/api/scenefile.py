"""Scene files: one YAML that names the motion source, the IMU and the outputs.

::

    motion:                       # exactly one of `scene` or `poses`
      scene: ellipse              # an analytic scene (splineimu scene --list) ...
      duration_s: 60
      t0_ns: 0
      params: {}                  # the scene's own parameters
      # poses: mocap.tum          # ... or a pose file (TUM, or EuRoC csv with format: euroc)
      # format: tum
      # spline: {kind: split, order: auto, knot_spacing_s: auto, smoothness: 1e-10, keep_outliers: false}
      # gaps: error               # error | bridge | split
      # max_gap_s: 0.5
      # repeated_stamps: error    # error | first
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
    vary:                         # optional: Monte-Carlo batches (splineimu.api.variants)
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

import difflib
from pathlib import Path

from ..errors import ConfigError
from .options import ImuOptions, OutputOptions, PosesInput, SceneInput, SplineOptions, SynthesisJob, YamlOrigin

#: Keys of each section (the file's structure).
KEYS = {
    (): ("motion", "imu", "seed", "output", "cameras", "landmarks", "vary"),
    ("motion",): ("scene", "duration_s", "t0_ns", "params", "poses", "format", "spline", "gaps", "max_gap_s",
                  "repeated_stamps"),
    ("motion", "spline"): ("kind", "order", "knot_spacing_s", "smoothness", "keep_outliers"),
    ("imu",): ("rate_hz", "timestamps", "model", "extrinsic", "gravity", "sampling", "increments", "timing",
               "vibration"),
    ("output",): ("dir", "bag", "plot", "force", "tum"),
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


def load_scene_file(path, run_index: int | None = None) -> SynthesisJob:
    """Read a scene file into a :class:`~splineimu.api.options.SynthesisJob`.

    Parameters
    ----------
    path : str or os.PathLike
        The YAML file (format in the module docstring). Relative paths in it are relative to
        its folder.
    run_index : int, optional
        Run ``k`` of a Monte-Carlo batch over the file's ``vary:`` block: its draws and seed
        (:class:`~splineimu.api.variants.SceneFile`); without it the nominal values.

    Returns
    -------
    SynthesisJob

    Raises
    ------
    ConfigError
        Unreadable or invalid YAML, an unknown key (with a did-you-mean), a missing or invalid
        value: each with the file and line.
    """
    from .variants import SceneFile

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
        source = _build(SceneInput, doc, motion, ("motion",), ("name", "duration_s", "t0_ns", "params"))
    else:
        m = dict(motion)
        rel(m, "poses")
        spline = _build(SplineOptions, doc, _section(doc, ("motion", "spline")), ("motion", "spline"),
                        ("kind", "order", "knot_spacing_s", "smoothness", "keep_outliers"))
        source = _build(PosesInput, doc, m, ("motion",), ("path", "format", "repeated_stamps", "max_gap_s", "gaps"),
                        spline=spline)
    if "seed" in top:
        imu["seed"] = top["seed"]
    imu_opts = _build(ImuOptions, doc, imu, ("imu",), ("rate_hz", "timestamps", "model", "extrinsic", "gravity",
                                                      "sampling", "increments", "seed", "timing", "vibration"),
                      extra={"seed": ("seed",)})
    output = _build(OutputOptions, doc, out, ("output",), ("dir", "force", "bag", "plot", "tum"))
    try:
        return SynthesisJob(source, imu_opts, output, cameras=top.get("cameras"), landmarks=top.get("landmarks"),
                            origin=YamlOrigin(doc, {"cameras": ("cameras",), "landmarks": ("landmarks",)}))
    except ConfigError as exc:
        if exc.path is not None:  # cameras and landmarks: at their file and line already
            raise
        raise ConfigError(exc.problem, path=doc.name, option=exc.option) from None


__all__ = ["load_scene_file", "job_from_document", "KEYS"]
