"""Where the synthesized IMU is less sure than the knot choice's prediction for the interior:
the ends, where the fit sees one-sided data, and the gaps between poses, where the IMU is the
fit's guess. Both are measured on the input itself, with the fits the choice uses
(:class:`~splineimu.spline.crossval._Window`): the ends by cutting the input short near them,
the gaps by opening gaps of the same length where there are poses (:mod:`splineimu.spline.knots`
reports them and warns)."""

from __future__ import annotations

from math import comb

import numpy as np

from .crossval import _Window

#: The least ratio of the signal's to the surrogate's truncation difference at which the ends'
#: motion error is counted (:func:`end_bias2`).
_END_MOTION = 4.0
#: Where the input is cut for :func:`end_bias2`, in end zones from its end.
_END_CUTS = np.array([1.0, 1.5, 2.0, 2.5])
#: The most the last zone's motion change may scale the cuts' estimate up (:func:`end_bias2`).
_END_CHANGE_MAX = 4.0


#: A pose interval longer than this many median spacings is a gap, across which the IMU is the
#: fit's guess (as the turn check, checks.check_rotation_steps, counts them).
GAP_SPACINGS = 3.0
#: Places where gaps of the input's lengths are opened to measure the error inside (_gap_bias2).
_GAP_PLACES = 6
#: Gap lengths measured at most (others interpolated in log-log).
_GAP_LENGTHS = 4


def find_gaps(t, w):
    """(start, end) [s] of the gaps between the weighted poses (intervals > GAP_SPACINGS
    median spacings)."""
    tw = t[w > 0]
    if tw.size < 3:
        return []
    d = np.diff(tw)
    big = np.flatnonzero(d > GAP_SPACINGS * float(np.median(d)))
    return [(float(tw[i]), float(tw[i + 1])) for i in big]


