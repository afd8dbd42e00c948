"""Sensor temperature over time, for the temperature terms of the IMU sensor model.

A :class:`TemperatureProfile` is built from the ``temperature_profile`` value of an IMU
configuration (:mod:`splineimu.imu.config`): a number (constant), ``{start, rate}`` (a linear
ramp from the record's first sample) or ``{file: PATH}`` (a two-column table, linearly
interpolated).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError
from ._config_values import finite_number, is_number

__all__ = ["TemperatureProfile"]

_KEY = "temperature_profile"


@dataclass(frozen=True)
class TemperatureProfile:
    """Sensor temperature over time.

    Exactly one form is set: ``constant_c``; ``start_c`` + ``rate_c_per_s`` (linear ramp
    from the first sample); or a table ``table_t_s`` / ``table_c`` (linear interpolation,
    held constant outside) read from ``file``.

    Examples
    --------
    >>> ramp = TemperatureProfile.parse({"start": 20.0, "rate": 0.5})
    >>> ramp([100.0, 102.0]).tolist()  # seconds; the ramp starts at the first sample
    [20.0, 21.0]
    >>> ramp.to_yaml_value()
    {'start': 20.0, 'rate': 0.5}
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
        """The ``temperature_profile`` value that :meth:`parse` reads back."""
        if self.constant_c is not None:
            return float(self.constant_c)
        if self.start_c is not None:
            return {"start": float(self.start_c), "rate": float(self.rate_c_per_s)}
        return {"file": self.file}

    @classmethod
    def parse(cls, value, base_dir: Path | None = None, source: str = "") -> TemperatureProfile:
        """A profile from a ``temperature_profile`` value.

        Parameters
        ----------
        value : float or dict
            A number [degC], ``{start: degC, rate: degC/s}`` or ``{file: PATH}``.
        base_dir : pathlib.Path, optional
            Folder that a relative ``PATH`` is relative to (the yaml file's).
        source : str
            Where the value came from, for messages.

        Raises
        ------
        ConfigError
            Another form, a non-finite number, or a missing file.
        InputError
            A file line that is not two numbers, or times not strictly increasing.
        """
        if is_number(value):
            return cls(constant_c=finite_number(value, _KEY, source))
        if isinstance(value, dict):
            keys = set(value)
            if keys == {"start", "rate"}:
                return cls(start_c=finite_number(value["start"], _KEY + ".start", source),
                           rate_c_per_s=finite_number(value["rate"], _KEY + ".rate", source))
            if keys == {"file"}:
                return cls._from_file(value["file"], base_dir, source)
        raise ConfigError(f"`{_KEY}` must be a number [degC], {{start: degC, rate: degC/s}} or {{file: PATH}}, "
                          f"got {value!r}", path=source or None, option=_KEY)

    @classmethod
    def _from_file(cls, name, base_dir, source):
        if not isinstance(name, str) or not name:
            raise ConfigError(f"`{_KEY}.file` must be a path, got {name!r}", path=source or None, option=_KEY)
        path = Path(name).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.is_file():
            raise ConfigError(f"temperature profile file not found: {path}", path=source or None, option=_KEY)
        t_s, c = _read_table(path)
        # keep the resolved path, so that a config written elsewhere (OUT/imu.yaml) still finds it
        return cls(file=str(path.resolve()), table_t_s=t_s, table_c=c)


def _read_table(path: Path):
    """Two columns ``time [s], temperature [degC]`` (comma or space separated, ``#`` comments)."""
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
    return tab[:, 0].copy(), tab[:, 1].copy()
