"""Automatic knot spacing: minimize the predicted error of the synthesized IMU signals.

For a least-squares spline of order ``k`` and knot spacing ``dt`` the error of an ``r``-th
derivative has two parts (in the spirit of Ovren & Forssen, "Spline Error Weighting",
CVPR 2018):

- **bias**: the spline is a low-pass filter; motion above its cut-off is lost. With the
  spline's relative error transfer ``E_r(f; dt)`` (measured by fitting sinusoids on a
  synthetic uniform grid with the same sample rate) and the motion's power spectrum
  ``S(f)``, ``bias^2 = sum_f E_r(f; dt) (2 pi f)^(2r) S(f)``;
- **variance**: pose noise passes through the fit; ``var = sigma^2 G_r(dt)`` with the noise
  gain ``G_r`` measured by fitting white noise on the same synthetic grid.

``S(f)`` is the periodogram of the positions (``r = 2``, accelerometer) and of the
accumulated body rotation increments (``r = 1``, gyroscope), resampled to a uniform grid;
the noise levels ``sigma`` are read from the flat high-frequency floor of those spectra
(nothing needs to be told). The chosen spacing minimizes
``E_acc / a_ref^2 + E_gyro / g_ref^2`` with ``a_ref / g_ref = 10`` (a typical MEMS IMU's
accelerometer-to-gyroscope noise-density ratio, e.g. 2e-3 / 1.7e-4 for the ADIS16448), over a
log-spaced grid from the sample spacing to a quarter of the span. With ``order="auto"`` the
orders 4, 5 and 6 are compared the same way and the best predicted one is taken.
"""

from __future__ import annotations

import numpy as np

from .. import lie
from .._kernels import fit as _kf
from .banded import DEFAULT_SMOOTHNESS, add_position_penalty, solve_banded_scalar
from .basis import basis_values, blending_matrix

ACCEL_TO_GYRO_WEIGHT = 10.0
_N_FREQ = 40
_SYN_SEGMENTS = 16


def _uniform_resample(t, X, rate):
    n = max(int(np.floor((t[-1] - t[0]) * rate)) + 1, 8)
    tu = t[0] + np.arange(n) / rate
    return tu, np.column_stack([np.interp(tu, t, X[:, i]) for i in range(X.shape[1])])


def _noise_sigma(X):
    """White-noise sigma (per axis, averaged) from 4th differences (var = 70 sigma^2), robust
    (MAD); smooth motion only contributes ~ h^4 times its 4th derivative."""
    if X.shape[0] < 12:
        return 0.0
    d4 = np.diff(X, n=4, axis=0)
    mad = np.median(np.abs(d4 - np.median(d4, axis=0)), axis=0) * 1.4826
    return float(np.sqrt(np.mean(mad**2) / 70.0))


def _derivative_spectrum(X, rate, deriv):
    """Signal power per bin of the deriv-th derivative of the motion (summed over axes) and the
    white-noise sigma of the samples.

    The spectrum is that of Hann-windowed finite differences. The noise level is read from
    the top 40 % of the band, where smooth motion has no power; the signal is what stands
    clearly (2x) above that floor after averaging 16 neighbouring bins, up to the highest
    such frequency, with the difference filter's response corrected to the true derivative
    (the floor is subtracted from the raw bins, so noise-only bins average out).
    """
    h = 1.0 / rate
    y = np.diff(X, n=deriv, axis=0) / h**deriv
    n = y.shape[0]
    w = np.hanning(n)
    F = np.fft.rfft((y - y.mean(axis=0)) * w[:, None], axis=0)
    P = (np.abs(F) ** 2).sum(axis=1) * 2.0 / (n * np.sum(w**2))
    f = np.fft.rfftfreq(n, h)
    shape = (2.0 * np.sin(np.pi * f * h) / h) ** (2 * deriv) * 2.0 / n  # white noise, unit variance
    hi = f > 0.6 * f[-1]
    nvar = float(np.mean(P[hi] / shape[hi])) if hi.sum() >= 4 else 0.0  # = axes * sigma^2
    noise = nvar * shape
    L = 16
    Ps = np.convolve(P, np.ones(L) / L, mode="same") if P.size > 4 * L else P
    above = np.flatnonzero(Ps > 2.0 * noise)
    S = np.zeros_like(P)
    if above.size:
        top = above[-1] + 1
        nz = slice(1, top)
        true = (2 * np.pi * f[nz]) ** (2 * deriv) / np.maximum(shape[nz] * n / 2.0, 1e-300)
        # the raw periodogram (not the averaged one, which would smear strong low-frequency lines
        # to where the spline's error transfer is large); noise-only bins average out
        S[nz] = (P[nz] - noise[nz]) * true
    return f, S, float(np.sqrt(nvar / X.shape[1]))


