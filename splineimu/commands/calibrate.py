"""``splineimu calibrate``: six-position accelerometer and rate-table gyro calibration."""

from __future__ import annotations

NAME = "calibrate"
ORDER = 65
HELP = "six-position accelerometer / rate-table gyro calibration: scale, misalignment and bias"
DESCRIPTION = """\
Estimate the 3x3 scale-misalignment matrix K = M S and the bias b of the accelerometer
(six-position test: at rest with each axis up and down) or of the gyro (rate table: each
axis at +rate and -rate, and at rest). The steady phases are found in the data alone (moving
standard deviation against the noise level); each phase's mean is assigned its nominal
reference from its dominant axis; K and b follow by generalized least squares, with predicted
standard deviations from the white noise of each phase and the bias drift (random walk) over the
timeline of the phases (its density estimated from the data unless --random-walk gives it).
With --tilt-sigma-deg the positions' orientation errors are modelled as random tilts (the
classical estimate is printed beside).

Output with -o CAL: CAL/calibration.yaml. Its `imu0` section holds the estimates under the
sensor-model keys (<sensor>_scale, <sensor>_misalignment with unit diagonal, <sensor>_bias), so
`--imu CAL/calibration.yaml` and splineimu.imu.config.load_imu_config read it; `std` holds
the predicted standard deviations under the same keys; `calibration` the details (K, its
covariance, the phases). Calibrating the other sensor into the same CAL adds to the file.
When the data folder (OUT of `splineimu scene`) has an imu.yaml, the estimates are compared
with it (and with the true biases of mav0/state_groundtruth_estimate0/data.csv).

examples:
  splineimu scene six-position -o six --imu imu.yaml --seed 1
  splineimu calibrate accel six/mav0/imu0/data.csv -o cal
  splineimu scene rate-table -o rt --imu imu.yaml --seed 2
  splineimu calibrate gyro rt/mav0/imu0/data.csv -o cal            (adds the gyro to cal/)
  splineimu scene six-position -o six2 --imu imu.yaml --param tilt_sigma_deg=2
  splineimu calibrate accel six2/mav0/imu0/data.csv --tilt-sigma-deg 2
"""

#: Library arguments -> flags, for their errors.
FLAGS = {"tilt_sigma_deg": "--tilt-sigma-deg", "noise_density": "--noise-density", "window_s": "--window",
         "threshold": "--threshold", "min_dwell_s": "--min-dwell", "random_walk": "--random-walk",
         "gravity_m_s2": "--gravity-magnitude", "table_rates_rad_s": "--table-rate"}


def _common(s):
    s.add_argument("input", metavar="IMU_CSV",
                   help="EuRoC imu csv (#timestamp [ns], gyro xyz [rad/s], accel xyz [m/s^2])")
    s.add_argument("-o", "--out", metavar="CAL", help="write CAL/calibration.yaml (added to an existing one)")
    s.add_argument("--force", action="store_true",
                   help="replace this sensor's entries in an existing CAL/calibration.yaml")
    s.add_argument("--tilt-sigma-deg", type=float, default=0.0, metavar="DEG",
                   help="std of each component of the orientation error of every position/mount [deg]; "
                        "0 (default): references exactly along the axes")
    s.add_argument("--noise-density", type=float, metavar="N",
                   help="white-noise density for the weights (default: each phase's own scatter)")
    s.add_argument("--random-walk", type=float, metavar="D",
                   help="bias random-walk density for the drift over the phases (accel m/s^3/sqrt(Hz), gyro "
                        "rad/s^2/sqrt(Hz); default: estimated from the data; 0: no drift)")
    s.add_argument("--window", type=float, default=0.5, metavar="S", help="moving window of the segmentation [s] (0.5)")
    s.add_argument("--threshold", type=float, default=1.5, metavar="X",
                   help="steady when the moving std is below X times the noise level (1.5)")
    s.add_argument("--min-dwell", type=float, default=2.0, metavar="S", help="shortest steady phase kept [s] (2)")
    s.add_argument("--truth", metavar="IMU.yaml",
                   help="true sensor model to compare with (default: imu.yaml of the data folder, if any)")


def add_arguments(p):
    import argparse

    sub = p.add_subparsers(dest="sensor", metavar="SENSOR")
    a = sub.add_parser("accel", help="six-position accelerometer calibration",
                       description="Six-position accelerometer calibration (see `splineimu calibrate --help`).",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    _common(a)
    a.add_argument("--gravity-magnitude", type=float, metavar="G",
                   help="local gravity [m/s^2] (default: from the data folder's report.json, else 9.81)")
    g = sub.add_parser("gyro", help="rate-table gyro calibration",
                       description="Rate-table gyro calibration (see `splineimu calibrate --help`).",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    _common(g)
    g.add_argument("--table-rate", type=float, nargs="+", metavar="RAD_S",
                   help="table rate magnitude(s) [rad/s] (default: from the data folder's report.json of a "
                        "rate-table scene)")
    g.add_argument("--separate-mounts", action="store_true",
                   help="each constant-rate phase has its own orientation error (default: the +rate and -rate "
                        "phases about one axis share a mount)")


def run(args) -> int:
    from ..api.calibration import calibrate_file
    from ..calibration import CalibrationOptions
    from ..errors import ConfigError
    from ._common import say, stderr
    from ._flags import flag_names

    if args.sensor is None:
        raise ConfigError("give the sensor: `splineimu calibrate accel IMU_CSV` or `splineimu calibrate gyro IMU_CSV`")
    accel = args.sensor == "accel"
    with flag_names(FLAGS):
        options = CalibrationOptions(tilt_sigma_deg=args.tilt_sigma_deg, noise_density=args.noise_density,
                                     window_s=args.window, threshold=args.threshold, min_dwell_s=args.min_dwell,
                                     random_walk=args.random_walk)
        result = calibrate_file(args.input, args.sensor, options, out_dir=args.out, force=args.force,
                                truth=args.truth, gravity_m_s2=args.gravity_magnitude if accel else None,
                                table_rates_rad_s=None if accel else args.table_rate,
                                shared_mount=accel or not args.separate_mounts)
    say(result.summary())
    for note in result.notes:
        stderr(f"note: {note}")
    return 0
