"""Cumulative uniform B-splines on SE3 and R3 x SO3, their fitting and knot-spacing choice."""

from .core import KINDS, Spline

__all__ = ["Spline", "KINDS"]
