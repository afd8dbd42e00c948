"""The derivative's predicted error on a ladder of knot spacings: step 3 of the knot choice
(:mod:`splineimu.spline.knots`, whose module notes give the method and its measurements)."""

from __future__ import annotations

import numpy as np

from .._kernels import cv as _kcv

#: Ratio between neighbouring spacings where the derivative's error is predicted.
_LADDER = 1.25
#: Most rungs the ladder is walked on past either end while its smallest error sits there.
_WALK_RUNGS = 8


def _ladder_errors(windows, k, ladder, noises, r, lag=1.0, finest=False):
    """Predicted r-th derivative error at the spacings ``ladder[1:]`` of a geometric ladder.

    Each rung fits the signal and the noise surrogate together (one system, six columns): the
    noise part is the surrogate fit's derivative; the bias part is the change of the signal
    fit's derivative from the rung below (with ``finest``, from the first rung), less that of
    the surrogate fit's, times ``lag`` (see :data:`.knots.WHITE_BIAS_LAG`). Returns (noise
    variance, bias^2, per-window noise profiles) for each rung above the first.
    """
    var = np.zeros(len(ladder))
    bias2 = np.zeros(len(ladder))
    both = [np.ascontiguousarray(np.hstack([wd.X, nz])) for wd, nz in zip(windows, noises)]
    idx = [wd.scored_index for wd in windows]
    ends = []
    prev = [None] * len(windows)
    for j, dt in enumerate(ladder):
        nsc = 0
        change = 0.0
        e_list = []
        for i, wd in enumerate(windows):
            d = wd.derivative(k, dt, wd.zero, 1, r, both[i])[0]
            e2 = np.empty(wd.t.size)
            ds = np.empty((idx[i].size, 6))
            v, c = _kcv.ladder_stats(d, idx[i], ds if prev[i] is None else prev[i], prev[i] is not None, e2, ds,
                                     wd._scratch("ladder", (3 * idx[i].size,)))
            var[j] += v
            nsc += wd.n_scored
            if prev[i] is not None:
                change += c
            if prev[i] is None or not finest:
                prev[i] = ds
            e_list.append((wd.t, e2))
        var[j] = var[j] / max(nsc, 1) if np.isfinite(var[j]) else np.inf
        bias2[j] = lag * max(change / max(nsc, 1), 0.0) if np.isfinite(change) else np.inf
        ends.append(e_list)
    return var[1:], bias2[1:], ends[1:]


#: A best rung whose bias^2 is at most this share of its noise part (none read) is moved
#: between rungs (:func:`_between_rungs`). 0.25 moved the six-position scene's lucky rung too
#: (gyro 1.02 -> 1.20x the best fixed setting).
_BIAS_UNREAD = 1e-12


def _between_rungs(best, ladder, rows, windows, noises, r, lag):
    """A best rung whose bias estimate came out at or below zero (its prediction is the noise
    part alone, low by the bias) moved to the vertex of the parabola through its and its two
    neighbours' predictions in log spacing, at most half a rung away, with its own prediction.
    The ellipse's rotation (white noise, 200 Hz): every seed's best rung, 1017 ms, read no bias
    for a true 4e-4 rad/s (the change from the rung below is within the noise realization's
    scatter; other surrogate draws never moved it), gyro 1.00-1.15x the best fixed setting
    (905 ms, between the rungs) over seeds 1-10; at the vertex (937-968 ms, of the predictions
    with the floor of :func:`_extrapolate_bias`; the rung's own reading decides) 0.94-1.08x.
    Not applied where the bias was read: the six-position and rate-table scenes' errors are
    rough in the spacing (the knots' phase against their turns, +-15%), where a vertex moved
    them by chance (1.02 -> 1.14-1.20x)."""
    _, k, dt, _, _, dt_cv = best
    j = int(np.argmin(np.abs(np.log(ladder / dt))))
    if not 2 <= j <= ladder.size - 2:  # the rung below the first is a reference only
        return best
    pred = {round(float(np.log(row["knot_spacing_s"])), 9): row["predicted_rms"] for row in rows if row["order"] == k}
    em, e0, ep = (pred.get(round(float(np.log(x)), 9)) for x in ladder[j - 1: j + 2])
    if None in (em, e0, ep) or em + ep - 2.0 * e0 <= 0.0:
        return best
    x = float(np.clip((em - ep) / (2.0 * (em + ep - 2.0 * e0)), -0.5, 0.5))
    if abs(x) < 0.05:
        return best
    dn = dt * _LADDER**x
    var, bias2, ends = _ladder_errors(windows, k, np.array([dn / _LADDER, dn]), noises, r, lag)
    return float(np.sqrt(var[0] + bias2[0])), k, float(dn), float(var[0]), ends[0], dt_cv


