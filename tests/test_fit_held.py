"""Poses held by a logger (repeated exactly at later stamps): dropped before the fit, each pose
kept at its first stamp (spline/checks.py held_poses)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fit_scenes import HAND_SINES, sine_positions

from splineimu import fit, lie
from splineimu.scenes import make_scene
from splineimu.spline.checks import held_poses

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def _motion(t, noise=1e-3, seed=1):
    rng = np.random.default_rng(seed)
    p = sine_positions(t, HAND_SINES) + noise * rng.normal(size=(t.size, 3))
    R = lie.so3_exp(0.5 * sine_positions(t, HAND_SINES)) @ lie.so3_exp(np.radians(0.1) * rng.normal(size=(t.size, 3)))
    return p, lie.matrix_to_quat_xyzw(R)


def _held(t_log, t_pose, p, q):
    """The latest pose at each logging stamp (the pose stream at ``t_pose``, sampled and held)."""
    i = np.searchsorted(t_pose, t_log + 1e-12, side="right") - 1
    return p[i], q[i]


@pytest.mark.parametrize("pose_hz, log_hz", [(100.0, 200.0), (50.0, 200.0), (120.0, 200.0), (10.0, 20.0)])
def test_held_poses_are_found(pose_hz, log_hz):
    t_pose = np.arange(0.0, 20.0, 1.0 / pose_hz)
    t_log = np.arange(0.0, 20.0, 1.0 / log_hz)
    p, q = _held(t_log, t_pose, *_motion(t_pose))
    held = held_poses(p, q)
    repeat = np.r_[False, np.all(p[1:] == p[:-1], axis=1)]
    assert held is not None and np.array_equal(held, repeat)
    # what is left is the pose stream, each pose at the first stamp it was logged at
    assert np.count_nonzero(~held) == t_pose.size


def test_rests_and_measured_poses_are_not_held():
    """Exact poses with rests (still sensor: one pose repeated for seconds), a stop-and-go motion
    (0.2 s moves between 0.2 s rests), noisy poses, and a few repeats in motion (TUM RGB-D
    fr2/desk has 9 in 20 956) keep all of their poses."""
    t = np.arange(0.0, 60.0, 0.005)
    k = make_scene("six-position", duration_s=60.0).kinematics(t)
    assert held_poses(k.position_world, lie.matrix_to_quat_xyzw(k.world_R_body)) is None
    p, q = _motion(t, noise=0.0)
    still = (t % 0.4) >= 0.2  # stop and go: the pose at each rest's start held for 0.2 s
    i = np.where(still, np.searchsorted(t, np.floor(t / 0.4) * 0.4 + 0.2 - 1e-9), np.arange(t.size))
    assert held_poses(p[i], q[i]) is None
    p, q = _motion(t)
    assert held_poses(p, q) is None
    j = np.arange(t.size)
    j[1000:1010:2] -= 1  # five poses repeated once
    assert held_poses(p[j], q[j]) is None


def test_held_poses_are_fitted_as_the_poses_they_came_from():
    """100 Hz poses held at 200 Hz: the fit drops the repeats (warning poses_held, listed in
    dropped_poses) and equals the fit of the 100 Hz poses; reject_outliers=False keeps them."""
    t_pose = np.arange(0.0, 20.0, 0.01)
    t_log = np.arange(0.0, 20.0 - 0.005 + 1e-9, 0.005)
    pp, qq = _motion(t_pose)
    p, q = _held(t_log, t_pose, pp, qq)
    spl, rep = fit(t_log, p, q, return_report=True)
    ref = fit(t_pose, pp, qq)
    te = np.arange(1.0, 19.0, 0.005)
    for a, b in zip(spl.imu(te), ref.imu(te)):
        assert np.abs(a - b).max() < 1e-9
    (w,) = [w for w in rep.warnings if w.code == "poses_held"]
    assert f"{t_pose.size} of {t_log.size} poses repeat the pose before them" in w.message, w.message
    assert len(rep.dropped_poses) == t_pose.size
    _, rep = fit(t_log, p, q, reject_outliers=False, return_report=True)
    assert "poses_held" not in [w.code for w in rep.warnings] and not rep.dropped_poses


def test_held_real_ground_truth():
    """EuRoC V1_02's 200 Hz ground truth taken at 100 Hz and held at 200 Hz: found (against its
    real IMU the gyro below 10 Hz went from 3.2x to 0.52x the best fixed setting through the held
    poses, benchmarks/real_pairs.py euroc200h)."""
    from splineimu.io.euroc import read_euroc_groundtruth

    path = DATA / "euroc_V1_02_medium" / "groundtruth.csv"
    if not path.exists():
        pytest.skip("EuRoC V1_02 not in ../shared/data")
    tr = read_euroc_groundtruth(path)
    idx = np.arange(tr.t_ns.size) // 2 * 2
    held = held_poses(tr.positions[idx], tr.quat_xyzw[idx])
    assert held is not None and np.count_nonzero(held) == tr.t_ns.size // 2
    assert held_poses(tr.positions, tr.quat_xyzw) is None
