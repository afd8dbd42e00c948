"""``splineimu run``: a scene file names the motion, the IMU, the outputs and the seed."""

from __future__ import annotations

NAME = "run"
ORDER = 15
HELP = "run a scene file (YAML: motion source, spline, IMU rate and sensor model, outputs, seed)"
DESCRIPTION = """\
Run a scene file. See splineimu/api/scenefile.py (or examples/*.yaml) for the format:

  motion: {scene: ellipse, duration_s: 60}     or   motion: {poses: mocap.tum, spline: {order: 6}}
  imu:    {rate_hz: 200, model: adis16448}
  seed:   42
  output: {dir: out, plot: true}

The file and the command line build the same job: --print shows the command that gives the
same output bytes.

examples:
  splineimu run examples/ellipse_scene.yaml
  splineimu run examples/ellipse_scene.yaml --print    show the equivalent command line
  splineimu run examples/batch_scene.yaml --run-index 7 -o run7
                                   run 7 of `splineimu batch` alone (the same bytes as OUT/runs/00007)

A `vary:` block (see `splineimu batch --help`) is used at its nominal values (mean, midpoint,
first choice) unless --run-index picks a run's draws and seed.
"""


def add_arguments(p):
    p.add_argument("scene_file", metavar="SCENE.yaml")
    p.add_argument("--print", action="store_true", help="print the equivalent command line and exit")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    p.add_argument("-o", "--out", metavar="DIR", help="output folder instead of the file's output.dir")
    p.add_argument("--run-index", type=int, metavar="K",
                   help="run K of a batch over the file's vary: block (its draws and seed; no output.tum)")


def run(args) -> int:
    import dataclasses
    import shlex

    from ..api.scenefile import load_scene_file
    from ._common import echo, run_synthesis

    job = load_scene_file(args.scene_file, run_index=args.run_index)
    if args.force or args.out:
        job.output = dataclasses.replace(job.output, force=args.force or job.output.force,
                                         dir=args.out or job.output.dir)
    if args.print:
        echo("splineimu " + shlex.join(job.to_argv()))
        return 0
    return run_synthesis(job)
