"""The :class:`Spline` motion source: cumulative uniform B-splines on SE3 or R3 x SO3."""

from __future__ import annotations

import itertools

import numpy as np

from .. import lie
from .._kernels import se3_imu as _ks
from .._kernels import spline as _k
from .._kernels import spline_imu as _ki
from ..errors import SplineImuError
from ..motion import DEFAULT_GRAVITY, Kinematics, MotionSource
from .basis import MAX_ORDER, blending_matrix

KINDS = ("split", "se3")
#: Arrays of up to this many times are evaluated sample by sample in :meth:`Spline.imu`, which
#: is faster than setting up the vectorized kernel below ~130 (se3) to ~200 (split) samples
#: (measured at order 4: 1.8 against 15 us for one, 9 to 13 against 19 us for 64).
FEW_SAMPLES = 64
_F64 = np.dtype(np.float64)
# the default gravity as the kernels take it (private: the one-sample path passes it as it is)
_GRAVITY = np.array(DEFAULT_GRAVITY, dtype=np.float64)
# Outputs of the one-sample path of imu(): (1, 3) rows of (64, 1, 3) blocks, handed out in
# turn. Making a view costs half of making an array (~80 against ~160 ns on the project's
# machine, where a whole call costs ~0.6 us); a result that is kept keeps its block (1.5 kB).
_ROWS = itertools.chain.from_iterable(map(np.empty, itertools.repeat((64, 1, 3))))


def _check_order(order, name):
    order = int(order)
    if not (2 <= order <= MAX_ORDER):
        raise SplineImuError(f"spline {name} must be in [2, {MAX_ORDER}], got {order}")
    return order


def _check_dt(dt_s, name):
    dt_s = float(dt_s)
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise SplineImuError(f"knot spacing {name} must be positive and finite, got {dt_s}")
    return dt_s


