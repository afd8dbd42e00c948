"""Kernels of the automatic knot choice: fold-wise fits of ordinary B-splines in one call.

A cross-validated score at one (order, spacing) is one pass over the samples for the banded
normal equations of every fold (the basis rows kept for the second pass), a banded Cholesky
solve per fold with the training system (all folds but one) and its difference penalty, and
one pass for the held-out prediction errors. Sums run in the order of the general fitting and
evaluation kernels, so that exact input (where the scores are rounding noise) is scored alike.

The order ``k`` and the number of columns ``d`` reach the kernels as the lengths of the tuples
``kt`` and ``dt`` (e.g. ``(0.0,) * k``): tuple lengths are part of the compiled signature, so
each (k, d) gets its own machine code with fixed loop counts (unrolled: 2x faster passes).
"""

from __future__ import annotations

import numpy as np

from .._jit import jit
from .spline import _segment


@jit
def fold_systems(s_all, w_all, fold, X, M, nseg, H, rhs, counts, seg_all, B, kt, dt):
    """Per-fold normal equations: H (F, n, k) upper band, rhs (F, n, d), counts (F, nseg) of
    samples with weight > 0; each sample's segment and basis row (summed as
    :func:`.spline.basis_into` sums) go to ``seg_all`` (N,) and ``B`` (N, k) for the prediction
    pass."""
    k = len(kt)
    d = len(dt)
    pw = np.empty(k)
    for m in range(s_all.shape[0]):
        seg, u = _segment(s_all[m], nseg)
        seg_all[m] = seg
        un = 1.0
        pw[0] = 1.0
        for n in range(1, k):
            un = un * u
            pw[n] = un
        for j in range(k):
            s0 = 0.0
            for n in range(k):
                s0 += M[j, n] * pw[n]
            B[m, j] = s0
        f = fold[m]
        w = w_all[m]
        if w > 0.0:
            counts[f, seg] += 1.0
        for a in range(k):
            wa = w * B[m, a]
            for c in range(k - a):
                H[f, seg + a, c] += wa * B[m, a + c]
            for z in range(d):
                rhs[f, seg + a, z] += wa * X[m, z]


