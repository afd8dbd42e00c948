"""File formats: one reader and one writer per format, atomic outputs.

The names below are re-exported lazily (importing :mod:`splineimu.io` loads nothing
heavy; the first use of a name imports its module):

- poses (:mod:`~splineimu.io.poses`): :class:`PoseTrack`, :class:`Gap`, :func:`clean_poses`,
  :func:`find_gaps`, :func:`split_at_gaps`
- TUM (:mod:`~splineimu.io.tum`): :func:`read_tum`, :func:`write_tum`, :func:`write_scene_tum`,
  :class:`TumWriter`
- EuRoC (:mod:`~splineimu.io.euroc`): :func:`read_euroc_groundtruth`, :func:`write_euroc_imu`,
  :func:`write_euroc_groundtruth`, :class:`EurocImuWriter`, :class:`EurocGroundtruthWriter`,
  :func:`read_groundtruth`
- stamps (:mod:`~splineimu.io.timestamps`): :func:`read_timestamps`, :func:`parse_stamps`
- YAML (:mod:`~splineimu.io.yaml`): :func:`read_yaml`, :func:`parse_yaml`, :func:`dump_yaml`,
  :func:`write_yaml`
- atomic outputs (:mod:`~splineimu.io.files`): :class:`OutputFolder`, :func:`check_output_dir`,
  :func:`atomic_write_text`, :func:`atomic_write_bytes`, :func:`staged_path`
- text tables (:mod:`~splineimu.io.tables`): :func:`format_table`, :func:`write_table`,
  :class:`TableWriter`
- ROS bags (:mod:`~splineimu.io.bag`): :func:`write_bag`
- calibrations (:mod:`~splineimu.io.calibration_yaml`): :func:`read_calibration_yaml`,
  :func:`write_calibration_yaml`
- IMU models (:mod:`~splineimu.io.imu_yaml`): :func:`write_imu_config`
- cameras (:mod:`~splineimu.io.camera`): :func:`write_camchain`, :func:`write_openvins_imucam_chain`,
  :func:`write_features_csv`, :func:`write_landmarks_csv`, :func:`write_camera_outputs`

A ``*Writer`` writes a file piece by piece into an :class:`OutputFolder` (records too long
to hold); the ``write_*`` function of the same format writes one whole file atomically. Both
make the same bytes.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "PoseTrack": "poses",
    "Gap": "poses",
    "clean_poses": "poses",
    "find_gaps": "poses",
    "split_at_gaps": "poses",
    "read_tum": "tum",
    "write_tum": "tum",
    "TumWriter": "tum",
    "write_scene_tum": "tum",
    "read_euroc_groundtruth": "euroc",
    "write_euroc_imu": "euroc",
    "write_euroc_groundtruth": "euroc",
    "EurocImuWriter": "euroc",
    "EurocGroundtruthWriter": "euroc",
    "read_timestamps": "timestamps",
    "parse_stamps": "timestamps",
    "read_yaml": "yaml",
    "parse_yaml": "yaml",
    "dump_yaml": "yaml",
    "write_yaml": "yaml",
    "OutputFolder": "files",
    "check_output_dir": "files",
    "atomic_write_text": "files",
    "atomic_write_bytes": "files",
    "staged_path": "files",
    "format_table": "tables",
    "write_table": "tables",
    "TableWriter": "tables",
    "write_bag": "bag",
    "read_calibration_yaml": "calibration_yaml",
    "write_camchain": "camera",
    "write_openvins_imucam_chain": "camera",
    "write_features_csv": "camera",
    "write_landmarks_csv": "camera",
    "write_camera_outputs": "camera",
    "write_imu_config": "imu_yaml",
    "read_groundtruth": "euroc",
    "write_calibration_yaml": "calibration_yaml",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name):
    mod = _EXPORTS.get(name)
    if mod is None:
        raise AttributeError(f"module 'splineimu.io' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{mod}", __name__), name)


def __dir__():
    return sorted(list(globals()) + list(_EXPORTS))
