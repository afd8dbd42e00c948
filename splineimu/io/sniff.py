"""What a file looks like: the format and the stamp unit, for messages when the wrong reader or unit is used.

The readers call these when something does not fit, so that the message says what the file
seems to be and what to use instead:

- :func:`guess_format` looks at the first data lines (a few kB, never the whole file) and
  names the likely format: a TUM trajectory, a EuRoC ground truth, a EuRoC IMU csv;
- :func:`format_hint` is the sentence a reader appends to its error when the file looks
  like another format than the one it reads;
- :func:`check_ns_spacing` refuses integer-nanosecond stamps whose spacing is below a
  microsecond (seconds or milliseconds written in a nanosecond column);
- :func:`check_seconds_magnitude` refuses second stamps beyond the year 5000 (milli-, micro-
  or nanoseconds in a TUM file).

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

import numpy as np

from ..errors import InputError

__all__ = ["guess_format", "format_hint", "add_format_hint", "check_ns_spacing", "check_seconds_magnitude", "FORMATS"]

#: Format key -> (description, what to use).
FORMATS = {
    "tum": ("a TUM trajectory (t x y z qx qy qz qw, seconds)", "use `splineimu from-tum`"),
    "euroc_gt": ("a EuRoC ground-truth csv (ns, p xyz, q wxyz, ...)", "use `splineimu from-euroc`"),
    "euroc_imu": ("a EuRoC IMU csv (ns, gyro xyz, accel xyz)",
                  "it is IMU data, not poses: give it to integrate, allan or calibrate, or as --timestamps"),
}

_HEAD_BYTES = 16384


def _data_lines(path, n=5):
    try:
        with open(path, "rb") as f:
            head = f.read(_HEAD_BYTES)
    except OSError:
        return [], ""
    text = head.decode("utf-8", errors="replace")
    lines = text.splitlines()[:-1] if len(head) == _HEAD_BYTES else text.splitlines()
    header = " ".join(ln for ln in lines[:3] if ln.lstrip().startswith("#") or "_RS_" in ln)
    data = [ln.strip() for ln in lines if ln.strip() and not ln.lstrip().startswith("#") and "_RS_" not in ln]
    return data[:n], header


def _numbers(fields):
    try:
        return [float(f) for f in fields]
    except ValueError:
        return None


def guess_format(path) -> str | None:
    """``"tum"``, ``"euroc_gt"``, ``"euroc_imu"`` or None, from the first data lines of ``path``."""
    data, header = _data_lines(path)
    if not data:
        return None
    comma = "," in data[0]
    rows = [[f.strip() for f in (ln.split(",") if comma else ln.split())] for ln in data]
    nums = [_numbers(r) for r in rows]
    if any(v is None for v in nums):
        return None
    n = min(len(r) for r in rows)
    integer_stamps = all(r[0].lstrip("+-").isdigit() for r in rows)
    # first: the ground truth's bias columns b_w_RS_S_x, b_a_RS_S_x contain the IMU's names
    if "p_RS_R" in header or "q_RS" in header:
        return "euroc_gt"
    if "w_RS_S" in header or "a_RS_S" in header:
        return "euroc_imu"
    if comma and integer_stamps:
        if n == 7:
            return "euroc_imu"
        if n >= 8:
            return "euroc_gt"
    if not comma and n >= 8 and not integer_stamps:
        return "tum"
    return None


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


def add_format_hint(exc: InputError, path, expected: str, use: str | None = None) -> InputError:
    """``exc`` with :func:`format_hint`'s sentence appended when the file looks like another format."""
    hint = format_hint(path, expected, use)
    if hint is None or hint in exc.problem:
        return exc
    return type(exc)(f"{exc.problem}; {hint}", path=exc.path, line=exc.line, option=exc.option)
