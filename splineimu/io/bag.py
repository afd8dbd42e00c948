"""ROS bags of synthesized IMU data and ground-truth poses, written with ``rosbags``.

Two topics: ``sensor_msgs/msg/Imu`` (gyro and specific force, their covariances from the
noise model (:func:`imu_covariances`); no orientation estimate, so
``orientation_covariance[0] = -1`` as the message definition and REP 145 ask) and
``geometry_msgs/msg/PoseStamped`` (``world_T_body``). Header stamps are the exact integer
nanoseconds; the bag's record time is the header stamp.

ROS 2 bags are written in rosbag2 metadata version 8 with sqlite3 storage by default: the
newest version that ``rosbags`` writes and ROS 2 Humble parses (version 9 writes
``offered_qos_profiles`` as a list, which Humble's ``metadata_io`` cannot read; see
ros2/rosbag2 issue 2013). ``version=9`` suits Jazzy and newer. ROS 1 bags are format 2.0,
which every ROS 1 distribution reads.

``rosbags`` is imported inside :func:`write_bag`, so importing this module is cheap.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError, OutputExistsError
from ..validation import as_float_array, as_quat_xyzw, as_stamps_ns, as_vectors, one_of
from .files import staged_path
from .progress import progress_bar

__all__ = ["write_bag", "imu_covariances", "BAG_KINDS", "ROS2_BAG_VERSIONS", "ROS2_BAG_VERSION",
           "BAG_PROGRESS_MIN_MESSAGES"]

BAG_KINDS = ("ros1", "ros2")
#: rosbag2 metadata versions that can be written, and the default (read by Humble and newer).
ROS2_BAG_VERSIONS = (8, 9)
ROS2_BAG_VERSION = 8


def imu_covariances(config, rate_hz) -> tuple[np.ndarray, np.ndarray]:
    """Row-major 3x3 covariances (9 values) of ``angular_velocity`` and ``linear_acceleration``:
    the white noise of one sample, diagonal ``noise_density**2 * rate``.

    Zero ("unknown" in ``sensor_msgs/Imu``) without a sensor model or a rate.

    Examples
    --------
    >>> from splineimu.imu.config import ImuConfig
    >>> g, a = imu_covariances(ImuConfig.from_dict({"gyroscope_noise_density": 1e-3}), 400.0)
    >>> g.reshape(3, 3).diagonal().round(12).tolist(), bool(a.any())
    ([0.0004, 0.0004, 0.0004], False)
    """
    if config is None or rate_hz is None:
        return np.zeros(9), np.zeros(9)
    rate = float(rate_hz)
    return tuple(np.diag(np.asarray(getattr(config, f"{s}_noise_density"), dtype=np.float64) ** 2 * rate).ravel()
                 for s in ("gyroscope", "accelerometer"))


def _ros_stamps(t, name, kind):
    """Integer ns that ROS time can hold (unsigned; ROS 1 seconds are 32 bits)."""
    t = as_stamps_ns(t, name, increasing=False)
    if t.size and t.min() < 0:
        raise InputError(f"Expected `{name}` >= 0 (ROS time is unsigned), got {int(t.min())}")
    if kind == "ros1" and t.size and t.max() // 1_000_000_000 >= 2**32:
        raise InputError(f"Expected `{name}` below 2**32 s for ROS 1 time")
    if kind == "ros2" and t.size and t.max() // 1_000_000_000 >= 2**31:  # builtin_interfaces/Time: int32 sec
        raise InputError(f"Expected `{name}` below 2**31 s (year 2038) for ROS 2 time; shift the stamps (--t0-ns)")
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
    covariances=None,
    version: int | None = None,
    progress: bool | None = None,
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
    covariances : (gyro (9,), accel (9,)), optional
        ``angular_velocity_covariance`` and ``linear_acceleration_covariance`` of every IMU
        message (:func:`imu_covariances`); zero ("unknown") when omitted.
    version : {8, 9}, optional
        rosbag2 metadata version (``kind="ros2"`` only); default :data:`ROS2_BAG_VERSION`.
    progress : bool, optional
        Show a progress bar on stderr (default: for :data:`BAG_PROGRESS_MIN_MESSAGES` messages or
        more, when stderr is a terminal; a bag takes ~16 us per message, 23 s for an hour at 200 Hz).

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
    ``orientation = (0, 0, 0, 0)`` with ``orientation_covariance[0] = -1`` (no estimate).

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "imu.bag"
    >>> _ = write_bag(p, "ros1", [0, 5_000_000], np.zeros((2, 3)), np.tile([0, 0, 9.81], (2, 1)))
    >>> p.is_file()
    True
    """
    one_of(kind, "kind", BAG_KINDS)
    if version is not None and kind != "ros2":
        raise ConfigError("a bag version can only be chosen for ROS 2 bags", option="--bag-version")
    version = ROS2_BAG_VERSION if version is None else one_of(int(version), "version", ROS2_BAG_VERSIONS)
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
    gyro_cov, accel_cov = (np.zeros(9), np.zeros(9)) if covariances is None else (
        as_float_array(c, "covariances", shape=(9,)) for c in covariances)
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

            writer = Writer(tmp, version=version)
        with writer:
            c_imu = writer.add_connection(imu_topic, imu_type, typestore=store)
            c_pose = writer.add_connection(pose_topic, pose_type, typestore=store) if with_poses else None
            bar = _progress_bar(len(events), progress)
            try:
                for k, (t, which, i) in enumerate(events):
                    if bar is not None and k % 4096 == 4095:
                        bar.update(4096)
                    if which == 0:
                        gx, gy, gz = w_l[i]
                        ax, ay, az = a_l[i]
                        msg = Imu(
                            header=header(i, t, frame_id),
                            orientation=no_orientation,
                            orientation_covariance=orient_cov,
                            angular_velocity=Vector3(x=gx, y=gy, z=gz),
                            angular_velocity_covariance=gyro_cov,
                            linear_acceleration=Vector3(x=ax, y=ay, z=az),
                            linear_acceleration_covariance=accel_cov,
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
            finally:
                if bar is not None:
                    bar.close()
    return path


#: bags of at least this many messages get a progress bar (when stderr is a terminal)
BAG_PROGRESS_MIN_MESSAGES = 100_000


def _progress_bar(n, progress):
    return progress_bar(n, progress, BAG_PROGRESS_MIN_MESSAGES, " messages", "bag")
