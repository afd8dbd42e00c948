"""ROS bags of synthesized IMU data and ground-truth poses, written with ``rosbags``.

Two topics: ``sensor_msgs/msg/Imu`` (gyro and specific force; no orientation estimate,
so ``orientation_covariance[0] = -1`` as the message definition and REP 145 ask) and
``geometry_msgs/msg/PoseStamped`` (``world_T_body``). Header stamps are the exact integer
nanoseconds; the bag's record time is the header stamp.

``rosbags`` is imported inside :func:`write_bag`, so importing this module is cheap.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError, OutputExistsError
from ..validation import as_quat_xyzw, as_stamps_ns, as_vectors, one_of
from .files import staged_path

__all__ = ["write_bag", "BAG_KINDS"]

BAG_KINDS = ("ros1", "ros2")


def _ros_stamps(t, name, kind):
    """Integer ns that ROS time can hold (unsigned; ROS 1 seconds are 32 bits)."""
    t = as_stamps_ns(t, name, increasing=False)
    if t.size and t.min() < 0:
        raise InputError(f"Expected `{name}` >= 0 (ROS time is unsigned), got {int(t.min())}")
    if kind == "ros1" and t.size and t.max() // 1_000_000_000 >= 2**32:
        raise InputError(f"Expected `{name}` below 2**32 s for ROS 1 time")
    return t


def write_bag(
    path,
    kind: str,
    imu_t_ns,
    gyro,
    accel,
    gt_t_ns=None,
    positions=None,
    quat_xyzw=None,
    imu_topic: str = "/imu0",
    pose_topic: str = "/groundtruth/pose",
    frame_id: str = "imu0",
    world_frame_id: str = "world",
    force: bool = False,
) -> Path:
    """Write IMU samples and (optionally) ground-truth poses to a ROS 1 or ROS 2 bag.

    Parameters
    ----------
    path : str or os.PathLike
        ``kind="ros1"``: the ``.bag`` file. ``kind="ros2"``: the rosbag2 folder (sqlite3
        storage, rosbags' default, with ``metadata.yaml``).
    kind : {"ros1", "ros2"}
        Bag format; messages use the Noetic or Humble type definitions.
    imu_t_ns : array_like of int, shape (N,)
        IMU stamps in ns (>= 0).
    gyro : array_like, shape (N, 3)
        ``angular_velocity``, rad/s.
    accel : array_like, shape (N, 3)
        ``linear_acceleration`` (specific force), m/s^2.
    gt_t_ns : array_like of int, shape (M,), optional
        Pose stamps in ns; with ``positions`` and ``quat_xyzw`` it adds the pose topic.
    positions : array_like, shape (M, 3), optional
    quat_xyzw : array_like, shape (M, 4), optional
        ``world_T_body`` of the poses.
    imu_topic, pose_topic : str
        Topic names.
    frame_id : str, default "imu0"
        ``header.frame_id`` of the IMU messages.
    world_frame_id : str, default "world"
        ``header.frame_id`` of the pose messages.
    force : bool, default False
        Replace an existing ``path``.

    Returns
    -------
    pathlib.Path
        The bag file (ROS 1) or folder (ROS 2) written, ``path``.

    Raises
    ------
    OutputExistsError
        ``path`` exists and ``force`` is False.
    ConfigError, InputError
        (``ValueError`` subclasses) Unknown ``kind``; bad shapes, non-finite values or
        negative stamps.

    Notes
    -----
    The bag is written to a hidden temporary sibling and renamed into place when it is
    complete, so an interrupted run leaves no partial bag. IMU messages carry
    ``orientation = (0, 0, 0, 0)`` with ``orientation_covariance[0] = -1`` (no estimate)
    and all-zero ``angular_velocity_covariance`` / ``linear_acceleration_covariance``
    ("covariance unknown"), the way Kalibr's bag creator writes EuRoC data.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "imu.bag"
    >>> _ = write_bag(p, "ros1", [0, 5_000_000], np.zeros((2, 3)), np.tile([0, 0, 9.81], (2, 1)))
    >>> p.is_file()
    True
    """
    one_of(kind, "kind", BAG_KINDS)
    path = Path(path)
    if (path.exists() or path.is_symlink()) and not force:
        raise OutputExistsError(f"output '{path}' exists; use --force to replace it")
    t_imu = _ros_stamps(imu_t_ns, "imu_t_ns", kind)
    n = t_imu.shape[0]
    w = as_vectors(gyro, "gyro", n)
    a = as_vectors(accel, "accel", n)
    with_poses = gt_t_ns is not None
    if with_poses:
        if positions is None or quat_xyzw is None:
            raise InputError("`gt_t_ns` needs `positions` and `quat_xyzw` too")
        t_gt = _ros_stamps(gt_t_ns, "gt_t_ns", kind)
        m = t_gt.shape[0]
        p = as_vectors(positions, "positions", m)
        q = as_quat_xyzw(quat_xyzw, "quat_xyzw", m)
    elif positions is not None or quat_xyzw is not None:
        raise InputError("`positions` and `quat_xyzw` need `gt_t_ns`")

    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE)
    T = store.types
    Time = T["builtin_interfaces/msg/Time"]
    Header = T["std_msgs/msg/Header"]
    Vector3 = T["geometry_msgs/msg/Vector3"]
    Quaternion = T["geometry_msgs/msg/Quaternion"]
    Point = T["geometry_msgs/msg/Point"]
    Pose = T["geometry_msgs/msg/Pose"]
    PoseStamped = T["geometry_msgs/msg/PoseStamped"]
    Imu = T["sensor_msgs/msg/Imu"]
    imu_type = "sensor_msgs/msg/Imu"
    pose_type = "geometry_msgs/msg/PoseStamped"

    if kind == "ros1":
        def header(i, t, frame):
            return Header(seq=i, stamp=Time(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000),
                          frame_id=frame)
        serialize = store.serialize_ros1
    else:
        def header(i, t, frame):
            return Header(stamp=Time(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000),
                          frame_id=frame)
        serialize = store.serialize_cdr

    orient_cov = np.zeros(9)
    orient_cov[0] = -1.0
    zero_cov = np.zeros(9)
    no_orientation = Quaternion(x=0.0, y=0.0, z=0.0, w=0.0)

    # merge both streams by time so the bag is written in record-time order
    events = [(int(t), 0, i) for i, t in enumerate(t_imu.tolist())]
    if with_poses:
        events += [(int(t), 1, i) for i, t in enumerate(t_gt.tolist())]
        events.sort()
    w_l, a_l = w.tolist(), a.tolist()
    if with_poses:
        p_l, q_l = p.tolist(), q.tolist()

    # build the bag under its final name inside a hidden sibling folder (rosbag2 names
    # its storage file after the folder), then rename it into place
    with staged_path(path) as tmp:
        if kind == "ros1":
            from rosbags.rosbag1 import Writer

            writer = Writer(tmp)
        else:
            from rosbags.rosbag2 import Writer

            writer = Writer(tmp, version=Writer.VERSION_LATEST)
        with writer:
            c_imu = writer.add_connection(imu_topic, imu_type, typestore=store)
            c_pose = writer.add_connection(pose_topic, pose_type, typestore=store) if with_poses else None
            for t, which, i in events:
                if which == 0:
                    gx, gy, gz = w_l[i]
                    ax, ay, az = a_l[i]
                    msg = Imu(
                        header=header(i, t, frame_id),
                        orientation=no_orientation,
                        orientation_covariance=orient_cov,
                        angular_velocity=Vector3(x=gx, y=gy, z=gz),
                        angular_velocity_covariance=zero_cov,
                        linear_acceleration=Vector3(x=ax, y=ay, z=az),
                        linear_acceleration_covariance=zero_cov,
                    )
                    writer.write(c_imu, t, serialize(msg, imu_type))
                else:
                    px, py, pz = p_l[i]
                    qx, qy, qz, qw = q_l[i]
                    msg = PoseStamped(
                        header=header(i, t, world_frame_id),
                        pose=Pose(position=Point(x=px, y=py, z=pz),
                                  orientation=Quaternion(x=qx, y=qy, z=qz, w=qw)),
                    )
                    writer.write(c_pose, t, serialize(msg, pose_type))
    return path
