"""Using a calibration: the intrinsics of a sensor model and the correction ``x = K^-1 (y_m - b)``."""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..validation import as_vectors
from .result import SensorCalibration

__all__ = ["intrinsics_from_config", "apply_calibration"]


def intrinsics_from_config(config, sensor: str):
    """The ``(K, b)`` of one sensor of a sensor-model configuration.

    Parameters
    ----------
    config : ImuConfig, path, preset name or mapping (:func:`splineimu.imu.config.load_imu_config`)
    sensor : {"accelerometer", "gyroscope"}

    Returns
    -------
    K : (3, 3) ``M S`` (identity where the configuration sets neither)
    b : (3,) the fixed turn-on bias ``<sensor>_bias`` (zeros when absent; a random
        ``<sensor>_bias_sigma`` draw is not in the configuration)
    """
    from ..imu.config import load_imu_config

    cfg = load_imu_config(config)
    if sensor not in ("accelerometer", "gyroscope"):
        raise ConfigError(f"sensor must be 'accelerometer' or 'gyroscope', got {sensor!r}")
    p = cfg.sensor(sensor)
    S = np.diag(1.0 + (p["scale"] if p["scale"] is not None else np.zeros(3)))
    M = p["misalignment"] if p["misalignment"] is not None else np.eye(3)
    b = np.array(p["bias"], dtype=np.float64) if p["bias"] is not None else np.zeros(3)
    return M @ S, b



def _intrinsics(cal, sensor):
    if isinstance(cal, SensorCalibration):
        if cal.sensor != sensor:
            return None
        return cal.K, cal.bias, None
    K, b = intrinsics_from_config(cal, sensor)
    G = None
    if sensor == "gyroscope":
        from ..imu.config import load_imu_config

        G = load_imu_config(cal).gyroscope_g_sensitivity
    return K, b, G


def apply_calibration(calibration, gyro=None, accel=None):
    """Correct measurements with a calibration: ``x = K^-1 (y_m - b)`` per sensor.

    Parameters
    ----------
    calibration : SensorCalibration, sequence of them, or anything
        :func:`~splineimu.imu.config.load_imu_config` reads (e.g. ``CAL/calibration.yaml``).
        A sensor without intrinsics in it is returned unchanged (``K = I``, ``b = 0``).
    gyro, accel : (N, 3) array_like, optional

    Returns
    -------
    (gyro, accel) : corrected arrays (None where not given)

    Notes
    -----
    With a configuration that has ``gyroscope_g_sensitivity`` ``G`` and with ``accel``
    given, the gyro is corrected as ``K_g^-1 (w_m - b_g - G f)`` with ``f`` the corrected
    specific force.

    Examples
    --------
    >>> cfg = {"accelerometer_scale": [0.01, 0, 0], "accelerometer_bias": [0.1, 0, 0]}
    >>> _, f = apply_calibration(cfg, accel=[[1.11, 0, 9.81]])
    >>> f.round(12).tolist()
    [[1.0, 0.0, 9.81]]
    """
    cals = list(calibration) if isinstance(calibration, (list, tuple)) else [calibration]
    out = {}
    for sensor, y in (("accelerometer", accel), ("gyroscope", gyro)):
        if y is None:
            out[sensor] = None
            continue
        y = as_vectors(y, "gyro" if sensor == "gyroscope" else "accel")
        K, b, G = np.eye(3), np.zeros(3), None
        for c in cals:
            got = _intrinsics(c, sensor)
            if got is not None:
                K, b, G = got
        z = y - b
        if G is not None and out.get("accelerometer") is not None:
            z = z - out["accelerometer"] @ G.T
        out[sensor] = np.linalg.solve(K, z.T).T
    return out["gyroscope"], out["accelerometer"]
