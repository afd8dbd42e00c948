"""Camera models with Kalibr's keys: pinhole projection, radtan and equidistant distortion.

A :class:`Camera` holds what a Kalibr ``camchain-imucam.yaml`` entry holds (``camera_model``,
``intrinsics``, ``distortion_model``, ``distortion_coeffs``, ``resolution``, ``T_cam_imu``,
``timeshift_cam_imu``) plus what a synthesis needs on top: the frame rate ``rate_hz``, the
rolling-shutter ``line_delay_s`` (0 = global shutter) and the white pixel noise
``pixel_noise_px`` (standard deviation per coordinate).

Conventions
-----------
- ``cam_T_imu`` (Kalibr's ``T_cam_imu``) maps IMU-frame points into the camera frame:
  ``p_cam = cam_R_imu p_imu + cam_t_imu``.
- Time shift as Kalibr and OpenVINS define it: ``t_imu = t_cam + timeshift_cam_imu``.
- Pixel coordinates as OpenCV and Kalibr: ``(u, v) = (fu x_d + pu, fv y_d + pv)``; the centre
  of the top-left pixel is ``(0, 0)``; a projection is inside the image when
  ``0 <= u < width`` and ``0 <= v < height`` (Kalibr's ``PinholeProjection::isValid``).
- Rolling shutter: row ``v`` (continuous) is read at ``t_cam + v * line_delay_s``.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from ..validation import as_rate_hz, finite_float, int_in_range, nonnegative_float, one_of

__all__ = ["Camera", "DISTORTION_MODELS", "CAMERA_KEYS"]

#: distortion models and their number of coefficients (Kalibr's names)
DISTORTION_MODELS = {"radtan": 4, "equidistant": 4, "none": 0}

#: keys a camera mapping may hold: Kalibr's, ours, and Kalibr/OpenVINS keys that are accepted
#: (``T_imu_cam`` as OpenVINS writes it, Kalibr's rolling-shutter ``line_delay``) or ignored
#: (``cam_overlaps``, ``T_cn_cnm1``: they follow from the cameras themselves)
CAMERA_KEYS = (
    "camera_model", "intrinsics", "distortion_model", "distortion_coeffs", "resolution",
    "T_cam_imu", "timeshift_cam_imu", "rate_hz", "line_delay_s", "pixel_noise_px", "rostopic",
    "T_imu_cam", "line_delay", "cam_overlaps", "T_cn_cnm1",
)

#: below this radius (normalized image plane) the distortion factor is 1, as OpenCV and Kalibr
SMALL_RADIUS = 1e-8


@dataclass(frozen=True, eq=False)
class Camera:
    r"""A pinhole camera with radtan or equidistant distortion, rigidly mounted on the IMU.

    Parameters
    ----------
    intrinsics : (4,) float
        ``[fu, fv, pu, pv]``: focal lengths and principal point [px].
    resolution : (2,) int
        ``[width, height]`` [px].
    distortion_model : {"radtan", "equidistant", "none"}
    distortion_coeffs : (4,) or (0,) float
        radtan: ``[k1, k2, p1, p2]``; equidistant: ``[k1, k2, k3, k4]``; none: ``[]``.
    cam_T_imu : (4, 4) float
        Kalibr's ``T_cam_imu``: IMU-frame points to camera-frame points.
    timeshift_cam_imu_s : float
        ``t_imu = t_cam + timeshift_cam_imu_s`` [s].
    rate_hz : float
        Frame rate on the camera clock.
    line_delay_s : float
        Time between the reading of two consecutive rows; 0 is a global shutter.
    pixel_noise_px : float
        Standard deviation of the white noise added to each pixel coordinate.
    name : str
        ``cam0``, ``cam1``, ...
    rostopic : str or None
        Written to the camchain files; ``/<name>/image_raw`` when None.

    Notes
    -----
    With ``(X, Y, Z)`` a point in the camera frame, ``x = X / Z``, ``y = Y / Z``, ``r^2 = x^2 + y^2``:

    radtan (OpenCV's ``projectPoints`` with ``[k1, k2, p1, p2]``, Kalibr's radtan)::

        x_d = x (1 + k1 r^2 + k2 r^4) + 2 p1 x y + p2 (r^2 + 2 x^2)
        y_d = y (1 + k1 r^2 + k2 r^4) + p1 (r^2 + 2 y^2) + 2 p2 x y

    equidistant (OpenCV's ``fisheye.projectPoints``, Kalibr's equidistant)::

        theta = atan(r),  theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
        (x_d, y_d) = (theta_d / r) (x, y)      (1 when r < 1e-8)

    then ``u = fu x_d + pu``, ``v = fv y_d + pv``. A point is observable only with ``Z > 0``.
    The visibility rule is literal, as Kalibr's: a radtan model whose radial factor turns
    back (strongly negative ``k1`` with ``k2 <= 0``) maps some points far outside the field of
    view back into the image, and they count as visible, exactly where OpenCV projects them.

    References
    ----------
    Kalibr wiki, "Supported models" and "Yaml formats" (camchain.yaml keys).
    OpenCV, ``calib3d`` module: ``projectPoints`` and ``fisheye::projectPoints``.

    Examples
    --------
    >>> cam = Camera.from_kalibr({"intrinsics": [400.0, 400.0, 320.0, 240.0],
    ...                           "resolution": [640, 480], "rate_hz": 20.0})
    >>> cam.project([[0.1, -0.05, 2.0]])
    array([[340., 230.]])
    >>> cam.is_global_shutter, cam.distortion_model
    (True, 'none')
    """

    intrinsics: tuple
    resolution: tuple
    distortion_model: str = "none"
    distortion_coeffs: tuple = ()
    cam_T_imu: np.ndarray = field(default_factory=lambda: np.eye(4))
    timeshift_cam_imu_s: float = 0.0
    rate_hz: float = 20.0
    line_delay_s: float = 0.0
    pixel_noise_px: float = 0.0
    name: str = "cam0"
    rostopic: str | None = None

    def __post_init__(self):
        where = f"{self.name}: "
        set_ = object.__setattr__
        set_(self, "intrinsics", _numbers(self.intrinsics, 4, "intrinsics", where, "[fu, fv, pu, pv]"))
        if self.intrinsics[0] <= 0 or self.intrinsics[1] <= 0:
            raise _error(where, "intrinsics", f"`intrinsics` focal lengths fu, fv must be positive, got "
                                              f"{list(self.intrinsics[:2])}")
        set_(self, "resolution", _resolution(self.resolution, where))
        model = _check(one_of, self.distortion_model, "distortion_model", where, tuple(DISTORTION_MODELS))
        n = DISTORTION_MODELS[model]
        coeffs = () if self.distortion_coeffs is None else self.distortion_coeffs
        set_(self, "distortion_coeffs", _numbers(coeffs, n, "distortion_coeffs", where,
                                                 f"{n} numbers for {model}"))
        set_(self, "cam_T_imu", _transform(self.cam_T_imu, "T_cam_imu", where))
        set_(self, "timeshift_cam_imu_s", _check(finite_float, self.timeshift_cam_imu_s, "timeshift_cam_imu", where))
        set_(self, "rate_hz", _check(as_rate_hz, self.rate_hz, "rate_hz", where))
        set_(self, "line_delay_s", _check(nonnegative_float, self.line_delay_s, "line_delay_s", where))
        set_(self, "pixel_noise_px", _check(nonnegative_float, self.pixel_noise_px, "pixel_noise_px", where))
        if self.rostopic is not None and not isinstance(self.rostopic, str):
            raise _error(where, "rostopic", f"`rostopic` must be a string, got {self.rostopic!r}")

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_kalibr(cls, mapping, name: str = "cam0", **overrides) -> Camera:
        """A camera from one entry of a Kalibr camchain (a mapping of Kalibr keys).

        Parameters
        ----------
        mapping : dict
            Keys ``camera_model`` (``pinhole``), ``intrinsics``, ``resolution``,
            ``distortion_model`` and ``distortion_coeffs`` (default none), ``T_cam_imu``
            (default identity; OpenVINS's ``T_imu_cam`` is accepted instead),
            ``timeshift_cam_imu`` (default 0), ``rate_hz`` (required), ``line_delay_s``
            (default 0; Kalibr's ``line_delay`` is accepted), ``pixel_noise_px`` (default 0),
            ``rostopic``. ``cam_overlaps`` and ``T_cn_cnm1`` are ignored.
        name : str
            The camera's name, used in messages and output paths.
        **overrides
            Keys that replace (or add to) those of ``mapping``, e.g. ``rate_hz=20.0`` for a
            Kalibr file, which has no frame rate.

        Returns
        -------
        Camera

        Raises
        ------
        ConfigError
            A missing, unknown or invalid key; the message names the camera and the key.

        Examples
        --------
        >>> cam = Camera.from_kalibr({"camera_model": "pinhole",
        ...     "intrinsics": [458.654, 457.296, 367.215, 248.375],
        ...     "distortion_model": "radtan",
        ...     "distortion_coeffs": [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05],
        ...     "resolution": [752, 480], "timeshift_cam_imu": 0.005}, rate_hz=20.0)
        >>> cam.resolution, cam.timeshift_cam_imu_s
        ((752, 480), 0.005)
        >>> Camera.from_kalibr({"intrinsics": [1, 1, 0, 0], "resolution": [2, 2], "rate": 20})
        Traceback (most recent call last):
        ...
        splineimu.errors.ConfigError: cam0: unknown key `rate`; did you mean `rate_hz`?
        """
        where = f"{name}: "
        if not isinstance(mapping, dict):
            raise _error(where, None, f"expected a mapping of Kalibr camera keys, got {type(mapping).__name__}")
        d = dict(mapping)
        d.update(overrides)
        for key in d:
            if key not in CAMERA_KEYS:
                raise _error(where, key, f"unknown key `{key}`{_did_you_mean(key, CAMERA_KEYS, '; did you mean')}")
        model = d.get("camera_model", "pinhole")
        if model != "pinhole":
            raise _error(where, "camera_model", f"`camera_model` must be pinhole, got {model!r}")
        for key in ("intrinsics", "resolution", "rate_hz"):
            if key not in d:
                hint = " (Kalibr files have no frame rate: give it next to the file)" if key == "rate_hz" else ""
                raise _error(where, None, f"missing key `{key}`{hint}")
        dist = d.get("distortion_model", "none")
        if not isinstance(dist, str):
            raise _error(where, "distortion_model", f"`distortion_model` must be a string, got {dist!r}")
        cam_T_imu = _from_either(d, where)
        line_delay = d.get("line_delay_s", None)
        if "line_delay" in d:
            kalibr = _check(nonnegative_float, d["line_delay"], "line_delay", where)
            if line_delay is not None and _check(finite_float, line_delay, "line_delay_s", where) != kalibr:
                raise _error(where, "line_delay",
                             f"`line_delay` ({kalibr!r}) and `line_delay_s` ({line_delay!r}) differ")
            line_delay = kalibr
        return cls(
            intrinsics=d["intrinsics"], resolution=d["resolution"], distortion_model=dist,
            distortion_coeffs=d.get("distortion_coeffs", ()), cam_T_imu=cam_T_imu,
            timeshift_cam_imu_s=d.get("timeshift_cam_imu", 0.0), rate_hz=d["rate_hz"],
            line_delay_s=0.0 if line_delay is None else line_delay,
            pixel_noise_px=d.get("pixel_noise_px", 0.0), name=name, rostopic=d.get("rostopic"),
        )

    def to_kalibr(self) -> dict:
        """The camera as a Kalibr camchain entry (plain Python types), with our keys added.

        Examples
        --------
        >>> cam = Camera((400.0, 400.0, 320.0, 240.0), (640, 480), rate_hz=30.0)
        >>> d = cam.to_kalibr()
        >>> d["intrinsics"], d["resolution"], d["rate_hz"], d["T_cam_imu"][3]
        ([400.0, 400.0, 320.0, 240.0], [640, 480], 30.0, [0.0, 0.0, 0.0, 1.0])
        """
        return {
            "T_cam_imu": [[float(x) for x in row] for row in self.cam_T_imu],
            "camera_model": "pinhole",
            "distortion_coeffs": [float(x) for x in self.distortion_coeffs],
            "distortion_model": self.distortion_model,
            "intrinsics": [float(x) for x in self.intrinsics],
            "line_delay_s": float(self.line_delay_s),
            "pixel_noise_px": float(self.pixel_noise_px),
            "rate_hz": float(self.rate_hz),
            "resolution": [int(x) for x in self.resolution],
            "rostopic": self.topic,
            "timeshift_cam_imu": float(self.timeshift_cam_imu_s),
        }

    def __eq__(self, other):
        if not isinstance(other, Camera):
            return NotImplemented
        return self.to_kalibr() == other.to_kalibr() and self.name == other.name

    __hash__ = None

    # ------------------------------------------------------------------ properties
    @property
    def topic(self) -> str:
        """``rostopic``, or ``/<name>/image_raw``."""
        return self.rostopic if self.rostopic is not None else f"/{self.name}/image_raw"

    @property
    def width(self) -> int:
        return self.resolution[0]

    @property
    def height(self) -> int:
        return self.resolution[1]

    @property
    def is_global_shutter(self) -> bool:
        return self.line_delay_s == 0.0

    @property
    def readout_s(self) -> float:
        """Time from the top of row 0 to the bottom of the last row: ``height * line_delay_s``."""
        return self.height * self.line_delay_s

    @property
    def camera_matrix(self) -> np.ndarray:
        """``K = [[fu, 0, pu], [0, fv, pv], [0, 0, 1]]`` (OpenCV's cameraMatrix)."""
        fu, fv, pu, pv = self.intrinsics
        return np.array([[fu, 0.0, pu], [0.0, fv, pv], [0.0, 0.0, 1.0]])

    @property
    def imu_T_cam(self) -> np.ndarray:
        """Inverse of ``cam_T_imu`` (OpenVINS's ``T_imu_cam``)."""
        return _inverse(self.cam_T_imu)

    # ------------------------------------------------------------------ projection
    def project(self, points_cam) -> np.ndarray:
        """Distorted pixel coordinates of camera-frame points (no visibility test).

        Parameters
        ----------
        points_cam : array_like, (..., 3)

        Returns
        -------
        ndarray, (..., 2)
            ``(u, v)``; meaningless where ``Z <= 0`` (use :meth:`is_visible`).

        Examples
        --------
        >>> cam = Camera((100.0, 100.0, 50.0, 50.0), (100, 100), "equidistant", (0, 0, 0, 0))
        >>> cam.project([0.0, 0.0, 1.0]), cam.project([1.0, 0.0, 1.0]).round(6)
        (array([50., 50.]), array([128.539816,  50.      ]))
        """
        p = np.asarray(points_cam, dtype=np.float64)
        if p.shape[-1:] != (3,):
            raise ConfigError(f"Expected `points_cam` to have shape (..., 3), got {p.shape}")
        u, v = self._project_xyz(p[..., 0], p[..., 1], p[..., 2], extended=False)
        return np.stack([u, v], axis=-1)

    def is_visible(self, points_cam) -> np.ndarray:
        """True where a camera-frame point has ``Z > 0`` and its distorted projection is in the image.

        Examples
        --------
        >>> cam = Camera((100.0, 100.0, 50.0, 50.0), (100, 100))
        >>> cam.is_visible([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 1.0]])
        array([ True, False, False])
        """
        p = np.asarray(points_cam, dtype=np.float64)
        uv = self.project(p)
        return (p[..., 2] > 0.0) & self.in_image(uv[..., 0], uv[..., 1])

    def in_image(self, u, v) -> np.ndarray:
        """``0 <= u < width and 0 <= v < height`` (Kalibr's rule).

        Examples
        --------
        >>> cam = Camera((1.0, 1.0, 0.0, 0.0), (640, 480))
        >>> cam.in_image(np.array([0.0, 639.9, 640.0]), np.array([0.0, 479.9, 10.0]))
        array([ True,  True, False])
        >>> bool(cam.in_image(-1e-9, 5.0))
        False
        """
        return (u >= 0.0) & (u < self.width) & (v >= 0.0) & (v < self.height)

    def _project_xyz(self, X, Y, Z, extended: bool):
        """Pixel coordinates of camera-frame coordinates (arrays of one shape).

        ``extended=True`` gives a projection that is continuous through ``Z = 0`` where the
        model allows it: equidistant uses ``theta = atan2(sqrt(X^2 + Y^2), Z)`` (the fisheye
        image of a point behind the camera, ``theta > pi/2``); pinhole and radtan return
        ``v = copysign(inf, Y)`` and ``u = nan`` for ``Z <= 0`` (the limit from ``Z > 0``).
        For ``Z > 0`` both forms agree.
        """
        fu, fv, pu, pv = self.intrinsics
        c = self.distortion_coeffs
        if self.distortion_model == "equidistant":
            rho = np.hypot(X, Y)
            with np.errstate(divide="ignore", invalid="ignore"):
                if extended:
                    theta = np.arctan2(rho, Z)
                    small = rho < SMALL_RADIUS * Z  # never behind the camera
                else:
                    r = rho / Z
                    theta = np.arctan(r)
                    small = np.abs(r) < SMALL_RADIUS
                t2 = theta * theta
                theta_d = theta * (1.0 + t2 * (c[0] + t2 * (c[1] + t2 * (c[2] + t2 * c[3]))))
                # (x_d, y_d) = theta_d (X, Y) / rho : the same as theta_d / r * (x, y) for Z > 0
                flat = small | (rho == 0.0)
                scale = np.where(flat, 0.0, theta_d / np.where(flat, 1.0, rho))
                xd = np.where(small, X / Z, X * scale)
                yd = np.where(small, Y / Z, Y * scale)
            return fu * xd + pu, fv * yd + pv
        with np.errstate(divide="ignore", invalid="ignore"):
            x = X / Z
            y = Y / Z
        if self.distortion_model == "radtan":
            k1, k2, p1, p2 = c
            r2 = x * x + y * y
            radial = 1.0 + r2 * (k1 + r2 * k2)
            xy2 = 2.0 * x * y
            xd = x * radial + p1 * xy2 + p2 * (r2 + 2.0 * x * x)
            yd = y * radial + p1 * (r2 + 2.0 * y * y) + p2 * xy2
        else:
            xd, yd = x, y
        u = fu * xd + pu
        v = fv * yd + pv
        if extended:
            behind = ~(Z > 0.0)
            if np.any(behind):
                u = np.where(behind, np.nan, u)
                v = np.where(behind, np.copysign(np.inf, Y), v)
        return u, v


# ------------------------------------------------------------------------------ validation helpers


def _did_you_mean(word, choices, prefix=""):
    close = difflib.get_close_matches(str(word), list(choices), n=1)
    if not close:
        return ""
    return f"{prefix} `{close[0]}`?" if prefix else f" (did you mean {close[0]!r}?)"


def _error(where, key, message) -> ConfigError:
    """A :class:`ConfigError` about camera key ``key``; ``option`` carries the key so that a
    file reader can add the key's file and line."""
    return ConfigError(where + message, option=key)


def _check(check, value, key, where, *args):
    """``check(value, key, *args)`` from :mod:`splineimu.validation`, its message prefixed by the camera."""
    try:
        return check(value, key, *args)
    except ConfigError as exc:
        raise _error(where, key, exc.problem) from None


def _numbers(value, n, key, where, what) -> tuple:
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        raise _error(where, key, f"`{key}` must be {what}, got {value!r}")
    items = list(np.asarray(value, dtype=object).reshape(-1)) if isinstance(value, np.ndarray) else list(value)
    if len(items) != n:
        raise _error(where, key, f"`{key}` must be {what}: {n} values, got {len(items)}")
    return tuple(_check(finite_float, x, key, where) for x in items)


def _resolution(value, where) -> tuple:
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__") or len(value) != 2:
        raise _error(where, "resolution", f"`resolution` must be [width, height], got {value!r}")
    return tuple(_check(int_in_range, x, "resolution", where, 1) for x in value)


def _transform(value, key, where) -> np.ndarray:
    try:
        T = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise _error(where, key, f"`{key}` must be a 4x4 matrix of numbers, got {value!r}") from None
    if T.shape != (4, 4):
        raise _error(where, key, f"Expected `{key}` to have shape (4, 4), got {T.shape}")
    if not np.all(np.isfinite(T)):
        raise _error(where, key, f"`{key}` contains NaN or inf")
    if not np.array_equal(T[3], [0.0, 0.0, 0.0, 1.0]):
        raise _error(where, key, f"`{key}` last row must be [0, 0, 0, 1], got {T[3].tolist()}")
    R = T[:3, :3]
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > 1e-6 or np.linalg.det(R) < 0:
        raise _error(where, key, f"`{key}` rotation block is not a rotation (max |R^T R - I| = {err:.3g}, "
                                 f"det {np.linalg.det(R):.6g})")
    T.setflags(write=False)
    return T


def _inverse(T) -> np.ndarray:
    R = T[:3, :3]
    out = np.eye(4)
    out[:3, :3] = R.T
    out[:3, 3] = -R.T @ T[:3, 3]
    return out


def _from_either(d, where) -> np.ndarray:
    """``T_cam_imu`` from ``T_cam_imu`` or OpenVINS's ``T_imu_cam`` (consistent if both)."""
    if "T_cam_imu" in d:
        T = _transform(d["T_cam_imu"], "T_cam_imu", where)
        if "T_imu_cam" in d:
            other = _transform(d["T_imu_cam"], "T_imu_cam", where)
            if np.abs(other @ T - np.eye(4)).max() > 1e-6:
                raise _error(where, "T_imu_cam", "`T_cam_imu` and `T_imu_cam` are not inverses of each other")
        return T
    if "T_imu_cam" in d:
        return _inverse(_transform(d["T_imu_cam"], "T_imu_cam", where))
    return np.eye(4)
