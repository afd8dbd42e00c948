"""Kalibr camchain files and OpenVINS's ``kalibr_imucam_chain.yaml``: read, and their texts
(written by :mod:`splineimu.io.camera`).

Kalibr (``camchain-imucam.yaml``) holds one mapping per camera, ``cam0``, ``cam1``, ...,
written by PyYAML with sorted keys, short lists inline (``default_flow_style=None``). Ours
adds ``rate_hz``, ``line_delay_s`` and ``pixel_noise_px``, which Kalibr ignores, and
``T_cn_cnm1`` (camera n from camera n-1) for every camera after the first, as Kalibr writes.

OpenVINS reads its file with OpenCV's ``FileStorage``: a ``%YAML:1.0`` first line, per camera
``T_imu_cam`` (the inverse of Kalibr's ``T_cam_imu``), ``distortion_model`` (radtan or
equidistant), ``intrinsics``, ``distortion_coeffs``, ``resolution``, ``timeshift_cam_imu``
(read for cam0 only), plus ``cam_overlaps``, ``camera_model`` and ``rostopic``.
"""

from __future__ import annotations

import re

from ..errors import ConfigError
from .model import Camera

__all__ = ["load_camchain", "cameras_from_kalibr", "camchain_text", "openvins_imucam_chain_text",
           "camchain_dict", "cam_overlaps"]

_CAM_KEY = re.compile(r"cam(\d+)")


def cameras_from_kalibr(mapping, defaults=None, *, doc=None, keys=()) -> dict:
    """Cameras from a mapping ``{cam0: {...}, cam1: {...}}`` of Kalibr keys.

    Parameters
    ----------
    mapping : dict
        Camera name -> Kalibr camera keys (see :meth:`Camera.from_kalibr`). Names are
        ``cam<N>``; cameras are returned in the order of ``N``.
    defaults : dict, optional
        Keys used for every camera that lacks them (e.g. ``{"rate_hz": 20.0}``).
    doc : splineimu.io.yaml.YamlDoc, optional
        The document ``mapping`` was read from: errors then carry its file and the line of
        the key at fault.
    keys : tuple of str
        Where ``mapping`` sits in ``doc`` (e.g. ``("cameras",)`` in a scene file).

    Returns
    -------
    dict
        Name -> :class:`Camera`.

    Raises
    ------
    ConfigError
        Not a mapping, a name that is not ``cam<N>``, or a bad camera entry.

    Examples
    --------
    >>> cams = cameras_from_kalibr({"cam1": {"intrinsics": [1, 1, 0, 0], "resolution": [4, 4]},
    ...                             "cam0": {"intrinsics": [2, 2, 1, 1], "resolution": [4, 4]}},
    ...                            defaults={"rate_hz": 10})
    >>> list(cams), cams["cam1"].intrinsics
    (['cam0', 'cam1'], (1.0, 1.0, 0.0, 0.0))
    >>> from splineimu.io.yaml import parse_yaml
    >>> doc = parse_yaml("cameras:\\n  cam0:\\n    intrinsics: [1, 1, 0, 0]\\n    resolution: [4, 4]\\n"
    ...                  "    rate_hz: -20\\n", "scene.yaml")
    >>> cameras_from_kalibr(doc.data["cameras"], doc=doc, keys=("cameras",))
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: scene.yaml:5: cam0: `rate_hz` must be positive, got -20
    """
    keys = tuple(keys)

    def fail(message, *at):
        if doc is None:
            return ConfigError(message, option=".".join(map(str, at)) or None)
        return ConfigError(message, path=doc.name, line=doc.line(*keys, *at),
                           option=".".join(map(str, keys + at)) or None)

    if not isinstance(mapping, dict) or not mapping:
        raise fail(f"expected a mapping cam0: {{...}}, cam1: {{...}}, got {mapping!r}")
    names = []
    for key in mapping:
        if not isinstance(key, str) or not _CAM_KEY.fullmatch(key):
            raise fail(f"camera names must be cam0, cam1, ...; got {key!r}", key)
        names.append(key)
    names.sort(key=lambda k: int(k[3:]))
    out = {}
    for name in names:
        entry = mapping[name]
        if not isinstance(entry, dict):
            raise fail(f"{name}: expected a mapping of Kalibr camera keys, got {entry!r}", name)
        merged = dict(defaults or {})
        merged.update(entry)
        try:
            out[name] = Camera.from_kalibr(merged, name=name)
        except ConfigError as exc:
            at = (name,) if exc.option is None or exc.option not in entry else (name, exc.option)
            raise fail(exc.problem, *at) from None
    return out


