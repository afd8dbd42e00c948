"""Tracking glitches to drop, and steps and residual bursts to warn about, from a fit's residuals
and the poses' own jumps.

Outliers (tracking glitches) are told from fast valid motion by two tests that both must hold
for a run of poses:

1. their fit residuals stand out against the *local* residual level (a running median over
   :data:`LOCAL_WINDOW_S`, so that a stretch of fast motion the spline follows less closely
   raises its own yardstick), by :data:`OUTLIER_SIGMAS` and the absolute floors;
2. the data jump *into* the run and *out of* it: the first pose of the run departs from the
   linear extrapolation of the two poses before it, and the last from that of the two after,
   by half the run's residual and by :data:`OUTLIER_SIGMAS` robust sigmas of such
   extrapolation errors nearby (running median). Fast motion is smooth at the pose rate, a
   glitch is not.

A run that passes (1) and jumps in but not out (or out but not in) is a step (the tracking
moved its origin): it cannot be dropped and is warned about with its time range, as is a run
that passes (1) without any jump (motion faster than the spline follows there), once its
residual reaches :data:`WARN_RESIDUAL_M` or :data:`WARN_RESIDUAL_RAD`.

"""

from __future__ import annotations

import numpy as np

from .report import FitWarning

OUTLIER_SIGMAS = 8.0
OUTLIER_FLOOR_M = 2e-3
OUTLIER_FLOOR_RAD = 2e-3
LOCAL_WINDOW_S = 1.0
#: Residual runs that are not dropped are warned about from this size on (m, rad).
WARN_RESIDUAL_M = 5e-3
WARN_RESIDUAL_RAD = np.radians(1.0)
#: Runs of outliers longer than this are not glitches (steps, or motion not followed).
MAX_GLITCH_S = 0.5
#: A glitch found in the poses' own steps (:func:`_jump_glitches`): both steps above this many
#: robust sigmas of the steps nearby (and the warning size). Two matching steps, each with its
#: neighbours' signature, are far stronger evidence than one residual: with 8 sigmas a 2 cm glitch
#: of 200 ms under 1 mm white noise (steps of 8.9 sigmas) went unfound on 5 of 18 cases (accel
#: elsewhere up to 22x the best fixed setting).
STEP_SIGMAS = 6.0
#: ... or above this many, 8 poses or more apart, where the poses between sit off the motion
#: around them by one offset (:func:`_plateau`): for 200 ms under 1 mm white noise, 1.5 cm went
#: unfound on 1 of 18 cases (6 without), 1 cm on 8 (15; 1 with the box means below). At 3
#: sigmas no more were found, and the hour-long fit took 1.2 s more (hundreds of noise pairs).
PLATEAU_SIGMAS = 4.0


#: ... or above this many robust sigmas of the steps of box means of :data:`BOX_POSES` poses
#: (:func:`_box_steps`, 1/sqrt(BOX_POSES) of the single steps' noise), with the poses between
#: off the motion by one offset (:func:`_plateau`, with a quintic): 1 cm for 200 ms under 1 mm
#: white noise (single steps of about 4.5 sigmas) went unfound on 8 of 18 cases, 1 now (3 with
#: a cubic, which does not follow the flips scene's motion over 400 ms).
BOX_SIGMAS = 6.0
BOX_POSES = 8


#: A step of the poses standing alone, with no step back (the tracking moved its origin): above
#: this many robust sigmas of the steps nearby (and the warning size). Tracking steps stand far
#: out (EuRoC MH_04's ground truth: 1300-21000 sigmas, TUM RGB-D fr2_desk's mocap 100-310);
#: motion at 20 Hz makes steps of 6-9 (OpenVINS' okvis and udel_gore trajectories).
LONE_STEP_SIGMAS = 20.0


#: Window x samples up to which the running median runs in the kernel (a few ms); beyond, in
#: scipy.ndimage (O(N log w)), whose import (0.04-0.2 s) is then small next to the fit.
KERNEL_MEDIAN_MAX_WORK = 2e7


