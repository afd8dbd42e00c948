"""The ``timing`` and ``vibration`` options of :class:`~splineimu.api.options.ImuOptions`.

Each is given as a model object, a mapping (Python, or a scene file's block), YAML text, or
(vibration only) a YAML file holding the block; :func:`load_timing` and
:func:`load_vibration` turn it into a :class:`~splineimu.imu.timing.TimingModel` /
:class:`~splineimu.imu.vibration.VibrationModel` (None when nothing is modelled), with errors
named the way the value was written: the scene-file key at its file and line, the flag
(``--drop-probability``), or the Python argument (``timing.drop_probability``).

Examples
--------
>>> from splineimu.api.options import FlagOrigin
>>> load_timing({"clock_drift_ppm": 20}, FlagOrigin())
TimingModel(time_offset_s=0.0, clock_drift_ppm=20.0, stamp_noise_s=0.0, drop_probability=0.0, drop_burst_s=0.0)
>>> load_timing({"drop_probability": 2}, FlagOrigin())
Traceback (most recent call last):
...
splineimu.errors.ConfigError: `--drop-probability` must be below 1, got 2
>>> load_timing({"time_offset_s": 0}, FlagOrigin()) is None
True
"""

from __future__ import annotations

from ..errors import ConfigError, InputError


def _yaml_place(origin, fld):
    """``(doc, key path)`` when the value came from a scene file, else ``(None, None)``."""
    doc = getattr(origin, "doc", None)
    if doc is None:
        return None, None
    return doc, origin.keys.get(fld, (fld,))


def load_timing(value, origin):
    """A :class:`~splineimu.imu.timing.TimingModel` from ``value`` (None if no effect is set).

    Parameters
    ----------
    value : TimingModel, dict or None
    origin : splineimu.api.options.Origin
        Where the value came from (names it in errors).

    Raises
    ------
    ConfigError
        Not a mapping, an unknown key, a value out of range.
    """
    if value is None:  # (before the import, as in load_vibration)
        return None
    from ..imu.timing import TimingModel

    doc, keys = _yaml_place(origin, "timing")
    if isinstance(value, TimingModel):
        model = value
    elif doc is not None:  # errors at the block's file and line
        model = TimingModel.from_dict(value, doc, keys)
    elif not isinstance(value, dict):
        raise ConfigError(f"`{origin.name('timing')}` must be a mapping of timing keys, got {type(value).__name__}",
                          option=origin.name("timing"))
    else:
        try:
            model = TimingModel.from_dict(value)
        except ConfigError as exc:
            key = str(exc.option or "").split(".")[-1]
            name = origin.name(f"timing.{key}")
            raise ConfigError(exc.problem.replace(f"`{key}`", f"`{name}`"), option=name) from None
    return None if model.is_identity else model


def load_vibration(value, origin):
    """A :class:`~splineimu.imu.vibration.VibrationModel` from ``value`` (None if it has no component).

    Parameters
    ----------
    value : VibrationModel, dict, str (a YAML file) or None
    origin : splineimu.api.options.Origin

    Raises
    ------
    ConfigError
        A bad component (errors at the file and line of a scene file or vibration file).
    """
    if value is None:  # (before the import: runs without vibration do not load its module)
        return None
    from ..imu.vibration import VibrationModel

    if isinstance(value, VibrationModel):
        model = value
    elif isinstance(value, str):  # a YAML file holding the block: errors at its own lines
        from ..io.yaml import read_yaml

        doc = read_yaml(value, "vibration file")
        model = VibrationModel.from_dict(doc.data, doc)
    elif _yaml_place(origin, "vibration")[0] is not None:  # errors at the block's file and line
        model = VibrationModel.from_dict(value, *_yaml_place(origin, "vibration"))
    elif isinstance(value, dict):
        try:
            model = VibrationModel.from_dict(value)
        except (ConfigError, InputError) as exc:
            raise origin.relocate("vibration", ConfigError(exc.problem)) from None
    else:
        name = origin.name("vibration")
        raise ConfigError(f"`{name}` must be a file or a mapping, got {type(value).__name__}", option=name)
    return None if model.is_empty else model


__all__ = ["load_timing", "load_vibration"]
