"""``splineimu calibrate``: six-position accelerometer and rate-table gyro calibration."""

from __future__ import annotations

import math
from pathlib import Path

NAME = "calibrate"
ORDER = 65
HELP = "six-position accelerometer / rate-table gyro calibration: scale, misalignment and bias"
DESCRIPTION = """\
Estimate the 3x3 scale-misalignment matrix K = M S and the bias b of the accelerometer
(six-position test: at rest with each axis up and down) or of the gyro (rate table: each
axis at +rate and -rate, and at rest). The steady phases are found in the data alone (moving
standard deviation against the noise level); each phase's mean is assigned its nominal
reference from its dominant axis; K and b follow by weighted least squares, with predicted
standard deviations from the white noise of each phase. With --tilt-sigma-deg the positions'
orientation errors are modelled as random tilts (the classical estimate is printed beside).

Output with -o CAL: CAL/calibration.yaml. Its `imu0` section holds the estimates under the
sensor-model keys (<sensor>_scale, <sensor>_misalignment with unit diagonal, <sensor>_bias), so
`--imu CAL/calibration.yaml` and splineimu.imu.config.load_imu_config read it; `std` holds
the predicted standard deviations under the same keys; `calibration` the details (K, its
covariance, the phases). Calibrating the other sensor into the same CAL adds to the file.
When the data folder (OUT of `splineimu scene`) has an imu.yaml, the estimates are compared
with it (and with the true biases of state_groundtruth_estimate0/data.csv).

examples:
  splineimu scene six-position -o six --imu imu.yaml --seed 1
  splineimu calibrate accel six/imu0/data.csv -o cal
  splineimu scene rate-table -o rt --imu imu.yaml --seed 2
  splineimu calibrate gyro rt/imu0/data.csv -o cal            (adds the gyro to cal/)
  splineimu scene six-position -o six2 --imu imu.yaml --param tilt_sigma_deg=2
  splineimu calibrate accel six2/imu0/data.csv --tilt-sigma-deg 2
"""


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


# ------------------------------------------------------------------------------ helpers


def _data_folder(csv_path: Path) -> Path:
    return csv_path.parent.parent if csv_path.parent.name == "imu0" else csv_path.parent


def _report(folder: Path):
    import json

    p = folder / "report.json"
    if not p.is_file():
        return None
    try:
        return json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def _gravity(args, report):
    if args.gravity_magnitude is not None:
        return float(args.gravity_magnitude), "--gravity-magnitude"
    try:
        g = report["imu"]["gravity_m_s2"]
        return float(math.sqrt(sum(float(v) ** 2 for v in g))), "report.json"
    except (TypeError, KeyError, ValueError):
        return 9.81, "default"


def _table_rate(args, report):
    from ..errors import ConfigError

    if args.table_rate:
        return [float(r) for r in args.table_rate], "--table-rate"
    try:
        src = report["source"]
        if src.get("name") == "rate-table":
            return [float(src["params"]["rate_rad_s"])], "report.json"
    except (TypeError, KeyError, ValueError):
        pass
    raise ConfigError("give the table rate with --table-rate RAD_S (no rate-table report.json beside the data)")


def _truth(args, folder: Path, sensor: str, t_ns, cal):
    """(K_true, b_true, note) or None."""
    import numpy as np

    from ..calibration import intrinsics_from_config
    from ..imu.config import load_imu_config

    path = Path(args.truth) if args.truth else folder / "imu.yaml"
    if not args.truth and not path.is_file():
        return None
    cfg = load_imu_config(args.truth or str(path))  # --truth may also name a preset
    K, b = intrinsics_from_config(cfg, sensor)
    note = f"truth: {path}"
    gt = folder / "state_groundtruth_estimate0" / "data.csv"
    if gt.is_file():
        from ..io.euroc import read_euroc_groundtruth

        try:
            track = read_euroc_groundtruth(gt)
        except Exception:  # noqa: BLE001 - the comparison is optional
            track = None
        bias = None if track is None else (track.bias_accel if sensor == "accelerometer" else track.bias_gyro)
        if bias is not None and np.array_equal(track.t_ns, t_ns):
            idx = np.concatenate([np.arange(p.start, p.stop) for p in cal.phases if p.used])
            b = bias[idx].mean(axis=0)
            note += f"; true bias: mean of {gt.relative_to(folder)} over the phases used"
    elif cfg.sensor(sensor)["bias_sigma"] is not None:
        note += f" (its random {sensor}_bias_sigma draw is unknown: bias truth incomplete)"
    return K, b, note


def _fmt_phase_table(cal, unit):
    import numpy as np

    t0 = cal.phases[0].t_start_ns if cal.phases else 0
    lines = [f"{'phase':>5s}  {'t [s]':>17s}  {'samples':>7s}  {'ref':>5s}  {'mean [' + unit + ']':>36s}  note"]
    for k, p in enumerate(cal.phases):
        mean = np.array2string(p.mean, formatter={"float_kind": lambda v: f"{v:10.5f}"})
        note = p.note
        if p.tilt_rad is not None:
            d = np.degrees(p.tilt_rad)
            note = f"tilt {d[0]:+.2f} {d[1]:+.2f} deg" + (f"; {note}" if note else "")
        lines.append(f"{k:5d}  {(p.t_start_ns - t0) / 1e9:8.2f}-{(p.t_end_ns - t0) / 1e9:8.2f}  {p.samples:7d}  "
                     f"{(p.label if p.used else '-'):>5s}  {mean:>36s}  {note}")
    return "\n".join(lines)


