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
      --timestamps V1_02_medium/mav0/imu0/data.csv --imu euroc
"""


def add_arguments(p):
    from ._from_poses import add_pose_args

    add_pose_args(p, "EuRoC ground-truth csv")


def run(args) -> int:
    from ..io.euroc import read_euroc_groundtruth
    from ._from_poses import run_from_poses

    return run_from_poses(args, read_euroc_groundtruth)
