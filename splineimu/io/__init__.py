"""File formats: TUM, EuRoC, ROS bags, output folders.

The names below are re-exported lazily (importing :mod:`splineimu.io` loads nothing
heavy; the first use of a name imports its module):

- poses: :class:`PoseTrack`, :class:`Gap`, :func:`clean_poses`, :func:`find_gaps`,
  :func:`split_at_gaps`
- TUM: :func:`read_tum`, :func:`write_tum`
- EuRoC: :func:`read_euroc_groundtruth`, :func:`write_euroc_imu`,
  :func:`write_euroc_groundtruth`
- stamps: :func:`read_timestamps`, :func:`parse_stamps`
- output: :class:`OutputFolder`, :func:`check_output_dir`, :func:`atomic_write_text`,
  :func:`atomic_write_bytes`, :func:`format_table`
- bags: :func:`write_bag`
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
    "read_euroc_groundtruth": "euroc",
    "write_euroc_imu": "euroc",
    "write_euroc_groundtruth": "euroc",
    "read_timestamps": "timestamps",
    "parse_stamps": "timestamps",
    "OutputFolder": "output",
    "check_output_dir": "output",
    "atomic_write_text": "output",
    "atomic_write_bytes": "output",
    "format_table": "output",
    "write_bag": "bag",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name):
    mod = _EXPORTS.get(name)
    if mod is None:
        raise AttributeError(f"module 'splineimu.io' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{mod}", __name__), name)


def __dir__():
    return sorted(list(globals()) + list(_EXPORTS))
