"""Camera files: Kalibr's camchain, OpenVINS's ``kalibr_imucam_chain.yaml``, ``features.csv`` and
``landmarks.csv``, each written atomically, and :func:`write_camera_outputs`, the camera files of
an output folder (:mod:`splineimu.camera.config` lists them).

The texts come from :mod:`splineimu.camera` (:func:`~splineimu.camera.camchain.camchain_text`,
:func:`~splineimu.camera.camchain.openvins_imucam_chain_text`,
:func:`~splineimu.camera.features.features_csv_text`, :meth:`~splineimu.camera.Landmarks.csv_text`);
the readers are :func:`splineimu.camera.load_camchain`, :func:`splineimu.camera.read_features_csv`
and :meth:`splineimu.camera.Landmarks.from_csv`.
"""

from __future__ import annotations

from pathlib import Path

from ..camera.camchain import camchain_text, openvins_imucam_chain_text
from ..camera.features import features_csv_text
from ..camera.observations import _as_camera_list
from .files import atomic_write_text
from .yaml import write_yaml

__all__ = ["write_camchain", "write_openvins_imucam_chain", "write_features_csv", "write_landmarks_csv",
           "write_camera_outputs"]


def write_camchain(path, cameras, observations=None) -> Path:
    """Write ``cameras`` as a Kalibr camchain yaml file (atomically).

    The text is what Kalibr's own writer gives (``yaml.dump(..., default_flow_style=None)``,
    sorted keys); ``yaml.safe_load`` reads back every value bit for bit.

    Parameters
    ----------
    path : str or os.PathLike
    cameras : Camera, sequence of Camera, or dict name -> Camera
    observations : dict name -> Observations, optional
        Gives ``cam_overlaps``.

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile, pathlib, yaml
    >>> from splineimu.camera import Camera, load_camchain
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "camchain.yaml"
    >>> cam = Camera((458.654, 457.296, 367.215, 248.375), (752, 480), "radtan",
    ...              (-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05), rate_hz=20.0)
    >>> _ = write_camchain(p, [cam])
    >>> yaml.safe_load(p.read_text())["cam0"]["distortion_coeffs"]
    [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
    >>> load_camchain(p)["cam0"] == cam
    True
    """
    return write_yaml(path, None, text=camchain_text(cameras, observations))


def write_openvins_imucam_chain(path, cameras, observations=None) -> Path:
    """Write OpenVINS's ``kalibr_imucam_chain.yaml`` for ``cameras`` (atomically).

    The layout is the one of OpenVINS's ``config/*/kalibr_imucam_chain.yaml`` files: OpenCV's
    ``%YAML:1.0`` line, then per camera ``T_imu_cam`` (camera to IMU), ``cam_overlaps``,
    ``camera_model``, ``distortion_coeffs``, ``distortion_model``, ``intrinsics``,
    ``resolution``, ``rostopic`` and ``timeshift_cam_imu``.

    Notes
    -----
    OpenVINS reads ``timeshift_cam_imu`` of cam0 only and has no rolling-shutter model; the
    file says so in a comment when the cameras differ in time shift or read out by rows.
    ``distortion_model: none`` is written as radtan with zero coefficients (OpenVINS knows
    radtan and equidistant only).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from splineimu.camera import Camera
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "kalibr_imucam_chain.yaml"
    >>> _ = write_openvins_imucam_chain(p, [Camera((400.0, 400.0, 320.0, 240.0), (640, 480))])
    >>> print(p.read_text())  # doctest: +NORMALIZE_WHITESPACE
    %YAML:1.0
    <BLANKLINE>
    cam0:
      T_imu_cam: #rotation from camera to IMU R_CtoI, position of camera in IMU p_CinI
        - [1.0, 0.0, 0.0, 0.0]
        - [0.0, 1.0, 0.0, 0.0]
        - [0.0, 0.0, 1.0, 0.0]
        - [0.0, 0.0, 0.0, 1.0]
      cam_overlaps: []
      camera_model: pinhole
      distortion_coeffs: [0.0, 0.0, 0.0, 0.0]
      distortion_model: radtan
      intrinsics: [400.0, 400.0, 320.0, 240.0] #fu, fv, cu, cv
      resolution: [640, 480]
      rostopic: /cam0/image_raw
      timeshift_cam_imu: 0.0
    <BLANKLINE>
    """
    return write_yaml(path, None, text=openvins_imucam_chain_text(cameras, observations))


