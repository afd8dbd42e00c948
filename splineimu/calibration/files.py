"""The mapping of ``calibration.yaml``; :mod:`splineimu.io.calibration_yaml` reads and writes the file.

Layout: ``imu0`` holds the estimates under the sensor-model keys (so that
:func:`~splineimu.imu.config.load_imu_config` reads the file as a Kalibr-style chain), ``std``
the predicted standard deviations under the same keys, and ``calibration`` one informational
section per sensor (:meth:`~splineimu.calibration.SensorCalibration.to_dict`, plus ``source``).
"""

from __future__ import annotations

__all__ = ["calibration_yaml_dict", "CALIBRATION_YAML_HEADER"]

#: The comment lines that start ``calibration.yaml``.
CALIBRATION_YAML_HEADER = (
    "# splineimu calibration. `imu0`: estimated intrinsics under the sensor-model keys",
    "# (K = M S, S = I + diag(scale), unit-diagonal M; read with load_imu_config / --imu);",
    "# `std`: predicted standard deviations under the same keys; `calibration`: details.",
)


def calibration_yaml_dict(*calibrations, previous: dict | None = None, source: str = "") -> dict:
    """The mapping written to ``calibration.yaml`` (layout: module docstring).

    Entries of ``previous`` (an earlier file's mapping) for other sensors are kept.
    """
    d = {"imu0": {}, "std": {}, "calibration": {}}
    if previous:
        for key in ("imu0", "std", "calibration"):
            if isinstance(previous.get(key), dict):
                d[key].update(previous[key])
    for cal in calibrations:
        s = cal.sensor
        for key in ("imu0", "std"):
            d[key] = {k: v for k, v in d[key].items() if not k.startswith(s + "_")}
        d["imu0"].update(cal.to_config_dict())
        d["std"].update(cal.std_dict())
        info = {"source": source} if source else {}
        info.update(cal.to_dict())
        info.pop("estimates")
        info.pop("std")
        d["calibration"][s] = info
    return d
