"""Camera observations against OpenCV, brute force and the analytic ellipse scene (issue 18).

Acceptance set-up: exact poses of the analytic "ellipse" scene, two cameras (radtan global
shutter with a positive time shift, equidistant rolling shutter with a negative one),
1,500 landmarks.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from splineimu.camera import Camera, Landmarks, observe
from splineimu.camera.observations import frame_stamps_ns, observe_camera
from splineimu.io.camera import write_features_csv
from splineimu.motion import MotionSource
from splineimu.scenes import make_scene

cv2 = pytest.importorskip("cv2")

# camera looks along body x (forward), image x = -body y, image y = -body z; small lever arm
CAM_T_IMU = np.array([[0.0, -1.0, 0.0, 0.05], [0.0, 0.0, -1.0, -0.01], [1.0, 0.0, 0.0, 0.02], [0.0, 0.0, 0.0, 1.0]])
CAM_T_IMU_SIDE = np.array([[1.0, 0.0, 0.0, -0.05], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
RADTAN = Camera((458.654, 457.296, 367.215, 248.375), (752, 480), "radtan",
                (-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05), cam_T_imu=CAM_T_IMU, rate_hz=20.0,
                timeshift_cam_imu_s=0.0123, pixel_noise_px=1.0, name="cam0")
FISHEYE = Camera((190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504), (512, 512),
                 "equidistant", (0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202,
                                 0.00020293673591811182),
                 cam_T_imu=CAM_T_IMU_SIDE, rate_hz=30.0, timeshift_cam_imu_s=-0.0071, line_delay_s=4e-5,
                 pixel_noise_px=1.0, name="cam1")
DURATION_S = 3.0


@pytest.fixture(scope="module")
def scene():
    return make_scene("ellipse", duration_s=DURATION_S)


@pytest.fixture(scope="module")
def landmarks(scene):
    return Landmarks.random(1500, "shell", source=scene, radii_m=(3.0, 30.0), rng=11)


@pytest.fixture(scope="module")
def obs(scene, landmarks):
    return observe(scene, [RADTAN, FISHEYE], landmarks, rng=5)


# ------------------------------------------------------------------------------ independent helpers


def cam_from_world(scene, cam, t_s):
    """cam_R_world (N, 3, 3), cam_t_world (N, 3) through scipy's quaternion conversion."""
    pos, quat = scene.pose(np.atleast_1d(t_s))
    world_R_body = Rotation.from_quat(quat).as_matrix()
    R_ci, t_ci = cam.cam_T_imu[:3, :3], cam.cam_T_imu[:3, 3]
    R = R_ci @ np.transpose(world_R_body, (0, 2, 1))
    return R, t_ci - np.einsum("nij,nj->ni", R, pos)


def cv_project(cam, R, t, points):
    """OpenCV's projection of world points with cam_T_world = (R, t)."""
    rvec, _ = cv2.Rodrigues(R)
    K = cam.camera_matrix
    D = np.array(cam.distortion_coeffs)
    if cam.distortion_model == "equidistant":
        uv, _ = cv2.fisheye.projectPoints(points.reshape(-1, 1, 3), rvec, t.reshape(3, 1), K, D)
    else:
        uv, _ = cv2.projectPoints(points.reshape(-1, 1, 3), rvec, t.reshape(3, 1), K, D)
    return uv.reshape(-1, 2)


def extended_v(cam, p):
    """Row of camera-frame points, continuous through Z = 0 for the fisheye (test's own formula)."""
    X, Y, Z = p[..., 0], p[..., 1], p[..., 2]
    fu, fv, pu, pv = cam.intrinsics
    if cam.distortion_model == "equidistant":
        k = cam.distortion_coeffs
        rho = np.hypot(X, Y)
        th = np.arctan2(rho, Z)
        thd = th * (1 + k[0] * th**2 + k[1] * th**4 + k[2] * th**6 + k[3] * th**8)
        with np.errstate(invalid="ignore", divide="ignore"):
            return fu * np.where(rho > 0, X * thd / rho, 0) + pu, fv * np.where(rho > 0, Y * thd / rho, 0) + pv
    with np.errstate(invalid="ignore", divide="ignore"):
        uv = cam.project(np.stack([X, Y, np.where(Z > 0, Z, np.nan)], axis=-1))
    v = np.where(Z > 0, uv[..., 1], np.copysign(np.inf, Y))
    return uv[..., 0], v


