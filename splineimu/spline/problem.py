"""The least-squares problems of a fit at a fixed knot layout: the position (linear, banded),
the rotation on SO3 and the whole pose on SE3 (Gauss-Newton / Levenberg-Marquardt, banded), and
the rotation's starting point, and whether positions finer than their poses bend least between them
(:func:`bridge_weight`). :func:`splineimu.spline.fit.fit` chooses the layouts and runs
them; the formulation is in its module docstring."""

from __future__ import annotations

from functools import cache

import numpy as np

from .. import lie
from .._kernels import fit as _kf
from .._kernels import gauss_newton as _gn
from .banded import (
    BRIDGE_SMOOTHNESS,
    DEFAULT_SMOOTHNESS,
    SPARSE_SMOOTHNESS,
    BandSolver,
    add_position_penalty,
    row_weights,
    segments,
    solve_banded_scalar,
)
from .basis import blending_matrix
from .controls import _increments_se3, _to_matrices, _to_quats

#: Gauss-Newton stops when the largest update is below this (rad, or m for SE3 translation) ...
GN_STEP_TOL = 1e-9
#: ... or, for the rotation where the pose noise is known (the automatic choice measured it),
#: below this fraction of it: the rest moves the controls by far less than the noise does
#: (flips, 12k poses, 0.1 deg: steps 2e-2, 3e-5, 7e-8, 1e-9, 4e-12 rad; two passes fewer)
GN_STEP_REL = 1e-4
#: Gauss-Newton rebuilds the normal matrix after steps larger than this (rad, or m for SE3)
H_REFRESH_STEP = 1e-2
#: The initialization fits the outer controls to the poses of this many times the order segments
#: at each end, for at most END_ITERATIONS steps, down to steps of END_STEP_TOL (rad).
END_SEGMENTS = 2
END_ITERATIONS = 6
END_STEP_TOL = 1e-4
#: Prior on the second differences of the rotation increments that involve a control rotation
#: beyond the data (rad, one standard deviation, against the poses' weights of 1 / noise^2). The
#: data hardly see those controls (order 6: one 120th of the end pose's rotation), so without it
#: their least-squares value follows the end poses' noise by radians and Gauss-Newton wanders
#: (OpenVINS's udel_garage, 10 Hz, 169 ms knots: 143 iterations unconverged, 6 rad steps on the
#: last control; with it: 4). Real motion's second differences there are ~jerk * spacing^3,
#: hundredths of a radian; with exact poses (weights ~1e12) the prior is below the default
#: smoothness.
END_TURN_SIGMA_RAD = 0.1


@cache
def _blending(order):
    """Plain and cumulative blending matrices (built from exact fractions: worth keeping)."""
    return blending_matrix(order), blending_matrix(order, cumulative=True)


@cache
def _quasi_interpolant(order):
    """``(a1, a2)``: control points ~ ``(1 + a1 d2 + a2 d2^2) f`` for samples ``f`` at the control times
    (``d2`` the second difference), from the moments ``m2, m4`` of the basis weights with which
    a spline's value at a control time averages its control points (T = 1 + t1 d2 + t2 d2^2 + ...,
    t1 = m2 / 2, t2 = (m4 - m2) / 24, inverted)."""
    M = blending_matrix(order)
    uc = 0.0 if order % 2 == 0 else 0.5
    w = M @ uc ** np.arange(order)
    pos = np.arange(order) - (order - 2) / 2.0 - uc
    m2, m4 = float(w @ pos**2), float(w @ pos**4)
    t1, t2 = m2 / 2.0, (m4 - m2) / 24.0
    return -t1, t1 * t1 - t2


def _control_times(t0, dt, n, order):
    """Time at the centre of each control point's support."""
    return t0 + (np.arange(n) - (order - 2) / 2.0) * dt


