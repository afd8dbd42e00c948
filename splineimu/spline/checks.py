"""Checks of the input and of a fit other than its glitches (:mod:`.glitches`): input refused,
stamps, resampled and held poses, residuals far above the noise.

Stamps (:func:`stamp_warnings`): intervals far shorter than the median pose spacing in which the
poses move as far as in a whole one (mocap logged with receive times, poses re-stamped on arrival)
mean the stamps are jittered, not the motion; the fit can only read such input as noise or
jumps, so it is warned about with the share of such intervals and their time range.

Stretches of motion the knots do not follow (:func:`burst_warnings`): a window of the residual
whose spectrum stands far above its usual level at frequencies well below the Nyquist frequency
(a landing, a knock), with the IMU error that motion makes there where it is large.

Two checks of the whole input (:func:`input_warnings`): fit residuals far above the pose noise
(the automatic choice's cross-validated level, or, for a given spacing, a robust estimate from
third differences, which reads coloured noise low and so gets a wider margin), and input whose
top octave still holds motion (low-rate or re-estimated poses: whatever moves faster than half
the pose rate is not in the input, and no predicted error can include it).
"""

from __future__ import annotations

import numpy as np

from .. import lie
from ..errors import InputError, SplineImuError
from .basis import MAX_ORDER, MIN_ORDER
from .glitches import MAX_GLITCH_S, _running_median, _runs
from .report import WARN_ACCEL_M_S2, WARN_GYRO_RAD_S, FitWarning
from .signals import difference_noise
from .surrogate import band_power, motion_limited, noise_at_spacing, residual_bursts

#: Residual RMS above this many times the cross-validated pose noise (or, for a given spacing,
#: the third-difference estimate) is warned about.
RESIDUAL_OVER_NOISE = 3.0
RESIDUAL_OVER_DIFF_NOISE = 10.0
#: ... and only from this residual RMS on (m, rad): below, the input is as good as exact.
RESIDUAL_FLOOR = 1e-4
#: Input whose top octave holds at least this fraction of the derivative's power (and whose
#: second differences fall toward the Nyquist frequency) is warned about as rate-limited.
TOP_OCTAVE_POWER = 1e-3
#: A pose interval shorter than JITTER_SHORT x the median spacing in which the poses move at
#: least JITTER_STEP x what they move in a whole interval there (and that step at least
#: JITTER_OVER_NOISE x the pose noise's) is a stamp error; warned from JITTER_SHARE of the
#: intervals (and 3) on. Correctly stamped poses move at most JITTER_SHORT x a step plus noise.
JITTER_SHORT = 0.3
JITTER_STEP = 0.7
JITTER_OVER_NOISE = 10.0
JITTER_SHARE = 0.01
#: Consecutive poses rotating more than this are refused (pi/2: 120 deg cannot be told from -240).
MAX_STEP_ANGLE_RAD = np.pi / 2


