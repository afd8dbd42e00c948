"""Blocked cross-validation of ordinary B-spline fits of an R3 signal, on windows of the input:
step 1 of the knot choice (:mod:`splineimu.spline.knots`), and the fits its ladder and noise
surrogate reuse (:class:`_Window`)."""

from __future__ import annotations

from functools import cache

import numpy as np

from .._kernels import cv as _kcv
from .banded import DEFAULT_SMOOTHNESS, SPARSE_SMOOTHNESS, difference_coefficients, grid_layout, layout
from .basis import blending_matrix
from .signals import accumulate

N_FOLDS = 4
#: Longer inputs are cross-validated on windows totalling about this many poses.
MAX_CV_POSES = 24_000
_N_WINDOWS = 6
#: The least span of a cross-validated window [s] (:func:`_windows`).
MIN_WINDOW_S = 12.0
#: Coarse step of the spacing grid.
_STEP = 1.6
#: Score ratio to the best beyond which finer grid spacings stop being scored (see _search).
_PRUNE = 3.0
#: Fraction of each window's span at both ends left out of the score (one-sided data).
_END_FRACTION = 0.05
#: The residual autocorrelation below which noise counts as uncorrelated.
_ACF_LEVEL = 0.1


@cache
def _blending(k):
    return blending_matrix(k)


@cache
def _penalty(k):
    """Coefficients of the difference penalty of an order-k fit (3rd differences at most), as
    a tuple (its length is compiled in)."""
    return tuple(float(c) for c in difference_coefficients(min(3, k - 1)))


