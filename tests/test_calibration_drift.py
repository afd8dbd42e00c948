"""Bias drift in calibrations: the random-walk covariance of the phase means, its density from the
data, 2-sigma coverage with drifting sensors (EuRoC, TUM-VI and lecture noise models), the
drift-dominated flag, and calibrate_file, the library behind the command."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from test_calibration import TRUE_INTRINSICS as INTRINSICS

from splineimu.api.calibration import calibrate_file
from splineimu.calibration import (
    CalibrationOptions,
    calibrate_accel,
    calibrate_gyro,
    intrinsics_from_config,
)
from splineimu.calibration.drift import phase_drift_covariance
from splineimu.cli import main
from splineimu.errors import ConfigError, OutputExistsError
from splineimu.imu.noise import SensorModel
from splineimu.scenes import make_scene

RATE_HZ = 200.0
#: Noise models of splineimu/presets (EuRoC ADIS16448, TUM-VI BMI160, the lecture's example).
MODELS = {
    "adis16448": {"gyroscope_noise_density": 1.6968e-04, "gyroscope_random_walk": 1.9393e-05,
                  "accelerometer_noise_density": 2.0e-3, "accelerometer_random_walk": 3.0e-3},
    "bmi160": {"gyroscope_noise_density": 1.6e-4, "gyroscope_random_walk": 2.2e-5,
               "accelerometer_noise_density": 2.8e-3, "accelerometer_random_walk": 8.6e-4},
    "lecture": {"gyroscope_noise_density": 0.015, "gyroscope_random_walk": 5e-5,
                "accelerometer_noise_density": 0.019, "accelerometer_random_walk": 5e-4},
    "white": {"gyroscope_noise_density": 1.7e-4, "accelerometer_noise_density": 2.0e-3},
}


def _config(model):
    return {**INTRINSICS, **MODELS[model], "update_rate": RATE_HZ}


def _coverage(sensor, model, seeds, **settings):
    """2-sigma hits (seeds, 12) against the truth: K of the model, b the true bias averaged over the
    samples of the phases used (what a ground-truth file gives); and the calibrations."""
    cfg = _config(model)
    sc = make_scene("six-position" if sensor == "accelerometer" else "rate-table")
    t_ns = sc.sample_times_ns(RATE_HZ)
    t_s = sc.t_s_from_ns(t_ns)
    w, f = sc.imu(t_s)
    K, _ = intrinsics_from_config(cfg, sensor)
    hits, cals = [], []
    for seed in seeds:
        m = SensorModel(cfg).apply(t_s, w, f, rng=seed)
        if sensor == "accelerometer":
            cal, bias = calibrate_accel(t_ns, m.accel, gyro=m.gyro, **settings), m.bias_accel
        else:
            cal, bias = calibrate_gyro(t_ns, m.gyro, 1.0, accel=m.accel, **settings), m.bias_gyro
        idx = np.concatenate([np.arange(p.start, p.stop) for p in cal.phases if p.used])
        truth = np.concatenate([K.ravel(), bias[idx].mean(axis=0)])
        hits.append(np.abs(cal.parameters - truth) <= 2.0 * cal.std)
        cals.append(cal)
    return np.array(hits), cals


def test_phase_drift_covariance_matches_sampled_random_walks():
    t_ns = np.arange(2000, dtype=np.int64) * 10_000_000          # 100 Hz, 20 s
    phases = [type("P", (), {"start": a, "stop": b})() for a, b in ((0, 300), (800, 1100), (1500, 2000))]
    D = phase_drift_covariance(t_ns, phases)
    rng = np.random.default_rng(0)
    q = math.sqrt(0.01)                                           # density 1, dt 0.01 s
    walks = np.cumsum(rng.standard_normal((4000, 2000)) * q, axis=1)
    means = np.stack([walks[:, p.start:p.stop].mean(axis=1) for p in phases], axis=1)
    w = np.array([300, 300, 500]) / 1100
    rel = means - means @ w[:, None]
    # sampling error of a covariance from 4000 draws: about 2 % of the diagonal
    np.testing.assert_allclose(np.cov(rel.T), D, rtol=0, atol=0.08 * D.diagonal().max())
    assert abs(w @ D @ w) < 1e-12                                  # the weighted mean carries no drift


def test_random_walk_density_is_estimated_from_the_phases():
    _, cals = _coverage("accelerometer", "adis16448", range(6))
    rw = np.array([c.random_walk[0] for c in cals])
    assert all(c.random_walk_source == "estimated" for c in cals)
    # measured over 12 seeds: 2.0e-3 .. 3.6e-3, mean 3.03e-3 (truth 3e-3)
    assert abs(rw.mean() / 3e-3 - 1) < 0.2 and rw.min() > 1.5e-3, rw
    assert all(c.drift_dominated for c in cals)
    # white noise: no drift found, or one too small to be significant
    _, white = _coverage("accelerometer", "white", range(6))
    assert all(c.random_walk[0] < 1e-3 and not c.drift_dominated for c in white)
    # noise-free data: no drift beyond round-off (measured 6e-10, and 1.9e-8 with numpy 2.4.6 /
    # scipy 1.17.1 / numba 0.68.1: five orders below the ADIS16448's 3e-3), not flagged
    sc = make_scene("six-position")
    t_ns = sc.sample_times_ns(RATE_HZ)
    w, f = sc.imu(sc.t_s_from_ns(t_ns))
    m = SensorModel(INTRINSICS).apply(sc.t_s_from_ns(t_ns), w, f)
    cal = calibrate_accel(t_ns, m.accel, gyro=m.gyro)
    assert cal.random_walk[0] < 1e-7 and not cal.drift_dominated


def test_drifting_accelerometer_coverage_over_twelve_seeds():
    """Issue acceptance: EuRoC ADIS16448 (accel random walk 3e-3) six-position test, >= 85 % of
    the estimates within 2 stated std (26 % without the drift model; measured with it 96 %)."""
    hits, cals = _coverage("accelerometer", "adis16448", range(12))
    assert hits.mean() >= 0.85, hits.mean(axis=0)
    white_only, _ = _coverage("accelerometer", "adis16448", range(12), random_walk=0.0)
    assert white_only.mean() < 0.5                                  # the drift is what matters here
    # the given (true) density does as well as the estimated one
    given, _ = _coverage("accelerometer", "adis16448", range(12), random_walk=3e-3)
    assert given.mean() >= 0.85


@pytest.mark.slow
@pytest.mark.parametrize("model", ["adis16448", "bmi160", "lecture"])
@pytest.mark.parametrize("sensor", ["accelerometer", "gyroscope"])
def test_drift_coverage_monte_carlo(sensor, model):
    # measured over 100 seeds: adis16448 0.958 / 0.948 (accel / gyro); 40 seeds: bmi160 0.944 /
    # 0.940, lecture 0.958 / 0.942
    hits, _ = _coverage(sensor, model, range(100))
    assert abs(hits.mean() - 0.95) <= 0.03, hits.mean(axis=0)
    assert hits.mean(axis=0).min() >= 0.85, hits.mean(axis=0)


def test_options_are_validated():
    with pytest.raises(ConfigError, match="random_walk"):
        CalibrationOptions(random_walk=-1.0)
    with pytest.raises(ConfigError, match="noise_density"):
        CalibrationOptions(noise_density=[1e-3, 2e-3])
    with pytest.raises(ConfigError, match="max_axis_angle_deg"):
        CalibrationOptions(max_axis_angle_deg=50)
    assert CalibrationOptions(random_walk=0).random_walk == (0.0, 0.0, 0.0)
    with pytest.raises(TypeError, match="tilt_sigma"):
        calibrate_accel(np.arange(10), np.zeros((10, 3)), tilt_sigma=1.0)


def _scene(tmp_path, model, name="six-position", seed=3):
    imu = tmp_path / "imu.yaml"
    imu.write_text(yaml.safe_dump(_config(model)))
    out = tmp_path / f"{name}-{model}"
    assert main(["scene", name, "-o", str(out), "--imu", str(imu), "--seed", str(seed)]) == 0
    return out / "mav0" / "imu0" / "data.csv"


def test_calibrate_file_is_the_command_library(tmp_path, capsys):
    csv = _scene(tmp_path, "adis16448")
    run = calibrate_file(csv, "accel", CalibrationOptions(), out_dir=tmp_path / "cal")
    cal = run.calibration
    assert run.sensor == "accelerometer" and run.reference == "g = 9.81 m/s^2 (report.json)"
    assert run.written == tmp_path / "cal" / "calibration.yaml" and run.written.is_file()
    K, b = run.truth
    inside = np.abs(cal.parameters - np.concatenate([K.ravel(), b])) <= 2 * cal.std
    assert inside.sum() >= 10
    assert cal.drift_dominated and any("bias drift over the recording dominates" in n for n in run.notes)
    text = run.summary()
    assert "bias drift: random walk" in text and "(estimated)" in text and f"wrote {run.written}" in text
    with pytest.raises(OutputExistsError, match="already holds a accelerometer"):
        calibrate_file(csv, "accelerometer", out_dir=tmp_path / "cal")
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputExistsError, match="not a folder"):
        calibrate_file(csv, "accel", out_dir=tmp_path / "file")
    with pytest.raises(ConfigError, match="sensor"):
        calibrate_file(csv, "magnetometer")
    # the command prints the same summary, and the note on stderr
    capsys.readouterr()
    assert main(["calibrate", "accel", str(csv), "--random-walk", "3e-3"]) == 0
    cap = capsys.readouterr()
    assert "bias drift: random walk 0.003 m/s^3/sqrt(Hz) (given)" in cap.out
    assert "note: the bias drift over the recording dominates" in cap.err
    # a white-noise sensor: no drift note
    csv2 = _scene(tmp_path, "white")
    assert main(["calibrate", "accel", str(csv2)]) == 0
    assert "dominates" not in capsys.readouterr().err
