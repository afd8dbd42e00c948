"""Numba kernel of the rolling-shutter row search (private; no validation, outputs last).

:func:`rs_brackets` is the compiled form of the numpy code in
:func:`splineimu.camera.observations._rs_brackets_numpy` (the reference, also used when
numba's jit is disabled): for every frame ``f``, landmark ``m`` and pair of consecutive row
samples ``(s, s + 1)`` it tests whether the row residual ``proj_v(p) - row`` changes sign
with positive depth at one end at least, and lists those brackets.
"""

from __future__ import annotations

import math

from .._jit import jit

#: distortion model codes of the kernels
MODEL_NONE, MODEL_RADTAN, MODEL_EQUIDISTANT = 0, 1, 2
#: below this radius the fisheye distortion factor is 1 (OpenCV, Kalibr)
SMALL_RADIUS = 1e-8


@jit(inline="always")
def _row_extended(X, Y, Z, model, k):
    """``v`` of a camera-frame point, continuous through ``Z = 0`` for the fisheye; for
    pinhole and radtan ``copysign(inf, Y)`` when ``Z <= 0`` (as ``Camera._project_xyz``)."""
    fv, pv = k[1], k[3]
    if model == MODEL_EQUIDISTANT:
        rho = math.hypot(X, Y)
        if Z > 0.0 and rho < SMALL_RADIUS * Z:
            return fv * (Y / Z) + pv
        if rho == 0.0:
            return pv
        th = math.atan2(rho, Z)
        t2 = th * th
        thd = th * (1.0 + t2 * (k[4] + t2 * (k[5] + t2 * (k[6] + t2 * k[7]))))
        return fv * (Y * (thd / rho)) + pv
    if not Z > 0.0:
        return math.copysign(math.inf, Y)
    x = X / Z
    y = Y / Z
    if model == MODEL_RADTAN:
        r2 = x * x + y * y
        radial = 1.0 + r2 * (k[4] + r2 * k[5])
        yd = y * radial + k[6] * (r2 + 2.0 * y * y) + k[7] * (2.0 * x * y)
        return fv * yd + pv
    return fv * y + pv


@jit(nogil=True)
def rs_brackets(R, t, points, rows, model, k, out_f, out_s, out_m, out_lo, out_hi):
    """Fill the bracket lists; return how many brackets there are (may exceed the capacity).

    R : (F, S, 3, 3) cam_R_world at the row samples; t : (F, S, 3) cam_t_world;
    points : (M, 3) world; rows : (S,); k : [fu, fv, pu, pv, c0, c1, c2, c3].
    Outputs (capacity C): frame, sample, landmark indices and residuals at both ends.
    """
    nf, ns = R.shape[0], R.shape[1]
    nm = points.shape[0]
    cap = out_f.shape[0]
    count = 0
    for f in range(nf):
        for m in range(nm):
            px, py, pz = points[m, 0], points[m, 1], points[m, 2]
            prev_res = 0.0
            prev_front = False
            for s in range(ns):
                X = R[f, s, 0, 0] * px + R[f, s, 0, 1] * py + R[f, s, 0, 2] * pz + t[f, s, 0]
                Y = R[f, s, 1, 0] * px + R[f, s, 1, 1] * py + R[f, s, 1, 2] * pz + t[f, s, 1]
                Z = R[f, s, 2, 0] * px + R[f, s, 2, 1] * py + R[f, s, 2, 2] * pz + t[f, s, 2]
                res = _row_extended(X, Y, Z, model, k) - rows[s]
                front = Z > 0.0
                change = (prev_res >= 0.0 and res < 0.0) or (prev_res < 0.0 and res >= 0.0)
                if s > 0 and change and (front or prev_front):
                    if count < cap:
                        out_f[count] = f
                        out_s[count] = s - 1
                        out_m[count] = m
                        out_lo[count] = prev_res
                        out_hi[count] = res
                    count += 1
                prev_res = res
                prev_front = front
    return count
