"""splineimu: realistic IMU data from recorded or designed trajectories.

Main entry points
-----------------
- :class:`splineimu.Spline`: cumulative uniform B-splines on SE3 or R3 x SO3 with exact
  derivatives (body rate, angular acceleration, velocity, acceleration, specific force).
- :func:`splineimu.fit`: least-squares spline fit to timestamped poses.
- :mod:`splineimu.lie`: SO3 / SE3 maps and Jacobians.
"""

from __future__ import annotations

__version__ = "0.1.0"

from .errors import ConfigError, InputError, RangeError, SplineImuError  # noqa: E402


def __getattr__(name):
    # Lazy so that `splineimu --help` does not compile or load kernels (nor import numpy).
    if name in ("Kinematics", "MotionSource"):
        from . import motion

        return getattr(motion, name)
    if name == "Spline":
        from .spline import Spline

        return Spline
    if name == "fit":
        from .spline.fit import fit

        return fit
    raise AttributeError(f"module 'splineimu' has no attribute {name!r}")


__all__ = [
    "Spline", "fit", "Kinematics", "MotionSource",
    "SplineImuError", "InputError", "ConfigError", "RangeError", "__version__",
]
