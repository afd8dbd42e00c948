"""The output folder as a EuRoC / ASL dataset: its paths, its ``sensor.yaml`` files, and
the sampling mode it records.

Layout written by :func:`splineimu.api.output.write_output` (the form of the published EuRoC
zips, so that the EuRoC loaders of Kimera, ORB-SLAM3 and others find the files)::

    OUT/mav0/imu0/data.csv                          IMU samples
    OUT/mav0/imu0/sensor.yaml                       %YAML:1.0: sensor_type imu, T_BS, rate_hz, noise
    OUT/mav0/state_groundtruth_estimate0/data.csv   the IMU's pose, velocity and true biases
    OUT/mav0/state_groundtruth_estimate0/sensor.yaml
    OUT/mav0/body.yaml                              what the body frame is
    OUT/groundtruth.tum, imu.yaml, kalibr_imu_chain.yaml, report.json

Folders written before this layout (``OUT/imu0/data.csv`` and
``OUT/state_groundtruth_estimate0/data.csv`` without ``mav0``) are read as well.

The sampling mode of the data (``point`` or ``mean``) is recorded in ``report.json``
(``imu.sampling``); :func:`recorded_sampling` reads it back for dead reckoning and
preintegration. A folder without ``report.json`` holds point samples. The IMU clock's offset
and drift (``timing.model``) are read back by :func:`recorded_timing`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .yaml import float_text

__all__ = ["IMU_CSV", "IMU_SENSOR_YAML", "GROUNDTRUTH_CSV", "GROUNDTRUTH_SENSOR_YAML", "BODY_YAML",
           "INCREMENTS_CSV", "VIBRATION_CSV", "dataset_file", "dataset_root", "groundtruth_beside", "recorded_sampling",
           "recorded_timing", "sensor_yaml_text", "body_yaml_text"]

IMU_CSV = "mav0/imu0/data.csv"
IMU_SENSOR_YAML = "mav0/imu0/sensor.yaml"
INCREMENTS_CSV = "mav0/imu0/increments.csv"
VIBRATION_CSV = "mav0/imu0/vibration.csv"
GROUNDTRUTH_CSV = "mav0/state_groundtruth_estimate0/data.csv"
GROUNDTRUTH_SENSOR_YAML = "mav0/state_groundtruth_estimate0/sensor.yaml"
BODY_YAML = "mav0/body.yaml"


def dataset_file(folder, name: str) -> Path:
    """``folder / name`` in the EuRoC layout, or in the older layout without ``mav0/`` when only
    that exists (the EuRoC path when neither does, for the error message).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> (d / "imu0").mkdir(); _ = (d / "imu0" / "data.csv").write_text("")
    >>> dataset_file(d, IMU_CSV).relative_to(d).as_posix(), dataset_file(d, GROUNDTRUTH_CSV).relative_to(d).as_posix()
    ('imu0/data.csv', 'mav0/state_groundtruth_estimate0/data.csv')
    """
    folder = Path(folder)
    new = folder / name
    if not new.exists() and name.startswith("mav0/"):
        old = folder / name[len("mav0/"):]
        if old.exists():
            return old
    return new


def dataset_root(imu_csv) -> Path:
    """The output folder of an ``imu0/data.csv``: the folder holding ``mav0/`` (or, in the older
    layout, ``imu0/``); the csv's own folder for a loose file."""
    p = Path(imu_csv).resolve()
    if p.parent.name != "imu0":
        return p.parent
    up = p.parent.parent
    return up.parent if up.name == "mav0" else up


def groundtruth_beside(imu_csv) -> Path:
    """``.../state_groundtruth_estimate0/data.csv`` beside ``.../imu0/data.csv`` (either layout)."""
    return Path(imu_csv).resolve().parent.parent / "state_groundtruth_estimate0" / "data.csv"


def _recorded_report(imu_csv, advice: str):
    """``(report.json path, its mapping)`` of an IMU csv's output folder; ``(path, None)`` without one."""
    from ..errors import InputError

    report = dataset_root(imu_csv) / "report.json"
    try:
        text = report.read_text(encoding="utf-8")
    except FileNotFoundError:
        return report, None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read ({getattr(exc, 'strerror', None) or exc}); {advice}", path=report) from None
    try:
        data = json.loads(text)
    except ValueError as exc:
        raise InputError(f"not valid JSON ({exc.msg}); {advice}", path=report, line=exc.lineno) from None
    return report, data if isinstance(data, dict) else None


