"""``calibration.yaml``: the one reader and writer of calibration files (through :mod:`splineimu.io.yaml`).

Layout: ``imu0`` holds the estimates under the sensor-model keys (so that
:func:`~splineimu.imu.config.load_imu_config` reads the file as a Kalibr-style chain), ``std``
the predicted standard deviations under the same keys, and ``calibration`` one informational
section per sensor (:meth:`~splineimu.calibration.SensorCalibration.to_dict`, plus ``source``).
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ConfigError, OutputExistsError

__all__ = ["calibration_yaml_dict", "read_calibration_yaml", "write_calibration_yaml", "check_calibration_target"]

_HEADER = (
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
    from ..imu.config import ImuConfig
    from ..io.yaml import read_yaml

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
    from ..io.yaml import read_yaml

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
    from ..io.yaml import write_yaml

    previous = check_calibration_target(path, [c.sensor for c in calibrations], force)
    d = calibration_yaml_dict(*calibrations, previous=previous, source=source)
    lines = list(_HEADER)
    for sensor, info in d["calibration"].items():
        if isinstance(info, dict) and info.get("source"):
            lines.append(f"# {sensor}: {' '.join(str(info['source']).split())}")
    return write_yaml(path, d, lines)
