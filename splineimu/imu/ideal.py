"""Stage 2 of IMU synthesis: ideal measurements of a sensor mounted on a moving body.

Stage 1 (kinematics) is any :class:`splineimu.motion.MotionSource` (fitted spline or
analytic scene); stage 3 (sensor errors) is :mod:`splineimu.imu.noise`.

A sensor frame S is mounted on the body B by the extrinsic ``body_T_sensor`` with rotation
``R_bs`` and lever arm ``r = t_bs`` (DESIGN.md section 1):

    omega_s = R_bs^T omega_b
    f_s     = R_bs^T (f_b + alpha_b x r + omega_b x (omega_b x r)),  f_b = R_wb^T (a_w - g_w)

The sensor's own ground truth is ``world_T_sensor = world_T_body body_T_sensor`` with velocity
``v_s = v_b + R_wb (omega_b x r)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from ..motion import DEFAULT_GRAVITY, Kinematics, MotionSource


@dataclass
class Extrinsic:
    """``body_T_sensor``: rotation ``body_R_sensor`` (3, 3) and lever arm ``body_t_sensor`` (3,) [m]."""

    body_R_sensor: np.ndarray = field(default_factory=lambda: np.eye(3))
    body_t_sensor: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        R = np.asarray(self.body_R_sensor, dtype=np.float64)
        t = np.asarray(self.body_t_sensor, dtype=np.float64).reshape(-1)
        if R.shape != (3, 3) or t.shape != (3,):
            raise ConfigError(f"extrinsic needs a 3x3 rotation and a 3-vector, got {R.shape} and {t.shape}")
        if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
            raise ConfigError("extrinsic contains NaN or inf")
        if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
            raise ConfigError("extrinsic rotation is not a rotation matrix (R^T R != I or det < 0)")
        # Re-orthonormalize so that round-off in a file does not leak into the data.
        u, _, vt = np.linalg.svd(R)
        self.body_R_sensor = u @ vt
        self.body_t_sensor = t

    @property
    def is_identity(self) -> bool:
        return bool(np.array_equal(self.body_R_sensor, np.eye(3)) and not np.any(self.body_t_sensor))

    @property
    def matrix(self) -> np.ndarray:
        """``body_T_sensor`` as a (4, 4) homogeneous matrix."""
        return np.block([[self.body_R_sensor, self.body_t_sensor[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]])

    @classmethod
    def from_matrix(cls, T) -> Extrinsic:
        T = np.asarray(T, dtype=np.float64)
        if T.shape == (16,):
            T = T.reshape(4, 4)
        if T.shape != (4, 4):
            raise ConfigError(f"extrinsic must be a 4x4 matrix, got shape {T.shape}")
        if np.abs(T[3] - [0, 0, 0, 1]).max() > 1e-9:
            raise ConfigError("extrinsic 4x4 matrix must have last row [0, 0, 0, 1]")
        return cls(T[:3, :3], T[:3, 3])

    @classmethod
    def from_dict(cls, d, where=None) -> Extrinsic:
        """``body_T_sensor`` from a mapping (an extrinsic file's content, or a scene file's value).

        Accepted forms: a 4x4 matrix under ``T_BS`` (EuRoC sensor.yaml, ``{rows, cols, data}``
        or nested lists), ``T_bs``, ``body_T_sensor``, OpenVINS's ``T_i_b`` (maps body points
        into the IMU frame: the IMU's pose is its inverse), Kalibr's camchain ``T_cam_imu`` (for
        poses of the camera: the IMU's pose in the camera frame, taken as it is) or OpenVINS's
        ``T_imu_cam`` (its inverse); or ``translation: [x, y, z]`` with
        ``quat_xyzw: [x, y, z, w]``. A mapping of entries (``{imu0: {T_i_b: ...}}``,
        ``{cam0: {T_cam_imu: ...}, cam1: ...}``) gives the first entry holding such a key.

        Parameters
        ----------
        d : dict
        where : (path, line) or path, optional
            Where the mapping came from, for error messages.

        Raises
        ------
        ConfigError
            No known key, a matrix that is not a rigid transform, or bad numbers.

        Examples
        --------
        >>> Extrinsic.from_dict({"translation": [0.1, 0, 0], "quat_xyzw": [0, 0, 0, 1]}).body_t_sensor.tolist()
        [0.1, 0.0, 0.0]
        """
        path, line = where if isinstance(where, tuple) else (where, None)
        keys = ("T_BS", "T_bs", "body_T_sensor", "T_i_b", "T_cam_imu", "T_imu_cam")
        if isinstance(d, dict) and not any(k in d for k in (*keys, "translation", "quat_xyzw")):
            d = next((v for v in d.values() if isinstance(v, dict) and any(k in v for k in keys)), d)
        if not isinstance(d, dict):
            raise ConfigError("expected a mapping with T_BS / T_bs / translation+quat_xyzw", path=path, line=line)

        def mat(v):
            if isinstance(v, dict) and "data" in v:
                v = v["data"]
            return cls.from_matrix(np.asarray(v, dtype=np.float64)).matrix

        try:
            for key in ("T_BS", "T_bs", "body_T_sensor", "T_cam_imu"):
                if key in d:
                    return cls.from_matrix(mat(d[key]))
            for key in ("T_i_b", "T_imu_cam"):
                if key in d:
                    return cls.from_matrix(_rigid_inverse(mat(d[key])))
            if "translation" in d or "quat_xyzw" in d:
                from ..lie import quat_xyzw_to_matrix

                q = d.get("quat_xyzw", [0, 0, 0, 1])
                return cls(quat_xyzw_to_matrix(np.asarray(q, dtype=np.float64)), d.get("translation", [0, 0, 0]))
        except ConfigError as exc:
            raise ConfigError(exc.problem, path=path, line=line) from None
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"bad extrinsic ({exc})", path=path, line=line) from None
        raise ConfigError("no T_BS, T_bs, body_T_sensor, T_i_b, T_cam_imu, T_imu_cam or translation/quat_xyzw key",
                          path=path, line=line)

    @classmethod
    def from_file(cls, path) -> Extrinsic:
        """Read ``body_T_sensor`` from a YAML file (the forms of :meth:`from_dict`)."""
        from ..yamldoc import read_yaml

        doc = read_yaml(path, "extrinsic file")
        return cls.from_dict(doc.data, where=doc.name)


def _rigid_inverse(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 transform (``R^T``, ``-R^T t``: exact for an identity)."""
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -(T[:3, :3].T @ T[:3, 3]) + 0.0
    return out


@dataclass
class IdealImu:
    """Noise-free sensor measurements and the sensor's ground truth at ``t_s``.

    Attributes
    ----------
    t_s : (N,) seconds in the source's time base
    gyro : (N, 3) angular rate of S in S [rad/s]
    specific_force : (N, 3) specific force at the origin of S, in S [m/s^2]
    position_world, quat_xyzw, velocity_world : the sensor's pose and velocity (N, 3 / 4 / 3)
    body : the body :class:`Kinematics` they were computed from
    """

    t_s: np.ndarray
    gyro: np.ndarray
    specific_force: np.ndarray
    position_world: np.ndarray
    quat_xyzw: np.ndarray
    velocity_world: np.ndarray
    body: Kinematics


def ideal_imu(source: MotionSource, t_s, gravity=DEFAULT_GRAVITY, extrinsic: Extrinsic | None = None) -> IdealImu:
    """Ideal gyro and accelerometer readings of a sensor on ``source`` at times ``t_s``.

    Parameters
    ----------
    source : MotionSource
        Fitted :class:`~splineimu.Spline` or analytic scene.
    t_s : (N,) array_like
        Sample times, seconds in the source's time base.
    gravity : (3,) array_like
        World gravity vector ``g_w`` [m/s^2].
    extrinsic : Extrinsic, optional
        ``body_T_sensor``; identity when omitted.

    Returns
    -------
    IdealImu

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> imu = ideal_imu(make_scene("static", duration_s=1.0), [0.5])
    >>> imu.specific_force.round(12).tolist()
    [[0.0, 0.0, 9.81]]
    """
    from ..lie import matrix_to_quat_xyzw

    k = source.kinematics(t_s)
    g = np.asarray(gravity, dtype=np.float64).reshape(3)
    f_b = k.specific_force_body(g)
    w_b = k.omega_body
    if extrinsic is None or extrinsic.is_identity:
        return IdealImu(k.t_s, w_b, f_b, k.position_world, matrix_to_quat_xyzw(k.world_R_body),
                        k.velocity_world, k)
    R_bs = extrinsic.body_R_sensor
    r = extrinsic.body_t_sensor
    w_x_r = np.cross(w_b, r)
    f_lever = f_b + np.cross(k.alpha_body, r) + np.cross(w_b, w_x_r)
    gyro = w_b @ R_bs  # rows: R_bs^T w
    accel = f_lever @ R_bs
    R_ws = k.world_R_body @ R_bs
    pos_s = k.position_world + k.world_R_body @ r
    vel_s = k.velocity_world + np.einsum("nij,nj->ni", k.world_R_body, w_x_r)
    return IdealImu(k.t_s, gyro, accel, pos_s, matrix_to_quat_xyzw(R_ws), vel_s, k)
