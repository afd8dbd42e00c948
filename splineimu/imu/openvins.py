"""OpenVINS's IMU intrinsics (``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg``) and the
sensor model of :mod:`splineimu.imu.noise`, both ways.

The two models
--------------
This project's sensor model (:mod:`splineimu.imu.noise`), with ``S = I + diag(s)`` the
scale factors, ``M`` the misalignment and ``G`` the gyro's g-sensitivity::

    w_m = M_g S_g w + G f + b_g + n_g
    a_m = M_a S_a f       + b_a + n_a

OpenVINS (``kalibr_imu_chain.yaml``, read in ``VioManagerOptions::print_and_load_state``
and used by its simulator, ``Simulator::get_next_imu``)::

    w_m = Tw R_IMUtoGYRO w + Tg f + b_g + n_g
    a_m = Ta R_IMUtoACC f      + b_a + n_a

with ``w`` the body rate and ``f`` the specific force in the IMU frame. So the exact
correspondence is::

    Tw R_IMUtoGYRO = M_g S_g,     Ta R_IMUtoACC = M_a S_a,     Tg = G.

OpenVINS keeps only a triangle of the inverses ``Dw = Tw^-1``, ``Da = Ta^-1``: the lower
triangle for ``model: kalibr`` (also spelt ``calibrated``), the upper for ``model: rpng``.
Its effective ``Tw`` is therefore ``inv(tril(inv(Tw)))`` (``triu`` for rpng); a triangular
``Tw`` is kept as it is.

Writing (:func:`to_openvins`): ``model: kalibr``; ``K = M S`` is split as ``K = L Q`` with
``L`` lower triangular (positive diagonal) and ``Q`` a rotation (an LQ decomposition), so
``Tw = L``, ``R_IMUtoGYRO = Q`` (and ``Ta = L_a``, ``R_IMUtoACC = Q_a``). When ``K`` is already
lower triangular (no misalignment, or Kalibr's triangular one) ``Tw = K`` and the rotation is
the identity, exactly. Scale and misalignment off: identity matrices; no g-sensitivity:
``Tg = 0``. Temperature-dependent scale has no OpenVINS counterpart and is not written.

Reading (:func:`from_openvins`): ``gyroscope_misalignment = Tw_eff R_IMUtoGYRO``,
``accelerometer_misalignment = Ta_eff R_IMUtoACC``, ``gyroscope_g_sensitivity = Tg`` (each
left out when it is the identity / zero), so the sensor model reproduces OpenVINS's
measurements.
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError

__all__ = ["OPENVINS_KEYS", "OPENVINS_MODELS", "to_openvins", "from_openvins"]

#: Intrinsic keys of an OpenVINS ``imu0`` entry.
OPENVINS_KEYS = ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg")
#: Values of its ``model`` key and the triangle of ``D = T^-1`` each keeps.
OPENVINS_MODELS = {"kalibr": np.tril, "calibrated": np.tril, "rpng": np.triu}


def _lq(K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``K = L Q``, ``L`` lower triangular with non-negative diagonal (but the last entry when
    ``det K < 0``), ``Q`` a rotation; ``Q = I`` exactly for a lower-triangular ``K``."""
    if not np.any(np.triu(K, 1)):
        return K.copy(), np.eye(3)
    q, r = np.linalg.qr(K.T)
    L, Q = r.T, q.T
    d = np.where(np.diag(L) < 0, -1.0, 1.0)
    L, Q = L * d[None, :], Q * d[:, None]
    if np.linalg.det(Q) < 0:
        L[:, 2], Q[2] = -L[:, 2], -Q[2]
    return L, Q


def _gain(config, sensor: str) -> np.ndarray:
    """``M S`` of one sensor (the identity when neither is set)."""
    K = np.eye(3)
    scale = getattr(config, f"{sensor}_scale")
    if scale is not None:
        K = np.diag(1.0 + scale)
    mis = getattr(config, f"{sensor}_misalignment")
    if mis is not None:
        K = mis @ K
    return K


