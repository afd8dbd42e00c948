"""Scene files (`splineimu run`): translation to the command line and end-to-end runs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from splineimu.cli import main
from splineimu.errors import ConfigError
from splineimu.io.imu_csv import read_imu_csv
from splineimu.scenefile import scene_to_argv

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_scene_file_runs_and_is_reproducible(tmp_path):
    text = (EXAMPLES / "ellipse_scene.yaml").read_text().replace("../out_ellipse_scene", "out").replace(
        "duration_s: 60", "duration_s: 5")
    f = tmp_path / "s.yaml"
    f.write_text(text)
    assert main(["run", str(f)]) == 0
    first = (tmp_path / "out" / "imu0" / "data.csv").read_bytes()
    assert main(["run", str(f), "--force"]) == 0
    assert (tmp_path / "out" / "imu0" / "data.csv").read_bytes() == first
    _, gyro, _ = read_imu_csv(tmp_path / "out" / "imu0" / "data.csv")
    assert 0.5 < np.std(np.diff(gyro[:, 0])) / (0.015 * np.sqrt(200) * np.sqrt(2)) < 1.5
    assert "0.015" in (tmp_path / "out" / "imu.yaml").read_text()


def test_pose_file_scene_with_extrinsic(tmp_path):
    text = (EXAMPLES / "mocap_scene.yaml").read_text().replace("../out_mocap_scene", str(tmp_path / "o"))
    f = EXAMPLES / "_test_mocap_scene.yaml"
    try:
        f.write_text(text)
        argv = scene_to_argv(f, tmp_path)
        assert argv[:2] == ["from-tum", str(EXAMPLES / "ellipse_mocap.tum")]
        assert "--extrinsic" in argv and argv[argv.index("--rate") + 1] == "400"
        assert main(["run", str(f)]) == 0
    finally:
        f.unlink()
    t_ns, _, _ = read_imu_csv(tmp_path / "o" / "imu0" / "data.csv")
    assert t_ns[1] - t_ns[0] == 2_500_000


@pytest.mark.parametrize("text, msg", [
    ("motion: {scene: ellipse}\nimu: {rate: 100}\noutput: {dir: o}\n", "did you mean `rate_hz`"),
    ("motion: {scene: ellipse, poses: a.tum}\noutput: {dir: o}\n", "exactly one of"),
    ("motion: {scene: ellipse}\n", "output.dir"),
    ("motion: [1, 2\n", "not valid YAML"),
])
def test_bad_scene_files(tmp_path, text, msg):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=msg.replace("`", ".")):
        scene_to_argv(f, tmp_path)
    assert main(["run", str(f)]) == 1
