"""``splineimu from-euroc``: IMU data from EuRoC ground truth."""

from __future__ import annotations

NAME = "from-euroc"
ORDER = 11
HELP = "IMU data from EuRoC ground truth csv (17 columns, or ns + p + q wxyz)"
DESCRIPTION = """\
Like from-tum, for EuRoC's state_groundtruth_estimate0/data.csv (quaternion w first) or an
8-column csv 'ns, px, py, pz, qw, qx, qy, qz'.

examples:
  splineimu from-euroc V1_02_medium/mav0/state_groundtruth_estimate0/data.csv -o out \\
      --timestamps V1_02_medium/mav0/imu0/data.csv --imu adis16448
"""


def add_arguments(p):
    from ._common import add_pose_args

    add_pose_args(p, "EuRoC ground-truth csv")


def run(args) -> int:
    from ._common import options_from_args, run_synthesis
    from ._startup import POSE_JOB_MODULES, start_up

    with start_up(*POSE_JOB_MODULES):
        job = options_from_args(args, "euroc")
    return run_synthesis(job)
