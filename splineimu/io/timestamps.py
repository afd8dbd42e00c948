"""Exact timestamps and the shared text-table scanner of the readers.

Timestamps are parsed from their decimal text straight to integer nanoseconds, never
through a float: ``"1305031102.175304"`` is ``1305031102175304000`` exactly, and EuRoC's
``1403715524907143168`` (1.4e18 ns, beyond float64's 2**53) keeps every digit.

:func:`read_table` is the scanner behind :func:`splineimu.io.tum.read_tum`,
:func:`splineimu.io.euroc.read_euroc_groundtruth` and :func:`read_timestamps`: a bulk
numpy parse for clean files, with a line-by-line pass that is used only when the bulk
parse fails, to either accept a ragged file or name the first bad line.
"""

from __future__ import annotations

import decimal
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..validation import one_of

__all__ = ["parse_stamps", "read_timestamps", "read_table", "Table", "check_line_lengths", "MAX_LINE_BYTES"]

#: Longest line a text table may have (a data row is some hundred bytes; a longer "line" is
#: a binary or foreign file, refused before it is read whole).
MAX_LINE_BYTES = 1 << 20

_NS_PER_S = 1_000_000_000
_INT64_MAX = np.iinfo(np.int64).max
_DEC_CONTEXT = decimal.Context(
    prec=80, rounding=decimal.ROUND_HALF_EVEN, Emax=decimal.MAX_EMAX, Emin=decimal.MIN_EMIN
)


def _is_integer_text(s: str) -> bool:
    body = s[1:] if s[:1] in "+-" else s
    return body.isascii() and body.isdigit()


def _slow_stamp(s: str, unit: str, path, line):
    """One stamp through Decimal. Returns (ns, rounded?)."""
    try:
        d = decimal.Decimal(s)
    except decimal.InvalidOperation:
        raise InputError(f"timestamp is not a number: {s!r}", path=path, line=line) from None
    if not d.is_finite():
        raise InputError(f"timestamp is not a finite number: {s!r}", path=path, line=line)
    out_of_range = InputError(
        f"timestamp {s!r} is out of range (|t| must stay below 2**63 ns, about 292 years)",
        path=path, line=line,
    )
    if d.adjusted() > 19:
        raise out_of_range
    if unit == "ns":
        if d != d.to_integral_value():
            raise InputError(
                f"timestamp {s!r} is not an integer number of nanoseconds", path=path, line=line
            )
        ns = int(d)
        rounded = False
    else:
        scaled = _DEC_CONTEXT.multiply(d, decimal.Decimal(_NS_PER_S))
        q = scaled.to_integral_value(rounding=decimal.ROUND_HALF_EVEN, context=_DEC_CONTEXT)
        ns = int(q)
        rounded = q != scaled
    if abs(ns) > _INT64_MAX:
        raise out_of_range
    return ns, rounded


