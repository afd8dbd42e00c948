"""The knot choice's kernels (splineimu/_kernels/cv.py) against plain numpy references: fold-wise
fits with their penalties, held-out errors, derivatives, and numpy's own summation order."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu._kernels import cv as kcv
from splineimu.spline import knots
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
    wd = knots._Window(t, X, w)
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
    wd = knots._Window(t, X, np.ones(t.size))
    d = wd.derivative(k, dt, wd.zero, 1, r)[0]
    C, s, seg, _, _, dt_, _ = wd.fit_folds(k, dt, wd.zero, 1)
    Br = basis_values(k, s - seg, derivative=r) / dt_**r
    ref = np.einsum("mj,mjz->mz", Br, C[0][seg[:, None] + np.arange(k)])
    np.testing.assert_allclose(d, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
