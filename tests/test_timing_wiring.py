"""Sensor timing and vibration through the product: options, scene files, synthesis, files, report.

Analytic scenes with exact derivatives, noise-free sensor model unless said otherwise.
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import numpy as np
import pytest

from splineimu import scenes
from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, load_scene_file, run_job
from splineimu.api.output import write_output
from splineimu.errors import ConfigError
from splineimu.imu.timing import TimingModel
from splineimu.imu.vibration import VibrationModel
from splineimu.pipeline import VIBRATION_SEED_KEY, child_seed, synthesize_stream
from splineimu.timegrid import uniform_stamps_ns

RATE = 200.0
ACCEPT = {"time_offset_s": 0.0123, "clock_drift_ppm": 50.0, "stamp_noise_s": 1e-4, "drop_probability": 0.01}
VIB37 = {"accel": [{"freq_hz": 37.0, "amplitude": [0.5, 0.0, 0.0]}]}


def read_rows(path):
    """(stamps int64, values (N, k)) of a csv written by splineimu (exact integer stamps)."""
    sep = " " if str(path).endswith(".tum") else ","
    vals = np.loadtxt(path, delimiter=sep, comments="#", ndmin=2)
    if str(path).endswith(".tum"):
        with open(path) as f:
            t = np.array([int(line.split()[0].replace(".", "")) for line in f if not line.startswith("#")])
        return t, vals[:, 1:]
    t = np.loadtxt(path, delimiter=sep, comments="#", usecols=0, dtype=np.int64, ndmin=1)
    return t, vals[:, 1:]


def run_scene(tmp_path, name="flips", seed=7, sub="o", **imu):
    job = SynthesisJob(SceneInput(name, duration_s=60.0), ImuOptions(rate_hz=RATE, seed=seed, **imu),
                       OutputOptions(str(tmp_path / sub)))
    res = run_job(job)
    out = res.out_dir
    t, imu_vals = read_rows(out / "mav0" / "imu0" / "data.csv")
    t_gt, gt = read_rows(out / "mav0" / "state_groundtruth_estimate0" / "data.csv")
    t_tum, _ = read_rows(out / "groundtruth.tum")
    return res, out, t, imu_vals, t_gt, gt, t_tum


def rms(x):
    return float(np.sqrt(np.mean(np.sum(np.square(x), axis=1) / x.shape[1])))


@pytest.mark.parametrize("scene", ["flips", "ellipse"])
def test_issue_acceptance_timing(tmp_path, scene):
    res, out, stamps, vals, t_true, gt, t_tum = run_scene(tmp_path, scene, timing=dict(ACCEPT))
    rep = json.loads((out / "report.json").read_text())["timing"]
    # one ground-truth row per written sample, same order, at its true time (both files)
    assert stamps.size == t_true.size == t_tum.size == rep["samples_written"]
    assert np.array_equal(t_true, t_tum) and np.all(np.diff(t_true) > 0)
    # straight line of written stamps against true times
    x, y = t_true / 1e9, stamps / 1e9
    slope, offset = np.polyfit(x, y, 1)
    assert abs(slope - (1 + 50e-6)) < 1e-6
    assert abs(offset - 0.0123) < 10e-6
    assert abs(np.std(y - (slope * x + offset)) / 1e-4 - 1) < 0.05
    n, p = rep["samples_on_clock"], 0.01
    assert n == 12001  # the fast clock's grid reaches 60.003 s of its own time at true 60 s
    assert abs(rep["dropped"] - n * p) < 4 * np.sqrt(n * p * (1 - p))
    assert rep["dropped"] == n - stamps.size == sum(r["count"] for r in rep["dropped_runs"])
    # every written sample is the motion at its true time ...
    src = res.source
    g_true, a_true = src.imu(src.t_s_from_ns(t_true))
    err_g, err_a = rms(vals[:, :3] - g_true), rms(vals[:, 3:] - a_true)
    assert err_g < 1e-12 and err_a < 1e-12  # the issue's bounds: 1e-3 rad/s, 1e-2 m/s^2 (text rounding here)
    # ... and not the motion at its written stamp
    inside = stamps <= src.origin_ns + int(src.t_max_s * 1e9)
    g_st, a_st = src.imu(src.t_s_from_ns(stamps[inside]))
    if scene == "flips":
        assert rms(vals[inside, :3] - g_st) > 0.05
    else:  # the lecture's ellipse turns slowly: 12.3 ms move its gyro by ~2e-3 rad/s only, its accel by 0.27 m/s^2
        assert rms(vals[inside, 3:] - a_st) > 0.05


def test_vibration_appears_in_the_data_and_in_vibration_csv(tmp_path):
    res, out, stamps, vals, t_true, _, _ = run_scene(tmp_path, "ellipse", timing=dict(ACCEPT), vibration=VIB37)
    src = res.source
    t_s = src.t_s_from_ns(t_true)
    g_true, a_true = src.imu(t_s)
    resid = vals[:, 3:] - a_true
    # least squares of (data - motion) on a 37 Hz cosine and sine at the true times
    A = np.column_stack([np.cos(2 * np.pi * 37.0 * t_s), np.sin(2 * np.pi * 37.0 * t_s)])
    coef = np.linalg.lstsq(A, resid, rcond=None)[0]
    amp = np.hypot(coef[0], coef[1])
    assert amp[0] == pytest.approx(0.5, rel=1e-2) and amp[1] < 1e-9 and amp[2] < 1e-9
    assert np.abs(vals[:, :3] - g_true).max() < 1e-12  # accel only
    t_vib, vib = read_rows(out / "mav0" / "imu0" / "vibration.csv")
    assert np.array_equal(t_vib, stamps)
    assert rms(vals[:, 3:] - vib[:, 3:] - a_true) < 1e-12  # as accurate as without vibration
    assert not vib[:, :3].any()
    rep = json.loads((out / "report.json").read_text())
    assert rep["vibration"]["model"] == {"accel": [{"freq_hz": 37.0, "amplitude": [0.5, 0.0, 0.0]}]}


def test_timing_and_vibration_leave_the_sensor_noise_streams_alone(tmp_path):
    model = {"gyroscope_noise_density": 0.01, "accelerometer_noise_density": 0.02,
             "gyroscope_random_walk": 1e-4, "accelerometer_random_walk": 1e-3}
    _, _, t0, v0, _, gt0, _ = run_scene(tmp_path, "ellipse", sub="plain", model=model)
    _, out, t1, v1, _, gt1, _ = run_scene(tmp_path, "ellipse", sub="vib", model=model, vibration=VIB37)
    _, vib = read_rows(out / "mav0" / "imu0" / "vibration.csv")
    assert np.array_equal(t0, t1) and np.array_equal(gt0[:, -6:], gt1[:, -6:])  # same bias walk
    assert np.abs(v1 - vib - v0).max() < 1e-12  # same white noise: the data differ by the vibration only
    # with timing on the IMU clock the sensor draws the same numbers per sample (same white noise sequence)
    _, _, t2, v2, t2_true, gt2, _ = run_scene(tmp_path, "ellipse", sub="clock", model=model,
                                              timing={"time_offset_s": 0.5})
    assert np.array_equal(t2, t0 + 500_000_000) and np.array_equal(t2_true, t0)
    assert np.array_equal(v2, v0) and np.array_equal(gt2, gt0)


def test_mean_sampling_and_increments_use_the_interval_from_the_previous_clock_sample(tmp_path):
    timing = {"clock_drift_ppm": -300.0, "drop_probability": 0.05}
    res, out, stamps, vals, t_true, _, _ = run_scene(tmp_path, "flips", seed=3, timing=timing, vibration=VIB37,
                                                     sampling="mean", increments=True)
    src = res.source
    rep = json.loads((out / "report.json").read_text())["timing"]
    first = rep["dropped_runs"][0]["first_index"] + rep["dropped_runs"][0]["count"]  # a sample after a loss
    k = np.arange(first - 3, first + 3)
    clock = np.round(k * 1e9 / RATE)
    true_k = np.rint(clock / (1 - 300e-6)).astype(np.int64)
    start_k = np.rint(np.round((k - 1) * 1e9 / RATE) / (1 - 300e-6)).astype(np.int64)
    rows = np.searchsorted(t_true, true_k)
    kept = t_true[np.minimum(rows, t_true.size - 1)] == true_k
    assert kept.sum() >= 4 and not kept.all()
    x, w = np.polynomial.legendre.leggauss(24)
    # the run's vibration: phases from the seed's own child stream
    real = VibrationModel.from_dict(VIB37).realize(child_seed(3, VIBRATION_SEED_KEY))
    _, vib = read_rows(out / "mav0" / "imu0" / "vibration.csv")
    for r, a, b in zip(rows[kept], start_k[kept], true_k[kept]):
        ta, tb = src.t_s_from_ns([a, b])
        nodes = 0.5 * (ta + tb) + 0.5 * (tb - ta) * x
        g, f = src.imu(nodes)
        assert np.abs(vals[r, :3] - 0.5 * w @ g).max() < 1e-9
        assert np.abs(vals[r, 3:] - vib[r, 3:] - 0.5 * w @ f).max() < 1e-9
        assert np.abs(vib[r, 3:] - 0.5 * w @ real.evaluate(nodes)[1]).max() < 1e-12
    # increments: over [true time of the previous clock sample, true time], at the written stamps
    t_inc, inc = read_rows(out / "mav0" / "imu0" / "increments.csv")
    assert np.array_equal(t_inc, stamps)
    from splineimu.lie import quat_xyzw_to_matrix, so3_log

    for r, a, b in zip(rows[kept], start_k[kept], true_k[kept]):
        R = quat_xyzw_to_matrix(src.pose(src.t_s_from_ns([a, b]))[1])
        assert np.abs(inc[r, :3] - so3_log(R[0].T @ R[1])).max() < 1e-9


def test_pieces_give_the_same_bytes_as_one_piece(tmp_path):
    src = scenes.make_scene("ellipse", duration_s=3.0)
    st = TimingModel(**ACCEPT, drop_burst_s=0.02).sample_times(0, 3_000_000_000, RATE, rng=5)
    vib = VibrationModel.from_dict({"accel": [{"band_hz": [20.0, 80.0], "psd": [1e-4, 1e-4, 0.0]}], **{
        "gyro": [{"freq_hz": 37.0, "amplitude": [0.0, 0.0, 0.01]}]}})
    kw = dict(imu_config="adis16448", seed=11, sampling="mean", with_increments=True, vibration=vib)
    write_output(synthesize_stream(src, st, chunk_samples=97, **kw), tmp_path / "pieces")
    write_output(synthesize_stream(src, st, **kw).collect(), tmp_path / "whole")
    for f in ("mav0/imu0/data.csv", "mav0/imu0/vibration.csv", "mav0/imu0/increments.csv",
              "mav0/state_groundtruth_estimate0/data.csv",
              "groundtruth.tum", "report.json"):
        a, b = (tmp_path / d / f for d in ("pieces", "whole"))
        assert a.read_bytes() == b.read_bytes() if f != "report.json" else (
            json.loads(a.read_text())["timing"] == json.loads(b.read_text())["timing"]), f


def test_identity_timing_is_the_plain_path_bit_for_bit(tmp_path):
    """A timing model with no effect, passed as SampleTimes, writes the same bytes as plain stamps."""
    src = scenes.make_scene("flips", duration_s=2.0)
    plain = uniform_stamps_ns(0, 2_000_000_000, RATE)
    st = TimingModel().sample_times(0, 2_000_000_000, RATE, rng=1)
    kw = dict(imu_config="adis16448", seed=2, sampling="mean", with_increments=True)
    write_output(synthesize_stream(src, plain, **kw), tmp_path / "plain")
    write_output(synthesize_stream(src, st, **kw), tmp_path / "clock")
    for f in ("mav0/imu0/data.csv", "mav0/imu0/increments.csv", "mav0/state_groundtruth_estimate0/data.csv",
              "groundtruth.tum"):
        assert (tmp_path / "plain" / f).read_bytes() == (tmp_path / "clock" / f).read_bytes(), f
    rep = json.loads((tmp_path / "plain" / "report.json").read_text())
    assert "timing" not in rep and "vibration" not in rep
    assert not (tmp_path / "plain" / "mav0" / "imu0" / "vibration.csv").exists()
    # all-zero blocks are no blocks
    assert ImuOptions(timing={"drop_probability": 0}, vibration={"accel": []}) == ImuOptions()


SCENE = """motion: {scene: ellipse, duration_s: 2}
imu:
  rate_hz: 200
  timing:
    time_offset_s: -0.002
    clock_drift_ppm: 20
    stamp_noise_s: 5.0e-5
    drop_probability: 0.1
    drop_burst_s: 0.02
  vibration:
    accel:
      - {freq_hz: 37, amplitude: [0.5, 0, 0]}
    gyro:
      - {band_hz: [10, 40], psd: [1.0e-6, 0, 1.0e-6]}