def write_features_csv(path, observations) -> Path:
    """Write one camera's observations to ``path`` (atomically: temporary file, then rename).

    Parameters
    ----------
    path : str or os.PathLike
        Target file; its folder must exist.
    observations : Observations
        Uses ``t_ns``, ``landmark_id``, ``u`` and ``v`` (the noisy coordinates).

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> from splineimu.camera import read_features_csv
    >>> from types import SimpleNamespace
    >>> obs = SimpleNamespace(t_ns=np.array([0, 0, 50_000_000]), landmark_id=np.array([4, 9, 4]),
    ...                       u=np.array([10.5, 0.1, 1 / 3]), v=np.array([2.0, 479.75, 7.0]))
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "features.csv"
    >>> _ = write_features_csv(p, obs); print(p.read_text(), end="")
    #timestamp_ns,landmark_id,u,v
    0,4,10.5,2.0
    0,9,0.1,479.75
    50000000,4,0.3333333333333333,7.0
    >>> bool(read_features_csv(p)["u"][2] == 1 / 3)
    True
    """
    return atomic_write_text(path, features_csv_text(observations))


def write_landmarks_csv(path, landmarks) -> Path:
    """Write ``id,x,y,z`` rows atomically (:meth:`Landmarks.csv_text`); floats are written so they
    read back bit for bit.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from splineimu.camera import Landmarks
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "landmarks.csv"
    >>> lm = Landmarks([3], [[0.1, 1 / 3, -2.0]])
    >>> _ = write_landmarks_csv(p, lm); print(p.read_text(), end="")
    id,x,y,z
    3,0.1,0.3333333333333333,-2.0
    >>> Landmarks.from_csv(p) == lm
    True
    """
    return atomic_write_text(path, landmarks.csv_text())


def write_camera_outputs(out_dir, cameras, observations, landmarks=None) -> list:
    """Write the camera files of an output folder (see the module notes); returns their paths.

    Parameters
    ----------
    out_dir : str or os.PathLike
        The output folder (e.g. the temporary folder of an ``OutputFolder``).
    cameras : Camera, sequence of Camera, or dict name -> Camera
    observations : dict name -> Observations
    landmarks : Landmarks, optional
        Written to ``landmarks.csv`` when given.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from splineimu.camera import Camera, Landmarks, observe
    >>> from splineimu.scenes import make_scene
    >>> scene = make_scene("ellipse", duration_s=0.5)
    >>> cam = Camera((300.0, 300.0, 320.0, 240.0), (640, 480), rate_hz=4.0,
    ...              cam_T_imu=[[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0], [0, 0, 0, 1]])
    >>> lm = Landmarks.random(100, source=scene, rng=0)
    >>> out = pathlib.Path(tempfile.mkdtemp())
    >>> paths = write_camera_outputs(out, [cam], observe(scene, [cam], lm, rng=0), lm)
    >>> sorted(str(p.relative_to(out)) for p in paths)
    ['camchain.yaml', 'kalibr_imucam_chain.yaml', 'landmarks.csv', 'mav0/cam0/features.csv']
    """
    out = Path(out_dir)
    cams = _as_camera_list(cameras)
    paths = []
    for cam in cams:
        folder = out / "mav0" / cam.name
        folder.mkdir(parents=True, exist_ok=True)
        paths.append(write_features_csv(folder / "features.csv", observations[cam.name]))
    if landmarks is not None:
        paths.append(write_landmarks_csv(out / "landmarks.csv", landmarks))
    paths.append(write_camchain(out / "camchain.yaml", cams, observations))
    paths.append(write_openvins_imucam_chain(out / "kalibr_imucam_chain.yaml", cams, observations))
    return paths
