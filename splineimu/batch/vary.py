"""The ``vary:`` block of a scene file: which keys a Monte-Carlo batch draws, and from what.

::

    vary:
      imu.model.gyroscope_noise_density: {normal: [1.8e-4, 2.0e-5]}
      imu.model.accelerometer_noise_density: {uniform: [1.0e-3, 3.0e-3]}
      imu.rate_hz: {choice: [100, 200, 400]}

Keys are dotted paths of the scene format; distributions are ``{normal: [mean, std]}``,
``{uniform: [low, high]}`` and ``{choice: [a, b, ...]}``.

Reproducibility: run ``k``'s seed and draws depend on the scene's ``seed`` and ``k`` alone,
through numpy's :class:`~numpy.random.SeedSequence` spawn keys: the draws come from
``SeedSequence(seed, spawn_key=(k, 0))`` in the order of the block, the run's own seed (which
replaces the scene's ``seed`` for that run) from ``SeedSequence(seed, spawn_key=(k, 1))``. So a
run is the same on any scheduler, with any number of workers and in any order of completion.

Examples
--------
>>> from splineimu.io.yaml import parse_yaml
>>> doc = parse_yaml("vary:\\n  imu.rate_hz: {choice: [100, 200]}\\n", "scene.yaml")
>>> v = parse_vary(doc.data["vary"], doc)
>>> v["imu.rate_hz"]
Distribution(kind='choice', params=(100, 200))
>>> draws_for_run(v, scene_seed=42, k=0) == draws_for_run(v, scene_seed=42, k=0)
True
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

KINDS = ("normal", "uniform", "choice")


@dataclass(frozen=True)
class Distribution:
    """One distribution of the ``vary:`` block."""

    kind: str
    params: tuple

    def draw(self, rng: np.random.Generator):
        """One value (a Python float, or the chosen item as written)."""
        if self.kind == "normal":
            return float(rng.normal(self.params[0], self.params[1]))
        if self.kind == "uniform":
            return float(rng.uniform(self.params[0], self.params[1]))
        return self.params[int(rng.integers(len(self.params)))]

    def nominal(self):
        """The value a single run without ``--run-index`` uses: mean, midpoint, or first choice."""
        if self.kind == "normal":
            return float(self.params[0])
        if self.kind == "uniform":
            return 0.5 * (self.params[0] + self.params[1])
        return self.params[0]

    def to_dict(self) -> dict:
        return {self.kind: list(self.params)}


def _num(v):
    return isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(float(v))


def parse_vary(block, doc=None, keys: tuple = ("vary",)) -> dict:
    """Check a ``vary:`` mapping: ``{dotted key: Distribution}`` in the file's order.

    Only the form is checked here (that each key names a key of the scene format is checked
    when the draws are applied, see :func:`set_dotted`).

    Raises
    ------
    ConfigError
        A key that is not a dotted path, an unknown distribution, bad parameters; with the
        yaml file and line when ``doc`` is given.
    """
    from ..errors import ConfigError

    def err(msg, *k):
        if doc is None:
            return ConfigError(msg, option=".".join(map(str, k)) or None)
        return doc.error(msg, *k)

    if block is None:
        return {}
    if not isinstance(block, dict):
        raise err("`vary` must be a mapping of dotted scene keys to distributions", *keys)
    out = {}
    for key, spec in block.items():
        where = keys + (key,)
        if not isinstance(key, str) or not key or any(not part for part in key.split(".")):
            raise err(f"`vary` key {key!r} must be a dotted path of the scene, e.g. imu.model.gyroscope_noise_density",
                      *where)
        if not (isinstance(spec, dict) and len(spec) == 1):
            raise err(f"`vary.{key}` must be one of {{normal: [mean, std]}}, {{uniform: [low, high]}}, "
                      "{choice: [a, b, ...]}", *where)
        kind, params = next(iter(spec.items()))
        if kind not in KINDS:
            raise err(f"`vary.{key}`: unknown distribution `{kind}`; use normal, uniform or choice", *where)
        if not isinstance(params, list):
            raise err(f"`vary.{key}.{kind}` must be a list", *where)
        if kind == "normal":
            if len(params) != 2 or not all(map(_num, params)) or params[1] < 0:
                raise err(f"`vary.{key}.normal` must be [mean, std] with std >= 0, got {params}", *where)
        elif kind == "uniform":
            if len(params) != 2 or not all(map(_num, params)) or not params[1] > params[0]:
                raise err(f"`vary.{key}.uniform` must be [low, high] with high > low, got {params}", *where)
        elif not params:
            raise err(f"`vary.{key}.choice` must list at least one value", *where)
        out[key] = Distribution(kind, tuple(params))
    return out


def run_seed(scene_seed: int, k: int) -> int:
    """Run ``k``'s seed: 63 bits from ``SeedSequence(scene_seed, spawn_key=(k, 1))``."""
    words = np.random.SeedSequence(int(scene_seed), spawn_key=(int(k), 1)).generate_state(2, np.uint32)
    return (int(words[0]) << 31) ^ int(words[1])


def draws_for_run(vary: dict, scene_seed: int, k: int) -> dict:
    """The values drawn for run ``k``: ``{dotted key: value}`` in the order of ``vary``."""
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(scene_seed), spawn_key=(int(k), 0))))
    return {key: dist.draw(rng) for key, dist in vary.items()}


def nominal_values(vary: dict) -> dict:
    """The values of a run without ``--run-index``."""
    return {key: dist.nominal() for key, dist in vary.items()}


def _child(node, part):
    """``node[part]`` of a mapping, or of a list when ``part`` is an index; None if absent."""
    if isinstance(node, dict):
        return node.get(part)
    if isinstance(node, list) and part.isdigit() and int(part) < len(node):
        return node[int(part)]
    return None


def set_dotted(data: dict, key: str, value, expand=None) -> None:
    """Set ``data[a][b][c] = value`` for ``key = "a.b.c"`` in a scene-file mapping (in place).

    A part that is a number indexes a list (``imu.extrinsic.translation.0``). Intermediate
    mappings must exist, except where ``expand(path_so_far, current_value)`` turns a scalar
    into a mapping (e.g. an IMU preset name into its keys) or returns ``{}`` for an absent
    optional block (or the default list of an absent vector); it returns ``None`` where the
    path is not part of the scene format.

    Raises
    ------
    KeyError
        With the first part of ``key`` that does not exist.

    Examples
    --------
    >>> d = {"imu": {"extrinsic": {"translation": [0.1, 0.0, 0.0]}}}
    >>> set_dotted(d, "imu.extrinsic.translation.2", 0.5)
    >>> d["imu"]["extrinsic"]["translation"]
    [0.1, 0.0, 0.5]
    """
    parts = key.split(".")
    node = data
    for i, part in enumerate(parts[:-1]):
        nxt = _child(node, part)
        if not isinstance(nxt, (dict, list)):
            nxt = expand(".".join(parts[: i + 1]), nxt) if expand is not None and isinstance(node, dict) else None
            if not isinstance(nxt, (dict, list)):
                raise KeyError(".".join(parts[: i + 1]))
            node[part] = nxt
        node = nxt
    last = parts[-1]
    if isinstance(node, list):
        if _child(node, last) is None:
            raise KeyError(key)
        node[int(last)] = value
    else:
        node[last] = value


__all__ = ["Distribution", "parse_vary", "run_seed", "draws_for_run", "nominal_values", "set_dotted", "KINDS"]
