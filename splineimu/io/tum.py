"""TUM trajectory files: ``timestamp tx ty tz qx qy qz qw``, one pose per line.

The format of the TUM RGB-D benchmark, used by evo, ORB-SLAM, OpenVINS and most VIO
evaluation tools: seconds (any number of decimals), position of the body in the world,
and the Hamilton quaternion ``world_R_body`` with ``w`` last.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..validation import as_quat_xyzw, as_stamps_ns, as_vectors
from .files import atomic_write_bytes
from .poses import PoseTrack, track_from_table
from .tables import TableWriter, format_table_chunks, write_table
from .timestamps import read_table

__all__ = ["read_tum", "write_tum", "write_scene_tum", "TumWriter", "TUM_COLUMNS", "TUM_HEADER"]

TUM_COLUMNS = ("timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw")
TUM_HEADER = "# timestamp tx ty tz qx qy qz qw"

#: poses a scene's TUM file is evaluated and written in at a time (bounded memory)
SCENE_TUM_PIECE = 1 << 18


def read_tum(path, min_poses: int = 2, repeated_stamps: str = "error") -> PoseTrack:
    """Read a TUM trajectory file.

    Parameters
    ----------
    path : str or os.PathLike
        Text file with lines ``t x y z qx qy qz qw``, separated by whitespace (or by
        commas, if the first data line has one). Blank lines and lines starting with
        ``#`` are skipped, and so is a first line without numbers (a header). Columns
        after the 8th are ignored with one notice (OpenVINS's ``udel_gore.txt`` has 6
        covariance columns).
    min_poses : int, default 2
        Fewest poses accepted.
    repeated_stamps : {"error", "first"}, default "error"
        A stamp that repeats with a different pose is an error, or (``"first"``) the
        later row is dropped with a notice. Exact duplicate rows are always dropped.

    Returns
    -------
    PoseTrack
        With ``notices`` about anything ignored or repaired.

    Raises
    ------
    InputError
        Missing file, fewer than 8 columns, a non-numeric or non-finite value, a zero
        quaternion, unsorted stamps, an ambiguous repeated stamp, or too few poses; the
        message is ``"file:line: problem"``. Before any line is read as a pose: a file that
        looks like a EuRoC ground-truth or IMU csv or a KITTI pose file, or whose header
        names the quaternion in another order than ``qx qy qz qw``
        (:func:`splineimu.io.sniff.check_tum_layout`). Stamps that are not seconds: beyond
        the year 5000, or integers stepping by 1000 s or more (ns or us counted from 0).

    Notes
    -----
    The stamp is parsed from its text to integer nanoseconds exactly
    (``"1305031102.175304"`` -> ``1305031102175304000``); up to 9 decimals are kept
    exactly, more are rounded half-to-even to the ns (one notice), and exponent notation
    (``1.706282470098386526e+09``) is accepted. The other columns are parsed in bulk by
    ``numpy.loadtxt`` (correctly rounded); only a file that fails the bulk parse is
    scanned line by line, to accept ragged extra columns or to name the first bad line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "poses.txt"
    >>> _ = p.write_text("# t x y z qx qy qz qw\\n"
    ...                  "1305031102.175304 0 0 0 0 0 0 1\\n"
    ...                  "1305031102.185304 1 0 0 0 0 0 1\\n")
    >>> tr = read_tum(p)
    >>> tr.t_ns.tolist(), tr.line_numbers.tolist()
    ([1305031102175304000, 1305031102185304000], [2, 3])
    """
    from ..errors import InputError
    from .sniff import (
        add_format_hint,
        check_integer_seconds_step,
        check_seconds_magnitude,
        check_tum_layout,
        relative_seconds_notice,
    )

    has_header = check_tum_layout(path)  # EuRoC, KITTI, a header with qw first: refused before reading
    try:
        table = read_table(path, n_cols=8, column_names=TUM_COLUMNS, sep="auto", allow_header=has_header)
        convert = "TUM stamps are decimal seconds: convert the column"
        check_seconds_magnitude(table.stamps[0], path=path, line=int(table.line_numbers[0]), advice=convert)
        check_integer_seconds_step(table.stamps, path=path, line=int(table.line_numbers[0]), advice=convert)
        track = track_from_table(table, "s", table.values[:, 3:7], path=path, min_poses=min_poses,
                                 repeated_stamps=repeated_stamps)
    except InputError as exc:
        raise add_format_hint(exc, path, "tum") from None
    note = relative_seconds_notice(track.t_ns)
    if note is not None:
        track.notices.append(note)
    return track


def _tum_table(t_ns, positions, quat_xyzw):
    """Stamps and the ``(N, 7)`` value columns of TUM lines, checked."""
    t = as_stamps_ns(t_ns, increasing=False)
    n = t.shape[0]
    return t, np.hstack([as_vectors(positions, "positions", n), as_quat_xyzw(quat_xyzw, "quat_xyzw", n)])


def write_tum(path, t_ns, positions, quat_xyzw, header: bool = True):
    """Write a TUM trajectory file atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file (replaced if it exists; written to a temporary file beside it first).
    t_ns : array_like of int, shape (N,)
        Stamps in ns, written as seconds with exactly 9 decimals (``"%d.%09d"``).
    positions : array_like, shape (N, 3)
    quat_xyzw : array_like, shape (N, 4)
        Written as given, ``qx qy qz qw``.
    header : bool, default True
        Start with the comment line ``# timestamp tx ty tz qx qy qz qw``.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    InputError
        (a ``ValueError``) Shapes that do not match, non-finite values, a zero quaternion.

    See Also
    --------
    TumWriter : the same lines, written piece by piece.

    Notes
    -----
    Values are written losslessly (``float(text) == value``): the shortest decimal of up
    to 15 significant digits that reads back exactly, else 17 digits; see
    :func:`splineimu.io.tables.format_table`.

    Examples
    --------
    A round trip gives back the exact stamps and values:

    >>> import tempfile, pathlib, numpy as np
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "out.tum"
    >>> t_ns = [1305031102175304000, 1305031102185304001]
    >>> q = [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, np.sin(0.05), np.cos(0.05)]]
    >>> _ = write_tum(p, t_ns, [[0.1, 2.0, -3.5], [0.2, 2.0, -3.5]], q)
    >>> print(p.read_text().splitlines()[1])
    1305031102.175304000 0.1 2 -3.5 0 0 0 1
    >>> back = read_tum(p)
    >>> back.t_ns.tolist() == t_ns, back.positions[1].tolist(), bool((back.quat_xyzw == q).all())
    (True, [0.2, 2.0, -3.5], True)
    """
    t, table = _tum_table(t_ns, positions, quat_xyzw)
    return write_table(path, t, table, TUM_HEADER if header else None, sep=" ", stamp="s")


class TumWriter(TableWriter):
    """A TUM trajectory file written piece by piece, for records too long to hold at once.

    The same lines as :func:`write_tum`, into a new file (created exclusively; meant for an
    :class:`~splineimu.io.files.OutputFolder`'s temporary folder, which makes the output
    atomic). Pieces are formatted in background threads; :meth:`close` (or the end of a
    ``with`` block) writes the rest.

    Parameters
    ----------
    path : str or os.PathLike
        New file.
    header : bool, default True
        Start with ``# timestamp tx ty tz qx qy qz qw``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "poses.tum"
    >>> with TumWriter(p) as w:
    ...     w.write_poses([0], [[0.0, 0.0, 1.0]], [[0.0, 0.0, 0.0, 1.0]])
    ...     w.write_poses([5_000_000], [[0.5, 0.0, 1.0]], [[0.0, 0.0, 0.0, 1.0]])
    >>> print(p.read_text(), end="")
    # timestamp tx ty tz qx qy qz qw
    0.000000000 0 0 1 0 0 0 1
    0.005000000 0.5 0 1 0 0 0 1
    """

    def __init__(self, path, header: bool = True):
        super().__init__(path, TUM_HEADER if header else None, sep=" ", stamp="s")

    def write_poses(self, t_ns, positions, quat_xyzw) -> None:
        """Append poses (arguments as for :func:`write_tum`)."""
        self.write(*_tum_table(t_ns, positions, quat_xyzw))


def write_scene_tum(scene, path, rate_hz: float) -> Path:
    """Write a scene's poses at a uniform rate as a TUM trajectory file, atomically.

    Parameters
    ----------
    scene : Scene
        Any motion source with ``origin_ns``, ``t_min_s``, ``t_max_s`` and ``pose``.
    path : str or os.PathLike
        Output file; replaced if it exists (written to a temporary file in the same
        directory, then ``os.replace``); missing parent folders are made.
    rate_hz : float
        Sample rate [Hz]. Stamps are ``origin_ns + round(t_min_s 1e9) + round(k 1e9 / rate_hz)``
        (:func:`splineimu.timegrid.uniform_stamps_ns`, the grid of :meth:`Scene.sample_times_ns`).

    Returns
    -------
    pathlib.Path
        The written path.

    Notes
    -----
    Lines are ``timestamp tx ty tz qx qy qz qw`` with the absolute timestamp printed
    exactly from integer nanoseconds as ``"%d.%09d"`` (seconds.nanoseconds) and
    quaternions made sign-continuous along time.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from splineimu.scenes import make_scene
    >>> p = write_scene_tum(make_scene("static", duration_s=1.0), pathlib.Path(tempfile.mkdtemp()) / "s.tum", 2)
    >>> print(p.read_text(), end="")
    # timestamp tx ty tz qx qy qz qw
    0.000000000 0 0 0 0 0 0 1
    0.500000000 0 0 0 0 0 0 1
    1.000000000 0 0 0 0 0 0 1
    """
    from ..lie import quat_make_continuous
    from ..timegrid import uniform_stamps_ns

    origin = int(scene.origin_ns)
    t_ns = uniform_stamps_ns(origin + int(round(scene.t_min_s * 1e9)), origin + int(round(scene.t_max_s * 1e9)),
                             rate_hz)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)

    def text():  # evaluated and formatted piece by piece: a 10 kHz hour held ~390 bytes per pose (14 GB)
        yield (TUM_HEADER + "\n").encode()
        last = np.empty((0, 4))
        for i0 in range(0, t_ns.size, SCENE_TUM_PIECE):
            t = t_ns[i0:i0 + SCENE_TUM_PIECE]
            pos, quat = scene.pose(np.clip(scene.t_s_from_ns(t), scene.t_min_s, scene.t_max_s))
            quat = quat_make_continuous(np.vstack([last, quat]))[last.shape[0]:]  # signs continue across pieces
            last = quat[-1:]
            yield from format_table_chunks(*_tum_table(t, pos, quat), sep=" ", stamp="s")

    return atomic_write_bytes(path, text())
