"""SO3 and SE3: exponential and logarithm maps, Jacobians, adjoints, quaternion helpers.

Conventions (fixed for the whole package)
-----------------------------------------
- Rotations are ``(..., 3, 3)`` matrices in the array API; quaternions are Hamilton,
  ``quat_xyzw`` order (scipy's). Poses are ``(..., 4, 4)`` homogeneous matrices ``a_T_b``.
- SE3 tangent vectors are ``[rho, phi]``: translation part first, rotation part second.
- Jacobians are for the *right* perturbation unless the name says ``left``:
  ``Exp(phi + dphi) ~= Exp(phi) Exp(J_r(phi) dphi)`` and
  ``Exp(phi + dphi) ~= Exp(J_l(phi) dphi) Exp(phi)``.
- Every function accepts one element (``(3,)``, ``(3, 3)``, ...) or any batch with leading
  dimensions, and returns the same leading dimensions.

Numerics: each closed form has a named small-angle threshold below which a Taylor series of
matching order is used (see :mod:`splineimu._kernels.lie`); Log goes through a quaternion
(Shepperd's method + ``atan2``), which is stable at and near pi and indifferent to the sign
of a quaternion input.

References
----------
J. Sola, J. Deray, D. Atchuthan, "A micro Lie theory for state estimation in robotics", 2018.
T. Barfoot, "State Estimation for Robotics", 2017 (SE3 Jacobian blocks).
"""

from __future__ import annotations

import numpy as np

from ._kernels import lie as _k
from .errors import InputError
from .validation import as_float_array

__all__ = [
    "so3_hat", "so3_vee", "so3_exp", "so3_log", "so3_compose", "so3_inverse", "so3_act",
    "so3_adjoint", "so3_left_jacobian", "so3_right_jacobian", "so3_left_jacobian_inv",
    "so3_right_jacobian_inv",
    "se3_hat", "se3_vee", "se3_exp", "se3_log", "se3_compose", "se3_inverse", "se3_act",
    "se3_adjoint", "se3_left_jacobian", "se3_right_jacobian", "se3_left_jacobian_inv",
    "se3_right_jacobian_inv",
    "quat_xyzw_to_matrix", "matrix_to_quat_xyzw", "quat_make_continuous", "quat_normalize",
]


def _as_batch(x, tail: tuple, name: str):
    """Return ``(x as (N, *tail) contiguous float64, leading shape)``; NaN passes through."""
    a = as_float_array(x, name, finite=False)
    nt = len(tail)
    if a.ndim < nt or a.shape[a.ndim - nt:] != tail:
        want = "(..., " + ", ".join(map(str, tail)) + ")"
        raise InputError(f"Expected `{name}` to have shape {want}, got {a.shape}")
    lead = a.shape[: a.ndim - nt]
    return np.ascontiguousarray(a.reshape((-1,) + tail)), lead


def _unbatch(out, lead, tail):
    return out.reshape(lead + tail)


def _map(kernel, x, tail_in, name, tail_out, *args):
    """``kernel(x as (N, *tail_in), *args, out (N, *tail_out))`` with ``x``'s leading shape."""
    a, lead = _as_batch(x, tail_in, name)
    out = np.empty((a.shape[0],) + tail_out)
    kernel(a, *args, out)
    return _unbatch(out, lead, tail_out)


# --------------------------------------------------------------------------------- SO3


def so3_hat(phi):
    """Skew-symmetric matrix ``[phi]x`` of ``phi`` (..., 3) -> (..., 3, 3), ``[phi]x v = phi x v``."""
    return _map(_k.so3_hat_batch, phi, (3,), "phi", (3, 3))


def so3_vee(K):
    """Inverse of :func:`so3_hat` (uses the antisymmetric part): (..., 3, 3) -> (..., 3)."""
    M, lead = _as_batch(K, (3, 3), "K")
    v = 0.5 * np.stack([M[:, 2, 1] - M[:, 1, 2], M[:, 0, 2] - M[:, 2, 0], M[:, 1, 0] - M[:, 0, 1]], axis=1)
    return _unbatch(v, lead, (3,))


def so3_exp(phi):
    """Exponential map ``Exp(phi) = exp([phi]x)`` (Rodrigues), (..., 3) -> (..., 3, 3).

    Parameters
    ----------
    phi : array_like, (..., 3)
        Rotation vectors [rad], any norm.

    Returns
    -------
    ndarray, (..., 3, 3)
        ``I + sin(t)/t K + (1 - cos t)/t^2 K^2`` with ``K = [phi]x``, ``t = |phi|``; below
        ``EXP_SMALL_ANGLE`` the coefficients come from their Taylor series.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(so3_exp([0.0, 0.0, np.pi / 2]), 12)[:2]
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.]])
    """
    return _map(_k.so3_exp_batch, phi, (3,), "phi", (3, 3))


