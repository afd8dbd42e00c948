"""Timestamped pose tracks read from files, their hygiene, and gaps.

Every pose reader (TUM, EuRoC) ends in :func:`clean_poses`, so all of them reject and
repair the same things in the same words:

- non-finite values and zero-norm quaternions are errors naming the line;
- quaternions are normalized (a notice if any norm was off by more than
  :data:`NORM_NOTICE_TOL`) and their signs made continuous along time;
- stamps must increase: an earlier stamp is an error naming the line; a repeated stamp
  is dropped silently-but-noticed when the whole row repeats (an exact duplicate), and is
  an error naming both lines when the pose differs (or, on request, the later row is
  dropped);
- too few poses is an error.

Errors are :class:`splineimu.errors.InputError`, which prints as one line
``"poses.txt:17: quaternion has zero norm"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..lie import quat_make_continuous
from ..validation import as_vectors, one_of, positive_float
from .timestamps import format_ns, parse_stamps

__all__ = ["PoseTrack", "Gap", "clean_poses", "find_gaps", "split_at_gaps", "NORM_NOTICE_TOL"]

#: Quaternions whose norm differs from 1 by more than this are counted in a notice
#: (they are normalized either way).
NORM_NOTICE_TOL = 1e-3
#: Quaternions with a norm below this are an error ("zero norm").
ZERO_NORM_TOL = 1e-9

_EXTRA_FIELDS = ("velocity_world", "bias_gyro", "bias_accel")


@dataclass
class PoseTrack:
    """Timestamped poses ``world_T_body`` read from a file.

    Attributes
    ----------
    t_ns : numpy.ndarray of int64, shape (N,)
        Strictly increasing stamps in nanoseconds.
    positions : numpy.ndarray, shape (N, 3)
        Body origin in the world frame, float64.
    quat_xyzw : numpy.ndarray, shape (N, 4)
        ``world_R_body`` as unit Hamilton quaternions (x, y, z, w), signs continuous
        (consecutive dot products >= 0).
    path : str
        The source file ("" for tracks made in memory).
    notices : list of str
        Human-readable one-liners about what was repaired or ignored while reading, e.g.
        ``"dropped 1 exact duplicate row (line 812)"``.
    velocity_world : numpy.ndarray, shape (N, 3), optional
        World-frame velocity (EuRoC 17-column ground truth), else None.
    bias_gyro, bias_accel : numpy.ndarray, shape (N, 3), optional
        IMU biases (EuRoC 17-column ground truth), else None.
    line_numbers : numpy.ndarray of int64, shape (N,), optional
        1-based source line of each pose (defaults to 1..N).

    Examples
    --------
    >>> import numpy as np
    >>> tr = PoseTrack(np.array([0, 10**9]), np.zeros((2, 3)), np.tile([0., 0, 0, 1], (2, 1)))
    >>> len(tr), tr.duration_s, tr.line_numbers.tolist()
    (2, 1.0, [1, 2])
    """

    t_ns: np.ndarray
    positions: np.ndarray
    quat_xyzw: np.ndarray
    path: str = ""
    notices: list = field(default_factory=list)
    velocity_world: np.ndarray | None = None
    bias_gyro: np.ndarray | None = None
    bias_accel: np.ndarray | None = None
    line_numbers: np.ndarray | None = None

    def __post_init__(self):
        self.t_ns = np.ascontiguousarray(self.t_ns, dtype=np.int64)
        n = self.t_ns.shape[0]
        self.positions = as_vectors(self.positions, "positions", n, 3, finite=False)
        self.quat_xyzw = as_vectors(self.quat_xyzw, "quat_xyzw", n, 4, finite=False)
        for name in _EXTRA_FIELDS:
            v = getattr(self, name)
            if v is not None:
                setattr(self, name, as_vectors(v, name, n, 3, finite=False))
        if self.line_numbers is None:
            self.line_numbers = np.arange(1, n + 1, dtype=np.int64)
        else:
            self.line_numbers = np.ascontiguousarray(self.line_numbers, dtype=np.int64)
            if self.line_numbers.shape != (n,):
                raise ValueError(
                    f"Expected `line_numbers` to have shape ({n},), got {self.line_numbers.shape}"
                )
        self.path = str(self.path)
        self.notices = list(self.notices)

    def __len__(self) -> int:
        return int(self.t_ns.shape[0])

    @property
    def origin_ns(self) -> int:
        """The first stamp, the origin of :attr:`t_s`."""
        return int(self.t_ns[0])

    @property
    def t_s(self) -> np.ndarray:
        """Float seconds relative to the first stamp (exact integer difference first)."""
        return (self.t_ns - self.t_ns[0]).astype(np.float64) * 1e-9

    @property
    def duration_s(self) -> float:
        """Last stamp minus first, in seconds."""
        return float(self.t_ns[-1] - self.t_ns[0]) * 1e-9 if len(self) else 0.0

    def subset(self, index) -> PoseTrack:
        """A new track with the rows selected by ``index`` (slice, mask or indices).

        Path and notices are copied; signs stay continuous only for contiguous slices.
        """
        def pick(a):
            return None if a is None else np.ascontiguousarray(a[index])

        return PoseTrack(
            t_ns=pick(self.t_ns),
            positions=pick(self.positions),
            quat_xyzw=pick(self.quat_xyzw),
            path=self.path,
            notices=list(self.notices),
            velocity_world=pick(self.velocity_world),
            bias_gyro=pick(self.bias_gyro),
            bias_accel=pick(self.bias_accel),
            line_numbers=pick(self.line_numbers),
        )


def _lines_text(lines, limit=5) -> str:
    lines = [int(x) for x in lines]
    head = ", ".join(str(x) for x in lines[:limit])
    more = f", ... ({len(lines) - limit} more)" if len(lines) > limit else ""
    return ("line " if len(lines) == 1 else "lines ") + head + more


def _plural(n, word):
    return f"{n} {word}" + ("" if n == 1 else "s")


def clean_poses(
    t_ns,
    positions,
    quat_xyzw,
    *,
    path=None,
    line_numbers=None,
    notices=None,
    min_poses: int = 2,
    velocity_world=None,
    bias_gyro=None,
    bias_accel=None,
    repeated_stamps: str = "error",
) -> PoseTrack:
    """Validate and repair parsed poses; the one hygiene step of every pose reader.

    Parameters
    ----------
    t_ns : array_like of int, shape (N,)
        Stamps in ns, in file order.
    positions : array_like, shape (N, 3)
    quat_xyzw : array_like, shape (N, 4)
        As parsed (any norm, any sign).
    path : str or os.PathLike, optional
        Source file, for messages and :attr:`PoseTrack.path`.
    line_numbers : array_like of int, shape (N,), optional
        1-based source lines (default 1..N).
    notices : list of str, optional
        Notices gathered by the reader so far; more are appended.
    min_poses : int, default 2
        Fewest poses accepted after dropping duplicates.
    velocity_world, bias_gyro, bias_accel : array_like, shape (N, 3), optional
        Extra per-pose columns (EuRoC ground truth); checked for finiteness and kept in
        step with the poses.
    repeated_stamps : {"error", "first"}, default "error"
        What to do when a stamp repeats with a *different* pose: raise, or keep the first
        row and drop the later one(s) with a notice. Exact duplicate rows are always
        dropped with a notice.

    Returns
    -------
    PoseTrack

    Raises
    ------
    InputError
        Non-finite value, quaternion norm below :data:`ZERO_NORM_TOL`, a stamp earlier
        than its predecessor, a repeated stamp with a different pose (naming both lines),
        or fewer than ``min_poses`` poses. The message starts with ``path:line:``.

    Examples
    --------
    >>> import numpy as np
    >>> tr = clean_poses([0, 0, 5], np.zeros((3, 3)), [[0, 0, 0, 1.0]] * 2 + [[0, 0, 0, -2.0]],
    ...                  path="p.txt", line_numbers=[2, 3, 4])
    >>> tr.t_ns.tolist(), (tr.quat_xyzw + 0.0).tolist()  # sign made continuous
    ([0, 5], [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]])
    >>> tr.notices  # doctest: +NORMALIZE_WHITESPACE
    ['normalized 1 quaternion whose norm differed from 1 by more than 0.001 (worst: 2 on line 4)',
     'dropped 1 exact duplicate row (line 3)']
    """
    one_of(repeated_stamps, "repeated_stamps", ("error", "first"))
    t = np.ascontiguousarray(t_ns, dtype=np.int64)
    n = t.shape[0]
    p = as_vectors(positions, "positions", n, 3, finite=False)
    q = as_vectors(quat_xyzw, "quat_xyzw", n, 4, finite=False)
    extras = {}
    for name, v in zip(_EXTRA_FIELDS, (velocity_world, bias_gyro, bias_accel)):
        if v is not None:
            extras[name] = as_vectors(v, name, n, 3, finite=False)
    ln = np.arange(1, n + 1, dtype=np.int64) if line_numbers is None else np.asarray(line_numbers, np.int64)
    notices = [] if notices is None else list(notices)
    spath = None if path is None else str(path)

    def fail(msg, i=None):
        raise InputError(msg, path=spath, line=None if i is None else int(ln[i]))

    # 1. finiteness, in line order (so that the message names the file line)
    blocks = [("position", p), ("quaternion", q)] + [
        (name.replace("_", " "), v) for name, v in extras.items()
    ]
    bad_rows = [(int(np.flatnonzero(~np.isfinite(v).all(axis=1))[0]), what, v)
                for what, v in blocks if not np.isfinite(v).all()]
    if bad_rows:
        i, what, v = min(bad_rows, key=lambda r: r[0])
        fail(f"{what} is not finite: {_fmt_row(v[i])}", i)

    # 2. quaternion norms
    with np.errstate(over="ignore"):
        norm = np.linalg.norm(q, axis=1)
    big = ~np.isfinite(norm)  # finite components whose squares overflow (1e300): scaled first
    if big.any():
        scale = np.max(np.abs(q[big]), axis=1)
        norm[big] = scale * np.linalg.norm(q[big] / scale[:, None], axis=1)
    small = np.flatnonzero(norm < ZERO_NORM_TOL)
    if small.size:
        fail(f"quaternion has zero norm: {_fmt_row(q[small[0]])}", small[0])
    off = np.abs(norm - 1.0)
    n_off = int(np.count_nonzero(off > NORM_NOTICE_TOL))
    if n_off:
        w = int(np.argmax(off))
        notices.append(
            f"normalized {_plural(n_off, 'quaternion')} whose norm differed from 1 by more than "
            f"{NORM_NOTICE_TOL:g} (worst: {norm[w]:.6g} on line {int(ln[w])})"
        )

    # 3. order
    d = np.diff(t)
    back = np.flatnonzero(d < 0)
    if back.size:
        i = int(back[0]) + 1
        fail(
            f"timestamp {format_ns(t[i])} is earlier than {format_ns(t[i - 1])} on line "
            f"{int(ln[i - 1])}; poses must be sorted by time",
            i,
        )

    # 4. repeated stamps
    keep = np.ones(n, dtype=bool)
    rep = np.flatnonzero(d == 0) + 1
    if rep.size:
        rows = np.hstack([p, q] + list(extras.values()))
        same = np.all(rows[rep] == rows[rep - 1], axis=1)
        dup = rep[same]
        diff = rep[~same]
        if diff.size and repeated_stamps == "error":
            i = int(diff[0])
            fail(
                f"timestamp {format_ns(t[i])} repeats line {int(ln[i - 1])} with a different pose "
                "(exact duplicate rows would be dropped; this one is ambiguous)",
                i,
            )
        if dup.size:
            keep[dup] = False
            notices.append(
                f"dropped {_plural(dup.size, 'exact duplicate row')} ({_lines_text(ln[dup])})"
            )
        if diff.size:
            keep[diff] = False
            notices.append(
                f"dropped {_plural(diff.size, 'row')} repeating the timestamp of the previous row "
                f"with a different pose ({_lines_text(ln[diff])}); kept the first"
            )
        t, p, q, norm, ln = t[keep], p[keep], q[keep], norm[keep], ln[keep]
        extras = {k: v[keep] for k, v in extras.items()}

    # 5. count
    if t.shape[0] < min_poses:
        raise InputError(f"too few poses: got {t.shape[0]}, need at least {min_poses}", path=spath)

    # leave quaternions that are unit to rounding untouched, so write -> read is bit-exact
    norm = np.where(np.abs(norm - 1.0) <= 4.0 * np.finfo(float).eps, 1.0, norm)
    q = quat_make_continuous(q / norm[:, None])
    return PoseTrack(
        t_ns=t, positions=p, quat_xyzw=q, path=spath or "", notices=notices,
        line_numbers=ln, **extras,
    )


def _fmt_row(v) -> str:
    return "[" + ", ".join(f"{x:.9g}" for x in np.asarray(v).tolist()) + "]"


# ----------------------------------------------------------------------------------------
# gaps


@dataclass(frozen=True)
class Gap:
    """A pause between two consecutive poses longer than a threshold.

    Attributes
    ----------
    index : int
        Position in the track of the pose where the gap ends (the gap lies between
        ``index - 1`` and ``index``).
    start_ns, end_ns : int
        Stamps of those two poses.
    duration_s : float
        ``(end_ns - start_ns) / 1e9``.
    line : int or None
        Source line of the pose at ``index``, if known.
    """

    index: int
    start_ns: int
    end_ns: int
    duration_s: float
    line: int | None = None

    def __str__(self) -> str:
        where = f" (line {self.line})" if self.line is not None else ""
        return f"gap of {self.duration_s:.3f} s after t = {format_ns(self.start_ns)}{where}"


def find_gaps(t_ns, max_gap_s: float, line_numbers=None) -> list[Gap]:
    """Intervals between consecutive stamps longer than ``max_gap_s``.

    Parameters
    ----------
    t_ns : array_like of int, shape (N,), or PoseTrack
        Increasing stamps in ns; a :class:`PoseTrack` supplies its line numbers too.
    max_gap_s : float
        Threshold in seconds; a gap must be strictly longer.
    line_numbers : array_like of int, shape (N,), optional
        Source lines, to fill :attr:`Gap.line`.

    Returns
    -------
    list of Gap
        In time order.

    Examples
    --------
    >>> [g.index for g in find_gaps([0, 10**7, 2 * 10**7, 10**9, 10**9 + 10**7], 0.05)]
    [3]
    """
    if isinstance(t_ns, PoseTrack):
        if line_numbers is None:
            line_numbers = t_ns.line_numbers
        t_ns = t_ns.t_ns
    t = np.asarray(t_ns, dtype=np.int64)
    max_gap_s = positive_float(max_gap_s, "max_gap_s")
    d = np.diff(t)
    # compare in integer ns (the threshold rounded to the nearest ns)
    idx = np.flatnonzero(d > int(round(max_gap_s * 1e9))) + 1
    ln = None if line_numbers is None else np.asarray(line_numbers)
    return [
        Gap(
            index=int(i),
            start_ns=int(t[i - 1]),
            end_ns=int(t[i]),
            duration_s=float(t[i] - t[i - 1]) * 1e-9,
            line=None if ln is None else int(ln[i]),
        )
        for i in idx.tolist()
    ]


def split_at_gaps(track: PoseTrack, gaps) -> list[PoseTrack]:
    """Cut a track into the pieces between gaps.

    Parameters
    ----------
    track : PoseTrack
    gaps : sequence of Gap
        From :func:`find_gaps` on this track (only ``Gap.index`` is used).

    Returns
    -------
    list of PoseTrack
        ``len(gaps) + 1`` pieces in time order, each a contiguous run of poses. Pieces
        can be as short as one pose; the caller decides what to do with those.

    Examples
    --------
    >>> import numpy as np
    >>> tr = PoseTrack(np.array([0, 1, 2, 10, 11]) * 10**8, np.zeros((5, 3)),
    ...                np.tile([0., 0, 0, 1], (5, 1)))
    >>> [len(p) for p in split_at_gaps(tr, find_gaps(tr, 0.5))]
    [3, 2]
    """
    cuts = sorted({int(g.index) for g in gaps})
    if any(c <= 0 or c >= len(track) for c in cuts):
        raise ValueError(f"Expected gap indices in 1..{len(track) - 1}, got {cuts}")
    bounds = [0] + cuts + [len(track)]
    return [track.subset(slice(a, b)) for a, b in zip(bounds[:-1], bounds[1:])]


def track_from_table(table, unit: str, quat_xyzw, *, path, notices=(), min_poses: int = 2,
                     repeated_stamps: str = "error", **extras) -> PoseTrack:
    """A :class:`PoseTrack` from a pose file's :class:`~splineimu.io.timestamps.Table`.

    The common end of every pose reader: stamps parsed exactly in ``unit``, positions from
    the first three value columns, ``quat_xyzw`` (the reader's own column order already turned
    into ``x, y, z, w``) and any ``extras`` (``velocity_world``...), then :func:`clean_poses`.
    Notices about ignored extra columns and rounded stamps come first and last.
    """
    notices = list(notices)
    extra = table.extra_columns_notice()
    if extra:
        notices.insert(0, extra)
    t_ns, n_rounded = parse_stamps(table.stamps, unit, path=path, line_numbers=table.line_numbers)
    if n_rounded:
        where = "every timestamp" if n_rounded == len(t_ns) else f"{n_rounded} timestamps"
        notices.append(f"rounded {where} with more than 9 decimals to the nearest ns")
    return clean_poses(t_ns, table.values[:, 0:3], quat_xyzw, path=path, line_numbers=table.line_numbers,
                       notices=notices, min_poses=min_poses, repeated_stamps=repeated_stamps, **extras)
