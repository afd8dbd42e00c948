"""ROS 1 / ROS 2 bags written with rosbags and read back with rosbags' own reader."""

from __future__ import annotations

import os

import numpy as np
import pytest

from splineimu.errors import OutputExistsError
from splineimu.io.bag import write_bag

pytest.importorskip("rosbags")

from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402


def _data(n=200, m=50, seed=0):
    rng = np.random.default_rng(seed)
    t_imu = 1403715524907143168 + np.arange(n, dtype=np.int64) * 5_000_000
    t_gt = t_imu[0] + 1 + np.arange(m, dtype=np.int64) * 20_000_000
    q = rng.normal(size=(m, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return dict(imu_t_ns=t_imu, gyro=rng.normal(size=(n, 3)), accel=rng.normal(size=(n, 3)) + [0, 0, 9.81],
                gt_t_ns=t_gt, positions=rng.normal(size=(m, 3)) * 10, quat_xyzw=q)


def _read(path, kind):
    store = get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE)
    out = {}
    with AnyReader([path], default_typestore=store) as reader:
        counts = {c.topic: (c.msgcount, c.msgtype) for c in reader.connections}
        for conn, t, raw in reader.messages():
            out.setdefault(conn.topic, []).append((t, reader.deserialize(raw, conn.msgtype)))
    return counts, out


@pytest.mark.parametrize("kind, name", [("ros1", "synth.bag"), ("ros2", "synth_ros2")])
def test_write_bag_round_trip(tmp_path, kind, name):
    d = _data()
    path = tmp_path / name
    assert write_bag(path, kind, **d) == path
    assert os.listdir(tmp_path) == [name]  # no temporary left behind
    if kind == "ros2":
        assert sorted(os.listdir(path)) == ["metadata.yaml", "synth_ros2.db3"]
    counts, msgs = _read(path, kind)
    assert counts == {"/imu0": (200, "sensor_msgs/msg/Imu"),
                      "/groundtruth/pose": (50, "geometry_msgs/msg/PoseStamped")}

    imu = msgs["/imu0"]
    t_rec = np.array([t for t, _ in imu])
    t_hdr = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in imu])
    assert np.array_equal(t_rec, d["imu_t_ns"]) and np.array_equal(t_hdr, d["imu_t_ns"])
    gyro = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for _, m in imu])
    acc = np.array([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                    for _, m in imu])
    assert np.array_equal(gyro, d["gyro"]) and np.array_equal(acc, d["accel"])
    m0 = imu[0][1]
    assert m0.header.frame_id == "imu0"
    assert m0.orientation_covariance[0] == -1.0 and not m0.orientation_covariance[1:].any()
    assert not m0.angular_velocity_covariance.any() and not m0.linear_acceleration_covariance.any()
    if kind == "ros1":
        assert [m.header.seq for _, m in imu[:3]] == [0, 1, 2]

    poses = msgs["/groundtruth/pose"]
    t_hdr = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in poses])
    assert np.array_equal(t_hdr, d["gt_t_ns"])
    pos = np.array([[m.pose.position.x, m.pose.position.y, m.pose.position.z] for _, m in poses])
    q = np.array([[m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w]
                  for _, m in poses])
    assert np.array_equal(pos, d["positions"]) and np.array_equal(q, d["quat_xyzw"])
    assert poses[0][1].header.frame_id == "world"


def test_write_bag_imu_only_custom_topics(tmp_path):
    d = _data(n=10)
    path = tmp_path / "imu.bag"
    write_bag(path, "ros1", d["imu_t_ns"], d["gyro"], d["accel"], imu_topic="/imu/data_raw",
              frame_id="imu_link")
    counts, msgs = _read(path, "ros1")
    assert counts == {"/imu/data_raw": (10, "sensor_msgs/msg/Imu")}
    assert msgs["/imu/data_raw"][0][1].header.frame_id == "imu_link"


@pytest.mark.parametrize("kind, name", [("ros1", "x.bag"), ("ros2", "x")])
def test_write_bag_exists_force_and_failure(tmp_path, kind, name, monkeypatch):
    d = _data(n=5, m=2)
    path = tmp_path / name
    write_bag(path, kind, **d)
    with pytest.raises(OutputExistsError):
        write_bag(path, kind, **d)
    d2 = _data(n=7, m=3, seed=1)
    write_bag(path, kind, force=True, **d2)
    counts, _ = _read(path, kind)
    assert counts["/imu0"][0] == 7 and os.listdir(tmp_path) == [name]

    # a failure in the middle of writing leaves the previous bag and no temporaries
    from rosbags import rosbag1, rosbag2

    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr((rosbag1 if kind == "ros1" else rosbag2).Writer, "write", boom)
    with pytest.raises(RuntimeError, match="disk full"):
        write_bag(path, kind, force=True, **d)
    monkeypatch.undo()
    assert os.listdir(tmp_path) == [name]
    assert _read(path, kind)[0]["/imu0"][0] == 7


def test_write_bag_validates(tmp_path):
    d = _data(n=5, m=2)
    with pytest.raises(ValueError, match="kind"):
        write_bag(tmp_path / "a.bag", "ros3", **d)
    with pytest.raises(ValueError, match="gyro"):
        write_bag(tmp_path / "a.bag", "ros1", d["imu_t_ns"], d["gyro"][:4], d["accel"])
    with pytest.raises(ValueError, match=">= 0"):
        write_bag(tmp_path / "a.bag", "ros1", d["imu_t_ns"] - 2 * 10**18, d["gyro"], d["accel"])
    with pytest.raises(ValueError, match="positions"):
        write_bag(tmp_path / "a.bag", "ros2", d["imu_t_ns"], d["gyro"], d["accel"], gt_t_ns=d["gt_t_ns"])
    assert os.listdir(tmp_path) == []