class Spline(MotionSource):
    r"""Cumulative uniform B-spline of order ``k`` on SE3 (``kind="se3"``) or R3 x SO3 (``"split"``).

    Control poses ``T_0 .. T_{n-1}`` at uniform knot spacing ``dt``; for ``t`` in segment ``i``
    with ``u(t) = (t - t_min)/dt - i`` in [0, 1):

    - ``"se3"`` (Lovegrove et al., BMVC 2013):
      ``T(t) = T_i prod_{j=1}^{k-1} Exp(Btilde_j(u) Log(T_{i+j-1}^-1 T_{i+j}))``.
    - ``"split"``: the same cumulative product on SO3 for the rotation, and an ordinary
      B-spline ``p(t) = sum_j B_j(u) p_{i+j}`` for the position, so that translation and
      rotation are decoupled and the world acceleration is the basis' second derivative. The
      position may have its own grid (``position_t0_s``, ``position_dt_s``,
      ``position_order``; its own ``u`` and segment), so that rotation and position are
      smoothed independently; the valid range is then the intersection of both.

    ``B(u) = M [1, u, ..., u^(k-1)]`` with the blending matrix ``M`` of
    :func:`splineimu.spline.basis.blending_matrix`; ``Btilde`` uses the cumulative matrix.
    Segment ``i`` is supported by control points ``i .. i+k-1``; the valid time range is
    ``[t_min_s, t_max_s] = [t0_s, t0_s + (n - k + 1) dt_s]``. Times are float seconds since the
    integer-nanosecond origin ``origin_ns``, so Unix-epoch stamps keep full precision.

    Derivatives are analytic (Sommer et al., CVPR 2020, O(k) recursion): body angular
    velocity ``omega_body`` (``R^T dR/dt = [omega]x``) and acceleration, world velocity and
    acceleration of the body origin, and specific force ``f_b = R^T (a_w - g_w)``. For
    ``"se3"`` the world acceleration is ``a_w = R (w_b x v_b + dv_b/dt)``.

    Examples
    --------
    >>> import numpy as np
    >>> n = 8
    >>> pos = np.c_[np.arange(n, dtype=float), np.zeros(n), np.zeros(n)]
    >>> quat = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    >>> spl = Spline.from_control_points(0.0, 0.1, pos, quat, kind="split", order=4)
    >>> float(spl.t_max_s)
    0.5
    >>> np.round(spl.velocity_world([0.25])[0], 12)
    array([10.,  0.,  0.])
    """

    # caches of imu(), built on first use (class defaults also serve splines pickled before them)
    _imu_knots = None
    _imu_one = None
    _imu_one_table = None

    def __init__(self, t0_s, dt_s, positions, rotations, kind="split", order=4, origin_ns=0, *,
                 position_t0_s=None, position_dt_s=None, position_order=None):
        kind = str(kind).lower()
        if kind not in KINDS:
            raise SplineImuError(f"spline kind must be one of {KINDS}, got {kind!r}")
        order = _check_order(order, "order")
        dt_s = _check_dt(dt_s, "dt_s")
        separate = not (position_t0_s is None and position_dt_s is None and position_order is None)
        if separate and kind != "split":
            raise SplineImuError("a separate position grid needs kind='split'")
        p_order = order if position_order is None else _check_order(position_order, "position_order")
        p_dt = dt_s if position_dt_s is None else _check_dt(position_dt_s, "position_dt_s")
        p_t0 = float(t0_s) if position_t0_s is None else float(position_t0_s)
        P = np.ascontiguousarray(np.asarray(positions, dtype=np.float64))
        R = np.ascontiguousarray(np.asarray(rotations, dtype=np.float64))
        if P.ndim != 2 or P.shape[1] != 3:
            raise SplineImuError(f"Expected `positions` to have shape (n, 3), got {P.shape}")
        if R.ndim != 3 or R.shape[1:] != (3, 3) or (not separate and R.shape[0] != P.shape[0]):
            want = "(n, 3, 3)" if separate else f"({P.shape[0]}, 3, 3)"
            raise SplineImuError(f"Expected rotations of shape {want}, got {R.shape}")
        if R.shape[0] < order:
            raise SplineImuError(f"an order-{order} spline needs at least {order} control points, got {R.shape[0]}")
        if P.shape[0] < p_order:
            raise SplineImuError(f"an order-{p_order} spline needs at least {p_order} control points, got {P.shape[0]}")
        if not (np.all(np.isfinite(P)) and np.all(np.isfinite(R))):
            raise SplineImuError("control points contain NaN or inf")
        self.kind = kind
        self.order = order
        self.dt_s = dt_s
        self.t0_s = float(t0_s)
        self.position_order = p_order
        self.position_dt_s = p_dt
        self.position_t0_s = p_t0
        self.origin_ns = int(origin_ns)
        self.control_positions = P
        self.control_rotations = R
        self._M = blending_matrix(p_order)
        self._Mc = blending_matrix(order, cumulative=True)
        self._build_increments()

    # ----------------------------------------------------------------- construction
    @classmethod
    def from_control_points(cls, t0_s, dt_s, positions, quat_xyzw, kind="split", order=4, origin_ns=0, *,
                            position_t0_s=None, position_dt_s=None, position_order=None):
        """Spline from control positions (n, 3) and quaternions ``quat_xyzw`` (n, 4).

        Quaternions are normalized; their signs do not matter (each increment between
        neighbouring control rotations is taken as the shortest rotation).

        Parameters
        ----------
        t0_s : float
            Start of the valid range, seconds since ``origin_ns``.
        dt_s : float
            Knot spacing [s].
        positions : (n, 3) array_like
        quat_xyzw : (n, 4) array_like
        kind : {"split", "se3"}
        order : int
            4 (cubic, default) to 8; 5 and 6 give smoother derivatives.
        origin_ns : int
            Integer time origin [ns] of the time base.
        position_t0_s, position_dt_s, position_order : optional
            Split splines only: the position grid's start, knot spacing and order, when they
            differ from the rotation grid's (``t0_s``, ``dt_s``, ``order``); ``positions`` then
            has its own length.

        Raises
        ------
        SplineImuError
            Bad shapes, fewer than ``order`` control points, zero quaternions, bad ``dt_s``.
        """
        q = np.asarray(quat_xyzw, dtype=np.float64)
        if q.ndim != 2 or q.shape[1] != 4:
            raise SplineImuError(f"Expected `quat_xyzw` to have shape (n, 4), got {q.shape}")
        return cls(t0_s, dt_s, positions, lie.quat_xyzw_to_matrix(q), kind, order, origin_ns,
                   position_t0_s=position_t0_s, position_dt_s=position_dt_s, position_order=position_order)

    def _build_increments(self):
        R = self.control_rotations
        n = R.shape[0]
        rel_R = np.matmul(np.swapaxes(R[:-1], 1, 2), R[1:])
        if self.kind == "split":
            D = np.zeros((n, 3))
            D[1:] = lie.so3_log(rel_R)
        else:
            T = np.zeros((n - 1, 4, 4))
            T[:, :3, :3] = rel_R
            dp = self.control_positions[1:] - self.control_positions[:-1]
            T[:, :3, 3] = np.einsum("nji,nj->ni", R[:-1], dp)
            T[:, 3, 3] = 1.0
            D = np.zeros((n, 6))
            D[1:] = lie.se3_log(T)
        self._D = np.ascontiguousarray(D)
        # per-knot table of the vectorized imu() kernels, built on their first call (32 or 64
        # bytes per knot, not worth holding for splines that never produce IMU data)
        self._imu_knots = None
        # imu() at one float time: the compiled kernel and its table, built on first use
        self._imu_one = None
        self._imu_one_table = None

    def __getstate__(self):
        # the one-sample path holds a compiled function, which does not pickle; it is rebuilt
        # (with its table) on first use
        state = self.__dict__.copy()
        state["_imu_one"] = None
        state["_imu_one_table"] = None
        return state

    # ------------------------------------------------------------------- properties
    @property
    def n_control(self) -> int:
        """Number of control rotations (and positions, unless the position grid is separate)."""
        return int(self.control_rotations.shape[0])

    @property
    def n_segments(self) -> int:
        return self.n_control - self.order + 1

    @property
    def n_position_segments(self) -> int:
        return int(self.control_positions.shape[0]) - self.position_order + 1

    @property
    def t_min_s(self) -> float:
        return max(self.t0_s, self.position_t0_s)

    @property
    def t_max_s(self) -> float:
        return min(self.t0_s + self.n_segments * self.dt_s,
                   self.position_t0_s + self.n_position_segments * self.position_dt_s)

    @property
    def control_quat_xyzw(self) -> np.ndarray:
        return lie.matrix_to_quat_xyzw(self.control_rotations)

    def __repr__(self):
        grid = ""
        if (self.position_dt_s, self.position_order, self.position_t0_s) != (self.dt_s, self.order, self.t0_s):
            grid = (f", position_order={self.position_order}, n_position_control={self.control_positions.shape[0]}, "
                    f"position_dt_s={self.position_dt_s:g}")
        return (f"Spline(kind={self.kind!r}, order={self.order}, n_control={self.n_control}, "
                f"dt_s={self.dt_s:g}{grid}, range=[{self.t_min_s:.6f}, {self.t_max_s:.6f}] s)")

    # ------------------------------------------------------------------- evaluation
    def _evaluate(self, t_s, want, gravity=DEFAULT_GRAVITY):
        t = self.check_times(t_s)
        n = t.shape[0]
        s = (t - self.t0_s) / self.dt_s
        g = np.ascontiguousarray(np.asarray(gravity, dtype=np.float64).reshape(3))

        def buf(flag, shape):
            return np.empty((n,) + shape) if want & flag else np.empty((0,) + shape)

        out = dict(
            R=buf(_k.WANT_ROT, (3, 3)), q=buf(_k.WANT_QUAT, (4,)), p=buf(_k.WANT_POS, (3,)),
            w=buf(_k.WANT_OMEGA, (3,)), wd=buf(_k.WANT_ALPHA, (3,)), v=buf(_k.WANT_VEL, (3,)),
            a=buf(_k.WANT_ACC, (3,)), f=buf(_k.WANT_FORCE, (3,)),
        )
        outs = (out["R"], out["q"], out["p"], out["w"], out["wd"], out["v"], out["a"], out["f"])
        if self.kind == "split":
            sp = s if self.position_t0_s == self.t0_s and self.position_dt_s == self.dt_s else \
                (t - self.position_t0_s) / self.position_dt_s
            _k.eval_split(s, self.n_segments, self.dt_s, self.control_rotations, self._D, self._Mc,
                          sp, self.n_position_segments, self.position_dt_s, self.control_positions, self._M,
                          g, int(want), *outs)
        else:
            _k.eval_se3(s, self.n_segments, self.dt_s, self.control_rotations, self._D, self.control_positions,
                        self._Mc, self._M, g, int(want), *outs)
        out["t"] = t
        return out

    def kinematics(self, t_s) -> Kinematics:
        """All kinematic quantities at ``t_s`` (N,) in one pass; see :class:`Kinematics`."""
        want = _k.WANT_ROT | _k.WANT_POS | _k.WANT_OMEGA | _k.WANT_ALPHA | _k.WANT_VEL | _k.WANT_ACC
        o = self._evaluate(t_s, want)
        return Kinematics(o["t"], o["p"], o["R"], o["w"], o["wd"], o["v"], o["a"])

    def pose(self, t_s):
        """``(positions (N, 3), quat_xyzw (N, 4))`` of ``world_T_body`` at ``t_s``."""
        o = self._evaluate(t_s, _k.WANT_POS | _k.WANT_QUAT)
        return o["p"], o["q"]

    def rotation_matrix(self, t_s) -> np.ndarray:
        """``world_R_body`` (N, 3, 3) at ``t_s``."""
        return self._evaluate(t_s, _k.WANT_ROT)["R"]

    def angular_velocity_body(self, t_s) -> np.ndarray:
        """Body angular rate ``omega_body`` (N, 3) [rad/s]."""
        return self._evaluate(t_s, _k.WANT_OMEGA)["w"]

    def angular_acceleration_body(self, t_s) -> np.ndarray:
        """Time derivative of ``omega_body`` (N, 3) [rad/s^2]."""
        return self._evaluate(t_s, _k.WANT_ALPHA)["wd"]

    def velocity_world(self, t_s) -> np.ndarray:
        """Velocity of the body origin in the world frame (N, 3) [m/s]."""
        return self._evaluate(t_s, _k.WANT_VEL)["v"]

    def acceleration_world(self, t_s) -> np.ndarray:
        """Acceleration of the body origin in the world frame (N, 3) [m/s^2]."""
        return self._evaluate(t_s, _k.WANT_ACC)["a"]

    def specific_force_body(self, t_s, gravity=DEFAULT_GRAVITY) -> np.ndarray:
        """``f_b = R^T (a_w - g_w)`` (N, 3) [m/s^2]; a level body at rest reads (0, 0, +9.81)."""
        return self._evaluate(t_s, _k.WANT_FORCE, gravity)["f"]

    def _imu_knot_table(self):
        if self._imu_knots is None:
            make = _ki.split_imu_knots if self.kind == "split" else _ks.se3_imu_knots
            self._imu_knots = make(self._D)
        return self._imu_knots

    def _imu_small_table(self):
        """The table of the one-sample and few-sample kernels (built on first use)."""
        if self._imu_one_table is None:
            tol = 1e-9 * max(1.0, abs(self.t_max_s - self.t_min_s))  # that of check_times
            lo = self.t_min_s - tol
            hi = self.t_max_s + tol
            if self.kind == "split":
                self._imu_one_table = _ki.split_one_sample_table(
                    self.t0_s, self.dt_s, self.n_segments, self._Mc, self.position_t0_s, self.position_dt_s,
                    self.n_position_segments, self._M, self._imu_knot_table(), self.control_rotations,
                    self.control_positions, lo, hi)
            else:
                self._imu_one_table = _ks.se3_one_sample_table(self.t0_s, self.dt_s, self.n_segments, self._Mc,
                                                               self._imu_knot_table(), self.control_rotations,
                                                               lo, hi)
        return self._imu_one_table

    def _build_imu_one(self):
        """The compiled kernel of the one-sample path of :meth:`imu` (its table built first)."""
        kernel = _ki.imu_split_one if self.kind == "split" else _ks.se3_imu_one
        H = self._imu_small_table()
        self._imu_one = _ki.compiled(kernel, (self.t_min_s, H, _GRAVITY, np.empty((1, 3)), np.empty((1, 3))))
        return self._imu_one

    def imu(self, t_s, gravity=DEFAULT_GRAVITY):
        """Ideal ``(gyro (N, 3), specific_force (N, 3))`` of a sensor at the body origin, in one pass.

        Vectorized across samples: split splines use
        :func:`splineimu._kernels.spline_imu.imu_split`, which rounds the basis and the
        acceleration as the general kernel of :meth:`angular_velocity_body` and
        :meth:`specific_force_body` does and differs from them by the rounding of the rotations
        only (a few 1e-15 relative); se3 splines use :func:`splineimu._kernels.se3_imu.se3_imu`
        (the same recursion as the general kernel, rounded differently: ~1e-15 relative). The two
        arrays returned are views of one (2, N, 3) block.

        One or a few samples take paths without validation in Python or allocation beyond the
        outputs, which give the same numbers as the vectorized one: a float ``t_s`` returns two
        (1, 3) arrays for a few times the cost of calling an empty compiled function; a float64
        array of up to :data:`FEW_SAMPLES` times is evaluated sample by sample, without the
        vectorized kernel's set-up.
        """
        if isinstance(t_s, float):
            # one sample: the compiled kernel is called directly (numba's dispatcher would type
            # each argument again); it checks the range, and outside it (or for NaN) the general
            # path below raises
            call = self._imu_one or self._build_imu_one()
            gyro = next(_ROWS)
            force = next(_ROWS)
            if call(t_s, self._imu_one_table,
                    _GRAVITY if gravity is DEFAULT_GRAVITY else np.array(gravity, dtype=np.float64).reshape(3),
                    gyro, force):
                return gyro, force
        elif type(t_s) is np.ndarray and t_s.ndim == 1 and t_s.shape[0] <= FEW_SAMPLES and t_s.dtype is _F64:
            few = _ki.imu_split_few if self.kind == "split" else _ks.se3_imu_few
            out = np.empty((2, t_s.shape[0], 3))
            if few(t_s, self._imu_small_table(),
                   _GRAVITY if gravity is DEFAULT_GRAVITY else np.array(gravity, dtype=np.float64).reshape(3), out):
                return out[0], out[1]
        return self._imu_vectorized(t_s, gravity)

    def _imu_vectorized(self, t_s, gravity=DEFAULT_GRAVITY):
        """:meth:`imu` through the vectorized kernels, at any number of samples."""
        t = self.check_times(t_s)
        g = np.ascontiguousarray(np.asarray(gravity, dtype=np.float64).reshape(3))
        K = self._imu_knot_table()
        # one allocation for both outputs: depending on its state, glibc maps large blocks
        # afresh and unmaps them on free, so that a call page-faults its outputs in (measured at
        # N = 1e5: up to 20 of 40 ns per sample with two blocks); a single block was not hit
        # (from 4 MB numpy asks for huge pages)
        out = np.empty((2, t.shape[0], 3))
        if self.kind == "split":
            _ki.imu_split(t, self.t0_s, self.dt_s, self.n_segments, self.control_rotations, K, self._Mc,
                          self.position_t0_s, self.position_dt_s, self.n_position_segments,
                          self.control_positions, self._M, g, out)
        else:
            _ks.se3_imu(t, self.t0_s, self.dt_s, self.n_segments, self.control_rotations, K, self._Mc, g, out)
        return out[0], out[1]