def _extrapolate_bias(dts, var, bias2, p):
    """Bias^2 estimates of the rungs ``dts`` (increasing) floored by the nearest rung above
    whose estimate exceeds its noise part, scaled down as dt^p (the asymptotic order of a
    spline's bias: p = k - r for order k and derivative r) or as the bias grows from it to the
    next such rung where that is steeper.

    Below the noise part the estimate (the change from the rung below) is within the noise
    realization's scatter, and it lags a bias that grows with the spacing. The ellipse at
    1 kHz (white noise): its order-6 rungs read 1.3e-4 and 1.6e-4 rad/s at 794 and 992 ms for
    a true 1e-4 and 2.7e-4; the clear readings at 1240 and 1550 ms (1.0e-3 and 3.8e-3, as
    dt^5.9) scaled down give 0.7e-4 and 2.7e-4, and the choice went from 992 to 794 ms (gyro
    1.24-1.30x the best fixed setting on 3 of 6 seeds, now 0.91-0.94x on all). Closer to the
    cut-off the bias grows faster than dt^p, and a clear reading can itself be high (the flips
    scene's rotation proxy at 10 kHz read 2x the bias at 70 ms): scaled by dt^5 alone the floor
    sent the flips scene at 10 kHz to finer knots, 1.16-1.21x; with the steeper power 0.98x.
    Elsewhere within the bars either way (flips at 1 kHz 0.92-0.94x before, 1.07-1.14x now;
    rate-table at 1 kHz 1.12x before, 0.98x now). Applied where the gyro's estimate is doubled
    (noise read as white, :data:`.knots.WHITE_SLOPE`; AR(1) or upsampled noise under a coarse fit can
    read so). At 200 Hz, over 54 held-out cases (5 kinds of sum-of-sines motion, white, AR(1)
    and upsampled noise, 100-360 Hz, 0.2-3 mm): mean gyro ratio 0.975 -> 0.986x, worst
    unchanged (white 1.14x, coloured 1.18x); single cases moved either way (hand-held AR(1)
    0.88 -> 1.09x, slow white 1.03 -> 1.10x; rate-table AR(1) 1.11 -> 0.98x). Applied to the
    position too where its noise reads uncorrelated and flatter than f^-1 (the flips scene over 20 s: its
    value-optimal rung read no bias, accel 1.28-1.39x the best fixed setting on 5 of 13 seeds)."""
    out = bias2.copy()
    clear = np.flatnonzero((bias2 > var) & np.isfinite(bias2))  # (singular rungs read inf)
    for j in range(dts.size):
        above = clear[clear > j]
        if bias2[j] <= var[j] and above.size:
            i = above[0]
            q = p
            if above.size > 1:  # steeper between the clear rungs: that power
                with np.errstate(divide="ignore", over="ignore", under="ignore"):
                    g = 0.5 * np.log(bias2[above[1]] / bias2[i]) / np.log(dts[above[1]] / dts[i])
                q = max(p, g) if np.isfinite(g) else p
            with np.errstate(under="ignore"):
                out[j] = max(bias2[j], bias2[i] * (dts[j] / dts[i]) ** (2 * q))
    return out


def _walk_ladder(windows, k, ladder, noises, r, lo, hi, lag=1.0):
    """:func:`_ladder_errors` on ``ladder``, walked on two rungs at a time past whichever end
    holds the smallest predicted error while the error falls toward it (at most
    :data:`_WALK_RUNGS` rungs each way, within [lo, hi]): the derivative's optimum can lie
    several rungs from the value-optimal spacing the ladder is centred on. Returns the ladder
    and the errors of its rungs above the first."""
    var, bias2, ends = _ladder_errors(windows, k, ladder, noises, r, lag)
    up = down = 0
    while var.size >= 3:
        e = var + bias2
        j = int(np.argmin(e))
        # only a trend is followed: the error falls over the two rungs next to that end (a
        # single rung's scatter in the prediction is no reason to leave the ladder)
        if j == var.size - 1 and e[-3] > e[-2] and up < _WALK_RUNGS:
            more = ladder[-1] * _LADDER ** np.arange(3)
            more = more[more <= hi * (1.0 + 1e-9)]
        elif j == 0 and e[2] > e[1] and down < _WALK_RUNGS:
            more = ladder[0] * _LADDER ** np.arange(-2, 1)
            more = more[max(int(np.argmax(more >= lo * 0.99)) - 1, 0):] if more[-1] >= lo * 0.99 else more[:1]
        else:
            break
        if more.size < 2:
            break
        v, b, en = _ladder_errors(windows, k, more, noises, r, lag)
        if j == var.size - 1:
            up += v.size
            ladder, var, bias2, ends = np.r_[ladder, more[1:]], np.r_[var, v], np.r_[bias2, b], ends + en
        else:
            down += v.size
            ladder, var, bias2, ends = np.r_[more, ladder[1:]], np.r_[v, var], np.r_[b, bias2], en + ends
    return ladder, var, bias2, ends
