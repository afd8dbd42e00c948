"""YAML documents of configuration: the safe reader, with the file and line of every value.

The one YAML reader of the product (:func:`read_yaml`, :func:`parse_yaml`): PyYAML's safe loader,
hardened for files a user hands over:

- OpenCV's ``%YAML:1.0`` first line (EuRoC ``sensor.yaml``, OpenVINS and VINS configs) is
  accepted, and so is the ``!!opencv-matrix`` tag (read as its mapping ``rows, cols, dt, data``);
- aliases and nesting are bounded (a "billion laughs" file or 10,000 nested lists is refused
  with a one-line :class:`~splineimu.errors.ConfigError`, not run until killed);
- bytes that are not UTF-8 and files over :data:`MAX_YAML_BYTES` are refused with the file,
  line and problem.

:func:`read_yaml` returns a :class:`YamlDoc`: the data plus the line of every key, so that a
value checked later is still reported at its file and line (``doc.where("imu", "rate_hz")``).

It sits below the layers (it needs only :mod:`splineimu.errors`) because configuration is read
at every level: the IMU model reads its presets and ``imu.yaml``, the cameras their camchain, the
library API its scene files. The writer is :mod:`splineimu.io.yaml` (outputs are io's).

Examples
--------
>>> doc = parse_yaml("imu:\\n  rate_hz: 200\\n", "scene.yaml")
>>> doc.data["imu"]["rate_hz"], doc.line("imu", "rate_hz")
(200, 2)
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from .errors import ConfigError

#: Largest YAML file read (configuration files are a few kB; this refuses data files given by mistake).
MAX_YAML_BYTES = 16 * 1024 * 1024
#: Most aliases (``*name``) one document may use.
MAX_ALIASES = 200
#: Deepest nesting of mappings and lists.
MAX_DEPTH = 64
#: Most values a document may hold once its aliases are expanded (what a consumer walks).
MAX_EXPANDED = 1_000_000

_OPENCV_DIRECTIVE = re.compile(r"\A(\s*)%YAML:[^\n]*")


@dataclass
class YamlDoc:
    """A parsed YAML document and where each key stood.

    Attributes
    ----------
    data : object
        The document (``{}`` for an empty file).
    name : str
        The file (or a label) it came from.
    lines : dict
        ``tuple(keys...) -> 1-based line`` of every mapping key and list item.
    """

    data: object
    name: str = ""
    lines: dict = field(default_factory=dict)

    def line(self, *keys) -> int | None:
        """Line of the value at ``keys`` (or of its nearest enclosing key), ``None`` if unknown."""
        keys = tuple(keys)
        while keys:
            if keys in self.lines:
                return self.lines[keys]
            keys = keys[:-1]
        return None

    def where(self, *keys) -> tuple:
        """``(name, line)`` for :mod:`splineimu.validation` and the error classes."""
        return (self.name, self.line(*keys))

    def error(self, message: str, *keys) -> ConfigError:
        """A :class:`ConfigError` at the file and line of ``keys``."""
        return ConfigError(message, path=self.name, line=self.line(*keys),
                           option=".".join(map(str, keys)) or None)


def _loader_class():
    import yaml

    class _Loader(yaml.SafeLoader):
        def __init__(self, stream):
            super().__init__(stream)
            self._aliases = 0
            self._depth = 0

        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                self._aliases += 1
                if self._aliases > MAX_ALIASES:
                    ev = self.peek_event()
                    raise _Refused(f"more than {MAX_ALIASES} aliases", ev.start_mark.line + 1)
            self._depth += 1
            try:
                if self._depth > MAX_DEPTH:
                    ev = self.peek_event()
                    raise _Refused(f"nested deeper than {MAX_DEPTH} levels", ev.start_mark.line + 1)
                return super().compose_node(parent, index)
            finally:
                self._depth -= 1

    def _opencv_matrix(loader, node):
        return loader.construct_mapping(node, deep=True)

    _Loader.add_constructor("tag:yaml.org,2002:opencv-matrix", _opencv_matrix)
    # YAML 1.2 / JSON numbers without a dot (`1e-4`, as Kalibr files hold) are floats, not strings.
    _Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXP_FLOAT, list("-+0123456789"))
    return _Loader


_EXP_FLOAT = re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")


def _expanded_size(node, memo) -> int:
    """Values in ``node`` once aliases are expanded (linear time: shared nodes are memoized)."""
    import yaml

    key = id(node)
    if key in memo:
        return memo[key]
    memo[key] = 1  # a cycle (recursive alias) counts once
    n = 1
    if isinstance(node, yaml.MappingNode):
        n += sum(_expanded_size(k, memo) + _expanded_size(v, memo) for k, v in node.value)
    elif isinstance(node, yaml.SequenceNode):
        n += sum(_expanded_size(v, memo) for v in node.value)
    memo[key] = n
    return n


class _Refused(Exception):
    def __init__(self, problem, line):
        super().__init__(problem)
        self.problem = problem
        self.line = line


class _Repeated(_Refused):
    pass


def _record_lines(node, prefix, lines, seen):
    import yaml

    if id(node) in seen:  # aliased node: its lines are those of its anchor
        return
    seen.add(id(node))
    if isinstance(node, yaml.MappingNode):
        first_line = {}
        for k, v in node.value:
            key = k.value if isinstance(k, yaml.ScalarNode) else None
            if key is not None and key != "<<":  # PyYAML keeps the last of repeated keys, silently
                if key in first_line:
                    raise _Repeated(f"key `{key}` repeats the one on line {first_line[key]}", k.start_mark.line + 1)
                first_line[key] = k.start_mark.line + 1
            path = prefix + (key,)
            lines.setdefault(path, k.start_mark.line + 1)
            _record_lines(v, path, lines, seen)
    elif isinstance(node, yaml.SequenceNode):
        for i, v in enumerate(node.value):
            path = prefix + (i,)
            lines.setdefault(path, v.start_mark.line + 1)
            _record_lines(v, path, lines, seen)


def parse_yaml(text: str, name: str = "<yaml>") -> YamlDoc:
    """Parse YAML text safely (see the module notes); errors name ``name`` and the line.

    Raises
    ------
    ConfigError
        Not YAML, more than one document, too many aliases or too deep.
    """
    import yaml

    text = _OPENCV_DIRECTIVE.sub(r"\1", text, count=1)  # keep the line count for messages
    loader = None
    try:
        loader = _loader_class()(text)  # checks the characters (a NUL byte is refused here)
        node = loader.get_single_node()
        lines: dict = {}
        data = None
        if node is not None:
            if _expanded_size(node, {}) > MAX_EXPANDED:
                raise _Refused(f"more than {MAX_EXPANDED} values once its aliases are expanded", 1)
            _record_lines(node, (), lines, set())
            data = loader.construct_document(node)
    except _Repeated as exc:
        raise ConfigError(exc.problem, path=name, line=exc.line) from None
    except _Refused as exc:
        raise ConfigError(f"refused: {exc.problem} (a YAML file of this product is a small mapping)",
                          path=name, line=exc.line) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        line = None if mark is None else mark.line + 1
        if isinstance(exc, yaml.reader.ReaderError):  # a character YAML does not allow
            line = text.count("\n", 0, max(exc.position, 0)) + 1
        raise ConfigError(f"invalid YAML: {problem}", path=name, line=line) from None
    except RecursionError:
        raise ConfigError(f"refused: nested deeper than {MAX_DEPTH} levels", path=name) from None
    finally:
        if loader is not None:
            loader.dispose()
    return YamlDoc({} if data is None else data, name, lines)


def read_yaml(path, what: str = "YAML file") -> YamlDoc:
    """Read and parse a YAML file safely.

    Parameters
    ----------
    path : str or os.PathLike
    what : str
        What the file is, for messages ("scene file", "IMU model", ...).

    Raises
    ------
    ConfigError
        Missing or unreadable file, too large, not UTF-8, or not valid YAML.
    """
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_YAML_BYTES:
            raise ConfigError(f"{what} is {size / 2**20:.0f} MiB; refusing to read more than "
                              f"{MAX_YAML_BYTES >> 20} MiB of YAML", path=path)
        raw = path.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{what} not found", path=path) from None
    except IsADirectoryError:
        raise ConfigError(f"{what} is a folder, not a file", path=path) from None
    except OSError as exc:
        raise ConfigError(f"cannot read {what}: {exc.strerror}", path=path) from None
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise ConfigError(f"{what} is not UTF-8 text (byte 0x{raw[exc.start]:02x})", path=path, line=line) from None
    return parse_yaml(text, str(path))


__all__ = ["YamlDoc", "parse_yaml", "read_yaml", "MAX_YAML_BYTES", "MAX_ALIASES", "MAX_DEPTH", "MAX_EXPANDED"]