def _running_median(x, width):
    """scipy.ndimage ``median_filter(x, size, mode="mirror")`` with an odd ``size`` near ``width``.

    The ends are mirrored, not extended with their first and last values: the spline follows
    the end poses closely, and half a window of copies of the first residual set the local
    level near the start (10 kHz poses, 1 s window: 0.37x the level elsewhere, and valid poses
    8 sigmas above it were dropped as glitches)."""
    size = max(int(width) | 1, 3)
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.size == 0:
        return x.copy()
    h = size // 2
    xp = np.pad(x, h, mode="reflect")
    if xp.size * size > KERNEL_MEDIAN_MAX_WORK:
        from scipy.ndimage import median_filter

        return median_filter(xp, size=size, mode="nearest")[h:h + x.size]
    from .._kernels.median import running_median

    out = np.empty_like(xp)
    running_median(xp, size, out)
    return out[h:h + x.size]


def _extrapolation_errors(t, Y, norm=False):
    """Y_i less its linear extrapolation from i-2, i-1 (forward) and from i+1, i+2 (backward),
    (N, d) each, or with ``norm`` their lengths (N,); zero where the three poses span a gap (more
    than 3 median spacings between two of them)."""
    shape = (t.size,) if norm else Y.shape
    fwd, bwd = np.zeros(shape), np.zeros(shape)
    if t.size < 3:
        return fwd, bwd
    dt = np.diff(t)
    ok = (np.maximum(dt[1:], dt[:-1]) <= 3.0 * np.median(dt))[:, None]  # poses i, i+1, i+2 close together

    def error(x0, x1, x2, r):
        v = np.where(ok, x0 - x1 - r[:, None] * (x1 - x2), 0.0)
        return np.linalg.norm(v, axis=1) if norm else v

    fwd[2:] = error(Y[2:], Y[1:-1], Y[:-2], dt[1:] / dt[:-1])
    bwd[:-2] = error(Y[:-2], Y[1:-1], Y[2:], dt[:-1] / dt[1:])
    return fwd, bwd


def _inner_glitch(t, Y, e, fwd, bwd, jmin, a, b):
    """(first, last) pose of a glitch inside the run [a, b) of large residuals ``e``, or None: a
    jump in before the largest residual and a jump out after it (as large as half of it and as
    the local jump level ``jmin``), by the same offset (the poses between moved together: their
    forward and backward extrapolation errors agree within half their size)."""
    top = float(e[a:b].max())
    peak = a + int(np.argmax(e[a:b]))
    ins = a + np.flatnonzero(fwd[a:peak + 1] > np.maximum(0.5 * top, jmin[a:peak + 1]))
    outs = peak + np.flatnonzero(bwd[peak:b] > np.maximum(0.5 * top, jmin[peak:b]))
    if not (ins.size and outs.size):
        return None
    i, k = int(ins[0]), int(outs[-1])
    jump_in = _extrapolation_errors(t[i - 2:i + 1], Y[i - 2:i + 1])[0][2]  # the vectors of fwd[i], bwd[k]
    jump_out = _extrapolation_errors(t[k:k + 3], Y[k:k + 3])[1][0]
    if np.linalg.norm(jump_in - jump_out) > 0.5 * min(fwd[i], bwd[k]):
        return None
    return i, k


def _steps(t, Y):
    """(N, d) steps of the poses: the move from pose i - 1 to i less the mean of its neighbours'
    moves (i - 2 to i - 1 and i to i + 1, as velocities times the interval); zero where the
    poses span a gap (more than 3 median spacings between two of them) and at the ends. A jump
    of the poses by d at pose i reads d there (its neighbours -d/2); smooth motion, however fast,
    only its jerk (about half the third derivative times h^3), where the poses' extrapolation
    errors read its acceleration (h^2 times it: BROAD 07's fast turns look like one-pose glitches
    to those)."""
    out = np.zeros(Y.shape)
    if t.size < 4:
        return out
    dt = np.diff(t)
    d = np.diff(Y, axis=0)  # d[j]: pose j to j + 1
    v = d / dt[:, None]
    step = out[2:-1]  # poses 2 .. N - 2 (in place: an hour of poses is 17 MB an array)
    np.add(v[:-2], v[2:], out=step)
    step *= (-0.5 * dt[1:-1])[:, None]
    step += d[1:-1]
    step[np.maximum(np.maximum(dt[:-2], dt[1:-1]), dt[2:]) > 3.0 * np.median(dt)] = 0.0
    return out


