"""Running median kernel (the fit's local residual level, :mod:`splineimu.spline.checks`).

No validation here: ``x`` is C-contiguous float64 without NaN, ``size`` odd and >= 1.
"""

from __future__ import annotations

import numpy as np

from .._jit import jit


@jit
def running_median(x, size, out):
    """``out[i]`` = median of ``x[i - h .. i + h]`` (``h = size // 2``), the ends extended with
    the first and last values (scipy.ndimage's ``mode="nearest"``).

    A sorted copy of the window is kept: per step one value leaves and one enters (binary
    search, then the values between the two places shift by one), O(N size) in the worst
    case and exact (the median is one of the values).
    """
    n = x.shape[0]
    if n == 0:
        return
    h = size // 2
    win = np.empty(size)
    for k in range(size):
        win[k] = x[min(max(k - h, 0), n - 1)]
    win.sort()
    out[0] = win[h]
    for i in range(1, n):
        old = x[min(max(i - h - 1, 0), n - 1)]
        new = x[min(i + h, n - 1)]
        p = np.searchsorted(win, old)  # the leftmost copy of the value leaving
        q = np.searchsorted(win, new)
        if q <= p:
            for k in range(p, q, -1):
                win[k] = win[k - 1]
            win[q] = new
        else:
            for k in range(p, q - 1):
                win[k] = win[k + 1]
            win[q - 1] = new
        out[i] = win[h]
