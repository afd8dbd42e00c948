"""The shared IMU sensor model: every component does exactly what splineimu.imu.noise says."""

from __future__ import annotations

import time

import numpy as np
import pytest

from splineimu.errors import ConfigError, InputError
from splineimu.imu import noise as noise_mod
from splineimu.imu.config import ImuConfig
from splineimu.imu.noise import NOISE_PROCESSES, ImuMeasurement, SensorModel

RATE = 200.0


def static(n, rate=RATE):
    t = np.arange(n) / rate
    g = np.zeros((n, 3))
    a = np.zeros((n, 3))
    a[:, 2] = 9.81
    return t, g, a


def moving(n, rate=RATE, seed=0):
    """Smooth but rich ideal signals (so that least squares can separate the axes)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    g = rng.uniform(-3.0, 3.0, (n, 3))
    a = rng.uniform(-20.0, 20.0, (n, 3))
    return t, g, a


def model(**kw):
    return SensorModel(ImuConfig.from_dict(kw, source="test"))


# ------------------------------------------------------------------------------ white noise, random walk


def test_white_noise_std_is_sigma_over_sqrt_dt():
    n = 200_000
    sig = np.array([0.01, 0.02, 0.005])
    t, g, a = static(n)
    m = model(gyroscope_noise_density=sig.tolist(), accelerometer_noise_density=0.03).apply(t, g, a, rng=1)
    assert m.applied == ["gyroscope.white_noise", "accelerometer.white_noise"]
    assert m.dt_white_s == pytest.approx(1.0 / RATE, rel=1e-12)
    sd = m.gyro.std(axis=0)
    # sample std of n normals: relative sd 1/sqrt(2n) = 0.16 %; 1 % is > 6 sigma
    np.testing.assert_allclose(sd, sig * np.sqrt(RATE), rtol=0.01)
    np.testing.assert_allclose((m.accel - a).std(axis=0), 0.03 * np.sqrt(RATE), rtol=0.01)
    assert np.all(np.abs(m.gyro.mean(axis=0)) < 5 * sig * np.sqrt(RATE) / np.sqrt(n))
    assert np.all(m.bias_gyro == 0) and np.all(m.bias_accel == 0)


def test_random_walk_increments_use_the_actual_intervals():
    n = 200_000
    rng = np.random.default_rng(5)
    dt = rng.uniform(0.002, 0.02, n - 1)  # very irregular stamps
    t = np.concatenate([[0.0], np.cumsum(dt)])
    g = np.zeros((n, 3))
    a = np.zeros((n, 3))
    sig_b = np.array([1e-3, 2e-3, 5e-4])
    m = model(gyroscope_random_walk=sig_b.tolist(), accelerometer_random_walk=0.01).apply(t, g, a, rng=2)
    assert m.applied == ["gyroscope.bias_random_walk", "accelerometer.bias_random_walk"]
    assert np.all(m.bias_gyro[0] == 0)
    inc = np.diff(m.bias_gyro, axis=0) / np.sqrt(dt)[:, None]
    np.testing.assert_allclose(inc.std(axis=0), sig_b, rtol=0.01)
    # a random walk step uses the interval it spans: normalized steps are uncorrelated with dt
    assert abs(np.corrcoef(np.abs(inc[:, 0]), dt)[0, 1]) < 0.01
    # the measurement is ideal + bias exactly (no white noise configured)
    np.testing.assert_array_equal(m.gyro, g + m.bias_gyro)
    inc_a = np.diff(m.bias_accel, axis=0) / np.sqrt(dt)[:, None]
    np.testing.assert_allclose(inc_a.std(axis=0), 0.01, rtol=0.01)


def test_white_noise_uses_median_interval_on_irregular_stamps():
    n = 100_000
    rng = np.random.default_rng(8)
    dt = np.where(rng.random(n - 1) < 0.7, 0.005, 0.0075)  # median 0.005
    t = np.concatenate([[0.0], np.cumsum(dt)])
    m = model(gyroscope_noise_density=0.01).apply(t, np.zeros((n, 3)), np.zeros((n, 3)), rng=3)
    assert m.dt_white_s == pytest.approx(0.005, rel=1e-9)
    np.testing.assert_allclose(m.gyro.std(axis=0), 0.01 / np.sqrt(0.005), rtol=0.015)


# ------------------------------------------------------------------------------ reproducibility


FULL = dict(
    gyroscope_noise_density=0.01, gyroscope_random_walk=1e-4, gyroscope_bias_sigma=0.01,
    gyroscope_bias_instability=1e-3, gyroscope_bias_correlation_time=10.0,
    accelerometer_noise_density=0.02, accelerometer_random_walk=1e-3, accelerometer_bias_sigma=0.05,
    accelerometer_bias_instability=1e-2, accelerometer_bias_correlation_time=5.0, update_rate=200.0,
)


def test_same_seed_same_bytes():
    t, g, a = moving(5000)
    sm = model(**FULL)
    m1 = sm.apply(t, g, a, rng=123)
    m2 = sm.apply(t, g, a, rng=123)
    m3 = model(**FULL).apply(t, g, a, rng=np.random.SeedSequence(123))
    for x in (m2, m3):
        assert x.gyro.tobytes() == m1.gyro.tobytes()
        assert x.accel.tobytes() == m1.accel.tobytes()
        assert x.bias_gyro.tobytes() == m1.bias_gyro.tobytes()
        assert x.bias_accel.tobytes() == m1.bias_accel.tobytes()
    assert m1.seed_entropy == 123
    other = sm.apply(t, g, a, rng=124)
    assert not np.array_equal(other.gyro, m1.gyro)
    # a SeedSequence is not consumed: using it twice repeats the run
    ss = np.random.SeedSequence(99)
    assert sm.apply(t, g, a, rng=ss).gyro.tobytes() == sm.apply(t, g, a, rng=ss).gyro.tobytes()
    # rng=None records fresh entropy that reproduces the run
    m4 = sm.apply(t, g, a)
    m5 = sm.apply(t, g, a, rng=np.random.SeedSequence(m4.seed_entropy))
    assert m4.gyro.tobytes() == m5.gyro.tobytes()
    # Generators: reproducible from the same state, and each call advances
    r1, r2 = np.random.default_rng(7), np.random.default_rng(7)
    x1, x2 = sm.apply(t, g, a, rng=r1), sm.apply(t, g, a, rng=r2)
    assert x1.gyro.tobytes() == x2.gyro.tobytes() and x1.seed_entropy is None
    assert not np.array_equal(sm.apply(t, g, a, rng=r1).gyro, x1.gyro)


@pytest.mark.parametrize("pieces", [[5000], [1, 4999], [2500, 2500], [1, 1, 1, 3, 994, 4000], [7] * 714 + [2]])
def test_pieces_give_the_same_bytes_as_the_whole_record(pieces):
    """SensorModel.stream: every process continues across pieces (random walk, Gauss-Markov,
    turn-on bias, white noise, temperature, quantization), bit for bit."""
    t, g, a = moving(5000)
    t = t + 1e-4 * np.sin(np.arange(5000))  # irregular intervals: the steps across pieces matter
    cfg = dict(FULL, gyroscope_quantization=1e-4, accelerometer_bias_temperature_coefficient=[1e-3, 0, 0],
               temperature_profile={"start": 20.0, "rate": 0.01})
    sm = model(**cfg)
    whole = sm.apply(t, g, a, rng=123)
    st = sm.stream(rng=123, dt_white_s=float(np.median(np.diff(t))))
    edges = np.cumsum([0] + pieces)
    parts = [st.apply(t[i:j], g[i:j], a[i:j]) for i, j in zip(edges[:-1], edges[1:])]
    for name in ("gyro", "accel", "bias_gyro", "bias_accel"):
        assert np.vstack([getattr(m, name) for m in parts]).tobytes() == getattr(whole, name).tobytes(), name
    assert parts[-1].applied == whole.applied
    with pytest.raises(InputError, match="strictly increasing"):
        st.apply(t[-1:], g[-1:], a[-1:])


def test_child_streams_follow_the_documented_order():
    # child i of seed s is SeedSequence(s, spawn_key=(i,)): white noise of the gyro is child 0
    n = 1000
    t, g, a = static(n)
    m = model(gyroscope_noise_density=0.01).apply(t, g, a, rng=42)
    z = np.random.default_rng(np.random.SeedSequence(42, spawn_key=(0,))).standard_normal((n, 3))
    np.testing.assert_allclose(m.gyro, 0.01 * np.sqrt(RATE) * z, rtol=1e-9, atol=0)
    i = NOISE_PROCESSES.index("accelerometer.bias_random_walk")
    m = model(accelerometer_random_walk=0.1).apply(t, g, a, rng=42)
    z = np.random.default_rng(np.random.SeedSequence(42, spawn_key=(i,))).standard_normal((n - 1, 3))
    np.testing.assert_allclose(np.diff(m.bias_accel, axis=0), 0.1 * np.sqrt(1 / RATE) * z,
                               rtol=1e-9, atol=1e-15)


def test_changing_accelerometer_leaves_gyro_bit_identical():
    t, g, a = moving(20_000)
    base = model(**FULL).apply(t, g, a, rng=2024)
    changed = dict(FULL, accelerometer_noise_density=0.5, accelerometer_random_walk=0.0,
                   accelerometer_bias_sigma=1.0, accelerometer_bias_instability=0.3,
                   accelerometer_bias_correlation_time=1.0, accelerometer_quantization=0.01,
                   accelerometer_scale=[1e-3, 2e-3, 3e-3], accelerometer_saturation=50.0)
    other = model(**changed).apply(t, g, a, rng=2024)
    assert other.gyro.tobytes() == base.gyro.tobytes()
    assert other.bias_gyro.tobytes() == base.bias_gyro.tobytes()
    assert not np.array_equal(other.accel, base.accel)
    # and the other way round
    other = model(**dict(FULL, gyroscope_noise_density=0.0, gyroscope_scale=0.01)).apply(t, g, a, rng=2024)
    assert other.accel.tobytes() == base.accel.tobytes()
    assert other.bias_accel.tobytes() == base.bias_accel.tobytes()


def test_unnamed_components_draw_nothing(monkeypatch):
    asked = []
    orig = noise_mod._Streams.__call__

    def spy(self, process):
        asked.append(process)
        return orig(self, process)

    monkeypatch.setattr(noise_mod._Streams, "__call__", spy)
    t, g, a = moving(1000)
    m = SensorModel("ideal").apply(t, g, a, rng=1)
    assert asked == [] and m.applied == []
    np.testing.assert_array_equal(m.gyro, g)
    np.testing.assert_array_equal(m.accel, a)
    assert m.gyro is not g  # a new array, the input is untouched
    model(gyroscope_noise_density=0.01, accelerometer_bias=[0.1, 0, 0]).apply(t, g, a, rng=1)
    assert asked == ["gyroscope.white_noise"]


def test_inputs_are_not_modified_and_validated():
    t, g, a = moving(100)
    g0, a0 = g.copy(), a.copy()
    model(**FULL, gyroscope_quantization=0.01, gyroscope_saturation=1.0).apply(t, g, a, rng=0)
    np.testing.assert_array_equal(g, g0)
    np.testing.assert_array_equal(a, a0)
    sm = model(**FULL)
    with pytest.raises(InputError, match=r"shape \(100, 3\)"):
        sm.apply(t, g[:, :2], a)
    with pytest.raises(InputError, match="strictly increasing"):
        sm.apply(t[::-1].copy(), g, a)
    g[3, 1] = np.nan
    with pytest.raises(InputError, match="NaN"):
        sm.apply(t, g, a)
    with pytest.raises(ConfigError, match="rng"):
        sm.apply(t, g0, a, rng="seed")
    with pytest.raises(ConfigError, match="`rng` must be between 0"):
        sm.apply(t, g0, a, rng=-1)


def test_single_sample_uses_update_rate():
    sm = model(gyroscope_noise_density=0.01, update_rate=100.0)
    m = sm.apply([0.0], [[0, 0, 0]], [[0, 0, 9.81]], rng=1)
    assert m.dt_white_s == 0.01 and m.gyro.shape == (1, 3)
    with pytest.raises(ConfigError, match="update_rate"):
        model(gyroscope_noise_density=0.01).apply([0.0], [[0, 0, 0]], [[0, 0, 9.81]], rng=1)


# ------------------------------------------------------------------------------ turn-on bias, Gauss-Markov


def test_turn_on_bias_fixed_plus_drawn():
    t, g, a = static(10)
    m = model(gyroscope_bias=[0.1, -0.2, 0.3]).apply(t, g, a, rng=0)
    np.testing.assert_array_equal(m.bias_gyro, np.tile([0.1, -0.2, 0.3], (10, 1)))
    np.testing.assert_array_equal(m.gyro, m.bias_gyro)
    sm = model(accelerometer_bias=[0.0, 0.0, 1.0], accelerometer_bias_sigma=[0.5, 0.1, 0.2])
    b = np.array([sm.apply(t, g, a, rng=s).bias_accel[0] for s in range(600)])
    # sample std over 600 runs: relative sd 2.9 %; 12 % is > 4 sigma
    np.testing.assert_allclose(b.std(axis=0), [0.5, 0.1, 0.2], rtol=0.12)
    np.testing.assert_allclose(b.mean(axis=0), [0.0, 0.0, 1.0], atol=4 * 0.5 / np.sqrt(600))
    m = sm.apply(t, g, a, rng=3)
    assert np.all(m.bias_accel == m.bias_accel[0])  # constant over the run


def test_gauss_markov_variance_and_correlation_match_theory():
    n, rate = 1_000_000, 100.0
    dt = 1.0 / rate
    sigma = np.array([0.5, 0.1, 2.0])
    tau = np.array([2.0, 2.0, 0.5])
    t, g, a = static(n, rate)
    m = model(gyroscope_bias_instability=sigma.tolist(), gyroscope_bias_correlation_time=tau.tolist()).apply(
        t, g, a, rng=11)
    b = m.bias_gyro
    # stationary variance sigma^2: ~ duration / (2 tau) = 2500 independent samples -> 2.8 % sd
    np.testing.assert_allclose(b.std(axis=0), sigma, rtol=0.06)
    # one-step regression coefficient exp(-dt/tau): sd ~ sqrt((1 - phi^2) / n) ~ 1e-4
    phi = np.exp(-dt / tau)
    phi_hat = np.sum(b[1:] * b[:-1], axis=0) / np.sum(b[:-1] ** 2, axis=0)
    np.testing.assert_allclose(phi_hat, phi, atol=6e-4)
    resid = b[1:] - phi_hat * b[:-1]
    np.testing.assert_allclose(resid.std(axis=0), sigma * np.sqrt(1 - phi**2), rtol=0.01)
    # autocorrelation at lag tau is 1/e
    for k in range(3):
        lag = int(round(tau[k] * rate))
        r = np.corrcoef(b[lag:, k], b[:-lag, k])[0, 1]
        assert abs(r - np.exp(-1.0)) < 0.05


def test_gauss_markov_allan_peak_is_0617_sigma():
    # the documented relation used to choose sigma from an Allan-plot bias instability
    from splineimu.allan import allan_deviation

    n, rate, sigma, T = 1_000_000, 100.0, 1.0, 2.0
    t, g, a = static(n, rate)
    m = model(gyroscope_bias_instability=sigma, gyroscope_bias_correlation_time=T).apply(t, g, a, rng=4)
    r = allan_deviation(m.bias_gyro, rate, taus=[1.89 * T])
    # edf ~ 1.5 N / m ~ 4000 per axis: the mean of 3 axes is within a few percent
    assert r.adev[0].mean() == pytest.approx(0.617 * sigma, rel=0.08)


# ------------------------------------------------------------------------------ intrinsics


def _lstsq_with_se(x, y):
    """Fit y = x @ A.T + c; return A, c and the standard errors of A."""
    X = np.column_stack([x, np.ones(len(x))])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    resid = y - X @ coef
    s2 = (resid**2).sum(axis=0) / (len(x) - 4)
    cov = np.linalg.inv(X.T @ X)
    se = np.sqrt(np.outer(np.diag(cov)[:3], s2)).T  # (3 outputs, 3 inputs)
    return coef[:3].T, coef[3], se


def test_scale_and_misalignment_recovered_by_least_squares():
    n = 20_000
    t, g, a = moving(n, seed=3)
    s = np.array([1e-3, -2e-3, 5e-4])
    M = np.array([[1.0, 0.0, 0.0], [2e-3, 1.0, 0.0], [-1e-3, 3e-3, 1.0]])
    Ma = np.array([[1.0, 1e-3, -2e-3], [0.5e-3, 1.0, 1e-3], [0.0, -1e-3, 1.0]])
    # gyro misalignment in Kalibr's lower-triangle form [m21, m31, m32]
    cfg = dict(gyroscope_scale=s.tolist(), gyroscope_misalignment=[2e-3, -1e-3, 3e-3],
               accelerometer_scale=0.01, accelerometer_misalignment=Ma.tolist(),
               gyroscope_noise_density=1e-3, accelerometer_noise_density=1e-2)
    m = model(**cfg).apply(t, g, a, rng=9)
    assert m.applied == ["gyroscope.scale", "gyroscope.misalignment", "gyroscope.white_noise",
                         "accelerometer.scale", "accelerometer.misalignment", "accelerometer.white_noise"]
    for x, y, true in ((g, m.gyro, M @ np.diag(1 + s)), (a, m.accel, Ma * 1.01)):
        A, c, se = _lstsq_with_se(x, y)
        err = np.abs(A - true)
        assert np.all(err < 5 * se), (err / se)  # to the noise limit
        assert np.all(np.abs(c) < 5 * y.std() / np.sqrt(n))
    # without noise: exact
    cfg.pop("gyroscope_noise_density")
    cfg.pop("accelerometer_noise_density")
    m = model(**cfg).apply(t, g, a, rng=9)
    np.testing.assert_allclose(m.gyro, g @ (M @ np.diag(1 + s)).T, rtol=0, atol=1e-14)
    np.testing.assert_allclose(m.accel, a @ (Ma * 1.01).T, rtol=0, atol=1e-13)


def test_g_sensitivity_adds_G_times_specific_force():
    t, g, a = moving(5000, seed=4)
    G = np.array([[1e-4, 2e-5, 0.0], [0.0, 1e-4, -3e-5], [5e-5, 0.0, 2e-4]])
    base = model(gyroscope_noise_density=0.01, gyroscope_random_walk=1e-3).apply(t, g, a, rng=5)
    with_g = model(gyroscope_noise_density=0.01, gyroscope_random_walk=1e-3,
                   gyroscope_g_sensitivity=G.tolist()).apply(t, g, a, rng=5)
    assert "gyroscope.g_sensitivity" in with_g.applied
    np.testing.assert_allclose(with_g.gyro - base.gyro, a @ G.T, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(with_g.accel, base.accel)


def test_quantization_steps_equal_the_lsb():
    t, g, a = moving(20_000, seed=6)
    lsb = np.array([0.01, 0.02, 0.005])
    raw = model(gyroscope_noise_density=1e-3).apply(t, g, a, rng=1)
    q = model(gyroscope_noise_density=1e-3, gyroscope_quantization=lsb.tolist()).apply(t, g, a, rng=1)
    assert q.applied[-1] == "gyroscope.quantization"
    codes = q.gyro / lsb
    np.testing.assert_allclose(codes, np.round(codes), rtol=0, atol=1e-9)
    assert np.all(np.abs(q.gyro - raw.gyro) <= lsb / 2 * (1 + 1e-12))
    for k in range(3):
        steps = np.diff(np.unique(q.gyro[:, k]))
        assert steps.min() == pytest.approx(lsb[k], rel=1e-9)
    # quantization error is uniform: std LSB / sqrt(12)
    np.testing.assert_allclose((q.gyro - raw.gyro).std(axis=0), lsb / np.sqrt(12), rtol=0.03)


def test_saturation_clips_at_the_range_after_quantization():
    n = 2001
    t = np.arange(n) / RATE
    ramp = np.linspace(-5.0, 5.0, n)
    g = np.column_stack([ramp, 0.5 * ramp, np.zeros(n)])
    a = np.column_stack([10 * ramp, np.zeros(n), np.full(n, 9.81)])
    r = np.array([2.0, 2.0, 1.0])
    m = model(gyroscope_saturation=r.tolist(), gyroscope_quantization=0.3,
              accelerometer_saturation=16.0).apply(t, g, a, rng=0)
    assert m.applied == ["gyroscope.quantization", "gyroscope.saturation", "accelerometer.saturation"]
    assert m.gyro[:, 0].max() == 2.0 and m.gyro[:, 0].min() == -2.0
    assert m.gyro[:, 1].max() == 2.0 and m.gyro[:, 1].min() == -2.0  # 0.5 * 5 > 2
    inside = np.abs(g[:, 0]) < 1.8
    np.testing.assert_allclose(m.gyro[inside, 0], 0.3 * np.round(g[inside, 0] / 0.3), atol=1e-12)
    assert m.accel[:, 0].max() == 16.0 and m.accel[:, 0].min() == -16.0
    ok = np.abs(a[:, 0]) < 16.0
    np.testing.assert_array_equal(m.accel[ok, 0], a[ok, 0])


# ------------------------------------------------------------------------------ temperature


def test_temperature_bias_and_scale_are_linear(tmp_path):
    n = 1000
    t, g, a = moving(n, seed=7)
    cb = [1e-4, -2e-4, 3e-4]
    cs = [1e-5, 2e-5, -1e-5]
    cfg = dict(gyroscope_bias_temperature_coefficient=cb, gyroscope_scale_temperature_coefficient=cs,
               gyroscope_scale=[1e-3, 0, 0], temperature_profile={"start": 15.0, "rate": 0.1},
               temperature_reference=20.0, accelerometer_bias_temperature_coefficient=0.01)
    m = model(**cfg).apply(t, g, a, rng=0)
    T = 15.0 + 0.1 * t
    np.testing.assert_allclose(m.temperature_c, T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.bias_gyro, np.outer(T - 20.0, cb), rtol=0, atol=1e-15)
    expect = g * (1 + np.array([1e-3, 0, 0]) + np.outer(T - 20.0, cs)) + np.outer(T - 20.0, cb)
    np.testing.assert_allclose(m.gyro, expect, rtol=0, atol=1e-14)
    np.testing.assert_allclose(m.accel - a, np.outer(T - 20.0, [0.01] * 3), rtol=0, atol=1e-12)
    assert {"gyroscope.bias_temperature", "gyroscope.scale_temperature"} <= set(m.applied)
    # an explicit temperature overrides the profile; the reference defaults to 25 degC
    m = model(gyroscope_bias_temperature_coefficient=cb).apply(t, g, a, rng=0, temperature_c=30.0)
    np.testing.assert_allclose(m.bias_gyro, np.tile(np.multiply(cb, 5.0), (n, 1)), rtol=1e-14)
    # a temperature table from a file (relative to the yaml), interpolated linearly
    (tmp_path / "temp.csv").write_text("# time_s, temperature_c\n0, 10\n2.5, 35\n")
    (tmp_path / "imu.yaml").write_text("gyroscope_bias_temperature_coefficient: 1.0e-3\n"
                                       "temperature_profile: {file: temp.csv}\n")
    m = SensorModel(str(tmp_path / "imu.yaml")).apply(t, g, a, rng=0)
    T = np.interp(t, [0, 2.5], [10, 35])
    np.testing.assert_allclose(m.bias_gyro[:, 0], 1e-3 * (T - 25.0), rtol=0, atol=1e-15)
    with pytest.raises(ConfigError, match="temperature"):
        model(gyroscope_bias_temperature_coefficient=cb).apply(t, g, a, rng=0)


# ------------------------------------------------------------------------------ result object, speed


def test_measurement_dataframe_and_components():
    t, g, a = static(50)
    sm = model(**FULL)
    m = sm.apply(t, g, a, rng=1)
    assert isinstance(m, ImuMeasurement)
    assert m.applied == sm.components()
    df = m.to_dataframe()
    assert list(df.columns[:4]) == ["t_s", "gyro_x_rad_s", "gyro_y_rad_s", "gyro_z_rad_s"]
    np.testing.assert_array_equal(df["bias_accel_z_m_s2"].to_numpy(), m.bias_accel[:, 2])


@pytest.mark.slow
def test_three_hour_static_generation():
    """3 h at 200 Hz in one call (its speed is a benchmark's business, not a test's)."""
    n = int(3 * 3600 * RATE)
    t, g, a = static(n)
    sm = SensorModel("lecture")
    sm.apply(t[:1000], g[:1000], a[:1000], rng=0)  # JIT warm-up / cache load
    t0 = time.perf_counter()
    m = sm.apply(t, g, a, rng=0)
    el = time.perf_counter() - t0
    print(f"3 h x 200 Hz generation: {el:.2f} s")
    assert m.gyro.shape == (n, 3) and np.all(np.isfinite(m.gyro)) and np.all(np.isfinite(m.accel))