def _gap_bias2(windows, noises, k, dt, r, zone, lengths):
    """The mean squared r-th derivative error inside gaps of ``lengths`` [s], measured by opening
    such gaps where there are poses: the fit of a stretch around the place with the poses inside
    left out against the fit with them, over the gap (the other is interior there), at up to
    :data:`_GAP_PLACES` places spread over the windows. NaN where no place has room. Flips at 200
    Hz with white noise: gyro 1.34 rad/s inside a 0.4 s gap (bridged without a word) against
    0.024 elsewhere."""
    out = np.full(len(lengths), np.nan)
    per = max(_GAP_PLACES // len(windows), 1)
    spacing = [float(np.median(np.diff(wd.t))) for wd in windows]
    for j, G in enumerate(lengths):
        acc = n = 0.0
        for wd, nz, h in zip(windows, noises, spacing):
            t, w = wd.t, wd.w
            reach = G / 2.0 + 3.0 * zone
            if t[-1] - t[0] <= 2.0 * reach:
                continue
            for c in np.linspace(t[0] + reach, t[-1] - reach, per + 2)[1:-1]:
                sel = np.flatnonzero((t >= c - reach) & (t <= c + reach))
                near = sel[np.abs(t[sel] - c) <= G / 2.0 + zone]
                edge = G / 2.0 + zone - GAP_SPACINGS * h  # (poses up to both ends of the place: one
                # beside a gap of the input's, which near's own spacing does not show, read a longer gap)
                if (near.size < 2 or np.any(w[near] <= 0) or np.any(np.diff(t[near]) > GAP_SPACINGS * h)
                        or t[near[0]] > c - edge or t[near[-1]] < c + edge):
                    continue  # a gap or left-out poses there already
                ts = t[sel]
                inside = (ts > c - G / 2.0) & (ts < c + G / 2.0)
                Y = np.ascontiguousarray(np.hstack([wd.X[sel], nz[sel]]))
                a = _Window(ts, Y, w[sel])
                b = _Window(ts, Y, np.where(inside, 0.0, w[sel]))
                d = a.derivative(k, dt, a.zero, 1, r)[0][inside] - b.derivative(k, dt, b.zero, 1, r)[0][inside]
                if np.all(np.isfinite(d)):
                    acc += float(np.sum(d[:, :3] ** 2))
                    n += int(np.count_nonzero(inside))
        if n:
            out[j] = acc / n
    return out


def gap_predictions(windows, noises, k, dt, r, zone, gaps, pred):
    """[(start, end, predicted r-th derivative error RMS)] over each of ``gaps``; None for a gap
    longer than the knot spacing ``dt`` and than any gap that could be opened where there are
    poses (its error is not measured: BROAD 07 with 20 s of its mocap left out, windows of 14 s,
    was bridged with no gap_bridged warning). A gap within a knot spacing that cannot be measured
    (the end zones around it too long for the input) is left out, as it costs little."""
    if not gaps:
        return []
    length = np.array([b - a for a, b in gaps])
    probe = np.unique(np.geomspace(length.min(), length.max(), _GAP_LENGTHS)) if length.size > 1 else length
    e2 = _gap_bias2(windows, noises, k, dt, r, zone, probe)
    ok = np.isfinite(e2) & (e2 > 0)
    if not ok.any():
        return [(a, b, None) for a, b in gaps if b - a > dt]
    if ok.sum() == 1:
        at = np.full(length.size, e2[ok][0])
    else:
        at = np.exp(np.interp(np.log(length), np.log(probe[ok]), np.log(e2[ok])))
    longest = max(float(probe[ok].max()), dt) * (1.0 + 1e-9)
    return [(a, b, float(np.sqrt(pred**2 + e)) if b - a <= longest else None) for (a, b), e in zip(gaps, at)]


def _change(t, X, m, lag, ranges):
    """Mean squared m-th difference of X at ``lag`` samples over the differences centred in each
    [lo, hi] of ``ranges`` (NaN: none): how much the motion's derivative r = m - 1 changes there."""
    n = X.shape[0]
    if n <= m * lag:
        return [np.nan] * len(ranges)
    D = sum(comb(m, j) * (-1.0) ** (m - j) * X[j * lag: n - (m - j) * lag] for j in range(m + 1))
    D2 = np.sum(D**2, axis=1)
    centre = t[(m * lag) // 2: (m * lag) // 2 + D.shape[0]]
    out = []
    for lo, hi in ranges:
        sel = (centre >= lo) & (centre <= hi)
        out.append(float(np.mean(D2[sel])) if np.any(sel) else np.nan)
    return out


def end_bias2(windows, noises, k, dt, r, zone):
    """The squared r-th derivative error the ends add to the interior's through the motion a
    one-sided fit misses, measured by truncation: the fit of the last (first) 6 ``zone`` of the
    input and those of the same poses cut 1-2.5 zones before the end differ, over the ``zone``
    before each cut, by the cut fit's end error (the other is interior there). The surrogate's
    difference is the noise's share of it (counted already) and taken off; it is counted only
    where the motion's share dominates (:data:`_END_MOTION`): one zone's difference of noisy
    poses scatters (BROAD 05, 11, 16: the signal's 1.6-2.6x the surrogate's, with measured
    ends within 1.3-2.6x of the interior against the real IMU). Exact or clean
    low-rate input: the noise part alone predicted 0.001-0.2 m/s^2 where the ends' accel is
    0.2-2.4 m/s^2 off (ellipse at 2-20 Hz). The cuts lie up to 3.5 zones in, so the estimate is
    scaled by how much the motion's derivative changes over the last zone against over the cuts'
    (:func:`_change`, at most :data:`_END_CHANGE_MAX` x): drones that land a second before the
    end and then rest (EuRoC V2_03, vicon2gt V1_02) had their ends warned about for the landing.
    Returns 0 where the input is shorter than 4 zones."""
    worst = 0.0
    span = (_END_CUTS[-1] + 3.5) * zone
    for wd, nz, tail in ((windows[0], noises[0], False), (windows[-1], noises[-1], True)):
        # the end's stretch alone; the head as the tail of the reversed input (squared errors
        # keep no sign)
        sel = wd.t >= wd.t[-1] - span if tail else wd.t <= wd.t[0] + span
        t, Y, w = wd.t[sel], np.hstack([wd.X[sel], nz[sel]]), wd.w[sel]
        if not tail:
            t, Y, w = wd.t[-1] - t[::-1], Y[::-1], w[::-1]
        a = max(t[-1] - span, t[0])
        full = t >= a
        da = _Window(t[full], np.ascontiguousarray(Y[full]), w[full])
        ref = None
        sig = sur = 0.0
        n = 0
        for c in t[-1] - _END_CUTS * zone:
            short = full & (t <= c)
            near = t[short] >= c - zone
            if c - zone - a < 2.0 * zone or np.count_nonzero(near) < 2 or np.count_nonzero(w[short] > 0) <= k:
                continue
            if ref is None:
                ref = da.derivative(k, dt, da.zero, 1, r)[0].copy()
            db = _Window(t[short], np.ascontiguousarray(Y[short]), w[short])
            d = ref[:near.size][near] - db.derivative(k, dt, db.zero, 1, r)[0][near]
            if np.all(np.isfinite(d)):
                sig, sur = sig + np.sum(d[:, :3] ** 2), sur + np.sum(d[:, 3:] ** 2)
                n += d.shape[0]
        if n and sig > _END_MOTION * sur:
            # the cuts lie up to 3.5 zones in: scaled by how much the motion changes in the last
            # zone against there (a landing 1 s before the end, then rest, is no error of the end)
            lag = max(int(round(dt / float(np.median(np.diff(wd.t))))), 1)
            cuts = t[-1] - _END_CUTS * zone
            here, there = _change(t, Y[:, :3], r + 1, lag, ((t[-1] - zone, t[-1]), (cuts.min() - zone, cuts.max())))
            ratio = min(here / there, _END_CHANGE_MAX) if there > 0 else 1.0
            worst = max(worst, (sig - sur) / n * (ratio if np.isfinite(ratio) else 1.0))
    return worst
