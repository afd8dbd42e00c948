"""Calibrating a recording on disk: :func:`calibrate_file`, the library behind ``splineimu calibrate``.

Reads a EuRoC imu csv, takes the reference (gravity, table rate) from the options or from the
data folder's ``report.json`` (a ``splineimu scene`` output), calibrates, compares with the true
sensor model when one is known (the data folder's ``imu.yaml`` and the true biases of its ground
truth) and adds the result to ``OUT/calibration.yaml``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..calibration.correct import intrinsics_from_config
from ..calibration.estimate import calibrate_accel, calibrate_gyro
from ..calibration.options import CalibrationOptions
from ..calibration.report import chi2_summary, estimates_table, phase_table
from ..calibration.result import SensorCalibration
from ..errors import ConfigError, InputError, OutputExistsError
from ..imu.config import load_imu_config
from ..io.calibration_yaml import check_calibration_target, write_calibration_yaml
from ..io.dataset import GROUNDTRUTH_CSV, dataset_file, dataset_root
from ..io.euroc import read_euroc_groundtruth
from ..io.files import check_output_file
from ..io.imu_csv import read_imu_csv
from ..validation import one_of, positive_float

__all__ = ["CalibrationRun", "calibrate_file", "SENSOR_NAMES"]

#: Accepted sensor names -> the sensor-model prefix.
SENSOR_NAMES = {"accel": "accelerometer", "accelerometer": "accelerometer", "gyro": "gyroscope",
                "gyroscope": "gyroscope"}


@dataclass
class CalibrationRun:
    """What :func:`calibrate_file` did: the calibration, its reference, the truth and the output.

    Attributes
    ----------
    sensor : {"accelerometer", "gyroscope"}
    input_path : pathlib.Path
    calibration : SensorCalibration
    reference : str
        The reference used and where it came from, e.g. ``"g = 9.81 m/s^2 (report.json)"``.
    truth : (K (3, 3), b (3,)) or None
        The true intrinsics, when the data folder (or ``truth``) gives them.
    truth_note : str
        Where the truth came from.
    written : pathlib.Path or None
        The calibration file written.
    notes : list of str
        Warnings for the user (e.g. a fit statistic that the noise does not explain).
    """

    sensor: str
    input_path: Path
    calibration: SensorCalibration
    reference: str
    truth: tuple | None = None
    truth_note: str = ""
    written: Path | None = None
    notes: list = field(default_factory=list)

    @property
    def unit(self) -> str:
        return "m/s^2" if self.sensor == "accelerometer" else "rad/s"

    def drift_line(self) -> str:
        """The bias drift used, or ``""`` when none was modelled."""
        cal = self.calibration
        if cal.random_walk_source == "none":
            return ""
        if not np.any(cal.random_walk > 0):
            return "bias drift: no random walk found in the phases (white noise only)"
        unit = "m/s^3/sqrt(Hz)" if self.sensor == "accelerometer" else "rad/s^2/sqrt(Hz)"
        rw = np.unique(cal.random_walk)
        text = ", ".join(f"{v:.3g}" for v in (rw if rw.size > 1 else rw[:1]))
        return (f"bias drift: random walk {text} {unit} ({cal.random_walk_source}); up to "
                f"{100 * cal.drift_share:.0f}% of a parameter's predicted variance")

    def summary(self) -> str:
        """The text ``splineimu calibrate`` prints: phases, fit statistic, estimates, truth, noise."""
        cal = self.calibration
        used = sum(p.used for p in cal.phases)
        method = "nominal references" if cal.method == "nominal" else \
            f"random tilts, sigma {math.degrees(cal.tilt_sigma_rad):g} deg (nominal method beside)"
        lines = [f"{self.sensor} calibration of {self.input_path}: {len(cal.phases)} steady phases, {used} used; "
                 f"{self.reference}; {method}",
                 phase_table(cal, self.unit), chi2_summary(cal)[0], estimates_table(cal, self.truth)]
        if self.truth is not None:
            lines.append(self.truth_note)
        if self.drift_line():
            lines.append(self.drift_line())
        lines.append(f"noise density from the phases: {np.array2string(cal.noise_density, precision=4)} "
                     f"{self.unit}/sqrt(Hz)")
        if self.written is not None:
            lines.append(f"wrote {self.written}")
        return "\n".join(lines)


def _data_folder(csv_path: Path) -> Path:
    return dataset_root(csv_path)


def _report(folder: Path):
    """The data folder's report.json (None without one); one that exists but is not JSON is an
    error, not a silent g = 9.81 and no table rate."""
    path = folder / "report.json"
    advice = "it gives g and the table rates: repair it, or give --gravity-magnitude / --table-rate"
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read ({getattr(exc, 'strerror', None) or exc}); {advice}", path=path) from None
    try:
        return json.loads(text)
    except ValueError as exc:
        raise InputError(f"not valid JSON ({exc.msg}); {advice}", path=path, line=exc.lineno) from None


def _gravity(given, report):
    if given is not None:
        return positive_float(given, "gravity_m_s2"), "--gravity-magnitude"
    try:
        g = report["imu"]["gravity_m_s2"]
        return float(math.sqrt(sum(float(v) ** 2 for v in g))), "report.json"
    except (TypeError, KeyError, ValueError):
        return 9.81, "default"


def _table_rates(given, report):
    if given:
        return [positive_float(r, "table_rates_rad_s") for r in np.atleast_1d(given).tolist()], "--table-rate"
    try:
        src = report["source"]
        if src.get("name") == "rate-table":
            return [float(src["params"]["rate_rad_s"])], "report.json"
    except (TypeError, KeyError, ValueError, AttributeError):
        pass
    raise ConfigError("give the table rate with --table-rate RAD_S (no rate-table report.json beside the data)",
                      option="--table-rate")


def _truth(truth, folder: Path, sensor: str, t_ns, cal):
    """``(K, b, note)`` of the true sensor model, or ``None``."""
    path = Path(truth) if truth else folder / "imu.yaml"
    if not truth and not path.is_file():
        return None
    cfg = load_imu_config(str(truth) if truth else str(path))  # `truth` may also name a preset
    K, b = intrinsics_from_config(cfg, sensor)
    note = f"truth: {path}"
    gt = dataset_file(folder, GROUNDTRUTH_CSV)
    if gt.is_file():
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


#: The sections of calibration.yaml (io.calibration_yaml) and the sensors of its `calibration` section.
_SECTIONS = ("imu0", "std", "calibration")


def _check_known_keys(target: Path) -> None:
    """Refuse an existing calibration.yaml with keys the writer does not know: rewriting it dropped
    the unknown top-level keys (and ``imu0`` / ``std`` keys of the sensor calibrated) in silence,
    and kept the other unknown ``imu0`` keys, so that the file written no longer loaded as a sensor
    model. The check names the file, the line and the keys, before any work."""
    from ..imu._config_values import IGNORED_KEYS, field_names
    from ..imu.config import ImuConfig
    from ..io.yaml import read_yaml

    if not target.is_file():
        return
    try:
        doc = read_yaml(target, "calibration file")
    except ConfigError:
        return  # not a calibration file: check_calibration_target decided (refused, or replaced with --force)
    if not isinstance(doc.data, dict):
        return
    known = {"std": set(field_names()) | {"rate_hz"} | set(IGNORED_KEYS),
             "calibration": set(SENSOR_NAMES.values())}
    unknown = [(k,) for k in doc.data if k not in _SECTIONS]
    for section, names in known.items():
        block = doc.data.get(section)
        unknown += [(section, k) for k in (block if isinstance(block, dict) else ()) if k not in names]
    if unknown:
        keys = ", ".join(f"`{'.'.join(map(str, k))}`" for k in unknown)
        one = len(unknown) == 1
        raise ConfigError(f"unknown key{'' if one else 's'} {keys}: not part of a calibration file (writing it again "
                          f"would drop or keep {'it' if one else 'them'} unchecked); remove {'it' if one else 'them'}, "
                          "or write to another folder", path=target, line=doc.line(*unknown[0]))
    imu0 = doc.data.get("imu0")
    if isinstance(imu0, dict) and imu0:
        try:
            ImuConfig.from_dict(imu0, source=str(target), base_dir=target.parent)
        except ConfigError as exc:
            named = [k for k in imu0 if f"`{k}`" in exc.problem]  # the key the message names, if any
            line = doc.line("imu0", named[0]) if named else doc.line("imu0")
            raise ConfigError(f"`imu0`: {exc.problem}; the file must load as a sensor model: repair it, or write to "
                              "another folder", path=target, line=line) from None


def calibrate_file(path, sensor: str, options: CalibrationOptions | None = None, *, gravity_m_s2=None,
                   table_rates_rad_s=None, shared_mount: bool = True, out_dir=None, force: bool = False,
                   truth=None) -> CalibrationRun:
    """Calibrate one sensor from a EuRoC imu csv and (optionally) add it to ``out_dir/calibration.yaml``.

    Parameters
    ----------
    path : str or os.PathLike
        EuRoC imu csv (``#timestamp [ns]``, gyro xyz [rad/s], accel xyz [m/s^2]).
    sensor : {"accel", "gyro", "accelerometer", "gyroscope"}
    options : CalibrationOptions, optional
        Segmentation, weighting and orientation-error settings.
    gravity_m_s2 : float, optional
        Local gravity (accelerometer); default: the data folder's ``report.json``, else 9.81.
    table_rates_rad_s : float or sequence of float, optional
        Table rate magnitude(s) (gyro); default: a rate-table ``report.json`` beside the data.
    shared_mount : bool, default True
        The +rate and -rate phases about one axis share a mount (gyro).
    out_dir : str or os.PathLike, optional
        Write ``out_dir/calibration.yaml`` (added to an existing one).
    force : bool, default False
        Replace this sensor's entries in an existing ``calibration.yaml``.
    truth : str, optional
        True sensor model to compare with (a file or preset); default: the data folder's ``imu.yaml``.

    Returns
    -------
    CalibrationRun

    Raises
    ------
    OutputExistsError
        ``out_dir`` is a file, or its ``calibration.yaml`` already holds this sensor (checked
        before any work) and ``force`` is False.
    ConfigError
        An existing ``calibration.yaml`` has keys a calibration file does not have, or an
        ``imu0`` section that does not load as a sensor model (checked before any work, with
        ``force`` too: they would be lost or written back unchecked).
    ConfigError, InputError
        Bad options, no table rate for a gyro, unreadable data, too few usable phases.
    """
    sensor = SENSOR_NAMES[one_of(sensor, "sensor", tuple(SENSOR_NAMES))]
    options = CalibrationOptions() if options is None else options
    target = None
    if out_dir is not None:
        if Path(out_dir).exists() and not Path(out_dir).is_dir():
            raise OutputExistsError(f"output path '{out_dir}' exists and is not a folder")
        target = Path(out_dir) / "calibration.yaml"
        check_output_file(target, True, inputs=[path, truth])  # never a link, a folder or an input
        check_calibration_target(target, [sensor], force)
        _check_known_keys(target)
    csv = Path(path)
    folder = _data_folder(csv)
    given = gravity_m_s2 is not None if sensor == "accelerometer" else bool(table_rates_rad_s)
    report = None if given else _report(folder)  # read only for what was not given
    t_ns, gyro, accel = read_imu_csv(csv)
    if t_ns.shape[0] < 3:  # the segmentation's own check does not know the file
        raise InputError(f"need at least 3 IMU samples for a calibration, got {t_ns.shape[0]}", path=csv)
    if sensor == "accelerometer":
        g, g_src = _gravity(gravity_m_s2, report)
        cal = calibrate_accel(t_ns, accel, g, gyro=gyro, options=options)
        reference = f"g = {g:.6g} m/s^2 ({g_src})"
    else:
        rates, r_src = _table_rates(table_rates_rad_s, report)
        cal = calibrate_gyro(t_ns, gyro, rates, accel=accel, shared_mount=shared_mount, options=options)
        reference = f"table rate {', '.join(f'{r:g}' for r in rates)} rad/s ({r_src})"
    run = CalibrationRun(sensor, csv, cal, reference)
    if chi2_summary(cal)[1]:
        run.notes.append("the phase means scatter more than the white noise explains (orientation error? "
                         "bias drift?); consider --tilt-sigma-deg")
    if cal.drift_dominated:
        run.notes.append(f"the bias drift over the recording dominates the uncertainty ({100 * cal.drift_share:.0f}% "
                         "of some parameter's predicted variance): shorter moves between the phases, or a sensor "
                         "whose bias has settled, give better estimates")
    got = _truth(truth, folder, sensor, t_ns, cal)
    if got is not None:
        run.truth, run.truth_note = got[:2], got[2]
    if target is not None:
        used = sum(p.used for p in cal.phases)
        source = f"{csv} ({cal.method} method, {used} phases; {reference})"
        run.written = write_calibration_yaml(target, cal, source=source, force=force)
    return run