def parse_stamps(strings, unit: str = "s", *, path=None, line_numbers=None):
    """Parse timestamp strings exactly to integer nanoseconds.

    Parameters
    ----------
    strings : sequence of str, length N
        Decimal text such as ``"1305031102.175304"``, ``"1403715524907143168"`` or
        ``"1.5e9"``.
    unit : {"s", "ns"}, default "s"
        What the numbers are. Seconds may carry up to 9 decimals exactly; more decimals
        are rounded (half to even) to the nanosecond and counted. Nanoseconds must be
        integers.
    path : str or os.PathLike, optional
        File name for error messages.
    line_numbers : array_like of int, shape (N,), optional
        1-based source line of each string, for error messages.

    Returns
    -------
    t_ns : numpy.ndarray of int64, shape (N,)
        The stamps.
    n_rounded : int
        How many seconds-stamps had more than 9 decimals and were rounded.

    Raises
    ------
    InputError
        A stamp that is not a number, not finite, out of the int64 range, or (with
        ``unit="ns"``) not an integer; the message names the line.

    Notes
    -----
    Plain ``digits[.digits]`` strings (the usual case) are converted with vectorized
    integer arithmetic on the two halves around the point; anything else (a sign, an
    exponent, more than 9 decimals, a leading point) goes through :class:`decimal.Decimal`
    at 80 significant digits, which is exact for any realistic stamp.

    Examples
    --------
    >>> parse_stamps(["1305031102.175304", "1.5e9"])[0].tolist()
    [1305031102175304000, 1500000000000000000]
    >>> parse_stamps(["1403715524907143168"], unit="ns")[0].tolist()
    [1403715524907143168]
    """
    one_of(unit, "unit", ("s", "ns"))
    strings = list(strings)
    n = len(strings)
    t_ns = np.zeros(n, dtype=np.int64)
    if n == 0:
        return t_ns, 0
    arr = np.array(strings, dtype=str)
    ip, dot, fp = np.strings.partition(arr, ".")
    ilen = np.strings.str_len(ip)
    flen = np.strings.str_len(fp)
    fast = np.strings.isdecimal(ip) & (ilen >= 1)
    if unit == "s":
        fast &= (ilen <= 10) & (flen <= 9) & ((flen == 0) | np.strings.isdecimal(fp))
    else:
        fast &= (ilen <= 18) & (np.strings.str_len(dot) == 0)
    if not "".join(strings).isascii():  # isdecimal accepts non-ASCII digits: slow path
        fast &= np.array([s.isascii() for s in strings])
    idx = np.flatnonzero(fast)
    if idx.size:
        whole = _digits_value(ip[idx])
        if unit == "s":
            ok = whole <= _INT64_MAX // _NS_PER_S - 1  # no overflow in whole * 1e9 + frac
            fast[idx[~ok]] = False
            idx, whole = idx[ok], whole[ok]
            if idx.size:
                frac = _digits_value(fp[idx], width=9)  # the decimals, padded with zeros to ns
                t_ns[idx] = whole * _NS_PER_S + frac
        else:
            t_ns[idx] = whole
    n_rounded = 0
    for i in np.flatnonzero(~fast).tolist():
        line = None if line_numbers is None else int(line_numbers[i])
        ns, rounded = _slow_stamp(strings[i].strip(), unit, path, line)
        t_ns[i] = ns
        n_rounded += bool(rounded)
    return t_ns, n_rounded


def _digits_value(a, width=None):
    """int64 values of the strings of ASCII digits ``a`` (a numpy unicode array, at most 18
    digits each), read from their code points (``astype(np.int64)``: 0.25 us a string); with
    ``width``, each is first padded on the right with zeros to that many digits."""
    n = a.size
    w = a.dtype.itemsize // 4
    codes = np.ascontiguousarray(a).view(np.uint32).reshape(n, w) if w else np.zeros((n, 0), np.uint32)
    out = np.zeros(n, dtype=np.int64)
    for i in range(w if width is None else width):
        c = codes[:, i].astype(np.int64) if i < w else np.zeros(n, dtype=np.int64)
        digit = c != 0  # numpy pads shorter strings with NUL
        out = np.where(digit, out * 10 + (c - 48), out if width is None else out * 10)
    return out


# ----------------------------------------------------------------------------------------
# the text-table scanner


@dataclass
class Table:
    """Result of :func:`read_table`.

    Attributes
    ----------
    stamps : list of str, length N
        The first field of every data row, stripped.
    values : numpy.ndarray, shape (N, n_cols - 1)
        Columns 2 .. n_cols as float64 (no finiteness check yet).
    line_numbers : numpy.ndarray of int64, shape (N,)
        1-based source line of every row.
    n_fields : int
        Most fields seen on a row.
    n_rows_with_extra : int
        Rows with more than ``n_cols`` fields (their extra fields are ignored).
    header_line : int or None
        The line that was skipped as a non-numeric header, if any.
    n_cols : int
        Columns read (``values`` has ``n_cols - 1``).
    """

    stamps: list
    values: np.ndarray
    line_numbers: np.ndarray
    n_fields: int
    n_rows_with_extra: int
    header_line: int | None = None
    n_cols: int = 0

    def extra_columns_notice(self) -> str | None:
        """One-line notice about ignored columns, or None."""
        n_cols = self.n_cols
        if self.n_rows_with_extra == 0:
            return None
        cols = f"column {n_cols + 1}" if self.n_fields == n_cols + 1 else (
            f"columns {n_cols + 1}-{self.n_fields}"
        )
        where = "every line" if self.n_rows_with_extra == len(self.stamps) else (
            f"{self.n_rows_with_extra} of {len(self.stamps)} lines"
        )
        return f"ignored {cols} on {where}"