@jit
def _block_sum(a, lo, n):
    """numpy's pairwise-sum leaf (n <= 128): 8 accumulators, then the rest in order."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - (n % 8):
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@jit
def pairwise_sum(a, lo, n):
    """``numpy.sum`` of the contiguous ``a[lo:lo + n]``, bitwise: numpy's pairwise summation
    (leaves of at most 128, split in halves rounded to 8 above), with an explicit stack (numba
    does not cache recursive functions safely)."""
    if n <= 128:
        return _block_sum(a, lo, n)
    f_lo = np.empty(64, dtype=np.int64)
    f_n = np.empty(64, dtype=np.int64)
    f_stage = np.empty(64, dtype=np.int64)
    vals = np.empty(64)
    sp = 0
    vp = 0
    f_lo[0], f_n[0], f_stage[0] = lo, n, 0
    sp = 1
    while sp > 0:
        top = sp - 1
        lo_, n_ = f_lo[top], f_n[top]
        if n_ <= 128:
            vals[vp] = _block_sum(a, lo_, n_)
            vp += 1
            sp -= 1
            continue
        n2 = n_ // 2
        n2 -= n2 % 8
        if f_stage[top] == 0:
            f_stage[top] = 1
            f_lo[sp], f_n[sp], f_stage[sp] = lo_, n2, 0
            sp += 1
        elif f_stage[top] == 1:
            f_stage[top] = 2
            f_lo[sp], f_n[sp], f_stage[sp] = lo_ + n2, n_ - n2, 0
            sp += 1
        else:
            vals[vp - 2] = vals[vp - 2] + vals[vp - 1]
            vp -= 1
            sp -= 1
    return vals[0]


@jit
def solve_folds(H, rhs, counts, pen, mu_dense, mu_sparse, Hf, C, kt, dt):
    """Training fits of every fold: control points ``C`` (F, n, d) (NaN where singular).

    The training system of fold f is the sum of the other folds' (all of them when F = 1) plus
    the difference penalty of coefficients ``pen`` (a tuple of r + 1) with per-row weight ``mu_sparse``
    (rows touching a control point whose support has a training-free segment) or ``mu_dense``,
    times the mean diagonal. ``Hf`` (n, k) scratch.

    One pass over the rows builds each row of the training system, adds the penalty rows that
    reach it and factors it (:func:`_factor_row`) as soon as it is complete: the sums of
    building the whole system, then :func:`.fit.band_cholesky_solve`, in their order.
    """
    nf = H.shape[0]
    n = H.shape[1]
    k = len(kt)
    d = len(dt)
    nseg = counts.shape[1]
    L = len(pen)
    penalize = L <= k and n >= L
    col = np.empty(n)
    prod = np.empty((2, L, L))
    sparse = np.empty(n, dtype=np.int64)
    Ht = H[0].copy()
    rt = rhs[0].copy()
    for g in range(1, nf):
        Ht += H[g]
        rt += rhs[g]
    # folds with samples in each segment (counts are sums of ones: a segment's training count
    # is zero exactly when no fold but the held-out one has samples there)
    nonzero = np.zeros(nseg, dtype=np.int64)
    for g in range(nf):
        for j in range(nseg):
            if counts[g, j] != 0.0:
                nonzero[j] += 1
    free = np.empty(nseg + 1, dtype=np.int64)  # training-free segments before each segment
    for f in range(nf):
        free[0] = 0
        for j in range(nseg):
            empty = nonzero[j] == 0 or (nf > 1 and nonzero[j] == 1 and counts[f, j] != 0.0)
            free[j + 1] = free[j] + (1 if empty else 0)
        for i in range(n):
            col[i] = Ht[i, 0] - H[f, i, 0] if nf > 1 else Ht[i, 0]
        per_ctrl = max(pairwise_sum(col, 0, n) / n, 1e-12)
        if penalize:
            # the two row weights' products mu pen[a] pen[b], rounded as each row would round them
            m0 = mu_dense * per_ctrl
            m1 = mu_sparse * per_ctrl
            for a in range(L):
                for b in range(L):
                    prod[0, a, b] = m0 * pen[a] * pen[b]
                    prod[1, a, b] = m1 * pen[a] * pen[b]
            for j in range(n - L + 1):
                # row j touches controls j .. j + L - 1, whose supports span segments j - k + 1 ..
                # j + L - 1: sparse if one of those has no training samples
                lo = max(j - k + 1, 0)
                hi = min(j + L - 1, nseg - 1)
                sparse[j] = 1 if hi >= lo and free[hi + 1] > free[lo] else 0
        ok = True
        Cf = C[f]
        for i in range(n):
            # row i of the training system, then the penalty rows j = i - L + 1 .. i that reach
            # it, in that order (row j adds prod[a, a + c] at column c of its row j + a)
            for c in range(k):
                Hf[i, c] = Ht[i, c] - H[f, i, c] if nf > 1 else Ht[i, c]
            for z in range(d):
                Cf[i, z] = rt[i, z] - rhs[f, i, z] if nf > 1 else rt[i, z]
            if penalize:
                for a in range(L - 1, -1, -1):
                    j = i - a
                    if j >= 0 and j <= n - L:
                        sp = sparse[j]
                        for c in range(L - a):
                            Hf[i, c] += prod[sp, a, a + c]
            if ok:
                if i >= k and i < n - k:
                    ok = _factor_row_interior(Hf, Cf, i, kt, dt)
                else:
                    ok = _factor_row(Hf, Cf, i, kt, dt)
        if ok:
            _back_substitute(Hf, Cf, kt, dt)
        else:
            for i in range(n):
                for z in range(d):
                    Cf[i, z] = np.nan


@jit(inline="always")
def _factor_row(A, B, i, kt, dt):
    """Row i of the banded Cholesky factorization of A (n, w) upper band (rows 0 .. i - 1
    factored), then of the forward substitution of B (n, m); False if the pivot is not positive.
    :func:`.fit.band_cholesky_solve`'s sums in its order."""
    n = A.shape[0]
    w = len(kt)
    m = len(dt)
    for c in range(w):
        if c >= n - i:
            break
        s = A[i, c]
        for q in range(1, w - c):
            if q > i:
                break
            s -= A[i - q, q] * A[i - q, q + c]
        if c == 0:
            if not s > 0.0:
                return False
            A[i, 0] = np.sqrt(s)
        else:
            A[i, c] = s / A[i, 0]
    piv = A[i, 0]
    for z in range(m):
        s = B[i, z]
        for q in range(1, w):
            if q > i:
                break
            s -= A[i - q, q] * B[i - q, z]
        B[i, z] = s / piv
    return True


@jit(inline="always")
def _factor_row_interior(A, B, i, kt, dt):
    """:func:`_factor_row` of a row at least w from both ends: no bounds to check (10% faster)."""
    w = len(kt)
    m = len(dt)
    for c in range(w):
        s = A[i, c]
        for q in range(1, w - c):
            s -= A[i - q, q] * A[i - q, q + c]
        if c == 0:
            if not s > 0.0:
                return False
            A[i, 0] = np.sqrt(s)
        else:
            A[i, c] = s / A[i, 0]
    piv = A[i, 0]
    for z in range(m):
        s = B[i, z]
        for q in range(1, w):
            s -= A[i - q, q] * B[i - q, z]
        B[i, z] = s / piv
    return True


