"""The :class:`ImuConfig` dataclass: parameters of the IMU sensor model, checked.

Public through :mod:`splineimu.imu.config`, whose docstring lists every key, its unit and meaning.
"""

from __future__ import annotations

import dataclasses
import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..validation import as_rate_hz
from ._config_values import (
    IGNORED_KEYS,
    KALIBR_KEYS,
    SENSORS,
    VECTOR_SUFFIXES,
    compact,
    error,
    field_names,
    finite_number,
    matrix,
    unwrap_chain,
    vector,
)
from .openvins import OPENVINS_KEYS, from_openvins
from .temperature import TemperatureProfile

__all__ = ["ImuConfig"]


def _with_openvins_intrinsics(d: dict, source: str) -> dict:
    """``d`` with OpenVINS's ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` replaced by
    the equivalent misalignment and g-sensitivity keys (:mod:`splineimu.imu.openvins`)."""
    present = [k for k in OPENVINS_KEYS if d.get(k) is not None]
    if not present:
        return d
    values = {k: matrix(d[k], k, source) for k in present}
    if "model" in d:
        values["model"] = d["model"]
    derived = from_openvins(values, source)
    for key in derived:
        sensor = key.split("_")[0]
        clash = [k for k in (key, f"{sensor}_scale") if d.get(k) is not None]
        if clash:
            raise error(f"`{clash[0]}` and OpenVINS's intrinsics ({', '.join(present)}) both describe "
                        f"the {sensor}: give one or the other", source, clash[0])
    return {**{k: v for k, v in d.items() if k not in OPENVINS_KEYS}, **derived}


def _vec_field():
    return field(default=None)


