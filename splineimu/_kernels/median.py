"""Running median kernel (the fit's local residual level, :mod:`splineimu.spline.checks`).

No validation here: ``x`` is C-contiguous float64 without NaN, ``size`` odd and >= 1.
"""

from __future__ import annotations

import numpy as np

from .._jit import jit


@jit
def _left(win, v):
    """Leftmost index at which ``v`` could be inserted in sorted ``win`` (``np.searchsorted``)."""
    lo = 0
    hi = win.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if win[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@jit
def _sift_down(a, root, end):
    while 2 * root + 1 < end:
        child = 2 * root + 1
        if child + 1 < end and a[child] < a[child + 1]:
            child += 1
        if a[root] < a[child]:
            a[root], a[child] = a[child], a[root]
            root = child
        else:
            return


@jit
def _heap_sort(a):
    n = a.shape[0]
    for start in range(n // 2 - 1, -1, -1):
        _sift_down(a, start, n)
    for end in range(n - 1, 0, -1):
        a[0], a[end] = a[end], a[0]
        _sift_down(a, 0, end)


@jit
def running_median(x, size, out):
    """``out[i]`` = median of ``x[i - h .. i + h]`` (``h = size // 2``), the ends extended with
    the first and last values (scipy.ndimage's ``mode="nearest"``).

    A sorted copy of the window is kept: per step one value leaves and one enters (binary
    search, then the values between the two places shift by one), O(N size) in the worst
    case and exact (the median is one of the values). Written without numpy's sort and
    searchsorted, whose implementations would be loaded with the kernel from the cache.
    """
    n = x.shape[0]
    if n == 0:
        return
    h = size // 2
    win = np.empty(size)
    for k in range(size):
        win[k] = x[min(max(k - h, 0), n - 1)]
    _heap_sort(win)
    out[0] = win[h]
    for i in range(1, n):
        old = x[min(max(i - h - 1, 0), n - 1)]
        new = x[min(i + h, n - 1)]
        p = _left(win, old)  # the leftmost copy of the value leaving
        q = _left(win, new)
        if q <= p:
            for k in range(p, q, -1):
                win[k] = win[k - 1]
            win[q] = new
        else:
            for k in range(p, q - 1):
                win[k] = win[k + 1]
            win[q - 1] = new
        out[i] = win[h]
