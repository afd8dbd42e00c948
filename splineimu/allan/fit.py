"""Noise parameters of an IMU axis read off its Allan-deviation curve.

White-noise density N (the -1/2 slope line at tau = 1 s), random walk K (the +1/2 slope line
at tau = 3 s) and bias instability B (the curve's minimum / 0.664), each with a 95 % interval,
from a non-negative weighted least-squares fit of the IEEE Std 952-1997 model
``sigma^2(tau) = N^2 / tau + (2 ln 2 / pi) B^2 + K^2 tau / 3`` (see :mod:`.deviation`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .deviation import (
    FLICKER_FLOOR,
    FLICKER_FM,
    RANDOM_WALK_FM,
    WHITE_FM,
    AllanResult,
    _chi2_interval_factors,
    _chi2_ppf,
    edf_oadev,
)

__all__ = ["NoiseFit", "fit_noise_parameters"]


def _nnls(A, b):
    """Non-negative least squares ``min |A x - b|, x >= 0`` for a few columns, exactly: the
    optimum is the unconstrained solution on its support, so every support is tried (2^3
    for the noise model) and the best feasible one kept. (``scipy.optimize.nnls`` gives the
    same; importing ``scipy.optimize`` costs 0.34 s, measured.)"""
    n = A.shape[1]
    best_x = np.zeros(n)
    best_r = float(b @ b)
    live = [j for j in range(n) if np.any(A[:, j] != 0.0)]
    for mask in range(1, 1 << len(live)):
        cols = [live[i] for i in range(len(live)) if mask >> i & 1]
        xs = np.linalg.lstsq(A[:, cols], b, rcond=None)[0]
        if np.any(xs < 0.0):
            continue
        r = b - A[:, cols] @ xs
        rr = float(r @ r)
        if rr < best_r:
            best_r = rr
            best_x = np.zeros(n)
            best_x[cols] = xs
    return best_x


@dataclass
class NoiseFit:
    """Noise parameters per axis read off an Allan-deviation curve (K axes).

    Units follow the data: for a gyro in rad/s, ``white_noise_density`` is rad/s/sqrt(Hz)
    (Kalibr's ``gyroscope_noise_density``), ``random_walk`` rad/s^2/sqrt(Hz)
    (``gyroscope_random_walk``) and ``bias_instability`` rad/s.

    Attributes
    ----------
    white_noise_density, random_walk, bias_instability : (K,) float64
        N (the -1/2 line at tau = 1 s), K (the +1/2 line at tau = 3 s), B (floor / 0.664).
    white_noise_density_ci95, random_walk_ci95, bias_instability_ci95 : (K, 2) float64
        95 % intervals ``[low, high]`` (``high`` may be ``inf``: not bounded by the data).
    random_walk_resolved : (K,) bool
        False when the random walk is not significant (its 95 % interval includes 0, or the
        +1/2 slope never dominates the curve): ``random_walk`` is then the 95 % upper bound
        and its interval ``[0, bound]``.
    bias_instability_resolved : (K,) bool
        False when the curve's minimum is explained by the white and random-walk terms alone
        (no flat region): ``bias_instability`` is then only an upper bound on B.
    bias_instability_tau_s : (K,) float64
        Cluster time of the minimum.
    white_fit_tau_range_s, random_walk_fit_tau_range_s : (K, 2) float64
        Cluster times used for each line (``nan`` when unresolved).
    model_coefficients : (K, 3) float64
        ``(N^2, c, K^2)`` of the weighted least-squares model ``N^2/tau + c + K^2 tau/3`` used to
        decide which term dominates where (``c`` = flat floor's variance).
    labels : list of str
    """

    white_noise_density: np.ndarray
    white_noise_density_ci95: np.ndarray
    random_walk: np.ndarray
    random_walk_ci95: np.ndarray
    random_walk_resolved: np.ndarray
    bias_instability: np.ndarray
    bias_instability_ci95: np.ndarray
    bias_instability_resolved: np.ndarray
    bias_instability_tau_s: np.ndarray
    white_fit_tau_range_s: np.ndarray
    random_walk_fit_tau_range_s: np.ndarray
    model_coefficients: np.ndarray
    labels: list = field(default_factory=list)

    def white_line(self, taus_s) -> np.ndarray:
        """The fitted -1/2 slope lines ``N / sqrt(tau)``, (T, K)."""
        t = np.asarray(taus_s, dtype=np.float64)[:, None]
        return self.white_noise_density[None, :] / np.sqrt(t)

    def random_walk_line(self, taus_s) -> np.ndarray:
        """The fitted +1/2 slope lines ``K sqrt(tau / 3)``, (T, K)."""
        t = np.asarray(taus_s, dtype=np.float64)[:, None]
        return self.random_walk[None, :] * np.sqrt(t / 3.0)

    def model_adev(self, taus_s) -> np.ndarray:
        """The least-squares model ``sqrt(N^2/tau + c + K^2 tau/3)``, (T, K)."""
        t = np.asarray(taus_s, dtype=np.float64)[:, None]
        c = self.model_coefficients
        return np.sqrt(c[None, :, 0] / t + c[None, :, 1] + c[None, :, 2] * t / 3.0)

    def to_dataframe(self):
        """:class:`pandas.DataFrame` with one row per axis: N, K, B, their 95 % bounds, the flags."""
        import pandas as pd

        cols = {"axis": list(self.labels) or [str(k) for k in range(self.white_noise_density.size)]}
        for name in ("white_noise_density", "random_walk", "bias_instability"):
            ci = getattr(self, name + "_ci95")
            cols[name] = getattr(self, name)
            cols[name + "_ci95_low"] = ci[:, 0]
            cols[name + "_ci95_high"] = ci[:, 1]
        cols["random_walk_resolved"] = self.random_walk_resolved
        cols["bias_instability_resolved"] = self.bias_instability_resolved
        cols["bias_instability_tau_s"] = self.bias_instability_tau_s
        return pd.DataFrame(cols)


# ------------------------------------------------------------------------------ fit


def _wls_model(taus, s2, edf_of_alpha, flat=True, n_iter=12):
    """Non-negative weighted least squares of ``s2 ~ a/tau + c + b tau/3`` (``c = 0`` unless
    ``flat``).

    The weight of a point is ``edf / (2 model^2)`` (the variance of a chi-square estimate),
    recomputed from the current model, with the EDF of the term that dominates there.
    """
    A = np.column_stack([1.0 / taus, np.ones_like(taus) if flat else np.zeros_like(taus), taus / 3.0])
    model = s2.copy()
    x = np.zeros(3)
    for _ in range(n_iter):
        terms = A * x[None, :] if np.any(x > 0) else None
        if terms is None:
            alpha = np.full(taus.shape, WHITE_FM)
        else:
            alpha = np.array([WHITE_FM, FLICKER_FM, RANDOM_WALK_FM])[np.argmax(terms, axis=1)]
        nu = edf_of_alpha(alpha)
        w = np.sqrt(nu / 2.0) / np.maximum(model, 1e-300)
        Aw = A * w[:, None]
        scale = np.linalg.norm(Aw, axis=0)
        scale[scale == 0] = 1.0
        xs = _nnls(Aw / scale, s2 * w)
        x_new = xs / scale
        new_model = A @ x_new
        if np.all(new_model > 0):
            converged = np.allclose(x_new, x, rtol=1e-9, atol=0.0)
            x, model = x_new, new_model
            if converged:
                break
        else:
            x = x_new
            break
    return x, A


def _combine(s2, other, g, nu, frac):
    """Combine per-point estimates of one coefficient ``p`` of the model ``s2 = other + p g``.

    Point j gives ``p_j = (s2_j - other_j) / g_j`` (the other model terms subtracted); its
    relative standard deviation is ``r_j = sqrt(2 / nu_j) / frac_j`` (``frac_j``: share of
    the point's variance due to this term), and the points are averaged with weights
    ``1 / r_j^2``. Overlapping Allan estimates at neighbouring taus are strongly correlated,
    so the interval assumes them fully (rank-)correlated: each point's exact chi-square
    interval of the total variance, ``[s2 nu / chi2_0.975(nu), s2 nu / chi2_0.025(nu)]``, is
    mapped to ``p`` and the bounds are averaged with the same weights. For one point this is
    the exact interval; for several it is conservative. Returns ``(estimate, low, high)``.
    """
    r = np.sqrt(2.0 / nu) / np.maximum(frac, 1e-12)
    w = 1.0 / r**2
    w /= w.sum()
    est = float(w @ ((s2 - other) / g))
    lo = float(w @ ((s2 * nu / _chi2_ppf(0.975, nu) - other) / g))
    hi = float(w @ ((s2 * nu / _chi2_ppf(0.025, nu) - other) / g))
    return max(est, 0.0), max(lo, 0.0), max(hi, 0.0)


def fit_noise_parameters(result: AllanResult, *, min_white_tau_s: float | None = None,
                         white_fraction: float = 0.9, random_walk_fraction: float = 0.5,
                         flat_fraction: float = 0.5, max_bias_tau_fraction: float = 0.1) -> NoiseFit:
    """Read white-noise density N, random walk K and bias instability B off each axis.

    Parameters
    ----------
    result : AllanResult
        From :func:`allan_deviation` (the default cluster times suit this fit).
    min_white_tau_s : float, optional
        Shortest cluster time for the white-noise line (default ``10 / rate``: the first few
        samples are shaped by the sensor's internal filters and by quantization).
    white_fraction : float
        The -1/2 line is fitted where the white term explains at least this share of the
        model variance.
    random_walk_fraction : float
        The +1/2 line is fitted where the random-walk term explains at least this share.
    flat_fraction : float
        The model keeps its flat (bias-instability) term only if that term explains at least
        this share of the variance at some tau with 10 or more degrees of freedom; otherwise
        it is refitted without it.
    max_bias_tau_fraction : float
        The minimum for B is searched up to this fraction of the record (at least 10
        independent clusters).

    Returns
    -------
    NoiseFit

    Notes
    -----
    1. A non-negative weighted least-squares fit of ``sigma^2 = N^2/tau + c + K^2 tau/3`` to
       all points (weights: inverse chi-square variance of each point from its EDF,
       iterated on the model) decides which term dominates at each tau. The flat term is
       dropped (refit with ``c = 0``) when it never reaches ``flat_fraction`` of the variance
       where the curve is known to 10 degrees of freedom or better.
    2. **N**: on the points where white noise dominates, the other two model terms are
       subtracted and ``N^2 = tau sigma^2`` (the -1/2 line, equal to N at tau = 1 s) is
       averaged with inverse-variance weights.
    3. **K**: likewise ``K^2 = 3 sigma^2 / tau`` (the +1/2 line, equal to K at tau = 3 s) on
       the points where the random walk dominates. If its interval includes 0 the walk is
       "not resolved" and K is reported as the interval's upper end.
    4. **B**: the minimum of the curve up to ``max_bias_tau_fraction`` of the record,
       divided by 0.664, with the chi-square interval of that point (flicker-FM EDF). The
       selection of a minimum biases it slightly low.

    Intervals: each point's chi-square interval of the total variance (EDF of the dominant
    noise type) is mapped to the coefficient with the other terms subtracted, and the bounds
    are averaged with the estimate's weights, i.e. the points of a line are assumed fully
    correlated (see ``_combine``): exact for one point, conservative for several. They hold
    only for the model above (no drift, no temperature trend, no flicker component other
    than a flat floor) and ignore the small uncertainty of the subtracted terms.

    Examples
    --------
    >>> from splineimu.allan import allan_deviation
    >>> rng = np.random.default_rng(1)
    >>> y = 0.01 * np.sqrt(100.0) * rng.standard_normal(200_000)  # N = 0.01 at 100 Hz
    >>> f = fit_noise_parameters(allan_deviation(y, 100.0))
    >>> bool(abs(f.white_noise_density[0] / 0.01 - 1) < 0.02)
    True
    """
    taus = result.taus_s
    T, K = result.adev.shape
    n_phase = result.n_samples + 1
    rate = result.rate_hz
    if min_white_tau_s is None:
        min_white_tau_s = 10.0 / rate
    def edf_of_alpha(alpha):
        return edf_oadev(n_phase, result.m, alpha)

    nan2 = np.full((K, 2), np.nan)
    nu_white = edf_of_alpha(WHITE_FM)
    nu_rw = edf_of_alpha(RANDOM_WALK_FM)
    nu_ff = edf_of_alpha(FLICKER_FM)
    out = {
        "white_noise_density": np.zeros(K), "white_noise_density_ci95": np.zeros((K, 2)),
        "random_walk": np.zeros(K), "random_walk_ci95": np.zeros((K, 2)),
        "random_walk_resolved": np.zeros(K, dtype=bool),
        "bias_instability": np.zeros(K), "bias_instability_ci95": np.zeros((K, 2)),
        "bias_instability_resolved": np.zeros(K, dtype=bool), "bias_instability_tau_s": np.zeros(K),
        "white_fit_tau_range_s": nan2.copy(), "random_walk_fit_tau_range_s": nan2.copy(),
        "model_coefficients": np.zeros((K, 3)),
    }
    for k in range(K):
        s2 = result.adev[:, k] ** 2
        if not np.any(s2 > 0):  # a constant signal: every term is zero
            out["bias_instability_tau_s"][k] = taus[0]
            continue
        x, A = _wls_model(taus, s2, edf_of_alpha)
        terms = A * x[None, :]
        model = np.maximum(terms.sum(axis=1), 1e-300)
        frac = terms / model[:, None]
        informative = nu_ff >= 10.0  # a floor seen only in the last few clusters is noise
        if not informative.any() or frac[informative, 1].max() < flat_fraction:
            # no visible floor: a small constant soaked up by the fit would only bias the
            # white and random-walk coefficients that it is subtracted from
            x, A = _wls_model(taus, s2, edf_of_alpha, flat=False)
            terms = A * x[None, :]
            model = np.maximum(terms.sum(axis=1), 1e-300)
            frac = terms / model[:, None]
        out["model_coefficients"][k] = x

        # --- white noise: -1/2 line
        sel = (frac[:, 0] >= white_fraction) & (taus >= min_white_tau_s - 1e-12)
        if not sel.any():
            sel = frac[:, 0] >= 0.5
        if not sel.any():
            sel = np.zeros(T, dtype=bool)
            sel[0] = True
        est, lo, hi = _combine(s2[sel], terms[sel, 1] + terms[sel, 2], 1.0 / taus[sel], nu_white[sel],
                               frac[sel, 0])
        out["white_noise_density"][k] = math.sqrt(est)
        out["white_noise_density_ci95"][k] = (math.sqrt(lo), math.sqrt(hi))
        out["white_fit_tau_range_s"][k] = (taus[sel].min(), taus[sel].max())

        # --- random walk: +1/2 line
        sel = frac[:, 2] >= random_walk_fraction
        est = lo = hi = 0.0
        if sel.any():
            est, lo, hi = _combine(s2[sel], terms[sel, 0] + terms[sel, 1], taus[sel] / 3.0, nu_rw[sel],
                                   frac[sel, 2])
            out["random_walk_fit_tau_range_s"][k] = (taus[sel].min(), taus[sel].max())
        if lo > 0.0:
            out["random_walk"][k] = math.sqrt(est)
            out["random_walk_ci95"][k] = (math.sqrt(lo), math.sqrt(hi))
            out["random_walk_resolved"][k] = True
        else:
            # not significant: report the 95 % upper bound. Without a +1/2 region, attribute
            # all of a point's variance to the random walk, at the point (chosen on the model)
            # where that bound is tightest.
            if not sel.any():
                q_lo = _chi2_ppf(0.025, nu_rw)
                j = int(np.argmin(3.0 * model * nu_rw / (q_lo * taus)))
                hi = 3.0 * s2[j] * nu_rw[j] / (q_lo[j] * taus[j])
            out["random_walk"][k] = math.sqrt(hi)
            out["random_walk_ci95"][k] = (0.0, math.sqrt(hi))

        # --- bias instability: minimum of the curve
        cand = np.flatnonzero(taus <= max_bias_tau_fraction * result.duration_s + 1e-12)
        if cand.size == 0:
            cand = np.arange(T)
        j = int(cand[np.argmin(result.adev[cand, k])])
        lo_f, hi_f = _chi2_interval_factors(nu_ff[j])
        a = result.adev[j, k]
        out["bias_instability"][k] = a / FLICKER_FLOOR
        out["bias_instability_ci95"][k] = (a * math.sqrt(lo_f) / FLICKER_FLOOR,
                                           a * math.sqrt(hi_f) / FLICKER_FLOOR)
        out["bias_instability_tau_s"][k] = taus[j]
        out["bias_instability_resolved"][k] = bool(frac[j, 1] >= 0.5)
    return NoiseFit(labels=list(result.labels), **out)
