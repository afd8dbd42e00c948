"""The keys of an IMU configuration and the checks of their values (see :mod:`splineimu.imu.config`).

Values come from yaml files or mappings: a "vector" is one number or three, a matrix a 3x3
nested list (or, for a misalignment, Kalibr's lower-triangle forms). Every error is a
:class:`~splineimu.errors.ConfigError` whose path is ``source`` (the file or preset the
values came from) and whose message names the key.
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import ConfigError
from ..validation import finite_float

SENSORS = ("gyroscope", "accelerometer")

#: Kalibr noise keys, in the order they are written.
KALIBR_KEYS = (
    "gyroscope_noise_density", "gyroscope_random_walk",
    "accelerometer_noise_density", "accelerometer_random_walk",
)

#: Keys of other tools' IMU files that are read and ignored.
IGNORED_KEYS = frozenset({
    "rostopic", "time_offset", "model", "T_i_b", "T_BS", "Tw", "Tg", "Ta", "R_IMUtoGYRO",
    "R_IMUtoACC", "sensor_type", "comment", "accelerometers", "gyroscopes", "allan",
})

#: Per-sensor optional vector keys: suffix -> constraint on the values.
VECTOR_SUFFIXES = {
    "bias": None,
    "bias_sigma": "nonneg",
    "scale": "gt-1",
    "bias_instability": "nonneg",
    "bias_correlation_time": "pos",
    "bias_temperature_coefficient": None,
    "scale_temperature_coefficient": None,
    "quantization": "pos",
    "saturation": "pos",
}


def field_names() -> list[str]:
    """Every key of the configuration, in the order they are written."""
    names = list(KALIBR_KEYS) + ["update_rate"]
    for s in SENSORS:
        names += [f"{s}_{suffix}" for suffix in VECTOR_SUFFIXES]
        names.append(f"{s}_misalignment")
    names.append("gyroscope_g_sensitivity")
    names += ["temperature_profile", "temperature_reference"]
    return names


def error(message: str, source: str, key: str | None = None) -> ConfigError:
    """A :class:`ConfigError` about ``key`` of the configuration read from ``source``."""
    return ConfigError(message, path=source or None, option=key)


def is_number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


def finite_number(v, key: str, source: str) -> float:
    """A finite float from a number (numeric text is refused: a yaml string is a mistake here)."""
    if not is_number(v):
        raise error(f"`{key}` must be a number, got {v!r}", source, key)
    return finite_float(v, key, where=source or None)


def _check_constraint(arr, key, constraint, source):
    got = repr(np.asarray(arr).tolist())
    if constraint == "nonneg" and np.any(arr < 0):
        raise error(f"`{key}` must not be negative, got {got}", source, key)
    if constraint == "pos" and np.any(arr <= 0):
        raise error(f"`{key}` must be positive, got {got}", source, key)
    if constraint == "gt-1" and np.any(arr <= -1):
        raise error(f"`{key}` (scale-factor error, S = 1 + s) must be > -1, got {got}", source, key)


def vector(v, key: str, source: str, constraint: str | None = None) -> np.ndarray:
    """A number or a list of three numbers -> (3,) float64, with ``constraint``
    (``"nonneg"``, ``"pos"``, ``"gt-1"`` or None) on every value."""
    if is_number(v):
        arr = np.full(3, finite_number(v, key, source))
    elif isinstance(v, (list, tuple, np.ndarray)):
        items = list(np.asarray(v, dtype=object).ravel()) if isinstance(v, np.ndarray) else list(v)
        if len(items) != 3 or (isinstance(v, np.ndarray) and v.ndim != 1):
            raise error(f"`{key}` must be a number or a list of 3 numbers [x, y, z], "
                        f"got {len(items)} values: {v!r}", source, key)
        arr = np.array([finite_number(x, key, source) for x in items])
    else:
        raise error(f"`{key}` must be a number or a list of 3 numbers [x, y, z], got {v!r}", source, key)
    _check_constraint(arr, key, constraint, source)
    return arr


def matrix(v, key: str, source: str, allow_kalibr: bool = False) -> np.ndarray:
    """A 3x3 nested list (or an OpenCV matrix node; for a misalignment also Kalibr's
    lower-triangle forms) -> (3, 3) float64."""
    if isinstance(v, dict) and {"rows", "cols", "data"} <= set(v):  # OpenCV matrix node
        v = np.asarray(v["data"], dtype=object).reshape(int(v["rows"]), int(v["cols"])).tolist()
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if not isinstance(v, (list, tuple)):
        raise error(f"`{key}` must be a 3x3 matrix (list of 3 rows of 3 numbers), got {v!r}", source, key)
    if allow_kalibr and all(is_number(x) for x in v) and len(v) in (3, 6):
        vals = [finite_number(x, key, source) for x in v]
        M = np.eye(3)
        if len(v) == 3:
            M[1, 0], M[2, 0], M[2, 1] = vals
        else:
            M[0, 0], M[1, 0], M[1, 1], M[2, 0], M[2, 1], M[2, 2] = vals
        return M
    shape_ok = len(v) == 3 and all(isinstance(r, (list, tuple)) and len(r) == 3 for r in v)
    if not shape_ok:
        if all(isinstance(r, (list, tuple)) for r in v):
            got = np.asarray(v, dtype=object).shape
        else:
            got = f"{len(v)} values"
        extra = (" or Kalibr's lower triangle as 6 numbers [m11, m21, m22, m31, m32, m33] or 3 numbers "
                 "[m21, m31, m32]") if allow_kalibr else ""
        raise error(f"`{key}` must be a 3x3 matrix{extra}, got shape {got}", source, key)
    return np.array([[finite_number(x, key, source) for x in row] for row in v])


def compact(arr) -> float | list:
    """Vector -> a number if its three values are equal, else a list."""
    a = np.asarray(arr, dtype=np.float64)
    if a.ndim == 1 and np.all(a == a[0]):
        return float(a[0])
    return a.tolist()


def unwrap_chain(d: dict, source: str) -> dict:
    """``{imu0: {...}, ...}`` (Kalibr / OpenVINS chain) -> the lowest-numbered imu's mapping."""
    chain = sorted((k for k in d if isinstance(k, str) and re.fullmatch(r"imu\d+", k)),
                   key=lambda k: int(k[3:]))
    if not chain:
        return d
    others = [k for k in d if k not in chain]
    noise_keys_at_top = [k for k in others if isinstance(k, str) and k.split("_")[0] in SENSORS]
    if noise_keys_at_top:
        raise error(f"both a chain entry `{chain[0]}` and top-level IMU keys "
                    f"({', '.join(noise_keys_at_top)}): use one or the other", source)
    inner = d[chain[0]]
    if not isinstance(inner, dict):
        raise error(f"`{chain[0]}` must be a mapping of IMU parameters", source, chain[0])
    return inner
