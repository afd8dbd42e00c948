"""The synthesis library (splineimu.api): options, jobs, results, and the command line on top."""

from __future__ import annotations

import dataclasses
import json
import shlex

import numpy as np
import pytest

import splineimu
from splineimu.api import (
    ImuOptions,
    OutputOptions,
    PosesInput,
    SceneInput,
    SplineOptions,
    SynthesisJob,
    load_scene_file,
    run_job,
    synthesize_to_memory,
)
from splineimu.cli import main
from splineimu.errors import ConfigError, OutputExistsError
from splineimu.io.imu_csv import read_imu_csv
from splineimu.io.tum import write_tum
from splineimu.scenes import make_scene

ORIGIN_NS = 1_700_000_000_000_000_000


def files_of(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def poses(tmp_path_factory):
    """6 s of the ellipse at 100 Hz as a TUM file, with a 1.5 s hole from 3 s."""
    path = tmp_path_factory.mktemp("poses") / "ell.tum"
    t = np.concatenate([np.arange(0, 300), np.arange(450, 601)]) * 10_000_000
    k = make_scene("ellipse", duration_s=6.0).kinematics(t / 1e9)
    write_tum(path, ORIGIN_NS + t, k.position_world, k.quat_xyzw)
    return path


def test_options_are_validated_with_their_names():
    with pytest.raises(ConfigError, match="`rate_hz` must be positive"):
        ImuOptions(rate_hz=0)
    with pytest.raises(ConfigError, match="`sampling` must be one of point, mean, got 'men'; did you mean 'mean'"):
        ImuOptions(sampling="men")
    with pytest.raises(ConfigError, match="`kind` must be one of split, se3"):
        SplineOptions(kind="bspline")
    with pytest.raises(ConfigError, match="`path` is required"):
        PosesInput()
    with pytest.raises(ConfigError, match="no IMU preset named `adis1644`"):
        ImuOptions(model="adis1644")
    assert SplineOptions(order="5", knot_spacing_s="AUTO") == SplineOptions(order=5)
    assert PosesInput("gt.csv").format == "euroc" and PosesInput("gt.txt").format == "tum"
    assert SceneInput("circle", params={"center_m": "1, 2,3"}).params == {"center_m": [1.0, 2.0, 3.0]}
    assert ImuOptions(gravity=[0, 0, -9.8]).gravity == (0.0, 0.0, -9.8)


def test_inline_mappings_as_text_equal_the_mappings():
    a = ImuOptions(model="{gyroscope_noise_density: 0.01}", extrinsic="{translation: [0, 0, 1]}")
    b = ImuOptions(model={"gyroscope_noise_density": 0.01}, extrinsic={"translation": [0, 0, 1]})
    assert a == b and a.imu_config == b.imu_config
    assert a.body_T_sensor.body_t_sensor.tolist() == [0.0, 0.0, 1.0]


def test_job_renders_only_what_differs_from_the_defaults():
    job = SynthesisJob(PosesInput("p.tum", spline=SplineOptions(order=6, keep_outliers=True), gaps="split"),
                       ImuOptions(rate_hz=400.5, gravity=(0, 0, -9.80665), sampling="mean", increments=True),
                       OutputOptions("o", bag="ros2"))
    assert job.to_argv() == ["from-tum", "p.tum", "--order", "6", "--keep-outliers", "--gaps", "split",
                             "--rate", "400.5", "--gravity", "0", "0", "-9.80665", "--sampling", "mean",
                             "--increments", "-o", "o", "--bag", "ros2"]
    with pytest.raises(ConfigError, match="for scenes"):
        SynthesisJob(PosesInput("p.tum"), output=OutputOptions("o", tum="x.tum"))


def test_run_job_returns_the_report_and_writes_the_folder(poses, tmp_path):
    job = SynthesisJob(PosesInput(str(poses), gaps="bridge", spline=SplineOptions(knot_spacing_s=0.1, order=5)),
                       ImuOptions(rate_hz=100, model="adis16448", seed=3), OutputOptions(str(tmp_path / "o")))
    lines = []
    res = run_job(job, echo=lambda text, note: lines.append(text))
    assert res.out_dir == tmp_path / "o" and res.lines == lines
    assert res.report == json.loads((tmp_path / "o" / "report.json").read_text())
    assert res.report["spline"]["order"] == 5 and res.fit_report.knot_spacing_s == pytest.approx(0.1, rel=0.05)
    assert "time_s" not in res.report["spline"] and len(res.report["gaps"]["bridged"]) == 1
    assert res.report["imu"]["samples"] == 601 and res.report["imu"]["seed"] == 3
    assert any(s.startswith("gaps ") for s in lines) and lines[-1].startswith("written")
    with pytest.raises(OutputExistsError):
        run_job(job)
    # in memory: the same arrays, nothing written
    mem = synthesize_to_memory(dataclasses.replace(job, output=OutputOptions()))
    assert mem.out_dir is None and mem.report["spline"] == res.report["spline"]
    t_ns, gyro, accel = read_imu_csv(tmp_path / "o" / "imu0" / "data.csv")
    np.testing.assert_array_equal(t_ns, mem.synthesis.t_ns)
    np.testing.assert_array_equal(gyro, mem.synthesis.gyro_rad_s)  # the text holds every double exactly
    np.testing.assert_array_equal(accel, mem.synthesis.accel_m_s2)


def test_gaps_split_into_pieces(poses, tmp_path):
    job = SynthesisJob(PosesInput(str(poses), gaps="split"), ImuOptions(rate_hz=50), OutputOptions(str(tmp_path / "o")))
    mem = synthesize_to_memory(job)
    assert [p.synthesis.t_ns[0] - ORIGIN_NS for p in mem.pieces] == [0, 4_500_000_000]
    assert [p.synthesis.t_ns.size for p in mem.pieces] == [150, 76]
    res = run_job(job)
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["part_000", "part_001"]
    assert [p.out_dir.name for p in res.pieces] == ["part_000", "part_001"]
    assert res.pieces[1].report["source"]["first_ns"] == ORIGIN_NS + 4_500_000_000
    np.testing.assert_array_equal(read_imu_csv(tmp_path / "o" / "part_001" / "imu0" / "data.csv")[0],
                                  mem.pieces[1].synthesis.t_ns)


def test_scene_file_command_line_and_library_give_the_same_bytes(poses, tmp_path, capsys):
    """`run FILE`, the command `run FILE --print` shows, and run_job(load_scene_file(FILE)): one output."""
    (tmp_path / "ell.tum").write_bytes(poses.read_bytes())
    f = tmp_path / "job.yaml"
    f.write_text("motion:\n  poses: ell.tum\n  gaps: bridge\n  spline: {order: 4, knot_spacing_s: 0.05}\n"
                 "imu:\n  rate_hz: 200\n  model: {gyroscope_noise_density: 0.01, accelerometer_random_walk: 1.0e-4}\n"
                 "  extrinsic: {translation: [0.1, 0.0, 0.0], quat_xyzw: [0, 0, 0.6, 0.8]}\n  sampling: mean\n"
                 "seed: 11\noutput: {dir: a}\n")
    assert main(["run", str(f)]) == 0
    capsys.readouterr()
    assert main(["run", str(f), "--print"]) == 0
    argv = shlex.split(capsys.readouterr().out)[1:]
    assert argv[argv.index("-o") + 1] == str(tmp_path / "a")
    argv[argv.index("-o") + 1] = str(tmp_path / "b")
    assert main(argv) == 0
    job = load_scene_file(f)
    run_job(dataclasses.replace(job, output=OutputOptions(str(tmp_path / "c"))))
    a = files_of(tmp_path / "a")
    assert sorted(a) == ["groundtruth.tum", "imu.yaml", "imu0/data.csv", "report.json",
                         "state_groundtruth_estimate0/data.csv"]
    assert files_of(tmp_path / "b") == a and files_of(tmp_path / "c") == a


def test_scene_job_writes_poses_only_when_asked(tmp_path):
    job = SynthesisJob(SceneInput("circle", duration_s=2, t0_ns=5, params={"radius_m": 2}),
                       ImuOptions(rate_hz=10), OutputOptions(tum=str(tmp_path / "c.tum")))
    res = run_job(job)
    assert res.out_dir is None and [p.name for p in tmp_path.iterdir()] == ["c.tum"]
    assert len((tmp_path / "c.tum").read_text().splitlines()) == 1 + 21
    with pytest.raises(ConfigError, match="nothing to write"):
        run_job(dataclasses.replace(job, output=OutputOptions()))


def test_noise_free_imu_yaml_gives_the_rate_synthesized(tmp_path):
    job = SynthesisJob(SceneInput("static", duration_s=1), ImuOptions(rate_hz=250), OutputOptions(str(tmp_path / "o")))
    run_job(job)
    from splineimu.imu.config import ImuConfig

    cfg = ImuConfig.from_yaml(tmp_path / "o" / "imu.yaml")
    assert cfg.update_rate == 250.0 and not cfg.gyroscope_noise_density.any()
    assert "# noise-free synthesis" in (tmp_path / "o" / "imu.yaml").read_text()


def test_package_exports_the_api_lazily():
    assert splineimu.SynthesisJob is SynthesisJob and splineimu.run_job is run_job
    import subprocess
    import sys

    code = "import sys, splineimu, splineimu.api; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
