"""Packaged presets of real IMUs, and :func:`load_imu_config`, which takes a preset or a file.

The presets are Kalibr-style yaml files in ``splineimu/presets/``; their names can be given
wherever an IMU configuration file is expected (``--imu adis16448``).
"""

from __future__ import annotations

import difflib
import os
from importlib import resources
from pathlib import Path

from ..errors import ConfigError
from ..yamldoc import parse_yaml
from ._config import ImuConfig

__all__ = ["list_presets", "load_preset", "load_imu_config"]


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
    return ImuConfig.from_dict(parse_yaml(text, f"preset {key}").data, source=f"preset {key}")


def load_imu_config(spec) -> ImuConfig:
    """An :class:`ImuConfig` from a yaml path, a preset name, a mapping or an ImuConfig.

    An existing file wins over a preset of the same name.

    Parameters
    ----------
    spec : ImuConfig, dict, str or os.PathLike
        A configuration, a mapping of its keys, a yaml file (any form that
        :meth:`ImuConfig.from_yaml` reads) or the name of a packaged preset.

    Returns
    -------
    ImuConfig

    Raises
    ------
    ConfigError
        Unknown preset (with a did-you-mean), missing file, invalid keys or values.

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
