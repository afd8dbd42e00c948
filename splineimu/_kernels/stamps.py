"""Kernel of the stamps' re-timing (:mod:`splineimu.stamps`): the slot of each pose on a capture
clock, by dynamic programming over its delivery delay in whole periods."""

from __future__ import annotations

import numpy as np

from .._jit import jit


@jit
def assign_slots(m, Y, scales, h, S, prior, back):
    """Delays ``s`` (N,) in periods, ``0 <= s < S``, below the latest slots ``m`` (N,) the stamps
    allow (strictly increasing), such that the slots ``n = m - s`` increase strictly and the poses
    ``Y`` (N, 6: position and accumulated rotation) move smoothly at the slot times ``n h``: the
    cost of pose i is the pseudo-Huber norm of its second difference (per part, in units of
    ``scales``) plus ``prior`` per period of delay. ``back`` (N, S, S) int8 scratch. Returns the
    least total cost (inf: no strictly increasing assignment within S)."""
    N = m.shape[0]
    inf = np.inf
    D = np.full((S, S), inf)  # D[a, b]: least cost with s_{i-1} = a, s_i = b
    for a in range(S):
        for b in range(S):
            if m[1] - b > m[0] - a:
                D[a, b] = prior * (a + b)
    E = np.empty((S, S))
    for i in range(1, N - 1):
        for b in range(S):
            for c in range(S):
                E[b, c] = inf
        for a in range(S):
            na = m[i - 1] - a
            for b in range(S):
                if D[a, b] == inf:
                    continue
                nb = m[i] - b
                d1 = (nb - na) * h
                for c in range(S):
                    nc = m[i + 1] - c
                    if nc <= nb:
                        continue
                    d2 = (nc - nb) * h
                    cost = D[a, b] + prior * c
                    for part in range(2):
                        acc2 = 0.0
                        for z in range(3):
                            j = 3 * part + z
                            v1 = (Y[i, j] - Y[i - 1, j]) / d1
                            v2 = (Y[i + 1, j] - Y[i, j]) / d2
                            acc = 2.0 * (v2 - v1) / (d1 + d2)
                            acc2 += acc * acc
                        cost += 2.0 * (np.sqrt(1.0 + acc2 / (scales[part] * scales[part])) - 1.0)
                    if cost < E[b, c]:
                        E[b, c] = cost
                        back[i + 1, b, c] = a
        for b in range(S):
            for c in range(S):
                D[b, c] = E[b, c]
    best = inf
    bb = 0
    cc = 0
    for b in range(S):
        for c in range(S):
            if D[b, c] < best:
                best = D[b, c]
                bb = b
                cc = c
    s = np.zeros(N, dtype=np.int64)
    if best == inf:
        return s, best
    s[N - 1] = cc
    s[N - 2] = bb
    for i in range(N - 1, 1, -1):
        s[i - 2] = back[i, s[i - 1], s[i]]
    return s, best
