"""``splineimu allan``: Allan deviation and noise parameters of a static IMU recording."""

from __future__ import annotations

import math
import sys
from pathlib import Path

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

With -o DIR: DIR/allan.yaml (Kalibr keys with the three per-axis values, <key>_avg, <key>_ci95
and update_rate; usable as --imu DIR/allan.yaml), and with --plot DIR/allan.png.

examples:
  splineimu allan imu0/data.csv -o allan_out --plot
  splineimu allan adis_16405_imu1.rda --format rda --gyro-unit deg/s --accel-unit g
"""

_LABELS = ["gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z"]


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


def load_recording(path, fmt=None, rate_hz=None, gyro_unit=None, accel_unit=None):
    """Read a recording for Allan analysis.

    Returns
    -------
    (data (N, 6): gyro [rad/s] then accel [m/s^2] columns, rate_hz, notes: list of str)
    """
    import numpy as np

    from ..errors import ConfigError
    from ..io.imu_csv import ACCEL_UNITS, GYRO_UNITS, read_imu_table, read_static_rda, unit_factor

    path = Path(path)
    if fmt is None:
        fmt = "rda" if path.suffix.lower() in (".rda", ".rdata") else "euroc"
    notes = []
    if rate_hz is not None and not (math.isfinite(rate_hz) and rate_hz > 0):
        raise ConfigError(f"--rate must be a positive number of Hz, got {rate_hz}")
    if fmt == "rda":
        rate = 100.0 if rate_hz is None else rate_hz
        _, gyro, accel = read_static_rda(path, rate_hz=rate, gyro_unit=gyro_unit or "deg/s",
                                         accel_unit=accel_unit or "g")
        notes.append(f"no stamps in an .rda file: {rate:g} Hz assumed; units gyro {gyro_unit or 'deg/s'}, "
                     f"accel {accel_unit or 'g'}")
        return np.hstack([gyro, accel]), rate, notes
    t_ns, data = read_imu_table(path)
    if gyro_unit:
        data[:, :3] *= unit_factor(gyro_unit, GYRO_UNITS, "gyro")
    if accel_unit:
        data[:, 3:] *= unit_factor(accel_unit, ACCEL_UNITS, "accelerometer")
    if t_ns.size < 3:
        raise ConfigError(f"{path}: need at least 3 samples for an Allan deviation, got {t_ns.size}")
    d = np.diff(t_ns)
    med = float(np.median(d))
    rate = 1e9 / med if rate_hz is None else rate_hz
    gaps = int(np.count_nonzero(d > 1.5 * med))
    if gaps:
        notes.append(f"{gaps} gap(s) longer than 1.5 sample intervals (longest {d.max() / 1e9:.3g} s): "
                     "the Allan deviation assumes even sampling")
    return data, rate, notes


def _fmt_ci(v, ci, mark=""):
    hi = "inf" if not math.isfinite(ci[1]) else f"{ci[1]:.3e}"
    return f"{v:.3e}{mark:1s} [{ci[0]:.3e}, {hi}]"


def format_table(result, fit, source="") -> str:
    """The stdout table of ``splineimu allan``."""
    lines = []
    if source:
        lines.append(f"Allan deviation of {source}")
    lines.append(f"  {result.n_samples} samples at {result.rate_hz:.6g} Hz ({result.duration_s:.1f} s); "
                 f"{result.taus_s.size} cluster times {result.taus_s[0]:.3g} s .. {result.taus_s[-1]:.4g} s")
    w = 37
    lines.append(f"{'axis':8s}  {'white noise N [95% CI]':{w}s}  {'random walk K [95% CI]':{w}s}  "
                 f"{'bias instability B [95% CI]':{w}s}  tau_B [s]")
    any_k = any_b = False
    for k in range(result.adev.shape[1]):
        km = "" if fit.random_walk_resolved[k] else "*"
        bm = "" if fit.bias_instability_resolved[k] else "~"
        any_k |= bool(km)
        any_b |= bool(bm)
        n_txt = _fmt_ci(fit.white_noise_density[k], fit.white_noise_density_ci95[k])
        k_txt = _fmt_ci(fit.random_walk[k], fit.random_walk_ci95[k], km)
        b_txt = _fmt_ci(fit.bias_instability[k], fit.bias_instability_ci95[k], bm)
        lines.append(f"{result.labels[k]:8s}  {n_txt:{w}s}  {k_txt:{w}s}  {b_txt:{w}s}"
                     f"  {fit.bias_instability_tau_s[k]:.4g}")
    if result.adev.shape[1] == 6:
        lines.append("units: gyro N rad/s/sqrt(Hz), K rad/s^2/sqrt(Hz), B rad/s; "
                     "accel N m/s^2/sqrt(Hz), K m/s^3/sqrt(Hz), B m/s^2")
    if any_k:
        lines.append("* random walk not resolved (not significant at 95%): the value is its 95% upper bound")
    if any_b:
        lines.append("~ no flat region (the minimum is the white / random-walk crossover): "
                     "B is an upper bound")
    return "\n".join(lines)


def run(args) -> int:

    from ..allan import allan_deviation, fit_noise_parameters, imu_noise_dict, plot_allan
    from ..errors import ConfigError, OutputExistsError
    from ..imu.config import write_yaml_atomic

    if args.plot and not args.output:
        raise ConfigError("--plot needs -o DIR (the plot is written to DIR/allan.png)")
    out_dir = Path(args.output) if args.output else None
    targets = []
    if out_dir is not None:
        if out_dir.exists() and not out_dir.is_dir():
            raise ConfigError(f"-o {out_dir}: exists and is not a directory")
        targets = [out_dir / "allan.yaml"] + ([out_dir / "allan.png"] if args.plot else [])
        existing = [str(p) for p in targets if p.exists()]
        if existing and not args.force:
            raise OutputExistsError(f"{', '.join(existing)} exist(s); use --force to overwrite")

    data, rate, notes = load_recording(args.input, args.format, args.rate, args.gyro_unit,
                                              args.accel_unit)
    for note in notes:
        print(f"note: {note}", file=sys.stderr)
    result = allan_deviation(data, rate, points_per_decade=args.points_per_decade,
                             labels=_LABELS)
    fit = fit_noise_parameters(result)
    print(format_table(result, fit, source=str(args.input)))

    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        d = imu_noise_dict(result, fit, source=str(args.input))
        header = [
            f"# splineimu allan: noise parameters identified from {args.input}",
            f"# {result.n_samples} samples at {rate:.6g} Hz ({result.duration_s:.1f} s).",
            "# Each Kalibr key holds [x, y, z]; <key>_avg is their mean, <key>_ci95 the 95% interval",
            "# per axis.",
            "# Units: gyro noise rad/s/sqrt(Hz), gyro walk rad/s^2/sqrt(Hz), accel noise m/s^2/sqrt(Hz),",
            "# accel walk m/s^3/sqrt(Hz). Usable as `--imu` (the `allan` section is informational).",
        ]
        write_yaml_atomic(out_dir / "allan.yaml", d, header)
        print(f"wrote {out_dir / 'allan.yaml'}")
        if args.plot:
            plot_allan(result, fit, out_dir / "allan.png",
                       title=f"{Path(args.input).name}: {result.duration_s / 3600:.2f} h at {rate:.6g} Hz")
            print(f"wrote {out_dir / 'allan.png'}")
    return 0
