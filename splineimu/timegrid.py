"""Uniform sample grids in integer nanoseconds: the one implementation.

Stamps are ``start_ns + round(k * 1e9 / rate_hz)`` for ``k = 0, 1, ...`` while they lie in
``[start_ns, end_ns]``. Rates whose period is not a whole number of nanoseconds (300 Hz, 1 kHz
/ 3, ...) are rounded exactly in integer arithmetic for integer rates (half-way cases away from
zero), so the grid is the same on every machine and for every length; other rates round the
float product, which is exact to well below a nanosecond for any realistic record.

Examples
--------
>>> uniform_stamps_ns(0, 10_000_000, 300).tolist()
[0, 3333333, 6666667, 10000000]
>>> int(uniform_stamps_ns(1_700_000_000_000_000_000, 1_700_000_000_010_000_000, 200)[-1])
1700000000010000000
"""

from __future__ import annotations

import numpy as np

from .validation import as_rate_hz


def uniform_stamps_ns(start_ns: int, end_ns: int, rate_hz: float) -> np.ndarray:
    """Integer-nanosecond stamps ``start + round(k 1e9 / rate)`` that lie in ``[start, end]``.

    Parameters
    ----------
    start_ns, end_ns : int
        First stamp and the last admissible one (inclusive), integer nanoseconds.
    rate_hz : float
        Sample rate (> 0).

    Returns
    -------
    t_ns : (N,) int64

    Raises
    ------
    ConfigError
        A rate that is not a positive finite number; ``end_ns < start_ns``.
    """
    from .errors import ConfigError

    rate = as_rate_hz(rate_hz)
    start, span = int(start_ns), int(end_ns) - int(start_ns)
    if span < 0:
        raise ConfigError(f"empty time span: end {end_ns} ns is before start {start_ns} ns")
    n = int(np.floor(span * rate / 1e9 + 1e-9)) + 1
    k = np.arange(n, dtype=np.int64)
    if rate == int(rate):
        r = int(rate)
        off = (2 * k * 1_000_000_000 + r) // (2 * r)
    else:
        off = np.rint(k * (1e9 / rate)).astype(np.int64)
    return np.int64(start) + off[off <= span]


__all__ = ["uniform_stamps_ns"]
