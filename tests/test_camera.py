"""Camera models, Kalibr / OpenVINS camchain files, landmarks and features.csv (issue 18)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from splineimu.camera import (
    Camera,
    Landmarks,
    load_camchain,
    read_features_csv,
)
from splineimu.camera.camchain import cameras_from_kalibr
from splineimu.errors import ConfigError, InputError
from splineimu.io.camera import write_camchain, write_features_csv, write_landmarks_csv, write_openvins_imucam_chain
from splineimu.scenes import make_scene

cv2 = pytest.importorskip("cv2")

EUROC_CAM0 = {  # Kalibr's camchain-imucam entry of EuRoC's cam0 (as in OpenVINS's config/euroc_mav)
    "T_cam_imu": [[0.0148655429818, 0.999557249008, -0.0257744366974, 0.0652229095355],
                  [-0.999880929698, 0.0149672133247, 0.00375618835797, -0.0207063854745],
                  [0.00414029679422, 0.025715529948, 0.999660727178, -0.00805460533553],
                  [0.0, 0.0, 0.0, 1.0]],
    "camera_model": "pinhole",
    "distortion_coeffs": [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05],
    "distortion_model": "radtan",
    "intrinsics": [458.654, 457.296, 367.215, 248.375],
    "resolution": [752, 480],
    "rostopic": "/cam0/image_raw",
    "timeshift_cam_imu": 0.005,
    "cam_overlaps": [1],
}
TUMVI_CAM0 = {
    "camera_model": "pinhole",
    "distortion_coeffs": [0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202,
                          0.00020293673591811182],
    "distortion_model": "equidistant",
    "intrinsics": [190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504],
    "resolution": [512, 512],
    "timeshift_cam_imu": -0.0031,
    "line_delay_s": 2.5e-05,
    "pixel_noise_px": 0.75,
}


def two_cameras():
    cams = cameras_from_kalibr({"cam0": EUROC_CAM0, "cam1": TUMVI_CAM0}, defaults={"rate_hz": 20.0})
    return list(cams.values())


# ------------------------------------------------------------------------------ projection


@pytest.mark.parametrize("model", ["radtan", "equidistant", "none"])
def test_projection_matches_opencv(model):
    rng = np.random.default_rng(1)
    p = np.column_stack([rng.uniform(-1.5, 1.5, (5000, 2)), rng.uniform(0.5, 4.0, 5000)])
    p[0] = [0.0, 0.0, 2.0]  # on the axis (the small-radius branch)
    p[1] = [1e-12, -1e-12, 1.0]
    coeffs = {"radtan": (-0.28, 0.07, 2e-4, -3e-4), "equidistant": (0.0035, 7e-4, -2e-3, 2e-4), "none": ()}[model]
    cam = Camera((458.6, 457.3, 367.2, 248.4), (752, 480), model, coeffs)
    uv = cam.project(p)
    K, D = cam.camera_matrix, np.array(coeffs if coeffs else (0.0, 0.0, 0.0, 0.0))
    if model == "equidistant":
        ref, _ = cv2.fisheye.projectPoints(p.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D)
    else:
        ref, _ = cv2.projectPoints(p.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D)
    assert np.abs(uv - ref.reshape(-1, 2)).max() < 1e-6


def test_visibility_rule_is_kalibrs():
    cam = Camera((100.0, 100.0, 0.0, 0.0), (10, 20))  # u = 100 X / Z, v = 100 Y / Z
    pts = np.array([[0.0, 0.0, 1.0], [0.099, 0.199, 1.0], [0.1, 0.0, 1.0], [0.0, 0.2, 1.0],
                    [-1e-9, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 0.0]])
    assert cam.is_visible(pts).tolist() == [True, True, False, False, False, False, False]


# ------------------------------------------------------------------------------ parsing


def test_from_kalibr_reads_every_key():
    cam = Camera.from_kalibr(dict(TUMVI_CAM0, rate_hz=30), name="cam1")
    assert cam.distortion_model == "equidistant" and cam.distortion_coeffs == tuple(TUMVI_CAM0["distortion_coeffs"])
    assert cam.intrinsics == tuple(TUMVI_CAM0["intrinsics"]) and cam.resolution == (512, 512)
    got = (cam.timeshift_cam_imu_s, cam.line_delay_s, cam.pixel_noise_px, cam.rate_hz)
    assert got == (-0.0031, 2.5e-05, 0.75, 30.0)
    assert cam.topic == "/cam1/image_raw" and not cam.is_global_shutter
    euroc = Camera.from_kalibr(EUROC_CAM0, rate_hz=20)
    assert np.array_equal(euroc.cam_T_imu, EUROC_CAM0["T_cam_imu"]) and euroc.is_global_shutter


def test_openvins_T_imu_cam_and_kalibr_line_delay_are_accepted():
    T = np.array(EUROC_CAM0["T_cam_imu"])
    d = {k: v for k, v in EUROC_CAM0.items() if k != "T_cam_imu"}
    inv = np.linalg.inv(T)
    inv[3] = [0, 0, 0, 1]
    cam = Camera.from_kalibr(dict(d, T_imu_cam=inv.tolist(), line_delay=3e-5), rate_hz=20)
    assert np.abs(cam.cam_T_imu - T).max() < 1e-12 and cam.line_delay_s == 3e-5
    with pytest.raises(ConfigError, match="not inverses"):
        Camera.from_kalibr(dict(EUROC_CAM0, T_imu_cam=np.eye(4).tolist()), rate_hz=20)


@pytest.mark.parametrize("change, message", [
    ({"intrinsics": [1.0, 2.0, 3.0]}, "`intrinsics` must be .*4 values, got 3"),
    ({"intrinsics": [-1.0, 2.0, 3.0, 4.0]}, "focal lengths"),
    ({"intrinsics": [1.0, "a", 3.0, 4.0]}, "`intrinsics` must be a number"),
    ({"resolution": [752.5, 480]}, "`resolution` must be an integer, got 752.5"),
    ({"resolution": [0, 480]}, "`resolution` must be >= 1, got 0"),
    ({"resolution": [752]}, r"`resolution` must be \[width, height\]"),
    ({"distortion_model": "radial"}, "`distortion_model` must be one of radtan, equidistant, none"),
    ({"distortion_coeffs": [0.1, 0.2]}, "`distortion_coeffs` must be 4 numbers for radtan"),
    ({"camera_model": "omni"}, "`camera_model` must be pinhole"),
    ({"T_cam_imu": np.eye(3).tolist()}, r"`T_cam_imu` to have shape \(4, 4\)"),
    ({"T_cam_imu": (2 * np.eye(4)).tolist()}, "last row"),
    ({"T_cam_imu": np.diag([1.0, 1.0, -1.0, 1.0]).tolist()}, "not a rotation"),
    ({"timeshift_cam_imu": float("nan")}, "`timeshift_cam_imu` must be finite"),
    ({"rate_hz": 0}, "`rate_hz` must be positive"),
    ({"line_delay_s": -1e-5}, "`line_delay_s` must be zero or positive"),
    ({"pixel_noise_px": True}, "`pixel_noise_px` must be a number"),
    ({"pixel_nosie_px": 1.0}, "unknown key `pixel_nosie_px`; did you mean `pixel_noise_px`"),
])
def test_bad_camera_keys_are_named(change, message):
    d = dict(EUROC_CAM0, rate_hz=20.0)
    d.update(change)
    with pytest.raises(ConfigError, match=message) as info:
        Camera.from_kalibr(d, name="cam3")
    assert str(info.value).startswith("cam3: ") and isinstance(info.value, ValueError)


def test_missing_rate_says_where_to_give_it():
    with pytest.raises(ConfigError, match="missing key `rate_hz`.*Kalibr files have no frame rate"):
        Camera.from_kalibr(EUROC_CAM0)


# ------------------------------------------------------------------------------ camchain files


def test_camchain_round_trip_through_pyyaml(tmp_path):
    cams = two_cameras()
    path = write_camchain(tmp_path / "camchain.yaml", cams)
    data = yaml.safe_load(path.read_text())
    assert list(data) == ["cam0", "cam1"]
    for cam in cams:
        entry = data[cam.name]
        assert entry["T_cam_imu"] == cam.cam_T_imu.tolist()
        assert entry["intrinsics"] == list(cam.intrinsics)
        assert entry["distortion_coeffs"] == list(cam.distortion_coeffs)
        assert entry["distortion_model"] == cam.distortion_model and entry["camera_model"] == "pinhole"
        assert entry["resolution"] == list(cam.resolution)
        assert entry["timeshift_cam_imu"] == cam.timeshift_cam_imu_s
        assert (entry["rate_hz"], entry["line_delay_s"], entry["pixel_noise_px"]) == \
            (cam.rate_hz, cam.line_delay_s, cam.pixel_noise_px)
        assert entry["rostopic"] == f"/{cam.name}/image_raw"
    # Kalibr's baseline: camera 1 from camera 0
    T10 = np.array(data["cam1"]["T_cn_cnm1"])
    assert np.abs(T10 @ cams[0].cam_T_imu - cams[1].cam_T_imu).max() < 1e-12
    assert load_camchain(path) == {c.name: c for c in cams}
    # the text is what Kalibr's own writer makes of the same mapping
    kalibr_text = yaml.dump(data, default_flow_style=None, width=2147483647)
    assert path.read_text() == kalibr_text


def test_openvins_chain_is_read_by_opencv_filestorage(tmp_path):
    cams = two_cameras()
    path = write_openvins_imucam_chain(tmp_path / "kalibr_imucam_chain.yaml", cams)
    text = path.read_text()
    assert text.startswith("%YAML:1.0\n") and "timeshift_cam_imu of cam0 only" in text
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    try:
        for i, cam in enumerate(cams):
            node = fs.getNode(f"cam{i}")
            T = np.array([[node.getNode("T_imu_cam").at(r).at(c).real() for c in range(4)] for r in range(4)])
            assert np.abs(T @ cam.cam_T_imu - np.eye(4)).max() < 1e-12
            intr = [node.getNode("intrinsics").at(j).real() for j in range(4)]
            dist = [node.getNode("distortion_coeffs").at(j).real() for j in range(4)]
            assert intr == list(cam.intrinsics) and dist == list(cam.distortion_coeffs)
            assert node.getNode("distortion_model").string() == cam.distortion_model
            assert [int(node.getNode("resolution").at(j).real()) for j in range(2)] == list(cam.resolution)
            assert node.getNode("timeshift_cam_imu").real() == cam.timeshift_cam_imu_s
    finally:
        fs.release()
    back = load_camchain(path, defaults={"rate_hz": 20.0})  # and we read OpenVINS's form too
    assert np.abs(back["cam1"].cam_T_imu - cams[1].cam_T_imu).max() < 1e-12


def test_camchain_file_errors_name_the_file_and_line(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("cam0:\n  intrinsics: [1, 1, 0, 0]\n  resolution: [4, 4]\n  rate_hz: 0\n")
    with pytest.raises(ConfigError, match="bad.yaml:4: cam0: `rate_hz` must be positive") as info:
        load_camchain(p)
    assert info.value.line == 4 and info.value.option == "cam0.rate_hz"
    p.write_text("cam0:\n  intrinsics: [1, 1, 0, 0]\n  resolution: [4, 4]\n")
    with pytest.raises(ConfigError, match="bad.yaml:1: cam0: missing key `rate_hz`"):
        load_camchain(p)
    p.write_text("imu0: {}\n")
    with pytest.raises(ConfigError, match="camera names must be cam0, cam1"):
        load_camchain(p)
    p.write_text("cam0: [1, 2\n")
    with pytest.raises(ConfigError, match="invalid YAML"):
        load_camchain(p)
    with pytest.raises(ConfigError, match="camchain not found"):
        load_camchain(tmp_path / "missing.yaml")


# ------------------------------------------------------------------------------ landmarks


def test_landmarks_csv_round_trip_keeps_ids(tmp_path):
    lm = Landmarks([1000, 3, 42], [[0.1, 2.0, -3.5], [1 / 3, 1e-17, 5e20], [0.0, -0.0, 7.0]])
    path = write_landmarks_csv(tmp_path / "landmarks.csv", lm)
    back = Landmarks.from_csv(path)
    assert back == lm and back.id.tolist() == [1000, 3, 42]


@pytest.mark.parametrize("text, message, line", [
    ("x,y,z\n1,2,3\n", "expected the header `id,x,y,z`", 1),
    ("id,x,y,z\n1,2,3\n", "expected 4 comma-separated values", 2),
    ("id,x,y,z\n1.5,2,3,4\n", "landmark id must be a whole number", 2),
    ("id,x,y,z\n1,2,b,4\n", "x, y, z must be numbers", 2),
    ("id,x,y,z\n1,2,3,4\n\n1,5,6,7\n", "landmark id 1 already on line 2", 4),
    ("id,x,y,z\n1,2,nan,4\n", "finite", 2),
])
def test_landmarks_csv_errors_give_the_line(tmp_path, text, message, line):
    p = tmp_path / "points.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        Landmarks.from_csv(p)
    assert info.value.line == line and info.value.path == str(p)


def test_random_landmarks_are_seeded_and_in_shape():
    scene = make_scene("ellipse", duration_s=20.0)
    a = Landmarks.random(2000, "shell", source=scene, rng=7)
    assert a == Landmarks.random(2000, "shell", source=scene, rng=np.random.default_rng(7))
    assert a != Landmarks.random(2000, "shell", source=scene, rng=8)
    pos, _ = scene.pose(np.linspace(0, 20, 1001))
    centre = 0.5 * (pos.min(0) + pos.max(0))
    R = np.linalg.norm(pos - centre, axis=1).max()
    r = np.linalg.norm(a.position_world - centre, axis=1)
    assert r.min() >= R + 2 - 1e-9 and r.max() <= R + 10 + 1e-9
    # uniform in volume: the fraction inside the middle radius is (rm^3 - r0^3) / (r1^3 - r0^3)
    r0, r1 = R + 2, R + 10
    rm = 0.5 * (r0 + r1)
    assert abs(np.mean(r < rm) - (rm**3 - r0**3) / (r1**3 - r0**3)) < 0.04
    box = Landmarks.random(3000, "box", source=scene, margin_m=4.0, rng=1)
    lo, hi = pos.min(0) - 4.0, pos.max(0) + 4.0
    p = box.position_world
    assert np.all(p >= lo - 1e-9) and np.all(p <= hi + 1e-9)
    assert np.all(np.any(np.isclose(p, lo) | np.isclose(p, hi), axis=1))
    with pytest.raises(ConfigError, match="needs `center` or a motion source"):
        Landmarks.random(10, "shell")
    with pytest.raises(ConfigError, match="`shape` must be one of shell, box"):
        Landmarks.random(10, "sphere", center=[0, 0, 0], radii_m=(1, 2))


# ------------------------------------------------------------------------------ features.csv


def test_features_csv_is_exact_and_atomic(tmp_path):
    from types import SimpleNamespace

    rng = np.random.default_rng(0)
    obs = SimpleNamespace(t_ns=np.repeat(np.arange(5, dtype=np.int64) * 50_000_000 + 1403715524907143168, 20),
                          landmark_id=np.tile(np.arange(20), 5), u=rng.uniform(0, 752, 100), v=rng.uniform(0, 480, 100))
    path = tmp_path / "features.csv"
    path.write_text("old\n")
    write_features_csv(path, obs)
    back = read_features_csv(path)
    assert np.array_equal(back["t_ns"], obs.t_ns) and np.array_equal(back["u"], obs.u)
    assert np.array_equal(back["v"], obs.v) and np.array_equal(back["landmark_id"], obs.landmark_id)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["features.csv"]  # no temporary file left


# ------------------------------------------------------------------------------ scene-file values, output files


def test_scene_values_and_output_files(tmp_path):
    from splineimu.camera import cameras_from_config, landmarks_from_config, observe
    from splineimu.io.camera import write_camera_outputs

    write_camchain(tmp_path / "kalibr.yaml", two_cameras())
    text = (tmp_path / "kalibr.yaml").read_text().replace("  rate_hz: 20.0\n", "")  # as Kalibr writes it
    (tmp_path / "kalibr.yaml").write_text(text)
    cams = cameras_from_config({"file": "kalibr.yaml", "rate_hz": 10.0}, base_dir=tmp_path)
    assert [c.rate_hz for c in cams.values()] == [10.0, 10.0]
    assert cams["cam1"].pixel_noise_px == 0.75  # the file's own value wins over a default
    write_landmarks_csv(tmp_path / "points.csv", Landmarks([5, 6], [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]))
    assert landmarks_from_config({"file": "points.csv"}, base_dir=tmp_path).id.tolist() == [5, 6]
    scene = make_scene("ellipse", duration_s=1.0)
    lm = landmarks_from_config({"random": {"count": 300, "shape": "shell", "radii_m": [3, 30]}}, source=scene, rng=2)
    for bad in ({"file": "a.csv", "random": {}}, {"random": {"count": 3, "radius": 2}}, {"points": 3}):
        with pytest.raises(ConfigError, match="landmarks"):
            landmarks_from_config(bad, source=scene)
    obs = observe(scene, cams, lm, rng=0)
    paths = write_camera_outputs(tmp_path / "out", cams, obs, lm)
    assert {str(p.relative_to(tmp_path / "out")) for p in paths} == {
        "mav0/cam0/features.csv", "mav0/cam1/features.csv", "landmarks.csv", "camchain.yaml",
        "kalibr_imucam_chain.yaml"}
    back = read_features_csv(tmp_path / "out" / "mav0" / "cam1" / "features.csv")
    assert np.array_equal(back["u"], obs["cam1"].u) and np.array_equal(back["t_ns"], obs["cam1"].t_ns)
    chain = yaml.safe_load((tmp_path / "out" / "camchain.yaml").read_text())
    assert chain["cam0"]["cam_overlaps"] == ([1] if np.intersect1d(obs["cam0"].landmark_id,
                                                                    obs["cam1"].landmark_id).size else [])
    assert Landmarks.from_csv(tmp_path / "out" / "landmarks.csv") == lm


def test_scene_file_errors_point_at_the_line():
    from splineimu.camera import cameras_from_config
    from splineimu.io.yaml import parse_yaml

    doc = parse_yaml("duration_s: 3\ncameras:\n  cam0:\n    intrinsics: [1, 1, 0, 0]\n    resolution: [4, 4]\n"
                     "    rate_hz: 20\n    distortion_model: radial\n", "scene.yaml")
    with pytest.raises(ConfigError, match="scene.yaml:7: cam0: `distortion_model` must be one of") as info:
        cameras_from_config(doc.data["cameras"], doc=doc)
    assert info.value.option == "cameras.cam0.distortion_model"
