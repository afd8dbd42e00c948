"""calibrate and an existing calibration.yaml with keys a calibration file does not have.

Writing the file again dropped unknown top-level keys (a `notes:` added by hand) in silence,
and kept unknown `imu0` keys of the other sensor, so that the file written no longer loaded as
a sensor model. Such a file is now refused before any work, naming the file, line and keys.
"""

from __future__ import annotations

import json

import pytest

from splineimu.api.calibration import calibrate_file
from splineimu.api.options import ImuOptions
from splineimu.cli import main
from splineimu.errors import ConfigError
from splineimu.imu.config import load_imu_config

IMU = {"gyroscope_noise_density": 1e-4, "accelerometer_noise_density": 1e-3,
       "accelerometer_scale": [0.001, 0.0, 0.0], "gyroscope_scale": [0.0, 0.002, 0.0]}


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("cal")
    for scene, seed in (("six-position", 4), ("rate-table", 5)):
        assert main(["scene", scene, "-o", str(d / scene), "--imu", json.dumps(IMU), "--seed", str(seed)]) == 0
    cal = d / "cal"
    calibrate_file(d / "six-position" / "mav0" / "imu0" / "data.csv", "accel", out_dir=cal)
    return d, (cal / "calibration.yaml").read_text()


def _gyro(d, out, **kw):
    return calibrate_file(d / "rate-table" / "mav0" / "imu0" / "data.csv", "gyro", out_dir=out, **kw)


def test_an_unknown_top_level_key_is_refused_not_dropped(data, tmp_path):
    d, text = data
    target = tmp_path / "calibration.yaml"
    target.write_text(text + "notes: measured on the bench\n")
    line = len(text.splitlines()) + 1
    for force in (False, True):
        with pytest.raises(ConfigError) as e:
            _gyro(d, tmp_path, force=force)
        assert str(e.value) == (f"{target}:{line}: unknown key `notes`: not part of a calibration file (writing it "
                                "again would drop or keep it unchecked); remove it, or write to another folder")
    assert target.read_text() == text + "notes: measured on the bench\n"  # untouched
    target.write_text(text)
    run = _gyro(d, tmp_path)  # the file as written is taken
    assert run.written == target
    cfg = load_imu_config(str(target))
    assert abs(cfg.gyroscope_scale[1] - 0.002) < 5e-4 and abs(cfg.accelerometer_scale[0] - 0.001) < 5e-4


def test_unknown_section_keys_and_imu0_keys_that_do_not_load(data, tmp_path):
    d, text = data
    target = tmp_path / "calibration.yaml"
    target.write_text(text.replace("\nstd:\n", "\nstd:\n  gyro_bias: 1\n").replace(
        "\ncalibration:\n", "\ncalibration:\n  magnetometer: {}\n"))
    with pytest.raises(ConfigError) as e:
        _gyro(d, tmp_path)
    std_line = target.read_text().splitlines().index("  gyro_bias: 1") + 1
    assert str(e.value).startswith(f"{target}:{std_line}: unknown keys `std.gyro_bias`, `calibration.magnetometer`: "
                                   "not part of a calibration file")
    # an unknown imu0 key was kept and the file written no longer loaded (`--imu calibration.yaml` failed later)
    target.write_text(text.replace("\nimu0:\n", "\nimu0:\n  accelerometer_noise_densty: 1.0e-3\n"))
    with pytest.raises(ConfigError) as e:
        _gyro(d, tmp_path, force=True)
    assert str(e.value) == (f"{target}:6: `imu0`: unknown IMU key `accelerometer_noise_densty` (did you mean "
                            "`accelerometer_noise_density`?); see `splineimu.imu.config` for the list; the file must "
                            "load as a sensor model: repair it, or write to another folder")
    # known keys of a sensor model (the rate, a noise density, an ignored key) are fine
    target.write_text(text.replace("\nimu0:\n", "\nimu0:\n  update_rate: 200.0\n  rostopic: /imu0\n"))
    _gyro(d, tmp_path)
    assert load_imu_config(str(target)).update_rate == 200.0
    assert ImuOptions(model=str(target)).imu_config.update_rate == 200.0
