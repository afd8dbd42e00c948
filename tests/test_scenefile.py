"""Scene files: loaded into the same job the flags build, errors at their file and line."""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest

from splineimu.api import ImuOptions, OutputOptions, PosesInput, SceneInput, SplineOptions, load_scene_file
from splineimu.cli import build_parser, main
from splineimu.commands._common import options_from_args
from splineimu.errors import ConfigError
from splineimu.io.imu_csv import read_imu_csv

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def job_from_argv(argv):
    args = build_parser().parse_args(argv)
    motion = {"from-tum": "tum", "from-euroc": "euroc", "scene": "scene"}[args.command]
    return options_from_args(args, motion)


@pytest.fixture
def examples(tmp_path):
    d = tmp_path / "examples"
    shutil.copytree(EXAMPLES, d)
    return d


@pytest.mark.parametrize("name", ["ellipse_scene.yaml", "mocap_scene.yaml"])
def test_examples_round_trip_through_the_command_line(examples, name):
    job = load_scene_file(examples / name)
    argv = job.to_argv()
    assert job_from_argv(argv) == job
    assert job_from_argv(shlex.split(shlex.join(argv))) == job  # what `run --print` shows, as a shell reads it


@pytest.mark.parametrize("text", [
    "motion:\n  scene: circle\n  t0_ns: 1700000000000000001\n  params: {center_m: [1, 2.5, 3], speed_m_s: -1}\n"
    "imu: {rate_hz: 333.3, gravity: [0, 0, -9.80665], sampling: mean, increments: true}\n"
    "output: {dir: o, tum: c.tum, bag: ros1, plot: true, force: true}\n",
    "motion:\n  poses: gt.csv\n  max_gap_s: 1.5\n  repeated_stamps: first\n  gaps: split\n"
    "  spline: {kind: se3, order: 5, knot_spacing_s: 0.025, smoothness: 1e-6, keep_outliers: true,\n"
    "           rotation_source: estimate}\n"
    "imu: {timestamps: imu0.csv, model: {accelerometer_random_walk: 2.0e-3}, extrinsic: {T_BS: "
    "[[0, -1, 0, 0.1], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}\nseed: 0\noutput: {dir: o}\n",
    "motion:\n  poses: mocap.tum\n  spline: {order: 5, position_order: auto, position_knot_spacing_s: 0.04}\n"
    "output: {dir: o}\n",
])
def test_every_key_round_trips_through_the_command_line(tmp_path, text):
    f = tmp_path / "job.yaml"
    f.write_text(text)
    job = load_scene_file(f)
    argv = job.to_argv()
    every = ({"--t0-ns", "--param", "--rate", "--gravity", "--sampling", "--increments", "--tum", "--bag", "--plot",
              "--force"} if "circle" in text else
             {"--order", "--position-order", "--position-knot-spacing"} if "mocap" in text else
             {"--max-gap", "--repeated-stamps", "--gaps", "--spline", "--order", "--knot-spacing", "--smoothness",
              "--keep-outliers", "--rotation-source", "--timestamps", "--imu", "--extrinsic", "--seed"})
    assert every <= set(argv), every - set(argv)
    assert job_from_argv(shlex.split(shlex.join(argv))) == job


def test_mocap_example_builds_the_expected_job(examples):
    job = load_scene_file(examples / "mocap_scene.yaml")
    assert job.motion == PosesInput(str(examples / "ellipse_mocap.tum"), "tum", spline=SplineOptions())
    assert job.imu == ImuOptions(rate_hz=400, model="adis16448", seed=7,
                                 extrinsic={"translation": [0.1, 0.0, 0.0], "quat_xyzw": [0, 0, 0, 1]})
    assert job.imu.body_T_sensor.body_t_sensor.tolist() == [0.1, 0.0, 0.0]
    assert job.output == OutputOptions(str(examples / "../out_mocap_scene"))


def test_inline_model_is_read_in_memory(examples):
    job = load_scene_file(examples / "ellipse_scene.yaml")
    assert job.motion == SceneInput("ellipse", duration_s=60)
    cfg = job.imu.imu_config
    assert cfg.gyroscope_random_walk.tolist() == [5e-5] * 3 and cfg.update_rate is None
    assert job.output.plot and job.seed == 42


