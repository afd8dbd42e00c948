"""Kernel of the stamps' re-timing (:mod:`splineimu.stamps`): the slot of each pose on a capture
clock, by dynamic programming over its delivery delay in whole periods."""

from __future__ import annotations

import numpy as np

from .._jit import jit


@jit
def _velocities(Y, i, m, h, S, ok, V):
    """``V[a, b]`` (S, S, 6): the velocity from pose i (delay a) to pose i + 1 (delay b), for the
    pairs ``ok[a, b]`` whose slots increase."""
    for a in range(S):
        for b in range(S):
            if ok[a, b]:
                d = ((m[i + 1] - b) - (m[i] - a)) * h
                for j in range(6):
                    V[a, b, j] = (Y[i + 1, j] - Y[i, j]) / d


@jit
def assign_slots(m, Y, scales, h, S, prior, back):
    """Delays ``s`` (N,) in periods, ``0 <= s < S``, below the latest slots ``m`` (N,) the stamps
    allow (strictly increasing), such that the slots ``n = m - s`` increase strictly and the poses
    ``Y`` (N, 6: position and accumulated rotation) move smoothly at the slot times ``n h``: the
    cost of pose i is the pseudo-Huber norm of its second difference (per part, in units of
    ``scales``) plus ``prior`` per period of delay. ``back`` (N, S, S) int8 scratch. Returns the
    least total cost (inf: no strictly increasing assignment within S).

    Each state (delays of poses i and i + 1) takes the least over the delay of pose i - 1, whose
    candidates are visited in order of their cost so far: the smoothness term is never negative,
    so the visit stops at the first whose cost so far already reaches the best found (the work
    per pose falls from S^3 terms to about S^2)."""
    N = m.shape[0]
    inf = np.inf
    D = np.full((S, S), inf)  # D[a, b]: least cost with s_{i-1} = a, s_i = b
    for a in range(S):
        for b in range(S):
            if m[1] - b > m[0] - a:
                D[a, b] = prior * (a + b)
    E = np.empty((S, S))
    V1 = np.zeros((S, S, 6))  # velocities of the pairs (i - 1, i) ...
    V2 = np.zeros((S, S, 6))  # ... and (i, i + 1)
    ok = np.empty((S, S), dtype=np.bool_)
    for a in range(S):
        for b in range(S):
            ok[a, b] = D[a, b] < inf
    _velocities(Y, 0, m, h, S, ok, V1)
    inv0 = 1.0 / (scales[0] * scales[0])
    inv1 = 1.0 / (scales[1] * scales[1])
    cand = np.empty(S, dtype=np.int64)
    key = np.empty(S)
    for i in range(1, N - 1):
        for b in range(S):
            for c in range(S):
                E[b, c] = inf
                ok[b, c] = m[i + 1] - c > m[i] - b
        _velocities(Y, i, m, h, S, ok, V2)
        for b in range(S):
            nb = m[i] - b
            cnt = 0
            for a in range(S):
                if D[a, b] < inf:
                    cand[cnt] = a
                    key[cnt] = D[a, b]
                    cnt += 1
            if cnt == 0:
                continue
            order = np.argsort(key[:cnt], kind="mergesort")
            for c in range(S):
                if not ok[b, c]:
                    continue
                d2 = (m[i + 1] - c - nb) * h
                pc = prior * c
                for o in range(cnt):
                    a = cand[order[o]]
                    base = D[a, b] + pc
                    if base >= E[b, c]:
                        break
                    d1 = (nb - (m[i - 1] - a)) * h
                    acc2p = 0.0
                    acc2r = 0.0
                    for z in range(3):
                        accp = 2.0 * (V2[b, c, z] - V1[a, b, z]) / (d1 + d2)
                        accr = 2.0 * (V2[b, c, 3 + z] - V1[a, b, 3 + z]) / (d1 + d2)
                        acc2p += accp * accp
                        acc2r += accr * accr
                    cost = base + 2.0 * (np.sqrt(1.0 + acc2p * inv0) - 1.0) + 2.0 * (np.sqrt(1.0 + acc2r * inv1) - 1.0)
                    if cost < E[b, c]:
                        E[b, c] = cost
                        back[i + 1, b, c] = a
        for b in range(S):
            for c in range(S):
                D[b, c] = E[b, c]
        V1, V2 = V2, V1
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
