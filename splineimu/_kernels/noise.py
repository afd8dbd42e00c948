"""Sensor-model kernels: bias processes driven by pre-drawn standard normals.

No validation and no random generation here (see :mod:`splineimu.imu.noise`); all arrays are
C-contiguous float64, outputs come last and are accumulated into (``+=``).
"""

from __future__ import annotations

import math

from .._jit import jit


@jit
def random_walk_add(z, sigma, sqrt_dt, bias):
    """Add a random walk starting at 0: ``w_0 = 0``, ``w_k = w_{k-1} + sigma * sqrt_dt[k-1] * z[k-1]``.

    ``z`` (N-1, 3) standard normals, ``sigma`` (3,), ``sqrt_dt`` (N-1,), ``bias`` (N, 3) += w.
    """
    n = bias.shape[0]
    w0 = 0.0
    w1 = 0.0
    w2 = 0.0
    s0 = sigma[0]
    s1 = sigma[1]
    s2 = sigma[2]
    for k in range(1, n):
        h = sqrt_dt[k - 1]
        w0 += s0 * h * z[k - 1, 0]
        w1 += s1 * h * z[k - 1, 1]
        w2 += s2 * h * z[k - 1, 2]
        bias[k, 0] += w0
        bias[k, 1] += w1
        bias[k, 2] += w2


@jit
def gauss_markov_add(z, sigma, tau, dt, bias):
    """Add a stationary first-order Gauss-Markov process per axis.

    ``g_0 = sigma z_0``; ``g_k = phi g_{k-1} + sigma sqrt(1 - phi^2) z_k`` with
    ``phi = exp(-dt[k-1] / tau)``: the exact discretization of
    ``dg/dt = -g / tau + sqrt(2 sigma^2 / tau) w(t)`` for any step. ``z`` (N, 3), ``sigma``,
    ``tau`` (3,), ``dt`` (N-1,), ``bias`` (N, 3) += g.
    """
    n = bias.shape[0]
    for a in range(3):
        s = sigma[a]
        ta = tau[a]
        g = s * z[0, a]
        bias[0, a] += g
        last_dt = -1.0
        phi = 0.0
        q = 0.0
        for k in range(1, n):
            h = dt[k - 1]
            if h != last_dt:  # regular stamps: one exp per axis
                phi = math.exp(-h / ta)
                q = s * math.sqrt(max(0.0, 1.0 - phi * phi))
                last_dt = h
            g = phi * g + q * z[k, a]
            bias[k, a] += g


@jit
def add_scaled_noise(x, sigma_d, z):
    """``x[k, a] += sigma_d[a] * z[k, a]`` (white noise, in place)."""
    n = x.shape[0]
    s0 = sigma_d[0]
    s1 = sigma_d[1]
    s2 = sigma_d[2]
    for k in range(n):
        x[k, 0] += s0 * z[k, 0]
        x[k, 1] += s1 * z[k, 1]
        x[k, 2] += s2 * z[k, 2]