def test_scene_file_runs_and_is_reproducible(tmp_path, capsys):
    f = tmp_path / "s.yaml"
    f.write_text("motion: {scene: ellipse, duration_s: 5}\n"
                 "imu:\n  rate_hz: 200\n  model: {gyroscope_noise_density: 0.015, accelerometer_noise_density: 0.019}\n"
                 "seed: 42\noutput: {dir: out}\n")
    assert main(["run", str(f)]) == 0
    first = {p: (tmp_path / "out" / p).read_bytes() for p in ("mav0/imu0/data.csv", "report.json", "imu.yaml")}
    assert main(["run", str(f), "--force"]) == 0
    for p, data in first.items():  # report.json too: no timings in it
        assert (tmp_path / "out" / p).read_bytes() == data, p
    _, gyro, _ = read_imu_csv(tmp_path / "out" / "mav0" / "imu0" / "data.csv")
    assert 0.8 < np.std(np.diff(gyro[:, 0])) / (0.015 * np.sqrt(200) * np.sqrt(2)) < 1.2
    assert "0.015" in (tmp_path / "out" / "imu.yaml").read_text()
    capsys.readouterr()
    assert main(["run", str(f), "--print", "--force"]) == 0
    assert capsys.readouterr().out.strip().endswith(f"-o {tmp_path / 'out'} --force")


BAD = [
    # text, line, message
    ("motion: {scene: ellipse}\nimu:\n  rate: 100\noutput: {dir: o}\n", 3,
     "unknown key `imu.rate`; did you mean `rate_hz`"),
    ("motion: {scene: ellipse}\nimu:\n  rate_hz: -100\noutput: {dir: o}\n", 3, "`imu.rate_hz` must be positive"),
    ("motion: {scene: ellipse, poses: a.tum}\noutput: {dir: o}\n", 1, "exactly one of"),
    ("motion: {scene: ellipse}\n", 1, "`output.dir` is required"),
    ("motion: {scene: ellipse}\noutput:\n  plot: true\n  dir:\n", 4, "`output.dir` is empty"),
    ("motion: [1, 2\n", 2, "invalid YAML"),
    ("motion: {scene: elipse}\noutput: {dir: o}\n", 1, "did you mean 'ellipse'"),
    ("motion:\n  scene: circle\n  params:\n    radius: 3\noutput: {dir: o}\n", 4, "did you mean 'radius_m'"),
    ("motion:\n  poses: a.tum\n  spline:\n    order: 12\noutput: {dir: o}\n", 4,
     "`motion.spline.order` must be between 2 and 8"),
    ("motion:\n  poses: a.tum\n  gaps: brige\noutput: {dir: o}\n", 3, "did you mean 'bridge'"),
    ("motion: {scene: static}\nimu:\n  model:\n    gyroscope_noise_density: 0.1\n    gyro_random_walk: 1\n"
     "output: {dir: o}\n", 5, "did you mean `gyroscope_random_walk`"),
    ("motion: {scene: static}\nimu:\n  extrinsic: {translation: [1, 2]}\noutput: {dir: o}\n", 3, "extrinsic"),
    ("motion: {scene: static}\nimu: {gravity: [0, 0]}\noutput: {dir: o}\n", 2, "`imu.gravity` to have shape (3,)"),
    ("motion: {scene: static}\nseed: -3\noutput: {dir: o}\n", 2, "`seed` must be between 0"),
    ("motion: {scene: static}\noutput: {dir: o, plot: yes please}\n", 2, "`output.plot` must be true or false"),
]


@pytest.mark.parametrize("text, line, msg", BAD)
def test_bad_scene_files_name_file_line_and_key(tmp_path, capsys, text, line, msg):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_scene_file(f)
    assert info.value.path == str(f) and info.value.line == line, str(info.value)
    assert msg in str(info.value)
    assert main(["run", str(f)]) == 1
    err = capsys.readouterr().err
    assert f"bad.yaml:{line}:" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists() and not (tmp_path / "None").exists()


@pytest.mark.parametrize("argv, flag", [
    (["scene", "static", "--rate", "-5"], "`--rate` must be positive"),
    (["scene", "static", "--param", "position_m=1,x,3"], "--param"),
    (["scene", "static", "--imu", "{gyroscope_noise_densty: 1}"], "did you mean `gyroscope_noise_density`"),
    (["scene", "static", "--seed", "-1"], "`--seed` must be between 0"),
    (["scene", "static", "--duration", "0"], "`--duration` must be positive"),
    (["from-tum", "a.tum", "--order", "nine"], "`--order` must be an integer"),
    (["from-tum", "a.tum", "--knot-spacing", "-1"], "`--knot-spacing` must be positive"),
    (["from-tum", "a.tum", "--position-knot-spacing", "0"], "`--position-knot-spacing` must be positive"),
    (["from-tum", "a.tum", "--position-order", "2"], "`--position-order` 2 (piecewise linear) has no acceleration"),
    (["from-tum", "a.tum", "--spline", "se3", "--position-order", "5"], "`--position-order` needs the split spline"),
])
def test_flag_errors_name_the_flag(tmp_path, capsys, argv, flag):
    assert main(argv + ["-o", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err
    assert flag in err, err
    assert not (tmp_path / "o").exists()
