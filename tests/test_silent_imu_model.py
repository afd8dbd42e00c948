"""An IMU model without parameters is not an ideal sensor in silence.

`model: {}` in a scene file (or `--imu '{}'`, a chain file `imu0: {}`, a mapping of ignored
keys or of the rate alone) was read as a sensor with no noise: the data came out noise-free
while the summary said "sensor model (see imu.yaml)". An empty IMU yaml was already refused
with the advice to name the preset `ideal`; these now are too.
"""

from __future__ import annotations

import pytest

from splineimu import cli
from splineimu.api import ImuOptions, load_scene_file
from splineimu.errors import ConfigError
from splineimu.imu.config import ImuConfig, load_imu_config

ADVICE = "for a noise-free sensor give the preset `ideal`"


def test_an_empty_model_in_a_scene_file_is_refused_at_its_line(tmp_path, capsys):
    f = tmp_path / "s.yaml"
    f.write_text("motion:\n  scene: ellipse\n  duration_s: 1\nimu:\n  rate_hz: 100\n  model: {}\noutput:\n  dir: o\n")
    with pytest.raises(ConfigError) as e:
        load_scene_file(f)
    assert str(e.value) == f"{f}:6: `imu.model`: holds no IMU parameters (an empty mapping); {ADVICE}"
    assert cli.main(["run", str(f)]) == 1
    assert capsys.readouterr().err.strip() == f"splineimu run: error: {e.value}"
    assert not (tmp_path / "o").exists()
    f.write_text(f.read_text().replace("model: {}", "model: ideal"))  # the advice works
    cfg = load_scene_file(f).imu.imu_config
    assert cfg is not None and cfg.gyroscope_noise_density.tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize("model, what", [({}, "an empty mapping"),
                                         ({"rostopic": "/imu0"}, "only rostopic, which is ignored"),
                                         ({"update_rate": 200}, "only update_rate"),
                                         ({"imu0": {}}, "an empty mapping")])
def test_mappings_without_parameters_are_refused(model, what):
    with pytest.raises(ConfigError) as e:
        ImuOptions(model=model)
    assert str(e.value) == f"`model`: holds no IMU parameters ({what}); {ADVICE}"
    with pytest.raises(ConfigError, match="holds no IMU parameters"):
        ImuConfig.from_dict(model)


def test_flags_and_chain_files(tmp_path, capsys):
    assert cli.main(["scene", "ellipse", "--imu", "{}", "-o", str(tmp_path / "o")]) == 1
    assert capsys.readouterr().err.strip() == ("splineimu scene: error: `--imu`: holds no IMU parameters (an empty "
                                               f"mapping); {ADVICE}")
    chain = tmp_path / "chain.yaml"
    chain.write_text("imu0: {}\n")
    with pytest.raises(ConfigError) as e:
        load_imu_config(chain)
    assert str(e.value) == f"{chain}: holds no IMU parameters (an empty mapping); {ADVICE}"
    # one real parameter is a model (its other densities are 0), and the preset still loads
    assert ImuConfig.from_dict({"gyroscope_noise_density": 1e-3}).gyroscope_noise_density.tolist() == [1e-3] * 3
    assert load_imu_config("ideal").accelerometer_random_walk.tolist() == [0.0, 0.0, 0.0]