def so3_log(rot):
    """Logarithm map, the rotation vector with norm in [0, pi].

    Parameters
    ----------
    rot : array_like, (..., 3, 3) rotation matrices or (..., 4) quaternions ``quat_xyzw``
        A quaternion need not be unit (it is normalized) and its sign does not matter.

    Returns
    -------
    phi : ndarray, (..., 3)

    Raises
    ------
    InputError
        A wrong shape, or a zero or non-finite quaternion.

    Notes
    -----
    Computed as ``2 atan2(|v|, |w|) v / |v| sign(w)`` on the (Shepperd) quaternion, which is
    accurate at both ends of [0, pi]. At exactly pi the sign of the axis is arbitrary.

    Examples
    --------
    A half turn about z, from its matrix and from either sign of its quaternion:

    >>> import numpy as np
    >>> R = np.diag([-1.0, -1.0, 1.0])
    >>> bool(np.allclose(so3_log(R), [0.0, 0.0, np.pi], rtol=0, atol=1e-15))
    True
    >>> so3_log([0.0, 0.0, 1.0, 0.0]), so3_log([0.0, 0.0, -1.0, 0.0])
    (array([0.        , 0.        , 3.14159265]), array([ 0.        ,  0.        , -3.14159265]))
    """
    a = as_float_array(rot, "rot", finite=False)
    if a.ndim >= 1 and a.shape[-1] == 4:
        q, lead = _as_batch(a, (4,), "rot")
        wxyz = np.ascontiguousarray(q[:, [3, 0, 1, 2]])
        _check_quat_norm(wxyz, "rot")
        return _map(_k.quat_wxyz_log_batch, wxyz, (4,), "rot", (3,)).reshape(lead + (3,))
    return _map(_k.so3_log_batch, a, (3, 3), "rot", (3,))


def so3_compose(R_ab, R_bc):
    """``a_R_c = a_R_b @ b_R_c`` with broadcasting over leading dimensions."""
    return np.matmul(np.asarray(R_ab, dtype=np.float64), np.asarray(R_bc, dtype=np.float64))


def so3_inverse(R):
    """Inverse (transpose) of rotation matrices (..., 3, 3)."""
    return np.swapaxes(np.asarray(R, dtype=np.float64), -1, -2).copy()


def so3_act(R, v):
    """Rotate vectors: ``R @ v`` for (..., 3, 3) and (..., 3), broadcasting."""
    return np.einsum("...ij,...j->...i", np.asarray(R, dtype=np.float64), np.asarray(v, dtype=np.float64))


def so3_adjoint(R):
    """Adjoint of SO3 on its tangent space, which is ``R`` itself: ``R Exp(v) R^T = Exp(R v)``."""
    return np.array(R, dtype=np.float64)


#: batch kernel of each Jacobian: (group, inverse) -> kernel(x, sign, out)
_JACOBIAN_KERNELS = {
    ("so3", False): _k.so3_jacobian_batch,
    ("so3", True): _k.so3_jacobian_inv_batch,
    ("se3", False): _k.se3_jacobian_batch,
    ("se3", True): _k.se3_jacobian_inv_batch,
}
#: the kernels' ``sign`` argument: +1 for the left Jacobian, -1 for the right one
_SIDE_SIGN = {"left": 1.0, "right": -1.0}


def _jacobian(x, group: str, side: str, inverse: bool):
    dim, name = (3, "phi") if group == "so3" else (6, "xi")
    return _map(_JACOBIAN_KERNELS[group, inverse], x, (dim,), name, (dim, dim), _SIDE_SIGN[side])


def so3_right_jacobian(phi):
    """Right Jacobian of SO3: ``Exp(phi + dphi) ~= Exp(phi) Exp(J_r(phi) dphi)``.

    Parameters
    ----------
    phi : array_like, (..., 3)

    Returns
    -------
    ndarray, (..., 3, 3)
        ``J_r = I - (1 - cos t)/t^2 K + (t - sin t)/t^3 K^2``, ``K = [phi]x``, ``t = |phi|``
        (Taylor series below ``JAC_SMALL_ANGLE``).

    Examples
    --------
    A small increment on the right of ``Exp(phi)`` moves ``phi`` by ``J_r^-1`` of it:

    >>> import numpy as np
    >>> phi, d = np.array([0.3, -1.2, 0.5]), 1e-7 * np.array([1.0, 2.0, -1.0])
    >>> moved = so3_log(so3_exp(phi) @ so3_exp(d))
    >>> bool(np.allclose(moved - phi, so3_right_jacobian_inv(phi) @ d, rtol=1e-6, atol=0))
    True
    """
    return _jacobian(phi, "so3", "right", False)