def brute_force_rows(source, cam, points, frame_s, want_behind=False):
    """Set of (frame index, landmark index) observed by scanning every row (step 1 px) and bisecting."""
    ld, h = cam.line_delay_s, cam.height
    rows = np.arange(h + 1, dtype=np.float64)
    found, borderline, behind = set(), set(), set()
    for fi, t0 in enumerate(frame_s):
        R, t = cam_from_world(source, cam, t0 + rows * ld)
        p = np.einsum("sij,mj->smi", R, points) + t[:, None, :]
        _, v = extended_v(cam, p)
        res = v - rows[:, None]
        sign_change = (res[:-1] >= 0) != (res[1:] >= 0)
        s_idx, m_idx = np.nonzero(sign_change & ((p[:-1, :, 2] > 0) | (p[1:, :, 2] > 0)))
        lo, hi = rows[s_idx], rows[s_idx + 1]
        flo = res[s_idx, m_idx]
        for _ in range(50):  # bisection
            mid = 0.5 * (lo + hi)
            Rm, tm = cam_from_world(source, cam, t0 + mid * ld)
            pm = np.einsum("nij,nj->ni", Rm, points[m_idx]) + tm
            fm = extended_v(cam, pm)[1] - mid
            left = (fm >= 0) == (flo >= 0)
            lo, flo = np.where(left, mid, lo), np.where(left, fm, flo)
            hi = np.where(left, hi, mid)
        row = 0.5 * (lo + hi)
        Rm, tm = cam_from_world(source, cam, t0 + row * ld)
        pm = np.einsum("nij,nj->ni", Rm, points[m_idx]) + tm
        u, v = extended_v(cam, pm)
        real = np.abs(v - row) < 1e-4
        inside = real & (pm[:, 2] > 0) & cam.in_image(u, v)
        near = real & (pm[:, 2] > 0) & (np.abs(np.minimum.reduce([u, cam.width - u, v, cam.height - v])) < 1e-6)
        found |= {(fi, int(m)) for m in m_idx[inside]}
        borderline |= {(fi, int(m)) for m in m_idx[near]}
        behind |= {(fi, int(m)) for m in m_idx[real & (pm[:, 2] <= 0) & cam.in_image(u, v)]}
    if want_behind:
        return found, borderline, behind
    return found, borderline


# ------------------------------------------------------------------------------ tests


def test_frames_on_the_camera_grid_and_covering_the_motion(scene, obs):
    for cam in (RADTAN, FISHEYE):
        o = obs[cam.name]
        t = o.frame_t_ns
        k = np.arange(t.size)
        assert np.array_equal(t - t[0], np.rint(k * (1e9 / cam.rate_hz)).astype(np.int64))
        start = (t - scene.origin_ns) / 1e9 + cam.timeshift_cam_imu_s
        assert start[0] >= scene.t_min_s and start[0] - 1e-9 < scene.t_min_s  # first: earliest ns inside
        assert start[-1] + cam.readout_s <= scene.t_max_s
        assert start[-1] + 1.0 / cam.rate_hz + cam.readout_s > scene.t_max_s  # none left out at the end
        assert np.all(np.isin(o.t_ns, t)) and np.all(np.diff(o.t_ns) >= 0)
    assert obs["cam0"].frame_t_ns[0] == -12_300_000  # t_imu = t_cam + 0.0123 s starts at 0


