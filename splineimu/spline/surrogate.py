"""The pose noise as the knot choice sees it (:mod:`splineimu.spline.knots`, steps 2 and 4):
whether the top of the band holds motion or noise, the noise spectrum read from a fit's
residual, and noise series drawn with that spectrum to propagate through fits; and, from the
final fit's residual, the motion it left out: periodic (:func:`residual_lines`) or in bursts
(:func:`residual_bursts`)."""

from __future__ import annotations

import copy
import functools

import numpy as np

#: Steepest slope of the noise spectrum's continuation below its cut-off (f^-2: white rate).
_MIN_NOISE_SLOPE = -2.0
#: Octaves below its cut-off over which the noise spectrum is continued with its slope (flat
#: beyond), and where the octave above falls faster than _MIN_NOISE_SLOPE: noise past its own
#: corner, which keeps rising below the cut-off (:func:`noise_surrogates`).
_CONTINUE_OCTAVES = 1
_STEEP_CONTINUE_OCTAVES = 2
#: Share of the mean power of the tapered second differences below which their top octave is
#: rounding, not noise (:func:`motion_limited`; exact input 1e-20-5e-13, 0.2 mm noise at 20 Hz
#: on 0.3 m of hand-held motion 1e-4).
_ROUNDING_SHARE = 1e-9
#: Noise read as white (:func:`noise_surrogates`' ``white``) is flat above twice the cut-off:
#: log-log slope within +-_FLAT_SLOPE over _FLAT_BINS periodogram bins at least.
_FLAT_SLOPE = 0.5
_FLAT_BINS = 32


def fast_len(n):
    """The least 2^a 3^b 5^c >= n: an FFT of a length with a large prime factor (11998 = 2 x
    5999, an hour at 200 Hz less two: 719998) runs 10-1000x slower than of one nearby."""
    best = 1 << max(int(n) - 1, 0).bit_length()
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            m = p35
            while m < n:
                m *= 2
            best = min(best, m)
            p35 *= 3
        p5 *= 5
    return best


