"""Cameras on the same motion as the IMU: landmark observations with Kalibr's camera models.

Nothing here is imported by ``import splineimu``: IMU-only runs do not load it.

Main entry points
-----------------
- :class:`Camera` (``Camera.from_kalibr``), :func:`load_camchain`: camera models and Kalibr /
  OpenVINS files.
- :class:`Landmarks` (``Landmarks.from_csv``, ``Landmarks.random``, ``csv_text``).
- :func:`observe` -> ``{name: Observations}``; :func:`read_features_csv`; :func:`plot_frame`.
- :func:`cameras_from_config`, :func:`landmarks_from_config`: the scene-file values ``cameras:``
  and ``landmarks:`` (:mod:`splineimu.camera.config` lists the keys and files).

The files are written by :mod:`splineimu.io.camera` (:func:`~splineimu.io.camera.write_camchain`,
:func:`~splineimu.io.camera.write_openvins_imucam_chain`, :func:`~splineimu.io.camera.write_features_csv`,
:func:`~splineimu.io.camera.write_landmarks_csv`, :func:`~splineimu.io.camera.write_camera_outputs`).
"""

from __future__ import annotations

from .camchain import cameras_from_kalibr, load_camchain
from .config import cameras_from_config, landmarks_from_config
from .features import read_features_csv
from .landmarks import Landmarks
from .model import Camera
from .observations import Observations, camera_rngs, frame_stamps_ns, observe, observe_camera
from .plot import plot_frame

__all__ = [
    "Camera", "Landmarks", "Observations", "observe", "observe_camera", "frame_stamps_ns",
    "camera_rngs", "load_camchain", "read_features_csv", "plot_frame", "cameras_from_kalibr",
    "cameras_from_config", "landmarks_from_config",
]