def validate_poses(t_s, positions, quat_xyzw, weights):
    """The poses of :func:`splineimu.spline.fit.fit` as float64 ``(t, P, R, w)``, or an InputError;
    ``w`` scaled to a mean of 1 over the poses of positive weight."""
    t = np.ascontiguousarray(np.asarray(t_s, dtype=np.float64).reshape(-1))
    P = np.ascontiguousarray(np.asarray(positions, dtype=np.float64))
    q = np.asarray(quat_xyzw, dtype=np.float64)
    if P.shape != (t.size, 3):
        raise InputError(f"Expected `positions` to have shape ({t.size}, 3), got {P.shape}")
    if q.shape != (t.size, 4):
        raise InputError(f"Expected `quat_xyzw` to have shape ({t.size}, 4), got {q.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(P)) and np.all(np.isfinite(q))):
        raise InputError("poses contain NaN or inf")
    if t.size > 1 and np.any(np.diff(t) <= 0):
        i = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise InputError(f"timestamps must be strictly increasing (pose {i + 1} at {t[i + 1]!r} s)")
    R = lie.quat_xyzw_to_matrix(q)
    if weights is None:
        w = np.ones(t.size)
    else:
        w = np.ascontiguousarray(np.asarray(weights, dtype=np.float64).reshape(-1))
        if w.shape != t.shape or np.any(~np.isfinite(w)) or np.any(w < 0):
            raise InputError("`weights` must be (N,) finite and non-negative")
        if w.any():  # relative: the fit's priors (END_TURN_SIGMA_RAD, the penalty) hold against weights ~1
            w = w / w.max() / np.mean(w[w > 0] / w.max())
    return t, P, R, w


#: Stamps whose median interval is below this fraction of their 90th percentile come in clusters.
CLUSTER_RATIO = 0.05


def check_stamp_clusters(t):
    """Refuse stamps in clusters for the automatic knot choice, which takes the median interval for
    the pose spacing and tries knots from 0.7 times it: poses logged twice 1 us apart (100 Hz, 10 s)
    had it fit million-segment splines, 14 minutes and 6 GB before it was stopped (the same pose
    twice is dropped as held before this, :func:`held_poses`; different poses in bursts are not).
    Gaps and irregular sampling leave the median near the 90th percentile (random 0.2-1.8x: 0.6
    of it)."""
    dt = np.diff(t)
    if dt.size < 10:
        return
    h, h90 = np.median(dt), np.percentile(dt, 90)
    if h < CLUSTER_RATIO * h90:
        raise InputError(
            f"the pose stamps come in clusters: half the intervals are under {h * 1e3:.3g} ms, a tenth over "
            f"{h90 * 1e3:.3g} ms (poses logged twice, or in bursts?); the automatic knot choice reads the median "
            "interval as the pose spacing: give the knot spacing and the order, or keep one pose per cluster")


def resolve_setting(value, name, kind_name):
    """``"auto"`` or a positive number (spacing) / an integer (order)."""
    if isinstance(value, str):
        if value == "auto":
            return "auto"
        try:
            value = float(value)
        except ValueError:
            raise SplineImuError(f"{name} must be a number or 'auto', got {value!r}") from None
    if kind_name == "order":
        if not (value == int(value) and MIN_ORDER <= value <= MAX_ORDER):  # 4.5 was cut to 4, 1 a ValueError
            raise SplineImuError(f"{name} must be an integer in [{MIN_ORDER}, {MAX_ORDER}] or 'auto', got {value!r}")
        return int(value)
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise SplineImuError(f"{name} must be positive and finite, got {value!r}")
    return value


def _angle(Ra, Rb):
    """Rotation angles between Ra and Rb (N, 3, 3), from the trace of Ra^T Rb."""
    c = np.einsum("nij,nij->n", Ra, Rb)  # trace(R_a^T R_b) = 1 + 2 cos(angle)
    return np.arccos(np.clip((c - 1.0) / 2.0, -1.0, 1.0))


def rotation_flips(t, R):
    """Poses (bool (N,)) of orientation flips: runs that turn by more than
    :data:`MAX_STEP_ANGLE_RAD` away from the pose before them and back, to within half of it,
    within :data:`MAX_GLITCH_S` (a mocap body's markers matched the wrong way round). No
    rotation spline can follow them (no turn that large between poses can be told from its
    opposite); everything else about such a pose is suspect too."""
    flip = np.zeros(t.size, dtype=bool)
    if t.size < 3:
        return flip
    ang = _angle(R[:-1], R[1:])
    big = np.flatnonzero(ang > MAX_STEP_ANGLE_RAD)
    i = 0
    while i < big.size:
        a = big[i]  # the run starts at pose a + 1
        for j in range(i + 1, big.size):
            b = big[j]  # ... and ends at pose b, back at b + 1
            if t[b] - t[a + 1] > MAX_GLITCH_S:
                break
            if _angle(R[a:a + 1], R[b + 1:b + 2])[0] <= 0.5 * MAX_STEP_ANGLE_RAD:
                flip[a + 1:b + 1] = True
                i = j
                break
        i += 1
    return flip


def check_rotation_steps(t, R, index=None):
    """Refuse input whose consecutive poses rotate by more than :data:`MAX_STEP_ANGLE_RAD`.

    Across a gap (more than 3 median pose spacings) such a turn is not refused but returned as a
    warning: the fit bridges the gap with the shortest turn, which may not be what happened.
    ``index``: the poses' indices in the caller's input (poses dropped before: orientation
    flips); the refusal names those, and carries the first as ``pose_index`` (a command maps it
    to the file's line).
    """
    if R.shape[0] < 2:
        return []
    index = np.arange(t.size) if index is None else np.asarray(index)
    ang = _angle(R[:-1], R[1:])
    dt = np.diff(t)
    gap = dt > 3.0 * np.median(dt)
    big = ang > MAX_STEP_ANGLE_RAD
    if np.any(big & ~gap):
        i = int(np.argmax(np.where(gap, 0.0, ang)))
        flip = np.flatnonzero(rotation_flips(t, R))
        if flip.size:
            i = int(flip[0])
            message = (f"pose {index[i]} (t = {t[i]:.6f} s) turns by {np.degrees(ang[i - 1]):.1f} deg away from "
                       "the one before and back: an orientation flip of the tracking; remove such poses, or fit "
                       "with outlier rejection (the default), which drops them")
        else:
            message = (f"poses {index[i]} and {index[i + 1]} (t = {t[i]:.6f} s and {t[i + 1]:.6f} s) rotate by "
                       f"{np.degrees(ang[i]):.1f} deg: {np.degrees(MAX_STEP_ANGLE_RAD):.0f} deg or more between "
                       "consecutive poses cannot be told from the opposite turn; record or export the poses at a "
                       "higher rate")
        exc = InputError(message)
        exc.pose_index = int(index[i])
        raise exc
    return [FitWarning("gap_turn_ambiguous", f"the poses turn by {np.degrees(ang[i]):.0f} deg across the gap from "
                       f"{t[i]:.3f} s to {t[i + 1]:.3f} s: the fit bridges it with the shortest turn",
                       float(t[i]), float(t[i + 1])) for i in np.flatnonzero(big & gap)]


def stamp_warnings(t, P, theta):
    """A warning if the stamps are jittered (module docstring): the share of the intervals
    too short for the distance the position or the rotation ``theta`` (accumulated increments)
    moves in them, and the time from the first to the last."""
    dt = np.diff(t)
    if dt.size < 16:
        return []
    h = float(np.median(dt))
    short = dt < JITTER_SHORT * h
    whole = np.flatnonzero((dt > 0.75 * h) & (dt < 1.25 * h))
    if np.count_nonzero(short) < 3 or whole.size < 8:
        return []
    hit = np.zeros(dt.size, dtype=bool)
    for Y in (P, theta):
        step = np.linalg.norm(np.diff(Y, axis=0), axis=1)
        # what the poses move in a whole interval nearby (running median over 21 of them)
        ref = np.interp(np.arange(dt.size), whole, _running_median(step[whole] * (h / dt[whole]), 21))
        noise = np.sqrt(2.0) * _diff_noise(Y)  # a step of the pose noise alone
        hit |= short & (step > JITTER_STEP * ref) & (ref > JITTER_OVER_NOISE * noise)
    k = int(np.count_nonzero(hit))
    if k < max(3, JITTER_SHARE * dt.size):
        return []
    i = np.flatnonzero(hit)
    a, b = float(t[i[0]]), float(t[i[-1] + 1])
    return [FitWarning(
        "timestamps_jittered", f"{k} of {dt.size} pose intervals ({100 * k / dt.size:.2g}%, {a:.3f} s to {b:.3f} s) "
        f"are shorter than {JITTER_SHORT:g}x the median spacing ({1e3 * h:.3g} ms) yet the poses move in them as far "
        "as in a whole one: the stamps are jittered (receive times?), not the motion; the fit reads the jitter as "
        "noise or jumps and the synthesized IMU is wrong at the motion's rates: stamp the poses with their capture "
        "times, or re-time them onto the capture clock (--retime-stamps; splineimu.stamps.retime_stamps)", a, b)]


#: Poses that repeat their predecessor exactly (a later stamp, the same pose) in short runs within
#: motion count as held (a trajectory sampled and held at a lower rate, logged at a higher one)
#: when they are at least this share of the steps taken (:func:`held_poses`).
HELD_SHARE = 0.1
#: Longest run of repeats that counts as held (a rate 5x the poses'); longer ones are rests.
_HELD_RUN = 4


def held_poses(P, q):
    """Poses to drop as held (bool (N,)): those equal to the one before (position and
    quaternion, exactly) in runs of at most :data:`_HELD_RUN` between steps that move, where they
    are at least :data:`HELD_SHARE` of those steps and repeats; else None.

    A logger that writes the latest pose at a higher rate than the poses come (mocap at 100 Hz
    written at 200 Hz, 120 Hz at 200 Hz) repeats a pose at later stamps: the stamps of the
    repeats are not its time, and the staircase they make is read as motion (EuRoC V1_02's
    ground truth held at 100 Hz and written at 200 Hz: gyro below 10 Hz 3.2x the best fixed
    setting against its real IMU, nothing told). The first of each run keeps its stamp (the
    closest to when the pose was taken). Rests are not held poses: longer runs of one pose are
    kept (a still sensor given exactly keeps all of its poses), and so are a few short ones
    (real ground truth: no repeat in EuRoC, TUM-VI, OpenVINS' files and 21 BROAD trials; 9 of
    20 956 poses in TUM RGB-D fr2/desk)."""
    same = np.all(P[1:] == P[:-1], axis=1) & np.all(q[1:] == q[:-1], axis=1)
    if np.count_nonzero(same) < 8:
        return None
    held = np.zeros(P.shape[0], dtype=bool)
    for a, b in _runs(same, bridge=0):
        if b - a <= _HELD_RUN:
            held[a + 1:b + 1] = True  # the poses after the first of the run
    k = int(np.count_nonzero(held))
    if k < 8 or k < HELD_SHARE * (np.count_nonzero(~same) + k):
        return None
    return held


#: Poses count as resampled by interpolation when, for one phase modulo m of the uniformly spaced
#: poses, the squared second differences of the others (their upper quartile) are below this
#: share of that phase's (its lower quartile), for position and rotation alike
#: (:func:`interpolated_poses`).
INTERPOLATED_SHARE = 0.01
_INTERPOLATION_FACTORS = (5, 4, 3, 2)
_JUDGED_POSES = 24_000


def _evenly_spaced(t):
    """The median spacing, whether each spacing is within 1% of it, and whether each pose has
    such spacings on both sides (the ends: not)."""
    dt = np.diff(t)
    h = float(np.median(dt))
    uniform = np.abs(dt - h) <= 0.01 * h
    ok = np.zeros(t.size, dtype=bool)
    ok[1:-1] = uniform[:-1] & uniform[1:]
    return h, uniform, ok


def _middle(n):
    """The first index and the slice of the middle :data:`_JUDGED_POSES` of ``n`` poses."""
    a = max((n - _JUDGED_POSES) // 2, 0)
    return a, slice(a, min(a + _JUDGED_POSES, n))


def interpolated_poses(t, P, theta):
    """Poses that lie on the straight line (or geodesic) through their neighbours, every m-th
    pose carrying the data: ``(m, mask)`` of those poses, or None.

    A trajectory exported at one rate and resampled to a higher one (mocap at 100 Hz written at
    200 Hz, a 10 Hz estimate interpolated to 20 Hz) has second differences at the interpolated
    poses of the motion alone, and of the noise too at the others. The choice cross-validates
    held-out poses, and an interpolated pose is predicted by the two it was made from: it read
    the interpolation as motion (poses at 10 Hz interpolated to 20 Hz: fast hand-held accel
    5.5-7.4x the best fixed setting, predicted 0.04x). Judged on the uniformly spaced poses
    (within 1% of the median spacing) by quartiles per phase, so that a few glitches do not
    count (a phase of m = 3 on poses resampled 2x holds both kinds: its quartiles differ),
    largest m first; a phase whose second differences are at rounding level (exact or piecewise
    linear motion) is not judged. The share measured 3.1-150 on real ground truth (EuRoC,
    TUM-VI, TUM RGB-D, OpenVINS' files, 21 BROAD trials), 1.0 and above on sampled analytic
    motion (16 scenes at 2 Hz-1 kHz, exact, white or AR(1) noise), 6.5e-20 at most on resampled
    poses (20-200 Hz); noise resampled onto exact motion is found where
    the motion's own second differences are below the noise's (200 Hz from 100 Hz: 8 of 16
    motions)."""
    n = t.size
    if n < 64:
        return None
    _, uniform, ok = _evenly_spaced(t)

    def second(Y):  # squared second differences (0 at the ends)
        e = np.zeros(Y.shape[0])
        e[1:-1] = np.sum((Y[2:] - 2.0 * Y[1:-1] + Y[:-2]) ** 2, axis=1)
        return e

    def quartiles(e, where):
        return np.percentile(e[where], (25, 75)) if np.count_nonzero(where) >= 8 else (np.nan, np.nan)

    # judged on a stretch of _JUDGED_POSES in the middle (an hour at 200 Hz took 0.3 s), then
    # confirmed on all of the input (the phase of the poses carrying the data holds throughout)
    a, part = _middle(n)
    judged = [(second(Y[part]), (64.0 * np.finfo(float).eps * max(float(np.max(np.abs(Y))), 1.0)) ** 2)
              for Y in (P, theta)]
    for m in _INTERPOLATION_FACTORS:
        phases = set()
        for e, floor in judged:
            lo, hi = np.array([quartiles(e[f::m], ok[part][f::m]) for f in range(m)]).T
            if not np.all(np.isfinite(lo)):
                return None
            c = int(np.argmax(lo))
            if not lo[c] > floor or np.max(np.delete(hi, c)) > INTERPOLATED_SHARE * lo[c]:
                break
            phases.add((a + c) % m)
        else:
            if len(phases) == 1:
                between = ok & (np.arange(n) % m != phases.pop())
                # (on all of it, 99% of the poses between must hold: a stretch of another phase
                # is a few percent of them, and a glitch at a data pose leaves them on the line)
                full = [e for e, _ in judged] if n <= _JUDGED_POSES else [second(Y) for Y in (P, theta)]
                if all(np.percentile(e[between], 99) <= INTERPOLATED_SHARE * quartiles(e, ok & ~between)[0]
                       for e in full):
                    return m, between
            return None
    return None


#: Poses predicted (quintic, from the other half) at one phase of two that miss by more than this
#: many times the other phase's error (median squares) carry noise that the others interpolate
#: (:func:`noise_interpolated`).
NOISE_PARITY_RATIO = 3.0
#: ... and at most this many: interpolated noise gives 8.6x at most (motion adds to both phases
#: alike); more is motion aliased onto every 2nd pose (the lecture ellipse's vertical motion at a
#: quarter of a 2 Hz pose rate, zero at every other pose: 1.4e8x).
NOISE_PARITY_MAX = 13.0


def noise_interpolated(t, P, theta):
    """Pose noise drawn at every 2nd pose and interpolated at the poses between (a mocap stream
    resampled to twice its rate where the motion was not): ``(2, mask)`` of the poses between, as
    :func:`interpolated_poses`, or None. Its second differences hold the motion, which hides the
    interpolation where the motion is fast. Each pose is predicted from the other half's six
    nearest by quintic interpolation ((3, -25, 150, 150, -25, 3) / 256 at -5 .. 5 spacings), which
    leaves little of the motion: noise drawn at half the rate and interpolated linearly is missed
    by 0.29 sigma^2 at the poses carrying it and by 0.034 sigma^2 at the others (8.6x), white
    noise alike at both. Judged by median squares per phase on uniformly spaced poses (the middle
    _JUDGED_POSES): sums of sines with such noise at 20-200 Hz 3.9-8.6x, but fast hand-held motion
    at 20 Hz hides it (1.0x); white and AR(1) noise and exact motion 1.00-1.13x (but see
    NOISE_PARITY_MAX); real ground
    truth (BROAD, EuRoC at 200 and 20 Hz) 1.00-1.31x. Its choice at 20 Hz had followed that noise
    as motion (car: 18 / 35 ms knots, accel 16x the best fixed setting, predicted 0.25x); chosen
    on the poses carrying the noise, 0.96x."""
    n = t.size
    if n < 64:
        return None
    a, part = _middle(n)
    _, uniform, between_uniform = _evenly_spaced(t)
    # poses i whose ten spacings i-5 .. i+5 are uniform
    ok = np.convolve(uniform[a: part.stop - 1].astype(np.float64), np.ones(10), mode="valid") > 9.5  # from i - 5
    idx = np.arange(5, 5 + ok.size)
    data = set()
    for Y in (P[part], theta[part]):
        e = Y[5:-5] - (150.0 * (Y[4:-6] + Y[6:-4]) - 25.0 * (Y[2:-8] + Y[8:-2]) + 3.0 * (Y[:-10] + Y[10:])) / 256.0
        e2 = np.sum(e**2, axis=1)
        miss = []
        for f in (0, 1):
            at = ok & (idx % 2 == f)
            if np.count_nonzero(at) < 16:
                return None
            miss.append(float(np.median(e2[at])))
        if max(miss) > NOISE_PARITY_MAX * min(miss):
            return None
        if max(miss) > NOISE_PARITY_RATIO * min(miss):
            data.add((a + int(np.argmax(miss))) % 2)
    if len(data) != 1:
        return None
    return 2, between_uniform & (np.arange(n) % 2 != data.pop())


def _diff_noise(X):
    """Robust per-axis noise level from third differences (white noise: var = 20 sigma^2), as a
    vector norm."""
    return float(np.linalg.norm(difference_noise(X, 3)))


def _top_octave_fraction(h, X, r):
    """Share of the power of the r-th difference quotient of X (poses ``h`` apart) in the top
    octave of the band."""
    P = band_power(np.diff(X, r, axis=0) / h**r)
    return float(P[P.size // 2:].sum() / max(P.sum(), 1e-300))


def input_warnings(t, P, theta, res_pos, res_rot, keep, choice=None, spacings=None):
    """Warnings about the whole input: residuals far above the pose noise, poses too sparse for
    the motion they hold (see the module docstring), and given knot ``spacings`` ({"rotation":
    s, "position": s}) so fine for noisy poses that the noise alone makes the IMU error large."""
    out = []
    if t.size < 64:
        return out
    parts = (("position", P, res_pos, "m", 2, "accel"), ("rotation", theta, res_rot, "rad", 1, "gyro"))
    enough = np.count_nonzero(keep) >= 64  # fewer weighted poses: no noise level
    diff_noise = {key: _diff_noise(X[keep]) for key, X, *_ in parts} if enough and choice is None else {}
    for key, _, res, unit, _, _ in parts if enough else ():
        rms = float(np.sqrt(np.mean(np.sum(res[keep] ** 2, axis=1))))
        if choice is not None:
            noise, lim, how = choice[key]["cv_rms"], RESIDUAL_OVER_NOISE, "cross-validated"
        else:
            noise, lim, how = diff_noise[key], RESIDUAL_OVER_DIFF_NOISE, "third-difference"
        if rms > lim * max(noise, 1e-12) and rms > RESIDUAL_FLOOR:
            ratio = f"{rms / noise:.1f}x" if noise > 0 else "far above"  # exact poses: no noise at all
            out.append(FitWarning("residual_above_noise", f"the {key} fit residual ({rms:.3g} {unit} RMS) is "
                                  f"{ratio} the {how} pose noise ({noise:.3g} {unit}): the knot spacing "
                                  f"is too coarse for the motion, or the poses hold steps"))
    limited = {key: choice[key]["motion_limited"] if choice is not None else motion_limited(X)
               for key, X, *_ in parts}
    h = float(np.median(np.diff(t)))
    for key, _, _, unit, r, imu in parts if diff_noise and spacings else ():
        # the derivative of white pose noise of norm n: sqrt(2) n / h (rate) or sqrt(6) n / h^2
        # (acceleration) for knots at the pose spacing h, less by (h / spacing)^(r + 1/2) for
        # coarser ones (ellipse, 100 Hz, 1 mm / 0.1 deg, order 4 at 1-30 ms: 0.5-0.9x measured)
        n = diff_noise[key]
        est = noise_at_spacing(np.sqrt(2.0 if r == 1 else 6.0) * n / h**r, h, max(spacings[key], h), r)
        lim = WARN_GYRO_RAD_S if r == 1 else WARN_ACCEL_M_S2
        if not limited[key] and est > lim:
            out.append(FitWarning("knots_follow_noise", f"the given {key} knot spacing ({1e3 * spacings[key]:.3g} ms, "
                                  f"poses every {1e3 * h:.3g} ms) follows the pose noise ({n:.3g} {unit} from third "
                                  f"differences): the {imu} error from it alone is ~{est:.3g} {unit}/s"
                                  f"{'' if r == 1 else '^2'} (a coarser spacing, or the automatic choice, smooths it)"))
    # the spectra only where the input is motion-limited (the choice has already said so)
    frac = {key: _top_octave_fraction(h, X, r) for key, X, _, _, r, _ in parts if limited[key]}
    hit = [(key, imu) for key, _, _, _, _, imu in parts if frac.get(key, 0.0) > TOP_OCTAVE_POWER]
    if hit:
        nyq = 0.5 / h
        what = ", ".join(f"{100 * frac[k]:.2g}% of the {imu} power" for k, imu in hit)
        out.append(FitWarning("input_rate_low", f"the poses hold motion up to their Nyquist frequency "
                              f"({nyq:.3g} Hz; {nyq / 2:.3g}-{nyq:.3g} Hz holds {what}): motion faster than "
                              f"{nyq:.3g} Hz is not in the input, so the synthesized IMU lacks it, and the motion "
                              "between poses is interpolated: the predicted errors include neither (exact fast "
                              "hand-held poses at 20 Hz: predicted gyro error 0.25x the measured)"))
    return out


#: Warnings whose time range already tells of a local problem (a burst there is not told again).
_LOCAL_CODES = ("unexplained_jump", "residual_burst", "outliers_dropped")


def burst_warnings(t, res_pos, res_rot, keep, choice, spacings, told=()):
    """``motion_not_followed`` where a stretch of the residual holds motion the knots miss
    (:func:`.surrogate.residual_bursts`) whose IMU error there is above the warning level and
    3x the predicted error elsewhere; consecutive windows are told as one range, and not where
    a warning in ``told`` covers part of it already."""
    out = []
    ranges = [(w.t_start_s, w.t_end_s) for w in told if w.code in _LOCAL_CODES and w.t_start_s is not None]
    for key, res, r, imu, unit, lim, pred_key in (
            ("position", res_pos, 2, "accel", "m/s^2", WARN_ACCEL_M_S2, "predicted_accel_rms_m_s2"),
            ("rotation", res_rot, 1, "gyro", "rad/s", WARN_GYRO_RAD_S, "predicted_gyro_rms_rad_s")):
        pred = choice[pred_key] if choice is not None else None
        level = max(lim, 3.0 * pred) if pred is not None else lim
        found = [b for b in residual_bursts(t, res, keep, r) if b[2] > level]
        runs = []
        for b in found:  # windows overlapping the one before join its range
            if runs and b[0] <= runs[-1][-1][1]:
                runs[-1].append(b)
            else:
                runs.append([b])
        for run in runs:
            t0, t1 = run[0][0], run[-1][1]
            if any(a <= t1 and t0 <= z for a, z in ranges):
                continue
            _, _, rms, f, ratio = max(run, key=lambda b: b[2])
            elsewhere = f" (predicted ~{pred:.3g} elsewhere)" if pred is not None else ""
            out.append(FitWarning(
                "motion_not_followed", f"between {t0:.3f} s and {t1:.3f} s the {key} poses move at ~{f:.3g} Hz "
                f"beyond what the {1e3 * spacings[key]:.4g} ms {key} knots follow ({ratio:.0f}x the residual's usual "
                f"power there): the synthesized {imu} there is off by ~{rms:.3g} {unit}{elsewhere}; a finer "
                f"{key} knot spacing follows it (unless it is a burst of pose noise)", t0, t1))
    return out


#: A gap without poses longer than this many knot spacings is named when a fit is singular.
SINGULAR_GAP_KNOTS = 100


def singular_message(t, w, dt, smoothness):
    """Why a fit at knot spacing ``dt`` is singular, and what to do: the penalty bridges a gap of
    ``m`` knot spacings with a conditioning ~m^5 (third differences), which double precision
    loses from a few thousand on (circle scene, 20 s at 100 Hz, order 4: a 300 s gap fits at
    0.5 s knots, a 3600 s gap does not)."""
    tw = t[w > 0]
    gaps = np.diff(tw)
    i = int(np.argmax(gaps)) if gaps.size else 0
    if gaps.size and gaps[i] > SINGULAR_GAP_KNOTS * dt:
        return (f"the fit is singular: the {gaps[i]:.6g} s without poses from {tw[i]:.3f} s to {tw[i + 1]:.3f} s "
                f"spans {gaps[i] / dt:.0f} knot spacings of {dt:g} s, too many to bridge; split the poses at the gap "
                "(from-tum/from-euroc --gaps split) or use a larger knot spacing")
    return (f"the fit is singular at knot spacing {dt:g} s with smoothness {smoothness:g}: use a larger knot "
            "spacing or a larger smoothness")