def _local_median(x, width):
    """The running median of ``x`` over about ``width`` samples, as the running median of medians
    of blocks of width / 8 (a level to compare with, not a filter: an hour of poses at 200 Hz
    in 30 ms, where :func:`_running_median` takes 0.3 s)."""
    b = max(int(width) // 8, 1)
    if b == 1 or x.size < 4 * b:
        return _running_median(x, width)
    nb = x.size // b
    med = np.median(x[:nb * b].reshape(nb, b), axis=1)
    out = np.repeat(_running_median(med, width / b), b)
    return np.r_[out, np.full(x.size - out.size, out[-1])]


def _plateau(t, Y, i, m, J, warn, degree=3):
    """Whether poses i .. m - 1 sit off the motion around them by one offset: a cubic (or a
    polynomial of ``degree``) in time through the poses on both sides (as many as between, at
    least 10 each) leaves the poses between off by a mean at least the warning size and 4x the
    residual outside, agreeing with the steps ``J`` at i and m (within half), and about it no
    more spread than the residual outside (twice its RMS)."""
    k = max(m - i, 10)
    a, b = i - k, m + k
    if a < 0 or b > t.size:
        return False
    side = np.r_[a:i, m:b]
    tc = (t - t[i]) / max(t[m] - t[i], 1e-12)
    V = np.vander(tc[side], degree + 1)
    coef = np.linalg.lstsq(V, Y[side], rcond=None)[0]
    r_out = Y[side] - V @ coef
    s_out = float(np.sqrt(np.mean(np.sum(r_out**2, axis=1))))
    r_in = Y[i:m] - np.vander(tc[i:m], degree + 1) @ coef
    off = r_in.mean(axis=0)
    size = float(np.linalg.norm(off))
    spread = float(np.sqrt(np.mean(np.sum((r_in - off) ** 2, axis=1))))
    return (size >= max(warn, 4.0 * s_out) and np.linalg.norm(off - 0.5 * (J[i] - J[m])) <= 0.5 * size
            and spread <= 2.0 * s_out)


def _box_steps(t, Y, n, h=None):
    """(N, d) steps of box means: the mean of poses i .. i + n - 1 less that of i - n .. i - 1,
    less the mean of that difference n poses before and after (as :func:`_steps` for single
    poses: a jump by d at pose i reads d, linear and quadratic motion nothing, white noise
    1/sqrt(n) of the single steps'); zero where the boxes span a gap (more than 3 median
    spacings ``h`` between two poses) and near the ends."""
    N = t.size
    out = np.zeros(Y.shape)
    if N < 4 * n + 1:
        return out
    # B[i]: the sum of Y[j] - Y[j - n] over j = i .. i + n - 1, from the running sum of those
    # differences (it telescopes to two box sums, so stays within 2n |Y|: a running sum of the
    # poses themselves would round georeferenced ones, hours long, at 1e-4 m)
    c = np.zeros((N - n + 1, Y.shape[1]))
    np.cumsum(Y[n:] - Y[:-n], axis=0, out=c[1:])
    B = np.zeros(Y.shape)
    np.subtract(c[n:], c[:N - 2 * n + 1], out=B[n:N - n + 1])
    B /= n
    out[2 * n:N - 2 * n + 1] = B[2 * n:N - 2 * n + 1] - 0.5 * (B[n:N - 3 * n + 1] + B[3 * n:N - n + 1])
    h = float(np.median(np.diff(t))) if h is None else h
    for g in np.flatnonzero(np.diff(t) > 3.0 * h).tolist():  # (the interval g .. g + 1)
        out[max(g - 2 * n + 1, 0):g + 2 * n + 1] = 0.0
    return out


def _box_glitches(t, Y, J, warn, width, h):
    """(i, m) pairs of glitches of :data:`BOX_POSES` poses or more found by the box steps
    (:func:`_box_steps`): opposite steps (within half the larger) at most :data:`MAX_GLITCH_S`
    apart, each a local peak above :data:`BOX_SIGMAS` robust sigmas and the warning size, placed
    at the largest single step along it within half a box, and confirmed by :func:`_plateau`."""
    n = BOX_POSES
    K = _box_steps(t, Y, n, h)
    size = np.sqrt(np.einsum("ij,ij->i", K, K))
    if not np.any(size > warn):  # (the noise level is read only where a step could count)
        return []
    sigma = _local_median(size, width) / 1.538
    peak = size > np.maximum(BOX_SIGMAS * sigma, warn)
    idx = [i for i in np.flatnonzero(peak).tolist() if size[i] >= size[max(i - n, 0):i + n + 1].max()]

    def strongest(c, u):  # the pose of the largest single step along u within half a box of c
        near = np.arange(max(c - n // 2, 0), min(c + n // 2 + 1, t.size))
        return int(near[np.argmax(J[near] @ u)])

    found = []
    last = -1
    for a_, a in enumerate(idx):
        if a <= last:  # (inside a glitch found)
            continue
        for b in idx[a_ + 1:]:
            if t[b] - t[a] > MAX_GLITCH_S:
                break
            if b - a < n or np.linalg.norm(K[a] + K[b]) > 0.5 * max(size[a], size[b]):
                continue
            u = K[a] / size[a]
            i, m = strongest(a, u), strongest(b, -u)
            # (the offset against the box steps, less noisy; a quintic follows fast motion over
            # the sides, where a cubic left the flips scene's 1 cm glitch under 4x its residual)
            if m - i >= 8 and _plateau(t, Y, i, m, K, warn, degree=5):
                found.append((i, m))
                last = b
                break
    return found


def _jump_glitches(t, parts, w):
    """The poses (bool (N,)) of glitches found in the poses with weight ``w`` > 0: a step by d and a step
    by -d (within half their size) 4 poses or more and at most :data:`MAX_GLITCH_S` apart, each above
    :data:`STEP_SIGMAS` robust sigmas of the steps nearby and the warning size, with its
    neighbours' steps near -d/2 (:func:`_steps`), and the other steps from 5 poses before to 5
    after under 0.7 of them; or above :data:`PLATEAU_SIGMAS`, 8 poses or more apart, with the
    poses between off the motion around them by one offset (:func:`_plateau`); or opposite steps
    of box means (:func:`_box_glitches`) with that offset. Every pose between is dropped (they
    moved together).

    A glitch long against the knots escapes the residual runs: 5 cm for 200 ms was partly
    followed (circle scene: position knots 129 ms, its residual two runs, each warned as a
    step, accel elsewhere 73x the best fixed setting) or smeared over 0.6 s by knots as long as
    itself, above the local residual level nowhere (ellipse, AR(1) noise: nothing told, 2x).

    Also returns the poses (bool (N,)) where a step above :data:`LONE_STEP_SIGMAS` stands alone,
    with no step back: the tracking moved its origin (EuRoC MH_03's ground truth: 8 cm within 5 ms
    at 35.395 s; told here, as the residual runs miss many at coarse knots, and taken off what the
    knot choice reads: :func:`without_steps`)."""
    out = np.zeros(t.size, dtype=bool)
    single = np.zeros(t.size, dtype=bool)
    used = np.flatnonzero(w > 0)  # (poses left out, e.g. resampled ones between the data, are not read)
    every = used.size == t.size
    t = t if every else t[used]
    if t.size < 4:
        return out, single
    h = float(np.median(np.diff(t)))
    width = LOCAL_WINDOW_S / h
    for Y, _, _, _, _, warn in parts:
        Yu = Y if every else Y[used]
        J = _steps(t, Yu)
        size = np.sqrt(np.einsum("ij,ij->i", J, J))
        if not np.any(size > warn):
            continue
        sigma = _local_median(size, width) / 1.538
        level = np.maximum(STEP_SIGMAS * sigma, warn)
        # a step's neighbours read about minus half of it (a glitch of 3 poses or more; shorter
        # ones are the residual runs'): not so the kinks of poses resampled by interpolation
        half = np.zeros(size.size, dtype=bool)
        half[1:-1] = ((np.linalg.norm(J[:-2] + 0.5 * J[1:-1], axis=1) <= 0.5 * size[1:-1])
                      & (np.linalg.norm(J[2:] + 0.5 * J[1:-1], axis=1) <= 0.5 * size[1:-1]))
        idx = np.flatnonzero((size > np.maximum(PLATEAU_SIGMAS * sigma, warn)) & half)
        strong = size > level
        lone = (size > np.maximum(LONE_STEP_SIGMAS * sigma, warn)) & half
        for i in np.flatnonzero(lone).tolist():  # steps standing alone (see the docstring)
            near = np.r_[max(i - 5, 0):i - 1, i + 2:min(i + 6, size.size)]
            if near.size and size[near].max() <= 0.7 * size[i]:
                single[used[i]] = True
        # every pair of such steps 4 poses or more and at most MAX_GLITCH_S apart, in order, and
        # of those the ones whose steps are opposite (within half): at once (an hour of noisy
        # poses has thousands of such steps)
        lo = np.searchsorted(idx, idx + 4)
        cnt = np.maximum(np.searchsorted(t[idx], t[idx] + MAX_GLITCH_S, side="right") - lo, 0)
        first = np.repeat(np.arange(idx.size), cnt)
        second = np.arange(int(cnt.sum())) + np.repeat(lo - np.cumsum(cnt) + cnt, cnt)
        ii, mm = idx[first], idx[second]
        keep = np.linalg.norm(J[ii] + J[mm], axis=1) <= 0.5 * np.minimum(size[ii], size[mm])
        ii, mm = ii[keep], mm[keep]
        last = -1
        for i, m in zip(ii.tolist(), mm.tolist()):
            if i <= last:
                continue
            if not (strong[i] and strong[m]):
                # weaker steps: the poses between must sit off the motion around them by one
                # offset (a long glitch under white noise: 1-1.5 cm for 200 ms under 1 mm)
                if m - i >= 8 and _plateau(t, Yu, i, m, J, warn):
                    out[used[i]:used[m]] = True
                    last = m
                continue
            # (4 poses or more, whose steps inside are the motion's, not a step's neighbours')
            # the two steps stand out: every other step from 5 poses before to 5 after (but
            # their neighbours') is under 0.7 of them (motion at a low pose rate can step as
            # much all around: OpenVINS' udel_gore at 20 Hz, 3 deg, alternating at 10 Hz)
            near = np.r_[max(i - 5, 0):i - 1, i + 2:m - 1, m + 2:min(m + 6, size.size)]
            if near.size == 0 or size[near].max() <= 0.7 * min(size[i], size[m]):
                out[used[i]:used[m]] = True
                last = m
        for i, m in _box_glitches(t, Yu, J, warn, width, h):  # (long glitches under the single steps' noise)
            out[used[i]:used[m]] = True
    single &= ~out
    single[1:] &= ~out[:-1]  # (the step back of a glitch)
    return out, single


def without_steps(t, Y, w, warn):
    """Y (N, d) less the steps that stand alone (:func:`_jump_glitches`: the tracking moved its
    origin), each taken off the poses from its own on: what the knot choice reads (the fit
    follows the poses as they are, and tells the steps). A step is neither noise nor motion; read
    as either it coarsens the knots of all the input: EuRoC MH_01's ground truth with 25 steps of
    2-8 cm added got position knots of 359 ms for 42, its accel against its real IMU away from the
    steps (10 Hz low-passed) 0.360 m/s^2 for 0.214, and 15 of the steps (up to 7.6 cm) went untold
    at those knots; EuRoC MH_03's ground truth (steps of up to 8 cm) 258 ms. Y itself where there
    are none."""
    _, alone = _jump_glitches(t, [(Y, None, None, None, None, warn)], w)
    if not alone.any():
        return Y
    used = np.flatnonzero(w > 0)  # (the steps as _jump_glitches reads them: between weighted poses)
    offsets = np.zeros(Y.shape)
    offsets[used] = np.where(alone[used][:, None], _steps(t[used], Y[used]), 0.0)
    return Y - np.cumsum(offsets, axis=0)


def _runs(mask, bridge=2):
    """(start, stop) index pairs of runs of True, joining runs separated by <= bridge Falses."""
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        return []
    cut = np.flatnonzero(np.diff(idx) > bridge + 1)
    starts = np.r_[idx[0], idx[cut + 1]]
    stops = np.r_[idx[cut], idx[-1]] + 1
    return list(zip(starts.tolist(), stops.tolist()))


def classify_residuals(t, P, theta, res_pos, res_rot, w):
    """Glitch poses to drop (bool (N,)) and warnings for steps and unexplained residual bursts."""
    n = t.size
    drop = np.zeros(n, dtype=bool)
    warnings = []
    if n < 10:
        return drop, warnings
    h = float(np.median(np.diff(t)))
    width = LOCAL_WINDOW_S / h
    cand = np.zeros(n, dtype=bool)
    score = np.zeros(n)
    parts = []
    for res, Y, floor, warn in ((res_pos, P, OUTLIER_FLOOR_M, WARN_RESIDUAL_M),
                                (res_rot, theta, OUTLIER_FLOOR_RAD, WARN_RESIDUAL_RAD)):
        e = np.linalg.norm(res, axis=1)
        sigma = _running_median(np.where(w > 0, e, np.median(e[w > 0])), width) / 1.538
        c = (e > OUTLIER_SIGMAS * sigma) & (e > floor) & (w > 0)
        cand |= c
        score = np.maximum(score, e / np.maximum(OUTLIER_SIGMAS * sigma, floor))
        fwd, bwd = _extrapolation_errors(t, Y, norm=True)
        # jumps are judged against the local size of such extrapolation errors (fast motion has
        # larger ones), by the same number of robust sigmas
        jmin = np.maximum(OUTLIER_SIGMAS * _running_median(fwd, width) / 1.538, floor)
        parts.append((Y, e, fwd, bwd, jmin, warn))
    jumped, alone = _jump_glitches(t, parts, w)
    drop |= jumped
    for a, b in _runs(cand):
        if jumped[a:b].any():  # the residual of a glitch found above
            continue
        t0, t1 = float(t[a]), float(t[b - 1])
        jin = jout = inside = big = False
        core = None  # (first, last) pose of a glitch whose jumps lie inside the run
        for Y, e, fwd, bwd, jmin, warn in parts:
            top = float(e[a:b].max())
            jin |= a == 0 or bool(fwd[a] > max(0.5 * top, jmin[a]))
            jout |= b == n or bool(bwd[b - 1] > max(0.5 * top, jmin[b - 1]))
            inside |= bool(np.any(fwd[a:b + 1] > np.maximum(0.25 * top, jmin[a:b + 1])))
            big |= top >= warn
            if core is None and 0 < a and b < n and top >= warn:
                core = _inner_glitch(t, Y, e, fwd, bwd, jmin, a, b)
        if not (jin and jout) and core is not None:
            # the fit spread a large glitch's residual onto valid neighbours (fast motion, short
            # knots), which joined the run: drop the poses between the jumps only (below the
            # warning level such runs on BROAD's mocap, 0.1-0.4 degrees, were as often motion)
            (a, b), jin, jout = (core[0], core[1] + 1), True, True
            t0, t1 = float(t[a]), float(t[b - 1])
        if jin and jout and (t1 - t0) <= MAX_GLITCH_S and (b - a) < 0.5 * n:
            drop[a:b] = cand[a:b] | (score[a:b] > 0.5)
        elif not big:
            continue
        elif jin or jout or inside:
            warnings.append(_jump_warning(t0, t1))
        else:
            warnings.append(FitWarning(
                "residual_burst", f"between {t0:.3f} s and {t1:.3f} s the fit residuals are far above their level "
                "elsewhere (motion faster than the chosen knot spacing follows)", t0, t1))
    told = [(wn.t_start_s, wn.t_end_s) for wn in warnings]
    for i in np.flatnonzero(alone).tolist():
        t0, t1 = float(t[max(i - 1, 0)]), float(t[i])
        if not any(a <= t1 and t0 <= b for a, b in told):  # (a step the residual runs missed)
            warnings.append(_jump_warning(t0, t1))
    warnings.sort(key=lambda wn: wn.t_start_s)
    return drop & (w > 0), _merge(warnings)


def _jump_warning(t0, t1):
    return FitWarning("unexplained_jump", f"the poses jump between {t0:.3f} s and {t1:.3f} s and the fit cannot "
                      "follow (a step of the tracking?): the synthesized IMU is wrong there", t0, t1)


def _merge(warnings, max_listed=20):
    """Keep at most max_listed warnings per code; say how many more there were."""
    out, count = [], {}
    for wn in warnings:
        count[wn.code] = count.get(wn.code, 0) + 1
        if count[wn.code] <= max_listed:
            out.append(wn)
    for code, c in count.items():
        if c > max_listed:
            out.append(FitWarning(code, f"{c - max_listed} more '{code}' warnings not listed"))
    return out


def dropped_warning(t, drop, what="a tracking glitch"):
    """One warning per run of dropped poses."""
    out = []
    for a, b in _runs(drop, bridge=0):
        where = f"1 pose at {t[a]:.3f} s" if b - a == 1 else f"{b - a} poses between {t[a]:.3f} s and {t[b - 1]:.3f} s"
        out.append(FitWarning("outliers_dropped", f"{where} dropped as {what}", float(t[a]), float(t[b - 1])))
    return _merge(out)
