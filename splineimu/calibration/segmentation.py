"""Step 1 of a calibration: steady phases (rest or constant rate) found in the data alone.

Moving standard deviation and moving half-window drift of every channel against the channel's
robust white-noise level; the procedure is described in :mod:`splineimu.calibration`, step 1.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..validation import as_float_array, as_stamps_ns, nonnegative_float, positive_float

__all__ = ["find_steady_phases", "as_stamps_ns_checked", "FLOOR_REL"]

#: Relative floor of the noise level (noise-free data).
FLOOR_REL = 1e-9


def as_stamps_ns_checked(t_ns, name: str = "t_ns"):
    """Strictly increasing int64 stamps, at least three of them (a moving window needs them)."""
    t = as_stamps_ns(t_ns, name)
    if t.size < 3:
        raise InputError(f"Expected `{name}` to hold at least 3 stamps, got {t.size}")
    return t


def _moving_std(x, half):
    """Moving standard deviation of every column over the centred window ``2 half + 1``.

    Windows are clamped inside the record. O(N) with running sums that stay accurate: the
    windows starting in block ``j`` (``w`` samples) are summed relative to the block's first
    sample, so the sums never grow beyond ``2 w`` deviations from a nearby value (constant data
    give exactly 0).
    """
    n, c = x.shape
    w = 2 * half + 1
    if n < w:
        return np.tile(x.std(axis=0), (n, 1))
    from numpy.lib.stride_tricks import sliding_window_view

    starts = n - w + 1
    nb = -(-starts // w)
    pad = np.empty(((nb + 1) * w, c))
    pad[:n] = x
    pad[n:] = x[-1]
    blocks = sliding_window_view(pad, 2 * w, axis=0)[::w][:nb]  # (nb, c, 2w)
    d = blocks - blocks[:, :, :1]
    cs1 = np.zeros((nb, c, 2 * w + 1))
    cs2 = np.zeros((nb, c, 2 * w + 1))
    np.cumsum(d, axis=2, out=cs1[:, :, 1:])
    np.cumsum(d * d, axis=2, out=cs2[:, :, 1:])
    s1 = cs1[:, :, w:2 * w] - cs1[:, :, :w]  # window sums for start offsets 0..w-1
    s2 = cs2[:, :, w:2 * w] - cs2[:, :, :w]
    var = np.maximum(s2 - s1 * s1 / w, 0.0) / w
    full = np.sqrt(var).transpose(0, 2, 1).reshape(nb * w, c)[:starts]
    idx = np.clip(np.arange(n) - half, 0, n - w)
    return full[idx]


def _moving_drift(x, half):
    """``|mean(x[k+1 .. k+half]) - mean(x[k-half .. k-1])|`` per column, clamped at the ends."""
    n, c = x.shape
    if n < 2 * half + 1:
        return np.zeros((n, c))
    cs = np.zeros((n + 1, c))
    np.cumsum(x - x[0], axis=0, out=cs[1:])
    k = np.arange(half, n - half)
    d = np.abs((cs[k + half + 1] - cs[k + 1]) - (cs[k] - cs[k - half])) / half
    idx = np.clip(np.arange(n) - half, 0, n - 2 * half - 1)
    return d[idx]



def find_steady_phases(t_ns, signals, *, window_s: float = 0.5, threshold: float = 1.5,
                       min_dwell_s: float = 2.0, margin_s: float | None = None, drift_threshold: float = 5.0):
    """Steady phases (rest or constant rate) of a recording, from the data alone.

    Parameters
    ----------
    t_ns : (N,) int64
        Strictly increasing stamps [ns].
    signals : (N, C) array_like
        The channels to watch (e.g. gyro and accelerometer side by side).
    window_s : float, default 0.5
        Length of the centred moving window [s].
    threshold : float, default 1.5
        A sample is steady when every channel's moving standard deviation is at most
        ``threshold`` times that channel's noise level (module docstring, step 1).
    min_dwell_s : float, default 2.0
        Shortest phase kept [s] (after shrinking).
    margin_s : float, optional
        Samples removed at each end of a phase that borders motion [s]; default ``2 window_s``.
    drift_threshold : float, default 5
        A sample is also unsteady when the means of the two halves of its window differ by
        more than ``drift_threshold`` standard deviations of that difference
        (``sigma_c sqrt(2 / half)``): a slow ramp shows up there long before it raises the
        moving standard deviation.

    Returns
    -------
    phases : list of (start, stop)
        Sample index ranges ``[start, stop)``, in time order.
    noise_level : (C,) float64
        The per-channel noise level ``sigma_c`` used.

    Raises
    ------
    InputError
        Bad shapes or stamps.
    ConfigError
        Non-positive window, threshold or dwell.

    Examples
    --------
    >>> t = np.arange(3000, dtype=np.int64) * 10_000_000          # 100 Hz, 30 s
    >>> x = np.zeros((3000, 1)); x[1000:1200, 0] = np.linspace(0, 1, 200); x[1200:, 0] = 1
    >>> x += np.random.default_rng(0).normal(0, 1e-3, x.shape)
    >>> phases, _ = find_steady_phases(t, x)
    >>> [(int(a), int(b)) for a, b in phases]
    [(0, 877), (1323, 3000)]
    """
    t = as_stamps_ns_checked(t_ns)
    x = np.asarray(signals)
    x = as_float_array(x[:, None] if x.ndim == 1 else x, "signals", (t.size, None))
    window_s = positive_float(window_s, "window_s")
    threshold = positive_float(threshold, "threshold")
    min_dwell_s = positive_float(min_dwell_s, "min_dwell_s")
    drift_threshold = positive_float(drift_threshold, "drift_threshold")
    margin_s = 2.0 * window_s if margin_s is None else nonnegative_float(margin_s, "margin_s")
    dt = float(np.median(np.diff(t))) / 1e9
    half = max(2, int(round(0.5 * window_s / dt)))
    margin = int(round(margin_s / dt))
    min_len = max(2, int(round(min_dwell_s / dt)))

    s = _moving_std(np.ascontiguousarray(x), half)
    from scipy.stats import chi2

    w = 2 * half + 1
    # the 25th percentile of the moving std of white noise is sigma sqrt(chi2_{w-1}(0.25) / w)
    sigma = np.percentile(s, 25.0, axis=0) / math.sqrt(chi2.ppf(0.25, w - 1) / w)
    floor = FLOOR_REL * np.maximum(1.0, np.median(np.abs(x), axis=0))
    dx = np.abs(np.diff(x, axis=0))
    for c in range(x.shape[1]):  # quantized data: half the smallest step (the LSB)
        nz = dx[:, c][dx[:, c] > floor[c]]
        if nz.size:
            floor[c] = max(floor[c], 0.5 * float(nz.min()))
    drift = _moving_drift(x, half)
    steady = np.all((s <= threshold * sigma + floor)
                    & (drift <= drift_threshold * sigma * math.sqrt(2.0 / half) + floor), axis=1)

    # runs of True
    edges = np.diff(np.concatenate([[0], steady.astype(np.int8), [0]]))
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1)
    n = t.size
    out = []
    for a, b in zip(starts, stops):
        a2 = a + margin if a > 0 else a
        b2 = b - margin if b < n else b
        if b2 - a2 >= min_len:
            out.append((int(a2), int(b2)))
    return out, sigma

