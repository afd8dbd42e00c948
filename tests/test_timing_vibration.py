"""IMU timing (clock offset, drift, stamp noise, losses) and vibration, against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu.errors import ConfigError
from splineimu.imu.timing import TimingModel
from splineimu.imu.vibration import N_TONES, VibrationModel
from splineimu.io.yaml import parse_yaml
from splineimu.timegrid import uniform_stamps_ns

T0 = 1_700_000_000_000_000_000
SPAN = 60_000_000_000


def test_no_timing_is_the_plain_grid():
    st = TimingModel().sample_times(T0, T0 + SPAN, 200.0, rng=0)
    grid = uniform_stamps_ns(T0, T0 + SPAN, 200.0)
    assert np.array_equal(st.true_ns, grid) and np.array_equal(st.stamp_ns, grid)
    assert st.n_dropped == 0 and TimingModel().is_identity


def test_offset_drift_noise_and_losses_recovered():
    tm = TimingModel(time_offset_s=0.0123, clock_drift_ppm=50.0, stamp_noise_s=1e-4, drop_probability=0.01)
    st = tm.sample_times(T0, T0 + SPAN, 200.0, rng=7)
    x = (st.true_ns - T0) / 1e9
    y = (st.stamp_ns - T0) / 1e9
    slope, offset = np.polyfit(x, y, 1)
    assert abs(slope - (1 + 50e-6)) < 1e-6
    assert abs(offset - 0.0123) < 10e-6
    resid = y - (slope * x + offset)
    assert abs(resid.std() / 1e-4 - 1) < 0.05
    n, p = st.n_taken, 0.01
    assert abs(st.n_dropped - n * p) < 4 * np.sqrt(n * p * (1 - p))
    # the clock grid: index k taken at true time first + (k / rate) / (1 + drift)
    expect = T0 + np.rint(np.round(st.index * 1e9 / 200.0) / (1 + 50e-6)).astype(np.int64)
    assert np.array_equal(st.true_ns, expect)
    assert st.true_ns[-1] <= T0 + SPAN
    rep = st.report()
    assert rep["dropped"] == st.n_dropped and rep["samples_written"] == st.index.size


def test_negative_drift_covers_the_span():
    st = TimingModel(clock_drift_ppm=-200.0).sample_times(0, 10_000_000_000, 100.0)
    assert st.true_ns[-1] <= 10_000_000_000 and 10_000_000_000 - st.true_ns[-1] < 10_000_000
    assert st.index[-1] == 999  # the slow clock reaches 9.998 s of its own time at true 10 s


def test_dropped_runs_cover_every_loss_and_effects_draw_apart():
    tm = TimingModel(drop_probability=0.4)
    st = tm.sample_times(0, 2_000_000_000, 100.0, rng=3)
    runs = st.dropped_ranges(max_ranges=10**6)
    assert sum(r["count"] for r in runs) == st.n_dropped == st.n_taken - st.index.size
    assert len(runs) == st.n_dropped_runs() == st.report()["dropped_runs_total"]
    ends = [r for r in runs if r["first_index"] == 0 or r["first_index"] + r["count"] == st.n_taken]
    assert len(ends) == 2  # this seed loses samples at both ends of the record
    for r in ends:
        assert r["t_start_ns"] == 0 if r["first_index"] == 0 else r["t_end_ns"] == 2_000_000_000
    # stamp noise does not move the losses (each effect has its own stream)
    noisy = TimingModel(drop_probability=0.4, stamp_noise_s=1e-4).sample_times(0, 2_000_000_000, 100.0, rng=3)
    assert np.array_equal(noisy.index, st.index) and not np.array_equal(noisy.stamp_ns, st.stamp_ns)


def test_burst_losses_have_the_asked_fraction_and_length():
    tm = TimingModel(drop_probability=0.05, drop_burst_s=0.1)
    st = tm.sample_times(0, 600_000_000_000, 200.0, rng=3)
    frac = st.n_dropped / st.n_taken
    assert abs(frac - 0.05) < 0.01
    runs = [r["count"] for r in st.dropped_ranges(max_ranges=10**6)]
    assert 15 < np.mean(runs) < 25  # mean burst 0.1 s = 20 samples at 200 Hz


def test_timing_errors_name_file_and_line():
    doc = parse_yaml("imu:\n  timing:\n    clock_drift_ppm: 5\n    drop_probabilty: 0.1\n", "scene.yaml")
    with pytest.raises(ConfigError, match=r"scene\.yaml:4: unknown key `timing.drop_probabilty`; did you mean"):
        TimingModel.from_dict(doc.data["imu"]["timing"], doc, ("imu", "timing"))
    doc = parse_yaml("imu:\n  timing:\n    drop_probability: 1.5\n", "scene.yaml")
    with pytest.raises(ConfigError, match=r"scene\.yaml:3: `drop_probability` must be below 1"):
        TimingModel.from_dict(doc.data["imu"]["timing"], doc, ("imu", "timing"))


def test_sinusoid_amplitude_and_frequency():
    vib = VibrationModel.from_dict({"accel": [{"freq_hz": 37.0, "amplitude": [0.5, 0.0, 0.2]}]})
    t = np.arange(12000) / 200.0
    gyro, accel = vib.realize(rng=1).evaluate(t)
    assert not gyro.any()
    spec = np.abs(np.fft.rfft(accel, axis=0)) * 2 / t.size
    f = np.fft.rfftfreq(t.size, 1 / 200.0)
    k = int(np.argmax(spec[:, 0]))
    assert f[k] == pytest.approx(37.0)
    assert spec[k, 0] == pytest.approx(0.5, rel=1e-9) and spec[k, 2] == pytest.approx(0.2, rel=1e-9)
    assert np.abs(accel[:, 1]).max() == 0.0


def test_random_band_variance_and_band():
    psd = 1e-3
    vib = VibrationModel.from_dict({"gyro": [{"band_hz": [20.0, 60.0], "psd": [psd, 0.0, psd]}]})
    t = np.arange(200_000) / 400.0
    gyro, _ = vib.realize(rng=2).evaluate(t)
    assert gyro[:, 0].var() == pytest.approx(psd * 40.0, rel=0.02)  # exact: sum of amp^2 / 2
    spec = np.abs(np.fft.rfft(gyro[:, 2])) ** 2
    f = np.fft.rfftfreq(t.size, 1 / 400.0)
    inside = (f >= 20) & (f <= 60)
    assert spec[inside].sum() / spec.sum() > 0.999
    assert N_TONES >= 128


def test_interval_mean_is_exact():
    vib = VibrationModel.from_dict({"accel": [{"freq_hz": 13.0, "amplitude": [1.0, 2.0, 3.0]}]})
    real = vib.realize(rng=4)
    a, b = np.array([0.1, 0.5]), np.array([0.105, 0.52])
    _, mean = real.evaluate(b, interval_start_s=a)
    s = np.linspace(0, 1, 20001)
    for i in range(2):
        _, pts = real.evaluate(a[i] + (b[i] - a[i]) * s)
        ref = 0.5 * ((pts[1:] + pts[:-1]) * np.diff(s)[:, None]).sum(axis=0)  # trapezoidal rule
        assert np.allclose(mean[i], ref, atol=1e-8)


def test_same_seed_same_vibration():
    d = {"accel": [{"band_hz": [5.0, 50.0], "psd": [1e-4, 1e-4, 1e-4]}]}
    t = np.linspace(0, 3, 301)
    a1 = VibrationModel.from_dict(d).realize(rng=9).evaluate(t)[1]
    a2 = VibrationModel.from_dict(d).realize(rng=9).evaluate(t)[1]
    a3 = VibrationModel.from_dict(d).realize(rng=10).evaluate(t)[1]
    assert np.array_equal(a1, a2) and not np.array_equal(a1, a3)


@pytest.mark.parametrize("block, match", [
    ({"accel": [{"freq_hz": 0, "amplitude": [1, 0, 0]}]}, "must be positive"),
    ({"accel": [{"freq_hz": 5, "amplitude": [1, 0]}]}, r"shape \(3,\)"),
    ({"accel": [{"band_hz": [50, 20], "psd": [1, 1, 1]}]}, "high > low"),
    ({"accel": [{"freq": 5}]}, "exactly the keys"),
    ({"magnetometer": []}, "unknown key `vibration.magnetometer`"),
])
def test_vibration_errors(block, match):
    with pytest.raises((ConfigError, ValueError), match=match):
        VibrationModel.from_dict(block)


def test_stamp_noise_that_reorders_stamps_is_refused():
    """Stamps that go backwards are read by no estimator: the realization is checked, and a
    noise of a tenth of the period passes (2 h at 200 Hz: 7.07 sigma per step)."""
    with pytest.raises(ConfigError, match=r"stamp_noise_s.*1[0-9][0-9] of 400 stamps.*0\.0005 s"):
        TimingModel(stamp_noise_s=0.01).sample_times(0, 2_000_000_000, 200.0, rng=6118486862876944342)
    st = TimingModel(stamp_noise_s=0.0005).sample_times(0, 7_200_000_000_000, 200.0, rng=1)
    assert np.all(np.diff(st.stamp_ns) > 0) and st.stamp_ns.size == 1_440_001
