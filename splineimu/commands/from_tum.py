"""``splineimu from-tum``: the main job -- IMU data from a TUM pose file."""

from __future__ import annotations

NAME = "from-tum"
ORDER = 10
HELP = "IMU data from a TUM trajectory (t x y z qx qy qz qw): fit a spline, differentiate, add noise"
DESCRIPTION = """\
Fit a B-spline to the poses of a TUM file (world_T_body; extra columns after the 8th are
ignored) and write synthetic IMU data whose ground truth is the fitted trajectory.

The knot spacing and spline order are chosen automatically from the data (clean input is
followed closely, noisy mocap is smoothed); --knot-spacing and --order override them.

examples:
  splineimu from-tum poses.txt -o out
  splineimu from-tum mocap.txt -o out --imu adis16448 --seed 3 --rate 400 --plot
  splineimu from-tum poses.txt -o out --timestamps real_imu0.csv --extrinsic T_bs.yaml --bag ros2
"""


def add_arguments(p):
    from ._common import add_pose_args

    add_pose_args(p, "TUM pose file: 'timestamp[s] x y z qx qy qz qw' per line, # comments")


def run(args) -> int:
    from ._common import options_from_args, run_synthesis
    from ._startup import POSE_JOB_MODULES, start_up

    with start_up(*POSE_JOB_MODULES):
        job = options_from_args(args, "tum")
    return run_synthesis(job)
