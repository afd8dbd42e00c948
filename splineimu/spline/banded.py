"""Banded normal equations of spline fits: difference penalties and banded Cholesky solves.

A fit's normal matrix is kept as upper blocks ``H[i, c]`` = block ``(i, i + c)``, ``c = 0 .. k-1``,
shape (n, k, d, d) (``d = 1`` for the position part of split splines, as (n, k)).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solveh_banded

from .._kernels import fit as _kf

#: Relative weight of the default smoothness penalty where data are dense (negligible bias).
DEFAULT_SMOOTHNESS = 1e-10
#: Relative penalty weight on control points with little data in their support (gaps, sparse
#: stretches): there the curve is the smoothest bridge, instead of being steered by the noise of
#: the few poses at the gap's borders.
SPARSE_SMOOTHNESS = 1e-3


def solve_banded_scalar(Hs, rhs):
    """Solve the symmetric banded system with upper diagonals ``Hs`` (n, k) for ``rhs`` (n, ...)."""
    n, k = Hs.shape
    ab = np.zeros((k, n))
    for c in range(k):
        ab[k - 1 - c, c:] = Hs[: n - c, c]
    return solveh_banded(ab, rhs, lower=False, check_finite=False)


def solve_banded_blocks(H, rhs, damping=0.0):
    """Solve the symmetric block-banded system (upper blocks H (n, k, d, d)) for rhs (n*d, ...)."""
    n, k, d, _ = H.shape
    if damping:
        H = H.copy()
        idx = np.arange(d)
        H[:, 0, idx, idx] += damping * np.maximum(H[:, 0, idx, idx], 1e-12)
    ab = np.zeros((k * d, n * d))
    _kf.blocks_to_lapack_upper(np.ascontiguousarray(H), ab)
    return solveh_banded(ab, rhs, lower=False, check_finite=False)


def difference_coefficients(order_diff):
    """Coefficients of the order-r difference operator: row j touches j .. j + r."""
    c = np.array([1.0])
    for _ in range(order_diff):
        c = np.convolve(c, [-1.0, 1.0])
    return c  # length r + 1


def add_position_penalty(Hs, mu, r):
    """Add D_r^T diag(mu) D_r to scalar banded blocks Hs (n, k); mu scalar or per row (n - r,)."""
    n, k = Hs.shape
    c = difference_coefficients(r)
    L = c.size
    if L > k or n < L:
        return
    mu = np.broadcast_to(np.asarray(mu, dtype=np.float64), (n - L + 1,))
    for a in range(L):
        for b in range(a, L):
            Hs[a: n - L + 1 + a, b - a] += mu * c[a] * c[b]


def row_weights(sparse, width):
    """Per penalty row touching controls j .. j + width - 1: True where any of them is sparse."""
    n = sparse.size
    if n < width:
        return np.zeros(0, dtype=bool)
    win = np.lib.stride_tricks.sliding_window_view(sparse, width)
    return win.any(axis=1)
