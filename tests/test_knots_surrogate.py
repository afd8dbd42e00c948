"""The knot choice's noise surrogate against the noise it stands for: its power in the octave
above the fit's cut-off (measured there) and in the octave below (continued from the level on
the octave's trend with the octave's slope, bounded to [-2, 0]); two octaves below where that
slope is steeper than f^-2."""

from __future__ import annotations

import numpy as np
import pytest
from fit_scenes import sine_positions

from splineimu.spline import crossval, knots
from splineimu.spline import surrogate as sur

RATE_HZ = 200.0


def _noise(kind, n, rng):
    """(n, 3) pose noise: white, AR(1) with a 30 ms correlation time (f^-2 above 5 Hz), or that
    AR(1) low-passed once more at the same corner (f^-4 above it)."""
    if kind == "white":
        return 1e-3 * rng.normal(size=(n, 3))
    rho = np.exp(-1.0 / (RATE_HZ * 0.03))
    x = np.zeros((n, 3))
    y = np.zeros((n, 3))
    e = 1e-3 * np.sqrt(1.0 - rho**2) * rng.normal(size=(n, 3))
    for i in range(1, n):
        x[i] = rho * x[i - 1] + e[i]
        y[i] = rho * y[i - 1] + (1.0 - rho) * x[i]
    return x if kind == "ar1" else 10.0 * y  # "steep"


def _band_power(x, f, lo, hi):
    P = (np.abs(np.fft.rfft(x - x.mean(axis=0), axis=0)) ** 2).sum(axis=1)
    return P[(f >= lo) & (f < hi)].mean()


# measured (seed 3, k4, 30 and 50 ms): below 0.97 / 1.26-1.32 / 0.67-0.76, above 0.99-1.05
@pytest.mark.parametrize("kind, below", [("white", (0.8, 1.25)), ("ar1", (0.9, 1.6)), ("steep", (0.5, 0.95))])
@pytest.mark.parametrize("dt", [0.03, 0.05])
def test_surrogate_power_around_the_cut_off(kind, below, dt):
    t = np.arange(0.0, 60.0, 1.0 / RATE_HZ)
    motion = 0.5 * np.c_[np.sin(2 * np.pi * 0.3 * t), np.cos(2 * np.pi * 0.5 * t), np.sin(2 * np.pi * 0.2 * t + 1)]
    noise = _noise(kind, t.size, np.random.default_rng(3))
    windows = crossval._windows(t, np.ascontiguousarray(motion + noise), np.ones(t.size))
    first = sur.noise_spectrum(windows[0], 4, dt, np.random.default_rng(7))[1]
    surrogate = sur.noise_surrogates(windows, 4, dt)[0][0]
    f = np.fft.rfftfreq(t.size, 1.0 / RATE_HZ)
    fc = first / (t[-1] - t[0])
    above = _band_power(surrogate, f, fc, 2 * fc) / _band_power(noise, f, fc, 2 * fc)
    ratio = _band_power(surrogate, f, fc / 2, fc) / _band_power(noise, f, fc / 2, fc)
    assert 0.85 <= above <= 1.2, above
    # white stays flat, AR(1) follows f^-2 (a little above its flattening toward 5 Hz), the
    # f^-4 roll-off is continued at f^-2 only (steeper noise drifts like motion)
    assert below[0] <= ratio <= below[1], ratio


def _mocap_noise(n, rng, corner_hz):
    """(n, 3) noise as mocap orientation has it: power f^-2 from 2 Hz to ``corner_hz``, f^-6
    above (a filter's roll-off), flat below 2 Hz; 1e-3 RMS."""
    f = np.fft.rfftfreq(n, 1.0 / RATE_HZ)
    amp = 1.0 / np.maximum(f, 2.0) * np.minimum(1.0, corner_hz / np.maximum(f, 1e-9)) ** 2
    x = np.fft.irfft(np.fft.rfft(rng.normal(size=(n, 3)), axis=0) * amp[:, None], n, axis=0)
    return 1e-3 * x / x.std()


