"""Allan-deviation kernels: frequency -> phase integration and overlapping second-difference sums.

No validation here (see :mod:`splineimu.allan`). Arrays are C-contiguous float64; outputs are
preallocated and come last.
"""

from __future__ import annotations

from .._jit import jit


@jit
def freq_to_phase_into(y, mean, dt, phase):
    """``phase[k, 0] = 0``, ``phase[k, i + 1] = (sum_{j <= i} (y[j, k] - mean[k])) * dt``.

    ``y`` is (N, K) (samples by rows), ``phase`` is (K, N + 1) so that each column's phase
    is contiguous for :func:`oadev_sums`. The running sum is sequential, exactly as
    ``numpy.cumsum`` accumulates, then scaled by ``dt``.
    """
    n = y.shape[0]
    kk = y.shape[1]
    for k in range(kk):
        acc = 0.0
        mk = mean[k]
        phase[k, 0] = 0.0
        for i in range(n):
            acc += y[i, k] - mk
            phase[k, i + 1] = acc * dt


@jit
def oadev_sum_one(x, mj):
    """``sum_i (x[i + 2 mj] - 2 x[i + mj] + x[i])^2`` over ``i < len(x) - 2 mj``.

    Four interleaved accumulators break the floating-point add dependency chain (no
    ``fastmath`` needed); the order of the operations inside a term is numpy's
    (``(x2 - 2 x1) + x0``).
    """
    n = x.shape[0] - 2 * mj
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    i = 0
    n4 = n - 3
    while i < n4:
        v0 = (x[i + 2 * mj] - 2.0 * x[i + mj]) + x[i]
        v1 = (x[i + 1 + 2 * mj] - 2.0 * x[i + 1 + mj]) + x[i + 1]
        v2 = (x[i + 2 + 2 * mj] - 2.0 * x[i + 2 + mj]) + x[i + 2]
        v3 = (x[i + 3 + 2 * mj] - 2.0 * x[i + 3 + mj]) + x[i + 3]
        s0 += v0 * v0
        s1 += v1 * v1
        s2 += v2 * v2
        s3 += v3 * v3
        i += 4
    while i < n:
        v0 = (x[i + 2 * mj] - 2.0 * x[i + mj]) + x[i]
        s0 += v0 * v0
        i += 1
    return (s0 + s1) + (s2 + s3)


@jit(nogil=True)
def oadev_sums(phase, m, out, first, step):
    """``out[j, k] = oadev_sum_one(phase[k], m[j])`` for the (tau, column) pairs
    ``p = first, first + step, ...`` of the list that alternates the smallest and largest
    remaining ``m`` (so that ``step`` threads starting at ``first = 0 .. step - 1`` get equal
    work). ``phase`` is (K, L), ``m`` (T,) int64 with ``2 m_j < L``, ``out`` (T, K).

    Releases the GIL: plain Python threads run it in parallel without the first-call cost of
    numba's parallel backend (~0.5 s per process, measured), which dominated one-shot runs.
    """
    nt = m.shape[0]
    kk = phase.shape[0]
    total = nt * kk
    for p in range(first, total, step):
        q = p // kk
        k = p - q * kk
        # interleave: q = 0 -> smallest m, q = 1 -> largest m, ... balances the work
        if q % 2 == 0:
            j = q // 2
        else:
            j = nt - 1 - q // 2
        out[j, k] = oadev_sum_one(phase[k], m[j])