def to_openvins(config) -> dict:
    """OpenVINS's ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` and ``model`` for an
    :class:`~splineimu.imu.config.ImuConfig` (or None: no intrinsic errors).

    Returns
    -------
    dict
        ``(3, 3)`` arrays under the five keys, and ``model: "kalibr"``.

    Examples
    --------
    >>> from splineimu.imu.config import ImuConfig
    >>> cfg = ImuConfig.from_dict({"gyroscope_scale": [0.01, 0, 0], "gyroscope_misalignment": [0.002, 0, 0]})
    >>> ov = to_openvins(cfg)
    >>> ov["Tw"].tolist(), ov["R_IMUtoGYRO"].tolist() == np.eye(3).tolist(), bool(ov["Tg"].any())
    ([[1.01, 0.0, 0.0], [0.00202, 1.0, 0.0], [0.0, 0.0, 1.0]], True, False)
    """
    out: dict = {}
    for sensor, T, R in (("gyroscope", "Tw", "R_IMUtoGYRO"), ("accelerometer", "Ta", "R_IMUtoACC")):
        L, Q = _lq(_gain(config, sensor) if config is not None else np.eye(3))
        out[T], out[R] = L, Q
    G = None if config is None else config.gyroscope_g_sensitivity
    out["Tg"] = np.zeros((3, 3)) if G is None else np.asarray(G, dtype=np.float64).copy()
    out["model"] = "kalibr"
    return {k: out[k] for k in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg", "model")}


def _effective(T: np.ndarray, tri, key: str, source: str) -> np.ndarray:
    if abs(np.linalg.det(T)) < 1e-12:
        raise ConfigError(f"`{key}` is singular: OpenVINS inverts it", path=source or None, option=key)
    if np.array_equal(tri(T), T):  # the inverse of a triangle is the same triangle: kept exactly
        return T
    return np.linalg.inv(tri(np.linalg.inv(T)))


def from_openvins(values: dict, source: str = "") -> dict:
    """Sensor-model keys equivalent to OpenVINS's intrinsics in an ``imu0`` mapping.

    Parameters
    ----------
    values : dict
        3x3 matrices (already checked) under any of :data:`OPENVINS_KEYS`, and optionally the
        ``model`` string. Missing matrices take OpenVINS's defaults (identity; ``Tg`` zero).
    source : str
        The file, for error messages.

    Returns
    -------
    dict
        ``gyroscope_misalignment``, ``accelerometer_misalignment``, ``gyroscope_g_sensitivity``
        as ``(3, 3)`` arrays, each present only when it is not the identity (zero for ``Tg``).

    Raises
    ------
    ConfigError
        Unknown ``model``, or a singular ``Tw`` / ``Ta``.

    Examples
    --------
    >>> Tw = np.array([[1.01, 0, 0], [0.00202, 1.0, 0], [0, 0, 1]])
    >>> sorted(from_openvins({"Tw": Tw, "model": "kalibr"}))
    ['gyroscope_misalignment']
    >>> bool(np.allclose(from_openvins({"Tw": Tw})["gyroscope_misalignment"], Tw, rtol=0, atol=1e-15))
    True
    """
    model = values.get("model", "kalibr")
    if model not in OPENVINS_MODELS:
        raise ConfigError(f"`model` must be one of {', '.join(OPENVINS_MODELS)} (OpenVINS), got {model!r}",
                          path=source or None, option="model")
    tri = OPENVINS_MODELS[model]
    out = {}
    for sensor, T, R in (("gyroscope", "Tw", "R_IMUtoGYRO"), ("accelerometer", "Ta", "R_IMUtoACC")):
        t_mat = values.get(T)
        r_mat = values.get(R)
        K = np.eye(3) if t_mat is None else _effective(np.asarray(t_mat, dtype=np.float64), tri, T, source)
        if r_mat is not None:
            Rm = np.asarray(r_mat, dtype=np.float64)
            if np.abs(Rm.T @ Rm - np.eye(3)).max() > 1e-6 or np.linalg.det(Rm) < 0:
                raise ConfigError(f"`{R}` is not a rotation matrix (R^T R != I or det < 0)",
                                  path=source or None, option=R)
            K = K @ Rm
        if not np.array_equal(K, np.eye(3)):
            out[f"{sensor}_misalignment"] = K
    Tg = values.get("Tg")
    if Tg is not None and np.any(Tg):
        out["gyroscope_g_sensitivity"] = np.asarray(Tg, dtype=np.float64)
    return out
