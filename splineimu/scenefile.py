"""Scene files: one YAML that names the motion source, the IMU and the outputs.

::

    motion:                       # exactly one of `scene` or `poses`
      scene: ellipse              # an analytic scene (splineimu scene --list) ...
      duration_s: 60
      t0_ns: 0
      params: {}                  # the scene's own parameters
      # poses: mocap.tum          # ... or a pose file (TUM, or EuRoC csv with format: euroc)
      # format: tum
      # spline: {kind: split, order: auto, knot_spacing_s: auto}
      # gaps: error               # error | bridge | split
      # max_gap_s: 0.5
    imu:
      rate_hz: 200
      timestamps: real_imu0.csv   # optional: synthesize at these stamps
      model: adis16448            # preset, Kalibr yaml path, or an inline mapping of its keys
      extrinsic: T_bs.yaml        # optional: file or {translation: [...], quat_xyzw: [...]}
      gravity: [0, 0, -9.81]
    seed: 42
    output:
      dir: out                    # relative paths are relative to the scene file
      bag: ros2                   # optional
      plot: true
      force: false

Only what the file names is modelled: without ``imu.model`` the data are noise-free, and the
sensor model applies only the components its keys name.
"""

from __future__ import annotations

import difflib
import tempfile
from pathlib import Path

from .errors import ConfigError

_KEYS = {
    "": {"motion", "imu", "seed", "output"},
    "motion": {"scene", "duration_s", "t0_ns", "params", "poses", "format", "spline", "gaps", "max_gap_s",
               "repeated_stamps"},
    "motion.spline": {"kind", "order", "knot_spacing_s", "smoothness"},
    "imu": {"rate_hz", "timestamps", "model", "extrinsic", "gravity"},
    "output": {"dir", "bag", "plot", "force"},
}


def _check_keys(d, where, path):
    if d is None:
        return {}
    if not isinstance(d, dict):
        raise ConfigError(f"{path}: `{where or 'top level'}` must be a mapping")
    allowed = _KEYS[where]
    for k in d:
        if k not in allowed:
            near = difflib.get_close_matches(str(k), sorted(allowed), n=1)
            hint = f"; did you mean `{near[0]}`?" if near else f"; known keys: {', '.join(sorted(allowed))}"
            raise ConfigError(f"{path}: unknown key `{(where + '.') if where else ''}{k}`{hint}")
    return d


def scene_to_argv(path, tmpdir: Path) -> list[str]:
    """Translate a scene file into the equivalent ``splineimu`` command line."""
    import yaml

    path = Path(path)
    try:
        doc = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise ConfigError(f"cannot read scene file {path}: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {str(exc).splitlines()[0]}") from None
    doc = _check_keys(doc, "", path)
    motion = _check_keys(doc.get("motion"), "motion", path)
    imu = _check_keys(doc.get("imu"), "imu", path)
    out = _check_keys(doc.get("output"), "output", path)
    base = path.parent

    def rel(p):
        q = Path(str(p)).expanduser()
        return str(q if q.is_absolute() else base / q)

    if ("scene" in motion) == ("poses" in motion):
        raise ConfigError(f"{path}: `motion` needs exactly one of `scene` or `poses`")
    if "dir" not in out:
        raise ConfigError(f"{path}: `output.dir` is required")
    argv: list[str]
    if "scene" in motion:
        argv = ["scene", str(motion["scene"])]
        if "duration_s" in motion:
            argv += ["--duration", str(motion["duration_s"])]
        if "t0_ns" in motion:
            argv += ["--t0-ns", str(int(motion["t0_ns"]))]
        params = motion.get("params") or {}
        if not isinstance(params, dict):
            raise ConfigError(f"{path}: `motion.params` must be a mapping")
        for k, v in params.items():
            v = ",".join(map(str, v)) if isinstance(v, (list, tuple)) else v
            argv += ["--param", f"{k}={v}"]
    else:
        fmt = str(motion.get("format", "euroc" if str(motion["poses"]).endswith(".csv") else "tum"))
        if fmt not in ("tum", "euroc"):
            raise ConfigError(f"{path}: `motion.format` must be tum or euroc, got {fmt!r}")
        argv = ["from-tum" if fmt == "tum" else "from-euroc", rel(motion["poses"])]
        spline = _check_keys(motion.get("spline"), "motion.spline", path)
        for key, opt in (("kind", "--spline"), ("order", "--order"), ("knot_spacing_s", "--knot-spacing"),
                         ("smoothness", "--smoothness")):
            if key in spline:
                argv += [opt, str(spline[key])]
        if "gaps" in motion:
            argv += ["--gaps", str(motion["gaps"])]
        if "max_gap_s" in motion:
            argv += ["--max-gap", str(motion["max_gap_s"])]
        if "repeated_stamps" in motion:
            argv += ["--repeated-stamps", str(motion["repeated_stamps"])]
        if "timestamps" in imu:
            argv += ["--timestamps", rel(imu["timestamps"])]
    if "rate_hz" in imu:
        argv += ["--rate", str(imu["rate_hz"])]
    model = imu.get("model")
    if isinstance(model, dict):
        f = tmpdir / "imu_model.yaml"
        f.write_text(yaml.safe_dump(model))
        argv += ["--imu", str(f)]
    elif model is not None:
        m = str(model)
        argv += ["--imu", rel(m) if (base / m).exists() or m.endswith((".yaml", ".yml")) else m]
    ext = imu.get("extrinsic")
    if isinstance(ext, dict):
        f = tmpdir / "extrinsic.yaml"
        f.write_text(yaml.safe_dump(ext))
        argv += ["--extrinsic", str(f)]
    elif ext is not None:
        argv += ["--extrinsic", rel(ext)]
    if "gravity" in imu:
        g = imu["gravity"]
        if not (isinstance(g, (list, tuple)) and len(g) == 3):
            raise ConfigError(f"{path}: `imu.gravity` must be a list of 3 numbers")
        argv += ["--gravity", *map(str, g)]
    if "seed" in doc and doc["seed"] is not None:
        argv += ["--seed", str(int(doc["seed"]))]
    argv += ["-o", rel(out["dir"])]
    if out.get("bag"):
        argv += ["--bag", str(out["bag"])]
    if out.get("plot"):
        argv.append("--plot")
    if out.get("force"):
        argv.append("--force")
    return argv


def run_scene_file(path, extra_argv=()) -> int:
    """Run a scene file through the command line it stands for."""
    from .cli import main

    with tempfile.TemporaryDirectory(prefix="splineimu-scene-") as tmp:
        argv = scene_to_argv(path, Path(tmp)) + list(extra_argv)
        return main(argv)
