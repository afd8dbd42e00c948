"""Float products and angles without their rounding, where it would show: the parameter of a
spline over an hour of poses (:func:`splineimu.spline.banded.segments`) and the angles of the
analytic scenes (``w t`` at t = 3600 s rounds by 2e-13 rad, which put 1e-12 m of noise on the
ellipse's exact positions and 20x the error of one minute on the accelerometer fitted to them).

>>> p, e = two_product(0.1, 3.0)
>>> (p, e) == (0.30000000000000004, -2.7755575615628914e-17)
True
>>> bool(abs(turn(np.pi / 10.0, np.array([3600.0]))[0]) < 1e-13)  # 180 laps of 20 s
True
>>> bool(abs(np.remainder(np.pi / 10.0 * 3600.0 + np.pi, 2 * np.pi) - np.pi) < 1e-13)
False
"""

from __future__ import annotations

import numpy as np

#: 2 pi as a short float (201/32: its multiples by integers below 2^44 are exact) and the rest.
_TWO_PI_HI = 6.28125
_TWO_PI_LO = 0.0019353071795864769252867665590057683943


def two_product(a, b):
    """``(p, e)`` with ``p + e = a b`` exactly (Dekker's product; |a b| well inside the float
    range), elementwise."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    p = a * b
    c = 134217729.0  # 2^27 + 1
    ah = c * a - (c * a - a)
    bh = c * b - (c * b - b)
    al, bl = a - ah, b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def turn(rate, t, phase=0.0):
    """``rate t + phase`` reduced to about [-pi, pi] (``phase`` up to a few radians), to ~1e-15 rad
    for |rate t| up to 1e13: the product is carried as two floats and 2 pi as two."""
    p, e = two_product(rate, t)
    n = np.round(p / (_TWO_PI_HI + _TWO_PI_LO))
    return ((p - n * _TWO_PI_HI) - n * _TWO_PI_LO) + (e + phase)
