"""Banded normal equations of spline fits: difference penalties and banded Cholesky solves.

A fit's normal matrix is kept as its scalar upper band ``band[i, c]`` = entry ``(i, i + c)``,
shape (n d, k d) for ``n`` controls of dimension ``d`` and order ``k`` ((n, k) for the position part
of split splines).
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .._kernels import fit as _kf
from .._kernels import gauss_newton as _gn
from ..exactfloat import two_product

#: Relative weight of the default smoothness penalty where data are dense (negligible bias).
DEFAULT_SMOOTHNESS = 1e-10
#: Relative penalty weight on control points with little data in their support (gaps, sparse
#: stretches): there the curve is the smoothest bridge, instead of being steered by the noise of
#: the few poses at the gap's borders.
SPARSE_SMOOTHNESS = 1e-3
#: Relative weight of the second-difference penalty on position controls whose segments hold no
#: pose only because the knots are finer than the poses (:class:`splineimu.spline.problem._Problem`'s
#: ``bridge``; where held-out poses are predicted better so, :func:`splineimu.spline.problem.bridge_weight`):
#: between the poses the curve bends least, as a cubic interpolating spline does, instead of
#: jerking least.
BRIDGE_SMOOTHNESS = 1e-2


def solve_banded_scalar(Hs, rhs):
    """Solve the symmetric banded system with upper diagonals ``Hs`` (n, k) for ``rhs`` (n, ...)
    (banded Cholesky in a kernel; ``Hs`` is left untouched)."""
    n = Hs.shape[0]
    B = np.array(rhs, dtype=np.float64, order="C").reshape(n, -1)
    if not _kf.band_cholesky_solve(np.array(Hs, dtype=np.float64, order="C"), B):
        raise np.linalg.LinAlgError("banded normal matrix is not positive definite")
    return B.reshape(np.shape(rhs))


@cache
def _difference_coefficients(order_diff):
    c = np.array([1.0])
    for _ in range(order_diff):
        c = np.convolve(c, [-1.0, 1.0])
    return tuple(c)


def difference_coefficients(order_diff):
    """Coefficients of the order-r difference operator: row j touches j .. j + r."""
    return np.array(_difference_coefficients(order_diff))  # length r + 1


def add_position_penalty(Hs, mu, r):
    """Add D_r^T diag(mu) D_r to scalar banded blocks Hs (n, k); mu scalar or per row (n - r,)."""
    n, k = Hs.shape
    L = r + 1
    if L > k or n < L:
        return
    mu = np.ascontiguousarray(np.broadcast_to(np.asarray(mu, dtype=np.float64), (n - L + 1,)))
    c = np.array(_difference_coefficients(r))
    if Hs.flags.c_contiguous and Hs.dtype == np.float64:
        _gn.add_difference_penalty(Hs, mu, c)
        return
    for a in range(L):
        for b in range(a, L):
            Hs[a: n - L + 1 + a, b - a] += mu * c[a] * c[b]


def row_weights(sparse, width):
    """Per penalty row touching controls j .. j + width - 1: True where any of them is sparse."""
    n = sparse.size
    if n < width:
        return np.zeros(0, dtype=bool)
    return np.convolve(np.asarray(sparse, dtype=np.float64), np.ones(width), mode="valid") > 0


def layout(t_first, t_last, knot_spacing_s, order):
    """Knot layout covering [t_first, t_last] exactly: (t0, dt, n_segments, n_control)."""
    span = float(t_last - t_first)
    nseg = max(1, int(round(span / float(knot_spacing_s))))
    dt = span / nseg if span > 0 else float(knot_spacing_s)
    return float(t_first), dt, nseg, nseg + order - 1


def grid_layout(t_first, t_last, origin, dt, order):
    """Knot layout (t0, dt, n_segments, n_control) of the grid ``origin + i dt`` over
    [t_first, t_last]: its first knot is the last one at or before ``t_first`` (a rotation grid
    shifted against the motion, :mod:`.phase`)."""
    m = np.floor((t_first - origin) / dt + 1e-9)
    t0 = float(origin + m * dt)
    nseg = max(1, int(np.ceil((t_last - t0) / dt - 1e-9)))
    return t0, float(dt), nseg, nseg + order - 1


def shifted_layout(t_first, t_last, dt, order, phase):
    """:func:`layout`, the grid moved ``phase`` spacings before ``t_first``."""
    lay = layout(t_first, t_last, dt, order)
    if phase == 0.0:
        return lay
    return grid_layout(t_first, t_last, t_first - phase * lay[1], lay[1], order)


#: A grid is moved half a spacing when its alternating control mode shows at the poses with
#: less than this share of its largest response (mean square over the poses).
UNSEEN_MODE_SHARE = 1e-2


@cache
def _alternating(order):
    """The value of the alternating controls (+1, -1, ...) at u (a callable), and its largest."""
    from .basis import basis_values

    sign = (-1.0) ** np.arange(order)
    top = float(np.abs(basis_values(order, np.linspace(0.0, 1.0, 65)) @ sign).max())
    return (lambda u: basis_values(order, u) @ sign), top


def observable_layout(t, lay, order):
    """``lay``, or the same grid moved half a spacing earlier where its alternating control
    mode ((+1, -1, ...): the finest detail a grid holds) is all but unseen at the poses ``t``,
    and whether it moved. That mode is zero at the knots of an odd order and midway between
    them for an even one. Poses at a regular rate with knots at that rate on them leave it to
    whatever shows it: stamps off the grid by their rounding (EuRoC's, +-128 ns at 20 Hz) give it
    a tiny weight against the data, and it follows the pose noise between the poses: V1_02's
    vicon2gt with order-5 knots at its 50 ms, gyro and accel 20x and 16x order 4's below 10 Hz
    against the real IMU (orders 3 and 7 alike; the flips scene 6-16x in gyro). Half a spacing
    further it is seen at every pose, as an even order's at its knots is: within 3% of order 4
    there. (Exactly regular stamps left the mode to the smoothness penalty, which set it to zero:
    orders 5 and 7 then dropped the top of the band, pose noise there included: accel 0.16 and
    0.13 m/s^2 on the ellipse at 20 Hz with 0.1 mm noise, 0.26 now, order 4 0.20, order 6 0.14.)
    Grids coarser than 1.5 pose spacings are not looked at (their poses fall at many phases)."""
    t0, dt, _, _ = lay
    if t.size < 2 or dt > 1.5 * (t[-1] - t[0]) / (t.size - 1):
        return lay, False
    value, top = _alternating(int(order))
    u = segments(t, t0, dt)[1]
    if float(np.mean(value(u) ** 2)) >= UNSEEN_MODE_SHARE * top**2:
        return lay, False
    return grid_layout(t[0], t[-1], t0 - 0.5 * dt, dt, order), True


def segments(t, t0, dt):
    """Segment index (int64) and the fraction u in [0, 1] of the knot spacing within it, of
    times ``t`` on the knots ``t0 + i dt``, without the rounding of ``s = (t - t0) / dt``: s
    held in one float has steps of 1.2e-10 at 6.5e5 segments (an hour at 5.5 ms), which moves
    each pose by 6e-13 s, for 6 m/s a position error of 4e-12 m; the fit passed that to the
    accelerometer (exact ellipse poses, 1 minute with such jitter: 3.8e-9 -> 2.4e-8 m/s^2)."""
    t = np.asarray(t, dtype=np.float64)
    seg = np.floor((t - t0) / dt)
    # r = t - t0 - seg dt, with t - t0 and seg dt each carried as two floats
    a = t - t0
    back = a - t
    a_lo = (t - (a - back)) + (-t0 - back)  # the rounding of t - t0 (Knuth's two-sum)
    p, e = two_product(seg, dt)
    r = ((a - p) - e) + a_lo
    u = r / dt
    seg = seg.astype(np.int64)
    low, high = u < 0.0, u >= 1.0
    seg[low] -= 1
    u[low] += 1.0
    seg[high] += 1
    u[high] -= 1.0
    return seg, u


class BandSolver:
    """Solves with one symmetric positive definite band matrix (upper diagonals ``band`` (n, w)),
    optionally damped (Levenberg-Marquardt: ``lam * max(diag, 1e-12)`` added to the diagonal);
    the Cholesky factor is kept for further right-hand sides with the same damping."""

    def __init__(self, band):
        self.band = band
        self._factor = None
        self._lam = None

    def solve(self, rhs, lam=0.0):
        B = np.array(rhs, dtype=np.float64, order="C").reshape(self.band.shape[0], -1)
        if self._factor is None or lam != self._lam:
            U = self.band.copy()
            if lam:
                U[:, 0] += lam * np.maximum(U[:, 0], 1e-12)
            if not _kf.band_cholesky_solve(U, B):
                raise np.linalg.LinAlgError("banded normal matrix is not positive definite")
            self._factor, self._lam = U, lam
        else:
            _kf.band_factored_solve(self._factor, B)
        return B.reshape(np.shape(rhs))