@functools.lru_cache(maxsize=64)
def fast_len_below(n):
    """The greatest 2^a 3^b 5^c 7^d 11^e <= n (1 for n < 1), a length numpy's FFT has radices for.
    The noise spectrum is read from, and its surrogate drawn at, twice that of half a window's
    poses (12000 of 60 s at 200 Hz, 12001 = 11 x 1091: FFTs of that length took 12% of a fit's
    time, 8x those of 12000); such lengths leave out at most 2.6% of the poses from 1000 on."""
    n = max(int(n), 1)
    best = 1
    for p11 in _powers(11, n):
        for p7 in _powers(7, n // p11):
            for p5 in _powers(5, n // (p11 * p7)):
                for p3 in _powers(3, n // (p11 * p7 * p5)):
                    m = p11 * p7 * p5 * p3
                    best = max(best, m << ((n // m).bit_length() - 1))
    return best


def _powers(p, n):
    """p^0, p^1, .. up to n."""
    out = [1]
    while out[-1] * p <= n:
        out.append(out[-1] * p)
    return out


def band_power(d, taper=False, pad=True):
    """Periodogram (summed over the columns) of the rows of d less their mean, zero-padded to
    :func:`fast_len` (band powers over octaves are those of the unpadded series, smoothed; not
    with ``pad`` False, where single bins matter); with ``taper``, of the centred rows times a
    Hann window (centred before the taper only: centring after would add back the plain
    window's leakage)."""
    d = d - d.mean(axis=0)
    if taper:
        d = d * np.hanning(d.shape[0])[:, None]
    return (np.abs(np.fft.rfft(d, fast_len(d.shape[0]) if pad else d.shape[0], axis=0)) ** 2).sum(axis=1)


def _falls(P):
    """Whether a second differences' periodogram falls toward the Nyquist frequency (see
    :func:`motion_limited`), and the top octave's share of the mean power."""
    n = P.size
    low, mid, top = (P[n * a // 8: n * b // 8].mean() for a, b in ((1, 2), (2, 4), (4, 8)))
    return bool(low > 3.0 * top and mid > 1.5 * top), top / max(P.mean(), 1e-300)


def motion_limited(X):
    """True when the top of the band holds motion rather than noise: the power of the second
    differences falls toward the Nyquist frequency (per octave: [1/8, 1/4] and [1/4, 1/2] of
    the band at least 3x and 1.5x the top octave), as for exact, low-rate or re-estimated poses.
    White noise rises there (f^4), coloured and upsampled noise stay within those ratios.

    Read on the plain periodogram and confirmed on a Hann-tapered one: a large slow motion's
    second differences leak from the ends of the series into the upper octaves (falling as
    f^-2), which can make white noise below them look like falling motion (a hand-held motion
    at 20 Hz with 0.2 mm noise: [1/4, 1/2] of the band read 2.2x the top plain, 0.16x tapered;
    knots 18 ms followed the noise, accel 7x the best fixed setting). A tapered top octave at
    rounding level (below :data:`_ROUNDING_SHARE` of the mean power: exact input) confirms
    nothing either way, and the plain reading stands."""
    if X.shape[0] < 64:
        return False
    d = np.diff(X, 2, axis=0)
    falls, _ = _falls(band_power(d))
    if not falls:
        return False
    tapered, share = _falls(band_power(d, taper=True))
    return tapered or share < _ROUNDING_SHARE


def rounding_only(X):
    """True when the top octave of X's second differences is at rounding level (tapered, below
    :data:`_ROUNDING_SHARE` of their mean power): exact input, whatever the plain reading says
    (the ellipse scene's exact positions at 20 Hz read as noise there: one sinusoid and rounding)."""
    return X.shape[0] >= 64 and bool(_falls(band_power(np.diff(X, 2, axis=0), taper=True))[1] < _ROUNDING_SHARE)


def noise_spectrum(wd, k, dt_cv, rng):
    """Smoothed periodogram (M, 3) of the pose noise from the fit at the value-optimal spacing,
    valid from index ``first`` up (None: nowhere), its log-log slope over the octave above, and
    its level (3,) at ``first`` on that slope.

    The residual of that fit is the pose noise times the fit's residual transfer ``(1 -
    H(f))^2`` (and motion the fit misses); that transfer is measured by passing a white draw
    through the same fit, and the residual's periodogram divided by it where it is at least 0.2
    (from about the fit's cut-off up). The level at ``first`` is the octave's mean detrended by
    its slope: the bin ``first`` itself, where the noisy measured transfer first reaches 0.2,
    reads low (the transfer is overestimated there; BROAD orientation: 1.2-3.7x)."""
    white = rng.normal(size=wd.X.shape)
    both = np.ascontiguousarray(np.hstack([wd.X, white]))
    res = both - wd.derivative(k, dt_cv, wd.zero, 1, 0, both)[0]
    res[wd.w <= 0] = 0.0  # poses left out (dropped glitches) are neither noise nor motion
    n = 2 * fast_len_below(res.shape[0] // 2)  # the FFTs' length (even): the window's first n poses
    res = res[:n] - res[:n].mean(axis=0)
    raw = [np.abs(np.fft.rfft(x, axis=0)) ** 2 for x in (res[:, :3], res[:, 3:], white[:n])]

    def smoothed(width):
        kernel = np.ones(width) / width
        P, Pw, W = (np.column_stack([np.convolve(x[:, j], kernel, mode="same") for j in range(x.shape[1])])
                    for x in raw)
        gain = np.mean(Pw / np.maximum(W, 1e-300), axis=1)
        ok = np.flatnonzero(gain >= 0.2)
        return P, gain, (int(ok[0]) if ok.size else None)

    width = max(8, (n // 2) // 256)
    P, gain, first = smoothed(width)
    if first is not None and first <= width // 4 and width > 8:
        # a cut-off within a quarter kernel of 0 Hz is smeared onto it (1 kHz, 60 s, 1 s knots:
        # 117 bins against a cut-off near bin 30 read the transfer 0.2 at 0 Hz and no slope, so
        # the white-noise bias correction was off: gyro 1.36x the best fixed setting): again with
        # the narrowest kernel
        P, gain, first = smoothed(8)
    if first is None:
        return P, None, np.nan, None
    P[first:] /= np.maximum(gain[first:, None], 0.2)
    band = np.arange(max(first, 1), min(2 * first, P.shape[0] - 1) + 1)
    # exact input (a static pose) leaves no residual at all: no slope to read
    slope = _loglog_slope(P, band) if band.size >= 4 else np.nan
    level = np.mean(P[band] * (first / band)[:, None] ** slope, axis=0) if np.isfinite(slope) else P[first].copy()
    return P, first, slope, level


def _loglog_slope(P, bins):
    """Log-log slope of the power of P (summed over its columns) over the periodogram ``bins``
    (NaN where a bin holds no power)."""
    power = P[bins].sum(axis=1)
    return float(np.polyfit(np.log(bins), np.log(power), 1)[0]) if np.all(power > 0) else np.nan


def _flat_above(P, first):
    """Whether the noise spectrum P (valid from ``first``) is flat from twice the cut-off to 0.9 of
    the Nyquist frequency: log-log slope within +-:data:`_FLAT_SLOPE` over :data:`_FLAT_BINS` bins at
    least. White noise reads 0.00-0.03; BROAD's mocap orientation falls as f^-5 to f^-7 there,
    AR(1) noise (30 ms) f^-1.4, noise drawn at half the rate and interpolated f^-3.4."""
    a, b = 2 * first, int(0.9 * P.shape[0])
    return b - a >= _FLAT_BINS and bool(abs(_loglog_slope(P, np.arange(a, b))) <= _FLAT_SLOPE)


def noise_surrogates(windows, k, dt_cv, seed=7, follow=True, also_flat=False, white=None):
    """Noise series (N, 3) per window with the spectrum of the pose noise, for propagation
    through fits: :func:`noise_spectrum` drawn with random phases, continued below its cut-off
    from its level there, flat or (``follow``) with the median over the windows of its slope
    over the octave above, within [:data:`_MIN_NOISE_SLOPE`, 0], for one octave (the spacings
    up to twice the fit's, where the ladder weighs noise against bias) and flat beyond. White,
    AR(1) and upsampled noise are flat or nearly so above the cut-off and stay flat; noise
    rolling off above its own corner (mocap filters) keeps rising below it, but not faster than
    f^-2 (BROAD orientation against the real gyro: f^-2 from 12 to 40 Hz, f^-3.8 above 31 Hz).
    Where the octave above falls faster than f^-2 (past such a corner) it is continued for two
    octaves: the spectrum's fit can sit well above the spacings the ladder then weighs. BROAD
    29's rotation (286 Hz), its spectrum read from 8.8 ms knots (cut-off at 50 Hz; 07, 16, 28:
    15-22 ms, 21-32 Hz) and falling as f^-5.6 there, was drawn flat below 25 Hz: the
    rung-to-rung changes of 18-34 ms knots held 1.7-2.5x the noise drawn
    (benchmarks/rung_split.py: the part of the changes that does not correlate with the real
    gyro; 0.4-1.6x on 9 other trials, 06 1.5-3.7x, 15 1.1-2.4x), which was read as bias, and the
    27 ms knots chosen synthesized 1.05x the real IMU's gyro content above 15 Hz (34 ms now:
    0.94x, full band 1.020 -> 1.019x the best fixed setting).
    ``white`` (a test of the slope read): noise it passes whose spectrum is flat above twice the
    cut-off (:func:`_flat_above`) is white, drawn flat at the mean level of that band (the level
    at the cut-off holds motion the fit misses too), and its slope is returned as 0.
    Returns ``(series, flat series or None, slope, drawn flat as white)``: with ``also_flat`` the same spectra and
    phases continued flat; ``slope`` the median of the windows' slopes as read (NaN: none read),
    before the clip."""
    rngs = [np.random.default_rng(seed) for _ in windows]
    spectra = [noise_spectrum(wd, k, dt_cv, rng) for wd, rng in zip(windows, rngs)]
    slopes = [sl for _, first, sl, _ in spectra if first is not None and np.isfinite(sl)]
    read = float(np.median(slopes)) if slopes else np.nan
    flat_white = bool(slopes) and white is not None and white(read) and all(
        _flat_above(P, first) for P, first, _, _ in spectra if first is not None)
    if flat_white:
        read = 0.0
    slope = float(np.clip(read, _MIN_NOISE_SLOPE, 0.0)) if slopes and follow else 0.0

    octaves = _STEEP_CONTINUE_OCTAVES if read < _MIN_NOISE_SLOPE else _CONTINUE_OCTAVES

    def draw(slope):
        out = []
        for (P, first, _, level), rng, wd in zip(spectra, rngs, windows):
            P = P.copy()
            if flat_white and first is not None:
                P[:] = P[2 * first: int(0.9 * P.shape[0])].mean(axis=0)
            elif first is not None:
                f = np.maximum(np.arange(first), first / 2.0**octaves)
                P[:first] = level * (f / first)[:, None] ** slope
            rng = copy.deepcopy(rng)  # every draw: the same phases
            phase = np.exp(2j * np.pi * rng.random(P.shape))
            phase[0] = 1.0
            x = np.fft.irfft(np.sqrt(P) * phase, 2 * (P.shape[0] - 1), axis=0)  # (an even length)
            # (drawn at the spectrum's length, continued periodically over the window's last poses)
            out.append(np.resize(x, (wd.X.shape[0], x.shape[1])))
        return out

    series = draw(slope)
    # (a flat draw with the same phases is the series itself where that is drawn flat already)
    return series, (None if not also_flat else series if flat_white or slope == 0.0 else draw(0.0)), read, flat_white


def noise_at_spacing(rms, dt_from, dt_to, r):
    """The noise part ``rms`` of the r-th derivative's error of a fit at knot spacing ``dt_from``,
    moved to ``dt_to``: a smoother of bandwidth 1/dt passes noise variance ~dt^-(2r+1)."""
    return rms * (dt_from / dt_to) ** (r + 0.5)


def prediction_at_spacing(c, dt, r):
    """A choice's predicted error of the r-th derivative (``c``: the rotation's or position's entry
    of :func:`splineimu.spline.knots.choose_knot_spacing`) at a finer spacing ``dt`` imposed by
    another grid (``kind="se3"`` fits both on the finer of the two). The noise part of a smoother
    of bandwidth 1/dt has a variance ~dt^-(2r+1); the bias part, which falls with dt, is kept (an
    upper bound). Ellipse scene, 1 mm / 0.1 deg, SE3 at 0.31 s against the rotation's 0.83 s:
    predicted gyro error 0.57 -> 2.5 mrad/s, measured 2.4 (20 Hz: 1.1 -> 5.7, measured 5.8)."""
    if dt >= c["knot_spacing_s"]:
        return c["predicted_rms"]
    noise = noise_at_spacing(c["predicted_noise_rms"], c["knot_spacing_s"], dt, r)
    return float(np.sqrt(noise**2 + max(c["predicted_rms"] ** 2 - c["predicted_noise_rms"] ** 2, 0.0)))


def noise_under_motion(held, block):
    """The noise part N of held-out mean squared errors ``held`` at blocks of 1, 2, 3 x ``block``
    poses (gaps g = m block + 1 pose spacings), read as ``N + M g^(2p)``: p from the ratio of the
    two differences, then M and N. Where the differences do not fit that (not both positive, or
    growing more slowly than any power), all of the first is taken for noise.

    Examples
    --------
    >>> g = np.array([2.0, 3.0, 4.0])
    >>> round(noise_under_motion(1e-6 + 1e-8 * g**6, 1), 12)  # p = 3
    1e-06
    """
    held = np.asarray(held, dtype=np.float64)
    g = np.array([block + 1.0, 2 * block + 1.0, 3 * block + 1.0])
    d1, d2 = held[1] - held[0], held[2] - held[1]
    if not (d1 > 0 and d2 > 0):
        return float(held[0])

    def ratio(p):
        return (g[2] ** (2 * p) - g[1] ** (2 * p)) / (g[1] ** (2 * p) - g[0] ** (2 * p))

    lo, hi = 0.05, 12.0
    if d2 / d1 <= ratio(lo):
        return float(held[0])
    if d2 / d1 >= ratio(hi):
        p = hi
    else:
        for _ in range(60):  # bisection: the ratio grows with p
            p = 0.5 * (lo + hi)
            lo, hi = (p, hi) if ratio(p) < d2 / d1 else (lo, p)
    M = d1 / (g[1] ** (2 * p) - g[0] ** (2 * p))
    return float(min(max(held[0] - M * g[0] ** (2 * p), 0.0), held[0]))


#: A periodogram bin of the rotation's fit residual above LINE_RATIO times the median of the
#: bins around it is a line: deterministic periodic content, not noise (the 6 degrees of freedom
#: of three axes' white noise exceed 7x once in 10^6 bins). Told where at least LINE_BINS such bins
#: hold gyro content of LINE_SHARE times the predicted gyro error or more (:func:`residual_lines`):
#: EuRoC V1_01's ground truth at 103 ms rotation knots holds 0.92x (its detail is motion: V1_02's
#: and MH_01's against their IMUs), BROAD's mocap 0.17x at most.
LINE_RATIO = 100.0
LINE_BINS = 3
LINE_SHARE = 0.5
#: ... and LINE_GYRO_FLOOR [rad/s] at least: below a tenth of a MEMS gyro's noise at 100 Hz
#: (exact poses of periodic motion: lines of rounding, 1e-13 rad/s).
LINE_GYRO_FLOOR = 1e-4
_LINE_BLOCK = 128  # bins per median of the baseline
_LINE_MAX_POSES = 1 << 17  # the middle of longer inputs


def residual_lines(t, res, dt):
    """Narrow spectral lines in a rotation fit's residual ``res`` (N, 3; rad, poses at ``t``)
    above 1.5x the cut-off of knots ``dt`` apart: ``(gyro RMS of their content [rad/s], their
    frequencies [Hz], strongest first, the strongest's ratio to the median around it)``,
    or None where there are none. A vibrating body's rotation measured above the mocap noise
    gives lines (slow turns plus 19-71 Hz vibration of 1e-4 rad under 2e-5 rad white noise:
    peaks 1e4x the noise, 0.03 rad/s of gyro the fit removed, predicted 0.001); so does EuRoC
    V1_01's 200 Hz ground truth (at multiples of 20 Hz, up to 302x; 0.013 rad/s at its 103 ms
    knots, 0.92x the predicted gyro error). Mocap noise gives none (BROAD: peaks
    8-25x, 218x near the mocap's 120 Hz frame rate, below the predicted error), nor white, AR(1)
    or upsampled pose noise (5-10x)."""
    n = t.size
    if n > _LINE_MAX_POSES:
        a = (n - _LINE_MAX_POSES) // 2
        t, res, n = t[a: a + _LINE_MAX_POSES], res[a: a + _LINE_MAX_POSES], _LINE_MAX_POSES
    if n < 8 * _LINE_BLOCK:
        return None
    n = 2 * fast_len_below(n // 2)  # an FFT of a length with a large prime factor is slow
    t, res = t[:n], res[:n]
    h = float(np.median(np.diff(t)))
    P = band_power(res, pad=False)
    f = np.fft.rfftfreq(n, h)
    m = P.size // _LINE_BLOCK * _LINE_BLOCK
    base = np.repeat(np.median(P[:m].reshape(-1, _LINE_BLOCK), axis=1), _LINE_BLOCK)
    base = np.r_[base, np.full(P.size - m, base[-1])]
    band = (f > 1.5 / (2.0 * dt)) & (f < 0.95 / (2.0 * h))
    ratio = P / np.maximum(base, 1e-300)
    line = band & (ratio > LINE_RATIO)
    if np.count_nonzero(line) < LINE_BINS:
        return None
    gyro = float(np.sqrt(2.0 * np.sum((P[line] - base[line]) * (2.0 * np.pi * f[line]) ** 2)) / n)
    idx = np.flatnonzero(line)
    peaks = []  # the strongest bin of each run of neighbouring line bins
    for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
        peaks.append(run[np.argmax(ratio[run])])
    peaks.sort(key=lambda i: -ratio[i])
    freqs = []  # one per line: side bins within 1% (0.2 Hz at least) of a stronger one are its own
    for i in peaks:
        if all(abs(f[i] - g) > max(0.2, 0.01 * g) for g in freqs):
            freqs.append(float(f[i]))
    return gyro, freqs, float(ratio[peaks[0]])


#: Windows of :func:`residual_bursts`: BURST_WINDOW_S long (BURST_MIN_POSES poses at least), each
#: overlapping the next by half.
BURST_WINDOW_S = 1.0
BURST_MIN_POSES = 32
#: An octave band of a window's residual is motion the knots missed from BURST_RATIO times the
#: band's median power over all windows on, below BURST_TOP_FRACTION of the Nyquist frequency,
#: in a window whose top octave holds less than BURST_TOP_RATIO times its median power.
BURST_RATIO = 20.0
BURST_TOP_FRACTION = 0.25
BURST_TOP_RATIO = 3.0
_BURST_CHUNK = 1024  # windows per FFT call (bounded memory for hour-long input)


def _tukey(m, alpha=0.5):
    """Tukey window of m points (cosine tapers over alpha / 2 of each end): scipy.signal.windows'
    tukey (its test oracle), without importing scipy.signal (~1 s cold) into every fit."""
    x = np.arange(m) / (m - 1)
    y = np.minimum(x, 1.0 - x)
    w = np.ones(m)
    edge = y < alpha / 2
    w[edge] = 0.5 * (1.0 + np.cos(2.0 * np.pi / alpha * (y[edge] - alpha / 2)))
    return w


def residual_bursts(t, res, keep, r):
    """Stretches where a fit's residual ``res`` (N, 3; poses at ``t``, ``keep`` the poses it
    followed) holds motion the knots missed: ``[(t_start, t_end, rms, f_peak, ratio)]`` for each
    window of :data:`BURST_WINDOW_S` with such motion, ``rms`` the r-th time derivative of its
    part of the residual (r = 2: the accel the spline lacks there; r = 1: the gyro), ``f_peak``
    the frequency of its largest share and ``ratio`` that bin's octave power over the octave's
    median over all windows.

    The residual of each window is tapered (Tukey, half its length), its periodogram summed over
    the axes; the power above the median of every window at each frequency counts where its
    octave holds BURST_RATIO times its median, below BURST_TOP_FRACTION of the Nyquist
    frequency, and not in windows whose top octave is raised too (BURST_TOP_RATIO: a burst of
    pose noise is broadband). Real mocap bursts of noise read as motion otherwise: BROAD 02's
    windows of 3-10x at 16-35 Hz (2-3 m/s^2 of accel if motion) are noise (a spline at 12 ms
    knots is 3-6x further from its real IMU there than the automatic one), and so are EuRoC MH_01's
    first seconds (20-140x at 21-25 Hz, top octave 80-590x: 2.3-5.0 m/s^2 from its IMU at 12 ms
    knots, 1.0-2.0 at the automatic 42 ms). A 1 s burst of motion
    of 5 mm at 5 Hz under 1 mm white noise (knots 1.4 s): its band 60x, 2.5 m/s^2 read for 2.2
    measured (a burst of the residual alone reads 1.2x its own); EuRoC V2_01's landing (104 ms
    knots): 1541x at 6 Hz, ~5 m/s^2.
    """
    n = t.size
    h = float(np.median(np.diff(t))) if n > 1 else 0.0
    if h <= 0.0:
        return []
    m = max(int(round(BURST_WINDOW_S / h)), BURST_MIN_POSES)
    hop = m // 2
    if n < m + 8 * hop:  # fewer than 9 windows: no usual level to compare with
        return []
    starts = np.arange(0, n - m + 1, hop)
    dropped = np.r_[0, np.cumsum(~keep)]
    ok = (t[starts + m - 1] - t[starts] <= 1.5 * (m - 1) * h) & (dropped[starts + m] == dropped[starts])
    if np.count_nonzero(ok) < 9:
        return []
    f = np.fft.rfftfreq(m, h)
    win = _tukey(m)
    S = np.empty((starts.size, f.size))
    view = np.lib.stride_tricks.sliding_window_view(np.ascontiguousarray(res, dtype=np.float64), m, axis=0)
    for a in range(0, starts.size, _BURST_CHUNK):
        x = view[starts[a:a + _BURST_CHUNK]]  # (c, 3, m)
        x = (x - x.mean(axis=2, keepdims=True)) * win
        S[a:a + x.shape[0]] = (np.abs(np.fft.rfft(x, axis=2)) ** 2).sum(axis=1)
    S *= 2.0 / m**2  # per bin: its share of the mean square of a burst within the taper's flat middle
    nyq = 0.5 / h
    low = (f > 0.0) & (f <= BURST_TOP_FRACTION * nyq)
    top = f > 0.5 * nyq
    if not low.any() or not top.any():
        return []
    octave = np.floor(np.log2(f[low] / f[1]) + 1e-9).astype(int)
    member = np.eye(octave.max() + 1)[octave]  # (bins, octaves)
    ref_bin = np.median(S[ok], axis=0)
    P = S[:, low] @ member
    ref = np.median(P[ok], axis=0)
    ratio = P / np.maximum(ref, 1e-300)
    broadband = S[:, top].sum(axis=1) >= BURST_TOP_RATIO * max(float(ref_bin[top].sum()), 1e-300)
    count = (ratio > BURST_RATIO)[:, octave] & (ok & ~broadband)[:, None]
    ex = np.where(count, np.maximum(S[:, low] - ref_bin[low], 0.0), 0.0) * (2.0 * np.pi * f[low]) ** (2 * r)
    out = []
    for i in np.flatnonzero(ex.sum(axis=1) > 0.0):
        j = int(np.argmax(ex[i]))
        out.append((float(t[starts[i]]), float(t[starts[i] + m - 1]), float(np.sqrt(ex[i].sum())),
                    float(f[low][j]), float(ratio[i, octave[j]])))
    return out