seed: 4
output: {dir: o}
"""


def test_scene_file_round_trips_through_the_command_line(tmp_path):
    from splineimu.cli import build_parser
    from splineimu.commands._common import options_from_args

    f = tmp_path / "s.yaml"
    f.write_text(SCENE)
    job = load_scene_file(f)
    assert job.imu.timing == TimingModel(-0.002, 20.0, 5e-5, 0.1, 0.02)
    argv = job.to_argv()
    assert {"--time-offset", "--clock-drift-ppm", "--stamp-noise", "--drop-probability", "--drop-burst",
            "--vibration"} <= set(argv)
    args = build_parser().parse_args(shlex.split(shlex.join(argv)))
    assert options_from_args(args, "scene") == job
    # the same block from a vibration file (relative to the scene file)
    (tmp_path / "vib.yaml").write_text("accel:\n  - {freq_hz: 37, amplitude: [0.5, 0, 0]}\n"
                                       "gyro:\n  - {band_hz: [10, 40], psd: [1.0e-6, 0, 1.0e-6]}\n")
    g = tmp_path / "t.yaml"
    g.write_text(SCENE.split("  vibration:")[0] + "  vibration: vib.yaml\nseed: 4\noutput: {dir: o}\n")
    assert load_scene_file(g) == job


@pytest.mark.parametrize("block, line, match", [
    ("  timing:\n    drop_probability: 1.5\n", 4, "`drop_probability` must be below 1"),
    ("  timing:\n    clock_drift: 5\n", 4, "unknown key `timing.clock_drift`; did you mean `clock_drift_ppm`"),
    ("  timing: 0.01\n", 3, "`timing` must be a mapping"),
    ("  vibration:\n    accel:\n      - {freq_hz: 37, amplitude: [0.5, 0, 0]}\n"
     "      - {freq_hz: -1, amplitude: [1, 0, 0]}\n", 6, "must be positive"),
    ("  vibration:\n    accel:\n      - {band_hz: [50, 20], psd: [1, 1, 1]}\n", 5, "high > low"),
    ("  vibration:\n    acel: []\n", 4, "unknown key `vibration.acel`"),
])
def test_scene_file_errors_name_file_and_line(tmp_path, block, line, match):
    f = tmp_path / "scene.yaml"
    f.write_text("motion: {scene: static}\nimu:\n" + block + "output: {dir: o}\n")
    with pytest.raises(ConfigError, match=rf"scene\.yaml:{line}: .*{match}"):
        load_scene_file(f)


def test_flag_and_python_errors_name_the_value():
    from splineimu.cli import build_parser
    from splineimu.commands._common import options_from_args

    args = build_parser().parse_args(["scene", "static", "--drop-probability", "1", "-o", "o"])
    with pytest.raises(ConfigError, match="`--drop-probability` must be below 1"):
        options_from_args(args, "scene")
    bad = "{accel: [{freq_hz: 0, amplitude: [1, 0, 0]}]}"
    args = build_parser().parse_args(["scene", "static", "--vibration", bad])
    with pytest.raises(ConfigError, match="`--vibration`: .*freq_hz. must be positive"):
        options_from_args(args, "scene")
    with pytest.raises(ConfigError, match="`timing.stamp_noise_s` must be zero or positive"):
        ImuOptions(timing={"stamp_noise_s": -1})
    with pytest.raises(ConfigError, match="not to given `timestamps`"):
        ImuOptions(timestamps="imu.csv", timing={"time_offset_s": 1.0})


def test_example_scene_file_runs(tmp_path):
    import shutil

    ex = Path(__file__).resolve().parent.parent / "examples"
    shutil.copytree(ex, tmp_path / "examples")
    job = load_scene_file(tmp_path / "examples" / "timing_scene.yaml")
    assert job.imu.timing is not None and job.imu.vibration is not None
    assert job.output.dir.startswith(str(tmp_path))


def test_allan_deviation_shows_the_sinusoid(tmp_path):
    """Static IMU with white accel noise and a 1 Hz sinusoid: the ADEV has the sinusoid's bump near
    tau = 0.371 / f (peak 0.7246 A) well above the white-noise line, and falls back at tau = 1 / f."""
    from splineimu.allan import allan_deviation

    f_hz, amp, white = 1.0, 0.05, 0.002
    model = {"accelerometer_noise_density": white}
    job = SynthesisJob(SceneInput("static", duration_s=600.0),
                       ImuOptions(rate_hz=RATE, seed=1, model=model,
                                  vibration={"accel": [{"freq_hz": f_hz, "amplitude": [amp, 0.0, 0.0]}]}))
    syn = run_job(job, write=False).synthesis
    taus = np.array([0.371 / f_hz, 1.0 / f_hz, 2.0 / f_hz])
    res = allan_deviation(syn.accel_m_s2, RATE, taus=taus)
    line = white / np.sqrt(res.taus_s)  # the white-noise line N / sqrt(tau)
    x, y = res.adev[:, 0], res.adev[:, 1]
    assert x[0] == pytest.approx(0.7246 * amp, rel=0.05)
    assert x[0] > 8 * line[0]
    assert np.all(y < 1.2 * line) and np.all(y > 0.8 * line)  # the other axis: white noise only
    assert x[1] < 1.5 * line[1] and x[2] < 1.5 * line[2]  # whole periods average the sinusoid out
