"""Block-vectorized gyro + specific force of a split (R3 x SO3) cumulative B-spline.

Computes what :func:`splineimu._kernels.spline.eval_split` computes with ``WANT_OMEGA |
WANT_FORCE``, in a form that LLVM vectorizes across samples (measured single-threaded with
AVX-512: 5.5e7 samples/s at order 4 against 1.0e7, 3.7e7 against 6.5e6 at order 6):

- Per knot ``m``, once per spline (:func:`split_imu_knots`): the increment
  ``D_m = Log(R_{m-1}^T R_m)``, its angle ``n_m = |D_m| <= pi`` and the control position
  ``P_m``, in one 64-byte row.
- ``A_j = Exp(b_j D)`` with ``b_j`` the cumulative basis value, in [0, 1] (a hair outside for
  times within the range tolerance): its angle ``t = b_j n`` needs no square root and its half
  angle ``h`` lies in [0, pi/2], where Taylor polynomials in ``h^2`` give ``sin h / h`` and
  ``cos h`` without a branch (first omitted terms < 1e-18 and < 2e-17). ``A_j^T v`` is
  Rodrigues' formula ``cos t v - alpha (D x v) + beta (D . v) D`` with ``alpha = b sin t / t``
  and ``beta = b^2 (1 - cos t) / t^2``, from ``sin t = 2 sin h cos h`` and
  ``1 - cos t = 2 sin^2 h`` (no cancellation at small angles), applied to the gyro and the
  specific-force vectors directly, without forming a matrix.
- The basis values, their derivatives and the world acceleration are ``eval_split``'s power
  sums, in the same order, so both kernels round them identically. That rounding dominates
  where a result is much smaller than its terms (a basis derivative near its multiple root at
  a segment end; the acceleration of control points far from the origin, ~ eps |P| / dt^2),
  and there the two kernels still agree: they differ by the rounding of the rotations only
  (measured <= 5e-15 relative to each vector).
- Samples go in blocks of :data:`BLOCK`, held as structure-of-arrays scratch: each loop over
  a block has a straight-line body and vectorizes, except the gathers through the segment
  index, which stay scalar (see :func:`imu_split`).

No ``fastmath`` (the project forbids it): without it LLVM neither reassociates nor contracts,
so a sample's result does not depend on whether it falls in a vector body or a scalar
remainder loop, that is on its position in the input.

One sample (``Spline.imu`` at a float time): :func:`imu_split_one` does the same operations in
the same order on scalars, so it returns the same numbers, reading one flat table
(:func:`split_one_sample_table`) so that a call passes few arguments; it is called through
:func:`compiled`, without numba's dispatcher. What a call costs is mostly Python's: the two
(1, 3) outputs (~0.15 us each on the project's machine), the method call and the kernel call
(~0.1 us); the kernel itself ~0.08 us at order 4, ~0.15 us at order 6.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import jit

#: Samples per block: the scratch rows, 8 * BLOCK bytes each, stay in L1 (64 to 512 measured
#: within 5% of each other).
BLOCK = 256

#: Columns of the per-knot table of the rotation grid built by :func:`split_imu_knots`: one
#: 32-byte row per knot. The position grid is read from the control positions directly.
KNOT_D = 0  # 3 entries: D_m = Log(R_{m-1}^T R_m) (zero for m = 0)
KNOT_ANGLE = 3  # |D_m|
KNOT_COLS = 4

# Taylor coefficients of sin(h)/h and cos(h) in x = h^2, highest power first; for |h| <= pi/2
# the first omitted terms are (pi/2)^22/23! < 1e-18 and (pi/2)^22/22! < 2e-17.
_SIN = tuple((-1.0) ** n / math.factorial(2 * n + 1) for n in range(10, -1, -1))
_COS = tuple((-1.0) ** n / math.factorial(2 * n) for n in range(10, -1, -1))
SN10, SN9, SN8, SN7, SN6, SN5, SN4, SN3, SN2, SN1, SN0 = _SIN
CS10, CS9, CS8, CS7, CS6, CS5, CS4, CS3, CS2, CS1, CS0 = _COS

# Rows of the scratch array of imu_split: on the rotation grid the power u^n is row _PW + n
# (n = 1 .. k-1); on the position grid (order kp, from row _PP = _PW + k) the power is row
# _PP + n (n = 1 .. kp-1) and the plain basis' second time derivative B_j''(u) row _PP + kp + j.
_B, _BD, _BDD, _W0, _W1, _W2, _F0, _F1, _F2, _D0, _D1, _D2, _ANG = range(13)
_PW = 12
_U = _PW + 1
_U4 = np.uint64(KNOT_COLS)  # unsigned indices: numba checks signed ones for wraparound
_U1, _U2, _U3, _U4, _U5, _U6, _U7, _U8, _U9 = (np.uint64(i) for i in range(1, 10))


def split_imu_knots(increments):
    """Per-knot table (n, :data:`KNOT_COLS`) of the rotation grid for :func:`imu_split`.

    Parameters
    ----------
    increments : (n, 3) array
        ``D_m = Log(R_{m-1}^T R_m)`` (row 0 unused), as held by the spline.
    """
    n = increments.shape[0]
    K = np.zeros((n, KNOT_COLS))
    K[:, KNOT_D:KNOT_D + 3] = increments
    K[:, KNOT_ANGLE] = np.sqrt(np.einsum("ni,ni->n", increments, increments))
    return K


@jit(inline="always")
def _exp_terms(b, n):
    """``(cos t, b sin t / t, b^2 (1 - cos t) / t^2, sin t / t, (t / 2)^2)`` at ``t = b n``, from
    the half angle."""
    h = 0.5 * (b * n)
    x = h * h
    # Estrin's scheme: a dependency chain of 5 multiply-adds rather than Horner's 10, which
    # is what one sample waits for (the vectorized kernel's throughput barely changes)
    x2 = x * x
    x4 = x2 * x2
    x8 = x4 * x4
    ps = (((SN0 + SN1 * x) + (SN2 + SN3 * x) * x2) + ((SN4 + SN5 * x) + (SN6 + SN7 * x) * x2) * x4) \
        + ((SN8 + SN9 * x) + SN10 * x2) * x8
    pc = (((CS0 + CS1 * x) + (CS2 + CS3 * x) * x2) + ((CS4 + CS5 * x) + (CS6 + CS7 * x) * x2) * x4) \
        + ((CS8 + CS9 * x) + CS10 * x2) * x8
    # sin t / t = ps pc, (1 - cos t) / t^2 = ps^2 / 2, 1 - cos t = 2 (h ps)^2
    sh = h * ps
    sinc = ps * pc
    return 1.0 - 2.0 * (sh * sh), sinc * b, (0.5 * (ps * ps)) * (b * b), sinc, x


@jit(inline="always")
def _exp_coefficients(b, n):
    """``(cos t, b sin t / t, b^2 (1 - cos t) / t^2)`` at ``t = b n``, from the half angle."""
    ct, al, be, _, _ = _exp_terms(b, n)
    return ct, al, be


@jit(inline="always")
def _rotate_back(v0, v1, v2, d0, d1, d2, ct, al, be):
    """``Exp(b D)^T v = cos t v - alpha (D x v) + beta (D . v) D`` with the coefficients above."""
    dd = be * (d0 * v0 + d1 * v1 + d2 * v2)
    return (ct * v0 - al * (d1 * v2 - d2 * v1) + dd * d0,
            ct * v1 - al * (d2 * v0 - d0 * v2) + dd * d1,
            ct * v2 - al * (d0 * v1 - d1 * v0) + dd * d2)


@jit
def _segments(t, start, m, t0, dt, top, seg, S, row):
    """Segment index (clamped to [0, top], as eval_split) and local parameter u into ``S[row]``."""
    for i in range(m):
        s = (t[start + i] - t0) / dt
        sg = int(math.floor(s))
        sg = 0 if sg < 0 else sg
        sg = top if sg > top else sg
        seg[i] = np.uint64(sg)
        S[row, i] = s - sg


@jit
def imu_split(t, t0, dt, nseg, Rc, K, Mc, t0_p, dt_p, nseg_p, Pc, M, g, out):
    """Gyro ``out[0]`` (N, 3) and specific force ``out[1]`` (N, 3) of a split spline at ``t`` (N,).

    ``t`` in seconds, already range-checked. Rotation grid: ``s = (t - t0) / dt`` picks segment
    ``clamp(floor(s), 0, nseg - 1)`` as in ``eval_split``; ``Rc`` (n, 3, 3) control rotations,
    ``K`` from :func:`split_imu_knots`, ``Mc`` the cumulative blending matrix (k, k). Position
    grid: ``t0_p``, ``dt_p``, ``nseg_p``, control positions ``Pc`` (n_p, 3), plain blending
    matrix ``M`` (kp, kp). ``g`` gravity (3,); ``out`` (2, N, 3) C-contiguous.
    """
    k = Mc.shape[0]
    kp = M.shape[0]
    N = t.shape[0]
    inv_dt = 1.0 / dt
    inv_dtp = 1.0 / dt_p
    g0 = g[0]
    g1 = g[1]
    g2 = g[2]
    B = BLOCK
    seg = np.empty(B, dtype=np.uint64)
    segp = np.empty(B, dtype=np.uint64)
    # flat views indexed by unsigned integers: no wraparound checks, constant strides
    Kf = K.reshape(K.size)
    Rf = Rc.reshape(Rc.size)
    Pf = Pc.reshape(Pc.size)
    of = out.reshape(out.size)
    PP = _PW + k
    Q = PP + kp
    # One scratch array with constant row offsets, so that LLVM sees that the rows do not
    # overlap and vectorizes without runtime alias checks (separate arrays need a check per
    # pair, beyond its limit). A loop that reads an argument array through seg (a gather)
    # and writes anything is not vectorized: the bounds of the gather are unknown, so LLVM
    # cannot rule out that it overlaps the writes. Those loops only gather and stay scalar.
    S = np.empty((Q + kp, B))
    for start in range(0, N, B):
        m = min(B, N - start)
        # segments and local parameters of both grids, clamped as in eval_split
        _segments(t, start, m, t0, dt, nseg - 1, seg, S, _U)
        _segments(t, start, m, t0_p, dt_p, nseg_p - 1, segp, S, PP + 1)
        # powers u^n, as eval_split's running product
        for n in range(2, k):
            for i in range(m):
                S[_PW + n, i] = S[_PW + n - 1, i] * S[_U, i]
        for n in range(2, kp):
            for i in range(m):
                S[PP + n, i] = S[PP + n - 1, i] * S[PP + 1, i]
        # B_j''(u) / dt^2, as eval_split: 0 + 2 M_j2 + M_j3 (6 u) + ..., same order
        for j in range(kp):
            m2 = 2.0 * M[j, 2] if kp > 2 else 0.0
            for i in range(m):
                S[_BDD, i] = 0.0 + m2
            for n in range(3, kp):
                cn = M[j, n]
                fn = float(n * (n - 1))
                for i in range(m):
                    S[_BDD, i] += cn * (fn * S[PP + n - 2, i])
            for i in range(m):
                S[Q + j, i] = (S[_BDD, i] * inv_dtp) * inv_dtp
        # world acceleration a = sum_j B_j'' P_{seg+j} (eval_split's order), f = R_seg^T (a - g)
        for i in range(m):
            c0 = 0.0
            c1 = 0.0
            c2 = 0.0
            rp = segp[i] * _U3
            for j in range(kp):
                e = S[Q + j, i]
                c0 += e * Pf[rp]
                c1 += e * Pf[rp + np.uint64(1)]
                c2 += e * Pf[rp + np.uint64(2)]
                rp += _U3
            h0 = c0 - g0
            h1 = c1 - g1
            h2 = c2 - g2
            r9 = seg[i] * _U9
            S[_F0, i] = Rf[r9] * h0 + Rf[r9 + np.uint64(3)] * h1 + Rf[r9 + np.uint64(6)] * h2
            S[_F1, i] = Rf[r9 + np.uint64(1)] * h0 + Rf[r9 + np.uint64(4)] * h1 + Rf[r9 + np.uint64(7)] * h2
            S[_F2, i] = Rf[r9 + np.uint64(2)] * h0 + Rf[r9 + np.uint64(5)] * h1 + Rf[r9 + np.uint64(8)] * h2
        # w and f through the steps A_j^T, j = 1 .. k-1
        for i in range(m):
            S[_W0, i] = 0.0
            S[_W1, i] = 0.0
            S[_W2, i] = 0.0
        for j in range(1, k):
            off = np.uint64(KNOT_COLS * j)
            for i in range(m):
                r = seg[i] * _U4 + off  # KNOT_D .. KNOT_ANGLE
                S[_D0, i] = Kf[r]
                S[_D1, i] = Kf[r + np.uint64(1)]
                S[_D2, i] = Kf[r + np.uint64(2)]
                S[_ANG, i] = Kf[r + np.uint64(3)]
            # cumulative basis value b and its u-derivative bd: eval_split's power sums
            # (0 + Mc0 + Mc1 u + Mc2 u^2 ..., 0 + Mc1 + Mc2 (2 u) + ...), same order and rounding
            c0 = Mc[j, 0]
            c1 = Mc[j, 1]
            for i in range(m):
                S[_B, i] = (0.0 + c0) + c1 * S[_U, i]
                S[_BD, i] = 0.0 + c1
            for n in range(2, k):
                cn = Mc[j, n]
                fn = float(n)
                for i in range(m):
                    S[_B, i] += cn * S[_PW + n, i]
                    S[_BD, i] += cn * (fn * S[_PW + n - 1, i])
            for i in range(m):
                d0 = S[_D0, i]
                d1 = S[_D1, i]
                d2 = S[_D2, i]
                ct, al, be = _exp_coefficients(S[_B, i], S[_ANG, i])
                S[_F0, i], S[_F1, i], S[_F2, i] = _rotate_back(S[_F0, i], S[_F1, i], S[_F2, i], d0, d1, d2,
                                                               ct, al, be)
                # w = 0 before the first step (set above), where A_1^T w adds exact zeros
                r0, r1, r2 = _rotate_back(S[_W0, i], S[_W1, i], S[_W2, i], d0, d1, d2, ct, al, be)
                bd = S[_BD, i] * inv_dt
                S[_W0, i] = r0 + bd * d0
                S[_W1, i] = r1 + bd * d1
                S[_W2, i] = r2 + bd * d2
        # out[0, start + i], out[1, start + i]
        for i in range(m):
            o = np.uint64(3 * (start + i))
            of[o] = S[_W0, i]
            of[o + np.uint64(1)] = S[_W1, i]
            of[o + np.uint64(2)] = S[_W2, i]
        for i in range(m):
            o = np.uint64(3 * (N + start + i))
            of[o] = S[_F0, i]
            of[o + np.uint64(1)] = S[_F1, i]
            of[o + np.uint64(2)] = S[_F2, i]


# The one-sample kernels (:func:`imu_split_one`, and se3's) read one flat float64 array, built
# once per spline, so that a call passes few arguments (each costs the call ~10 ns to unpack):
# a header of the grid parameters (segment counts, orders and offsets are whole numbers held
# as floats), the cumulative blending matrix of the rotation grid (k x k, row-major) from
# H_MC, the plain one of the position grid (kp x kp), one row of ROW_COLS per knot of the
# rotation grid from offset H_ROWS, and the control positions (n_p x 3) from H_POS.
H_T0, H_DT, H_NSEG, H_T0P, H_DTP, H_NSEGP, H_K, H_KP, H_ROWS, H_POS, H_LO, H_HI, H_MC = range(13)
#: Columns of a knot row of :func:`split_one_sample_table`: ``D_m`` and ``|D_m|`` as in the
#: vectorized kernel's table, then the control rotation ``R_m`` (row-major).
ROW_R = KNOT_COLS
ROW_COLS = KNOT_COLS + 9


def split_one_sample_table(t0, dt, nseg, Mc, t0_p, dt_p, nseg_p, M, K, Rc, Pc, t_lo, t_hi):
    """The array of :func:`imu_split_one` (layout at :data:`H_MC`), 104 bytes per knot.

    Parameters as those of :func:`imu_split`; ``K`` from :func:`split_imu_knots`; the kernel
    evaluates times in ``[t_lo, t_hi]`` only.
    """
    k = Mc.shape[0]
    kp = M.shape[0]
    rows = H_MC + k * k + kp * kp
    pos = rows + ROW_COLS * K.shape[0]
    head = np.array([t0, dt, nseg, t0_p, dt_p, nseg_p, k, kp, rows, pos, t_lo, t_hi], dtype=np.float64)
    table = np.concatenate([head, Mc.ravel(), M.ravel(), np.hstack([K, Rc.reshape(-1, 9)]).ravel(), Pc.ravel()])
    return np.ascontiguousarray(table, dtype=np.float64)


@jit(inline="always")
def _segment_one(t, t0, dt, top):
    """Segment (clamped to [0, top]) and u of one time, as :func:`_segments`."""
    s = (t - t0) / dt
    sg = int(math.floor(s))
    sg = 0 if sg < 0 else sg
    sg = top if sg > top else sg
    return sg, s - sg


@jit(inline="always")
def _cumulative_basis_one(H, row, k, u):
    """Cumulative basis value ``b`` and ``db/du`` at ``u`` of the blending matrix row that starts
    at ``H[row]``: imu_split's power sums, in its order."""
    b = (0.0 + H[row]) + H[row + _U1] * u
    bd = 0.0 + H[row + _U1]
    um1 = u  # u^(n-1)
    for n in range(2, k):
        cn = H[row + np.uint64(n)]
        un = um1 * u
        b += cn * un
        bd += cn * (float(n) * um1)
        um1 = un
    return b, bd


