"""IMU sensor-model configuration: Kalibr ``imu.yaml`` keys plus documented extras.

One :class:`ImuConfig` holds every parameter of the sensor model of
:mod:`splineimu.imu.noise`. It reads and writes flat yaml files with the keys below (the same
names both ways), Kalibr / OpenVINS chain files (``imu0: {...}``), the EuRoC ``sensor.yaml``
and the ``allan.yaml`` written by ``splineimu allan``; packaged presets of real IMUs can be
named wherever a file is expected (:func:`load_imu_config`).

Keys
----
A "vector" is a number (the same for the three axes) or a list of three numbers ``[x, y, z]``
in the sensor frame. Only the Kalibr keys are needed; everything else is applied only when
the file names it, and is written back only when set.

Kalibr keys (continuous-time densities; white noise and bias random walk are on whenever
they are non-zero; an absent density is zero)

=============================== =============================== =================================
key                             unit                            meaning
=============================== =============================== =================================
``gyroscope_noise_density``     rad/s/sqrt(Hz), vector >= 0     white noise; per sample
                                                                ``sigma / sqrt(dt)``
``gyroscope_random_walk``       rad/s^2/sqrt(Hz), vector >= 0   bias random walk; per step
                                                                ``sigma_b * sqrt(dt)``
``accelerometer_noise_density`` m/s^2/sqrt(Hz), vector >= 0     as above
``accelerometer_random_walk``   m/s^3/sqrt(Hz), vector >= 0     as above
``update_rate``                 Hz, > 0                         nominal sample rate (``rate_hz``
                                                                of EuRoC's sensor.yaml is read
                                                                as this)
=============================== =============================== =================================

Extra keys (``<s>`` is ``gyroscope`` or ``accelerometer``; ``<u>`` is rad/s or m/s^2)

====================================== ==================== ==========================================
key                                    unit                 meaning
====================================== ==================== ==========================================
``<s>_bias``                           <u>, vector          turn-on bias, fixed
``<s>_bias_sigma``                     <u>, vector >= 0     turn-on bias drawn from N(0, sigma^2) per
                                                            run (added to ``<s>_bias`` if both)
``<s>_scale``                          1, vector > -1       scale-factor errors ``s``:
                                                            ``S = I + diag(s)`` (1e-3 = 1000 ppm)
``<s>_misalignment``                   1, 3x3 matrix        ``M`` (applied after S). Also accepted:
                                                            6 numbers = Kalibr's lower triangle
                                                            ``[m11, m21, m22, m31, m32, m33]``, or 3
                                                            numbers = its off-diagonal part
                                                            ``[m21, m31, m32]`` with unit diagonal.
                                                            Written back as the 3x3 matrix.
``gyroscope_g_sensitivity``            rad/s per m/s^2,     ``G``: adds ``G f`` (f = true specific
                                       3x3 matrix           force) to the gyro
``<s>_bias_instability``               <u>, vector >= 0     first-order Gauss-Markov bias: its
                                                            stationary standard deviation sigma.
                                                            (Its Allan deviation peaks at
                                                            0.617 sigma near tau = 1.89 T; to mimic
                                                            an Allan-plot bias instability B,
                                                            floor 0.664 B, use sigma ~= 1.08 B.)
``<s>_bias_correlation_time``          s, vector > 0        its correlation time T (required with
                                                            ``<s>_bias_instability``)
``temperature_profile``                degC                 a number (constant), ``{start: degC,
                                                            rate: degC/s}`` (linear ramp from the
                                                            first sample) or ``{file: PATH}``: two
                                                            columns ``time [s] since the first
                                                            sample, temperature [degC]``, comma or
                                                            space separated, ``#`` comments,
                                                            linearly interpolated (held constant
                                                            outside); a relative PATH is relative
                                                            to the yaml file (written back as an
                                                            absolute path)
``temperature_reference``              degC                 temperature of zero temperature error
                                                            (default 25)
``<s>_bias_temperature_coefficient``   <u>/K, vector        bias ``+= c (T - T_ref)``
``<s>_scale_temperature_coefficient``  1/K, vector          ``s += c (T - T_ref)``
``<s>_quantization``                   <u>, vector > 0      LSB: output ``= LSB * round(x / LSB)``
``<s>_saturation``                     <u>, vector > 0      range: output clipped to ``[-r, r]``
====================================== ==================== ==========================================

Read but ignored: the non-noise keys of Kalibr, OpenVINS and EuRoC files (``rostopic``,
``time_offset``, ``model``, ``T_i_b``, ``T_BS``, ``Tw``, ``Tg``, ``Ta``, ``R_IMUtoGYRO``,
``R_IMUtoACC``, ``sensor_type``, ``comment``, ``accelerometers``, ``gyroscopes``; note that
OpenVINS's intrinsic matrices are *not* applied: use the keys above), the companions
``<key>_avg`` and ``<key>_ci95`` of any key, and the informational ``allan`` section that
``splineimu allan`` writes. Any other key is an error with a did-you-mean.

Examples
--------
>>> cfg = ImuConfig.from_dict({"gyroscope_noise_density": 1.6968e-4, "update_rate": 200})
>>> cfg.gyroscope_noise_density.tolist(), cfg.update_rate
([0.00016968, 0.00016968, 0.00016968], 200.0)
>>> sorted(cfg.to_dict())
['accelerometer_noise_density', 'accelerometer_random_walk', 'gyroscope_noise_density', \
'gyroscope_random_walk', 'update_rate']
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import ConfigError

__all__ = ["ImuConfig", "load_imu_config", "load_preset", "list_presets", "TemperatureProfile"]

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

# per-sensor optional keys: suffix -> (kind, constraint)
_VECTOR_SUFFIXES = {
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

_UNITS = {
    "gyroscope": "rad/s", "accelerometer": "m/s^2",
}


def _field_names():
    names = list(KALIBR_KEYS) + ["update_rate"]
    for s in SENSORS:
        names += [f"{s}_{suffix}" for suffix in _VECTOR_SUFFIXES]
        names.append(f"{s}_misalignment")
    names.append("gyroscope_g_sensitivity")
    names += ["temperature_profile", "temperature_reference"]
    return names


# ------------------------------------------------------------------------------ temperature


@dataclass(frozen=True)
class TemperatureProfile:
    """Sensor temperature over time.

    Exactly one form is set: ``constant_c``; ``start_c`` + ``rate_c_per_s`` (linear ramp
    from the first sample); or a table ``table_t_s`` / ``table_c`` (linear interpolation,
    held constant outside) read from ``file``.
    """

    constant_c: float | None = None
    start_c: float | None = None
    rate_c_per_s: float | None = None
    file: str | None = None
    table_t_s: np.ndarray | None = field(default=None, compare=False, repr=False)
    table_c: np.ndarray | None = field(default=None, compare=False, repr=False)

    def __call__(self, t_s, t_first_s: float | None = None) -> np.ndarray:
        """Temperature [degC] at ``t_s``; the profile's time is seconds since ``t_first_s``
        (the record's first sample; default ``t_s[0]``)."""
        t = np.asarray(t_s, dtype=np.float64)
        if self.constant_c is not None:
            return np.full(t.shape, self.constant_c)
        t0 = t_first_s if t_first_s is not None else (t.flat[0] if t.size else 0.0)
        if self.start_c is not None:
            return self.start_c + self.rate_c_per_s * (t - t0)
        return np.interp(t - t0, self.table_t_s, self.table_c)

    def to_yaml_value(self):
        if self.constant_c is not None:
            return float(self.constant_c)
        if self.start_c is not None:
            return {"start": float(self.start_c), "rate": float(self.rate_c_per_s)}
        return {"file": self.file}

    @classmethod
    def parse(cls, value, base_dir: Path | None, where: str) -> TemperatureProfile:
        key = "temperature_profile"
        if _is_number(value):
            return cls(constant_c=_finite(value, key, where))
        if isinstance(value, dict):
            keys = set(value)
            if keys == {"start", "rate"}:
                return cls(start_c=_finite(value["start"], key + ".start", where),
                           rate_c_per_s=_finite(value["rate"], key + ".rate", where))
            if keys == {"file"}:
                return cls._from_file(value["file"], base_dir, where)
        raise ConfigError(
            f"{where}`{key}` must be a number [degC], {{start: degC, rate: degC/s}} or {{file: PATH}}, "
            f"got {value!r}")

    @classmethod
    def _from_file(cls, name, base_dir, where):
        if not isinstance(name, str) or not name:
            raise ConfigError(f"{where}`temperature_profile.file` must be a path, got {name!r}")
        path = Path(name).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.is_file():
            raise ConfigError(f"{where}temperature profile file not found: {path}")
        from ..errors import InputError

        rows = []
        with open(path, encoding="utf-8") as fh:
            for lineno, line in enumerate(fh, 1):
                s = line.split("#", 1)[0].strip()
                if not s:
                    continue
                parts = [p for p in re.split(r"[,\s]+", s) if p]
                try:
                    if len(parts) != 2:
                        raise ValueError
                    rows.append((float(parts[0]), float(parts[1])))
                except ValueError:
                    raise InputError(f"expected two numbers 'time_s, temperature_c', got {line.strip()!r}",
                                     path, lineno) from None
        if not rows:
            raise InputError("no temperature samples", path)
        tab = np.asarray(rows)
        if not np.all(np.isfinite(tab)) or np.any(np.diff(tab[:, 0]) <= 0):
            raise InputError("times must be finite and strictly increasing", path)
        # keep the resolved path, so that a config written elsewhere (OUT/imu.yaml) still finds it
        return cls(file=str(path.resolve()), table_t_s=tab[:, 0].copy(), table_c=tab[:, 1].copy())


# ------------------------------------------------------------------------------ validation helpers


def _is_number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


def _finite(v, key, where) -> float:
    if not _is_number(v):
        raise ConfigError(f"{where}`{key}` must be a number, got {v!r}")
    f = float(v)
    if not math.isfinite(f):
        raise ConfigError(f"{where}`{key}` must be finite, got {v!r}")
    return f


def _check_constraint(arr, key, constraint, where):
    if constraint == "nonneg" and np.any(arr < 0):
        raise ConfigError(f"{where}`{key}` must not be negative, got {_fmt(arr)}")
    if constraint == "pos" and np.any(arr <= 0):
        raise ConfigError(f"{where}`{key}` must be positive, got {_fmt(arr)}")
    if constraint == "gt-1" and np.any(arr <= -1):
        raise ConfigError(f"{where}`{key}` (scale-factor error, S = 1 + s) must be > -1, got {_fmt(arr)}")


def _fmt(arr):
    a = np.asarray(arr)
    return repr(a.tolist())


def _vector(v, key, where, constraint=None) -> np.ndarray:
    """A number or a list of three numbers -> (3,) float64."""
    if _is_number(v):
        arr = np.full(3, _finite(v, key, where))
    elif isinstance(v, (list, tuple, np.ndarray)):
        items = list(np.asarray(v, dtype=object).ravel()) if isinstance(v, np.ndarray) else list(v)
        if len(items) != 3 or (isinstance(v, np.ndarray) and v.ndim != 1):
            raise ConfigError(f"{where}`{key}` must be a number or a list of 3 numbers [x, y, z], "
                              f"got {len(items)} values: {v!r}")
        arr = np.array([_finite(x, key, where) for x in items])
    else:
        raise ConfigError(f"{where}`{key}` must be a number or a list of 3 numbers [x, y, z], got {v!r}")
    _check_constraint(arr, key, constraint, where)
    return arr


def _matrix(v, key, where, allow_kalibr=False) -> np.ndarray:
    """A 3x3 nested list (or, for misalignment, the Kalibr lower-triangle forms) -> (3, 3)."""
    if isinstance(v, dict) and {"rows", "cols", "data"} <= set(v):  # OpenCV matrix node
        v = np.asarray(v["data"], dtype=object).reshape(int(v["rows"]), int(v["cols"])).tolist()
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if not isinstance(v, (list, tuple)):
        raise ConfigError(f"{where}`{key}` must be a 3x3 matrix (list of 3 rows of 3 numbers), got {v!r}")
    if allow_kalibr and all(_is_number(x) for x in v) and len(v) in (3, 6):
        vals = [_finite(x, key, where) for x in v]
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
        raise ConfigError(f"{where}`{key}` must be a 3x3 matrix{extra}, got shape {got}")
    return np.array([[_finite(x, key, where) for x in row] for row in v])


def _compact(arr) -> float | list:
    """Vector -> a number if its three values are equal, else a list."""
    a = np.asarray(arr, dtype=np.float64)
    if a.ndim == 1 and np.all(a == a[0]):
        return float(a[0])
    return a.tolist()


# ------------------------------------------------------------------------------ the config


def _vec_field():
    return field(default=None)


@dataclass(repr=False)
class ImuConfig:
    """Parameters of the IMU sensor model (see the module docstring for every key and unit).

    Vectors are ``(3,)`` float64 arrays, matrices ``(3, 3)``; ``None`` means "not modelled".
    The four Kalibr densities are always arrays (zeros when absent).

    Build with :meth:`from_dict`, :meth:`from_yaml`, :func:`load_preset` or
    :func:`load_imu_config`; write with :meth:`to_dict` / :meth:`to_yaml` (same key names).
    ``dataclasses.replace`` gives modified copies (e.g. another ``update_rate``).
    """

    gyroscope_noise_density: np.ndarray = field(default_factory=lambda: np.zeros(3))
    gyroscope_random_walk: np.ndarray = field(default_factory=lambda: np.zeros(3))
    accelerometer_noise_density: np.ndarray = field(default_factory=lambda: np.zeros(3))
    accelerometer_random_walk: np.ndarray = field(default_factory=lambda: np.zeros(3))
    update_rate: float | None = None

    gyroscope_bias: np.ndarray | None = _vec_field()
    gyroscope_bias_sigma: np.ndarray | None = _vec_field()
    gyroscope_scale: np.ndarray | None = _vec_field()
    gyroscope_bias_instability: np.ndarray | None = _vec_field()
    gyroscope_bias_correlation_time: np.ndarray | None = _vec_field()
    gyroscope_bias_temperature_coefficient: np.ndarray | None = _vec_field()
    gyroscope_scale_temperature_coefficient: np.ndarray | None = _vec_field()
    gyroscope_quantization: np.ndarray | None = _vec_field()
    gyroscope_saturation: np.ndarray | None = _vec_field()
    gyroscope_misalignment: np.ndarray | None = _vec_field()
    gyroscope_g_sensitivity: np.ndarray | None = _vec_field()

    accelerometer_bias: np.ndarray | None = _vec_field()
    accelerometer_bias_sigma: np.ndarray | None = _vec_field()
    accelerometer_scale: np.ndarray | None = _vec_field()
    accelerometer_bias_instability: np.ndarray | None = _vec_field()
    accelerometer_bias_correlation_time: np.ndarray | None = _vec_field()
    accelerometer_bias_temperature_coefficient: np.ndarray | None = _vec_field()
    accelerometer_scale_temperature_coefficient: np.ndarray | None = _vec_field()
    accelerometer_quantization: np.ndarray | None = _vec_field()
    accelerometer_saturation: np.ndarray | None = _vec_field()
    accelerometer_misalignment: np.ndarray | None = _vec_field()

    temperature_profile: TemperatureProfile | None = None
    temperature_reference: float | None = None

    source: str = field(default="", compare=False)
    ignored_keys: tuple = field(default=(), compare=False)

    # ---------------------------------------------------------------- construction

    @classmethod
    def from_dict(cls, d: dict, source: str = "", base_dir=None) -> ImuConfig:
        """Validate a mapping of keys (flat, or a Kalibr chain ``{imu0: {...}}``).

        Parameters
        ----------
        d : dict
            Keys of the module docstring.
        source : str
            Where it came from, used in error messages (a path, ``"preset adis16448"``...).
        base_dir : path-like, optional
            Directory that a relative ``temperature_profile.file`` is relative to.

        Raises
        ------
        ConfigError
            Unknown key (with a did-you-mean), non-numeric or non-finite value, negative
            density, wrong vector length or matrix shape, missing correlation time.
        """
        where = f"{source}: " if source else ""
        if not isinstance(d, dict):
            raise ConfigError(f"{where}expected a mapping of IMU parameters, got {type(d).__name__}")
        d = _unwrap_chain(d, where)
        names = set(_field_names())
        known = names | {"rate_hz"}
        kwargs: dict = {}
        ignored = []
        unknown = []
        for key, value in d.items():
            if not isinstance(key, str):
                unknown.append(str(key))
                continue
            if key in IGNORED_KEYS:
                ignored.append(key)
                continue
            base = re.sub(r"_(avg|ci95)$", "", key)
            if base != key and base in known:
                ignored.append(key)
                continue
            if key not in known:
                unknown.append(key)
                continue
            kwargs[key] = value
        if unknown:
            msgs = []
            for key in unknown:
                close = difflib.get_close_matches(key, sorted(known), n=1, cutoff=0.6)
                msgs.append(f"`{key}`" + (f" (did you mean `{close[0]}`?)" if close else ""))
            raise ConfigError(f"{where}unknown IMU key{'s' if len(msgs) > 1 else ''} " + ", ".join(msgs)
                              + "; see `splineimu.imu.config` for the list")
        if "rate_hz" in kwargs:
            if "update_rate" in kwargs:
                raise ConfigError(f"{where}give either `update_rate` or `rate_hz`, not both")
            kwargs["update_rate"] = kwargs.pop("rate_hz")

        vals: dict = {}
        for key in KALIBR_KEYS:
            if key in kwargs:
                vals[key] = _vector(kwargs[key], key, where, "nonneg")
        if kwargs.get("update_rate") is not None:
            rate = _finite(kwargs["update_rate"], "update_rate", where)
            if rate <= 0:
                raise ConfigError(f"{where}`update_rate` must be positive [Hz], "
                                  f"got {kwargs['update_rate']!r}")
            vals["update_rate"] = rate
        for s in SENSORS:
            for suffix, constraint in _VECTOR_SUFFIXES.items():
                key = f"{s}_{suffix}"
                if kwargs.get(key) is not None:
                    vals[key] = _vector(kwargs[key], key, where, constraint)
            key = f"{s}_misalignment"
            if kwargs.get(key) is not None:
                vals[key] = _matrix(kwargs[key], key, where, allow_kalibr=True)
            if (f"{s}_bias_instability" in vals) != (f"{s}_bias_correlation_time" in vals):
                raise ConfigError(f"{where}`{s}_bias_instability` and `{s}_bias_correlation_time` "
                                  "must be given together (first-order Gauss-Markov bias)")
        if kwargs.get("gyroscope_g_sensitivity") is not None:
            vals["gyroscope_g_sensitivity"] = _matrix(kwargs["gyroscope_g_sensitivity"],
                                                      "gyroscope_g_sensitivity", where)
        if kwargs.get("temperature_profile") is not None:
            bd = Path(base_dir) if base_dir is not None else None
            vals["temperature_profile"] = TemperatureProfile.parse(kwargs["temperature_profile"], bd, where)
        if kwargs.get("temperature_reference") is not None:
            vals["temperature_reference"] = _finite(kwargs["temperature_reference"],
                                                    "temperature_reference", where)
        return cls(**vals, source=source, ignored_keys=tuple(ignored))

    @classmethod
    def from_yaml(cls, path) -> ImuConfig:
        """Read a yaml file (flat keys, Kalibr/OpenVINS chain, EuRoC sensor.yaml, allan.yaml).

        A leading OpenCV ``%YAML:1.0`` line and ``!!opencv-matrix`` tags are accepted.

        Raises
        ------
        ConfigError
            File missing or unreadable, yaml syntax error (with its line), invalid keys.
        """
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise ConfigError(f"IMU configuration file not found: {path}") from None
        except OSError as exc:
            raise ConfigError(f"cannot read IMU configuration {path}: {exc}") from None
        d = _parse_yaml(text, str(path))
        return cls.from_dict(d, source=str(path), base_dir=path.parent)

    # ---------------------------------------------------------------- output

    def to_dict(self) -> dict:
        """Plain mapping with the documented keys (numbers, lists): what :meth:`to_yaml` writes.

        Vectors with three equal values are written as one number, so Kalibr and OpenVINS
        can read the Kalibr keys.
        """
        out: dict = {}
        for key in KALIBR_KEYS:
            out[key] = _compact(getattr(self, key))
        if self.update_rate is not None:
            out["update_rate"] = float(self.update_rate)
        for name in _field_names():
            if name in out or name in ("update_rate",):
                continue
            v = getattr(self, name)
            if v is None:
                continue
            if name == "temperature_profile":
                out[name] = v.to_yaml_value()
            elif name == "temperature_reference":
                out[name] = float(v)
            elif np.ndim(v) == 2:
                out[name] = np.asarray(v, dtype=np.float64).tolist()
            else:
                out[name] = _compact(v)
        return out

    def to_yaml(self, path, header: str | None = None) -> Path:
        """Write :meth:`to_dict` as yaml, atomically (temporary file + rename).

        Parameters
        ----------
        path : path-like
        header : str, optional
            Comment lines to put first (``#`` is added).

        Returns
        -------
        Path of the written file.
        """
        lines = [
            "# IMU sensor model (splineimu). Continuous-time Kalibr units:",
            "#   *_noise_density: gyro rad/s/sqrt(Hz), accel m/s^2/sqrt(Hz)",
            "#   *_random_walk:   gyro rad/s^2/sqrt(Hz), accel m/s^3/sqrt(Hz)",
            "#   update_rate: Hz. Other keys: see `python -m pydoc splineimu.imu.config`.",
        ]
        if header:
            lines = ["# " + h if h else "#" for h in header.splitlines()] + lines
        return write_yaml_atomic(path, self.to_dict(), lines)

    # ---------------------------------------------------------------- queries

    def sensor(self, name: str) -> dict:
        """The parameters of one sensor (``"gyroscope"`` or ``"accelerometer"``) by suffix."""
        if name not in SENSORS:
            raise ConfigError(f"sensor must be one of {SENSORS}, got {name!r}")
        out = {suffix: getattr(self, f"{name}_{suffix}")
               for suffix in ("noise_density", "random_walk", *_VECTOR_SUFFIXES, "misalignment")}
        out["g_sensitivity"] = self.gyroscope_g_sensitivity if name == "gyroscope" else None
        return out

    def __eq__(self, other):
        if not isinstance(other, ImuConfig):
            return NotImplemented
        for f in dataclasses.fields(self):
            if not f.compare:
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
                if a is None or b is None or not np.array_equal(a, b):
                    return False
            elif a != b:
                return False
        return True

    __hash__ = None

    def __repr__(self) -> str:
        items = ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items())
        src = f", source={self.source!r}" if self.source else ""
        return f"ImuConfig({items}{src})"