class _Problem:
    """One fit at a fixed knot layout."""

    def __init__(self, t, P, R, q, w, order, t0, dt, nseg, smoothness, w_rot, w_pos, noise_rad=None, bridge=0.0,
                 bridge_span=None):
        self.t, self.P, self.R, self.q, self.w = t, P, R, q, w
        self.noise_rad = noise_rad
        self.step_tol = GN_STEP_TOL if noise_rad is None else max(GN_STEP_TOL, GN_STEP_REL * noise_rad)
        self.order, self.t0, self.dt, self.nseg = order, t0, dt, nseg
        self.n = nseg + order - 1
        self.seg, self.u = segments(t, t0, dt)  # the kernels' parameter, without the rounding of s
        self.s = self.seg + self.u
        self.M, self.Mc = (m.copy() for m in _blending(order))
        self.smoothness = smoothness
        self.w_rot = w_rot
        self.w_pos = w_pos
        # penalty scale: data weight per control point
        self.data_per_ctrl = max(float(np.sum(w)) / self.n, 1e-12)
        # a control point whose support contains a segment without any pose borders a gap
        seg = np.clip(self.seg, 0, nseg - 1)
        empty = (np.bincount(seg[w > 0], minlength=nseg) == 0).astype(np.float64)
        self.sparse = np.convolve(empty, np.ones(order))[: self.n] > 0
        # with ``bridge`` > 0, the position controls of segments empty only because the knots are
        # finer than the poses (poses at most ``bridge_span`` apart around them, by default 1.5
        # median spacings: not a gap) take a second-difference penalty of that relative weight
        # instead of the third-difference one
        self.bridge = np.zeros(self.n, dtype=bool)
        if bridge > 0 and empty.any():
            tw = t[w > 0]
            j = np.flatnonzero(empty)
            i = np.clip(np.searchsorted(tw, t0 + j * dt), 1, tw.size - 1)
            between = np.zeros(nseg)
            span = 1.5 * float(np.median(np.diff(tw))) if bridge_span is None else bridge_span
            between[j[tw[i] - tw[i - 1] <= span]] = 1.0
            self.bridge = np.convolve(between, np.ones(order))[: self.n] > 0
            self.sparse = np.convolve(empty - between, np.ones(order))[: self.n] > 0
        self.bridge_weight = float(bridge)
        self.n_sparse = int(self.sparse.sum())
        # control rotations centred beyond the first or last pose (the data weigh them by the
        # tails of their basis functions: 1/120 at most for order 6)
        tc = _control_times(t0, dt, self.n, order)
        self.outside = (tc < t[0] - 1e-9 * dt) | (tc > t[-1] + 1e-9 * dt)

    def _mu(self, width):
        return np.where(row_weights(self.sparse, width), SPARSE_SMOOTHNESS, self.smoothness) * self.data_per_ctrl

    # ------------------------------------------------------------------ position (split)
    def solve_positions(self):
        k, n = self.order, self.n
        Hs = np.zeros((n, k))
        rhs = np.zeros((n, 3))
        w = self.w * self.w_pos
        _kf.fold_normal_equations(self.seg, self.u, w, np.zeros(self.t.size, dtype=np.int64), self.P, self.M, self.nseg,
                                  Hs[None], rhs[None])
        r = min(3, k - 1)
        add_position_penalty(Hs, self._mu(r + 1) * self.w_pos, r)
        if self.bridge.any():
            rows = row_weights(self.bridge, 3) & ~row_weights(self.sparse, 3)
            add_position_penalty(Hs, np.where(rows, self.bridge_weight * self.data_per_ctrl * self.w_pos, 0.0), 2)
        return solve_banded_scalar(Hs, rhs)

    def position_residuals(self, Pc):
        out = np.empty((self.t.size, 3))
        _kf.position_residuals(self.seg, self.u, self.P, Pc, self.M, self.nseg, out)
        return out

    # ------------------------------------------------------------------ rotation (split)
    def _so3_system(self, qc, want_h):
        n, k = self.n, self.order
        D = np.empty((n, 3))
        C = np.empty((n, 3, 3))
        _gn.so3_knot_terms(qc, D, C)
        band = np.zeros((3 * n, 3 * k)) if want_h else np.zeros((0, 0))
        g = np.zeros((n, 3))
        res = np.empty((self.t.size, 3))
        w = self.w * self.w_rot
        cost = _gn.so3_pass(self.seg, self.u, w, self.q, qc, D, C, self.Mc, self.nseg, want_h, band, g, res)
        Cl = np.ascontiguousarray(np.swapaxes(C, 1, 2))  # Jl^-1(d) = Jr^-1(d)^T
        cost += _gn.increment_penalty(D, C, Cl, self._penalty_weights(1.0), want_h, band, g)
        return cost, (band if want_h else None), g, res

    def initial_rotations(self):
        """Control rotations (n, 3, 3) to start Gauss-Newton from: the quasi-interpolant of the
        poses on the control grid (:func:`splineimu._kernels.gauss_newton.control_grid_init`),
        whose outermost controls, which the data pin down only weakly, are then fitted to the
        poses of the end segments alone."""
        qc = np.empty((self.n, 4))
        _gn.control_grid_init(self.t, self.q, _control_times(self.t0, self.dt, self.n, self.order),
                              *_quasi_interpolant(self.order), qc)
        m = END_SEGMENTS * self.order
        if self.nseg >= 3 * m:
            self._solve_end(qc, 0, m)
            self._solve_end(qc, self.nseg - m, m)
        return _to_matrices(qc)

    def _solve_end(self, qc, seg0, m, max_iter=END_ITERATIONS):
        """Gauss-Newton in place on ``qc`` for the outer ``m`` controls of the ``m`` segments from
        ``seg0`` (the first or the last ones), from their poses, the controls further in held."""
        k = self.order
        ns = m + k - 1
        i0, i1 = np.searchsorted(self.s, [seg0, seg0 + m])
        if seg0 > 0:
            i1 = self.s.size
        sl = slice(i0, i1)
        seg_sub, u_sub = self.seg[sl] - seg0, self.u[sl]
        w = self.w[sl] * self.w_rot
        mu = self._penalty_weights(1.0)[seg0: seg0 + ns - 2]
        free = slice(0, 3 * m) if seg0 == 0 else slice(3 * (k - 1), 3 * ns)
        q_sub = qc[seg0: seg0 + ns].copy()
        cost_prev = np.inf
        for _ in range(max_iter):
            D = np.empty((ns, 3))
            C = np.empty((ns, 3, 3))
            _gn.so3_knot_terms(q_sub, D, C)
            band = np.zeros((3 * ns, 3 * k))
            g = np.zeros((ns, 3))
            cost = _gn.so3_pass(seg_sub, u_sub, w, self.q[sl], q_sub, D, C, self.Mc, m, True, band, g,
                                np.empty((u_sub.size, 3)))
            cost += _gn.increment_penalty(D, C, np.ascontiguousarray(np.swapaxes(C, 1, 2)), mu, True, band, g)
            if not cost < cost_prev:
                break
            qc[seg0: seg0 + ns] = q_sub
            cost_prev = cost
            delta = np.zeros(3 * ns)
            try:
                delta[free] = BandSolver(np.ascontiguousarray(band[free])).solve(-g.reshape(-1)[free])
            except np.linalg.LinAlgError:
                break
            q_new = np.empty_like(q_sub)
            _gn.so3_retract(q_sub, delta.reshape(ns, 3), q_new)
            q_sub = q_new
            if np.abs(delta).max() < END_STEP_TOL:
                break

    def solve_rotations(self, Rc, max_iter=30, tol=1e-12, progress=None):
        def retract(qc, delta):
            out = np.empty_like(qc)
            _gn.so3_retract(qc, delta, out)
            return out

        qc, res, it, conv = self._gauss_newton(_to_quats(Rc), self._so3_system, retract, max_iter, tol, progress,
                                               self.step_tol)
        return _to_matrices(qc), res, it, conv

    def _penalty_weights(self, w_pen):
        key = float(w_pen)
        if getattr(self, "_mu_cache", (None,))[0] != key:
            mu = self._mu(3) * self.w_rot
            mu = np.where(row_weights(self.outside, 3), np.maximum(mu, END_TURN_SIGMA_RAD**-2), mu)
            self._mu_cache = (key, np.ascontiguousarray(mu * w_pen, dtype=np.float64))
        return self._mu_cache[1]

    # ------------------------------------------------------------------ SE3
    def _se3_system(self, x, want_h):
        """The SE3 kernel always builds the normal matrix; ``want_h`` only says whether it is kept."""
        Rc, pc = x
        n, k = self.n, self.order
        D = _increments_se3(Rc, pc)
        H = np.zeros((n, k, 6, 6))
        g = np.zeros((n, 6))
        res = np.empty((self.t.size, 6))
        w6 = np.ascontiguousarray(np.column_stack([self.w * self.w_pos] * 3 + [self.w * self.w_rot] * 3))
        cost = _kf.se3_normal_equations(self.seg, self.u, w6, self.R, self.P, Rc, pc, D, self.Mc, self.nseg, H, g, res)
        band = np.zeros((6 * n, 6 * k))
        _kf.blocks_to_band(H, band)
        Jr_inv = np.zeros((n, 6, 6))
        Jl_inv = np.zeros((n, 6, 6))
        Jr_inv[1:] = lie.se3_right_jacobian_inv(D[1:])
        Jl_inv[1:] = lie.se3_left_jacobian_inv(D[1:])
        # scale the penalty per component like the data weights
        cost += _gn.increment_penalty(D, Jr_inv, Jl_inv, self._penalty_weights(np.sqrt(self.w_pos / self.w_rot)),
                                      True, band, g)
        return cost, band, g, res

    def solve_se3(self, Rc, pc, max_iter=30, tol=1e-12, progress=None):
        def retract(x, delta):
            T = lie.se3_exp(delta)
            return np.matmul(x[0], T[:, :3, :3]), x[1] + np.einsum("nij,nj->ni", x[0], T[:, :3, 3])

        (Rc, pc), res, it, conv = self._gauss_newton((Rc, pc), self._se3_system, retract, max_iter, tol, progress)
        return Rc, pc, res, it, conv

    # ------------------------------------------------------------------ Gauss-Newton / LM
    @staticmethod
    def _gauss_newton(x, system, retract, max_iter, tol, progress, step_tol=GN_STEP_TOL):
        """Minimize over the state ``x``: ``system(x, want_h)`` gives ``(cost, band or None, g, res)``
        (``band`` the upper band of the normal matrix), ``retract(x, delta)`` the updated state.

        The normal matrix is rebuilt after steps larger than :data:`H_REFRESH_STEP` and when the
        steps stop shrinking fast; otherwise the steps reuse the last factorization (the fixed point,
        ``g = 0``, is the same; the matrix changes by O(step), so the convergence stays fast) and a
        pass needs the gradient alone. A step that raises the cost is retried with a fresh matrix,
        then with Levenberg-Marquardt damping. Converged: a step below ``step_tol``, or
        steps from a fresh matrix that no longer shrink while the cost no longer falls (rounding).
        """
        cost, band, g, res = system(x, True)
        solver = BandSolver(band)
        fresh = True  # the factorization was built at x
        lam = 0.0
        prev_step = np.inf
        it = 0
        converged = False
        for it in range(1, max_iter + 1):
            delta = solver.solve(-g.reshape(-1), lam).reshape(g.shape)
            step = float(np.abs(delta).max())
            x_new = retract(x, delta)
            if progress is not None:
                progress(it)
            if lam == 0.0 and step < step_tol:
                # converged: the residuals at the new point differ from these by O(step)
                x = x_new
                converged = True
                break
            slow = step > 0.5 * prev_step
            cost_new, band_new, g_new, res_new = system(x_new, step > H_REFRESH_STEP or (slow and not fresh))
            if cost_new <= cost * (1 + 1e-12) or not np.isfinite(cost):
                small = step < 1e-13 or (fresh and slow and (cost - cost_new) <= tol * max(cost, 1e-300))
                prev_step = step
                x, cost, g, res = x_new, cost_new, g_new, res_new
                if band_new is not None:
                    solver = BandSolver(band_new)
                fresh = band_new is not None
                lam = lam / 10 if lam > 1e-9 else 0.0
                if small:
                    converged = True
                    break
            elif not fresh:
                # the step came from an old matrix: rebuild it here and try again
                cost, band, g, res = system(x, True)
                solver = BandSolver(band)
                fresh = True
            else:
                lam = 1e-4 if lam == 0 else lam * 10
                if lam > 1e8:
                    break
        return x, res, it, converged


