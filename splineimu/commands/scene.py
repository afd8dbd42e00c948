"""``splineimu scene``: IMU data from an analytic reference scene with exact derivatives."""

from __future__ import annotations

NAME = "scene"
ORDER = 20
HELP = "IMU data from an analytic scene (ellipse, static, circle, screw, flips, ...) with exact ground truth"
DESCRIPTION = """\
Synthesize IMU data from an analytic trajectory whose derivatives are exact.

examples:
  splineimu scene ellipse -o out                      noise-free lecture ellipse, 200 Hz
  splineimu scene static --duration 10800 --imu adis16448 --seed 1 -o static3h
  splineimu scene flips --rate 1000 --imu imu.yaml -o flips
  splineimu scene ellipse --tum ellipse.tum --rate 100  poses only, as a TUM file
  splineimu scene --list                              scenes and their parameters
"""


def add_arguments(p):
    from ._common import add_imu_args, add_output_args

    p.add_argument("name", nargs="?", help="scene name (see --list)")
    p.add_argument("--list", action="store_true", help="list the scenes with their parameters and exit")
    p.add_argument("--duration", type=float, metavar="S", help="duration [s] (default: the scene's own)")
    p.add_argument("--t0-ns", type=int, metavar="NS", help="absolute time of the scene start [ns]")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="scene parameter, e.g. --param radius_m=3 (repeatable; vectors as 1,2,3)")
    p.add_argument("--tum", metavar="FILE", help="write the scene's poses at --rate to this TUM file")
    add_imu_args(p)
    add_output_args(p)


def run(args) -> int:
    from ..errors import ConfigError
    from ._common import echo, options_from_args, run_synthesis

    if args.list:
        from .. import scenes

        for name in scenes.scene_names():
            cls = scenes.SCENES[name]
            doc = (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else ""
            echo(f"{name:14s} {doc}")
            for pname, prm in getattr(cls, "PARAMS", {}).items():
                echo(f"    {pname:24s} default {prm.default!r} [{prm.unit}]")
        return 0
    if not args.name:
        raise ConfigError("give a scene name (or --list)")
    job = options_from_args(args, "scene")  # first: a misspelt scene or flag is the error to name
    if not args.out and not args.tum:
        raise ConfigError("nothing to write: give -o OUT and/or --tum FILE")
    return run_synthesis(job)