class _Window:
    """One stretch of the signal that is fitted on its own."""

    def __init__(self, t, X, w):
        self.t, self.X, self.w = t, X, w
        n = t.size
        self.index = np.arange(n)
        lo, hi = t[0] + _END_FRACTION * (t[-1] - t[0]), t[-1] - _END_FRACTION * (t[-1] - t[0])
        self.scored = (t >= lo) & (t <= hi) & (w > 0)
        weighted = np.flatnonzero(w > 0)
        if 2 * np.count_nonzero(self.scored) < weighted.size:
            # most poses within 5% of the span from its ends (a gap far longer than the data):
            # the 5% of the weighted poses at each end are left out instead
            m = max(int(_END_FRACTION * weighted.size), 1)
            self.scored = np.zeros(n, dtype=bool)
            self.scored[weighted[m:weighted.size - m]] = True
        self.scored_index = np.flatnonzero(self.scored)
        self.n_scored = int(self.scored_index.size)
        self.zero = np.zeros(n, dtype=np.int64)  # one fold
        self._buffers = {}

    def _scratch(self, name, shape, dtype=np.float64, zero=False):
        """A work array reused from call to call (valid until the next call with that name):
        fresh large arrays would cost page faults at every fit."""
        size = 1
        for m in shape:  # (np.prod: 5 us a call, 900 calls a choice)
            size *= m
        buf = self._buffers.get(name)
        if buf is None or buf.size < size:
            buf = self._buffers[name] = np.empty(size + size // 4, dtype=dtype)
        out = buf[:size].reshape(shape)
        if zero:
            out.fill(0)
        return out

    def folds(self, block):
        return ((self.index // max(int(block), 1)) % N_FOLDS).astype(np.int64)

    def fit_folds(self, k, dt, fold, nfold, X=None, origin=None):
        """Control points (nfold, n, d) of the fits of X (default: the signal) without each
        fold, the samples' spline parameters, segments and basis rows, and the layout (knots
        from the window's first pose, or on the grid ``origin + i dt``)."""
        X = self.X if X is None else X
        t0, dt_, nseg, n = (layout(self.t[0], self.t[-1], dt, k) if origin is None
                            else grid_layout(self.t[0], self.t[-1], origin, dt, k))
        s = np.ascontiguousarray((self.t - t0) / dt_)
        sizes = (0.0,) * k, (0.0,) * X.shape[1]  # compile-time order and column count
        H = self._scratch("H", (nfold, n, k), zero=True)
        rhs = self._scratch("rhs", (nfold, n, X.shape[1]), zero=True)
        counts = self._scratch("counts", (nfold, nseg), zero=True)
        seg = self._scratch("seg", (self.t.size,), np.int64)
        B = self._scratch("B", (self.t.size, k))
        _kcv.fold_systems(s, self.w, fold, X, _blending(k), nseg, H, rhs, counts, seg, B, *sizes)
        # long stretches without data at a fine spacing are numerically singular (NaN): a
        # spacing not to be chosen
        C = self._scratch("C", (nfold, n, X.shape[1]))
        _kcv.solve_folds(H, rhs, counts, _penalty(k), DEFAULT_SMOOTHNESS, SPARSE_SMOOTHNESS,
                         self._scratch("Hf", (n, k)), C, *sizes)
        return C, s, seg, B, nseg, dt_, sizes

    def score(self, k, dt, fold, X=None):
        """Summed squared held-out error of X (default: the signal) and the count scored."""
        X = self.X if X is None else X
        C, _, seg, B, _, _, sizes = self.fit_folds(k, dt, fold, N_FOLDS, X)
        total = _kcv.held_out_error(fold, X, C, seg, B, self.scored_index, self._scratch("e", (self.t.size,)),
                                    *sizes)
        return (total if np.isfinite(total) else np.inf), self.n_scored

    def derivative(self, k, dt, fold, nfold, r, X=None, origin=None):
        """r-th derivative of the fits without each fold (nfold, N, d) at every sample (valid
        until the next call)."""
        C, s, _, _, nseg, dt_, sizes = self.fit_folds(k, dt, fold, nfold, X, origin)
        out = self._scratch("out", (nfold, self.t.size, C.shape[2]))
        for f in range(nfold):
            _kcv.derivative_at(s, C[f], _blending(k), nseg, 1.0 / dt_, r, out[f], *sizes)
        return out

    def residual(self, k, dt, origin=None):
        d = self.derivative(k, dt, self.zero, 1, 0, origin=origin)[0]
        return (self.X - d)[self.scored]


def _windows(t, X, w, increments=False):
    """The stretches cross-validated: all of the input, or for long inputs :data:`_N_WINDOWS`
    spread evenly, each of MAX_CV_POSES / _N_WINDOWS poses or :data:`MIN_WINDOW_S`, whichever
    is longer (a window bounds the spacing at a quarter of its span: 4000 poses at 1 kHz held
    slow turning at 1 s, gyro 4.4x the best fixed setting; at 10 kHz, 0.1 s and 14x). With
    ``increments`` X holds the (N - 1, 3) increments of the signal, summed from zero in each
    window: a sum carried over an hour of rotation (thousands of radians) rounds each step by
    ~1e-13 rad, noise that would make exact input look noisy."""
    n = t.size
    length = n
    if n > MAX_CV_POSES:
        length = max(MAX_CV_POSES // _N_WINDOWS, int(np.ceil(MIN_WINDOW_S / float(np.median(np.diff(t))))))
    if length * _N_WINDOWS >= n:  # as much as all of it: all of it
        return [_Window(t, np.ascontiguousarray(accumulate(X) if increments else X), w)]
    return [_Window(t[a:a + length], np.ascontiguousarray(accumulate(X[a:a + length - 1]) if increments
                                                          else X[a:a + length]), w[a:a + length])
            for a in np.linspace(0, n - length, _N_WINDOWS).astype(int)]


def _correlation_lag(res):
    """Lag (samples) where the residual's autocorrelation first falls below _ACF_LEVEL."""
    x = res - res.mean(axis=0)
    n = x.shape[0]
    if n < 8:
        return 1
    lags = min(n // 4, 400)
    nfft = 1 << int(np.ceil(np.log2(n + lags)))  # zero padding beyond the lags kept: no wrap-around
    F = np.fft.rfft(x, nfft, axis=0)
    acf = np.fft.irfft((np.abs(F) ** 2).sum(axis=1), nfft)[:lags]
    if acf[0] <= 0:
        return 1
    below = np.flatnonzero(acf / acf[0] < _ACF_LEVEL)
    return int(below[0]) if below.size else int(acf.size)


def _search(windows, orders, grid, block, lo, hi=np.inf):
    """Scores {(k, dt): score} over a coarse grid and a refinement around each order's best."""
    folds = [wd.folds(block) for wd in windows]
    table = {}

    def score(k, dt):
        if (k, dt) not in table:
            num = den = 0
            for wd, fd in zip(windows, folds):
                if (wd.t[-1] - wd.t[0]) / dt < 2:
                    return np.inf
                a, b = wd.score(k, dt, fd)
                num, den = num + a, den + b
            table[(k, dt)] = num / max(den, 1)
        return table[(k, dt)]

    for k in orders:
        # coarse to fine; the finest spacings (the costliest fits) are left out once two in a
        # row have scored worse than their coarser neighbour and _PRUNE x the best so far
        vals = np.full(len(grid), np.inf)
        strikes = 0
        for j in range(len(grid) - 1, -1, -1):
            vals[j] = score(k, grid[j])
            best = np.min(vals)
            rising = j + 1 == len(grid) or not vals[j] <= vals[j + 1]
            strikes = strikes + 1 if vals[j] > _PRUNE * best and rising else 0
            if strikes == 2:
                break
        i = int(np.argmin(vals))
        for dt in (grid[i] / np.sqrt(_STEP), grid[i] * np.sqrt(_STEP)) if len(grid) > 1 else ():
            if lo <= dt <= hi:
                score(k, dt)
    return table
