"""What a file looks like: the format and the stamp unit, for messages when the wrong reader or unit is used.

The readers call these when something does not fit, so that the message says what the file
seems to be and what to use instead:

- :func:`guess_format` looks at the first data lines (a few kB, never the whole file) and
  names the likely format: a TUM trajectory, a EuRoC ground truth, a EuRoC IMU csv, a KITTI
  pose file;
- :func:`check_tum_layout` is the TUM reader's first step: it refuses a file that looks like
  another format (EuRoC, KITTI) or whose header names the quaternion in another order than
  ``qx qy qz qw``, before anything is read as a TUM line;
- :func:`format_hint` is the sentence a reader appends to its error when the file looks
  like another format than the one it reads;
- :func:`check_ns_spacing` refuses integer-nanosecond stamps whose spacing is below a
  microsecond (seconds or milliseconds written in a nanosecond column);
- :func:`check_seconds_magnitude` refuses second stamps beyond the year 5000 (milli-, micro-
  or nanoseconds in a TUM file), :func:`check_integer_seconds_step` integer second stamps
  that step by 1000 s or more (the same, counted from 0);
- :func:`relative_seconds_notice` words a notice for decimal stamps counted from 0 that step by a
  second or more (milliseconds written as decimals read as seconds).

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "poses.txt"
>>> _ = p.write_text("# t x y z qx qy qz qw\\n1700000000.0 0 0 0 0 0 0 1\\n")
>>> guess_format(p)
'tum'
>>> format_hint(p, "euroc_gt")
'the file looks like a TUM trajectory (t x y z qx qy qz qw, seconds): use `splineimu from-tum`'
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import InputError

__all__ = ["guess_format", "format_hint", "add_format_hint", "check_tum_layout", "check_ns_spacing",
           "check_seconds_magnitude", "check_integer_seconds_step", "relative_seconds_notice", "FORMATS"]

#: Format key -> (description, what to use).
FORMATS = {
    "tum": ("a TUM trajectory (t x y z qx qy qz qw, seconds)", "use `splineimu from-tum`"),
    "euroc_gt": ("a EuRoC ground-truth csv (ns, p xyz, q wxyz, ...)", "use `splineimu from-euroc`"),
    "euroc_imu": ("a EuRoC IMU csv (ns, gyro xyz, accel xyz)",
                  "it is IMU data, not poses: give it to integrate, allan or calibrate, or as --timestamps"),
    "kitti": ("a KITTI pose file (12 numbers a line: the 3x4 matrix [R | t], no timestamps)",
              "write TUM lines (timestamp tx ty tz qx qy qz qw) with the frames' times (KITTI's times.txt)"),
}

_HEAD_BYTES = 16384


def _head(path) -> list[tuple[int, str]]:
    """``(line number, text)`` of the whole lines in the first :data:`_HEAD_BYTES` of ``path``."""
    try:
        with open(path, "rb") as f:
            head = f.read(_HEAD_BYTES)
    except OSError:
        return []
    lines = head.decode("utf-8-sig", errors="replace").splitlines()
    if len(head) == _HEAD_BYTES:
        lines = lines[:-1]
    return list(enumerate(lines, start=1))


def _split_data(lines, n=5):
    """The first ``n`` data lines (stripped) and the header text (comment or ``_RS_`` lines among the first 3)."""
    header = " ".join(ln for _, ln in lines[:3] if ln.lstrip().startswith("#") or "_RS_" in ln)
    data = [ln.strip() for _, ln in lines if ln.strip() and not ln.lstrip().startswith("#") and "_RS_" not in ln]
    return data[:n], header


def _numbers(fields):
    try:
        return [float(f) for f in fields]
    except ValueError:
        return None


def _integers(texts):
    """The ints of ``texts`` if every one is a plain (signed) ASCII integer, else None."""
    if not all(t[1:].isdigit() if t[:1] in "+-" else t.isdigit() for t in texts) or not "".join(texts).isascii():
        return None
    return [int(t) for t in texts]


def _seconds_like(stamps) -> bool:
    """Integer stamps that read as seconds: below 1e11 (the year 5000) and stepping by less than 1000 s."""
    return max(abs(v) for v in stamps) < 1e11 and (len(stamps) < 2 or float(np.median(np.diff(stamps))) < 1000)


def _is_pose_matrix(row) -> bool:
    """Whether 12 numbers are a KITTI line: ``[R | t]`` row by row, ``R`` a rotation (to 1e-3)."""
    m = np.asarray(row, dtype=np.float64).reshape(3, 4)
    r = m[:, :3]
    return bool(np.abs(r @ r.T - np.eye(3)).max() < 1e-3 and np.linalg.det(r) > 0)


def _guess(data, header) -> str | None:
    if not data:
        return None
    comma = "," in data[0]
    rows = [[f.strip() for f in (ln.split(",") if comma else ln.split())] for ln in data]
    nums = [_numbers(r) for r in rows]
    if any(v is None for v in nums):
        return None
    n = min(len(r) for r in rows)
    int_stamps = _integers([r[0] for r in rows])
    # first: the ground truth's bias columns b_w_RS_S_x, b_a_RS_S_x contain the IMU's names
    if "p_RS_R" in header or "q_RS" in header:
        return "euroc_gt"
    if "w_RS_S" in header or "a_RS_S" in header:
        return "euroc_imu"
    if comma and int_stamps is not None:
        if n == 7:
            return "euroc_imu"
        if n >= 9 or (n == 8 and not _seconds_like(int_stamps)):  # 8 columns and seconds: a TUM csv
            return "euroc_gt"
    if n == 12 and max(len(r) for r in rows) == 12 and all(_is_pose_matrix(v) for v in nums):
        return "kitti"
    if not comma and n >= 8 and int_stamps is None:
        return "tum"
    return None


def guess_format(path) -> str | None:
    """``"tum"``, ``"euroc_gt"``, ``"euroc_imu"``, ``"kitti"`` or None, from the first data lines of ``path``."""
    return _guess(*_split_data(_head(path)))


#: A quaternion component's column name: qx, q_x, qw[], q_RS_w, quat_w, orientation.x; group 1 is the axis.
_QUAT_NAME = re.compile(r"(?:^|[^a-z0-9])(?:q|quat|quaternion|orientation)[_.\-]?(?:[a-z]{1,3}[_.\-])*"
                        r"([wxyz])(?![a-z0-9])")


def _quaternion_order(line: str) -> str | None:
    """The order of the quaternion components a header line names (``"xyzw"``, ``"wxyz"``), or None."""
    order = ""
    for tok in re.split(r"[\s,;]+", line.lower()):
        m = _QUAT_NAME.search(tok)
        if m and m.group(1) not in order:
            order += m.group(1)
    return order if len(order) == 4 else None


def check_tum_layout(path) -> bool:
    """Refuse a file given as a TUM trajectory that is laid out otherwise; tell whether it has a header line.

    Looks at the first 16 kB only (the reader's cost does not grow with it).

    Returns
    -------
    bool
        True when the first line that is not blank or a comment is a header (no field is a
        number), to be skipped.

    Raises
    ------
    InputError
        The file looks like a EuRoC ground-truth or IMU csv or a KITTI pose file (naming the
        command or conversion to use), or a header (a comment before the first pose, or the
        header line) names the quaternion in another order than ``qx qy qz qw`` (its line).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "poses.txt"
    >>> _ = p.write_text("timestamp tx ty tz qx qy qz qw\\n1700000000.0 0 0 0 0 0 0 1\\n")
    >>> check_tum_layout(p)
    True
    >>> _ = p.write_text("# t x y z qw qx qy qz\\n1700000000.0 0 0 0 1 0 0 0\\n")
    >>> check_tum_layout(p)
    Traceback (most recent call last):
    ...
    splineimu.errors.InputError: ...poses.txt:1: the header names the quaternion w x y z; TUM lines are ...
    """
    lines = _head(path)
    fmt = _guess(*_split_data(lines))
    if fmt in ("euroc_gt", "euroc_imu", "kitti"):
        what, advice = FORMATS[fmt]
        raise InputError(f"not a TUM trajectory (timestamp tx ty tz qx qy qz qw): the file looks like {what}: "
                         f"{advice}", path=path)
    has_header = False
    for number, text in lines:
        s = text.strip()
        if not s:
            continue
        is_comment = s.startswith("#")
        if not is_comment:
            has_header = not any(_numbers([f]) for f in re.split(r"[\s,]+", s) if f)
        if is_comment or has_header:
            order = _quaternion_order(s)
            if order is not None and order != "xyzw":
                raise InputError(f"the header names the quaternion {' '.join(order)}; TUM lines are timestamp "
                                 "tx ty tz qx qy qz qw (w last): reorder the columns", path=path, line=number)
        if not is_comment:
            break
    return has_header


def format_hint(path, expected: str, use: str | None = None) -> str | None:
    """A sentence naming the format ``path`` looks like, if that is not ``expected``; else None.
    ``use`` replaces the advice of :data:`FORMATS` (for a command that reads only ``expected``)."""
    fmt = guess_format(path)
    if fmt is None or fmt == expected:
        return None
    what, advice = FORMATS[fmt]
    return f"the file looks like {what}: {use or advice}"


def _unit_of(magnitude: float, step: float) -> str:
    """The unit integer stamps of this magnitude and step most likely are in."""
    for unit, lo, hi in (("seconds", 1e8, 1e11), ("milliseconds", 1e11, 1e14), ("microseconds", 1e14, 1e17)):
        if lo <= magnitude < hi:
            return unit
    return "seconds" if step >= 1 and magnitude < 1e8 else "a unit coarser than nanoseconds"


def check_ns_spacing(t_ns, *, path=None, line=None, advice: str = "") -> None:
    """Refuse nanosecond stamps whose median spacing is below a microsecond (above 1 MHz).

    Two stamps are judged only when their magnitude says they are not nanoseconds (a 1.4e9
    "ns" stamp is 1.4 s after 1970, but 1.4e9 seconds is 2014).

    Raises
    ------
    InputError
        Saying what the stamps look like (seconds, milliseconds, ...) and ``advice``.

    Examples
    --------
    >>> check_ns_spacing(np.array([1400000000, 1400000001, 1400000002]), advice="give nanoseconds")
    Traceback (most recent call last):
    ...
    splineimu.errors.InputError: stamps step by 1 ns (1e+09 Hz): they look like seconds, not nanoseconds; ...
    """
    t = np.asarray(t_ns)
    if t.size < 2:
        return
    step = float(np.median(np.diff(t)))
    magnitude = float(np.max(np.abs(t)))
    if step <= 0 or step >= 1000 or (t.size < 3 and magnitude < 1e8):  # two small stamps: too few to judge
        return
    unit = _unit_of(magnitude, step)
    raise InputError(f"stamps step by {step:g} ns ({1e9 / step:.3g} Hz): they look like {unit}, not nanoseconds"
                     + (f"; {advice}" if advice else ""), path=path, line=line)


def check_seconds_magnitude(stamp_text: str, *, path=None, line=None, advice: str = "") -> None:
    """Refuse a second stamp beyond about the year 5000 (it is in ms, us or ns).

    Examples
    --------
    >>> check_seconds_magnitude("1700000000000000000", advice="TUM stamps are seconds")
    Traceback (most recent call last):
    ...
    splineimu.errors.InputError: stamp 1700000000000000000 read as seconds is after ...: it looks like nanoseconds; ...
    """
    try:
        v = abs(float(stamp_text))
    except ValueError:
        return
    if not (1e11 <= v < float("inf")):
        return
    unit = "milliseconds" if v < 1e14 else "microseconds" if v < 1e17 else "nanoseconds"
    raise InputError(f"stamp {stamp_text} read as seconds is after the year 5000: it looks like {unit}"
                     + (f"; {advice}" if advice else ""), path=path, line=line)


def check_integer_seconds_step(stamps_text, *, path=None, line=None, advice: str = "") -> None:
    """Refuse integer second stamps that step by 1000 s or more (ns, us or ms counted from 0).

    Only the first 1000 stamps are looked at. :func:`check_seconds_magnitude` catches such
    stamps counted from 1970; counted from 0 they stay small (``0 5000000 10000000`` is 200 Hz
    in nanoseconds, one pose every 58 days in seconds).

    Examples
    --------
    >>> check_integer_seconds_step(["0", "5000000", "10000000"], advice="TUM stamps are seconds")
    Traceback (most recent call last):
    ...
    splineimu.errors.InputError: integer stamps step by 5000000 (read as seconds, one pose every 57.9 days): ...
    >>> check_integer_seconds_step(["0", "1", "2"])  # integer seconds: fine
    """
    stamps = _integers([str(t) for t in stamps_text[:1000]])
    if stamps is None or len(stamps) < 2:
        return
    step = float(np.median(np.diff(stamps)))
    if step < 1000:
        return
    # the unit that makes the rate closest to 100 Hz
    unit, rate = min((("milliseconds", 1e3 / step), ("microseconds", 1e6 / step), ("nanoseconds", 1e9 / step)),
                     key=lambda ur: abs(np.log10(ur[1]) - 2))
    every = f"{step / 86400:.3g} days" if step >= 86400 else f"{step / 3600:.3g} hours" if step >= 3600 else \
        f"{step:g} s"
    raise InputError(f"integer stamps step by {step:.10g} (read as seconds, one pose every {every}): they look like "
                     f"{unit} ({rate:.3g} Hz)" + (f"; {advice}" if advice else ""), path=path, line=line)


#: Stamps counted from 0 (the first below this, in s: no epoch) that step by a second or more over
#: at least RELATIVE_POSES poses get a notice (:func:`relative_seconds_notice`).
RELATIVE_START_S = 1e6
RELATIVE_POSES = 100


def _span(seconds: float) -> str:
    return (f"{seconds / 86400:.3g} days" if seconds >= 86400 else f"{seconds / 3600:.3g} h" if seconds >= 3600
            else f"{seconds / 60:.3g} min" if seconds >= 60 else f"{seconds:.3g} s")


def relative_seconds_notice(t_ns) -> str | None:
    """A notice for stamps that may be milliseconds written as decimals, or None.

    Decimal stamps are read as seconds as written (a decimal point says seconds), but
    ``0.000 5.000 10.000`` is also 200 Hz in milliseconds counted from 0: read as seconds, a 3 s
    recording spans 50 minutes and from-tum synthesizes IMU samples over all of it, with
    nothing else to tell. Said where the stamps are counted from 0 (the first below
    :data:`RELATIVE_START_S`: no epoch), step by a second or more, over at least
    :data:`RELATIVE_POSES` poses. A sparse trajectory counted from 0 gets it too; it only says
    what the stamps would be in milliseconds.

    Examples
    --------
    >>> relative_seconds_notice(np.arange(600) * 5 * 10**9)[:66]
    'stamps counted from 0 step by 5 s (0.2 Hz; the poses span 49.9 min'
    >>> relative_seconds_notice(1700000000 * 10**9 + np.arange(600) * 5 * 10**9) is None  # an epoch
    True
    """
    t = np.asarray(t_ns, dtype=np.int64)
    if t.size < RELATIVE_POSES or abs(int(t[0])) >= RELATIVE_START_S * 1e9:
        return None
    step = float(np.median(np.diff(t))) / 1e9
    if step < 1.0:
        return None
    span = float(t[-1] - t[0]) / 1e9
    return (f"stamps counted from 0 step by {step:g} s ({1.0 / step:.3g} Hz; the poses span {_span(span)}): if they "
            f"are milliseconds, the poses are {1e3 / step:.3g} Hz over {_span(span / 1e3)}; TUM stamps are decimal "
            "seconds: divide the column by 1000")


def add_format_hint(exc: InputError, path, expected: str, use: str | None = None) -> InputError:
    """``exc`` with :func:`format_hint`'s sentence appended when the file looks like another format."""
    hint = format_hint(path, expected, use)
    if hint is None or hint in exc.problem:
        return exc
    return type(exc)(f"{exc.problem}; {hint}", path=exc.path, line=exc.line, option=exc.option)
