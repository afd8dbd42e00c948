"""Argument checks of the public layer: one place, one wording.

Every public function validates and coerces its arguments through these helpers, so that the
same mistake gives the same message everywhere: the argument's name, what was expected and
what was given ("Expected `quat_xyzw` to have shape (N, 4), got (5, 3)"). Array problems raise
:class:`~splineimu.errors.InputError`, option values :class:`~splineimu.errors.ConfigError`;
both are :class:`ValueError` subclasses. ``where`` (a ``(path, line)`` pair, or a path) is
passed on to the error so that values read from a file are reported at their file and line.

Examples
--------
>>> as_vectors([[0, 0, 1]], "gyro_rad_s").shape
(1, 3)
>>> as_vectors([[0, 0]], "gyro_rad_s")
Traceback (most recent call last):
...
splineimu.errors.InputError: Expected `gyro_rad_s` to have shape (N, 3), got (1, 2)
>>> positive_float("200", "rate_hz")
200.0
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from .errors import ConfigError, InputError


def _where(where):
    if where is None:
        return {}
    if isinstance(where, tuple):
        path, line = where
        return {"path": path, "line": line}
    return {"path": where}


def _shape_text(shape) -> str:
    return "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def as_float_array(x, name: str, shape: tuple | None = None, *, finite: bool = True, where=None) -> np.ndarray:
    """``x`` as a C-contiguous float64 array, checked against ``shape`` (``None`` entries are free).

    Parameters
    ----------
    x : array_like
    name : str
        The argument's name, for the message.
    shape : tuple of int or None, optional
        Expected shape; ``None`` stands for any size (written ``N``).
    finite : bool
        Refuse NaN and inf.
    where : (path, line) or path, optional
        Where the values came from.

    Raises
    ------
    InputError
        Not numeric, wrong shape or not finite.
    """
    try:
        a = np.ascontiguousarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"Expected `{name}` to be numeric, got {type(x).__name__}", **_where(where)) from None
    if shape is not None:
        ok = a.ndim == len(shape) and all(s is None or s == n for s, n in zip(shape, a.shape))
        if not ok:
            want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
            raise InputError(f"Expected `{name}` to have shape {want}, got {_shape_text(a.shape)}", **_where(where))
    if finite and a.size and not np.isfinite(a).all():
        bad = np.argwhere(~np.isfinite(a))[0]
        at = "" if a.ndim == 0 else f" (first at index {tuple(int(i) for i in bad) if a.ndim > 1 else int(bad[0])})"
        raise InputError(f"`{name}` contains NaN or inf{at}", **_where(where))
    return a


def as_vectors(x, name: str, n: int | None = None, width: int = 3, **kw) -> np.ndarray:
    """``(N, width)`` float64 rows (``n`` rows if given)."""
    return as_float_array(x, name, (n, width), **kw)


def as_vector(x, name: str, size: int = 3, **kw) -> np.ndarray:
    """One ``(size,)`` float64 vector."""
    return as_float_array(x, name, (size,), **kw)


def as_times_s(x, name: str = "t_s", *, increasing: bool = False, **kw) -> np.ndarray:
    """``(N,)`` float64 times; with ``increasing`` strictly increasing."""
    t = as_float_array(x, name, (None,), **kw)
    if increasing and t.size > 1:
        d = np.diff(t)
        if not (d > 0).all():
            i = int(np.argmax(d <= 0)) + 1
            raise InputError(f"`{name}` must be strictly increasing (index {i}: {t[i]!r} after {t[i - 1]!r})",
                             **_where(kw.get("where")))
    return t


def as_stamps_ns(x, name: str = "t_ns", *, increasing: bool = True, where=None) -> np.ndarray:
    """``(N,)`` int64 nanosecond stamps, exact (floats must hold whole numbers)."""
    a = np.asarray(x)
    if a.dtype.kind == "f":
        if not np.isfinite(a).all() or (a.size and not (a == np.round(a)).all()):
            raise InputError(f"`{name}` must hold whole nanoseconds", **_where(where))
    elif a.dtype.kind not in "iu":
        raise InputError(f"Expected `{name}` to be integer nanoseconds, got dtype {a.dtype}", **_where(where))
    if a.ndim != 1:
        raise InputError(f"Expected `{name}` to have shape (N,), got {_shape_text(a.shape)}", **_where(where))
    t = np.ascontiguousarray(a, dtype=np.int64)
    if increasing and t.size > 1 and not (np.diff(t) > 0).all():
        i = int(np.argmax(np.diff(t) <= 0)) + 1
        raise InputError(f"`{name}` must be strictly increasing (index {i}: {t[i]} after {t[i - 1]})",
                         **_where(where))
    return t


def as_quat_xyzw(x, name: str = "quat_xyzw", n: int | None = None, *, where=None) -> np.ndarray:
    """``(N, 4)`` quaternions ``(x, y, z, w)``, finite and of non-zero norm (not normalized here)."""
    q = as_float_array(x, name, (n, 4), where=where)
    norm = np.linalg.norm(q, axis=1)
    if q.shape[0] and not (norm > 1e-12).all():
        i = int(np.argmax(norm <= 1e-12))
        raise InputError(f"`{name}` row {i} is a zero quaternion", **_where(where))
    return q


def _number(v, name: str, where):
    if isinstance(v, bool) or v is None:
        raise ConfigError(f"`{name}` must be a number, got {v!r}", option=name, **_where(where))
    if isinstance(v, numbers.Real):
        return float(v)
    try:
        return float(str(v).strip())
    except ValueError:
        raise ConfigError(f"`{name}` must be a number, got {v!r}", option=name, **_where(where)) from None


def finite_float(v, name: str, *, where=None) -> float:
    """A finite float from a number or numeric text."""
    x = _number(v, name, where)
    if not math.isfinite(x):
        raise ConfigError(f"`{name}` must be finite, got {v!r}", option=name, **_where(where))
    return x


def positive_float(v, name: str, *, where=None) -> float:
    """A finite float > 0."""
    x = finite_float(v, name, where=where)
    if not x > 0:
        raise ConfigError(f"`{name}` must be positive, got {v!r}", option=name, **_where(where))
    return x


def nonnegative_float(v, name: str, *, where=None) -> float:
    """A finite float >= 0."""
    x = finite_float(v, name, where=where)
    if not x >= 0:
        raise ConfigError(f"`{name}` must be zero or positive, got {v!r}", option=name, **_where(where))
    return x


def int_in_range(v, name: str, lo: int | None = None, hi: int | None = None, *, where=None) -> int:
    """An integer (not a bool, not a fraction) within ``[lo, hi]``."""
    if isinstance(v, bool) or v is None:
        raise ConfigError(f"`{name}` must be an integer, got {v!r}", option=name, **_where(where))
    if isinstance(v, numbers.Integral):
        k = int(v)
    else:
        try:
            k = int(str(v).strip())
        except ValueError:
            raise ConfigError(f"`{name}` must be an integer, got {v!r}", option=name, **_where(where)) from None
    if (lo is not None and k < lo) or (hi is not None and k > hi):
        rng = f"between {lo} and {hi}" if lo is not None and hi is not None else (
            f">= {lo}" if lo is not None else f"<= {hi}")
        raise ConfigError(f"`{name}` must be {rng}, got {k}", option=name, **_where(where))
    return k


def one_of(v, name: str, choices, *, where=None):
    """``v`` if it is one of ``choices`` (with a did-you-mean otherwise)."""
    if v in choices:
        return v
    import difflib

    near = difflib.get_close_matches(str(v), [str(c) for c in choices], n=1)
    hint = f"; did you mean {near[0]!r}?" if near else ""
    raise ConfigError(f"`{name}` must be one of {', '.join(map(str, choices))}, got {v!r}{hint}",
                      option=name, **_where(where))


def as_rate_hz(v, name: str = "rate_hz", *, where=None) -> float:
    """A sample rate in Hz: finite, > 0 (and at most 1 MHz, above which no IMU samples)."""
    x = positive_float(v, name, where=where)
    if x > 1e6:
        raise ConfigError(f"`{name}` = {x:g} Hz is above 1 MHz; is it in the right unit?", option=name,
                          **_where(where))
    return x


def as_seed(v, name: str = "seed", *, where=None) -> int | None:
    """A numpy seed: ``None`` or an integer in ``[0, 2**63)``."""
    if v is None:
        return None
    return int_in_range(v, name, 0, 2**63 - 1, where=where)


__all__ = [
    "as_float_array", "as_vectors", "as_vector", "as_times_s", "as_stamps_ns", "as_quat_xyzw",
    "finite_float", "positive_float", "nonnegative_float", "int_in_range", "one_of", "as_rate_hz", "as_seed",
]
