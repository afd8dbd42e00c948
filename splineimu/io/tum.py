"""TUM trajectory files: ``timestamp tx ty tz qx qy qz qw``, one pose per line.

The format of the TUM RGB-D benchmark, used by evo, ORB-SLAM, OpenVINS and most VIO
evaluation tools: seconds (any number of decimals), position of the body in the world,
and the Hamilton quaternion ``world_R_body`` with ``w`` last.
"""

from __future__ import annotations

import itertools

import numpy as np

from .output import atomic_write_bytes, format_table_chunks
from .poses import PoseTrack, clean_poses
from .timestamps import parse_stamps, read_table

__all__ = ["read_tum", "write_tum", "TUM_COLUMNS", "TUM_HEADER"]

TUM_COLUMNS = ("timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw")
TUM_HEADER = "# timestamp tx ty tz qx qy qz qw"


def read_tum(path, min_poses: int = 2, repeated_stamps: str = "error") -> PoseTrack:
    """Read a TUM trajectory file.

    Parameters
    ----------
    path : str or os.PathLike
        Text file with lines ``t x y z qx qy qz qw``, separated by whitespace (or by
        commas, if the first data line has one). Blank lines and lines starting with
        ``#`` are skipped. Columns after the 8th are ignored with one notice (OpenVINS's
        ``udel_gore.txt`` has 6 covariance columns).
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
        message is ``"file:line: problem"``.

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
    table = read_table(path, n_cols=8, column_names=TUM_COLUMNS, sep="auto")
    notices = []
    extra = table.extra_columns_notice()
    if extra:
        notices.append(extra)
    t_ns, n_rounded = parse_stamps(table.stamps, "s", path=path, line_numbers=table.line_numbers)
    if n_rounded:
        where = "every timestamp" if n_rounded == len(t_ns) else f"{n_rounded} timestamps"
        notices.append(f"rounded {where} with more than 9 decimals to the nearest ns")
    v = table.values
    return clean_poses(
        t_ns,
        v[:, 0:3],
        v[:, 3:7],
        path=path,
        line_numbers=table.line_numbers,
        notices=notices,
        min_poses=min_poses,
        repeated_stamps=repeated_stamps,
    )


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
        ``path``.

    Raises
    ------
    ValueError
        Shapes that do not match or non-finite values.

    Notes
    -----
    Values are written losslessly (``float(text) == value``): the shortest decimal of up
    to 15 significant digits that reads back exactly, else 17 digits; see
    :func:`splineimu.io.output.format_table`.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "out.tum"
    >>> _ = write_tum(p, [1305031102175304000], [[0.1, 2.0, -3.5]], [[0.0, 0.0, 0.0, 1.0]])
    >>> print(p.read_text(), end="")
    # timestamp tx ty tz qx qy qz qw
    1305031102.175304000 0.1 2 -3.5 0 0 0 1
    """
    t = np.asarray(t_ns)
    n = t.shape[0] if t.ndim == 1 else -1
    p = np.asarray(positions, dtype=np.float64)
    q = np.asarray(quat_xyzw, dtype=np.float64)
    if p.shape != (n, 3):
        raise ValueError(f"Expected `positions` to have shape ({n}, 3), got {p.shape}")
    if q.shape != (n, 4):
        raise ValueError(f"Expected `quat_xyzw` to have shape ({n}, 4), got {q.shape}")
    body = format_table_chunks(t, np.hstack([p, q]), sep=" ", stamp="s")
    head = (TUM_HEADER + "\n").encode() if header else b""
    return atomic_write_bytes(path, itertools.chain([head], body))