@dataclass(repr=False)
class ImuConfig:
    """Parameters of the IMU sensor model (see :mod:`splineimu.imu.config` for every key and unit).

    Vectors are ``(3,)`` float64 arrays, matrices ``(3, 3)``; ``None`` means "not modelled".
    The four Kalibr densities are always arrays (zeros when absent).

    Build with :meth:`from_dict`, :meth:`from_yaml`, :func:`~splineimu.imu.presets.load_preset`
    or :func:`~splineimu.imu.presets.load_imu_config`; write with :meth:`to_dict` /
    :func:`splineimu.io.imu_yaml.write_imu_config` (same key names).
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
            density, wrong vector length or matrix shape, missing correlation time; no
            parameter at all (an empty mapping: the preset ``ideal`` is the noise-free sensor).
        """
        if not isinstance(d, dict):
            raise error(f"expected a mapping of IMU parameters, got {type(d).__name__}", source)
        d = _with_openvins_intrinsics(unwrap_chain(d, source), source)
        names = set(field_names())
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
            base = re.sub(r"_(avg|ci95|xyz)$", "", key)
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
            raise error(f"unknown IMU key{'s' if len(msgs) > 1 else ''} " + ", ".join(msgs)
                        + "; see `splineimu.imu.config` for the list", source)
        if "rate_hz" in kwargs:
            if "update_rate" in kwargs:
                raise error("give either `update_rate` or `rate_hz`, not both", source, "rate_hz")
            kwargs["update_rate"] = kwargs.pop("rate_hz")

        vals: dict = {}
        for key in KALIBR_KEYS:
            if key in kwargs:
                vals[key] = vector(kwargs[key], key, source, "nonneg")
        if kwargs.get("update_rate") is not None:
            vals["update_rate"] = as_rate_hz(kwargs["update_rate"], "update_rate", where=source or None)
        for s in SENSORS:
            for suffix, constraint in VECTOR_SUFFIXES.items():
                key = f"{s}_{suffix}"
                if kwargs.get(key) is not None:
                    vals[key] = vector(kwargs[key], key, source, constraint)
            key = f"{s}_misalignment"
            if kwargs.get(key) is not None:
                vals[key] = matrix(kwargs[key], key, source, allow_kalibr=True)
            if (f"{s}_bias_instability" in vals) != (f"{s}_bias_correlation_time" in vals):
                raise error(f"`{s}_bias_instability` and `{s}_bias_correlation_time` "
                            "must be given together (first-order Gauss-Markov bias)", source)
        if kwargs.get("gyroscope_g_sensitivity") is not None:
            vals["gyroscope_g_sensitivity"] = matrix(kwargs["gyroscope_g_sensitivity"],
                                                     "gyroscope_g_sensitivity", source)
        if kwargs.get("temperature_profile") is not None:
            bd = Path(base_dir) if base_dir is not None else None
            vals["temperature_profile"] = TemperatureProfile.parse(kwargs["temperature_profile"], bd, source)
        if kwargs.get("temperature_reference") is not None:
            vals["temperature_reference"] = finite_number(kwargs["temperature_reference"],
                                                          "temperature_reference", source)
        if not set(kwargs) - {"update_rate"}:  # `model: {}` would silently be an ideal sensor
            rate = [k for k in d if k in ("update_rate", "rate_hz")]
            what = f"only {', '.join(ignored)}, which {'is' if len(ignored) == 1 else 'are'} ignored" if ignored \
                else "an empty mapping"
            what = f"only {', '.join(rate + ignored)}" if rate else what
            raise error(f"holds no IMU parameters ({what}); for a noise-free sensor give the preset `ideal`", source)
        return cls(**vals, source=source, ignored_keys=tuple(ignored))

    @classmethod
    def from_yaml(cls, path) -> ImuConfig:
        """Read a yaml file (flat keys, Kalibr/OpenVINS chain, EuRoC sensor.yaml, allan.yaml).

        A leading OpenCV ``%YAML:1.0`` line and ``!!opencv-matrix`` tags are accepted.

        Raises
        ------
        ConfigError
            File missing or unreadable, yaml syntax error, invalid keys or values; the
            message starts with the file and the line of the key at fault.
        """
        path = Path(path)
        doc = read_imu_yaml(path)
        try:
            return cls.from_dict(doc.data, source=str(path), base_dir=path.parent)
        except ConfigError as exc:
            if exc.line is not None or not exc.option:
                raise
            inner = unwrap_chain(doc.data, str(path))
            prefix = next((k,) for k, v in doc.data.items() if v is inner) if inner is not doc.data else ()
            line = doc.line(*prefix, *exc.option.split("."))
            raise type(exc)(exc.problem, path=exc.path, line=line, option=exc.option) from None

    # ---------------------------------------------------------------- output

    def to_dict(self) -> dict:
        """Plain mapping with the documented keys (numbers, lists): what
        :func:`~splineimu.io.imu_yaml.write_imu_config` writes.

        Vectors with three equal values are written as one number, so Kalibr and OpenVINS
        can read the Kalibr keys.
        """
        out: dict = {}
        for key in KALIBR_KEYS:
            out[key] = compact(getattr(self, key))
        if self.update_rate is not None:
            out["update_rate"] = float(self.update_rate)
        for name in field_names():
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
                out[name] = compact(v)
        return out

    # ---------------------------------------------------------------- queries

    def sensor(self, name: str) -> dict:
        """The parameters of one sensor (``"gyroscope"`` or ``"accelerometer"``) by suffix."""
        if name not in SENSORS:
            raise ConfigError(f"sensor must be one of {SENSORS}, got {name!r}")
        out = {suffix: getattr(self, f"{name}_{suffix}")
               for suffix in ("noise_density", "random_walk", *VECTOR_SUFFIXES, "misalignment")}
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


def read_imu_yaml(path):
    """Read an IMU configuration file: a mapping of keys (flat, or a chain ``imu0: {...}``).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    splineimu.yamldoc.YamlDoc
        ``data`` is the mapping; ``line(*keys)`` gives the line of each key.

    Raises
    ------
    ConfigError
        Missing or unreadable file, invalid YAML (with its line), or not a mapping.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "sensor.yaml"
    >>> _ = p.write_text("%YAML:1.0\\nrate_hz: 200\\ngyroscope_noise_density: 1.6968e-04\\n")
    >>> doc = read_imu_yaml(p)
    >>> doc.data["gyroscope_noise_density"], doc.line("rate_hz")
    (0.00016968, 2)
    """
    from ..yamldoc import read_yaml

    doc = read_yaml(path, "IMU configuration file")
    if not isinstance(doc.data, dict):
        raise ConfigError(f"expected a mapping of IMU parameters, got {type(doc.data).__name__}", path=doc.name)
    if not doc.data:  # an empty or truncated file would silently be a noise-free, ideal sensor
        raise ConfigError("holds no IMU parameters (empty); for a noise-free sensor give the preset `ideal`",
                          path=doc.name)
    return doc
