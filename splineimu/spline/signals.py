"""The R3 signals the knot choice fits: the rotation as accumulated body-frame increments
(white pose noise stays white in them, their time derivative is the body rate), and the largest
rotation spacing the input's turning allows."""

from __future__ import annotations

import numpy as np

from .. import lie

#: The rotation spline's neighbouring control rotations may turn by at most this (135 degrees)
#: at the input's fastest rate (increments are taken as the shortest turn, below pi; 60 degrees
#: cost fast smooth rotation a third more gyro error, 90 degrees slow steady turns 1.1-1.3x,
#: see knots.py step 5).
MAX_CONTROL_TURN_RAD = 0.75 * np.pi


def max_rotation_spacing(t, R, limit=MAX_CONTROL_TURN_RAD):
    """Largest rotation knot spacing over which the input turns by at most ``limit`` (default
    :data:`MAX_CONTROL_TURN_RAD`) anywhere (neighbouring control rotations must stay well within
    the shortest-turn range of their increments). Angles are measured over the spacing itself,
    so pose noise does not shrink the limit."""
    n = t.size
    h = float(np.median(np.diff(t))) if n > 1 else 1.0

    Rf = np.ascontiguousarray(R).reshape(n, 9)

    def within(m):
        """Whether the input turns by at most the limit over every m poses; the angle comes from
        the trace of the relative rotation, and from its Log (as the fit measures it) when
        that is within 1e-6 rad of the limit."""
        # windows that span a gap are left out (the fit bridges gaps with the smoothest turn)
        ok = (t[m:] - t[:-m]) <= 1.5 * m * h + 2.0 * h
        if not ok.any():
            return True
        tr = np.einsum("ij,ij->i", Rf[:-m], Rf[m:])
        ang = float(np.arccos(np.clip((np.min(tr[ok]) - 1.0) / 2.0, -1.0, 1.0)))
        if abs(ang - limit) < 1e-6:
            ang = float(np.max(np.linalg.norm(lie.so3_log(np.matmul(np.swapaxes(R[:-m][ok], 1, 2), R[m:][ok])),
                                              axis=1)))
        return ang <= limit

    if n < 2 or not within(1):
        return 0.7 * h
    # grow by at most pi / limit: a turn within the limit over m poses is then below pi over the
    # next m (the angle from the trace wraps beyond pi)
    grow = min(2.0, np.pi / limit)
    m = 1
    while (nxt := max(m + 1, int(m * grow))) < n and within(nxt):
        m = nxt
    if nxt >= n:
        return np.inf
    lo_m, hi_m = m, nxt  # within(lo_m), not within(hi_m)
    while hi_m - lo_m > max(1, lo_m // 8):
        mid = (lo_m + hi_m) // 2
        lo_m, hi_m = (mid, hi_m) if within(mid) else (lo_m, mid)
    return lo_m * h


def rotation_increments(R):
    """Body-frame increments ``Log(R_{m-1}^T R_m)`` (N - 1, 3) of rotations R (N, 3, 3)."""
    return lie.so3_log(np.matmul(np.swapaxes(R[:-1], 1, 2), R[1:]))


def accumulate(inc):
    """Running sums (N, 3) of increments (N - 1, 3), from zero."""
    return np.vstack([np.zeros(3), np.cumsum(inc, axis=0)])


def rotation_signal(R):
    """Accumulated body-frame increments (N, 3) of rotations R (N, 3, 3)."""
    return accumulate(rotation_increments(R))
