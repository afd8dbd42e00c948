"""Files other tools read and write: the output folder as a EuRoC dataset, Kalibr's imu.yaml,
OpenVINS's kalibr_imu_chain.yaml, ROS bags; and those tools' files accepted as input.

Checked the way those tools read them: PyYAML's safe_load (Kalibr), OpenCV's FileStorage
(OpenVINS, VINS-Fusion, Kimera) and rosbags.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from conftest import require_shared

from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, run_job, synthesize_to_memory
from splineimu.cli import main
from splineimu.errors import ConfigError, InputError
from splineimu.imu.config import ImuConfig, load_imu_config, load_preset
from splineimu.imu.ideal import Extrinsic
from splineimu.imu.noise import SensorModel
from splineimu.imu.openvins import from_openvins, to_openvins
from splineimu.io.dataset import dataset_file, dataset_root, recorded_sampling
from splineimu.io.imu_csv import read_imu_csv
from splineimu.io.imu_yaml import kalibr_imu_chain_text

cv2 = pytest.importorskip("cv2")

NOISE_KEYS = ("gyroscope_noise_density", "gyroscope_random_walk", "accelerometer_noise_density",
              "accelerometer_random_walk")


def _fs(path):
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    assert fs.isOpened(), path
    return fs


def _matrix(node):
    return np.array([[node.at(r).at(c).real() for c in range(node.at(r).size())] for r in range(node.size())])


def _scene_job(out, rate=400.0, model="adis16448", **imu):
    return SynthesisJob(SceneInput("ellipse", duration_s=2.0, t0_ns=1_700_000_000_000_000_000),
                        ImuOptions(rate_hz=rate, model=model, seed=3, **imu), OutputOptions(str(out)))


@pytest.fixture(scope="module")
def out400(tmp_path_factory):
    out = tmp_path_factory.mktemp("interop") / "out"
    assert main(["scene", "ellipse", "--duration", "2", "--rate", "400", "--imu", "adis16448", "--seed", "1",
                 "-o", str(out)]) == 0
    return out


# ------------------------------------------------------------------------------ output folder


def test_yaml_files_load_as_floats_with_the_rate_synthesized(out400):
    preset = load_preset("adis16448")
    assert preset.update_rate != 400.0  # the preset's own rate must not leak through
    want = {k: float(getattr(preset, k)[0]) for k in NOISE_KEYS}
    kalibr = yaml.safe_load((out400 / "imu.yaml").read_text())
    assert kalibr["update_rate"] == 400.0 and kalibr["rostopic"] == "/imu0"
    assert {k: kalibr[k] for k in NOISE_KEYS} == want
    assert all(isinstance(v, float) for v in kalibr.values() if not isinstance(v, str))
    for name, prefix in (("imu.yaml", ()), ("kalibr_imu_chain.yaml", ("imu0",)),
                         ("mav0/imu0/sensor.yaml", ())):
        fs = _fs(out400 / name)
        node = fs.getNode(prefix[0]) if prefix else fs.root()
        rate = node.getNode("rate_hz" if name.startswith("mav0") else "update_rate")
        assert rate.isReal() and rate.real() == 400.0, name
        for k in NOISE_KEYS:
            assert node.getNode(k).isReal() and node.getNode(k).real() == want[k], (name, k)
        fs.release()


def test_output_folder_is_a_euroc_dataset(out400):
    for name in ("mav0/imu0/data.csv", "mav0/state_groundtruth_estimate0/data.csv", "mav0/body.yaml",
                 "groundtruth.tum", "report.json"):
        assert (out400 / name).is_file(), name
    fs = _fs(out400 / "mav0" / "imu0" / "sensor.yaml")  # as Kimera / OpenVINS's ov_data read it
    assert fs.getNode("sensor_type").string() == "imu"
    np.testing.assert_array_equal(fs.getNode("T_BS").mat(), np.eye(4))
    assert fs.getNode("rate_hz").isReal()
    fs.release()
    gt = _fs(out400 / "mav0" / "state_groundtruth_estimate0" / "sensor.yaml")
    np.testing.assert_array_equal(gt.getNode("T_BS").mat(), np.eye(4))
    body = _fs(out400 / "mav0" / "body.yaml")
    assert body.getNode("comment").isString()
    # our own reader: the EuRoC sensor.yaml is an --imu file with the same values
    back = load_imu_config(str(out400 / "mav0" / "imu0" / "sensor.yaml"))
    assert back.update_rate == 400.0
    assert back.gyroscope_noise_density[0] == load_preset("adis16448").gyroscope_noise_density[0]


def test_chain_file_is_openvins_form_and_reads_back(out400):
    text = (out400 / "kalibr_imu_chain.yaml").read_text()
    assert text.startswith("%YAML:1.0\n")
    fs = _fs(out400 / "kalibr_imu_chain.yaml")
    imu0 = fs.getNode("imu0")
    assert imu0.getNode("rostopic").string() == "/imu0" and imu0.getNode("model").string() == "kalibr"
    assert imu0.getNode("time_offset").isReal()
    np.testing.assert_array_equal(_matrix(imu0.getNode("T_i_b")), np.eye(4))
    for key, want in (("Tw", np.eye(3)), ("R_IMUtoGYRO", np.eye(3)), ("Ta", np.eye(3)), ("R_IMUtoACC", np.eye(3)),
                      ("Tg", np.zeros((3, 3)))):
        np.testing.assert_array_equal(_matrix(imu0.getNode(key)), want)
    back = load_imu_config(str(out400 / "kalibr_imu_chain.yaml"))
    assert back == ImuConfig.from_dict({k: getattr(load_preset("adis16448"), k) for k in NOISE_KEYS}
                                       | {"update_rate": 400.0})


def test_rostopic_option_and_scene_key(tmp_path):
    out = tmp_path / "a"
    run_job(_scene_job(out, rostopic="/sensors/imu"))
    assert yaml.safe_load((out / "imu.yaml").read_text())["rostopic"] == "/sensors/imu"
    chain = _fs(out / "kalibr_imu_chain.yaml")
    assert chain.getNode("imu0").getNode("rostopic").string() == "/sensors/imu"
    scene = tmp_path / "s.yaml"
    scene.write_text("motion: {scene: static, duration_s: 1}\nimu: {rate_hz: 100, rostopic: /imu_raw}\n"
                     f"output: {{dir: {tmp_path / 'b'}}}\n")
    assert main(["run", str(scene)]) == 0
    assert yaml.safe_load((tmp_path / "b" / "imu.yaml").read_text())["rostopic"] == "/imu_raw"
    with pytest.raises(ConfigError, match="rostopic"):
        ImuOptions(rostopic="has space")


# ------------------------------------------------------------------------------ OpenVINS intrinsics


def _full_model():
    return ImuConfig.from_dict({
        "gyroscope_noise_density": 1e-4, "accelerometer_noise_density": 2e-3,
        "gyroscope_random_walk": 1e-5, "accelerometer_random_walk": 3e-3,
        "gyroscope_scale": [0.01, -0.02, 0.005], "accelerometer_scale": [0.002, 0.001, -0.003],
        "gyroscope_misalignment": [[1.0, 0.003, -0.002], [0.001, 1.0, 0.004], [-0.002, 0.001, 1.0]],
        "accelerometer_misalignment": [0.001, -0.002, 0.003],
        "gyroscope_g_sensitivity": [[1e-4, 0, 2e-5], [0, -1e-4, 0], [3e-5, 0, 1e-4]],
        "update_rate": 200.0})


def test_openvins_intrinsics_reproduce_the_sensor_model(tmp_path):
    cfg = _full_model()
    ov = to_openvins(cfg)
    assert not np.any(np.triu(ov["Tw"], 1)) and not np.any(np.triu(ov["Ta"], 1))  # kalibr: lower triangular
    np.testing.assert_allclose(ov["R_IMUtoGYRO"] @ ov["R_IMUtoGYRO"].T, np.eye(3), atol=1e-15)
    np.testing.assert_array_equal(ov["R_IMUtoACC"], np.eye(3))  # triangular misalignment: no rotation
    path = tmp_path / "kalibr_imu_chain.yaml"
    path.write_text(kalibr_imu_chain_text(cfg, update_rate=200.0))
    back = load_imu_config(str(path))
    for k in NOISE_KEYS:
        np.testing.assert_array_equal(getattr(back, k), getattr(cfg, k))
    rng = np.random.default_rng(0)
    t = np.arange(50) * 0.005
    w, f = rng.normal(size=(50, 3)), rng.normal(size=(50, 3)) + [0, 0, 9.81]
    noise_free = {k: 0.0 for k in NOISE_KEYS}
    a = SensorModel(ImuConfig.from_dict({**cfg.to_dict(), **noise_free})).apply(t, w, f, rng=1)
    b = SensorModel(ImuConfig.from_dict({**back.to_dict(), **noise_free})).apply(t, w, f, rng=1)
    np.testing.assert_allclose(b.gyro, a.gyro, rtol=0, atol=1e-14)
    np.testing.assert_allclose(b.accel, a.accel, rtol=0, atol=1e-13)
    assert np.abs(a.gyro - w).max() > 1e-3  # the intrinsics do something
    # written back: the same matrices (to round-off: Tw R_IMUtoGYRO is split again) ...
    for key, value in to_openvins(back).items():
        if key != "model":
            np.testing.assert_allclose(value, ov[key], rtol=0, atol=1e-15)
    # ... and the same text when the misalignment is triangular (Kalibr's form): nothing to split
    tri = ImuConfig.from_dict({**cfg.to_dict(), "gyroscope_misalignment": [0.003, -0.001, 0.002]})
    path.write_text(kalibr_imu_chain_text(tri, update_rate=200.0))
    assert kalibr_imu_chain_text(load_imu_config(str(path)), update_rate=200.0) == path.read_text()


def test_openvins_models_keep_their_triangle():
    Tw = np.array([[1.01, 0.02, 0.0], [0.003, 0.99, 0.0], [0.0, 0.01, 1.0]])
    for model, tri in (("kalibr", np.tril), ("rpng", np.triu)):
        got = from_openvins({"Tw": Tw, "model": model})["gyroscope_misalignment"]
        np.testing.assert_allclose(got, np.linalg.inv(tri(np.linalg.inv(Tw))), rtol=0, atol=1e-15)
    with pytest.raises(ConfigError, match="model"):
        from_openvins({"Tw": Tw, "model": "imu"})
    with pytest.raises(ConfigError, match="give one or the other"):
        ImuConfig.from_dict({"imu0": {"Tw": Tw.tolist(), "gyroscope_scale": 0.01}})


def test_openvins_tw_changes_the_synthesized_gyro(tmp_path):
    src = require_shared("kalibr", "euroc_kalibr_imu_chain.yaml").read_text()
    tw = "  Tw:\n    - [ 1.02, 0.0, 0.0 ]\n    - [ 0.004, 0.98, 0.0 ]\n    - [ 0.0, -0.003, 1.01 ]\n"
    ident = "  Tw:\n    - [ 1.0, 0.0, 0.0 ]\n    - [ 0.0, 1.0, 0.0 ]\n    - [ 0.0, 0.0, 1.0 ]\n"
    assert ident in src
    (tmp_path / "tw.yaml").write_text(src.replace(ident, tw))
    (tmp_path / "id.yaml").write_text(src)
    syn = {name: synthesize_to_memory(_scene_job(tmp_path / name, rate=200.0, model=str(tmp_path / f"{name}.yaml")))
           .synthesis for name in ("tw", "id")}
    Tw = np.array([[1.02, 0, 0], [0.004, 0.98, 0], [0, -0.003, 1.01]])
    w = syn["id"].ideal.gyro
    np.testing.assert_allclose(syn["tw"].gyro_rad_s - syn["id"].gyro_rad_s, w @ (Tw - np.eye(3)).T, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(syn["tw"].accel_m_s2, syn["id"].accel_m_s2)


# ------------------------------------------------------------------------------ inputs as they are


@pytest.mark.parametrize("name", [("kalibr", "euroc_kalibr_imu_chain.yaml"), ("kalibr", "tum_vi_kalibr_imu_chain.yaml"),
                                  ("euroc_V1_02_medium", "imu0_sensor.yaml")])
def test_other_tools_imu_files_are_echoed_back(tmp_path, name):
    path = require_shared(*name)
    given = yaml.safe_load("\n".join(path.read_text().splitlines()[1:]))
    given = given.get("imu0", given)
    out = tmp_path / "o"
    run_job(_scene_job(out, rate=100.0, model=str(path)))
    kalibr = yaml.safe_load((out / "imu.yaml").read_text())
    assert {k: kalibr[k] for k in NOISE_KEYS} == {k: float(given[k]) for k in NOISE_KEYS}
    assert kalibr["update_rate"] == 100.0  # the rate synthesized, not the file's 200
    sensor = _fs(out / "mav0" / "imu0" / "sensor.yaml")
    assert sensor.getNode("rate_hz").real() == 100.0
    assert [sensor.getNode(k).real() for k in NOISE_KEYS] == [float(given[k]) for k in NOISE_KEYS]


def test_extrinsic_files_of_other_tools(tmp_path):
    euroc = require_shared("euroc_V1_02_medium", "imu0_sensor.yaml")
    assert Extrinsic.from_file(euroc).is_identity
    T = np.array([[0.0, -1.0, 0.0, 0.1], [1.0, 0.0, 0.0, -0.2], [0.0, 0.0, 1.0, 0.05], [0.0, 0.0, 0.0, 1.0]])
    inv = np.linalg.inv(T)
    rows = lambda M: "".join(f"    - {list(map(float, r))}\n" for r in M)  # noqa: E731
    (tmp_path / "chain.yaml").write_text(f"%YAML:1.0\nimu0:\n  T_i_b:\n{rows(inv)}  rostopic: /imu0\n"
                                         "  update_rate: 200.0\n")
    (tmp_path / "camchain.yaml").write_text(f"cam0:\n  T_cam_imu:\n{rows(T)}  rostopic: /cam0/image_raw\n"
                                            f"cam1:\n  T_cam_imu:\n{rows(np.eye(4))}")
    (tmp_path / "imucam.yaml").write_text(f"%YAML:1.0\ncam0:\n  T_imu_cam:\n{rows(inv)}")
    for name in ("chain.yaml", "camchain.yaml", "imucam.yaml"):
        np.testing.assert_allclose(Extrinsic.from_file(tmp_path / name).matrix, T, rtol=0, atol=1e-15)
    out = tmp_path / "o"
    run_job(_scene_job(out, extrinsic=str(tmp_path / "camchain.yaml")))
    sensor, chain = _fs(out / "mav0" / "imu0" / "sensor.yaml"), _fs(out / "kalibr_imu_chain.yaml")
    np.testing.assert_allclose(sensor.getNode("T_BS").mat(), T, rtol=0, atol=1e-15)
    np.testing.assert_allclose(_matrix(chain.getNode("imu0").getNode("T_i_b")), inv, rtol=0, atol=1e-15)
    rep = json.loads((out / "report.json").read_text())
    np.testing.assert_allclose(rep["imu"]["extrinsic_body_T_sensor"], T, atol=1e-15)


def test_old_layout_is_still_read(tmp_path):
    (tmp_path / "imu0").mkdir()
    csv = tmp_path / "imu0" / "data.csv"
    csv.write_text("")
    assert dataset_file(tmp_path, "mav0/imu0/data.csv") == csv and dataset_root(csv) == tmp_path.resolve()
    (tmp_path / "report.json").write_text(json.dumps({"imu": {"sampling": "mean"}}))
    assert recorded_sampling(csv) == "mean"
    (tmp_path / "report.json").write_text("{")  # broken: refused, no longer taken for point samples
    with pytest.raises(InputError, match="report.json:1: not valid JSON"):
        recorded_sampling(csv)
    (tmp_path / "report.json").unlink()  # missing: point samples
    assert recorded_sampling(csv) == "point"


# ------------------------------------------------------------------------------ ROS bags


@pytest.mark.parametrize("bag, version", [("ros2", None), ("ros2", 9), ("ros1", None)])
def test_bags_equal_the_csv(tmp_path, bag, version):
    pytest.importorskip("rosbags")
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    out = tmp_path / "o"
    job = _scene_job(out, rate=200.0)
    job.output = OutputOptions(str(out), bag=bag, bag_version=version)
    run_job(job)
    path = out / ("imu.bag" if bag == "ros1" else "bag_ros2")
    if bag == "ros2":
        meta = yaml.safe_load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
        assert meta["version"] == (version or 8) and meta["storage_identifier"] == "sqlite3"
        qos = meta["topics_with_message_count"][0]["topic_metadata"]["offered_qos_profiles"]
        assert isinstance(qos, str) if version is None else isinstance(qos, list)  # Humble parses a string
    t_ns, gyro, accel = read_imu_csv(out / "mav0" / "imu0" / "data.csv")
    store = get_typestore(Stores.ROS1_NOETIC if bag == "ros1" else Stores.ROS2_HUMBLE)
    with AnyReader([path], default_typestore=store) as reader:
        conn = [c for c in reader.connections if c.topic == "/imu0"]
        msgs = [(t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages(connections=conn)]
    stamps = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in msgs])
    np.testing.assert_array_equal(stamps, t_ns)
    np.testing.assert_array_equal([t for t, _ in msgs], t_ns)
    np.testing.assert_array_equal([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
                                   for _, m in msgs], gyro)
    np.testing.assert_array_equal([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                                   for _, m in msgs], accel)
    preset = load_preset("adis16448")
    m = msgs[0][1]
    assert m.orientation_covariance[0] == -1.0
    np.testing.assert_allclose(m.angular_velocity_covariance.reshape(3, 3),
                               np.diag(preset.gyroscope_noise_density**2 * 200.0), rtol=1e-15, atol=0)
    np.testing.assert_allclose(m.linear_acceleration_covariance.reshape(3, 3),
                               np.diag(preset.accelerometer_noise_density**2 * 200.0), rtol=1e-15, atol=0)


def test_bag_version_needs_a_ros2_bag():
    with pytest.raises(ConfigError, match="bag_version"):
        OutputOptions("o", bag="ros1", bag_version=9)
    with pytest.raises(ConfigError, match="bag_version"):
        OutputOptions("o", bag="ros2", bag_version=7)


# ------------------------------------------------------------------------------ sampling mode


@pytest.mark.parametrize("method", ["rk4", "midpoint"])
def test_dead_reckoning_of_mean_samples_is_as_accurate_as_of_point_samples(tmp_path, method):
    from splineimu.api.integrate import dead_reckon
    from splineimu.api.preintegration import evaluate_recording

    err, pre = {}, {}
    for sampling in ("point", "mean"):
        out = tmp_path / sampling
        run_job(SynthesisJob(SceneInput("ellipse", duration_s=20.0), ImuOptions(rate_hz=100.0, sampling=sampling),
                             OutputOptions(str(out))))
        csv = out / "mav0" / "imu0" / "data.csv"
        assert recorded_sampling(csv) == sampling
        err[sampling] = dead_reckon(csv, method=method).final_position_error_m
        pre[sampling] = np.abs(evaluate_recording(out, every=100, method="midpoint").error_p_m).max()
    ignored = dead_reckon(tmp_path / "mean" / "mav0" / "imu0" / "data.csv", method=method,
                          sampling="point").final_position_error_m
    print(method, err, ignored, pre)
    assert err["mean"] <= 1.5 * err["point"]
    assert ignored > 10 * err["point"]  # what reading mean samples as points costs
    assert pre["mean"] <= 1.5 * pre["point"]


def test_per_axis_densities_reach_openvins_as_one_number(tmp_path):
    """OpenVINS reads each noise key as one double (cv::FileStorage): a per-axis density is
    written as its largest axis, the axes in a comment; imu.yaml keeps the three values."""
    run_job(_scene_job(tmp_path / "o", model={"gyroscope_noise_density": [1e-4, 2e-4, 3e-4],
                                              "accelerometer_noise_density": 2e-3}))
    fs = _fs(tmp_path / "o" / "kalibr_imu_chain.yaml")  # the nodes live as long as the storage
    imu0 = fs.getNode("imu0")
    assert imu0.getNode("gyroscope_noise_density").isReal()
    assert imu0.getNode("gyroscope_noise_density").real() == 3e-4
    assert imu0.getNode("accelerometer_noise_density").real() == 2e-3
    assert "per axis (x, y, z): 0.0001, 0.0002, 0.0003" in (tmp_path / "o" / "kalibr_imu_chain.yaml").read_text()
    full = yaml.safe_load((tmp_path / "o" / "imu.yaml").read_text())
    assert full["gyroscope_noise_density"] == [1e-4, 2e-4, 3e-4]