def _fmt_estimates(cal, truth):
    import numpy as np

    from ..calibration import PARAMETER_NAMES

    est, std = cal.parameters, cal.std
    tv = None if truth is None else np.concatenate([truth[0].ravel(), truth[1]])
    head = f"{'param':7s}"
    if tv is not None:
        head += f" {'truth':>13s}"
    head += f" {'estimate':>13s} {'std':>9s}"
    if tv is not None:
        head += f" {'err/std':>8s}"
    nom = cal.nominal
    if nom is not None:
        head += f"  | {'nominal':>13s} {'std':>9s}" + (f" {'err/std':>8s}" if tv is not None else "")
    lines = [head]
    for k, name in enumerate(PARAMETER_NAMES):
        row = f"{name:7s}"
        if tv is not None:
            row += f" {tv[k]:13.8f}"
        row += f" {est[k]:13.8f} {std[k]:9.2e}"
        if tv is not None:
            row += f" {(est[k] - tv[k]) / std[k]:8.2f}"
        if nom is not None:
            row += f"  | {nom.parameters[k]:13.8f} {nom.std[k]:9.2e}"
            if tv is not None:
                row += f" {(nom.parameters[k] - tv[k]) / nom.std[k]:8.2f}"
        lines.append(row)
    if tv is not None:
        inside = np.abs(est - tv) <= 2 * std
        lines.append(f"{int(inside.sum())} of 12 within 2 predicted std"
                     + (f" (nominal method: {int((np.abs(nom.parameters - tv) <= 2 * nom.std).sum())} of 12)"
                        if nom is not None else ""))
    return "\n".join(lines)


def _chi2_line(cal):
    from scipy.stats import chi2 as chi2_dist

    if cal.dof <= 0:
        return f"chi2 {cal.chi2:.3g} (no redundancy: {cal.dof} dof)", False
    p = float(chi2_dist.sf(cal.chi2, cal.dof))
    return f"chi2 {cal.chi2:.4g} for {cal.dof} dof (p = {p:.3g})", p < 1e-3


# ------------------------------------------------------------------------------ run


def run(args) -> int:
    import numpy as np

    from ..calibration import calibrate_accel, calibrate_gyro, write_calibration_yaml
    from ..errors import ConfigError, OutputExistsError
    from ..io.imu_csv import read_imu_csv
    from ._common import say, stderr

    if args.sensor is None:
        raise ConfigError("give the sensor: `splineimu calibrate accel IMU_CSV` or `splineimu calibrate gyro IMU_CSV`")
    sensor = "accelerometer" if args.sensor == "accel" else "gyroscope"
    target = Path(args.out) / "calibration.yaml" if args.out else None
    if target is not None:
        from ..io.files import check_output_file

        check_output_file(target, True, inputs=[args.input, args.truth])  # a link, a folder or an input
        if Path(args.out).exists() and not Path(args.out).is_dir():
            raise OutputExistsError(f"output path '{args.out}' exists and is not a folder")
        if target.exists() and not args.force:
            import yaml

            try:
                prev = yaml.safe_load(target.read_text(encoding="utf-8")) or {}
            except yaml.YAMLError:
                prev = None
            if not isinstance(prev, dict) or sensor in (prev.get("calibration") or {}):
                raise OutputExistsError(f"{target} already holds a {sensor} calibration (or is not a calibration "
                                        "file); use --force to replace it")

    csv = Path(args.input)
    folder = _data_folder(csv)
    report = _report(folder)
    t_ns, gyro, accel = read_imu_csv(csv)
    seg = {"window_s": args.window, "threshold": args.threshold, "min_dwell_s": args.min_dwell,
           "tilt_sigma_deg": args.tilt_sigma_deg}
    if args.noise_density is not None:
        seg["noise_density"] = args.noise_density
    if sensor == "accelerometer":
        g, g_src = _gravity(args, report)
        cal = calibrate_accel(t_ns, accel, g, gyro=gyro, **seg)
        ref = f"g = {g:.6g} m/s^2 ({g_src})"
        unit = "m/s^2"
    else:
        rates, r_src = _table_rate(args, report)
        cal = calibrate_gyro(t_ns, gyro, rates, accel=accel, shared_mount=not args.separate_mounts, **seg)
        ref = f"table rate {', '.join(f'{r:g}' for r in rates)} rad/s ({r_src})"
        unit = "rad/s"

    used = sum(p.used for p in cal.phases)
    method = "nominal references" if cal.method == "nominal" else \
        f"random tilts, sigma {args.tilt_sigma_deg:g} deg (nominal method beside)"
    say(f"{sensor} calibration of {csv}: {len(cal.phases)} steady phases, {used} used; {ref}; {method}")
    say(_fmt_phase_table(cal, unit))
    line, bad = _chi2_line(cal)
    say(line)
    if bad:
        stderr("note: the phase means scatter more than the white noise explains (orientation error? "
               "bias drift?); consider --tilt-sigma-deg")
    truth = _truth(args, folder, sensor, t_ns, cal)
    say(_fmt_estimates(cal, truth))
    if truth is not None:
        say(truth[2])
    say(f"noise density from the phases: {np.array2string(cal.noise_density, precision=4)} "
        f"{unit}/sqrt(Hz)")
    if target is not None:
        source = f"{csv} ({cal.method} method, {used} phases; {ref})"
        write_calibration_yaml(target, cal, source=source, force=args.force)
        say(f"wrote {target}")
    return 0
