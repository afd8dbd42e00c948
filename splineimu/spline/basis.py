"""Uniform B-spline blending matrices of any order.

For order ``k`` (degree ``k - 1``) and a segment parameter ``u`` in [0, 1), the ``k`` basis
values that weight control points ``i .. i + k - 1`` are ``B(u) = M @ [1, u, u^2, ..., u^(k-1)]``
with the blending matrix

    M[j, n] = C(k-1, n) / (k-1)! * sum_{s=j}^{k-1} (-1)^(s-j) C(k, s-j) (k-1-s)^(k-1-n)

(Qin, "General matrix representations for B-splines", The Visual Computer 16, 2000). The
cumulative matrix has rows ``Mc[j] = sum_{l >= j} M[l]``, so that ``Btilde_0 = 1`` and the
cumulative spline reads ``x(u) = x_i + sum_{j>=1} Btilde_j(u) (x_{i+j} - x_{i+j-1})``.
"""

from __future__ import annotations

from fractions import Fraction
from functools import cache
from math import comb, factorial

import numpy as np

from .._kernels import spline as _ks

MIN_ORDER = 2
MAX_ORDER = 8


@cache
def _blending_exact(order: int) -> tuple:
    k = order
    rows = []
    for j in range(k):
        row = []
        for n in range(k):
            acc = 0
            for s in range(j, k):
                acc += (-1) ** (s - j) * comb(k, s - j) * (k - 1 - s) ** (k - 1 - n)
            row.append(Fraction(comb(k - 1, n) * acc, factorial(k - 1)))
        rows.append(tuple(row))
    return tuple(rows)


def blending_matrix(order: int, cumulative: bool = False) -> np.ndarray:
    """Blending matrix ``M`` (order, order): basis values ``M @ u_powers``.

    Parameters
    ----------
    order : int
        Spline order ``k`` (4 is cubic).
    cumulative : bool
        Return the cumulative matrix ``Mc`` (row j sums rows j..k-1 of ``M``).

    Examples
    --------
    >>> blending_matrix(4) * 6
    array([[ 1., -3.,  3., -1.],
           [ 4.,  0., -6.,  3.],
           [ 1.,  3.,  3., -3.],
           [ 0.,  0.,  0.,  1.]])
    """
    if not (MIN_ORDER <= int(order) <= MAX_ORDER):
        raise ValueError(f"spline order must be in [{MIN_ORDER}, {MAX_ORDER}], got {order}")
    rows = _blending_exact(int(order))
    if cumulative:
        k = len(rows)
        rows = tuple(tuple(sum(rows[l][n] for l in range(j, k)) for n in range(k)) for j in range(k))
    return np.array([[float(v) for v in r] for r in rows], dtype=np.float64)


def basis_values(order: int, u, derivative: int = 0, cumulative: bool = False) -> np.ndarray:
    """Basis (or cumulative basis) values, or their ``derivative``-th u-derivative, at ``u`` (N,).

    Evaluated by the kernels' own :func:`splineimu._kernels.spline.basis_into` (one
    implementation for fitting, evaluation and this function).

    Parameters
    ----------
    order : int
    u : (N,) array_like
        Segment parameters, normally in [0, 1).
    derivative : {0, 1, 2}
    cumulative : bool

    Returns
    -------
    (N, order) ndarray

    Examples
    --------
    >>> basis_values(4, [0.0]) * 6
    array([[1., 4., 1., 0.]])
    """
    if derivative not in (0, 1, 2):
        raise ValueError(f"derivative must be 0, 1 or 2, got {derivative}")
    M = blending_matrix(order, cumulative)
    u = np.ascontiguousarray(np.atleast_1d(np.asarray(u, dtype=np.float64)).reshape(-1))
    out = np.empty((3, u.size, M.shape[0]))
    _ks.basis_table(M, u, 1.0, out)
    return out[derivative]
