"""Where the rotation's knot grid sits against the motion (step 6 of :mod:`.knots`).

At one knot spacing the gyro error of a fit still depends on where the knots fall against the
turns: a turn that starts at a knot is followed better than one that starts inside a segment.
On the rate-table scene (turns about fixed axes, 1 mm / 0.1 deg pose noise, 100 Hz) the gyro
error at 550 ms knots is 0.98-1.45x that of the grid on the first pose as the grid is moved by
eighths of a spacing, and 1.0-1.4x over +-4 segments on the same span (each count puts the
turns at other places in their segments); the errors of fixed settings are rough in the
spacing for that reason, and the best of a grid of them partly luck. The fit residual tells the
grids apart: one that follows the turns worse leaves more of them in the residual (correlation
0.96-0.99 with the gyro error over the shifts there, white and upsampled noise, 100 and 200 Hz).

Tried: :data:`PHASES` of the spacing before the first pose, each at the chosen segment count
and one segment either side (:data:`SEGMENT_STEPS`, from :data:`MIN_SEGMENTS_TO_STEP`
segments: a step of at most 2.5% of the spacing), fitting the R3 signal the choice fits and its
noise surrogate together. The grid with the least residual (the windows' scored poses) is taken
where the signal's residuals spread over the grids by more than :data:`NOISE_SPREADS` times the
surrogate's, i.e. more than the noise alone makes them; otherwise the grid stays on the first
pose. On smooth motion the residual's spread is the noise's, and there its ranking did not
follow the gyro's (lecture ellipse at 1 s knots, AR(1) noise: the least residual at the worst
gyro, 0.90-1.01x, end effects included); a gate on the relative spread alone (1.2%) let AR(1)
noise through on held-out motions (drone, car: 0.96-0.98 -> 1.00-1.01x).

Scene sweep, 6 scenes x white/AR(1)/upsampled noise x seeds 0-9 (benchmarks/scene_sweep.py),
gyro against the best fixed setting: 200 Hz mean 0.870 -> 0.855 (rate-table upsampled worst
1.290 -> 1.183, six-position AR(1) 1.086 -> 1.027, upsampled 1.130 -> 1.062; no scene's worst
up by more than 0.003), 100 Hz mean 0.909 -> 0.888 and cases above the bars 10 -> 6
(rate-table upsampled 1.424 -> 1.240, AR(1) 1.136 -> 1.020; rate-table white, 1.16-1.27x on 5
seeds, is the spacing's, not the phase's). Held-out motions (benchmarks/heldout_motions.py,
draws 1-2): 5 of 30 cases moved, to 0.98-1.09x of their earlier ratio. Where it does not
help: the spacing itself (the phase does not make up for a spacing a rung off); long inputs
are judged on their windows (each on the one grid over all of the input).

A split spline's rotation grid then starts that much before the first pose and has one segment
more; the position grid keeps its first knot on the first pose, so the spline still covers
exactly the poses' span. An se3 spline (one grid) keeps the spacing but not the shift.
"""

from __future__ import annotations

import numpy as np

from .banded import layout

#: The grid's shifts tried, in fractions of the spacing before the first pose.
PHASES = (0.0, 0.25, 0.5, 0.75)
#: Segment counts tried about the chosen one (the span fixed: the spacing moves a little).
SEGMENT_STEPS = (-1, 0, 1)
#: The least segment count at which other counts are tried.
MIN_SEGMENTS_TO_STEP = 40
#: The grid moves where the signal's residuals over the grids spread more than this many times
#: the noise surrogate's (its fits are the same: their spread is what the noise alone makes).
NOISE_SPREADS = 2.0


def choose_phase(windows, noises, k, dt, t_first, t_last):
    """``(phase, spacing)`` of the order-``k`` grid over [t_first, t_last] whose fits of the
    windows' signals leave the least squared residual (or ``(0.0, dt)``, see module notes)."""
    span = float(t_last - t_first)
    nseg = layout(t_first, t_last, dt, k)[2]
    both = [np.ascontiguousarray(np.hstack([wd.X, nz])) for wd, nz in zip(windows, noises)]
    scored = [x[wd.scored_index] for wd, x in zip(windows, both)]
    grids, totals = [], []
    for step in SEGMENT_STEPS if nseg >= MIN_SEGMENTS_TO_STEP else (0,):
        h = span / (nseg + step)
        for phase in PHASES:
            c = np.zeros(both[0].shape[1])
            for wd, x, xs in zip(windows, both, scored):
                e = xs - wd.derivative(k, h, wd.zero, 1, 0, x, origin=t_first - phase * h)[0][wd.scored_index]
                c += np.einsum("ij,ij->j", e, e)
            grids.append((phase, h))
            totals.append((c[:3].sum(), c[3:].sum()))
    totals = np.array(totals)
    spread = totals.max(axis=0) - totals.min(axis=0)
    # (the shifts at one segment count alone spread less: gated on them, 100 Hz cases above the
    # bars went 6 -> 9, rate-table upsampled 1.24 -> 1.42x)
    if not (np.all(np.isfinite(totals)) and spread[0] > NOISE_SPREADS * spread[1]):
        return 0.0, float(dt)
    return grids[int(np.argmin(totals[:, 0]))]