def load_camchain(path, defaults=None) -> dict:
    """Read a Kalibr camchain (or OpenVINS ``kalibr_imucam_chain.yaml``) into cameras.

    Parameters
    ----------
    path : str or os.PathLike
        The yaml file. A leading OpenCV ``%YAML:1.0`` line is accepted.
    defaults : dict, optional
        Keys for cameras that lack them; a Kalibr file has no ``rate_hz``, so give it here.

    Returns
    -------
    dict
        Name -> :class:`Camera`, ordered cam0, cam1, ...

    Raises
    ------
    ConfigError
        The file cannot be read, is not valid yaml, or has a bad camera entry (the message
        starts with the file and the line of the key at fault).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "camchain.yaml"
    >>> _ = p.write_text("cam0:\\n  camera_model: pinhole\\n  intrinsics: [400.0, 400.0, 320.0, 240.0]\\n"
    ...                  "  distortion_model: radtan\\n  distortion_coeffs: [-0.1, 0.01, 0.0, 0.0]\\n"
    ...                  "  resolution: [640, 480]\\n  timeshift_cam_imu: -0.002\\n")
    >>> cams = load_camchain(p, defaults={"rate_hz": 20.0})
    >>> cams["cam0"].distortion_coeffs, cams["cam0"].timeshift_cam_imu_s
    ((-0.1, 0.01, 0.0, 0.0), -0.002)
    """
    from ..yamldoc import read_yaml

    doc = read_yaml(path, "camchain")
    return cameras_from_kalibr(doc.data, defaults=defaults, doc=doc)


def camchain_dict(cameras, observations=None) -> dict:
    """The Kalibr camchain mapping of ``cameras`` (plain Python types).

    ``T_cn_cnm1`` is added for every camera after the first; ``cam_overlaps`` (indices of the
    cameras that observed a landmark this camera observed) when ``observations`` are given.

    Examples
    --------
    >>> import numpy as np
    >>> c0 = Camera((1.0, 1.0, 0.0, 0.0), (4, 4), name="cam0")
    >>> T = np.eye(4); T[0, 3] = -0.1
    >>> c1 = Camera((1.0, 1.0, 0.0, 0.0), (4, 4), name="cam1", cam_T_imu=T)
    >>> d = camchain_dict([c0, c1])
    >>> d["cam1"]["T_cn_cnm1"][0]
    [1.0, 0.0, 0.0, -0.1]
    """
    cams = _camera_list(cameras)
    overlaps = cam_overlaps(cams, observations) if observations is not None else None
    out = {}
    prev = None
    for i, cam in enumerate(cams):
        d = cam.to_kalibr()
        if prev is not None:
            d["T_cn_cnm1"] = [[float(x) for x in row] for row in cam.cam_T_imu @ prev.imu_T_cam]
        if overlaps is not None:
            d["cam_overlaps"] = overlaps[i]
        out[cam.name] = d
        prev = cam
    return out


