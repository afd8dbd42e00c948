"""Receive-time stamps put back on the capture clock.

Motion capture streamed over a network and logged as it arrives (drivers that stamp a pose when
they receive it) carries the delivery delays in its stamps: 1-10 ms of scheduling jitter, stalls
of 100-300 ms after which the queued poses arrive within a millisecond, and dropped frames. The
poses were captured on a steady clock, and a spline fitted at the receive times reads the jitter
as motion (ov_data's KAIST VIO mocap, 50 Hz: finite-difference accelerations of 3400 m/s^2 at the
95th percentile, 21 jump warnings, 2.5 s position knots and 36 mm of fit residual).
:func:`retime_stamps` finds that clock and each pose's slot on it:

1. **Period**: candidates are the one (within 2% of the median interval) at which the stamps'
   phases concentrate most, refined over growing spans, the nominal rate (whole hertz), and each
   refined as the line through the least delays of blocks of the record (a clock drift against
   the logger's clock is part of the period). Stalls queue poses that arrive at one phase
   whatever the period, and pull the median interval short of it (100 Hz with 1-10 ms delays:
   9.71 ms); so the phases of the poses delivered in turn are searched too, from 0.6 of the mean
   interval (the period times one plus the share of dropped frames) to just above it, and their
   three strongest peaks over the whole record (of the eight strongest over its first 1500
   periods) that reach half the strongest's concentration and lie within :data:`WHOLE_HZ` of a
   whole number of hertz add their period, that rate and its refinement. Each is assigned
   (step 3, one pass), and the one on which the poses move most smoothly is kept (mean
   pseudo-Huber norm of their second differences in common units), if more smoothly than at
   the stamps as given. Receive timers coarser than the jitter blur the phases (KAIST VIO:
   phase coherence 0.01-0.64).
2. **Offset**: the phase after the widest gap between the phases of the poses delivered in
   turn (their earliest), so that no delay is negative; the new stamps are the capture times plus
   the least delivery delay (a constant the IMU-to-pose time offset absorbs).
3. **Slots**: the latest slot at or before each stamp, made strictly increasing (a burst's poses
   back from the last), then each pose's further delay in whole periods chosen by dynamic
   programming over the record (:func:`splineimu._kernels.stamps.assign_slots`): the poses must
   move smoothly at their slots' times (pseudo-Huber norm of the second differences of position
   and accumulated rotation, in units of their median), at a small cost per period of delay.
   Once more on the clock kept, in the units of the first pass's slots.

Measured on the analytic scenes at 50 Hz (7% of the frames dropped, 1-10 ms delays, stalls of
100-270 ms one frame in 150, 0.3 mm / 0.05 deg pose noise; tests/test_stamps.py): every slot
right but for stalls at the very ends of a record, and the fitted IMU as good as from the capture
times (ellipse, 60 s: accel 0.0100 m/s^2 both; from the receive times 6.4). ov_data's KAIST VIO
mocap (11 recordings at 50 Hz, no IMU truth): fit residual 2.6-190 mm -> 0.06-0.63 mm, jump
warnings 21 -> 0-5 (circle: 36 -> 0.10 mm, position knots 2.5 s -> 43 ms); the clock at 20.0000
ms on 7 of them, 20.0016 (two), 20.0022 and 20.0027 ms on four (80-135 ppm: the mocap's clock
against the logger's); four told doubtful (:data:`DOUBTFUL_DELAY`). With the offset read as the
least phase around the phases' circular mean (before the widest gap, step 2): residual
0.06-2.4 mm, jumps 1-6, 9 clocks at 20.0000 ms, square_head on 8 ms rotation knots and 113
bridged gaps (now 206 ms, none).

Delays spread over a whole period or more leave the phases nearly uniform (coherence 0.05-0.11):
synthetic records at 50, 100, 120 and 200 Hz (ellipse and flips, seeds 0-2, 60 s) put every
slot right (98.5% at least) on 34 of 36, against 20 of 36 with the median interval's window
and the offset around the circular mean; the two left, 1-20 ms delays at 50 Hz (a period 0.4%
short, half the slots right), are told doubtful, and so are the four at 200 Hz with 1-10 ms
(up to two periods) whose slots are right.
Cost: about S^2 terms per pose and candidate clock (S = 0.3 s / the period), the clocks ranked
on :data:`RANK_POSES` of the poses: a minute at 50 Hz 0.45-0.5 s of CPU, 5.5-6x the fit of the
same poses; ten minutes at 200 Hz 17-18 s, 14-15x (benchmarks/results/stamps.md).

Where it fails: stamps without a steady capture clock (variable-rate input) are refused; a stall
at the very end of a record cannot be told from a late start of the following frames (no later
pose shows the delay); delays longer than ``max_delay_s`` beyond what the order of the stamps
forces; slow motion leaves the slot of a pose after a dropped frame ambiguous (where it matters
least).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import lie
from ._kernels import stamps as _kst
from .errors import InputError
from .spline.signals import rotation_increments

#: Cost of one period of delay against the smoothness of the motion (pseudo-Huber units).
DELAY_COST = 0.5
#: Most memory for the dynamic programme's traceback (poses x delay states^2 bytes): 9000
#: poses at 50 Hz take 16 states (0.3 s) in 2.3 MB; an hour at 200 Hz 18 states (90 ms).
MAX_TABLE_BYTES = 256e6
#: A re-timing whose median delay exceeds this share of the period is told as doubtful: on
#: KAIST VIO's mocap 7 of 11 recordings leave median delays of 0.05-0.61 of a period, four 0.72-1.03.
DOUBTFUL_DELAY = 0.65
#: Re-timing this many poses or more shows a progress bar (where stderr is a terminal): ten
#: minutes at 100 Hz take 11 s of CPU.
PROGRESS_MIN_POSES = 20_000
#: The candidate clocks are ranked on this many poses, the first and the last half of them (the
#: one kept then assigns the whole record): ten minutes at 200 Hz 47 -> 18 s of CPU, slots right
#: 99.97% either way (benchmarks/bench_stamps.py).
RANK_POSES = 20_000
#: Clock periods read from the phases of the poses delivered in turn are tried where they lie
#: within this share of a whole number of hertz (a capture clock's nominal rate and its drift).
WHOLE_HZ = 1e-3


@dataclass
class Retiming:
    """Result of :func:`retime_stamps`.

    Attributes
    ----------
    t_ns : (N,) int64
        The poses' stamps on the capture clock (strictly increasing).
    period_s : float
        The clock's period, on the logger's time scale.
    coherence : float
        Concentration of the stamps' phases on that clock (1: no jitter).
    dropped_frames : int
        Slots without a pose between the first and the last.
    moved : int
        Poses placed earlier than the latest slot their stamp allows at the least delay (stalls).
    delay_s : (N,) float
        Each stamp less its new stamp.
    """

    t_ns: np.ndarray
    period_s: float
    coherence: float
    dropped_frames: int
    moved: int
    delay_s: np.ndarray

    @property
    def doubtful(self) -> bool:
        """The median delay is over :data:`DOUBTFUL_DELAY` of a period: the clock may be off."""
        return bool(np.median(self.delay_s) > DOUBTFUL_DELAY * self.period_s)

    def summary(self) -> str:
        d = 1e3 * self.delay_s
        doubt = (f"; doubtful: the median delay is over {DOUBTFUL_DELAY:g} of a period (a period off, or "
                 "stamps quantized coarser than the jitter), check the fit's warnings" if self.doubtful else "")
        return (f"stamps re-timed onto a {1e3 * self.period_s:.4f} ms capture clock (phase coherence "
                f"{self.coherence:.2f}): delays {d.min():.1f}-{d.max():.1f} ms (median {np.median(d):.1f}), "
                f"{self.moved} poses placed before the latest slot their stamp allows, "
                f"{self.dropped_frames} dropped frames{doubt}")


def _coherence(t, h):
    """Concentration (0-1) of the phases of stamps t on a clock of period h."""
    return float(abs(np.exp(2j * np.pi * t / h).mean()))


def _nominal(h):
    """The period of the nearest whole number of hertz."""
    return 1.0 / max(round(1.0 / h), 1)


def _periods(t, h0, down=0.02, up=0.02, k=3, first=8):
    """The clock periods in [(1 - down) h0, (1 + up) h0] at which the phases of stamps t (seconds
    from the first) concentrate most, with their concentrations: the ``first`` highest peaks of
    that concentration over the first 1500 periods, each refined over spans 4x as long (a
    spurious peak fades), the ``k`` highest of them (best first; fewer where the others faded)."""
    span = float(t[-1])
    T = min(span, 1500.0 * h0)
    hs = np.linspace((1 - down) * h0, (1 + up) * h0, int(np.ceil((down + up) * h0 * 8 * T / h0**2)) + 1)
    tt = t[t <= T]
    z = np.array([_coherence(tt, hh) for hh in hs])
    peaks = [i for i in range(hs.size) if z[i] >= z[max(i - 1, 0)] and z[i] >= z[min(i + 1, hs.size - 1)]]
    step = float(hs[1] - hs[0]) if hs.size > 1 else 0.0
    # (period, concentration, grid step) of each peak, refined span after span; those under a
    # quarter of the strongest's concentration are dropped on the way (a spurious peak's halves
    # with each 4x span, a clock's stays)
    out = [(float(hs[i]), float(z[i]), step) for i in sorted(peaks, key=lambda i: -z[i])[:first]]
    while T < span:
        T = min(4.0 * T, span)
        tt = t[t <= T]
        for j, (h, _, step) in enumerate(out):
            grid = np.linspace(h - 2 * step, h + 2 * step, 41)
            zz = np.array([_coherence(tt, hh) for hh in grid])
            out[j] = (float(grid[int(np.argmax(zz))]), float(zz.max()), float(grid[1] - grid[0]))
        out.sort(key=lambda x: -x[1])
        out = [x for x in out if x[1] >= 0.25 * out[0][1]]
    return [(h, zi) for h, zi, _ in out[:k]]


def _monotone(m):
    """``m`` made strictly increasing by moving entries back (the largest such sequence <= m)."""
    k = np.arange(m.size)
    return np.minimum.accumulate((m - k)[::-1])[::-1] + k


def _second_differences(Y, t):
    """Second differences (N - 2, 6) of position and rotation ``Y`` at times ``t`` (uneven)."""
    d1, d2 = np.diff(t)[:-1, None], np.diff(t)[1:, None]
    return 2.0 * ((Y[2:] - Y[1:-1]) / d2 - (Y[1:-1] - Y[:-2]) / d1) / (d1 + d2)


def _scales(Y, t):
    """Median norm of the second differences of position and rotation (Y's two halves) at times t."""
    a = _second_differences(Y, t)
    return np.array([np.median(np.linalg.norm(a[:, 3 * j:3 * j + 3], axis=1)) + 1e-12 for j in range(2)])


def _envelope_period(t, h):
    """The clock period refined from h: the line through the least delays of blocks of the record
    (the slots, the latest at or before each stamp, taken again on each refinement, six times)."""
    T0 = 0.0
    k = int(np.clip(t.size // 200, 4, 50))
    for _ in range(6):
        m = _monotone(np.floor((t - T0) / h + 1e-6).astype(np.int64)).astype(np.float64)
        r = t - m * h
        idx = [b[np.argmin(r[b])] for b in np.array_split(np.arange(t.size), k)]
        slope, icpt = np.polyfit(m[idx], t[idx], 1)
        h, T0 = float(slope), float(icpt) - 1e-6 * float(slope)
    return h


def _offset(t, h):
    """The clock's offset at the least delay: the phase after the widest gap between the phases
    of the poses delivered in turn (a stall's queue arrives at any phase). Read as the least
    phase around their circular mean, it came out mid-period where the delays spread over a whole
    period or more, and the poses delayed less than that were forced a slot early (200 Hz with
    1-10 ms delays: 69-97% of the slots right, now 98.5-100%)."""
    gap = np.diff(t)
    turn = np.r_[False, (gap > 0.25 * h) & (gap < 1.75 * h)]
    v = np.sort((t[turn] if np.count_nonzero(turn) >= 16 else t) / h % 1.0)
    j = int(np.argmax(np.diff(np.r_[v, v[0] + 1.0])))
    return h * v[(j + 1) % v.size] - 1e-6 * h


def _roughness(Y, t, units):
    """Mean pseudo-Huber norm of the second differences of position and rotation at times t, in
    ``units`` (2,)."""
    a = _second_differences(Y, t)
    return float(sum(np.mean(2.0 * (np.sqrt(1.0 + np.sum(a[:, 3 * j:3 * j + 3] ** 2, axis=1) / units[j] ** 2) - 1.0))
                     for j in range(2)))


def retime_stamps(t_ns, positions, quat_xyzw, max_delay_s: float = 0.3, path: str | None = None,
                  progress: bool | None = None) -> Retiming:
    """Stamps ``t_ns`` (N,) of poses (positions (N, 3), ``quat_xyzw`` (N, 4)) logged at receive
    time, put on the capture clock (module docstring). Raises :class:`~splineimu.errors.InputError`
    (naming ``path``) where the stamps hold no steady clock. ``progress``: a bar over the clocks
    tried (None: from :data:`PROGRESS_MIN_POSES` poses on, where stderr is a terminal)."""
    t_ns = np.asarray(t_ns, dtype=np.int64)
    if t_ns.size < 16:
        raise InputError(f"re-timing needs 16 poses or more, got {t_ns.size}", path=path)
    t = (t_ns - t_ns[0]).astype(np.float64) / 1e9
    h0 = float(np.median(np.diff(t)))
    if not h0 > 0:
        raise InputError("re-timing: the median interval between stamps is zero", path=path)
    steps = rotation_increments(lie.quat_xyzw_to_matrix(np.asarray(quat_xyzw, dtype=np.float64)))
    Y = np.ascontiguousarray(np.hstack([np.asarray(positions, dtype=np.float64),
                                        np.vstack([np.zeros((1, 3)), np.cumsum(steps, axis=0)])]))
    h_coh = _periods(t, h0, k=1, first=1)[0][0]
    h_nom = _nominal(h0)  # the nominal rate, a whole number of hertz
    cands = [h_coh, h_nom, _envelope_period(t, h0), _envelope_period(t, h_coh), _envelope_period(t, h_nom)]
    # the delay's states: up to max_delay_s, within MAX_TABLE_BYTES for the traceback
    S_max = int(min(np.sqrt(MAX_TABLE_BYTES / t.size), 127))
    if S_max < 3:
        raise InputError(f"re-timing {t.size} poses needs more memory than {MAX_TABLE_BYTES / 1e6:.0f} MB: re-time "
                         "the recording in parts", path=path)

    def states(h):  # delays up to max_delay_s on a clock of period h
        return int(min(np.ceil(max_delay_s / h) + 1, S_max))

    S_of = dict.fromkeys((round(h, 12) for h in cands), states(min(cands)))
    # the median interval is short of the period where stalls queue many poses (100 Hz, 1-10 ms
    # delays: 9.72 ms): the phases of the poses delivered in turn (a queue arrives at one phase,
    # whatever the period) concentrate at the period too, which lies below the mean interval (the
    # period times one plus the share of dropped frames) and above 0.6 of it (its half); of
    # their peaks, those within WHOLE_HZ of a whole number of hertz (a capture clock's rate)
    h_mean = float(t[-1]) / (t.size - 1)
    turn = np.r_[True, np.diff(t) > 0.25 * h_mean]
    peaks = _periods(t[turn], h_mean, down=0.4)
    for h, z in peaks:
        nom = _nominal(h)
        if (z >= 0.5 * peaks[0][1] and abs(h / nom - 1.0) < WHOLE_HZ
                and min(abs(nom / c - 1.0) for c in cands) > WHOLE_HZ):
            cands += [h, nom, _envelope_period(t, nom)]
            S_of.update((round(x, 12), states(x)) for x in cands[-3:])
    back = np.zeros((t.size, max(S_of.values()), max(S_of.values())), dtype=np.int8)

    def assign(h, m, n, Yp=Y):
        s, cost = _kst.assign_slots(m, Yp, _scales(Yp, n * h), h, S_of[h], DELAY_COST, back)
        return m - s if np.isfinite(cost) else None

    from tqdm import tqdm

    tried = []
    # (progress None: shown from PROGRESS_MIN_POSES on, where stderr is a terminal; tqdm's disable=None)
    if progress is None:
        disable = True if t.size < PROGRESS_MIN_POSES else None
    else:
        disable = not progress
    bar = tqdm(total=len(S_of) + 1 + (t.size > RANK_POSES), unit=" clocks", desc="re-timing", leave=False,
               disable=disable)
    # the clocks are ranked on the first and the last RANK_POSES / 2 poses (a clock's drift shows
    # over the whole span)
    part = slice(None) if t.size <= RANK_POSES else np.r_[:RANK_POSES // 2, t.size - RANK_POSES // 2:t.size]
    Yr = np.ascontiguousarray(Y[part])
    for h in sorted(S_of):
        T0 = _offset(t, h)
        latest = np.floor((t - T0) / h).astype(np.int64)
        m = _monotone(latest)
        n = assign(h, m[part], m[part], Yr)
        if n is not None:
            tried.append((h, T0, m, n, latest))
        bar.update(1)
    # the clock on which the poses move most smoothly (mean pseudo-Huber norm of their second
    # differences in common units), if more smoothly than at the stamps as given
    times = [t[part]] + [T0 + n * h for h, T0, _, n, _ in tried]
    units = np.min([_scales(Yr, x) for x in times], axis=0)
    rough = [_roughness(Yr, x, units) for x in times]
    ok = sorted((rough[1 + i], i) for i in range(len(tried)) if rough[1 + i] < rough[0])
    for _, i in ok:
        h, T0, m, n, latest = tried[i]
        if t.size > RANK_POSES:  # the whole record on the clock kept (its delays may not fit in the states)
            n = assign(h, m, m)
            bar.update(1)
            if n is None:
                continue
        n = assign(h, m, n)  # again, in the units of the first pass's slots
        break
    else:
        n = None
    bar.close()
    if n is None:
        raise InputError("the stamps hold no steady capture clock to re-time onto: on none found do the poses "
                         "move more smoothly than at the stamps as given (variable-rate poses, not receive-time "
                         "jitter)", path=path)
    new = T0 + n.astype(np.float64) * h
    return Retiming(t_ns=t_ns[0] + np.round(new * 1e9).astype(np.int64), period_s=h,
                    coherence=_coherence(t, h), dropped_frames=int(n[-1] - n[0] + 1 - n.size),
                    moved=int(np.count_nonzero(n < latest)), delay_s=t - new)