@jit(inline="always")
def _position_accel_one(H, off, kp, up, inv_dtp, pos):
    """World acceleration ``sum_j B_j''(up) P_j`` (plain blending matrix from ``H[off]``, the
    control positions of the segment from ``H[pos]``): imu_split's sums, in its order."""
    c0 = 0.0
    c1 = 0.0
    c2 = 0.0
    for j in range(kp):
        row = off + np.uint64(j * kp)
        bdd = 0.0 + (2.0 * H[row + _U2] if kp > 2 else 0.0)
        um = up  # up^(n-2)
        for n in range(3, kp):
            bdd += H[row + np.uint64(n)] * (float(n * (n - 1)) * um)
            um = um * up
        e = (bdd * inv_dtp) * inv_dtp
        p = pos + np.uint64(3 * j)
        c0 += e * H[p]
        c1 += e * H[p + _U1]
        c2 += e * H[p + _U2]
    return c0, c1, c2


@jit(inline="always")
def _split_at(t, H, g0, g1, g2):
    """Gyro and specific force at one time (in the table's range): :func:`imu_split`'s operations
    in its order, on scalars. Unsigned indices: numba checks signed ones for wraparound."""
    k = int(H[H_K])
    kp = int(H[H_KP])
    dt = H[H_DT]
    inv_dt = 1.0 / dt
    dtp = H[H_DTP]
    inv_dtp = 1.0 / dtp
    seg, u = _segment_one(t, H[H_T0], dt, int(H[H_NSEG]) - 1)
    segp, up = _segment_one(t, H[H_T0P], dtp, int(H[H_NSEGP]) - 1)
    c0, c1, c2 = _position_accel_one(H, np.uint64(H_MC + k * k), kp, up, inv_dtp,
                                     np.uint64(int(H[H_POS]) + 3 * segp))
    h0 = c0 - g0
    h1 = c1 - g1
    h2 = c2 - g2
    r = np.uint64(int(H[H_ROWS]) + ROW_COLS * seg + ROW_R)  # R_seg, row-major
    f0 = H[r] * h0 + H[r + _U3] * h1 + H[r + _U6] * h2
    f1 = H[r + _U1] * h0 + H[r + _U4] * h1 + H[r + _U7] * h2
    f2 = H[r + _U2] * h0 + H[r + _U5] * h1 + H[r + _U8] * h2
    w0 = 0.0
    w1 = 0.0
    w2 = 0.0
    for j in range(1, k):
        r = np.uint64(int(H[H_ROWS]) + ROW_COLS * (seg + j))
        d0 = H[r]
        d1 = H[r + _U1]
        d2 = H[r + _U2]
        b, bd = _cumulative_basis_one(H, np.uint64(H_MC + j * k), k, u)
        ct, al, be = _exp_coefficients(b, H[r + _U3])
        f0, f1, f2 = _rotate_back(f0, f1, f2, d0, d1, d2, ct, al, be)
        r0, r1, r2 = _rotate_back(w0, w1, w2, d0, d1, d2, ct, al, be)
        bd = bd * inv_dt
        w0 = r0 + bd * d0
        w1 = r1 + bd * d1
        w2 = r2 + bd * d2
    return w0, w1, w2, f0, f1, f2


