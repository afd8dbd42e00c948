"""Control rotations and poses as the fit handles them: unit quaternions (w, x, y, z) to and from
matrices, and the increments between neighbouring controls."""

from __future__ import annotations

import numpy as np

from .. import lie
from .._kernels import lie as _k_lie


def _quat_wxyz(quat_xyzw):
    """Unit quaternions (w, x, y, z), C-contiguous, of validated input."""
    q = np.asarray(quat_xyzw, dtype=np.float64)[:, [3, 0, 1, 2]]
    return np.ascontiguousarray(q / np.linalg.norm(q, axis=1, keepdims=True))


def _to_matrices(q_wxyz):
    out = np.empty((q_wxyz.shape[0], 3, 3))
    _k_lie.quat_wxyz_to_mat_batch(q_wxyz, out)
    return out


def _to_quats(R):
    out = np.empty((R.shape[0], 4))
    _k_lie.mat_to_quat_wxyz_batch(np.ascontiguousarray(R), out)
    return out


def _increments_so3(Rc):
    D = np.zeros((Rc.shape[0], 3))
    D[1:] = lie.so3_log(np.matmul(np.swapaxes(Rc[:-1], 1, 2), Rc[1:]))
    return D


def _increments_se3(Rc, pc):
    n = Rc.shape[0]
    T = np.zeros((n - 1, 4, 4))
    T[:, :3, :3] = np.matmul(np.swapaxes(Rc[:-1], 1, 2), Rc[1:])
    T[:, :3, 3] = np.einsum("nji,nj->ni", Rc[:-1], pc[1:] - pc[:-1])
    T[:, 3, 3] = 1.0
    D = np.zeros((n, 6))
    D[1:] = lie.se3_log(T)
    return D
