"""Scene-file values for cameras and landmarks, and the camera files of an output folder.

Scene-file keys (issue 18)::

    cameras:                      # inline: Kalibr camchain keys per camera, plus ours
      cam0: {camera_model: pinhole, intrinsics: [458.654, 457.296, 367.215, 248.375],
             distortion_model: radtan, distortion_coeffs: [-0.28, 0.07, 0.0002, 0.00002],
             resolution: [752, 480], T_cam_imu: [[...], [...], [...], [0, 0, 0, 1]],
             timeshift_cam_imu: 0.005, rate_hz: 20, line_delay_s: 0, pixel_noise_px: 1.0}
    cameras: {file: camchain.yaml, rate_hz: 20, pixel_noise_px: 1.0}   # or a Kalibr file + defaults

    landmarks: {file: points.csv}                                       # id,x,y,z
    landmarks: {random: {count: 1500, shape: shell, radii_m: [5, 30]}}  # or box: margin_m / box_min, box_max

Output files (:func:`splineimu.io.camera.write_camera_outputs`)::

    OUT/mav0/<cam>/features.csv     timestamp_ns,landmark_id,u,v
    OUT/landmarks.csv               id,x,y,z
    OUT/camchain.yaml               Kalibr camchain-imucam form (+ rate_hz, line_delay_s, pixel_noise_px)
    OUT/kalibr_imucam_chain.yaml    OpenVINS's form
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ConfigError
from .camchain import cameras_from_kalibr, load_camchain
from .landmarks import SHAPES, Landmarks

__all__ = ["cameras_from_config", "landmarks_from_config", "RANDOM_LANDMARK_KEYS"]

#: keys of ``landmarks: {random: {...}}``
RANDOM_LANDMARK_KEYS = ("count", "shape", "center", "radii_m", "box_min", "box_max", "margin_m")


def cameras_from_config(value, *, base_dir=None, doc=None, keys=("cameras",)) -> dict:
    """Cameras from a scene file's ``cameras:`` value.

    Parameters
    ----------
    value : dict
        ``{cam0: {...}, cam1: {...}}`` (Kalibr keys inline), or ``{file: PATH, KEY: VALUE...}``:
        a Kalibr (or OpenVINS) camchain file whose cameras lack the given keys (``rate_hz``,
        ``pixel_noise_px``, ``line_delay_s``, ...).
    base_dir : str or os.PathLike, optional
        Folder a relative ``file`` is taken from (the scene file's).
    doc : splineimu.io.yaml.YamlDoc, optional
        The scene file, for errors at the file and line of the key at fault.
    keys : tuple
        Where ``value`` sits in ``doc``.

    Returns
    -------
    dict
        Name -> :class:`~splineimu.camera.Camera`.

    Examples
    --------
    >>> cams = cameras_from_config({"cam0": {"intrinsics": [400, 400, 320, 240], "resolution": [640, 480],
    ...                                      "rate_hz": 20}})
    >>> cams["cam0"].rate_hz
    20.0
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "camchain.yaml").write_text("cam0:\\n  intrinsics: [1.0, 1.0, 0.0, 0.0]\\n  resolution: [8, 8]\\n")
    >>> cameras_from_config({"file": "camchain.yaml", "rate_hz": 30}, base_dir=d)["cam0"].rate_hz
    30.0
    """
    if isinstance(value, dict) and "file" in value:
        path = Path(value["file"])
        if base_dir is not None and not path.is_absolute():
            path = Path(base_dir) / path
        defaults = {k: v for k, v in value.items() if k != "file"}
        return load_camchain(path, defaults=defaults)
    return cameras_from_kalibr(value, doc=doc, keys=keys)


def landmarks_from_config(value, *, source=None, rng=None, base_dir=None) -> Landmarks:
    """Landmarks from a scene file's ``landmarks:`` value.

    Parameters
    ----------
    value : dict
        ``{file: PATH}`` (``id,x,y,z`` csv) or ``{random: {count, shape, ...}}`` with the
        keyword arguments of :meth:`Landmarks.random` (:data:`RANDOM_LANDMARK_KEYS`).
    source : MotionSource, optional
        Gives the trajectory's centre and extent for the random shapes' defaults.
    rng : numpy.random.Generator, int or None
        For ``random``.
    base_dir : str or os.PathLike, optional
        Folder a relative ``file`` is taken from.

    Raises
    ------
    ConfigError
        Neither or both of ``file`` and ``random``, an unknown key, a bad value.
    InputError
        A bad landmarks file.

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> lm = landmarks_from_config({"random": {"count": 10, "shape": "box", "margin_m": 2}},
    ...                            source=make_scene("ellipse"), rng=0)
    >>> len(lm)
    10
    >>> landmarks_from_config({"random": {"cout": 10}})
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: landmarks.random: unknown key `cout`; did you mean `count`?
    """
    import difflib

    if not isinstance(value, dict) or len({"file", "random"} & set(value)) != 1 or len(value) != 1:
        raise ConfigError(f"landmarks: expected {{file: points.csv}} or {{random: {{count: N, shape: ...}}}}, "
                          f"got {value!r}", option="landmarks")
    if "file" in value:
        path = Path(value["file"])
        if base_dir is not None and not path.is_absolute():
            path = Path(base_dir) / path
        return Landmarks.from_csv(path)
    spec = value["random"]
    if not isinstance(spec, dict):
        raise ConfigError(f"landmarks.random: expected a mapping {{count: N, ...}}, got {spec!r}",
                          option="landmarks.random")
    for key in spec:
        if key not in RANDOM_LANDMARK_KEYS:
            near = difflib.get_close_matches(str(key), RANDOM_LANDMARK_KEYS, n=1)
            hint = f"; did you mean `{near[0]}`?" if near else f" (known: {', '.join(RANDOM_LANDMARK_KEYS)})"
            raise ConfigError(f"landmarks.random: unknown key `{key}`{hint}", option=f"landmarks.random.{key}")
    if "count" not in spec:
        raise ConfigError("landmarks.random: missing key `count`", option="landmarks.random")
    kw = dict(spec)
    count = kw.pop("count")
    shape = kw.pop("shape", SHAPES[0])
    return Landmarks.random(count, shape, source=source, rng=rng, **kw)