def cam_overlaps(cameras, observations) -> list:
    """For each camera, the indices of the other cameras that observed a common landmark.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> cams = [Camera((1.0, 1.0, 0.0, 0.0), (4, 4), name=f"cam{i}") for i in range(3)]
    >>> obs = {"cam0": SimpleNamespace(landmark_id=[1, 2]), "cam1": SimpleNamespace(landmark_id=[2, 5]),
    ...        "cam2": SimpleNamespace(landmark_id=[7])}
    >>> cam_overlaps(cams, obs)
    [[1], [0], []]
    >>> cam_overlaps(cams[:1], {})
    [[]]
    """
    import numpy as np

    cams = _camera_list(cameras)
    seen = [np.unique(observations[c.name].landmark_id) if c.name in observations else np.zeros(0, np.int64)
            for c in cams]
    return [[j for j in range(len(cams)) if j != i and np.intersect1d(seen[i], seen[j]).size]
            for i in range(len(cams))]


def camchain_text(cameras, observations=None) -> str:
    """The text of a Kalibr camchain yaml file for ``cameras`` (written by
    :func:`splineimu.io.camera.write_camchain`).

    The text is what Kalibr's own writer gives (``yaml.dump(..., default_flow_style=None)``,
    sorted keys); ``yaml.safe_load`` reads back every value bit for bit. ``observations``
    (dict name -> Observations, optional) gives ``cam_overlaps``.
    """
    import yaml

    data = camchain_dict(cameras, observations)
    # PyYAML's own float representer (not io.yaml's): `1.0e-05`, which every PyYAML reads as a float
    return yaml.safe_dump(data, default_flow_style=None, width=2147483647, sort_keys=True)


def openvins_imucam_chain_text(cameras, observations=None) -> str:
    """The text of OpenVINS's ``kalibr_imucam_chain.yaml`` for ``cameras`` (written by
    :func:`splineimu.io.camera.write_openvins_imucam_chain`, which describes the layout)."""
    cams = _camera_list(cameras)
    overlaps = cam_overlaps(cams, observations) if observations is not None else [[] for _ in cams]
    lines = ["%YAML:1.0", ""]
    if len({c.timeshift_cam_imu_s for c in cams}) > 1:
        lines.append("# OpenVINS reads timeshift_cam_imu of cam0 only; the cameras here differ")
    if any(not c.is_global_shutter for c in cams):
        lines.append("# rolling shutter (line_delay_s in camchain.yaml) is not modelled by OpenVINS")
    if len(lines) > 2:
        lines.append("")
    for cam, ov in zip(cams, overlaps):
        if cam.distortion_model == "none":
            model, coeffs = "radtan", (0.0, 0.0, 0.0, 0.0)
        else:
            model, coeffs = cam.distortion_model, cam.distortion_coeffs
        lines.append(f"{cam.name}:")
        lines.append("  T_imu_cam: #rotation from camera to IMU R_CtoI, position of camera in IMU p_CinI")
        lines += [f"    - {_flow(row)}" for row in cam.imu_T_cam]
        lines.append(f"  cam_overlaps: [{', '.join(str(j) for j in ov)}]")
        lines.append("  camera_model: pinhole")
        lines.append(f"  distortion_coeffs: {_flow(coeffs)}")
        lines.append(f"  distortion_model: {model}")
        lines.append(f"  intrinsics: {_flow(cam.intrinsics)} #fu, fv, cu, cv")
        lines.append(f"  resolution: [{cam.width}, {cam.height}]")
        lines.append(f"  rostopic: {cam.topic}")
        lines.append(f"  timeshift_cam_imu: {_real(cam.timeshift_cam_imu_s)}")
        lines.append("")
    return "\n".join(lines) + "\n"


def _real(x) -> str:
    """A float as PyYAML writes it (``repr``, with ``.0`` before a bare exponent) so that both
    PyYAML and OpenCV read it back bit for bit."""
    s = repr(float(x)).lower()
    if "." not in s and "e" in s:
        s = s.replace("e", ".0e")
    return s


def _flow(values) -> str:
    return "[" + ", ".join(_real(v) for v in values) + "]"


def _camera_list(cameras) -> list:
    from .observations import _as_camera_list

    return _as_camera_list(cameras)