def test_noise_free_projection_matches_opencv_at_the_capture_time(scene, landmarks, obs):
    worst = {}
    for cam in (RADTAN, FISHEYE):
        o = obs[cam.name]
        assert len(o) > 1000
        frame_s = (o.t_ns - scene.origin_ns) / 1e9 + cam.timeshift_cam_imu_s
        # the capture time is the frame's start plus the observed row's delay (row solved to 1e-6 px)
        np.testing.assert_allclose(o.t_capture_s, frame_s + o.v_exact * cam.line_delay_s, rtol=0,
                                   atol=1e-6 * cam.line_delay_s + 1e-12)
        points = landmarks.position_world[np.searchsorted(landmarks.id, o.landmark_id)]
        pick = np.random.default_rng(0).choice(len(o), size=min(len(o), 2500), replace=False)
        err = []
        for i in pick:
            R, t = cam_from_world(scene, cam, o.t_capture_s[i])
            uv = cv_project(cam, R[0], t[0], points[i][None])[0]
            err.append(np.abs(uv - [o.u_exact[i], o.v_exact[i]]).max())
        worst[cam.name] = max(err)
    print("largest difference to OpenCV [px]:", worst)
    assert worst["cam0"] < 1e-3 and worst["cam1"] < 1e-3, worst


def test_global_shutter_sees_exactly_the_visible_landmarks(scene, landmarks, obs):
    cam, o = RADTAN, obs["cam0"]
    points = landmarks.position_world
    frame_s = (o.frame_t_ns - scene.origin_ns) / 1e9 + cam.timeshift_cam_imu_s
    R, t = cam_from_world(scene, cam, frame_s)
    for fi in range(0, o.frame_t_ns.size, 3):
        depth = points @ R[fi][2] + t[fi][2]
        uv = cv_project(cam, R[fi], t[fi], points)
        inside = (depth > 0) & cam.in_image(uv[:, 0], uv[:, 1])
        margin = np.minimum.reduce([uv[:, 0], cam.width - uv[:, 0], uv[:, 1], cam.height - uv[:, 1]])
        seen = np.isin(landmarks.id, o.landmark_id[o.t_ns == o.frame_t_ns[fi]])
        differ = (seen != inside) & ~((depth > 0) & (np.abs(margin) < 1e-6))
        assert not np.any(differ), f"frame {fi}: {np.flatnonzero(differ)}"


def test_rolling_shutter_sees_exactly_the_landmarks_a_row_scan_finds(scene, landmarks, obs):
    cam, o = FISHEYE, obs["cam1"]
    frame_s = (o.frame_t_ns - scene.origin_ns) / 1e9 + cam.timeshift_cam_imu_s
    frames = np.arange(0, frame_s.size, 11)
    expected, borderline = brute_force_rows(scene, cam, landmarks.position_world, frame_s[frames])
    got = set()
    for j, fi in enumerate(frames):
        ids = o.landmark_id[o.t_ns == o.frame_t_ns[fi]]
        got |= {(j, int(m)) for m in np.searchsorted(landmarks.id, ids)}
    assert len(expected) > 500
    print(f"{len(expected)} expected, {len(got)} observed, {len(borderline)} within 1e-6 px of the border")
    assert (got ^ expected) <= borderline, sorted(got ^ expected)[:10]


def test_rolling_shutter_row_and_time_agree(scene, landmarks, obs):
    cam, o = FISHEYE, obs["cam1"]
    points = landmarks.position_world[np.searchsorted(landmarks.id, o.landmark_id)]
    R, t = cam_from_world(scene, cam, o.t_capture_s)
    p = np.einsum("nij,nj->ni", R, points) + t
    _, v = extended_v(cam, p)
    assert np.abs(v - o.v_exact).max() < 1e-3
    assert np.all(p[:, 2] > 0)
    assert o.v_exact.max() > 0.9 * cam.height  # rows over the whole readout are used