@jit(nrt=False)
def imu_split_one(t, H, g, gyro, force):
    """:func:`imu_split` at one time ``t``: the same operations in the same order, so the same
    numbers, without the block scratch. ``H`` from :func:`split_one_sample_table`, gravity
    ``g`` (3,); writes ``gyro`` (1, 3) and ``force`` (1, 3) and returns True, or returns False
    (and writes nothing) if ``t`` is outside the table's time range or NaN."""
    if not (H[H_LO] <= t <= H[H_HI]):
        return False
    gyro[0, 0], gyro[0, 1], gyro[0, 2], force[0, 0], force[0, 1], force[0, 2] = _split_at(t, H, g[0], g[1], g[2])
    return True


@jit(nrt=False)
def imu_split_few(t, H, g, out):
    """:func:`imu_split_one` at each of a few times ``t`` (N,) into ``out`` (2, N, 3), with no
    block set-up; returns False (writing nothing) if any time is outside the range or NaN."""
    lo = H[H_LO]
    hi = H[H_HI]
    for i in range(t.shape[0]):
        if not (lo <= t[i] <= hi):
            return False
    for i in range(t.shape[0]):
        out[0, i, 0], out[0, i, 1], out[0, i, 2], out[1, i, 0], out[1, i, 1], out[1, i, 2] = _split_at(
            t[i], H, g[0], g[1], g[2])
    return True


def compiled(kernel, args):
    """The machine-code function of ``kernel`` for the types of ``args``, to call without
    numba's dispatcher.

    The dispatcher types every argument at each call (~50 ns per array measured, more than a
    one-sample kernel computes); the function it then calls takes the arguments as they come.
    Only for kernels compiled with ``nrt=False`` and called with arguments of exactly these
    types, C-contiguous float64 arrays as given (it does not check them). Runs the kernel
    once with ``args`` (compiling it or loading it from the cache). Without the JIT
    (``NUMBA_DISABLE_JIT=1``) returns ``kernel`` itself.
    """
    kernel(*args)
    get_overload = getattr(kernel, "get_overload", None)
    if get_overload is None:
        return kernel
    import numba

    return get_overload(tuple(numba.typeof(a) for a in args))
