r"""Step 4 of a calibration: (generalized) least squares for ``K`` and ``b`` from the phase means.

``m_p = a_p K u_p + b + n_p`` with the rows of ``K`` and ``b`` decoupled; with random tilts of
the positions / mounts (``tilt_sigma`` > 0) the tilt moments of :func:`tilt_moments` give the
mean ``c`` and the covariance of the references (:mod:`splineimu.calibration`, "Orientation
error").
"""

from __future__ import annotations

import numpy as np

from ..lie import so3_hat

__all__ = ["tilt_moments", "solve_intrinsics"]


def _tangent_basis(u0):
    """(3, 2): the two unit axes other than the dominant axis of ``u0`` (the tilt axes)."""
    i = int(np.argmax(np.abs(u0)))
    others = [k for k in range(3) if k != i]
    return np.eye(3)[:, others]



def tilt_moments(sigma: float):
    """Moments of a random tilt ``theta ~ N(0, sigma^2 I_2)`` of a unit vector ``u0``.

    ``u = Exp(theta) u0 = cos|theta| u0 + sin|theta| (theta / |theta|) x u0``.

    Returns
    -------
    c : float
        ``E[cos|theta|] = 1 - sigma^2 + sigma^4 / 3 - ...`` (so ``E[u] = c u0``).
    var_parallel : float
        ``Var(cos|theta|)`` (about ``sigma^4``): the variance of ``u`` along ``u0``.
    var_perpendicular : float
        ``E[sin^2|theta|] / 2`` (about ``sigma^2``): the variance of ``u`` along each direction
        perpendicular to ``u0``.

    Notes
    -----
    ``|theta|`` is Rayleigh distributed with ``E|theta|^(2k) = 2^k k! sigma^(2k)``, so
    ``E[cos(m |theta|)] = sum_k (-1)^k 2^k k! (m sigma)^(2k) / (2k)!`` (an entire series).

    Examples
    --------
    >>> c, vpar, vperp = tilt_moments(0.01)
    >>> round((1 - c) / 1e-4, 6), round(vpar / 1e-8, 3), round(vperp / 1e-4, 3)
    (0.999967, 1.0, 1.0)
    """
    def e_cos(m):
        x = (m * sigma) ** 2
        total, term = 1.0, 1.0
        for k in range(1, 200):
            term *= -2.0 * k * x / ((2 * k - 1) * (2 * k))
            total += term
            if abs(term) < 1e-18 * abs(total):
                break
        return total

    c1, c2 = e_cos(1.0), e_cos(2.0)
    return c1, max(0.0, 0.5 * (1.0 + c2) - c1 * c1), 0.25 * (1.0 - c2)


def solve_intrinsics(m, var, a, u0, group, tilt_sigma, drift_cov=None):
    """Generalized least squares for ``K``, ``b`` with random orientation errors.

    Model: ``m_p = a_p K u_p + b + n_p``, ``n_p ~ N(0, diag(var_p))``; the phases of one
    group share ``u = Exp(theta_g) u0``, ``theta_g ~ N(0, tilt_sigma^2 I_2)``. Then
    ``E[m_p] = a_p c K u0_p + b`` and ``Cov(m_p, m_q) = a_p a_q K Sigma_u K^T`` within a group
    (:func:`tilt_moments`), which depends on ``K`` (iterated from the nominal estimate).
    ``drift_cov`` (3P, 3P), when given, is added to the covariance of the phase means (bias
    drift, :func:`~splineimu.calibration.drift.phase_drift_covariance`; index ``3 p + axis``).

    Returns (K, b, cov12, tilts (G, 2) best linear predictions, chi2, ok).
    """
    P = m.shape[0]
    use_tilt = tilt_sigma > 0.0
    c, vpar, vperp = tilt_moments(tilt_sigma) if use_tilt else (1.0, 0.0, 0.0)
    A = np.zeros((3 * P, 12))
    for p in range(P):
        for r in range(3):
            A[3 * p + r, 3 * r:3 * r + 3] = a[p] * c * u0[p]
            A[3 * p + r, 9 + r] = 1.0
    y = m.reshape(-1)
    tilted = [p for p in range(P) if use_tilt and group[p] >= 0 and a[p] != 0.0]
    K = np.eye(3)
    x = None
    for _ in range(20):
        C = np.diag(var.reshape(-1)) if drift_cov is None else np.diag(var.reshape(-1)) + drift_cov
        # the tilt covariance uses the estimated scale factors only: the off-diagonal part of
        # the estimate carries the common tilt of each axis pair, not misalignment
        Kc = np.diag(np.diag(K))
        for p in tilted:
            Su = vpar * np.outer(u0[p], u0[p]) + vperp * (np.eye(3) - np.outer(u0[p], u0[p]))
            KSK = Kc @ Su @ Kc.T
            for q in tilted:
                if group[q] == group[p]:
                    C[3 * p:3 * p + 3, 3 * q:3 * q + 3] += a[p] * a[q] * KSK
        L = np.linalg.cholesky(C)
        Aw = np.linalg.solve(L, A)
        yw = np.linalg.solve(L, y)
        sv = np.linalg.svd(Aw, compute_uv=False)
        if sv.size < 12 or sv[-1] <= 1e-10 * sv[0]:
            return None, None, None, None, None, False
        x_new, *_ = np.linalg.lstsq(Aw, yw, rcond=None)
        done = x is not None and np.max(np.abs(x_new - x)) <= 1e-13 * max(1.0, np.max(np.abs(x_new)))
        x = x_new
        K = x[:9].reshape(3, 3)
        if not tilted or done:
            break
    _, s, Vt = np.linalg.svd(Aw, full_matrices=False)
    cov = (Vt.T / s**2) @ Vt
    rw = yw - Aw @ x
    chi2 = float(rw @ rw)
    tilts = None
    if tilted:
        Cr = np.linalg.solve(L.T, rw).reshape(P, 3)  # C^-1 (y - A x)
        G = max(group[p] for p in tilted) + 1
        tilts = np.zeros((G, 2))
        for p in tilted:
            D = -a[p] * K @ so3_hat(u0[p]) @ _tangent_basis(u0[p])  # d m_p / d theta (3, 2)
            tilts[group[p]] += tilt_sigma**2 * (D.T @ Cr[p])
    return K.copy(), x[9:12].copy(), cov, tilts, chi2, True
