"""``splineimu allan``: Allan deviation and noise parameters of a static IMU recording."""

from __future__ import annotations

import sys

NAME = "allan"
HELP = "Allan deviation of a static IMU recording: white noise, random walk, bias instability per axis"
ORDER = 60
DESCRIPTION = """\
Overlapping Allan deviation of all six axes of a static IMU recording on log-spaced cluster
times, and the noise parameters in Kalibr's continuous units: white-noise density N read at
tau = 1 s on the -1/2 slope line, random walk K at tau = 3 s on the +1/2 slope line, bias
instability B = (curve minimum) / 0.664, each with a 95% confidence interval.

Input: an EuRoC imu0 csv (#timestamp [ns], gyro xyz [rad/s], accel xyz [m/s^2]), or an R
matrix (.rda, e.g. ../shared/data/static/adis_16405_imu1.rda: 100 Hz, deg/s and g).

With -o DIR: DIR/allan.yaml (the four Kalibr keys as the mean of the three axes, rostopic and
update_rate, read by Kalibr and OpenVINS as an imu.yaml and usable as --imu DIR/allan.yaml; the
per-axis values under <key>_xyz and <key>_ci95), and with --plot DIR/allan.png.

examples:
  splineimu allan OUT/mav0/imu0/data.csv -o allan_out --plot
  splineimu allan adis_16405_imu1.rda --format rda --gyro-unit deg/s --accel-unit g
"""

def add_arguments(parser) -> None:
    parser.add_argument("input", metavar="IMU_FILE", help="EuRoC imu csv, or .rda matrix (see --format)")
    parser.add_argument("-o", "--output", metavar="DIR",
                        help="write DIR/allan.yaml (and DIR/allan.png with --plot)")
    parser.add_argument("--plot", action="store_true", help="also write DIR/allan.png (needs -o)")
    parser.add_argument("--rate", type=float, metavar="HZ",
                        help="sample rate (default: from the csv stamps' median interval; 100 for .rda)")
    parser.add_argument("--format", choices=("euroc", "rda"),
                        help="input format (default: from the extension)")
    parser.add_argument("--gyro-unit", choices=("rad/s", "deg/s", "deg/h"),
                        help="unit of the gyro columns (default rad/s for csv, deg/s for rda)")
    parser.add_argument("--accel-unit", choices=("m/s^2", "g", "mg"),
                        help="unit of the accelerometer columns (default m/s^2 for csv, g for rda)")
    parser.add_argument("--points-per-decade", type=float, default=10.0, metavar="P",
                        help="density of the log-spaced cluster times (default 10)")
    parser.add_argument("--force", action="store_true",
                        help="overwrite an existing DIR/allan.yaml / allan.png")


def run(args) -> int:
    from ..api.allan import allan_output_paths, analyze_recording, write_allan_outputs
    from ..errors import ConfigError
    from ..validation import positive_float
    from ._flags import flag_names

    positive_float(args.points_per_decade, "--points-per-decade")
    if args.plot and not args.output:
        raise ConfigError("--plot needs -o DIR (the plot is written to DIR/allan.png)")
    if args.output:
        allan_output_paths(args.output, args.plot, args.force, inputs=[args.input])  # fail before the analysis
    with flag_names({"rate_hz": "--rate", "fmt": "--format", "gyro_unit": "--gyro-unit", "accel_unit": "--accel-unit"}):
        analysis = analyze_recording(args.input, args.format, args.rate, args.gyro_unit, args.accel_unit,
                                     points_per_decade=args.points_per_decade)
    for note in analysis.notes:
        print(f"note: {note}", file=sys.stderr)
    print(analysis.format_table())
    if args.output:
        for path in write_allan_outputs(analysis, args.output, plot=args.plot, force=args.force):
            print(f"wrote {path}")
    return 0