# ------------------------------------------------------------------------------ yaml helpers


def _parse_yaml(text: str, name: str):
    from ..io.yaml import parse_yaml

    d = parse_yaml(text, name).data
    if not isinstance(d, dict):
        raise ConfigError(f"{name}: expected a mapping of IMU parameters, got {type(d).__name__}")
    return d


def _unwrap_chain(d: dict, where: str) -> dict:
    """``{imu0: {...}, ...}`` (Kalibr / OpenVINS chain) -> the lowest-numbered imu's mapping."""
    chain = sorted((k for k in d if isinstance(k, str) and re.fullmatch(r"imu\d+", k)),
                   key=lambda k: int(k[3:]))
    if not chain:
        return d
    others = [k for k in d if k not in chain]
    noise_keys_at_top = [k for k in others if isinstance(k, str) and k.split("_")[0] in SENSORS]
    if noise_keys_at_top:
        raise ConfigError(f"{where}both a chain entry `{chain[0]}` and top-level IMU keys "
                          f"({', '.join(noise_keys_at_top)}): use one or the other")
    inner = d[chain[0]]
    if not isinstance(inner, dict):
        raise ConfigError(f"{where}`{chain[0]}` must be a mapping of IMU parameters")
    return inner


def write_yaml_atomic(path, data: dict, comment_lines=()) -> Path:
    """Dump ``data`` as block-style yaml (short lists inline) to ``path`` atomically."""
    from ..io.yaml import write_yaml

    return write_yaml(path, data, comment_lines)


