"""Sensor-model kernels: bias processes driven by pre-drawn standard normals.

No validation and no random generation here (see :mod:`splineimu.imu.noise`); all arrays are
C-contiguous float64, outputs come last and are accumulated into (``+=``).
"""

from __future__ import annotations

import math

from .._jit import jit


@jit
def random_walk_add(z, sigma, sqrt_dt, bias, state):
    """Add a random walk continuing from ``state`` (3,), and leave its last value there.

    ``z`` (M, 3) standard normals, ``sigma`` (3,), ``sqrt_dt`` (M,), ``bias`` (N, 3) += w with
    ``N - M`` in {0, 1}: when ``N = M + 1`` (the first piece of a record) the first sample
    is the start, ``w_0 = state``; every later sample takes one step,
    ``w_k = w_{k-1} + sigma * sqrt_dt * z``. Feeding a record piece by piece gives the
    same numbers as feeding it whole.
    """
    n = bias.shape[0]
    off = n - z.shape[0]
    w0 = state[0]
    w1 = state[1]
    w2 = state[2]
    s0 = sigma[0]
    s1 = sigma[1]
    s2 = sigma[2]
    for k in range(off):
        bias[k, 0] += w0
        bias[k, 1] += w1
        bias[k, 2] += w2
    for i in range(z.shape[0]):
        h = sqrt_dt[i]
        w0 += s0 * h * z[i, 0]
        w1 += s1 * h * z[i, 1]
        w2 += s2 * h * z[i, 2]
        bias[i + off, 0] += w0
        bias[i + off, 1] += w1
        bias[i + off, 2] += w2
    state[0] = w0
    state[1] = w1
    state[2] = w2


@jit
def gauss_markov_add(z, sigma, tau, dt, bias, state, first):
    """Add a stationary first-order Gauss-Markov process per axis, continuing from ``state``.

    ``g_0 = sigma z_0`` when ``first`` (stationary start); then
    ``g_k = phi g_{k-1} + sigma sqrt(1 - phi^2) z_k`` with ``phi = exp(-dt / tau)``: the exact
    discretization of ``dg/dt = -g / tau + sqrt(2 sigma^2 / tau) w(t)`` for any step.
    ``z`` (N, 3), ``sigma``, ``tau`` (3,), ``bias`` (N, 3) += g, ``state`` (3,) the last
    value (read unless ``first``, written at the end); ``dt`` holds the N - 1 steps inside
    the piece when ``first``, else the N steps from the previous piece's last sample.
    """
    n = bias.shape[0]
    for a in range(3):
        s = sigma[a]
        ta = tau[a]
        k0 = 0
        if first:
            g = s * z[0, a]
            bias[0, a] += g
            k0 = 1
        else:
            g = state[a]
        last_dt = -1.0
        phi = 0.0
        q = 0.0
        for k in range(k0, n):
            h = dt[k - k0]
            if h != last_dt:  # regular stamps: one exp per axis
                phi = math.exp(-h / ta)
                q = s * math.sqrt(max(0.0, 1.0 - phi * phi))
                last_dt = h
            g = phi * g + q * z[k, a]
            bias[k, a] += g
        state[a] = g


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
