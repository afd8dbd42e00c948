"""The ``splineimu`` command line of a :class:`~splineimu.api.options.SynthesisJob`
(:meth:`~splineimu.api.options.SynthesisJob.to_argv`)."""

from __future__ import annotations

import dataclasses
import json

from ..errors import ConfigError

#: The command-line flag of each option field (positional arguments in capitals).
FLAGS = {
    "rate_hz": "--rate", "timestamps": "--timestamps", "model": "--imu", "extrinsic": "--extrinsic",
    "gravity": "--gravity", "sampling": "--sampling", "increments": "--increments", "seed": "--seed",
    "rostopic": "--rostopic", "bag_version": "--bag-version",
    "kind": "--spline", "order": "--order", "knot_spacing_s": "--knot-spacing", "smoothness": "--smoothness",
    "position_order": "--position-order", "position_knot_spacing_s": "--position-knot-spacing",
    "keep_outliers": "--keep-outliers", "trim_ends_s": "--trim-ends", "rotation_source": "--rotation-source",
    "path": "POSES", "format": "COMMAND", "repeated_stamps": "--repeated-stamps", "max_gap_s": "--max-gap",
    "gaps": "--gaps", "retime_stamps": "--retime-stamps",
    "name": "SCENE", "duration_s": "--duration", "t0_ns": "--t0-ns", "params": "--param",
    "dir": "--out", "force": "--force", "bag": "--bag", "plot": "--plot", "tum": "--tum",
    "vibration": "--vibration", "timing": "--time-offset/--clock-drift-ppm/--stamp-noise/--drop-probability",
    "timing.time_offset_s": "--time-offset", "timing.clock_drift_ppm": "--clock-drift-ppm",
    "timing.stamp_noise_s": "--stamp-noise", "timing.drop_probability": "--drop-probability",
    "timing.drop_burst_s": "--drop-burst",
}

#: The fields of :class:`~splineimu.api.options.SplineOptions` a scene file or a command line gives.
SPLINE_FIELDS = ("kind", "order", "knot_spacing_s", "position_order", "position_knot_spacing_s", "smoothness",
                 "keep_outliers", "trim_ends_s", "rotation_source")


def job_argv(job) -> list[str]:
    """The command line of ``job`` (without the program name); see ``SynthesisJob.to_argv``."""
    if job.cameras is not None:
        raise ConfigError("cameras are only available from scene files: no command line gives this job",
                          option="cameras")
    m = job.motion
    if hasattr(m, "spline"):  # a pose file (PosesInput)
        argv = ["from-tum" if m.format == "tum" else "from-euroc", m.path]
        argv += _flags(m.spline, SPLINE_FIELDS)
        argv += _flags(m, ("repeated_stamps", "retime_stamps", "max_gap_s", "gaps"))
    else:
        argv = ["scene", m.name] + _flags(m, ("duration_s", "t0_ns"))
        for k, v in m.params.items():
            argv += ["--param", f"{k}={','.join(map(_num, v)) if isinstance(v, list) else _num(v)}"]
    argv += _flags(job.imu, ("rate_hz", "timestamps", "model", "extrinsic", "gravity", "sampling",
                             "increments", "seed", "rostopic"))
    if job.imu.timing is not None:
        argv += [x for k, v in job.imu.timing.to_dict().items() for x in (FLAGS[f"timing.{k}"], _num(v))]
    if job.imu.vibration is not None:
        argv += [FLAGS["vibration"], json.dumps(job.imu.vibration.to_dict())]
    if job.output.dir is not None:
        argv += ["-o", job.output.dir]
    argv += _flags(job.output, ("force", "bag", "plot", "tum", "bag_version"))
    return argv


def _num(x) -> str:
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x) if isinstance(x, float) else str(x)


def _inline(v) -> str:
    from ..imu.config import ImuConfig
    from ..imu.ideal import Extrinsic

    if isinstance(v, ImuConfig):
        v = v.to_dict()
    elif isinstance(v, Extrinsic):
        v = {"T_BS": v.matrix.tolist()}
    return json.dumps(v) if isinstance(v, dict) else str(v)


def _flags(opts, names) -> list[str]:
    defaults = {f.name: (f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default)
                for f in dataclasses.fields(opts)}
    out = []
    for n in names:
        v = getattr(opts, n)
        if v == defaults[n] or v is None:
            continue
        flag = FLAGS[n]
        if isinstance(v, bool):
            out.append(flag)
        elif n == "gravity":
            out += [flag, *map(_num, v)]
        elif n in ("model", "extrinsic"):
            out += [flag, _inline(v)]
        else:
            out += [flag, _num(v)]
    return out
