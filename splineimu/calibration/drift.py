r"""Bias drift over a calibration: the random-walk covariance of the phase means, and its density from the data.

The bias of each axis is modelled as a random walk, ``b(t_k) = b(t_{k-1}) + q z_k`` with
``q = sigma_K sqrt(dt)`` (``sigma_K`` the random-walk density in Kalibr's units, m/s^3/sqrt(Hz)
or rad/s^2/sqrt(Hz)), so ``Cov(b(s), b(t)) = sigma_K^2 min(s, t)`` up to a constant. A phase
``p`` averages it over its samples; the calibrated bias is the bias averaged over every sample
of the phases used (weights ``w_p = n_p / sum n``, the quantity a ground-truth file gives), so
the phase means carry ``B_p - sum_q w_q B_q`` with ``B_p`` the phase average. Its covariance
(:func:`phase_drift_covariance`) is

.. math::  D = sigma_K^2 (I - 1 w^T) M (I - 1 w^T)^T,\qquad
           M_{pq} = \text{mean}_{s \in p, t \in q} \min(s, t),

which, added to the white-noise variances of the phase means, makes the least squares of step 4
the best linear unbiased estimate under drift and its covariance the honest one: the drift over
the whole timeline (tens of seconds between the first and the last position) is often far larger
than the white noise of a phase mean (EuRoC's ADIS16448, 3e-3 m/s^3/sqrt(Hz): 0.025 m/s^2 over
70 s against 7e-4 m/s^2 for an 8 s phase).

Density from the data (:func:`estimate_random_walk`), when none is given: each phase is cut into
blocks of ``block_s``; per axis, all block means of all phases are one Gaussian vector whose mean
is linear in that axis' row of ``K`` and its bias and whose covariance is the white noise (from
the scatter inside the blocks), the tilts (if modelled) and ``sigma_K^2`` times the block version
of ``M`` over the whole timeline. One ``sigma_K`` for the sensor maximizes the restricted
likelihood of the three axes, so both the wander inside the phases and the scatter of the phase
means about the fit inform it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["phase_drift_covariance", "estimate_random_walk", "RandomWalkFit"]


def phase_drift_covariance(t_ns, phases) -> np.ndarray:
    """``D / sigma_K^2`` (P, P) [s] of the phase means' bias, relative to the sample-weighted mean bias.

    Parameters
    ----------
    t_ns : (N,) int64
        Stamps of the recording.
    phases : list of SteadyPhase
        The phases used (``start``, ``stop`` sample indices).

    Examples
    --------
    >>> from types import SimpleNamespace as P
    >>> t = np.arange(400, dtype=np.int64) * 10_000_000            # 100 Hz, 4 s
    >>> D = phase_drift_covariance(t, [P(start=0, stop=100), P(start=300, stop=400)])
    >>> D.round(3).tolist()                                         # two 1 s phases, 3 s apart
    [[0.667, -0.667], [-0.667, 0.667]]
    """
    t0 = int(t_ns[phases[0].start]) if phases else 0
    n = np.array([p.stop - p.start for p in phases], dtype=np.float64)
    means, self_terms = [], []
    for p in phases:
        ts = (np.asarray(t_ns[p.start:p.stop], dtype=np.int64) - t0) / 1e9  # sorted
        k = np.arange(ts.size, dtype=np.float64)
        means.append(float(ts.mean()))
        self_terms.append(float(np.sum(ts * (2.0 * (ts.size - k) - 1.0))) / ts.size**2)
    P = len(phases)
    M = np.empty((P, P))
    for i in range(P):
        for j in range(P):
            # phases do not overlap: the earlier one's mean time is the mean of min(s, t)
            M[i, j] = self_terms[i] if i == j else (means[i] if phases[i].start < phases[j].start else means[j])
    w = n / n.sum()
    C = np.eye(P) - np.outer(np.ones(P), w)
    return C @ M @ C.T


class RandomWalkFit(NamedTuple):
    """A random-walk density fitted to the phases, with its likelihood-ratio statistic against none."""

    density: float
    lr_statistic: float


def _blocks(t_ns, y, phases, block_s):
    """Block means of every phase.

    Returns ``z (B, 3)``, block sizes, owning phase, mean time, ``mean min(t, t')`` within each
    block (B,) and the white-noise variance per sample of each phase (P, 3).
    """
    dt = float(np.median(np.diff(np.asarray(t_ns[phases[0].start:phases[-1].stop], dtype=np.int64)))) / 1e9
    m = max(1, int(round(block_s / dt)))
    t0 = int(t_ns[phases[0].start])
    z, size, owner, tm, tself, white = [], [], [], [], [], []
    for k, p in enumerate(phases):
        idx = np.array_split(np.arange(p.start, p.stop), max(1, (p.stop - p.start) // m))
        ss = np.zeros(3)
        dof = 0
        for ix in idx:
            seg = y[ix]
            ts = (np.asarray(t_ns[ix], dtype=np.int64) - t0) / 1e9
            j = np.arange(ts.size, dtype=np.float64)
            z.append(seg.mean(axis=0))
            size.append(ts.size)
            owner.append(k)
            tm.append(ts.mean())
            tself.append(float(np.sum(ts * (2.0 * (ts.size - j) - 1.0))) / ts.size**2)
            if ts.size > 1:
                ss += seg.var(axis=0, ddof=1) * (ts.size - 1)
                dof += ts.size - 1
        white.append(ss / dof if dof else y[p.start:p.stop].var(axis=0, ddof=1))
    return (np.array(z), np.array(size, dtype=np.float64), np.array(owner), np.array(tm), np.array(tself),
            np.array(white))


def estimate_random_walk(t_ns, y, phases, a, u0, group, tilt_sigma: float = 0.0, block_s: float = 0.25,
                         floor: float = 0.0) -> RandomWalkFit:
    """Random-walk density of one sensor from its steady phases (restricted maximum likelihood).

    Parameters
    ----------
    t_ns : (N,) int64
        Stamps.
    y : (N, 3) float64
        The sensor's samples.
    phases : list of SteadyPhase
        The phases used, in time order.
    a, u0, group : (P,), (P, 3), (P,)
        Reference magnitude, nominal direction and tilt group of each phase (step 4 of
        :mod:`splineimu.calibration`).
    tilt_sigma : float
        Tilt prior [rad] (the tilts' covariance is part of the model).
    block_s : float, default 0.25
        Block length [s].
    floor : float
        Smallest white-noise standard deviation per sample (noise-free data).

    Returns
    -------
    RandomWalkFit
        ``density`` ``sigma_K`` (0 when the likelihood is largest without drift) and
        ``lr_statistic``, twice the log-likelihood gain over no drift.

    Notes
    -----
    Every block mean of every phase is ``a_p c K u0_p + b + drift + white + tilt``: per axis a
    Gaussian vector with covariance ``V + s D`` (``V`` white noise and tilts, ``D`` the
    block-mean kernel ``mean min(t, t')`` over the whole timeline, ``s = sigma_K^2``) and a mean
    linear in four unknowns (the axis' row of ``K`` and its bias), which the restricted
    likelihood removes. One ``s`` for the three axes maximizes the sum of their restricted
    log-likelihoods (bounded Brent search in ``log s``, compared with ``s = 0``); with the
    generalized eigenvectors ``U^T V U = I``, ``U^T D U = diag(lam)`` each evaluation is O(B).
    """
    from scipy.linalg import eigh
    from scipy.optimize import minimize_scalar

    from .solve import tilt_moments

    z, size, owner, tm, tself, white = _blocks(t_ns, y, phases, block_s)
    c, vpar, vperp = tilt_moments(tilt_sigma) if tilt_sigma > 0 else (1.0, 0.0, 0.0)
    X = np.column_stack([(a * c)[:, None] * u0, np.ones(len(phases))])[owner]      # (B, 4), the same per axis
    D = np.minimum.outer(tm, tm)
    D[np.diag_indices(tm.size)] = tself
    V = []
    for r in range(3):
        Vr = np.diag(np.maximum(white[owner, r], floor**2) / size)
        if tilt_sigma > 0:
            su = np.where(np.abs(u0[:, r]) > 0.5, vpar, vperp) * a          # a_p Sigma_u[r, r]
            same = (group[owner][:, None] == group[owner][None, :]) & (group[owner][:, None] >= 0)
            Vr += np.where(same, np.outer(su[owner], a[owner]), 0.0)
        V.append(Vr)

    # V + s D = U^-T (I + s lam) U^-1 with U^T V U = I (generalized eigenvectors): O(B) per evaluation
    axes = []
    for r in range(3):
        lam, U = eigh(D, V[r])
        axes.append((np.maximum(lam, 0.0), U.T @ X, U.T @ z[:, r]))

    def neg2_loglik(s):
        total = 0.0
        for lam, Xt, zt in axes:
            w = 1.0 / (1.0 + s * lam)
            G = Xt.T @ (w[:, None] * Xt)
            q = Xt.T @ (w * zt)
            total += np.sum(np.log1p(s * lam)) + np.linalg.slogdet(G)[1] + zt @ (w * zt) - q @ np.linalg.solve(G, q)
        return total

    s0 = float(np.median(np.diag(V[0]))) / max(float(tm[-1] - tm[0]), 1e-9)    # drift = block noise over the span
    best = minimize_scalar(lambda x: neg2_loglik(s0 * 10.0**x), bounds=(-8.0, 8.0), method="bounded",
                           options={"xatol": 1e-3})
    s = s0 * 10.0**best.x
    gain = neg2_loglik(0.0) - neg2_loglik(s)
    return RandomWalkFit(math.sqrt(s), gain) if gain > 0 else RandomWalkFit(0.0, 0.0)