def bridge_weight(choice, kind, position_dt, lay, t, P, w, order, sig_p, smoothness=DEFAULT_SMOOTHNESS):
    """Relative weight of the second-difference bridge between the poses of the position fit
    (:data:`.banded.BRIDGE_SMOOTHNESS`; 0: none), for positions read as motion-limited and chosen
    finer than their poses, where the knots between the poses are set by the penalty alone:
    bending least (as scipy's cubic interpolation does) or jerking least (the default). Bending
    least keeps less of the top of the band, where motion aliased by the pose rate and an
    estimator's error sit (EuRoC's 20 Hz vicon2gt against the real IMU: accel below 10 Hz
    1.017x -> 1.006x scipy's), but smooths motion that is there (exact poses of fast motion at
    20 Hz: 11x the error). Taken where it predicts every 4th pose from the others better (the
    held-out fits bridge the two spacings around each left-out pose alike): V1_02 / V1_03 /
    V2_02 / V2_03's vicon2gt (their 200 Hz poses every 10th), 7 of 15 BROAD trials every 14th
    pose; not V2_01, BROAD 16, white-noise or exact motion. Returns the weight and the ratio of the two
    held-out errors (bending least / jerking least; None where not tried)."""
    if choice is None or kind != "split" or position_dt != "auto" or not choice["position"]["motion_limited"]:
        return 0.0, None
    tw = t[w > 0]
    h = float(np.median(np.diff(tw)))
    if lay[1] >= h or tw.size < 64:
        return 0.0, None
    idx = np.arange(t.size)
    scores = []
    for weight in (0.0, BRIDGE_SMOOTHNESS):
        total = 0.0
        for f in range(4):
            held = (idx % 4 == f) & (w > 0)
            held[[0, -1]] = False
            prob = _Problem(t, P, None, None, np.where(held, 0.0, w), order, *lay[:3], smoothness, 1.0,
                            1.0 / sig_p**2, bridge=weight, bridge_span=2.5 * h)
            total += float(np.sum(prob.position_residuals(prob.solve_positions())[held] ** 2))
        scores.append(total)
    ratio = float(np.sqrt(scores[1] / scores[0])) if scores[0] > 0 else None
    return (BRIDGE_SMOOTHNESS if scores[1] < scores[0] else 0.0), ratio


def bridge_note(choice):
    """The report's note where the positions were bridged between their poses by least bending."""
    pos = choice["position"] if choice is not None else {}
    if not pos.get("bridge_smoothness"):
        return []
    return [f"positions bend least between the poses (second differences, as cubic interpolation): every 4th pose "
            f"held out is predicted {100 * (1 - pos['bridge_heldout_ratio']):.0f}% better so than jerking least"]