class Tumble(MotionSource):
    """A body at the origin turning about its x axis at ``rate`` rad/s (pure rotation)."""

    def __init__(self, rate, duration_s):
        self.rate, self.t_min_s, self.t_max_s, self.origin_ns = rate, 0.0, duration_s, 0

    def pose(self, t_s):
        t = self.check_times(t_s)
        return np.zeros((t.size, 3)), Rotation.from_rotvec(np.outer(self.rate * t, [1.0, 0.0, 0.0])).as_quat()


def test_fisheye_point_crossing_behind_during_readout_counts_only_with_positive_depth():
    # 120 px focal length: a ray at 90 deg (zero depth) lands 188 px from the centre, inside the image
    cam = Camera((120.0, 120.0, 256.0, 256.0), (512, 512), "equidistant", (0.01, -0.002, 0.0, 0.0),
                 rate_hz=10.0, line_delay_s=1e-4, name="cam0")
    source = Tumble(rate=8.0, duration_s=0.5)
    d = np.random.default_rng(2).standard_normal((3000, 3))
    points = d / np.linalg.norm(d, axis=1, keepdims=True) * 5.0
    o = observe_camera(source, cam, points)
    frame_s = o.frame_t_ns / 1e9
    expected, borderline, behind = brute_force_rows(source, cam, points, frame_s, want_behind=True)
    got = {(int(np.flatnonzero(o.frame_t_ns == t)[0]), int(m)) for t, m in zip(o.t_ns, o.landmark_id)}
    assert (got ^ expected) <= borderline
    # the scene does exercise crossings: depth changes sign during readout for observed landmarks
    R0, t0 = cam_from_world(source, cam, frame_s)
    R1, t1 = cam_from_world(source, cam, frame_s + cam.readout_s)
    crossing = set()
    for fi in range(frame_s.size):
        z0, z1 = points @ R0[fi][2], points @ R1[fi][2]
        crossing |= {(fi, int(m)) for m in np.flatnonzero((z0 > 0) != (z1 > 0))}
    print(f"{len(got)} observed, {len(crossing & got)} of them cross zero depth during the readout, "
          f"{len(crossing & behind)} crossing ones have their row only behind the camera")
    assert len(crossing & got) > 3
    # and some crossing points have their consistent row only behind the camera: not observed
    assert len(crossing & behind) >= 1 and not (behind & got)
    R, t = cam_from_world(source, cam, o.t_capture_s)
    assert np.all(np.einsum("nij,nj->ni", R, points[o.landmark_id])[:, 2] > 0)


def test_pixel_noise_is_white_with_the_configured_std(obs):
    for o in obs.values():
        for r in (o.u - o.u_exact, o.v - o.v_exact):
            assert r.size > 5000
            print(o.camera.name, r.size, "std", r.std(), "mean", r.mean())
            assert abs(r.std() - 1.0) < 0.05, r.std()
            assert abs(r.mean()) < 5.0 / np.sqrt(r.size)
            # white: neighbouring rows are uncorrelated
            assert abs(np.corrcoef(r[:-1], r[1:])[0, 1]) < 5.0 / np.sqrt(r.size)


def test_same_seed_same_bytes(scene, landmarks, tmp_path):
    def run(seed, cams, name):
        o = observe(scene, cams, landmarks, rng=seed)["cam1"]
        return write_features_csv(tmp_path / name, o).read_bytes()

    a = run(3, [RADTAN, FISHEYE], "a.csv")
    assert a == run(3, [RADTAN, FISHEYE], "b.csv")
    assert a == run(3, [FISHEYE], "c.csv")  # a camera's noise does not depend on the others
    assert a != run(4, [RADTAN, FISHEYE], "d.csv")
    lines = a.decode().splitlines()
    assert lines[0] == "#timestamp_ns,landmark_id,u,v"
    t, i, u, v = lines[1].split(",")
    assert int(t) % 1 == 0 and float(u) == float(repr(float(u)))


