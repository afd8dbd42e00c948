"""Cameras in scene files and synthesis jobs, end to end through run_job (issue 18 acceptance).

The scene is examples/camera_scene.yaml (analytic ellipse, cam0 radtan global shutter with a
positive time shift, cam1 equidistant rolling shutter with a negative one, 1,500 random
landmarks) with a shorter duration; the checks read the files written.
"""

from __future__ import annotations

import filecmp
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, load_scene_file, run_job
from splineimu.errors import ConfigError
from splineimu.scenes import make_scene

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "camera_scene.yaml"
DURATION_S = 3.0


def scene_dict(noise=None, cameras=True, plot=False):
    d = yaml.safe_load(EXAMPLE.read_text())
    d["motion"]["duration_s"] = DURATION_S
    d["output"] = {"dir": "out", "plot": plot}
    if not cameras:
        del d["cameras"], d["landmarks"]
    elif noise is not None:
        for cam in d["cameras"].values():
            cam["pixel_noise_px"] = noise
    return d


def run_scene(folder: Path, d: dict):
    folder.mkdir(parents=True)
    (folder / "scene.yaml").write_text(yaml.safe_dump(d, sort_keys=False))
    res = run_job(load_scene_file(folder / "scene.yaml"))
    return folder / "out", res


def read_features(path):
    rows = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
    return rows[:, 0].astype(np.int64), rows[:, 1].astype(np.int64), rows[:, 2], rows[:, 3]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("camera_scene")
    return {"exact": run_scene(base / "exact", scene_dict(noise=0.0)),
            "noisy": run_scene(base / "noisy", scene_dict()),
            "again": run_scene(base / "again", scene_dict()),
            "imu_only": run_scene(base / "imu_only", scene_dict(cameras=False))}


def cam_T_world(scene, cam_T_imu, t_s):
    """(R, t) of world -> camera at source times ``t_s`` (body = IMU: the example has no extrinsic)."""
    pos, quat = scene.pose(np.atleast_1d(np.asarray(t_s, dtype=np.float64)))
    w_R_b = Rotation.from_quat(quat).as_matrix()
    c_R_w = cam_T_imu[:3, :3] @ np.swapaxes(w_R_b, 1, 2)
    c_t_w = cam_T_imu[:3, 3] - np.einsum("nij,nj->ni", c_R_w, pos)
    return c_R_w, c_t_w


def opencv_project(cv2, cam, R, t, points):
    K = np.array([[cam["intrinsics"][0], 0, cam["intrinsics"][2]], [0, cam["intrinsics"][1], cam["intrinsics"][3]],
                  [0, 0, 1.0]])
    D = np.asarray(cam["distortion_coeffs"], dtype=np.float64)
    rvec = cv2.Rodrigues(R)[0]
    p = np.asarray(points, dtype=np.float64).reshape(-1, 1, 3)
    if cam["distortion_model"] == "equidistant":
        uv, _ = cv2.fisheye.projectPoints(p, rvec, t.reshape(3, 1), K, D)
    else:
        uv, _ = cv2.projectPoints(p, rvec, t, K, D)
    return uv.reshape(-1, 2)


def test_noise_free_observations_match_opencv_at_the_right_time(runs):
    cv2 = pytest.importorskip("cv2")
    out, _ = runs["exact"]
    spec = scene_dict()["cameras"]
    scene = make_scene("ellipse", duration_s=DURATION_S)
    lm = np.loadtxt(out / "landmarks.csv", delimiter=",", skiprows=1, ndmin=2)
    assert lm.shape == (1500, 4) and lm[:, 0].tolist() == list(range(1500))
    for name, cam in spec.items():
        t_ns, ids, u, v = read_features(out / "mav0" / name / "features.csv")
        assert t_ns.size > 1000
        T = np.asarray(cam["T_cam_imu"])
        t_s = t_ns / 1e9 + cam["timeshift_cam_imu"] + v * cam["line_delay_s"]  # row time (rolling shutter)
        worst = 0.0
        for k in np.unique(np.linspace(0, t_ns.size - 1, 800).astype(int)):
            R, t = cam_T_world(scene, T, t_s[k])
            ref = opencv_project(cv2, cam, R[0], t[0], lm[ids[k], 1:])
            worst = max(worst, float(np.abs(ref - [u[k], v[k]]).max()))
        print(f"{name}: {worst:.3g} px from OpenCV")
        assert worst < 1e-3, f"{name}: {worst:.3g} px from OpenCV"


