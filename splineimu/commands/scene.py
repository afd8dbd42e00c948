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
    p.add_argument("--t0-ns", type=int, default=0, metavar="NS", help="absolute time of the scene start [ns]")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="scene parameter, e.g. --param radius_m=3 (repeatable; vectors as 1,2,3)")
    p.add_argument("--tum", metavar="FILE", help="write the scene's poses at --rate to this TUM file")
    add_imu_args(p)
    add_output_args(p)


def _parse_params(items):
    from ..errors import ConfigError

    params = {}
    for it in items:
        if "=" not in it:
            raise ConfigError(f"--param expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        params[k.strip()] = v.strip()
    return params


def run(args) -> int:
    import time

    from .. import scenes
    from ..errors import ConfigError
    from ..pipeline import synthesize_stream, uniform_stamps_ns, write_output
    from ._common import fail_fast_output, load_extrinsic, say, seed_or_default, summary

    if args.list:
        for name in scenes.scene_names():
            cls = scenes.SCENES[name]
            doc = (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else ""
            say(f"{name:14s} {doc}")
            for pname, prm in getattr(cls, "PARAMS", {}).items():
                say(f"    {pname:24s} default {prm.default!r} [{prm.unit}]")
        return 0
    if not args.name:
        raise ConfigError("give a scene name (or --list)")
    if not args.out and not args.tum:
        raise ConfigError("nothing to write: give -o OUT and/or --tum FILE")
    t0 = time.perf_counter()
    fail_fast_output(args)
    scene = scenes.make_scene(args.name, duration_s=args.duration, t0_ns=args.t0_ns, **_parse_params(args.param))
    if args.tum:
        scenes.write_scene_tum(scene, args.tum, args.rate)
        say(f"poses         {args.tum} ({args.rate:g} Hz)")
    if not args.out:
        return 0
    t_ns = uniform_stamps_ns(scene.origin_ns, scene.origin_ns + int(round(scene.t_max_s * 1e9)), args.rate)
    seed = seed_or_default(args.seed) if args.imu else args.seed
    syn = synthesize_stream(scene, t_ns, gravity=tuple(args.gravity), extrinsic=load_extrinsic(args.extrinsic),
                            imu_config=args.imu, seed=seed, sampling=args.sampling,
                            with_increments=args.increments)
    report = {"source": {"kind": "analytic scene", **scene.describe()}, "rate_hz": args.rate}
    rep = write_output(syn, args.out, force=args.force, report=report, bag=args.bag, plot=args.plot)
    say(f"scene         {args.name}, {scene.t_max_s:g} s")
    summary(rep, args.out, t0)
    return 0