def test_body_to_imu_extrinsic_composes(scene, landmarks):
    X = np.eye(4)
    X[:3, :3] = Rotation.from_rotvec([0.1, -0.2, 0.3]).as_matrix()
    X[:3, 3] = [0.1, 0.2, -0.05]
    cam = Camera(RADTAN.intrinsics, RADTAN.resolution, "radtan", RADTAN.distortion_coeffs,
                 cam_T_imu=CAM_T_IMU @ X, rate_hz=20.0, name="cam0")
    a = observe_camera(scene, cam, landmarks, body_T_imu=X)
    b = observe_camera(scene, RADTAN, landmarks)
    assert np.array_equal(a.landmark_id, b.landmark_id)
    np.testing.assert_allclose(a.u_exact, b.u_exact, atol=1e-8)


def test_frames_need_a_long_enough_motion():
    cam = Camera((1.0, 1.0, 0.0, 0.0), (10, 1000), rate_hz=10.0, line_delay_s=1e-3)
    with pytest.raises(ValueError, match="shorter than one frame's readout"):
        frame_stamps_ns(make_scene("ellipse", duration_s=0.5), cam)


def test_importing_splineimu_does_not_load_the_camera_package():
    code = ("import sys, splineimu, splineimu.scenes, splineimu.motion; "
            "splineimu.Spline; print(any(m.startswith('splineimu.camera') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("cam", [RADTAN, FISHEYE], ids=["radtan", "equidistant"])
def test_row_bracket_kernel_agrees_with_numpy(scene, landmarks, cam):
    from splineimu.camera import observations as ob

    rows = np.linspace(0.0, cam.height, 7)
    frame_s = np.linspace(0.2, 2.5, 9)
    R, t = ob._cam_from_world(scene, cam.cam_T_imu, (frame_s[:, None] + rows * 4e-5).reshape(-1))
    args = (cam, R.reshape(9, 7, 3, 3), t.reshape(9, 7, 3), landmarks.position_world, rows)
    ref = ob._rs_brackets_numpy(*args)
    got = ob._rs_brackets_kernel(*args)
    assert ref[0].size > 50
    for a, b in zip(ref, got):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-9)


def test_unix_epoch_origin_shifts_the_stamps_only(landmarks):
    origin = 1403715524907143168  # EuRoC: beyond float64's exact integers
    a = observe_camera(make_scene("ellipse", duration_s=1.0), RADTAN, landmarks, rng=1)
    b = observe_camera(make_scene("ellipse", duration_s=1.0, t0_ns=origin), RADTAN, landmarks, rng=1)
    assert np.array_equal(b.frame_t_ns - origin, a.frame_t_ns) and np.array_equal(b.t_ns - origin, a.t_ns)
    assert np.array_equal(a.u, b.u) and np.array_equal(a.landmark_id, b.landmark_id)


def test_rolling_shutter_radtan_against_the_row_scan(scene, landmarks):
    # pinhole rows have a pole at zero depth: the search must not take it for a root
    cam = Camera(RADTAN.intrinsics, RADTAN.resolution, "radtan", RADTAN.distortion_coeffs, cam_T_imu=CAM_T_IMU_SIDE,
                 rate_hz=5.0, line_delay_s=6e-5, timeshift_cam_imu_s=0.002, name="cam0")
    o = observe_camera(scene, cam, landmarks)
    frame_s = (o.frame_t_ns - scene.origin_ns) / 1e9 + cam.timeshift_cam_imu_s
    frames = np.arange(0, frame_s.size, 4)
    expected, borderline = brute_force_rows(scene, cam, landmarks.position_world, frame_s[frames])
    got = set()
    for j, fi in enumerate(frames):
        got |= {(j, int(m)) for m in np.searchsorted(landmarks.id, o.landmark_id[o.t_ns == o.frame_t_ns[fi]])}
    assert len(expected) > 50 and (got ^ expected) <= borderline