def so3_left_jacobian(phi):
    """Left Jacobian of SO3, ``J_l(phi) = J_r(-phi) = Exp(phi) J_r(phi)``, (..., 3) -> (..., 3, 3):
    ``I + (1 - cos t)/t^2 K + (t - sin t)/t^3 K^2``. It also maps ``rho`` to the translation of
    ``se3_exp([rho, phi])``."""
    return _jacobian(phi, "so3", "left", False)


def so3_right_jacobian_inv(phi):
    """Inverse right Jacobian ``I + K/2 + (1/t^2 - cot(t/2)/(2t)) K^2``, (..., 3) -> (..., 3, 3);
    finite for ``|phi| < 2 pi``."""
    return _jacobian(phi, "so3", "right", True)


def so3_left_jacobian_inv(phi):
    """Inverse left Jacobian ``I - K/2 + (1/t^2 - cot(t/2)/(2t)) K^2``, the transpose of
    :func:`so3_right_jacobian_inv`; it maps a translation to ``rho`` in :func:`se3_log`."""
    return _jacobian(phi, "so3", "left", True)


# --------------------------------------------------------------------------------- SE3


def se3_hat(xi):
    """(..., 6) ``[rho, phi]`` -> (..., 4, 4) twist matrix ``[[phi]x, rho; 0, 0]``."""
    x, lead = _as_batch(xi, (6,), "xi")
    out = np.zeros((x.shape[0], 4, 4))
    out[:, :3, :3] = so3_hat(x[:, 3:])
    out[:, :3, 3] = x[:, :3]
    return _unbatch(out, lead, (4, 4))


def se3_vee(X):
    """Inverse of :func:`se3_hat`: (..., 4, 4) -> (..., 6) ``[rho, phi]``."""
    M, lead = _as_batch(X, (4, 4), "X")
    out = np.concatenate([M[:, :3, 3], so3_vee(M[:, :3, :3])], axis=1)
    return _unbatch(out, lead, (6,))


def se3_exp(xi):
    """Exponential map of ``xi = [rho, phi]`` (..., 6) -> (..., 4, 4): ``(Exp(phi), J_l(phi) rho)``.

    Examples
    --------
    A screw motion: a quarter turn about z while moving 1 m along it.

    >>> import numpy as np
    >>> np.round(se3_exp([0.0, 0.0, 1.0, 0.0, 0.0, np.pi / 2]), 12)
    array([[ 0., -1.,  0.,  0.],
           [ 1.,  0.,  0.,  0.],
           [ 0.,  0.,  1.,  1.],
           [ 0.,  0.,  0.,  1.]])
    """
    return _map(_k.se3_exp_batch, xi, (6,), "xi", (4, 4))


def se3_log(T):
    """Logarithm map (..., 4, 4) -> (..., 6) ``[rho, phi]``, ``|phi| <= pi``, ``rho = J_l(phi)^-1 t``.

    Examples
    --------
    >>> import numpy as np
    >>> xi = np.array([0.5, -1.0, 2.0, 0.1, 0.2, -0.3])
    >>> bool(np.allclose(se3_log(se3_exp(xi)), xi, rtol=0, atol=1e-15))
    True
    """
    return _map(_k.se3_log_batch, T, (4, 4), "T", (6,))


def se3_compose(T_ab, T_bc):
    """``a_T_c = a_T_b @ b_T_c``."""
    return np.matmul(np.asarray(T_ab, dtype=np.float64), np.asarray(T_bc, dtype=np.float64))


