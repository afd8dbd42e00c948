"""Numerical differentiation for the tests: the one place where analytic derivatives meet
central differences.

Conventions (the same as :mod:`splineimu.lie`)
----------------------------------------------
A *group* names how a value is perturbed and how two values are subtracted:

``"vec"``
    plain arrays, ``x (+) d = x + d`` and ``y1 (-) y0 = y1 - y0`` (any shape; flattened).
``"so3"``
    rotation matrices (3, 3), tangent dimension 3.
``"se3"``
    homogeneous poses (4, 4), tangent ``[rho, phi]`` (translation first), dimension 6.

On a group the perturbation is on the manifold, on the right by default:
``x (+) d = x Exp(d)`` and ``y1 (-) y0 = Log(y0^-1 y1)``; ``side="left"`` uses
``Exp(d) x`` and ``Log(y1 y0^-1)``. The numerical Jacobian of ``f`` at ``x`` is then
``d (f(x (+) d) (-) f(x)) / d d`` at ``d = 0``, shape ``(dim_out, dim_in)`` (STYLE.md 8).

Differences are taken in the chart centred at ``f(x)``: every column is the derivative at
``s = 0`` of the smooth function ``g(s) = f(x (+) s e_i) (-) f(x)`` (``g(0) = 0``), so that the
difference formulas below keep their full order on the manifold as well.

Difference formulas (``h`` is the outer step)
---------------------------------------------
``"central2"``   ``(g(h) - g(-h)) / 2h``, error ``h^2 g'''/6 + eps |g| / h``.
``"central4"``   ``(-g(2h) + 8 g(h) - 8 g(-h) + g(-2h)) / 12h``, error ``h^4 g^(5)/30``.
``"richardson"`` (default) the central2 estimate at ``h, h/2, ..., h/2^(levels-1)``,
                 extrapolated (Richardson / Romberg table) to order ``2 * levels``.

Choosing ``h``: the truncation error falls as ``h^(2 levels)`` and the rounding error grows as
``eps * |g| / h``. For functions that vary on a scale ``T`` (unit-size angles: ``T ~ 1``; a
signal of bandwidth ``w`` rad/s: ``T ~ 1/w``), ``h = 1e-2 T`` with ``levels=3`` leaves a
truncation error of about ``1e-13`` relative and a rounding error of ``~1e-13`` relative: good
for checks at 1e-9. The default ``h = 1e-3`` (used for Jacobians of unit-scale inputs) is
safe too.

Piecewise functions: every stencil point lies in ``[t - h, t + h]``. A B-spline is only
C^(k-2) at its knots, so for a high-order estimate that interval must not contain a knot (pick
sample times at least ``h`` away from every knot, or ``h`` smaller than that distance).
"""

from __future__ import annotations

from decimal import Decimal

import numpy as np

from splineimu.lie import se3_exp, se3_log, so3_exp, so3_log

__all__ = [
    "GROUP_DIMS",
    "oplus",
    "ominus",
    "derivative_at_zero",
    "numeric_jacobian",
    "time_derivative",
    "assert_jacobian_close",
    "assert_derivative_close",
]

#: tangent dimension of each group (None: the flattened size of the value)
GROUP_DIMS = {"vec": None, "so3": 3, "se3": 6}

_EXP = {"so3": so3_exp, "se3": se3_exp}
_LOG = {"so3": so3_log, "se3": se3_log}


def _check_group(group):
    if group not in GROUP_DIMS:
        raise ValueError(f"unknown group {group!r}; expected one of {sorted(GROUP_DIMS)}")