@jit(inline="always")
def _back_substitute(A, B, kt, dt):
    """The back substitution of the factored A (n, w) on B (n, m), as
    :func:`.fit.band_cholesky_solve` sums it."""
    n = A.shape[0]
    w = len(kt)
    m = len(dt)
    for i in range(n - 1, -1, -1):
        piv = A[i, 0]
        if i < n - w:  # w - 1 rows below: no bound to check
            for z in range(m):
                s = B[i, z]
                for c in range(1, w):
                    s -= A[i, c] * B[i + c, z]
                B[i, z] = s / piv
        else:
            for z in range(m):
                s = B[i, z]
                for c in range(1, w):
                    if c > n - 1 - i:
                        break
                    s -= A[i, c] * B[i + c, z]
                B[i, z] = s / piv


@jit
def held_out_error(fold, X, C, seg_all, B, idx, tmp, kt, dt):
    """Sum over the samples ``idx`` of ``|X_m - x_f(t_m)|^2``, ``x_f`` the fit without the
    sample's fold ``f = fold[m]``, summed as numpy sums ``e[idx]``. ``tmp`` (len(idx),) scratch."""
    k = len(kt)
    d = len(dt)
    for i in range(idx.shape[0]):
        m = idx[i]
        f = fold[m]
        seg = seg_all[m]
        e2 = 0.0
        for z in range(d):
            acc = 0.0
            for j in range(k):
                acc += B[m, j] * C[f, seg + j, z]
            e = X[m, z] - acc
            e2 += e * e
        tmp[i] = e2
    return pairwise_sum(tmp, 0, idx.shape[0])


@jit
def derivative_at(s_all, C, M, nseg, inv_dt, r, out, kt, dt):
    """``out`` (N, d): the ``r``-th time derivative (0, 1, 2) of the spline of control points
    C (n, d), the basis' derivative summed as :func:`.spline.basis_into` sums it."""
    k = len(kt)
    d = len(dt)
    b = np.empty(k)
    for m in range(s_all.shape[0]):
        seg, u = _segment(s_all[m], nseg)
        for j in range(k):
            s0 = 0.0
            un = 1.0  # u^n
            um1 = 0.0  # u^(n-1)
            um2 = 0.0  # u^(n-2)
            for n in range(k):
                if n >= 1:
                    um2 = um1
                    um1 = un
                    un = un * u
                if r == 0:
                    s0 += M[j, n] * un
                elif r == 1:
                    s0 += M[j, n] * (n * um1)
                else:
                    s0 += M[j, n] * (n * (n - 1) * um2 if n >= 2 else 0.0)
            b[j] = s0 if r == 0 else (s0 * inv_dt if r == 1 else s0 * inv_dt * inv_dt)
        for z in range(d):
            acc = 0.0
            for j in range(k):
                acc += b[j] * C[seg + j, z]
            out[m, z] = acc


# ------------------------------------------------------------------- ladder statistics
@jit
def ladder_stats(d, idx, prev, has_prev, e2, ds, tmp):
    """One rung of the derivative-error ladder: ``d`` (N, 6) the derivatives of the signal fit
    (columns 0-2) and of the noise surrogate fit (3-5); ``idx`` the scored samples. Writes the
    surrogate's squared derivative ``e2`` (N,) and the scored rows ``ds`` (len(idx), 6); returns
    the sum of ``e2`` over the scored samples and, against the previous rung's scored rows
    ``prev``, the change of the signal part less that of the surrogate (sum of squares), summed
    as numpy sums them. ``tmp`` (3 len(idx),) scratch."""
    n = d.shape[0]
    ns = idx.shape[0]
    for m in range(n):
        e2[m] = (d[m, 3] * d[m, 3] + d[m, 4] * d[m, 4]) + d[m, 5] * d[m, 5]
    for i in range(ns):
        tmp[i] = e2[idx[i]]
        for z in range(6):
            ds[i, z] = d[idx[i], z]
    var = pairwise_sum(tmp, 0, ns)
    if not has_prev:
        return var, 0.0
    sums = np.zeros(2)
    for part in range(2):
        for i in range(ns):
            for z in range(3):
                D = ds[i, 3 * part + z] - prev[i, 3 * part + z]
                tmp[3 * i + z] = D * D
        sums[part] = pairwise_sum(tmp, 0, 3 * ns)
    return var, sums[0] - sums[1]
