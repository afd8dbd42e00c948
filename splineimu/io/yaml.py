"""The one YAML module: safe reading with file and line for every value, and one writer.

Reading (:func:`read_yaml`, :func:`parse_yaml`, :class:`YamlDoc`: PyYAML's safe loader, hardened
for files a user hands over, with the file and line of every value) lives in
:mod:`splineimu.yamldoc` (configuration is read at every layer) and is re-exported here.

Writing (:func:`dump_yaml`, :func:`write_yaml`) gives block-style YAML with short lists inline,
floats written exactly (shortest repr that reads back to the same double, always with a ``.``
so that every YAML 1.1 reader sees a float: ``5.0e-05``) and atomic file replacement; on request
in a form that OpenCV's ``FileStorage`` reads too.

Examples
--------
>>> doc = parse_yaml("imu:\\n  rate_hz: 200\\n", "scene.yaml")
>>> doc.data["imu"]["rate_hz"], doc.line("imu", "rate_hz")
(200, 2)
>>> print(dump_yaml({"update_rate": 200.0, "T": [1.0, 0.5]}), end="")
update_rate: 200.0
T: [1.0, 0.5]
"""

from __future__ import annotations

import math
from pathlib import Path

from ..yamldoc import MAX_ALIASES, MAX_DEPTH, MAX_EXPANDED, MAX_YAML_BYTES, YamlDoc, parse_yaml, read_yaml
from .files import atomic_write_text


def float_text(value: float) -> str:
    """A float as YAML text that PyYAML's YAML 1.1 resolver and OpenCV's FileStorage both read
    as this float: the shortest repr that reads back exactly, with a ``.0`` in the mantissa
    and a signed exponent (``2.0e-05``, not ``2e-05``, which PyYAML reads as a string).

    Examples
    --------
    >>> [float_text(x) for x in (400.0, 2e-05, 1.5e-07, 1e16, -0.25)]
    ['400.0', '2.0e-05', '1.5e-07', '1.0e+16', '-0.25']
    """
    value = float(value)
    if math.isinf(value):
        return ".inf" if value > 0 else "-.inf"
    if math.isnan(value):
        return ".nan"
    text = repr(value)
    mantissa, e, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    if e and exponent[0] not in "+-":
        exponent = "+" + exponent
    return mantissa + e + exponent


def _dumper_class(opencv: bool = False):
    import yaml

    class _Dumper(yaml.SafeDumper):
        def ignore_aliases(self, data):  # a value used twice is written twice, never as `*id001`
            return True

        if opencv:
            def increase_indent(self, flow=False, indentless=False):
                # list items indented under their key, as OpenCV's parser needs
                return super().increase_indent(flow, False)

    def _repr_list(dumper, value):
        value = list(value)
        flat = all(not isinstance(v, (list, tuple, dict)) for v in value)
        small_rows = all(isinstance(v, (list, tuple)) and len(v) <= 3 for v in value)
        return dumper.represent_sequence("tag:yaml.org,2002:seq", value, flow_style=flat or small_rows)

    def _repr_float(dumper, value):
        return dumper.represent_scalar("tag:yaml.org,2002:float", float_text(value))

    _Dumper.add_representer(list, _repr_list)
    _Dumper.add_representer(tuple, _repr_list)
    _Dumper.add_representer(float, _repr_float)
    return _Dumper


#: First lines of a file that both PyYAML and OpenCV's FileStorage open: OpenCV needs a first
#: line starting with ``%YAML`` and PyYAML refuses OpenCV's own ``%YAML:1.0``.
OPENCV_COMPATIBLE_START = "%YAML 1.1\n---\n"


def dump_yaml(data, comment_lines=(), width: int = 110, *, opencv: bool = False) -> str:
    """``data`` as block-style YAML: short lists and lists of short rows inline, exact floats.

    Parameters
    ----------
    data : dict
        Plain values: numbers, strings, lists, mappings.
    comment_lines : sequence of str
        Lines starting with ``#``, written before the data.
    width : int
        Preferred line width.
    opencv : bool, default False
        Also readable by OpenCV's ``cv::FileStorage`` (as OpenVINS, VINS-Fusion and Kimera
        read their configuration): the document starts with :data:`OPENCV_COMPATIBLE_START`,
        block list items are indented under their key and long strings are not folded over
        lines (OpenCV cannot read a continued plain scalar; ``width`` is then ignored).

    Notes
    -----
    Floats are written by :func:`float_text`, so every reader sees a float (``5.0e-05``).

    Examples
    --------
    >>> T = [[1.0, 0.0, 0.0, 0.5], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
    >>> print(dump_yaml({"rate": 400.0, "noise": 2e-05, "T": T}, ["# made here"], opencv=True), end="")
    %YAML 1.1
    ---
    # made here
    rate: 400.0
    noise: 2.0e-05
    T:
      - [1.0, 0.0, 0.0, 0.5]
      - [0.0, 1.0, 0.0, 0.0]
      - [0.0, 0.0, 1.0, 0.0]
      - [0.0, 0.0, 0.0, 1.0]
    """
    import yaml

    if opencv:
        width = 1 << 30
    body = yaml.dump(data, Dumper=_dumper_class(opencv), sort_keys=False, default_flow_style=False, width=width)
    start = OPENCV_COMPATIBLE_START if opencv else ""
    return start + "".join(c + "\n" for c in comment_lines) + body


def write_yaml(path, data, comment_lines=(), *, text: str | None = None, opencv: bool = False) -> Path:
    """Write ``data`` (or ready ``text``) to ``path`` atomically (temp file, then rename).

    ``comment_lines`` and ``opencv`` as for :func:`dump_yaml`. The file gets mode
    ``0666 & ~umask`` like every other output file.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write_text(path, dump_yaml(data, comment_lines, opencv=opencv) if text is None else text)


__all__ = ["YamlDoc", "parse_yaml", "read_yaml", "dump_yaml", "write_yaml", "float_text", "MAX_YAML_BYTES",
           "MAX_ALIASES", "MAX_DEPTH", "MAX_EXPANDED", "OPENCV_COMPATIBLE_START"]
