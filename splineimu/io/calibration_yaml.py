"""``calibration.yaml``: the one reader and writer of calibration files (through :mod:`splineimu.io.yaml`).

The mapping itself is :func:`splineimu.calibration.files.calibration_yaml_dict`.

Layout: ``imu0`` holds the estimates under the sensor-model keys (so that
:func:`~splineimu.imu.config.load_imu_config` reads the file as a Kalibr-style chain), ``std``
the predicted standard deviations under the same keys, and ``calibration`` one informational
section per sensor (:meth:`~splineimu.calibration.SensorCalibration.to_dict`, plus ``source``).
"""

from __future__ import annotations

from pathlib import Path

from ..calibration.files import CALIBRATION_YAML_HEADER, calibration_yaml_dict
from ..errors import ConfigError, OutputExistsError
from ..imu.config import ImuConfig
from .yaml import read_yaml, write_yaml

__all__ = ["read_calibration_yaml", "write_calibration_yaml", "check_calibration_target"]


def read_calibration_yaml(path):
    """Read ``calibration.yaml`` (layout: module docstring).

    Returns
    -------
    config : ImuConfig
        The estimates (as :func:`~splineimu.imu.config.load_imu_config` reads them).
    std : dict
        Predicted standard deviations under the same keys.
    raw : dict
        The whole mapping (with the ``calibration`` details).

    Raises
    ------
    ConfigError
        Missing or unreadable file, yaml error, no ``imu0`` section, invalid keys.
    """
    path = Path(path)
    doc = read_yaml(path, "calibration file")
    raw = doc.data
    if not isinstance(raw, dict) or not isinstance(raw.get("imu0"), dict):
        raise ConfigError("not a splineimu calibration file (no `imu0` section)", path=path)
    cfg = ImuConfig.from_dict(raw["imu0"], source=str(path), base_dir=path.parent)
    return cfg, dict(raw.get("std") or {}), raw


def check_calibration_target(path, sensors, force: bool = False) -> dict | None:
    """The mapping of an existing ``calibration.yaml`` that may take ``sensors``, or ``None``.

    Raises
    ------
    OutputExistsError
        Without ``force``: ``path`` is not a calibration file, or already holds one of ``sensors``.
    """
    path = Path(path)
    if not path.exists():
        return None
    if path.is_dir():
        raise OutputExistsError(f"{path} is a folder, not a calibration file")
    try:
        previous = read_yaml(path, "calibration file").data
    except ConfigError:
        previous = None
    if not isinstance(previous, dict) or not isinstance(previous.get("imu0", {}), dict):
        if not force:
            raise OutputExistsError(f"{path} exists and is not a calibration file; use --force to replace it")
        return None
    clash = sorted(set((previous.get("calibration") or {}).keys()) & set(sensors))
    if clash and not force:
        raise OutputExistsError(f"{path} already holds a {' and '.join(clash)} calibration; "
                                "use --force to replace it")
    return previous


def write_calibration_yaml(path, *calibrations, source: str = "", force: bool = False):
    """Write (or update) ``calibration.yaml`` atomically (layout: module docstring).

    An existing file's entries for *other* sensors are kept; replacing a sensor that is
    already in it needs ``force``. ``source`` (one line, e.g. the input file and method) is
    stored with each sensor written and listed in the file's header comment.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    OutputExistsError
        The file already holds one of these sensors (or is not a calibration file) and
        ``force`` is False.
    """
    previous = check_calibration_target(path, [c.sensor for c in calibrations], force)
    d = calibration_yaml_dict(*calibrations, previous=previous, source=source)
    lines = list(CALIBRATION_YAML_HEADER)
    for sensor, info in d["calibration"].items():
        if isinstance(info, dict) and info.get("source"):
            lines.append(f"# {sensor}: {' '.join(str(info['source']).split())}")
    return write_yaml(path, d, lines)
