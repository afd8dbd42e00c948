"""``splineimu integrate``: dead-reckon an EuRoC IMU csv into a TUM trajectory."""

from __future__ import annotations

import sys

NAME = "integrate"
HELP = "dead-reckon an IMU csv (EuRoC mav0/imu0/data.csv) into a TUM trajectory"
ORDER = 50
DESCRIPTION = """\
Strapdown dead reckoning of an EuRoC-format IMU file (#timestamp [ns], w xyz [rad/s],
a xyz [m/s^2]; gyro = body rate, accel = specific force) from an initial state.

The initial pose, velocity and biases come from an EuRoC ground-truth csv (17 columns:
ns, p xyz, q w x y z, v xyz, b_w xyz, b_a xyz), by default
IMU_CSV/../../state_groundtruth_estimate0/data.csv (the layout `splineimu from-tum` writes),
interpolated to the first IMU stamp inside the ground truth's span; IMU samples before it
are skipped. Biases are held constant.

Samples taken with --sampling mean (recorded in the output folder's report.json) are turned
into point values first, so they integrate as accurately as point samples; --sampling
overrides what is recorded.

Stamps on an IMU clock with an offset or drift (`splineimu scene --time-offset S
--clock-drift-ppm PPM`, recorded in report.json as timing.model) are mapped to true time
before integrating, and the trajectory is written at true time; --time-offset and
--clock-drift-ppm override what is recorded (0 turns the correction off).

Methods: euler (1st order), midpoint (2nd), rk4 (4th, Munthe-Kaas on SO3). The rotation is
always advanced with the exact SO3 exponential.

Output: TUM file `t tx ty tz qx qy qz qw` at every IMU stamp, t written exactly from the
integer nanoseconds ("%d.%09d").

Example:
  splineimu integrate out/mav0/imu0/data.csv --method rk4 -o dead_reckoning.tum
  splineimu compare dead_reckoning.tum out/groundtruth.tum
"""


def add_arguments(parser) -> None:
    from ._flags import add_clock_args

    parser.add_argument("imu_csv", metavar="IMU_CSV", help="EuRoC imu csv (e.g. OUT/mav0/imu0/data.csv)")
    parser.add_argument("--method", choices=("euler", "midpoint", "rk4"), default="rk4",
                        help="integration method (default: rk4)")
    parser.add_argument("--init", metavar="GROUND_TRUTH", default=None,
                        help="EuRoC ground-truth csv for the initial state (default: "
                             "IMU_CSV/../../state_groundtruth_estimate0/data.csv)")
    parser.add_argument("--gravity", nargs=3, type=float, metavar=("GX", "GY", "GZ"),
                        default=(0.0, 0.0, -9.81), help="gravity in the world frame [m/s^2] "
                        "(default: 0 0 -9.81)")
    parser.add_argument("--sampling", choices=("point", "mean"), default=None,
                        help="the samples are values at the stamps, or means over [previous stamp, stamp] "
                             "(default: as recorded in the folder's report.json, else point)")
    add_clock_args(parser)
    parser.add_argument("-o", "--output", required=True, metavar="TRAJ.tum",
                        help="output TUM file (missing folders are created)")
    parser.add_argument("--force", action="store_true", help="replace an existing output file")


def run(args) -> int:
    from ..api.integrate import dead_reckon
    from ..io.files import check_output_file
    from ._flags import RECORDING_FLAGS, flag_names

    check_output_file(args.output, args.force, inputs=[args.imu_csv, args.init])
    with flag_names(RECORDING_FLAGS):
        res = dead_reckon(args.imu_csv, init=args.init, method=args.method, gravity=args.gravity,
                          sampling=args.sampling, time_offset_s=args.time_offset, clock_drift_ppm=args.clock_drift_ppm)
    for note in res.notes:
        print(f"note: {note}", file=sys.stderr)
    if res.clock_line:
        print(res.clock_line)
    if res.skipped_samples:
        print(f"skipping {res.skipped_samples} IMU samples before the ground truth starts")
    out = res.write_tum(args.output, args.force, inputs=[args.imu_csv, args.init])
    print(f"integrated {len(res.trajectory)} {res.sampling} samples ({res.trajectory.t_s[-1]:.3f} s) with {res.method} "
          f"in {res.integrate_time_s:.3f} s -> {out}")
    if res.final_position_error_m is not None:
        print(f"final position differs from the ground truth by {res.final_position_error_m:.6g} m")
    return 0
