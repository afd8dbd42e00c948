"""ImuConfig: Kalibr keys, extras, validation messages, presets, round trips."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from conftest import require_shared

from splineimu.errors import ConfigError, InputError
from splineimu.imu.config import ImuConfig, list_presets, load_imu_config, load_preset
from splineimu.io.imu_yaml import write_imu_config

EVERY_KEY = {
    "gyroscope_noise_density": [1e-4, 2e-4, 3e-4],
    "gyroscope_random_walk": 1e-5,
    "accelerometer_noise_density": 2e-3,
    "accelerometer_random_walk": [3e-3, 3e-3, 4e-3],
    "update_rate": 400.0,
    "gyroscope_bias": [0.01, -0.02, 0.0],
    "gyroscope_bias_sigma": 0.005,
    "gyroscope_scale": [1e-3, -1e-3, 0.0],
    "gyroscope_misalignment": [[1.0, 0.0, 0.0], [1e-3, 1.0, 0.0], [2e-3, -1e-3, 1.0]],
    "gyroscope_g_sensitivity": [[1e-4, 0, 0], [0, 1e-4, 0], [0, 0, 1e-4]],
    "gyroscope_bias_instability": 1e-4,
    "gyroscope_bias_correlation_time": [100.0, 100.0, 50.0],
    "gyroscope_bias_temperature_coefficient": 1e-5,
    "gyroscope_scale_temperature_coefficient": 1e-6,
    "gyroscope_quantization": 8.72665e-4,
    "gyroscope_saturation": 5.2,
    "accelerometer_bias": 0.1,
    "accelerometer_bias_sigma": [0.01, 0.02, 0.03],
    "accelerometer_scale": 2e-3,
    "accelerometer_misalignment": [[1.0, 1e-3, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    "accelerometer_bias_instability": 1e-3,
    "accelerometer_bias_correlation_time": 10.0,
    "accelerometer_bias_temperature_coefficient": [1e-4, 0.0, -1e-4],
    "accelerometer_scale_temperature_coefficient": 2e-6,
    "accelerometer_quantization": 0.0327,
    "accelerometer_saturation": 176.5,
    "temperature_profile": {"start": 20.0, "rate": 0.001},
    "temperature_reference": 25.0,
}


def test_kalibr_keys_scalar_and_per_axis():
    c = ImuConfig.from_dict({"gyroscope_noise_density": 1.6968e-4, "accelerometer_random_walk": [1, 2, 3],
                             "update_rate": 200})
    np.testing.assert_array_equal(c.gyroscope_noise_density, [1.6968e-4] * 3)
    np.testing.assert_array_equal(c.accelerometer_random_walk, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(c.gyroscope_random_walk, [0, 0, 0])  # absent -> off
    assert c.update_rate == 200.0 and c.gyroscope_scale is None
    d = c.to_dict()
    assert d["gyroscope_noise_density"] == 1.6968e-4  # equal axes written as one number
    assert d["accelerometer_random_walk"] == [1.0, 2.0, 3.0]
    assert set(d) == {"gyroscope_noise_density", "gyroscope_random_walk", "accelerometer_noise_density",
                      "accelerometer_random_walk", "update_rate"}


def test_every_key_round_trips_through_yaml(tmp_path):
    c = ImuConfig.from_dict(EVERY_KEY, source="test")
    p = write_imu_config(c, tmp_path / "imu.yaml", header="made by a test")
    assert sorted(x.name for x in tmp_path.iterdir()) == ["imu.yaml"]  # no temporary left behind
    text = p.read_text()
    assert text.startswith("%YAML 1.1\n---\n# made by a test\n")
    back = ImuConfig.from_yaml(p)
    assert back == c
    assert set(yaml.safe_load(text)) == set(EVERY_KEY) | {"rostopic"}  # the same names are written back
    # written values equal the given ones
    d = back.to_dict()
    for k, v in EVERY_KEY.items():
        if isinstance(v, (int, float)) and k != "temperature_profile":
            assert d[k] == v, k
    assert c != ImuConfig.from_dict(dict(EVERY_KEY, gyroscope_scale=0.0))


def _numbers(x):
    if isinstance(x, dict):
        return [n for v in x.values() for n in _numbers(v)]
    if isinstance(x, list):
        return [n for v in x for n in _numbers(v)]
    return [] if isinstance(x, str) else [x]


def test_imu_yaml_is_kalibr_form_read_by_pyyaml(tmp_path):
    c = ImuConfig.from_dict({"gyroscope_noise_density": 1.6968e-4, "gyroscope_random_walk": 2e-5,
                             "accelerometer_noise_density": 2e-3, "accelerometer_random_walk": 3e-3,
                             "update_rate": 200})
    p = write_imu_config(c, tmp_path / "imu.yaml", update_rate=400, rostopic="/vectornav/IMU")
    lines = [x for x in p.read_text().splitlines() if not x.startswith("#")]
    assert lines == ["%YAML 1.1", "---", "gyroscope_noise_density: 0.00016968", "gyroscope_random_walk: 2.0e-05",
                     "accelerometer_noise_density: 0.002", "accelerometer_random_walk: 0.003",
                     "rostopic: /vectornav/IMU", "update_rate: 400.0"]
    d = yaml.safe_load(p.read_text())  # plain PyYAML, as Kalibr reads it
    assert d["update_rate"] == 400.0 and d["gyroscope_random_walk"] == 2e-5 and d["rostopic"] == "/vectornav/IMU"
    assert all(type(v) is float for k, v in d.items() if k != "rostopic")
    assert ImuConfig.from_yaml(p).update_rate == 400.0
    full = write_imu_config(ImuConfig.from_dict(EVERY_KEY), tmp_path / "full.yaml")
    numbers = _numbers(yaml.safe_load(full.read_text()))
    assert len(numbers) > 60 and all(type(v) is float for v in numbers)
    assert "rostopic: /imu0\n" in full.read_text()  # the default topic


def test_imu_yaml_is_read_by_opencv_filestorage(tmp_path):
    cv2 = pytest.importorskip("cv2")
    c = ImuConfig.from_dict(dict(EVERY_KEY, temperature_profile=30.0, gyroscope_random_walk=2e-5))
    p = write_imu_config(c, tmp_path / "imu.yaml")
    fs = cv2.FileStorage(str(p), cv2.FILE_STORAGE_READ)
    assert fs.isOpened()
    d = c.to_dict()
    for key, want in d.items():
        node = fs.getNode(key)
        if isinstance(want, float):
            assert node.isReal() and node.real() == want, key
        else:  # per-axis vectors and 3x3 matrices
            items = [node.at(i) for i in range(node.size())]
            rows = [[it.at(j) for j in range(it.size())] if it.isSeq() else it for it in items]
            leaves = [x for r in rows for x in (r if isinstance(r, list) else [r])]
            assert node.isSeq() and all(x.isReal() for x in leaves), key
            assert [[x.real() for x in r] if isinstance(r, list) else r.real() for r in rows] == want, key
    assert fs.getNode("rostopic").string() == "/imu0"
    fs.release()


def test_shared_kalibr_chain_files_load():
    p = require_shared("kalibr", "euroc_kalibr_imu_chain.yaml")
    c = load_imu_config(p)
    np.testing.assert_array_equal(c.gyroscope_noise_density, [1.6968e-4] * 3)
    np.testing.assert_array_equal(c.accelerometer_random_walk, [3.0e-3] * 3)
    assert c.update_rate == 200.0
    assert {"rostopic", "T_i_b", "model"} <= set(c.ignored_keys)
    # OpenVINS's intrinsics are applied: identity Tw/Ta and zero Tg are no error at all
    assert c.gyroscope_misalignment is None and c.accelerometer_misalignment is None
    assert c.gyroscope_g_sensitivity is None
    tum = load_imu_config(require_shared("kalibr", "tum_vi_kalibr_imu_chain.yaml"))
    assert tum.to_dict() == {"gyroscope_noise_density": 0.00016, "gyroscope_random_walk": 2.2e-05,
                             "accelerometer_noise_density": 0.0028, "accelerometer_random_walk": 0.00086,
                             "update_rate": 200.0}
    assert tum == load_preset("bmi160")
    euroc = load_imu_config(require_shared("euroc_V1_02_medium", "imu0_sensor.yaml"))  # rate_hz, T_BS
    assert euroc == load_preset("adis16448") == c


def test_presets():
    names = list_presets()
    assert {"adis16448", "bmi160", "lecture", "adis16405", "ideal"} <= set(names)
    for n in names:
        c = load_preset(n)
        assert c.source == f"preset {n}"
    lec = load_imu_config("lecture")
    assert lec.to_dict()["gyroscope_noise_density"] == 0.015
    assert lec.to_dict()["accelerometer_noise_density"] == 0.019
    assert lec.to_dict()["gyroscope_random_walk"] == 5e-5
    assert lec.to_dict()["accelerometer_random_walk"] == 5e-4
    assert load_imu_config("ADIS16448") == load_preset("adis16448")  # case-insensitive
    adis = load_preset("adis16405")
    assert adis.gyroscope_quantization[0] == pytest.approx(0.05 * np.pi / 180, rel=1e-5)
    assert adis.accelerometer_saturation[0] == pytest.approx(18 * 9.80665, rel=1e-5)
    with pytest.raises(ConfigError, match="did you mean `adis16448`"):
        load_imu_config("adis1648")
    with pytest.raises(ConfigError, match="file not found"):
        load_imu_config("no/such/imu.yaml")


def test_a_file_wins_over_a_preset_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "lecture").write_text("gyroscope_noise_density: 0.5\n")
    assert load_imu_config("lecture").gyroscope_noise_density[0] == 0.5


@pytest.mark.parametrize("d, match", [
    ({"gyroscope_noise_densty": 0.1}, r"unknown IMU key `gyroscope_noise_densty` \(did you mean "
                                      r"`gyroscope_noise_density`\?\)"),
    ({"acelerometer_random_walk": 0.1, "foo": 1}, r"keys `acelerometer_random_walk` \(did you mean "
                                                  r"`accelerometer_random_walk`\?\), `foo`"),
    ({"gyroscope_noise_density": -1e-4}, r"`gyroscope_noise_density` must not be negative, got \[-0.0001"),
    ({"accelerometer_random_walk": [1e-3, -1e-3, 0]}, "must not be negative"),
    ({"gyroscope_noise_density": "abc"},
     r"`gyroscope_noise_density` must be a number or a list of 3 numbers"),
    ({"gyroscope_noise_density": [1, 2]}, r"list of 3 numbers \[x, y, z\], got 2 values"),
    ({"gyroscope_noise_density": True}, "must be a number"),
    ({"gyroscope_noise_density": [1, "x", 2]}, "must be a number, got 'x'"),
    ({"gyroscope_scale": float("nan")}, "must be finite"),
    ({"gyroscope_misalignment": [[1, 0], [0, 1]]}, r"must be a 3x3 matrix.*got shape \(2, 2\)"),
    ({"gyroscope_g_sensitivity": [1, 2, 3]}, r"`gyroscope_g_sensitivity` must be a 3x3 matrix, got shape"),
    ({"gyroscope_g_sensitivity": [[1, 2, 3], [1, 2, 3], [1, 2]]}, "3x3"),
    ({"gyroscope_bias_instability": 1e-4}, "must be given together"),
    ({"accelerometer_bias_correlation_time": 0.0, "accelerometer_bias_instability": 1.0}, "must be positive"),
    ({"gyroscope_quantization": 0.0}, "must be positive"),
    ({"gyroscope_scale": -1.0}, "must be > -1"),
    ({"update_rate": 0}, "`update_rate` must be positive"),
    ({"update_rate": 200, "rate_hz": 200}, "either `update_rate` or `rate_hz`"),
    ({"temperature_profile": [1, 2]}, r"`temperature_profile` must be a number"),
    ({"temperature_profile": {"start": 20}}, r"\{start: degC, rate: degC/s\}"),
    ({"imu0": {"gyroscope_noise_density": 1e-4}, "gyroscope_random_walk": 1e-5}, "one or the other"),
])
def test_validation_messages(d, match):
    with pytest.raises(ConfigError, match=match):
        ImuConfig.from_dict(d, source="cfg.yaml")


def test_error_names_the_source_and_yaml_line(tmp_path):
    p = tmp_path / "imu.yaml"
    p.write_text("gyroscope_noise_density: 1e-4\ngyroscope_random_walk: [1, 2\n")
    with pytest.raises(ConfigError, match=r"imu\.yaml:\d+: invalid YAML"):
        ImuConfig.from_yaml(p)
    p.write_text("gyroscope_noise_densty: 1e-4\n")
    with pytest.raises(ConfigError, match=r"^.*imu\.yaml: unknown IMU key"):
        ImuConfig.from_yaml(p)
    with pytest.raises(ConfigError, match="not found"):
        ImuConfig.from_yaml(tmp_path / "missing.yaml")
    p.write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="expected a mapping"):
        ImuConfig.from_yaml(p)


def test_bad_value_in_a_file_names_its_line(tmp_path):
    p = tmp_path / "imu.yaml"
    p.write_text("update_rate: 200\ngyroscope_noise_density: 1.0e-4\ngyroscope_random_walk: -2.0e-5\n")
    with pytest.raises(ConfigError, match=r"imu\.yaml:3: `gyroscope_random_walk` must not be negative") as ei:
        ImuConfig.from_yaml(p)
    assert ei.value.line == 3 and ei.value.option == "gyroscope_random_walk"
    p.write_text("%YAML:1.0\nimu0:\n  update_rate: 200\n  temperature_profile:\n    start: 20\n    rate: .nan\n")
    with pytest.raises(ConfigError, match=r"imu\.yaml:6: `temperature_profile\.rate` must be finite"):
        ImuConfig.from_yaml(p)


def test_opencv_header_chain_and_companion_keys(tmp_path):
    p = tmp_path / "chain.yaml"
    p.write_text(
        "%YAML:1.0\n"
        "imu1: {gyroscope_noise_density: 9.0}\n"
        "imu0:\n"
        "  T_BS: !!opencv-matrix\n    rows: 4\n    cols: 4\n    dt: d\n"
        "    data: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n"
        "  gyroscope_noise_density: [1.0e-4, 2.0e-4, 3.0e-4]\n"
        "  gyroscope_noise_density_avg: 2.0e-4\n"
        "  gyroscope_noise_density_ci95: [[0.9e-4, 1.1e-4], [1.9e-4, 2.1e-4], [2.9e-4, 3.1e-4]]\n"
        "  update_rate: 100\n"
        "  allan: {n_samples: 10}\n")
    c = ImuConfig.from_yaml(p)  # the lowest-numbered imu of a chain
    np.testing.assert_array_equal(c.gyroscope_noise_density, [1e-4, 2e-4, 3e-4])
    assert set(c.ignored_keys) == {"T_BS", "gyroscope_noise_density_avg", "gyroscope_noise_density_ci95",
                                   "allan"}
    with pytest.raises(ConfigError, match="unknown IMU key `bogus_avg`"):
        ImuConfig.from_dict({"bogus_avg": 1})


def test_kalibr_lower_triangular_misalignment_forms():
    c6 = ImuConfig.from_dict({"gyroscope_misalignment": [1.01, 0.002, 0.99, -0.001, 0.003, 1.0]})
    np.testing.assert_array_equal(c6.gyroscope_misalignment,
                                  [[1.01, 0, 0], [0.002, 0.99, 0], [-0.001, 0.003, 1.0]])
    c3 = ImuConfig.from_dict({"accelerometer_misalignment": [0.002, -0.001, 0.003]})
    expect = [[1.0, 0.0, 0.0], [0.002, 1.0, 0.0], [-0.001, 0.003, 1.0]]
    np.testing.assert_array_equal(c3.accelerometer_misalignment, expect)
    assert c3.to_dict()["accelerometer_misalignment"] == expect


def test_temperature_profile_forms(tmp_path):
    const = ImuConfig.from_dict({"temperature_profile": 30})
    np.testing.assert_array_equal(const.temperature_profile(np.array([0.0, 5.0])), [30.0, 30.0])
    ramp = ImuConfig.from_dict({"temperature_profile": {"start": 10, "rate": 0.5}})
    # the ramp starts at the first sample
    np.testing.assert_allclose(ramp.temperature_profile(np.array([2.0, 4.0])), [10.0, 11.0])
    (tmp_path / "t.txt").write_text("0 20\n10 30\n")
    f = ImuConfig.from_dict({"temperature_profile": {"file": "t.txt"}}, base_dir=tmp_path)
    np.testing.assert_allclose(f.temperature_profile(np.array([0.0, 5.0, 20.0])), [20.0, 25.0, 30.0])
    assert f.to_dict()["temperature_profile"] == {"file": str((tmp_path / "t.txt").resolve())}
    (tmp_path / "bad.txt").write_text("0 20\n10 x\n")
    with pytest.raises(InputError, match=r"bad\.txt:2: expected two numbers"):
        ImuConfig.from_dict({"temperature_profile": {"file": "bad.txt"}}, base_dir=tmp_path)
    with pytest.raises(ConfigError, match="not found"):
        ImuConfig.from_dict({"temperature_profile": {"file": "none.txt"}}, base_dir=tmp_path)