def test_global_shutter_sees_exactly_the_visible_landmarks(runs):
    cv2 = pytest.importorskip("cv2")
    out, _ = runs["exact"]
    cam = scene_dict()["cameras"]["cam0"]
    scene = make_scene("ellipse", duration_s=DURATION_S)
    lm = np.loadtxt(out / "landmarks.csv", delimiter=",", skiprows=1, ndmin=2)
    t_ns, ids, _, _ = read_features(out / "mav0" / "cam0" / "features.csv")
    frames = np.unique(t_ns)
    for f in frames[:: max(1, frames.size // 12)]:
        R, t = cam_T_world(scene, np.asarray(cam["T_cam_imu"]), f / 1e9 + cam["timeshift_cam_imu"])
        depth = lm[:, 1:] @ R[0].T + t[0]
        uv = opencv_project(cv2, cam, R[0], t[0], lm[:, 1:])
        w, h = cam["resolution"]
        seen = (depth[:, 2] > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)
        assert sorted(lm[seen, 0].astype(int).tolist()) == sorted(ids[t_ns == f].tolist())


def test_frame_stamps_lie_on_the_camera_rate_grid(runs):
    out, res = runs["exact"]
    spec = scene_dict()["cameras"]
    for name, cam in spec.items():
        rep = res.report["cameras"][name]
        first, rate = rep["first_ns"], cam["rate_hz"]
        k = np.arange(rep["frames"])
        grid = first + np.round(k * 1e9 / rate).astype(np.int64)
        assert grid[-1] == rep["last_ns"]
        t_ns, _, _, _ = read_features(out / "mav0" / name / "features.csv")
        assert np.isin(np.unique(t_ns), grid).all()
        # the first frame is the earliest one whose start is inside the motion; the last row of the last frame too
        start = cam["timeshift_cam_imu"]
        assert first / 1e9 + start >= 0 > first / 1e9 + start - 1 / rate
        readout = cam["line_delay_s"] * cam["resolution"][1]
        assert grid[-1] / 1e9 + start + readout <= DURATION_S < grid[-1] / 1e9 + start + readout + 1 / rate
        assert rep["shutter"] == ("rolling" if cam["line_delay_s"] else "global")


def test_camchain_holds_the_scene_values(runs):
    out, _ = runs["noisy"]
    chain = yaml.safe_load((out / "camchain.yaml").read_text())
    for name, cam in scene_dict()["cameras"].items():
        for key, value in cam.items():
            assert np.allclose(chain[name][key], value, rtol=0, atol=0) if not isinstance(value, str) \
                else chain[name][key] == value, (name, key)


def test_pixel_noise_is_white_with_the_given_std(runs):
    exact, _ = runs["exact"]
    noisy, res = runs["noisy"]
    du, dv = [], []
    for name in ("cam0", "cam1"):
        a = read_features(exact / "mav0" / name / "features.csv")
        b = read_features(noisy / "mav0" / name / "features.csv")
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])  # visibility is decided before the noise
        du.append(b[2] - a[2])
        dv.append(b[3] - a[3])
        o = res.observations[name]
        assert np.array_equal(o.u - o.u_exact, b[2] - a[2])
    for d in (np.concatenate(du), np.concatenate(dv)):
        assert d.size > 20_000
        assert abs(d.std() - 1.0) < 0.05 and abs(d.mean()) < 0.02
    assert abs(np.corrcoef(np.concatenate(du), np.concatenate(dv))[0, 1]) < 0.02


def test_same_seed_same_bytes_and_imu_unchanged_by_cameras(runs):
    a, _ = runs["noisy"]
    b, _ = runs["again"]
    imu_only, _ = runs["imu_only"]
    files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert Path("mav0/cam1/features.csv") in files and Path("landmarks.csv") in files
    assert sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file()) == files
    for f in files:
        assert filecmp.cmp(a / f, b / f, shallow=False), f
    imu_files = [p.relative_to(imu_only) for p in imu_only.rglob("*") if p.is_file() and p.name != "report.json"]
    assert len(imu_files) >= 4
    for f in imu_files:
        assert filecmp.cmp(a / f, imu_only / f, shallow=False), f


def test_report_and_summary(runs):
    _, res = runs["noisy"]
    rep = res.report
    assert rep["landmarks"] == {"count": 1500, "source": "random shell (seeded from the run's seed)",
                                "file": "landmarks.csv"}
    assert rep["cameras"]["cam0"]["rate_hz"] == 20.0 and rep["cameras"]["cam1"]["shutter"] == "rolling"
    assert rep["cameras"]["cam1"]["observations"] == len(res.observations["cam1"])
    assert any(line.startswith("cameras ") and "cam1" in line for line in res.lines)


