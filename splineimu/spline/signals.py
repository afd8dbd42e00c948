"""The R3 signals the knot choice fits: the rotation as accumulated body-frame increments
(white pose noise stays white in them, their time derivative is the body rate; at high rates
or noise their low band comes from block anchors, :func:`rotation_increments`), and the
largest rotation spacing the input's turning allows."""

from __future__ import annotations

import math

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


def rotation_increments(R, block=1, inc=None):
    """Body-frame increments ``Log(R_{m-1}^T R_m)`` (N - 1, 3) of rotations R (N, 3, 3) (``inc``:
    the plain ones, where already at hand).

    Summed, the increments of noisy rotations random-walk: each step's second-order term
    (~sigma^2 / 2, a cross product of two poses' noise) does not telescope as the first-order
    noise does. At a high rate that walk is motion to a slow fit (0.1 deg: the 1 s means of
    the sum spread 1.2x as far as the white noise's at 200 Hz, 2.4x at 1 kHz, 13-22x at 10 kHz;
    the screw scene at 10 kHz got 0.6-0.95 s rotation knots, gyro 4-7.6x the best fixed
    setting, now 0.93-0.96x). With ``block`` > 1 (see
    :func:`anchor_block`) the sum's content below a quarter of the block rate is taken from a
    development about anchors, the mean rotations of consecutive blocks of that many poses,
    whose steps carry 1/block of the noise (walk down by block^1.5); above it the increments
    are kept (the anchors' blending would add kinks there)."""
    if inc is None:
        inc = lie.so3_log(np.matmul(np.swapaxes(R[:-1], 1, 2), R[1:]))
    if block <= 1 or R.shape[0] < 4 * block:
        return inc
    d = accumulate(inc) - _anchored(R, block)
    for _ in range(2):  # triangular moving average over ~4 blocks
        d = moving_mean(d, 2 * block)
    return inc - np.diff(d, axis=0)


def moving_mean(x, size):
    """Means of ``size`` consecutive rows of x (N, ...) about each row, the ends continued by
    their edge rows (as scipy.ndimage's ``uniform_filter1d(x, size, axis=0, mode="nearest")``,
    whose import would add 0.1-0.4 s to every fit)."""
    left = size // 2
    pad = np.concatenate([np.repeat(x[:1], left, axis=0), x, np.repeat(x[-1:], size - 1 - left, axis=0)])
    c = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(pad, axis=0)])
    return (c[size:] - c[:-size]) / size


#: Rotations sampled at spacings of half this or less (666 Hz and faster) are developed about
#: block anchors of at least this length for the knot choice (:func:`rotation_increments`) ...
ANCHOR_SPACING_S = 3e-3
#: ... and those from 100 Hz up whose noise is large for their rate
#: (:data:`WALKING_NOISE_RAD_S`) about anchors of this length (at least two poses). The walk's
#: second-order part grows as (sigma / h)^2 against the white noise: at 200 Hz with 1 deg white
#: pose noise (sigma / h = 3.5 rad/s) the sum's 1 s means spread 7.7-7.9x as far as the noise's
#: (ellipse, circle, rate-table), which the choice read as the rotation's bias: the circle scene,
#: whose turn a spline follows exactly, read 1.3-2e-3 rad/s at 2-4 s knots, predicted gyro 3.6x
#: the measured on 2 of 5 seeds (1.8-2.2x at 100 Hz), and the rate-table got 1.22x the best fixed
#: setting; with 20 ms anchors, predicted 0.77-1.19x the measured on the six scenes at 100 and
#: 200 Hz (2.1x the noise's spread left, the part a turning body's noise has as well). At 1 kHz
#: the 3 ms anchors (two poses) left the circle and screw scenes at 1.85x and 1.84x the best fixed
#: setting with 1 deg of noise (30 s); with 20 ms 0.55x and 0.69x. At 10 kHz (30 poses) the
#: choices are the same either way.
NOISY_ANCHOR_S = 0.02
#: Those anchors from this ratio of the rotation noise (per axis, from the increments'
#: differences) to the pose spacing [rad/s]: 0.29 deg at 100 Hz, 0.14 deg at 200 Hz, 0.03 deg at
#: 1 kHz. Below it the walk is within the noise realization's scatter: with anchors at 1 mm /
#: 0.1 deg the choices moved either way by chance (120 Hz: 3 of 36 scene cases 1.00-1.02 ->
#: 1.12-1.14x the best fixed setting; 200 Hz: one 0.79 -> 0.51x); at 3x that noise (200 Hz,
#: anchored) every case stayed within the bars.
WALKING_NOISE_RAD_S = 0.5