class _Transfer:
    """Error transfer of LS spline fits on a synthetic uniform grid."""

    def __init__(self, rate):
        self.rate = rate

    def __call__(self, order, dt, freqs):
        from scipy.sparse import csr_matrix

        k = order
        nseg = _SYN_SEGMENTS
        span = nseg * dt
        m = max(int(np.floor(span * self.rate)), nseg * 2)
        t = np.linspace(0.0, span, m + 1)
        s = t / dt
        n = nseg + k - 1
        seg = np.minimum(np.floor(s).astype(int), nseg - 1)
        B = basis_values(k, s - seg)
        rows = np.repeat(np.arange(t.size), k)
        cols = (seg[:, None] + np.arange(k)).ravel()
        A = csr_matrix((B.ravel(), (rows, cols)), shape=(t.size, n))
        Hs = np.zeros((n, k))
        rhs0 = np.zeros((n, 3))
        _kf.position_normal_equations(np.ascontiguousarray(s), np.ones(t.size), np.zeros((t.size, 3)),
                                      blending_matrix(k), nseg, Hs, rhs0)
        add_position_penalty(Hs, DEFAULT_SMOOTHNESS * t.size / n, min(3, k - 1))
        w = 2 * np.pi * freqs
        ph = np.outer(t, w)
        rng = np.random.default_rng(12345)
        Y = np.concatenate([np.cos(ph), np.sin(ph), rng.normal(size=(t.size, 16))], axis=1)
        C = solve_banded_scalar(Hs, A.T @ Y)
        te = np.linspace(span * 0.3, span * 0.7, 240)
        se = te / dt
        sege = np.floor(se).astype(int)
        nf = freqs.size
        phe = np.outer(te, w)
        out = {}
        for r in (1, 2):
            Bd = basis_values(k, se - sege, derivative=r) / dt**r
            est = sum(Bd[:, j:j + 1] * C[sege + j] for j in range(k))
            if r == 1:
                true = np.concatenate([-np.sin(phe) * w, np.cos(phe) * w], axis=1)
            else:
                true = np.concatenate([-np.cos(phe) * w**2, -np.sin(phe) * w**2], axis=1)
            err = est[:, :2 * nf] - true
            E = (np.mean(err[:, :nf] ** 2, axis=0) + np.mean(err[:, nf:2 * nf] ** 2, axis=0)) / w ** (2 * r)
            G = float(np.mean(est[:, 2 * nf:] ** 2))
            out[r] = (E, G)
        return out


def _predict(transfer, order, dt, spec_a, spec_g, sig_p, sig_r):
    fr = np.geomspace(1e-3 / dt, 1.5 / dt, _N_FREQ)
    res = transfer(order, dt, fr)
    preds = []
    for (f, S), sigma, r in ((spec_a, sig_p, 2), (spec_g, sig_r, 1)):
        E, G = res[r]
        Ef = np.minimum(np.interp(f, fr, E, left=E[0], right=1.0), 1.0)
        Ef[f > fr[-1]] = 1.0
        bias2 = max(float(np.sum(Ef * S)), 0.0)
        var = sigma**2 * G * 3.0
        preds.append(np.sqrt(bias2 + var))
    return preds


def choose_knot_spacing(t, P, R, order=4, candidates=None):
    """Pick the knot spacing (and, with ``order="auto"``, the order) for a fit.

    Parameters
    ----------
    t : (N,) seconds, increasing
    P : (N, 3) positions
    R : (N, 3, 3) rotations
    order : int or "auto"

    Returns
    -------
    dict with ``knot_spacing_s``, ``order``, ``position_noise_m``, ``angle_noise_rad``,
    ``predicted_gyro_rms_rad_s``, ``predicted_accel_rms_m_s2``, ``candidates`` (table).
    """
    dts = np.diff(t)
    med = float(np.median(dts))
    rate = 1.0 / med
    span = float(t[-1] - t[0])
    # rotation "signal": accumulated body-frame increments (white pose noise stays white)
    inc = lie.so3_log(np.matmul(np.swapaxes(R[:-1], 1, 2), R[1:]))
    theta = np.vstack([np.zeros(3), np.cumsum(inc, axis=0)])
    # keep the spectrum estimate bounded in cost: at most ~2^18 samples
    rs = rate if span * rate <= 2**18 else 2**18 / span
    _, Pu = _uniform_resample(t, P, rs)
    _, Tu = _uniform_resample(t, theta, rs)
    f_a, S_a, sig_p = _derivative_spectrum(Pu, rs, 2)
    f_g, S_g, sig_r = _derivative_spectrum(Tu, rs, 1)
    spec_a, spec_g = (f_a, S_a), (f_g, S_g)
    refine = candidates is None
    if candidates is None:
        lo = 2.0 * med
        hi = max(min(span / 4.0, 2.0), lo * 1.01)
        candidates = np.geomspace(lo, hi, 12)
    orders = [4, 5, 6] if order == "auto" else [int(order)]
    transfer = _Transfer(rate)
    rows = []

    def evaluate(k, dt):
        ea, eg = _predict(transfer, k, dt, spec_a, spec_g, sig_p, sig_r)
        cost = (ea / ACCEL_TO_GYRO_WEIGHT) ** 2 + eg**2
        rows.append((k, float(dt), float(ea), float(eg), float(cost)))

    for k in orders:
        for dt in candidates:
            if span / dt >= 1:
                evaluate(k, dt)
    if refine and len(candidates) > 2:
        # coarse-to-fine: a finer grid between the neighbours of the best coarse spacing
        k0, dt0 = min(rows, key=lambda r: r[4])[:2]
        step = candidates[1] / candidates[0]
        for dt in np.geomspace(dt0 / step, dt0 * step, 7)[1:-1]:
            if dt != dt0 and dt >= candidates[0] and span / dt >= 1:
                evaluate(k0, dt)
    best = min(rows, key=lambda r: r[4])
    return {
        "knot_spacing_s": best[1],
        "order": best[0],
        "position_noise_m": sig_p,
        "angle_noise_rad": sig_r,
        "predicted_accel_rms_m_s2": best[2],
        "predicted_gyro_rms_rad_s": best[3],
        "method": "spectral error prediction (bias from the motion spectrum, variance from the noise floor)",
        "candidates": [
            {"order": r[0], "knot_spacing_s": r[1], "accel_rms": r[2], "gyro_rms": r[3]} for r in rows
        ],
    }
