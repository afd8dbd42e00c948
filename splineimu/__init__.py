"""splineimu: realistic IMU data from recorded or designed trajectories.

Main entry points
-----------------
- :class:`splineimu.Spline`: cumulative uniform B-splines on SE3 or R3 x SO3 with exact
  derivatives (body rate, angular acceleration, velocity, acceleration, specific force).
- :func:`splineimu.fit`: least-squares spline fit to timestamped poses.
- :mod:`splineimu.lie`: SO3 / SE3 maps and Jacobians.
- :func:`splineimu.run_job` with a :class:`splineimu.SynthesisJob` (or
  :func:`splineimu.load_scene_file`): IMU data, ground truth and report from a pose file or a
  scene, as the command line makes them (:mod:`splineimu.api`).
"""

from __future__ import annotations

__version__ = "0.1.0"

from .errors import ConfigError, InputError, RangeError, SplineImuError  # noqa: E402

#: Public names imported on first use: name -> module.
_LAZY = {
    "Kinematics": "motion", "MotionSource": "motion", "Spline": "spline", "fit": "spline.fit",
    **{name: "api" for name in ("SynthesisJob", "ImuOptions", "SplineOptions", "PosesInput", "SceneInput",
                                "OutputOptions", "SynthesisResult", "run_job", "synthesize_poses",
                                "synthesize_scene", "synthesize_to_memory", "load_scene_file")},
}


def __getattr__(name):
    # Lazy so that `splineimu --help` does not compile or load kernels (nor import numpy).
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module 'splineimu' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f"{__name__}.{mod}"), name)


__all__ = [
    "Spline", "fit", "Kinematics", "MotionSource", *sorted(k for k, v in _LAZY.items() if v == "api"),
    "SplineImuError", "InputError", "ConfigError", "RangeError", "__version__",
]