# measured (seeds 3 and 4): the second octave below the cut-off 1.10-1.16 (mocap, corner 40 Hz,
# read f^-5.7), 1.27 (corner 25 Hz, f^-5.8); 0.55-0.64 with one octave. AR(1), read f^-1.5 to
# f^-1.7, keeps one octave: 0.46-0.55 (flat below it; two octaves read its flattening toward
# 5 Hz as more noise)
@pytest.mark.parametrize("kind, dt, want", [("mocap40", 0.012, (0.85, 1.4)), ("mocap25", 0.02, (0.9, 1.6)),
                                            ("ar1", 0.02, (0.35, 0.7))])
@pytest.mark.parametrize("seed", [3, 4])
def test_surrogate_continues_noise_past_its_corner_two_octaves(kind, dt, want, seed):
    """Noise falling faster than f^-2 above the cut-off is past its own corner and keeps rising
    below it: continued at f^-2 for two octaves, not one (BROAD 29's rotation, read at a 50 Hz
    cut-off, was drawn flat below 25 Hz and its 18-34 ms rungs' noise read as bias)."""
    t = np.arange(0.0, 60.0, 1.0 / RATE_HZ)
    motion = 0.5 * np.c_[np.sin(2 * np.pi * 0.3 * t), np.cos(2 * np.pi * 0.5 * t), np.sin(2 * np.pi * 0.2 * t + 1)]
    rng = np.random.default_rng(seed)
    noise = _mocap_noise(t.size, rng, float(kind[5:])) if kind.startswith("mocap") else _noise(kind, t.size, rng)
    windows = crossval._windows(t, np.ascontiguousarray(motion + noise), np.ones(t.size))
    first = sur.noise_spectrum(windows[0], 4, dt, np.random.default_rng(7))[1]
    surrogate, _, read, _ = sur.noise_surrogates(windows, 4, dt)
    assert (read < sur._MIN_NOISE_SLOPE) == kind.startswith("mocap"), read
    f = np.fft.rfftfreq(t.size, 1.0 / RATE_HZ)
    fc = first / (t[-1] - t[0])
    ratio = _band_power(surrogate[0], f, fc / 4, fc / 2) / _band_power(noise, f, fc / 4, fc / 2)
    assert want[0] <= ratio <= want[1], ratio


def test_fast_len_is_the_least_5_smooth_length():
    """The spectra's FFT length: the least 2^a 3^b 5^c >= n (an hour at 200 Hz has 719998
    second differences, 2 x 359999: numpy took 445 ms for it, 4 ms for 720000)."""
    smooth = sorted({2**a * 3**b * 5**c for a in range(14) for b in range(9) for c in range(7)})
    for n in list(range(1, 3000)) + [11998, 719998, 1_000_001]:
        want = next(m for m in smooth if m >= n)
        assert sur.fast_len(n) == want, n


