"""``splineimu integrate``: dead-reckon an EuRoC IMU csv into a TUM trajectory."""

from __future__ import annotations

from pathlib import Path

NAME = "integrate"
HELP = "dead-reckon an IMU csv (EuRoC imu0/data.csv) into a TUM trajectory"
ORDER = 50
DESCRIPTION = """\
Strapdown dead reckoning of an EuRoC-format IMU file (#timestamp [ns], w xyz [rad/s],
a xyz [m/s^2]; gyro = body rate, accel = specific force) from an initial state.

The initial pose, velocity and biases come from an EuRoC ground-truth csv (17 columns:
ns, p xyz, q w x y z, v xyz, b_w xyz, b_a xyz), by default
IMU_CSV/../../state_groundtruth_estimate0/data.csv (the layout `splineimu from-tum` writes),
interpolated to the first IMU stamp inside the ground truth's span; IMU samples before it
are skipped. Biases are held constant.

Methods: euler (1st order), midpoint (2nd), rk4 (4th, Munthe-Kaas on SO3). The rotation is
always advanced with the exact SO3 exponential.

Output: TUM file `t tx ty tz qx qy qz qw` at every IMU stamp, t written exactly from the
integer nanoseconds ("%d.%09d").

Example:
  splineimu integrate out/imu0/data.csv --method rk4 -o dead_reckoning.tum
  splineimu compare dead_reckoning.tum out/groundtruth.tum
"""


def add_arguments(parser) -> None:
    parser.add_argument("imu_csv", metavar="IMU_CSV", help="EuRoC imu csv (e.g. OUT/imu0/data.csv)")
    parser.add_argument("--method", choices=("euler", "midpoint", "rk4"), default="rk4",
                        help="integration method (default: rk4)")
    parser.add_argument("--init", metavar="GROUND_TRUTH", default=None,
                        help="EuRoC ground-truth csv for the initial state (default: "
                             "IMU_CSV/../../state_groundtruth_estimate0/data.csv)")
    parser.add_argument("--gravity", nargs=3, type=float, metavar=("GX", "GY", "GZ"),
                        default=(0.0, 0.0, -9.81), help="gravity in the world frame [m/s^2] "
                        "(default: 0 0 -9.81)")
    parser.add_argument("-o", "--output", required=True, metavar="TRAJ.tum", help="output TUM file")


def default_groundtruth_path(imu_csv) -> Path:
    """``OUT/state_groundtruth_estimate0/data.csv`` for ``OUT/imu0/data.csv``."""
    return Path(imu_csv).resolve().parent.parent / "state_groundtruth_estimate0" / "data.csv"


def run(args) -> int:
    import time

    import numpy as np

    from ..errors import ConfigError
    from ..integrate import integrate
    from ..io.imu_csv import read_imu_csv

    imu_path = Path(args.imu_csv)
    gt_path = Path(args.init) if args.init else default_groundtruth_path(imu_path)
    if not gt_path.is_file():
        hint = "" if args.init else " (the default beside the IMU file); pass --init GROUND_TRUTH"
        raise ConfigError(f"initial-state file not found: {gt_path}{hint}")
    t_ns, gyro, accel = read_imu_csv(imu_path)
    gt = read_groundtruth(gt_path)
    init, i0 = initial_state(gt, t_ns, gt_path)
    if i0:
        print(f"skipping {i0} IMU samples before the ground truth starts")
    t_ns = t_ns[i0:]
    if t_ns.shape[0] < 2:
        raise ConfigError(f"fewer than 2 IMU samples inside the ground truth's time span ({gt_path})")
    t_s = (t_ns - t_ns[0]).astype(np.float64) / 1e9
    tic = time.perf_counter()
    traj = integrate(t_s, gyro[i0:], accel[i0:], init, method=args.method, gravity=args.gravity)
    elapsed = time.perf_counter() - tic
    out = write_tum_atomic(args.output, t_ns, traj.position_world, traj.quat_xyzw)
    print(f"integrated {len(traj)} samples ({t_s[-1]:.3f} s) with {args.method} in {elapsed:.3f} s "
          f"-> {out}")
    end = _groundtruth_at(gt, int(t_ns[-1]))
    if end is not None:
        err = float(np.linalg.norm(traj.position_world[-1] - end[0]))
        print(f"final position differs from the ground truth by {err:.6g} m")
    return 0