def test_imu_only_jobs_do_not_load_the_camera_library(tmp_path):
    code = ("import sys\nfrom splineimu.api import SynthesisJob, SceneInput, ImuOptions, OutputOptions\n"
            "from splineimu.api.synthesis import run_job\n"
            f"run_job(SynthesisJob(SceneInput('static', duration_s=0.5), ImuOptions(rate_hz=50),"
            f" OutputOptions({str(tmp_path / 'out')!r})))\n"
            "assert 'splineimu.camera' not in sys.modules, [m for m in sys.modules if 'camera' in m]\n")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_plot_and_pose_file_input(tmp_path):
    """A pose file's spline moves the cameras too; with plot on, one frame's plot per camera."""
    d = scene_dict(plot=True)
    d["motion"] = {"poses": str(EXAMPLE.parent / "ellipse_mocap.tum")}
    d["landmarks"]["random"]["count"] = 200
    for cam in d["cameras"].values():
        cam["rate_hz"] = 2.0
    out, res = run_scene(tmp_path / "poses", d)
    assert {"cam0_frame.png", "cam1_frame.png"} <= set(res.report["plots"])
    assert (out / "cam1_frame.png").stat().st_size > 1000
    assert len(res.observations["cam1"]) > 0 and (out / "mav0" / "cam0" / "features.csv").exists()


def test_cameras_have_no_command_line(tmp_path):
    from splineimu.cli import main

    f = tmp_path / "scene.yaml"
    f.write_text(yaml.safe_dump(scene_dict()))
    with pytest.raises(ConfigError, match="cameras are only available from scene files"):
        load_scene_file(f).to_argv()
    assert main(["run", str(f), "--print"]) != 0


def test_python_jobs_take_camera_objects(tmp_path):
    from splineimu.camera import Camera, Landmarks

    cam = Camera((300.0, 300.0, 320.0, 240.0), (640, 480), rate_hz=5.0, name="cam0",
                 cam_T_imu=[[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0], [0, 0, 0, 1]])
    lm = Landmarks.random(100, center=[0, 0, 0], radii_m=(5, 20), rng=0)
    job = SynthesisJob(SceneInput("ellipse", duration_s=1.0), ImuOptions(rate_hz=50, seed=1),
                       OutputOptions(str(tmp_path / "out")), cameras=[cam], landmarks=lm)
    assert list(job.cameras) == ["cam0"]
    res = run_job(job)
    assert res.report["landmarks"]["source"] == "given" and res.report["cameras"]["cam0"]["frames"] == 6
    with pytest.raises(ConfigError, match="need `landmarks`"):
        SynthesisJob(SceneInput("static"), cameras=[cam])
    with pytest.raises(ConfigError, match="need `cameras`"):
        SynthesisJob(SceneInput("static"), landmarks=lm)


@pytest.mark.parametrize("change, line, message", [
    (lambda d: d["cameras"]["cam0"].update(rate_hz=-20), "rate_hz: -20", "must be positive"),
    (lambda d: d["cameras"].update(camera0=d["cameras"].pop("cam0")), "camera0:", "cam0, cam1"),
    (lambda d: d["landmarks"]["random"].update(cout=5), "cout: 5", "did you mean `count`"),
    (lambda d: d["landmarks"]["random"].update(count=-5), "count: -5", "count"),
    (lambda d: d.update(landmarks={"file": "missing.csv"}), "landmarks:", "missing.csv"),
    (lambda d: d.pop("cameras"), "landmarks:", "need `cameras`"),
])
def test_scene_file_errors_give_the_file_and_line(tmp_path, change, line, message):
    d = scene_dict()
    change(d)
    f = tmp_path / "scene.yaml"
    text = yaml.safe_dump(d, sort_keys=False, default_flow_style=False)
    f.write_text(text)
    with pytest.raises((ConfigError, ValueError)) as info:
        load_scene_file(f)
    err = info.value
    assert message in str(err)
    if "missing.csv" not in message:
        expected = next(i for i, t in enumerate(text.splitlines(), start=1) if t.strip().startswith(line))
        assert err.line == expected and Path(err.path).name == "scene.yaml", str(err)


def test_trimmed_ends_trim_the_camera_frames_too(tmp_path):
    """motion.spline.trim_ends_s: the frames (on IMU time) keep to the trimmed record as the IMU
    samples do."""
    d = scene_dict()
    d["motion"] = {"poses": str(EXAMPLE.parent / "ellipse_mocap.tum"), "spline": {"trim_ends_s": 2.0}}
    d["landmarks"]["random"]["count"] = 50
    for cam in d["cameras"].values():
        cam["rate_hz"] = 4.0
    out, res = run_scene(tmp_path / "poses", d)
    from splineimu.io.imu_csv import read_imu_csv
    from splineimu.io.tum import read_tum

    t_imu = read_imu_csv(out / "mav0" / "imu0" / "data.csv")[0]
    t_poses = read_tum(EXAMPLE.parent / "ellipse_mocap.tum").t_ns
    t0_ns, t1_ns = int(t_poses[0]), int(t_poses[-1])
    assert t_imu[0] >= t0_ns + 2_000_000_000 and t_imu[-1] <= t1_ns - 2_000_000_000
    for name, cam in d["cameras"].items():
        shift_ns = int(round(cam.get("timeshift_cam_imu", 0.0) * 1e9))
        frames = res.observations[name].frame_t_ns + shift_ns  # on the IMU's clock
        assert frames.min() >= t0_ns + 2_000_000_000 and frames.max() <= t1_ns - 2_000_000_000, name