def test_fast_len_below_is_the_greatest_11_smooth_length():
    """The noise spectrum's FFT length: the greatest 2^a 3^b 5^c 7^d 11^e <= n (60 s at 200 Hz is
    12001 = 11 x 1091 poses); such lengths leave out at most 2.6% of n from 1000 on."""
    smooth = sorted({2**a * 3**b * 5**c * 7**d * 11**e for a in range(21) for b in range(13) for c in range(9)
                     for d in range(8) for e in range(6)})
    for n in list(range(1, 3000)) + [12001, 719999, 1_000_003]:
        want = max(m for m in smooth if m <= n)
        assert sur.fast_len_below(n) == want, n
    assert sur.fast_len_below(0) == 1  # (a window of one pose)
    worst = max(1.0 - 2 * sur.fast_len_below(n // 2) / n for n in range(1000, 60000, 7))
    assert worst <= 0.026, worst


def test_surrogate_covers_a_window_of_any_length():
    """Read on the window's first 2 fast_len_below(n / 2) poses, the surrogate is drawn at that
    length and continued periodically over the rest: every window gets a series of its own
    length, white noise at its level (12001 and 12000 poses: the same spectrum, within 10%)."""
    rng = np.random.default_rng(5)
    levels = []
    for n in (12001, 12000, 1847):
        t = np.arange(n) / RATE_HZ
        windows = crossval._windows(t, np.ascontiguousarray(1e-3 * rng.normal(size=(n, 3))), np.ones(n))
        series = sur.noise_surrogates(windows, 4, 0.05)[0]
        for wd, x in zip(windows, series):
            m = 2 * sur.fast_len_below(wd.X.shape[0] // 2)
            assert x.shape == wd.X.shape and m <= wd.X.shape[0]
            np.testing.assert_array_equal(x[m:], x[: wd.X.shape[0] - m])
        levels.append(np.sqrt(np.mean(series[0] ** 2)))
    assert 0.7e-3 <= min(levels) and max(levels) <= 1.3e-3, levels
    assert abs(levels[0] / levels[1] - 1.0) <= 0.1, levels


def test_motion_limited_on_lengths_with_a_large_prime_factor():
    """The padded periodogram keeps the decisions: white noise is noise, a smooth low-rate
    signal is motion, at lengths whose FFT would be slow (5999 + 2 poses) and fast ones."""
    from splineimu.scenes import make_scene

    rng = np.random.default_rng(3)
    for n in (6001, 6002, 12000):
        t = np.arange(n) * 0.05  # the flips scene at 20 Hz: its motion reaches the Nyquist frequency
        flips = make_scene("flips", duration_s=t[-1]).kinematics(t).position_world
        assert sur.motion_limited(flips) and not sur.motion_limited(rng.normal(size=(n, 3)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_slow_motion_leaking_into_the_top_octave_is_not_taken_for_motion(seed):
    """Hand-held positions at 20 Hz with 0.2 mm white noise: the plain periodogram of their second
    differences falls toward the Nyquist frequency (the slow motion's leakage from the series'
    ends, f^-2, lifts the octave below the top 2.2x above it), the tapered one rises as white
    noise does (0.16x): noise. The exact positions stay motion-limited (their tapered top octave
    is rounding), and so does the flips scene at 20 Hz."""
    t = np.arange(0.0, 60.0 + 1e-9, 0.05)
    X = sine_positions(t)
    noisy = X + 2e-4 * np.random.default_rng(seed).normal(size=X.shape)
    plain, _ = sur._falls(sur.band_power(np.diff(noisy, 2, axis=0)))
    assert plain  # what the plain reading alone decided
    assert not sur.motion_limited(noisy)
    assert sur.motion_limited(X)
    from splineimu.scenes import make_scene

    flips = make_scene("flips", duration_s=60.0).kinematics(t).position_world
    assert sur.motion_limited(flips + 2e-4 * np.random.default_rng(seed).normal(size=X.shape))


def test_rounding_only_top_octave_is_exact_input():
    """The ellipse scene's exact positions at 20 Hz are not motion-limited (one sinusoid, the
    top octave of their second differences rounding), but not noisy either: their tapered top
    octave is 4e-15 of the mean power. Noise of 1 um is 1e-3 of it."""
    from splineimu.scenes import make_scene

    t = np.arange(0.0, 60.0 + 1e-9, 0.05)
    X = make_scene("ellipse", duration_s=60.0).kinematics(t).position_world
    assert not sur.motion_limited(X) and sur.rounding_only(X)
    assert not sur.rounding_only(X + 1e-6 * np.random.default_rng(0).normal(size=X.shape))


def test_cut_off_near_zero_hz_is_not_smeared_onto_it():
    """A long window at a high rate and a coarse fit: 60 s at 1 kHz with 1 s knots puts the
    cut-off near bin 30, and the default smoothing (117 bins) read the transfer 0.2 at 0 Hz: no
    octave above it, no slope, so the white-noise bias correction stayed off (ellipse gyro 1.36x
    the best fixed setting). It is read again with the narrowest kernel: cut-off where it is, the
    white noise read as white (flatter than f^-1)."""
    rate = 1000.0
    t = np.arange(0.0, 60.0, 1.0 / rate)
    motion = 0.5 * np.c_[np.sin(2 * np.pi * 0.05 * t), np.cos(2 * np.pi * 0.08 * t), np.sin(0.3 * t)]
    noise = 1e-3 * np.random.default_rng(3).normal(size=(t.size, 3))
    (wd,) = crossval._windows(t, np.ascontiguousarray(motion + noise), np.ones(t.size))
    _, first, slope, _ = sur.noise_spectrum(wd, 6, 1.0, np.random.default_rng(7))
    fc = first / (t[-1] - t[0])  # the fit's cut-off, about 1 / (2 dt)
    assert 0.2 <= fc <= 0.8 and knots.WHITE_SLOPE < slope <= 0.5, (fc, slope)  # measured 0.47 Hz, -0.51
