"""``splineimu preintegrate``: preintegrate an output folder's IMU and compare with ground truth."""

from __future__ import annotations

from pathlib import Path

NAME = "preintegrate"
HELP = "preintegrate an output folder's IMU over windows and compare the deltas with ground truth"
ORDER = 55
DESCRIPTION = """\
VINS-style preintegration (splineimu.preintegration) of OUT/imu0/data.csv over windows, compared
with the exact deltas of OUT/state_groundtruth_estimate0/data.csv (EuRoC 17 columns: ns, p xyz,
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

Example:
  splineimu preintegrate out --every 200
  splineimu preintegrate out --stamps cam0_stamps.csv --imu imu.yaml -o windows.csv
"""

KALIBR_KEYS = ("gyroscope_noise_density", "accelerometer_noise_density",
               "gyroscope_random_walk", "accelerometer_random_walk")


def add_arguments(parser) -> None:
    parser.add_argument("out_folder", metavar="OUT_FOLDER",
                        help="folder with imu0/data.csv and state_groundtruth_estimate0/data.csv")
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
                        help="IMU csv instead of OUT_FOLDER/imu0/data.csv")
    parser.add_argument("--groundtruth", metavar="CSV", default=None,
                        help="ground truth instead of OUT_FOLDER/state_groundtruth_estimate0/data.csv")
    parser.add_argument("--all", action="store_true", help="print every window (default: at most 40)")
    parser.add_argument("-o", "--output", metavar="CSV", default=None, help="also write the table as csv")


# ----------------------------------------------------------------------------- readers


def read_euroc_groundtruth(path):
    """EuRoC ground truth -> (t_ns, p, quat_xyzw, v, b_w, b_a), through :mod:`splineimu.io.euroc`."""
    from ..errors import InputError
    from ..io.euroc import read_euroc_groundtruth as _read

    track = _read(path)
    if track.velocity_world is None:
        raise InputError("expected 17 columns (ns, p xyz, q wxyz, v xyz, b_w xyz, b_a xyz)", path)
    return (track.t_ns, track.positions, track.quat_xyzw, track.velocity_world, track.bias_gyro,
            track.bias_accel)


def read_noise_yaml(spec) -> dict:
    """The four Kalibr densities ((3,) arrays) of an IMU yaml or preset, via the shared
    :func:`splineimu.imu.config.load_imu_config` (Kalibr chains and OpenCV headers included)."""
    from ..imu.config import load_imu_config

    cfg = load_imu_config(spec)
    return {k: getattr(cfg, k).copy() for k in KALIBR_KEYS}


def make_windows(imu_t_ns, gt_t_ns, every=None, stamps_ns=None):
    """(W, 2) int64 windows inside both the IMU and the ground-truth spans."""
    import numpy as np

    from ..errors import ConfigError

    lo = max(int(imu_t_ns[0]), int(gt_t_ns[0]))
    hi = min(int(imu_t_ns[-1]), int(gt_t_ns[-1]))
    if stamps_ns is not None:
        s = np.asarray(stamps_ns, dtype=np.int64)
        s = s[(s >= lo) & (s <= hi)]
        if s.size < 2:
            raise ConfigError(f"fewer than 2 stamps inside the IMU and ground-truth span [{lo}, {hi}] ns")
        return np.stack([s[:-1], s[1:]], axis=1)
    t = imu_t_ns[(imu_t_ns >= lo) & (imu_t_ns <= hi)]
    if t.size < 2:
        raise ConfigError("fewer than 2 IMU samples inside the ground truth's span")
    if every is None:
        every = max(1, int(round(1e9 / float(np.median(np.diff(t))))))
    if every < 1:
        raise ConfigError(f"--every must be >= 1, got {every}")
    idx = np.arange(0, t.size, every)
    if idx.size < 2:
        raise ConfigError(f"--every {every} is longer than the {t.size} usable IMU samples")
    return np.stack([t[idx[:-1]], t[idx[1:]]], axis=1)


# ----------------------------------------------------------------------------- run


def run(args) -> int:
    import numpy as np
    from scipy import stats

    from ..errors import ConfigError
    from ..io.imu_csv import read_imu_csv
    from ..preintegration import evaluate_windows

    out = Path(args.out_folder)
    imu_path = Path(args.imu_csv) if args.imu_csv else out / "imu0" / "data.csv"
    gt_path = Path(args.groundtruth) if args.groundtruth else out / "state_groundtruth_estimate0" / "data.csv"
    for p, what in ((imu_path, "IMU csv"), (gt_path, "ground truth")):
        if not p.is_file():
            raise ConfigError(f"{what} not found: {p}")
    noise_path = args.imu if args.imu else (out / "imu.yaml" if (out / "imu.yaml").is_file() else None)
    noise = read_noise_yaml(noise_path) if noise_path is not None else None

    t_ns, gyro, accel = read_imu_csv(imu_path)
    gt = read_euroc_groundtruth(gt_path)
    stamps = None
    if args.stamps:
        from ..io.timestamps import read_timestamps

        stamps = read_timestamps(args.stamps)
    windows = make_windows(t_ns, gt[0], every=args.every, stamps_ns=stamps)
    res = evaluate_windows(t_ns, gyro, accel, gt[0], gt[1], gt[2], gt[3], gt[4], gt[5], windows,
                           noise=noise, method=args.method, covariance=args.covariance,
                           gravity=args.gravity)
    df = res.to_dataframe()
    print(f"{len(df)} windows, {args.method} / {args.covariance}; noise: "
          f"{noise_path if noise is not None else 'none (no NEES)'}")
    t0 = int(windows[0, 0])
    show = df.copy()
    show.insert(0, "t_i_s", (show["t_i_ns"] - t0) * 1e-9)
    show = show.drop(columns=["t_i_ns", "t_j_ns"])
    if noise is None:
        show = show.drop(columns=["nees9"])
    fmt = {"t_i_s": "{:.3f}".format, "dt_s": "{:.4f}".format, "err_p_m": "{:.3e}".format,
           "err_v_m_s": "{:.3e}".format, "err_theta_deg": "{:.3e}".format, "nees9": "{:.2f}".format}
    lines = show.to_string(index=False, formatters=fmt).splitlines()
    limit = None if args.all else 40
    if limit is not None and len(lines) - 1 > limit:
        half = limit // 2
        skipped = f"... {len(lines) - 1 - limit} windows not shown (--all) ..."
        lines = lines[: 1 + half] + [skipped] + lines[-half:]
    print("\n".join(lines))
    print(f"max error: p {df['err_p_m'].max():.3e} m, v {df['err_v_m_s'].max():.3e} m/s, "
          f"theta {df['err_theta_deg'].max():.3e} deg")
    if noise is not None:
        ok = np.isfinite(res.nees)
        n = int(ok.sum())
        if n < len(df):
            print(f"{len(df) - n} windows without NEES (singular covariance: too few samples)")
        if n:
            lo, hi = stats.chi2.ppf([0.025, 0.975], 9 * n) / n
            m = float(np.mean(res.nees[ok]))
            verdict = "inside" if lo <= m <= hi else "OUTSIDE"
            print(f"mean NEES {m:.3f} (9 dof; 95% interval for {n} windows [{lo:.3f}, {hi:.3f}]: {verdict})")
    if args.output:
        from ..io.output import atomic_write_text

        dest = atomic_write_text(args.output, df.to_csv(index=False))
        print(f"table -> {dest}")
    return 0