def _inverse(group, X):
    X = np.asarray(X, dtype=np.float64)
    if group == "so3":
        return np.swapaxes(X, -1, -2)
    Rt = np.swapaxes(X[..., :3, :3], -1, -2)
    out = np.zeros_like(X)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, X[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def oplus(group, x, d, side="right"):
    """``x (+) d``: ``x + d`` for vectors, ``x Exp(d)`` (right) or ``Exp(d) x`` (left) on a group.

    Works on batches: ``x`` (..., n, n) and ``d`` (..., dim).
    """
    _check_group(group)
    if group == "vec":
        return np.asarray(x, dtype=np.float64) + d
    E = _EXP[group](d)
    return np.matmul(x, E) if side == "right" else np.matmul(E, x)


def ominus(group, y1, y0, side="right"):
    """``y1 (-) y0``: ``y1 - y0`` (flattened per item) for vectors, ``Log(y0^-1 y1)`` (right) or
    ``Log(y1 y0^-1)`` (left) on a group."""
    _check_group(group)
    if group == "vec":
        return np.asarray(y1, dtype=np.float64) - np.asarray(y0, dtype=np.float64)
    inv0 = _inverse(group, y0)
    D = np.matmul(inv0, y1) if side == "right" else np.matmul(y1, inv0)
    return _LOG[group](D)


def _bcast(d, like):
    """Reshape per-sample steps ``d`` (scalar or (N,)) to broadcast against ``like`` (N, ...)."""
    d = np.asarray(d, dtype=np.float64)
    return d.reshape(d.shape + (1,) * (np.ndim(like) - d.ndim))


def derivative_at_zero(g, h=1e-3, method="richardson", levels=3, step=None):
    """``g'(0)`` of a smooth ``g: float -> ndarray`` by central differences.

    Parameters
    ----------
    g : callable
        ``g(s)`` for a scalar offset ``s``; returns an array (any fixed shape).
    h : float
        Outer step (see the module notes on choosing it).
    method : {"richardson", "central4", "central2"}
        ``"central4"`` is the five-point formula, written as ``(4 D(h) - D(2h)) / 3`` of the
        central differences ``D``.
    levels : int
        Richardson levels (order ``2 * levels``); 1 is plain ``central2``.
    step : callable, optional
        ``step(s)`` -> the offset that ``g(s)`` really applied (scalar, or one per leading
        index of ``g(s)``), e.g. ``(t + s) - t``: ``t + s`` is rounded, and dividing by the
        nominal ``2 s`` would add an error ``eps |t| / s``. Default: exactly ``s``.

    Returns
    -------
    ndarray, the shape of ``g(0)``.
    """

    def central(hj):
        gp = np.asarray(g(hj), dtype=np.float64)
        gm = np.asarray(g(-hj), dtype=np.float64)
        den = 2.0 * hj if step is None else _bcast(step(hj) - step(-hj), gp)
        return (gp - gm) / den

    if method == "central2":
        return central(h)
    if method == "central4":
        return (4.0 * central(h) - central(2.0 * h)) / 3.0
    if method != "richardson":
        raise ValueError(f"unknown method {method!r}")
    if levels < 1:
        raise ValueError("levels must be >= 1")
    # Romberg table: T[j][0] = central2 at h / 2^j; T[j][m] removes the h^(2m) error term.
    row = []
    for j in range(levels):
        new = [central(h / 2.0**j)]
        for m in range(1, j + 1):
            f = 4.0**m
            new.append((f * new[m - 1] - row[m - 1]) / (f - 1.0))
        row = new
    return row[-1]


def numeric_jacobian(f, x, group_in="vec", group_out="vec", eps=1e-3, *, side="right",
                     method="richardson", levels=3):
    """Jacobian ``d (f(x (+) d) (-) f(x)) / d d`` at ``d = 0`` by central differences.

    Parameters
    ----------
    f : callable
        One value in, one value out (``(n,)`` vector, ``(3, 3)`` rotation or ``(4, 4)`` pose).
    x : array_like
        Where to differentiate.
    group_in, group_out : {"vec", "so3", "se3"}
        How the input is perturbed and how outputs are subtracted (module notes).
    eps : float
        Outer finite-difference step ``h``.
    side : {"right", "left"}
        Manifold perturbation and difference side (both in and out; vectors ignore it).
    method, levels
        See :func:`derivative_at_zero`.

    Returns
    -------
    ndarray (dim_out, dim_in)
    """
    _check_group(group_in)
    _check_group(group_out)
    x = np.asarray(x, dtype=np.float64)
    y0 = np.asarray(f(x), dtype=np.float64)
    n_in = GROUP_DIMS[group_in] or x.size
    n_out = GROUP_DIMS[group_out] or y0.size
    J = np.empty((n_out, n_in))
    for i in range(n_in):
        e = np.zeros(n_in)
        e[i] = 1.0

        def g(s, e=e):
            if group_in == "vec":
                xs = x + s * e.reshape(x.shape)
            else:
                xs = oplus(group_in, x, s * e, side)
            return np.ravel(ominus(group_out, np.asarray(f(xs), dtype=np.float64), y0, side))

        step = None
        if group_in == "vec":
            xi = x.ravel()[i]

            def step(s, xi=xi):
                return (xi + s) - xi

        J[:, i] = derivative_at_zero(g, eps, method, levels, step)
    return J


def time_derivative(f, t, h=1e-3, *, group="vec", method="richardson", levels=3):
    """Derivative of a function of time at every ``t``, by central differences.

    Parameters
    ----------
    f : callable
        Vectorized: ``f(t_array (N,))`` returns ``(N, ...)`` values (vectors, or ``(N, 3, 3)``
        rotations / ``(N, 4, 4)`` poses for ``group="so3"`` / ``"se3"``).
    t : array_like (N,)
        Times.
    h : float
        Outer step in the units of ``t`` (module notes: ``1e-2`` times the time scale of the
        motion with the default Richardson ``levels=3``; stay clear of spline knots).
        The rounding of ``t + s`` is accounted for (the actual step ``(t + s) - t`` is used).
    group : {"vec", "so3", "se3"}
        ``"vec"``: ``df/dt``, shape of ``f(t)``. ``"so3"``: the *body* angular velocity
        ``vee(R^T dR/dt)`` (N, 3). ``"se3"``: the body twist ``vee(T^-1 dT/dt)`` =
        ``[R^T dp/dt, omega_body]`` (N, 6). Both are ``d/ds Log(f(t)^-1 f(t + s))`` at 0.
    method, levels
        See :func:`derivative_at_zero`.

    Returns
    -------
    ndarray
    """
    _check_group(group)
    t = np.asarray(t, dtype=np.float64)
    y0 = np.asarray(f(t), dtype=np.float64)
    if group == "vec":
        def g(s):
            return np.asarray(f(t + s), dtype=np.float64) - y0
    else:
        def g(s):
            return ominus(group, np.asarray(f(t + s), dtype=np.float64), y0)
    return derivative_at_zero(g, h, method, levels, step=lambda s: (t + s) - t)


def _fmt(a):
    return np.array2string(np.asarray(a), precision=17, max_line_width=160, floatmode="maxprec")


def assert_jacobian_close(analytic, numeric, rtol=1e-7, atol=0.0, label=""):
    """Assert ``max|A - N| <= atol + rtol * max|A|`` for each matrix (last two axes).

    On failure the message shows, for the worst matrix, the analytic Jacobian, the numeric
    one and their difference, with the achieved relative error.
    """
    A = np.asarray(analytic, dtype=np.float64)
    N = np.asarray(numeric, dtype=np.float64)
    if A.shape != N.shape:
        raise AssertionError(f"{label}: shape mismatch, analytic {A.shape} vs numeric {N.shape}")
    if A.ndim < 2:
        A = A.reshape(1, -1)
        N = N.reshape(1, -1)
    A3 = A.reshape((-1,) + A.shape[-2:])
    N3 = N.reshape((-1,) + N.shape[-2:])
    err = np.max(np.abs(A3 - N3), axis=(1, 2))
    scale = np.max(np.abs(A3), axis=(1, 2))
    allowed = atol + rtol * scale
    bad = ~(err <= allowed)
    if np.any(bad):
        k = int(np.argmax(np.where(bad, err / np.maximum(allowed, 1e-300), -np.inf)))
        rel = err[k] / scale[k] if scale[k] > 0 else np.inf
        raise AssertionError(
            f"{label}: Jacobian mismatch (matrix {k} of {len(A3)}): max|A - N| = {err[k]:.3e}, "
            f"relative {rel:.3e}, allowed {allowed[k]:.3e} (rtol={rtol:g}, atol={atol:g})\n"
            f"analytic:\n{_fmt(A3[k])}\nnumeric:\n{_fmt(N3[k])}\n"
            f"analytic - numeric:\n{_fmt(A3[k] - N3[k])}"
        )


def assert_derivative_close(analytic, numeric, rtol=1e-7, atol=0.0, label="", t=None):
    """Assert ``max|a - n| <= atol + rtol * max|a|`` for every sample (rows over the first axis;
    the rest of each row is one vector or matrix).

    On failure the message shows the worst samples (time, analytic, numeric, difference).
    """
    A = np.asarray(analytic, dtype=np.float64)
    N = np.asarray(numeric, dtype=np.float64)
    if A.shape != N.shape:
        raise AssertionError(f"{label}: shape mismatch, analytic {A.shape} vs numeric {N.shape}")
    A2 = A.reshape(A.shape[0], -1) if A.ndim > 1 else A.reshape(-1, 1)
    N2 = N.reshape(A2.shape)
    err = np.max(np.abs(A2 - N2), axis=1)
    scale = np.max(np.abs(A2), axis=1)
    allowed = atol + rtol * scale
    bad = ~(err <= allowed)
    if np.any(bad):
        order = np.argsort(-np.where(bad, err / np.maximum(allowed, 1e-300), -np.inf))
        lines = [
            f"{label}: derivative mismatch at {int(bad.sum())} of {len(A2)} samples "
            f"(rtol={rtol:g}, atol={atol:g}); worst:"
        ]
        for k in order[: min(3, int(bad.sum()))]:
            tk = "" if t is None else f" t={np.asarray(t).ravel()[k]!r}"
            rel = err[k] / scale[k] if scale[k] > 0 else np.inf
            lines.append(
                f"  sample {k}{tk}: max|a - n| = {err[k]:.3e}, relative {rel:.3e}\n"
                f"    analytic: {_fmt(A2[k])}\n    numeric:  {_fmt(N2[k])}\n"
                f"    diff:     {_fmt(A2[k] - N2[k])}"
            )
        raise AssertionError("\n".join(lines))


def decimal_sin_cos(t):
    """sin and cos of a Decimal by their series (exact to the context precision for |t| < 4)."""
    s, term, k = Decimal(0), t, 1
    while abs(term) > Decimal(10) ** -45:
        s += term
        term = -term * t * t / ((k + 1) * (k + 2))
        k += 2
    c, term, k = Decimal(0), Decimal(1), 0
    while abs(term) > Decimal(10) ** -45:
        c += term
        term = -term * t * t / ((k + 1) * (k + 2))
        k += 2
    return s, c
