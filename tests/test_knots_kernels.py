"""The knot choice's kernels (splineimu/_kernels/cv.py) against plain numpy references: fold-wise
fits with their penalties, held-out errors, derivatives, and numpy's own summation order."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu._kernels import cv as kcv
from splineimu.spline import crossval
from splineimu.spline.banded import (
    DEFAULT_SMOOTHNESS,
    SPARSE_SMOOTHNESS,
    add_position_penalty,
    layout,
    row_weights,
    solve_banded_scalar,
)
from splineimu.spline.basis import basis_values


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 127, 128, 129, 1000, 8193, 34201])
def test_pairwise_sum_is_numpys_sum_bitwise(n):
    a = np.random.default_rng(n).normal(size=n) ** 2 * 1e3
    assert kcv.pairwise_sum(a, 0, n) == np.sum(a)


def _reference_fold_fits(t, w, fold, X, k, dt):
    """The per-fold fits written with numpy and the banded helpers (dense basis, no kernel)."""
    t0, dt_, nseg, n = layout(t[0], t[-1], dt, k)
    s = (t - t0) / dt_
    seg = np.clip(np.floor(s).astype(int), 0, nseg - 1)
    B = basis_values(k, s - seg)
    C = np.empty((4, n, X.shape[1]))
    for f in range(4):
        train = (fold != f) & (w > 0)
        A = np.zeros((n, n))
        rhs = np.zeros((n, X.shape[1]))
        for m in np.flatnonzero(train):
            i = seg[m]
            A[i:i + k, i:i + k] += w[m] * np.outer(B[m], B[m])
            rhs[i:i + k] += w[m] * np.outer(B[m], X[m])
        Hs = np.array([[A[i, i + c] if i + c < n else 0.0 for c in range(k)] for i in range(n)])
        cf = np.bincount(seg[train], minlength=nseg)
        sparse = np.convolve((cf == 0).astype(float), np.ones(k))[:n] > 0
        mu = np.where(row_weights(sparse, 4), SPARSE_SMOOTHNESS, DEFAULT_SMOOTHNESS) * max(Hs[:, 0].sum() / n, 1e-12)
        add_position_penalty(Hs, mu, 3)
        C[f] = solve_banded_scalar(Hs, rhs)
    return C, s, seg, B, dt_


@pytest.mark.parametrize("k, dt, block", [(4, 0.031, 1), (5, 0.05, 3), (6, 0.013, 7)])
def test_fold_fits_and_held_out_error_match_a_dense_reference(k, dt, block):
    rng = np.random.default_rng(k)
    t = np.arange(400) / 100.0
    X = np.c_[np.sin(3 * t), np.cos(2 * t), t**2] + 1e-3 * rng.normal(size=(t.size, 3))
    w = np.ones(t.size)
    w[150:190] = 0.0  # a gap: training-free segments get the sparse penalty
    wd = crossval._Window(t, X, w)
    fold = wd.folds(block)
    C, s, seg, B, nseg, dt_, sizes = wd.fit_folds(k, dt, fold, 4)
    C_ref, _, seg_ref, B_ref, _ = _reference_fold_fits(t, w, fold, X, k, dt)
    # measured: up to 1.4e-8 of the largest control point (order 6 across the gap, where only the
    # weak penalty holds the fit: rounding of the two assemblies is amplified), 1e-13 elsewhere
    np.testing.assert_allclose(C, C_ref, rtol=0, atol=1e-7 * np.abs(C_ref).max())
    np.testing.assert_array_equal(seg, seg_ref)
    np.testing.assert_allclose(B, B_ref, rtol=0, atol=1e-15)
    total, count = wd.score(k, dt, fold)
    pred = np.einsum("mj,mjz->mz", B_ref, C_ref[fold[:, None], seg_ref[:, None] + np.arange(k)])
    e = np.sum((X - pred) ** 2, axis=1)
    assert count == int(np.count_nonzero(wd.scored))
    assert total == pytest.approx(float(np.sum(e[wd.scored])), rel=1e-9)


@pytest.mark.parametrize("r", [0, 1, 2])
def test_derivative_matches_the_basis_derivative(r):
    k, dt = 5, 0.07
    t = np.linspace(0.0, 2.0, 301)
    X = np.c_[np.sin(t), t**3, np.exp(-t)]
    wd = crossval._Window(t, X, np.ones(t.size))
    d = wd.derivative(k, dt, wd.zero, 1, r)[0]
    C, s, seg, _, _, dt_, _ = wd.fit_folds(k, dt, wd.zero, 1)
    Br = basis_values(k, s - seg, derivative=r) / dt_**r
    ref = np.einsum("mj,mjz->mz", Br, C[0][seg[:, None] + np.arange(k)])
    np.testing.assert_allclose(d, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def _reference_solve_folds(H, rhs, counts, pen, mu_dense, mu_sparse):
    """solve_folds step by step: each fold's training system in full, its penalty rows in order,
    then the fitting module's banded Cholesky solve."""
    from splineimu._kernels.fit import band_cholesky_solve

    nf, n, k = H.shape
    nseg, L = counts.shape[1], len(pen)
    Ht, rt = H[0].copy(), rhs[0].copy()
    for g in range(1, nf):
        Ht += H[g]
        rt += rhs[g]
    C = np.empty_like(rhs)
    for f in range(nf):
        Hf = Ht - H[f] if nf > 1 else Ht.copy()
        Cf = rt - rhs[f] if nf > 1 else rt.copy()
        train = counts.sum(axis=0) - counts[f] if nf > 1 else counts[0]
        free = np.r_[0, np.cumsum(train == 0.0)]
        per_ctrl = max(np.sum(Hf[:, 0]) / n, 1e-12)
        if L <= k and n >= L:
            for j in range(n - L + 1):
                lo, hi = max(j - k + 1, 0), min(j + L - 1, nseg - 1)
                mu = (mu_sparse if hi >= lo and free[hi + 1] > free[lo] else mu_dense) * per_ctrl
                for a in range(L):
                    for b in range(a, L):
                        Hf[j + a, b - a] += mu * pen[a] * pen[b]
        C[f] = Cf if band_cholesky_solve(Hf, Cf) else np.nan
    return C


@pytest.mark.parametrize("seed", range(40))
def test_solve_folds_is_the_stepwise_solve_bitwise(seed):
    # one pass over the rows (build, penalize, factor) against the passes it fuses: same bits,
    # singular training systems (NaN) included
    rng = np.random.default_rng(seed)
    k, d, nf = int(rng.integers(4, 7)), int(rng.choice([3, 6])), int(rng.choice([1, 4]))
    n = int(rng.integers(1, 40))
    nseg = max(n - k + 1, 1)
    H = rng.random((nf, n, k))
    H[:, :, 0] += 3.0 * rng.random((nf, n)) - (2.0 if seed % 5 == 0 else 0.0)  # some indefinite
    H[:, rng.integers(0, n, size=max(1, n // 3)), :] = 0.0  # rows without samples
    rhs = rng.normal(size=(nf, n, d))
    counts = (rng.random((nf, nseg)) < 0.6) * rng.integers(1, 4, size=(nf, nseg)).astype(float)
    pen = crossval._penalty(k)
    C = np.full((nf, n, d), 5.0)
    kcv.solve_folds(H, rhs, counts, pen, 1e-3, 1e-1, np.empty((n, k)), C, (0.0,) * k, (0.0,) * d)
    ref = _reference_solve_folds(H, rhs, counts, pen, 1e-3, 1e-1)
    assert C.tobytes() == ref.tobytes()