def check_line_lengths(path, max_bytes: int = MAX_LINE_BYTES) -> None:
    """Refuse a file with a line longer than ``max_bytes``, without reading that line whole.

    The file is mapped and only probed: every aligned block of ``max_bytes // 2`` bytes must
    hold a newline (the search stops at the first), so clean files cost a few microseconds
    per megabyte; only a block without one is looked at closely.

    Raises
    ------
    InputError
        The file is missing, a folder, unreadable, or has such a line (its number is given).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "t.txt"
    >>> _ = p.write_text("1 2\\n" + "x" * 100 + "\\n")
    >>> check_line_lengths(p, max_bytes=64)
    Traceback (most recent call last):
    ...
    splineimu.errors.InputError: ...t.txt:2: line longer than 64 bytes: not a text table of this kind
    """
    import mmap

    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size <= max_bytes:
                return
            with mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as mm:
                _probe_lines(mm, size, max_bytes, path)
    except FileNotFoundError:
        raise InputError("file not found", path=path) from None
    except IsADirectoryError:
        raise InputError("is a folder, expected a file", path=path) from None
    except PermissionError:
        raise InputError("permission denied", path=path) from None


def _probe_lines(mm, size, max_bytes, path):
    block = max(max_bytes // 2, 1)
    for start in range(0, size, block):
        end = min(start + block, size)
        if end - start < block or mm.find(b"\n", start, end) >= 0:
            continue
        first = mm.rfind(b"\n", 0, start) + 1  # the line holding this block starts here
        nxt = mm.find(b"\n", first, first + max_bytes + 1)
        if nxt < 0 and size - first > max_bytes:
            line = mm[:first].count(b"\n") + 1
            raise InputError(f"line longer than {max_bytes} bytes: not a text table of this kind",
                             path=path, line=line)


def _read_lines(path) -> list[str]:
    check_line_lengths(path)  # also: missing, a folder, no permission (one-line errors)
    raw = Path(path).read_bytes()
    if b"\x00" in raw[:4096]:
        raise InputError("looks like a binary file, expected text", path=path)
    text = raw.decode("utf-8-sig", errors="replace")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines


def _split(line: str, sep: str | None) -> list[str]:
    if sep is None:
        return line.split()
    fields = [f.strip() for f in line.split(sep)]
    while len(fields) > 1 and fields[-1] == "":  # tolerate a trailing separator
        fields.pop()
    return fields


def _looks_numeric(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True


def read_table(
    path,
    *,
    n_cols: int,
    column_names=None,
    sep: str | None = None,
    allow_header: bool = False,
    wide_cols: int | None = None,
) -> Table:
    """Scan a numeric text table: comments, a header, ragged extra columns, bad lines.

    Lines that are blank or whose first non-blank character is ``#`` are skipped. With
    ``allow_header`` the first remaining line is skipped too if its first field is not a
    number (a csv header without ``#``).

    Parameters
    ----------
    path : str or os.PathLike
        The file (UTF-8; a byte-order mark is ignored; ``\\r\\n`` endings are fine).
    n_cols : int
        Fields every row must have. Fields after ``n_cols`` are ignored (and counted).
    column_names : sequence of str, optional
        Names of the ``n_cols`` fields, for error messages.
    sep : str or None, default None
        Field separator; None splits on runs of whitespace, ``","`` on commas (with spaces
        around fields allowed, and a trailing comma tolerated), ``"auto"`` picks ``","``
        if the first data line has a comma, else whitespace.
    allow_header : bool, default False
        Skip one non-numeric first data line.
    wide_cols : int, optional
        If the first data row has at least this many fields, read ``wide_cols`` columns
        instead of ``n_cols`` (EuRoC: 8 pose columns or the 17-column ground truth).
        ``Table.n_cols`` says which.

    Returns
    -------
    Table

    Raises
    ------
    InputError
        The file cannot be read, has no data rows, a row has fewer than ``n_cols`` fields,
        or a field among the first ``n_cols`` (after the first) is not a number. The
        message names the first bad line. The first field (the stamp) is checked later
        by :func:`parse_stamps`.
    """
    names = list(column_names) if column_names is not None else [f"column {i + 1}" for i in range(n_cols)]
    lines = _read_lines(path)
    data_idx = [i for i, ln in enumerate(lines) if (s := ln.lstrip()) and s[0] != "#"]
    if sep == "auto":
        sep = "," if data_idx and "," in lines[data_idx[0]] else None
    header_line = None
    if allow_header and data_idx:
        first = _split(lines[data_idx[0]], sep)
        if not first or not _looks_numeric(first[0]):
            header_line = data_idx[0] + 1
            data_idx = data_idx[1:]
    if not data_idx:
        raise InputError("no data rows (only comments, blank lines or a header)", path=path)
    rows = [lines[i] for i in data_idx]
    if wide_cols is not None and len(_split(rows[0], sep)) >= wide_cols:
        n_cols = wide_cols
    names = names + [f"column {i + 1}" for i in range(len(names), n_cols)]
    line_numbers = np.asarray(data_idx, dtype=np.int64) + 1

    table = _bulk(rows, n_cols, sep, line_numbers)
    if table is None:
        table = _line_by_line(rows, n_cols, names, sep, line_numbers, path)
    table.header_line = header_line
    table.n_cols = n_cols
    return table


def _bulk(rows, n_cols, sep, line_numbers) -> Table | None:
    """numpy.loadtxt over every field; None if the rows are ragged or not all numeric."""
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            # all fields as float (the stamps are re-parsed exactly from their text)
            vals = np.loadtxt(rows, delimiter=sep, comments=None, ndmin=2, dtype=np.float64)
    except (ValueError, UserWarning):
        return None
    if vals.shape[1] < n_cols:
        return None
    stamps = [_first_field(r, sep) for r in rows]
    extra = vals.shape[1] > n_cols
    return Table(
        stamps=stamps,
        values=np.ascontiguousarray(vals[:, 1:n_cols]),
        line_numbers=line_numbers,
        n_fields=vals.shape[1],
        n_rows_with_extra=len(rows) if extra else 0,
    )


def _line_by_line(rows, n_cols, names, sep, line_numbers, path) -> Table:
    n = len(rows)
    values = np.empty((n, n_cols - 1))
    stamps = []
    n_fields = 0
    n_extra = 0
    for r, (row, ln) in enumerate(zip(rows, line_numbers.tolist())):
        f = _split(row, sep)
        if len(f) < n_cols:
            raise InputError(
                f"expected {n_cols} columns ({' '.join(names[:n_cols])}), got {len(f)}", path=path, line=ln
            )
        if len(f) > n_cols:
            n_extra += 1
        n_fields = max(n_fields, len(f))
        stamps.append(f[0])
        for j in range(1, n_cols):
            try:
                values[r, j - 1] = float(f[j])
            except ValueError:
                raise InputError(
                    f"column {j + 1} ({names[j]}) is not a number: {f[j]!r}", path=path, line=ln
                ) from None
    return Table(stamps=stamps, values=values, line_numbers=line_numbers, n_fields=n_fields,
                 n_rows_with_extra=n_extra)


def _check_increasing(t_ns, line_numbers, path, what="timestamps"):
    d = np.diff(t_ns)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        rel = "repeats" if d[i - 1] == 0 else "is earlier than"
        raise InputError(
            f"{what} must be strictly increasing: {format_ns(t_ns[i])} {rel} "
            f"{format_ns(t_ns[i - 1])} on line {int(line_numbers[i - 1])}",
            path=path,
            line=int(line_numbers[i]),
        )


def format_ns(t_ns) -> str:
    """Seconds text of an integer-ns stamp, exact: ``1305031102175304000 -> '1305031102.175304000'``."""
    t = int(t_ns)
    sign = "-" if t < 0 else ""
    s, f = divmod(abs(t), _NS_PER_S)
    return f"{sign}{s}.{f:09d}"


def read_timestamps(path, unit: str | None = None) -> np.ndarray:
    """Read the first column of a csv or text file as integer-nanosecond stamps.

    Use it for the sample times of a synthesized IMU, e.g. a real EuRoC
    ``imu0/data.csv`` (its header and other columns are ignored).

    Parameters
    ----------
    path : str or os.PathLike
        Text file. Blank lines and lines starting with ``#`` are skipped, and so is one
        non-numeric header line. Fields are separated by commas if the first data line
        has one, else by whitespace.
    unit : {None, "ns", "s"}, default None
        Unit of the numbers. ``None`` decides from the text: if any stamp has a decimal
        point or an exponent, all are seconds (parsed exactly, as in
        :func:`parse_stamps`); if all are plain integers they are nanoseconds, and stamps
        that then step by less than a microsecond are refused as what they look like
        (integer seconds such as ``0 1 2`` need ``unit="s"``).

    Returns
    -------
    numpy.ndarray of int64, shape (N,)
        Strictly increasing stamps in ns.

    Raises
    ------
    InputError
        Unreadable file, no rows, a stamp that is not a number, stamps that are not
        strictly increasing (naming the line and the previous one), or integer stamps
        that step by less than 1 us (seconds or milliseconds read as nanoseconds).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "t.csv"
    >>> _ = p.write_text("#timestamp [ns],w_x\\n1403715523912140000,0.1\\n1403715523917140000,0.2\\n")
    >>> read_timestamps(p).tolist()
    [1403715523912140000, 1403715523917140000]
    """
    one_of(unit, "unit", (None, "ns", "s"))
    table = _read_first_column(path)
    stamps = table.stamps
    guessed = unit is None
    if unit is None:
        unit = "ns" if all(_is_integer_text(s) for s in stamps) else "s"
    t_ns, _ = parse_stamps(stamps, unit, path=path, line_numbers=table.line_numbers)
    _check_increasing(t_ns, table.line_numbers, path)
    if guessed and unit == "ns":
        from .sniff import check_ns_spacing

        check_ns_spacing(t_ns, path=path, advice="integer stamps are read as nanoseconds: give nanoseconds, "
                         "or seconds with a decimal point (1.0)")
    return t_ns


def _read_first_column(path) -> Table:
    """The first field of every data line (other fields unchecked)."""
    lines = _read_lines(path)
    data_idx = [i for i, ln in enumerate(lines) if (s := ln.lstrip()) and s[0] != "#"]
    sep = "," if data_idx and "," in lines[data_idx[0]] else None
    if data_idx and not _looks_numeric(_first_field(lines[data_idx[0]], sep)):
        data_idx = data_idx[1:]
    if not data_idx:
        raise InputError("no data rows (only comments, blank lines or a header)", path=path)
    stamps = [_first_field(lines[i], sep) for i in data_idx]
    ln = np.asarray(data_idx, dtype=np.int64) + 1
    return Table(stamps=stamps, values=np.empty((len(stamps), 0)), line_numbers=ln,
                 n_fields=1, n_rows_with_extra=0)


def _first_field(line: str, sep: str | None) -> str:
    if sep is None:
        return line.split(None, 1)[0]
    return line.split(sep, 1)[0].strip()