# ----------------------------------------------------------------------------- file helpers
# The IMU csv is read by splineimu.io.imu_csv, the ground truth by splineimu.io.euroc and the
# TUM text is made by splineimu.io.output.


def read_groundtruth(path):
    """EuRoC ground truth (17 columns, quaternion w x y z) -> dict of arrays, quat in xyzw."""
    from ..errors import InputError
    from ..io.euroc import read_euroc_groundtruth

    track = read_euroc_groundtruth(path)
    if track.velocity_world is None:
        raise InputError("needs the 17-column EuRoC ground truth (velocity and biases) for the "
                         "initial state", path=path)
    return {
        "t_ns": track.t_ns,
        "positions": track.positions,
        "quat_xyzw": track.quat_xyzw,
        "velocity_world": track.velocity_world,
        "bias_gyro": track.bias_gyro,
        "bias_accel": track.bias_accel,
    }


def _groundtruth_at(gt, t_ns: int):
    """(position, quat_xyzw, velocity, bias_gyro, bias_accel) at ``t_ns`` by linear interpolation
    (slerp for the rotation), or None outside the ground truth's span."""
    import numpy as np

    from ..lie import matrix_to_quat_xyzw, quat_xyzw_to_matrix, so3_exp, so3_log

    ts = gt["t_ns"]
    if t_ns < ts[0] or t_ns > ts[-1]:
        return None
    j = int(np.searchsorted(ts, t_ns, side="right")) - 1
    keys = ("positions", "quat_xyzw", "velocity_world", "bias_gyro", "bias_accel")
    if ts[j] == t_ns:
        return tuple(gt[k][j].copy() for k in keys)
    a = float(t_ns - ts[j]) / float(ts[j + 1] - ts[j])
    out = [(1.0 - a) * gt[k][j] + a * gt[k][j + 1] for k in keys]
    R0, R1 = quat_xyzw_to_matrix(gt["quat_xyzw"][j]), quat_xyzw_to_matrix(gt["quat_xyzw"][j + 1])
    out[1] = matrix_to_quat_xyzw(R0 @ so3_exp(a * so3_log(R0.T @ R1)))
    return tuple(out)


def initial_state(gt, imu_t_ns, gt_path):
    """NavState at the first IMU stamp inside the ground truth's span, and that sample's index."""
    import numpy as np

    from ..errors import ConfigError
    from ..integrate import NavState

    i0 = int(np.searchsorted(imu_t_ns, gt["t_ns"][0], side="left"))
    if i0 >= imu_t_ns.shape[0] or imu_t_ns[i0] > gt["t_ns"][-1]:
        raise ConfigError(f"no IMU sample lies inside the ground truth's time span "
                          f"[{gt['t_ns'][0]}, {gt['t_ns'][-1]}] ns of {gt_path}")
    p, q, v, bg, ba = _groundtruth_at(gt, int(imu_t_ns[i0]))
    return NavState(0.0, p, q, v, bg, ba), i0


def write_tum_atomic(path, t_ns, positions, quat_xyzw) -> Path:
    """Write ``t tx ty tz qx qy qz qw`` lines (stamps "%d.%09d" from the integer ns, floats
    lossless) through a temporary file and an atomic rename."""
    import numpy as np

    from ..errors import ConfigError
    from ..io.output import atomic_write_bytes, format_table

    out = Path(path)
    if not out.resolve().parent.is_dir():
        raise ConfigError(f"output folder does not exist: {out.resolve().parent}")
    body = format_table(np.asarray(t_ns, dtype=np.int64), np.concatenate([positions, quat_xyzw], axis=1),
                        sep=" ", stamp="s")
    return atomic_write_bytes(out, b"# timestamp tx ty tz qx qy qz qw\n" + body)
