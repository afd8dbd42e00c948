"""Landmarks: world-frame points with integer ids, read from a csv file or drawn at random.

File format (``landmarks.csv``)::

    id,x,y,z
    0,12.5,-3.25,1.0
    ...

``id`` is a whole number (kept as given, unique), ``x, y, z`` are world coordinates [m].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError

__all__ = ["Landmarks", "SHAPES"]

#: shapes of :meth:`Landmarks.random`
SHAPES = ("shell", "box")

#: times at which a motion source is sampled to find its centre and extent
_TRAJECTORY_SAMPLES = 1001


@dataclass(eq=False)
class Landmarks:
    """World-frame points with ids.

    Attributes
    ----------
    id : (M,) int64
        Unique ids, kept from the input.
    position_world : (M, 3) float64
        Points in the world frame [m].

    Examples
    --------
    >>> lm = Landmarks([7, 9], [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    >>> len(lm), lm.id.tolist()
    (2, [7, 9])
    >>> Landmarks([1, 1], [[0, 0, 0], [1, 1, 1]])
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: landmark ids must be unique; 1 appears more than once
    """

    id: np.ndarray
    position_world: np.ndarray

    def __post_init__(self):
        p = np.asarray(self.position_world, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ConfigError(f"Expected `position_world` to have shape (M, 3), got {p.shape}")
        if not np.all(np.isfinite(p)):
            raise ConfigError("`position_world` contains NaN or inf")
        raw = np.asarray(self.id)
        if raw.shape != (p.shape[0],):
            raise ConfigError(f"Expected `id` to have shape ({p.shape[0]},), got {raw.shape}")
        if raw.size and raw.dtype.kind not in "iu":
            if raw.dtype.kind != "f" or not np.all(np.isfinite(raw)) or np.any(raw != np.round(raw)):
                raise ConfigError("landmark ids must be whole numbers")
        ids = raw.astype(np.int64)
        uniq, counts = np.unique(ids, return_counts=True)
        if np.any(counts > 1):
            raise ConfigError(f"landmark ids must be unique; {int(uniq[counts > 1][0])} appears more than once")
        self.id = np.ascontiguousarray(ids)
        self.position_world = np.ascontiguousarray(p)

    def __len__(self) -> int:
        return int(self.id.shape[0])

    def __eq__(self, other):
        if not isinstance(other, Landmarks):
            return NotImplemented
        return np.array_equal(self.id, other.id) and np.array_equal(self.position_world, other.position_world)

    __hash__ = None

    # ------------------------------------------------------------------ files
    @classmethod
    def from_csv(cls, path) -> Landmarks:
        """Read ``id,x,y,z`` rows (header line first; ``#`` lines and blank lines are skipped).

        Raises
        ------
        InputError
            Missing file, wrong header, a bad row (with its line number), duplicate ids.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "points.csv"
        >>> _ = p.write_text("id,x,y,z\\n10,1.5,2,3\\n11,-1,0,0.25\\n")
        >>> lm = Landmarks.from_csv(p)
        >>> lm.id.tolist(), lm.position_world[0].tolist()
        ([10, 11], [1.5, 2.0, 3.0])
        """
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(f"cannot read landmarks: {exc.strerror or exc}", path=path) from None
        ids, rows, header_seen, seen = [], [], False, {}
        for lineno, raw in enumerate(text.splitlines(), start=1):
            line = raw.strip()
            if not line or (line.startswith("#") and header_seen):
                continue
            fields = [f.strip() for f in line.lstrip("#").split(",")]
            if not header_seen:
                if [f.lower() for f in fields] != ["id", "x", "y", "z"]:
                    raise InputError(f"expected the header `id,x,y,z`, got {raw!r}", path=path, line=lineno)
                header_seen = True
                continue
            if len(fields) != 4:
                raise InputError(f"expected 4 comma-separated values (id,x,y,z), got {len(fields)}",
                                 path=path, line=lineno)
            try:
                ident = int(fields[0])
            except ValueError:
                raise InputError(f"landmark id must be a whole number, got {fields[0]!r}",
                                 path=path, line=lineno) from None
            try:
                xyz = [float(f) for f in fields[1:]]
            except ValueError:
                raise InputError(f"x, y, z must be numbers, got {fields[1:]!r}", path=path, line=lineno) from None
            if not all(math.isfinite(c) for c in xyz):
                raise InputError("x, y, z must be finite", path=path, line=lineno)
            if ident in seen:
                raise InputError(f"landmark id {ident} already on line {seen[ident]}", path=path, line=lineno)
            seen[ident] = lineno
            ids.append(ident)
            rows.append(xyz)
        if not header_seen:
            raise InputError("empty landmarks file (expected the header `id,x,y,z`)", path=path)
        return cls(np.array(ids, dtype=np.int64), np.array(rows, dtype=np.float64).reshape(-1, 3))

    def csv_text(self) -> str:
        """The text of a landmarks file: ``id,x,y,z`` rows, floats written so they read back bit for
        bit (:func:`splineimu.io.camera.write_landmarks_csv` writes it)."""
        lines = ["id,x,y,z"]
        lines += [f"{i},{x!r},{y!r},{z!r}" for i, (x, y, z) in zip(self.id.tolist(), self.position_world.tolist())]
        return "\n".join(lines) + "\n"

    # ------------------------------------------------------------------ random
    @classmethod
    def random(cls, count: int, shape: str = "shell", *, source=None, center=None, radii_m=None,
               box_min=None, box_max=None, margin_m: float = 5.0, rng=None) -> Landmarks:
        """Draw ``count`` landmarks with ids ``0 .. count-1``.

        Parameters
        ----------
        count : int
            Number of landmarks (>= 0).
        shape : {"shell", "box"}
            ``shell``: uniform in the volume between two spheres of radii ``radii_m`` around
            ``center``. ``box``: uniform over the area of the six walls of the axis-aligned box
            ``[box_min, box_max]``.
        source : MotionSource, optional
            Gives the defaults: its positions at 1001 times spanning its range make the
            trajectory's centre (midpoint of the bounding box) and extent ``R`` (largest
            distance from the centre). ``radii_m`` defaults to ``(R + 2, R + 10)`` [m]; the box
            to the trajectory's bounding box grown by ``margin_m`` on each side.
        center : (3,) float, optional
            Shell centre (default: the trajectory's centre).
        radii_m : (2,) float, optional
            Inner and outer shell radii, ``0 <= r_in <= r_out``, ``r_out > 0``.
        box_min, box_max : (3,) float, optional
            Box corners (default: from ``source`` and ``margin_m``).
        margin_m : float
            Gap between the trajectory's bounding box and the walls.
        rng : numpy.random.Generator, int or None
            Random source; the same seed gives the same landmarks.

        Returns
        -------
        Landmarks

        Raises
        ------
        ConfigError
            Unknown shape, bad count or geometry, or a default that needs ``source`` without it.

        Examples
        --------
        >>> lm = Landmarks.random(500, "shell", center=[0, 0, 0], radii_m=(10, 20), rng=1)
        >>> r = np.linalg.norm(lm.position_world, axis=1)
        >>> bool(r.min() >= 10 and r.max() <= 20), lm.id[:3].tolist()
        (True, [0, 1, 2])
        >>> box = Landmarks.random(100, "box", box_min=[0, 0, 0], box_max=[4, 2, 1], rng=1)
        >>> on_wall = np.isclose(box.position_world, [0, 0, 0]) | np.isclose(box.position_world, [4, 2, 1])
        >>> bool(on_wall.any(axis=1).all())
        True
        """
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
            raise ConfigError(f"landmarks: `count` must be a whole number >= 0, got {count!r}")
        if shape not in SHAPES:
            raise ConfigError(f"landmarks: `shape` must be one of {', '.join(SHAPES)}, got {shape!r}")
        gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        traj = _trajectory_positions(source) if source is not None else None
        if shape == "shell":
            c = _vec3(center, "center") if center is not None else _bbox_mid(_need(traj, "center", shape))
            if radii_m is None:
                R = float(np.linalg.norm(_need(traj, "radii_m", shape) - c, axis=1).max())
                radii_m = (R + 2.0, R + 10.0)
            r_in, r_out = _radii(radii_m)
            direction = gen.standard_normal((count, 3))
            norm = np.linalg.norm(direction, axis=1, keepdims=True)
            direction /= np.where(norm > 0, norm, 1.0)
            r = np.cbrt(r_in ** 3 + gen.random(count) * (r_out ** 3 - r_in ** 3))
            points = c + direction * r[:, None]
        else:
            if box_min is None or box_max is None:
                lo = _need(traj, "box_min/box_max", shape).min(0) - float(margin_m)
                hi = traj.max(0) + float(margin_m)
            lo = _vec3(box_min, "box_min") if box_min is not None else lo
            hi = _vec3(box_max, "box_max") if box_max is not None else hi
            if np.any(hi <= lo):
                raise ConfigError(f"landmarks: the box needs box_min < box_max on every axis, got {lo} and {hi}")
            points = _box_walls(gen, count, lo, hi)
        return cls(np.arange(count, dtype=np.int64), points)


def _trajectory_positions(source) -> np.ndarray:
    t = np.linspace(source.t_min_s, source.t_max_s, _TRAJECTORY_SAMPLES)
    positions, _ = source.pose(t)
    return np.asarray(positions, dtype=np.float64)


def _bbox_mid(traj) -> np.ndarray:
    return 0.5 * (traj.min(0) + traj.max(0))


def _need(traj, what, shape):
    if traj is None:
        raise ConfigError(f"landmarks: shape {shape!r} needs `{what}` or a motion source to derive it from")
    return traj


def _vec3(value, key) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ConfigError(f"landmarks: `{key}` must be 3 finite numbers, got {value!r}")
    return v


def _radii(value):
    r = np.asarray(value, dtype=np.float64)
    if r.shape != (2,) or not np.all(np.isfinite(r)) or r[0] < 0 or r[1] < r[0] or r[1] <= 0:
        raise ConfigError(f"landmarks: `radii_m` must be [r_in, r_out] with 0 <= r_in <= r_out, r_out > 0, "
                          f"got {value!r}")
    return float(r[0]), float(r[1])


def _box_walls(gen, count, lo, hi) -> np.ndarray:
    """Uniform over the six faces of [lo, hi] (face chosen with probability proportional to area)."""
    size = hi - lo
    # faces: axis a fixed at lo or hi; area = product of the two other sizes
    areas = np.array([size[(a + 1) % 3] * size[(a + 2) % 3] for a in range(3)] * 2)
    face = gen.choice(6, size=count, p=areas / areas.sum())
    points = lo + gen.random((count, 3)) * size
    axis = face % 3
    rows = np.arange(count)
    points[rows, axis] = np.where(face < 3, lo[axis], hi[axis])
    return points