def anchor_block(t, inc=None):
    """Poses per anchor block of :func:`rotation_increments` for stamps t and the plain rotation
    increments ``inc`` (N - 1, 3) (1: no anchors; without them the noise is not read: 3 ms blocks
    from 666 Hz, none below)."""
    h = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    if not h > 0:
        return 1
    block = int(ANCHOR_SPACING_S / h)
    block = block if block >= 2 else 1
    noisy = int(NOISY_ANCHOR_S / h + 1e-6)
    if noisy < 2 or inc is None or rotation_noise(inc) < WALKING_NOISE_RAD_S * h:
        return block
    return max(block, noisy)


#: Poses (the middle ones) from which :func:`rotation_noise` is read.
NOISE_POSES = 100_000


def rotation_noise(inc):
    """White noise (per axis, the axes' mean) of rotations from their body-frame increments
    ``inc`` (N - 1, 3): :func:`difference_noise` of their sum's second differences (within 1% on
    the analytic scenes at 100-200 Hz, 1.2-1.7x on the flips scene's fast turns at 100 Hz and
    0.05-0.1 deg)."""
    if inc.shape[0] < 7:
        return 0.0
    lo = max((inc.shape[0] - NOISE_POSES) // 2, 0)
    return float(difference_noise(accumulate(inc[lo: lo + NOISE_POSES]), 2).mean())


def difference_noise(X, k):
    """Per-axis white noise of X (N, ...), robustly from its k-th differences (the median absolute
    deviation; white noise: var = C(2k, k) sigma^2)."""
    d = np.diff(X, k, axis=0)
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0) / 0.6745
    return mad / np.sqrt(math.comb(2 * k, k))


def _anchored(R, block):
    """A development (N, 3) of rotations R about the mean rotations ``A_j`` of consecutive
    blocks: ``phi_j + Log(A_j^T R_m)``, with ``phi`` the summed anchor steps, blended linearly
    between the two anchors whose centres bracket pose m."""
    n = R.shape[0]
    nb = n // block
    idx = np.minimum(np.arange(n) // block, nb - 1)
    q = lie.matrix_to_quat_xyzw(R)
    q = q * np.where(np.sum(q * q[idx * block], axis=1) < 0, -1.0, 1.0)[:, None]
    sums = np.zeros((nb, 4))
    np.add.at(sums, idx, q)
    A = lie.quat_xyzw_to_matrix(sums / np.linalg.norm(sums, axis=1, keepdims=True))
    centre = np.bincount(idx, weights=np.arange(n), minlength=nb) / np.bincount(idx, minlength=nb)
    steps = lie.so3_log(np.matmul(np.swapaxes(A[:-1], 1, 2), A[1:]))
    phi = accumulate(steps)
    m = np.arange(n)
    j = np.clip(np.searchsorted(centre, m, side="right") - 1, 0, nb - 2)
    lam = np.clip((m - centre[j]) / (centre[j + 1] - centre[j]), 0.0, 1.0)[:, None]
    lo = lie.so3_log(np.matmul(np.swapaxes(A[j], 1, 2), R))
    hi = lie.so3_log(np.matmul(np.swapaxes(A[j + 1], 1, 2), R))
    return phi[j] + (1.0 - lam) * lo + lam * (steps[j] + hi)


def accumulate(inc):
    """Running sums (N, 3) of increments (N - 1, 3), from zero."""
    return np.vstack([np.zeros(3), np.cumsum(inc, axis=0)])


def rotation_signal(R):
    """Accumulated body-frame increments (N, 3) of rotations R (N, 3, 3)."""
    return accumulate(rotation_increments(R))