# ------------------------------------------------------------------------------ presets


def _preset_dir():
    return resources.files("splineimu").joinpath("presets")


def _norm_preset(name: str) -> str:
    return name.strip().lower().replace("-", "_")


def list_presets() -> list[str]:
    """Names of the packaged IMU presets (``splineimu/presets/*.yaml``).

    Examples
    --------
    >>> "adis16448" in list_presets()
    True
    """
    d = _preset_dir()
    return sorted(p.name[:-5] for p in d.iterdir() if p.name.endswith(".yaml"))


def load_preset(name: str) -> ImuConfig:
    """Load a packaged preset by name (case-insensitive, ``-`` = ``_``).

    Raises
    ------
    ConfigError
        Unknown name (with the list of presets and a did-you-mean).
    """
    names = list_presets()
    key = _norm_preset(str(name))
    if key not in names:
        close = difflib.get_close_matches(key, names, n=1, cutoff=0.5)
        hint = f" (did you mean `{close[0]}`?)" if close else ""
        raise ConfigError(f"no IMU preset named `{name}`{hint}; presets: {', '.join(names)}")
    text = _preset_dir().joinpath(key + ".yaml").read_text(encoding="utf-8")
    return ImuConfig.from_dict(_parse_yaml(text, f"preset {key}"), source=f"preset {key}")


def load_imu_config(spec) -> ImuConfig:
    """An :class:`ImuConfig` from a yaml path, a preset name, a mapping or an ImuConfig.

    An existing file wins over a preset of the same name.

    Examples
    --------
    >>> load_imu_config("adis16448").accelerometer_random_walk.tolist()
    [0.003, 0.003, 0.003]
    """
    if isinstance(spec, ImuConfig):
        return spec
    if isinstance(spec, dict):
        return ImuConfig.from_dict(spec, source="mapping")
    if not isinstance(spec, (str, os.PathLike)):
        raise ConfigError(f"expected an IMU yaml path or preset name, got {type(spec).__name__}")
    path = Path(spec).expanduser()
    if path.is_file():
        return ImuConfig.from_yaml(path)
    s = str(spec)
    if _norm_preset(s) in list_presets():
        return load_preset(s)
    if path.suffix.lower() in (".yaml", ".yml") or os.sep in s or "/" in s:
        raise ConfigError(f"IMU configuration file not found: {spec} (presets: {', '.join(list_presets())})")
    return load_preset(s)  # raises with a did-you-mean over the presets