def recorded_sampling(imu_csv) -> str:
    """The sampling mode recorded with an IMU csv: ``"mean"`` or ``"point"``.

    Read from ``report.json`` (key ``imu.sampling``) in the csv's output folder
    (:func:`dataset_root`); ``"point"`` when there is none or it does not say.

    Raises
    ------
    InputError
        ``report.json`` exists but cannot be read or is not JSON (taking such a folder's mean
        samples for point values costs the ellipse 0.24 m in 10 s, in silence).
    """
    _, data = _recorded_report(imu_csv, "it records how the samples were taken: repair it, or give "
                                        "--sampling point|mean")
    sampling = data.get("imu", {}).get("sampling") if data is not None else None
    return "mean" if sampling == "mean" else "point"


def recorded_timing(imu_csv) -> tuple:
    """The IMU clock recorded with an IMU csv: ``(timing model mapping, report.json path)``.

    The mapping is ``report.json``'s ``timing.model`` (keys of
    :class:`splineimu.imu.timing.TimingModel` that were set, e.g. ``time_offset_s``,
    ``clock_drift_ppm``); empty when the folder has no ``report.json`` or it records no timing.

    Raises
    ------
    InputError
        ``report.json`` exists but cannot be read, is not JSON, or its ``timing.model`` is not
        a mapping.
    """
    from ..errors import InputError

    report, data = _recorded_report(imu_csv, "it records the IMU clock's offset and drift: repair it, or give "
                                             "--time-offset and --clock-drift-ppm")
    timing = data.get("timing") if data is not None else None
    if timing is None:
        return {}, report
    model = timing.get("model") if isinstance(timing, dict) else None
    if not isinstance(model, dict):
        raise InputError("`timing.model` is not a mapping; give --time-offset and --clock-drift-ppm", path=report)
    return dict(model), report


def _matrix_block(key: str, T) -> list[str]:
    T = np.asarray(T, dtype=np.float64)
    rows = [", ".join(float_text(v + 0.0) for v in row) for row in T]
    pad = " " * (len("  data: ["))
    data = [f"  data: [{rows[0]},"] + [f"{pad}{r}," for r in rows[1:-1]] + [f"{pad}{rows[-1]}]"]
    return [f"{key}:", f"  cols: {T.shape[1]}", f"  rows: {T.shape[0]}", "  dt: d", *data]


def sensor_yaml_text(sensor_type: str, comment: str, T_BS, values: dict | None = None,
                     header=()) -> str:
    """A EuRoC ``sensor.yaml``: ``%YAML:1.0``, ``sensor_type``, ``comment``, ``T_BS`` and
    ``values`` (``rate_hz`` and the noise keys for an IMU).

    ``T_BS`` (the sensor's pose in the body frame) is written as in EuRoC's files, with
    ``cols``, ``rows`` and ``data``, plus ``dt: d`` so that OpenCV's ``FileStorage`` also reads
    it as a matrix; floats are written so that every reader sees a float (``400.0``).

    Examples
    --------
    >>> print(sensor_yaml_text("imu", "test", np.eye(4), {"rate_hz": 400.0}), end="")
    %YAML:1.0
    sensor_type: imu
    comment: "test"
    T_BS:
      cols: 4
      rows: 4
      dt: d
      data: [1.0, 0.0, 0.0, 0.0,
             0.0, 1.0, 0.0, 0.0,
             0.0, 0.0, 1.0, 0.0,
             0.0, 0.0, 0.0, 1.0]
    rate_hz: 400.0
    """
    lines = ["%YAML:1.0", *("# " + h for h in header), f"sensor_type: {sensor_type}",
             f"comment: {json.dumps(comment)}", *_matrix_block("T_BS", T_BS)]
    for key, value in (values or {}).items():
        lines.append(f"{key}: {float_text(value) if isinstance(value, float) else value}")
    return "\n".join(lines) + "\n"


def body_yaml_text(comment: str) -> str:
    """``mav0/body.yaml``: what the body frame of the dataset is."""
    return f"%YAML:1.0\ncomment: {json.dumps(comment)}\n"