def se3_inverse(T):
    """Inverse of poses (..., 4, 4): ``(R^T, -R^T t)``."""
    M = np.asarray(T, dtype=np.float64)
    out = np.zeros_like(M)
    Rt = np.swapaxes(M[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, M[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def se3_act(T, p):
    """Transform points: ``R p + t`` for (..., 4, 4) and (..., 3), broadcasting."""
    M = np.asarray(T, dtype=np.float64)
    return np.einsum("...ij,...j->...i", M[..., :3, :3], np.asarray(p, dtype=np.float64)) + M[..., :3, 3]


def se3_adjoint(T):
    """Adjoint (..., 6, 6) for ``[rho, phi]``: ``[[R, [t]x R], [0, R]]``, so that
    ``T Exp(xi) T^-1 = Exp(Ad_T xi)``."""
    return _map(_k.se3_adjoint_batch, T, (4, 4), "T", (6, 6))


def se3_left_jacobian(xi):
    """Left Jacobian of SE3, (..., 6) -> (..., 6, 6): ``[[J_l(phi), Q(rho, phi)], [0, J_l(phi)]]``
    with Barfoot's ``Q`` block (Taylor series below ``SE3_Q_SMALL_ANGLE``)."""
    return _jacobian(xi, "se3", "left", False)


def se3_right_jacobian(xi):
    """Right Jacobian of SE3, ``J_r(xi) = J_l(-xi)``: ``Exp(xi + dxi) ~= Exp(xi) Exp(J_r(xi) dxi)``.

    Parameters
    ----------
    xi : array_like, (..., 6)
        ``[rho, phi]``.

    Returns
    -------
    ndarray, (..., 6, 6)
        ``[[J_r(phi), Q(-rho, -phi)], [0, J_r(phi)]]``.
    """
    return _jacobian(xi, "se3", "right", False)


def se3_left_jacobian_inv(xi):
    """Inverse of :func:`se3_left_jacobian`: ``[[Ji, -Ji Q Ji], [0, Ji]]`` with ``Ji = J_l(phi)^-1``."""
    return _jacobian(xi, "se3", "left", True)


def se3_right_jacobian_inv(xi):
    """Inverse of :func:`se3_right_jacobian`; finite for ``|phi| < 2 pi``."""
    return _jacobian(xi, "se3", "right", True)


# --------------------------------------------------------------------------- quaternions


def _check_quat_norm(q, name):
    n = np.linalg.norm(q, axis=-1)
    bad = ~np.isfinite(n) | (n < 1e-12)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise InputError(f"`{name}` row {i} is not a valid quaternion (norm {n[i]:g})")


def quat_normalize(quat_xyzw):
    """Unit quaternions; raises on a zero or non-finite norm."""
    q, lead = _as_batch(quat_xyzw, (4,), "quat_xyzw")
    _check_quat_norm(q, "quat_xyzw")
    return _unbatch(q / np.linalg.norm(q, axis=1, keepdims=True), lead, (4,))


def quat_xyzw_to_matrix(quat_xyzw):
    """Rotation matrices of quaternions (normalized first), (..., 4) -> (..., 3, 3)."""
    q, lead = _as_batch(quat_xyzw, (4,), "quat_xyzw")
    _check_quat_norm(q, "quat_xyzw")
    out = _map(_k.quat_wxyz_to_mat_batch, q[:, [3, 0, 1, 2]], (4,), "quat_xyzw", (3, 3))
    return _unbatch(out, lead, (3, 3))


def matrix_to_quat_xyzw(R):
    """Unit quaternions with ``w >= 0`` of rotation matrices, (..., 3, 3) -> (..., 4)."""
    wxyz = _map(_k.mat_to_quat_wxyz_batch, R, (3, 3), "R", (4,))
    return np.ascontiguousarray(wxyz[..., [1, 2, 3, 0]])


def quat_make_continuous(quat_xyzw):
    """Flip signs so that consecutive quaternions have a non-negative dot product.

    ``q`` and ``-q`` are the same rotation; differencing or interpolating a sequence needs
    the representative that is closest to its predecessor. The first quaternion keeps its sign.

    Parameters
    ----------
    quat_xyzw : array_like, (N, 4) or (..., N, 4)
        A sequence along the second-to-last axis (each leading index is its own sequence).
        A single ``(4,)`` quaternion is returned unchanged.

    Returns
    -------
    ndarray, same shape as ``quat_xyzw``; each row is ``+q`` or ``-q`` (not renormalized).

    Examples
    --------
    >>> quat_make_continuous([[0.5, 0.5, 0.5, 0.5], [-0.5, -0.5, -0.1, -0.7], [0.1, 0.7, 0.5, 0.5]])
    array([[0.5, 0.5, 0.5, 0.5],
           [0.5, 0.5, 0.1, 0.7],
           [0.1, 0.7, 0.5, 0.5]])
    """
    q = np.array(quat_xyzw, dtype=np.float64)
    if q.ndim == 0 or q.shape[-1] != 4:
        raise InputError(f"Expected `quat_xyzw` to have shape (N, 4), got {q.shape}")
    if q.ndim == 1 or q.shape[-2] == 0:
        return q
    d = np.einsum("...ij,...ij->...i", q[..., 1:, :], q[..., :-1, :])
    step = np.where(d < 0.0, -1.0, 1.0)
    flips = np.concatenate([np.ones(step.shape[:-1] + (1,)), np.cumprod(step, axis=-1)], axis=-1)
    return q * flips[..., None]
