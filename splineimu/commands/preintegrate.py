"""``splineimu preintegrate``: preintegrate an output folder's IMU and compare with ground truth."""

from __future__ import annotations

import sys

NAME = "preintegrate"
HELP = "preintegrate an output folder's IMU over windows and compare the deltas with ground truth"
ORDER = 55
DESCRIPTION = """\
VINS-style preintegration (splineimu.preintegration) of OUT/mav0/imu0/data.csv over windows, compared
with the exact deltas of OUT/mav0/state_groundtruth_estimate0/data.csv (EuRoC 17 columns: ns, p xyz,
q w x y z, v xyz, b_w xyz, b_a xyz). Each window is linearized at the ground-truth biases at its
start, so the errors are what the noise (and the bias drift inside the window) leaves.

Windows: every N IMU samples (--every, default: about 1 s of samples), or between consecutive
stamps of a file (--stamps; first column, ns or s, e.g. a camera's data.csv). IMU samples at
window bounds that fall between samples are interpolated linearly; ground truth between its
stamps is interpolated (slerp for the rotation).

With noise densities (--imu: an IMU yaml with Kalibr keys, a Kalibr imu chain, or a preset name;
default OUT/imu.yaml when it exists) the table also has each window's 9-dof NEES of the
(p, theta, v) error and a summary against the chi-square interval. One-step windows get no
NEES (their 9x9 covariance is singular); windows of a few samples are dominated by the
midpoint rule's deterministic discretization error in p, which the covariance does not model.

Samples taken with --sampling mean (recorded in OUT/report.json) are turned into point values
first; --sampling overrides what is recorded. Stamps on an IMU clock with an offset or drift
(`splineimu scene --time-offset S --clock-drift-ppm PPM`, recorded in OUT/report.json as
timing.model) are mapped to true time before the windows are cut; --time-offset and
--clock-drift-ppm override what is recorded (0 turns the correction off). Folders without mav0/
(older layout) are read too.

Example:
  splineimu preintegrate out --every 200
  splineimu preintegrate out --stamps cam0_stamps.csv --imu imu.yaml -o windows.csv
"""

def add_arguments(parser) -> None:
    from ._flags import add_clock_args

    parser.add_argument("out_folder", metavar="OUT_FOLDER",
                        help="folder with mav0/imu0/data.csv and mav0/state_groundtruth_estimate0/data.csv")
    win = parser.add_mutually_exclusive_group()
    win.add_argument("--every", type=int, metavar="N", default=None,
                     help="window length in IMU samples (default: about 1 s)")
    win.add_argument("--stamps", metavar="FILE", default=None,
                     help="window bounds: first column of FILE, ns (integers) or s (decimals)")
    parser.add_argument("--imu", metavar="IMU.yaml", default=None,
                        help="noise parameters (yaml with Kalibr keys, or a preset name) for the "
                             "covariance and NEES (default: OUT_FOLDER/imu.yaml if present)")
    parser.add_argument("--method", choices=("midpoint", "euler"), default="midpoint",
                        help="discretization (default: midpoint)")
    parser.add_argument("--covariance", choices=("consistent", "vins"), default="consistent",
                        help="noise model of the covariance (default: consistent)")
    parser.add_argument("--gravity", nargs=3, type=float, metavar=("GX", "GY", "GZ"),
                        default=(0.0, 0.0, -9.81), help="world gravity [m/s^2] (default: 0 0 -9.81)")
    parser.add_argument("--imu-csv", metavar="CSV", default=None,
                        help="IMU csv instead of OUT_FOLDER/mav0/imu0/data.csv")
    parser.add_argument("--groundtruth", metavar="CSV", default=None,
                        help="ground truth instead of OUT_FOLDER/mav0/state_groundtruth_estimate0/data.csv")
    parser.add_argument("--sampling", choices=("point", "mean"), default=None,
                        help="samples at the stamps, or means over [previous stamp, stamp] "
                             "(default: as recorded in OUT_FOLDER/report.json, else point)")
    add_clock_args(parser, "OUT_FOLDER/")
    parser.add_argument("--all", action="store_true", help="print every window (default: at most 40)")
    parser.add_argument("-o", "--output", metavar="CSV", default=None, help="also write the table as csv")
    parser.add_argument("--force", action="store_true", help="replace an existing output file")


def run(args) -> int:
    from pathlib import Path

    from ..api.preintegration import evaluate_recording
    from ..io.files import check_output_file, write_output_file
    from ._flags import RECORDING_FLAGS, flag_names

    folder = Path(args.out_folder)
    inputs = [args.imu_csv, args.stamps, args.imu, args.groundtruth, folder / "imu.yaml"]
    inputs += [base / sub / "data.csv" for base in (folder, folder / "mav0")  # the defaults, either layout
               for sub in ("imu0", "state_groundtruth_estimate0")]
    if args.output:
        check_output_file(args.output, args.force, inputs=inputs)
    with flag_names(RECORDING_FLAGS):
        res = evaluate_recording(args.out_folder, imu_csv=args.imu_csv, groundtruth=args.groundtruth,
                                 every=args.every, stamps=args.stamps, imu=args.imu, method=args.method,
                                 covariance=args.covariance, gravity=args.gravity, sampling=args.sampling,
                                 time_offset_s=args.time_offset, clock_drift_ppm=args.clock_drift_ppm)
    df = res.to_dataframe()
    for note in res.notes:
        print(f"note: {note}", file=sys.stderr)
    if res.clock_line:
        print(res.clock_line)
    print(f"{len(df)} windows, {args.method} / {args.covariance}; noise: "
          f"{res.noise_source if res.noise is not None else 'none (no NEES)'}")
    print(res.format_table(limit=None if args.all else 40))
    print(f"max error: p {df['err_p_m'].max():.3e} m, v {df['err_v_m_s'].max():.3e} m/s, "
          f"theta {df['err_theta_deg'].max():.3e} deg")
    if res.noise is not None:
        if res.n_nees < len(df):
            why = "the noise densities are all 0" if res.noise_free else "singular covariance: too few samples"
            print(f"{len(df) - res.n_nees} windows without NEES ({why})")
        test = res.nees_test()
        if test is not None:
            print(f"mean NEES {test.mean:.3f} (9 dof; 95% interval for {test.n_windows} windows "
                  f"[{test.low:.3f}, {test.high:.3f}]: {'inside' if test.inside else 'OUTSIDE'})")
    if args.output:
        print(f"table -> {write_output_file(args.output, df.to_csv(index=False), args.force, inputs=inputs)}")
    return 0
