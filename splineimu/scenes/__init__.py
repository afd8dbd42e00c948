"""Analytic reference scenes: closed-form trajectories with exact derivatives.

A scene is a :class:`~splineimu.motion.MotionSource` whose pose, body rate, angular
acceleration, velocity and acceleration are all written out in closed form (no finite
differences), so it is the reference that splines, IMU synthesis, integrators and
preintegration are checked against.

Time base: a scene starts at the integer nanosecond stamp ``origin_ns`` (``t0_ns``), and every
query time is float seconds since then, in ``[0, duration_s]``. Epoch stamps such as
``1_403_636_579_758_555_392`` lose nothing because the large origin is never converted to
float.

Modules
-------
- :mod:`~splineimu.scenes.base`: :class:`Param`, :class:`Scene` and the registry
  (:func:`register_scene`, :func:`scene_names`, :func:`make_scene`, :data:`SCENES`);
- :mod:`~splineimu.scenes.kinematics`: ZYX Euler-angle kinematics and other closed forms;
- :mod:`~splineimu.scenes.lecture`: ``ellipse`` (the lecture's scene, DESIGN.md section 4),
  ``static``, ``circle``;
- :mod:`~splineimu.scenes.tumbling`: ``screw`` (constant body twist), ``flips`` (aggressive
  hand-held-like tumbling);
- :mod:`~splineimu.scenes.calibration`: ``six-position`` and ``rate-table``;

Registry
--------
Scenes register themselves by name with :func:`register_scene`; any module can add one::

    from splineimu.scenes import Scene, Param, register_scene

    @register_scene("my-scene")
    class MyScene(Scene):
        '''Formulas, default duration, parameters with units.'''
        DEFAULT_DURATION_S = 10.0
        PARAMS = {"speed_m_s": Param(1.0, "m/s", "forward speed")}

        def _evaluate(self, t):
            ...  # return p, v, a, R, omega, alpha

Examples
--------
>>> sc = make_scene("ellipse")
>>> sc.sample_times_ns(200)[:3].tolist()
[0, 5000000, 10000000]
>>> {"ellipse", "six-position", "rate-table"} <= set(scene_names())
True
"""

from __future__ import annotations

from .base import EXTRA_SCENE_MODULES, SCENES, Param, Scene, make_scene, register_scene, scene_names
from .calibration import CalibrationScene, RateTableScene, SixPositionScene
from .kinematics import euler_zyx_kinematics
from .lecture import CircleScene, EllipseScene, StaticScene
from .tumbling import FlipsScene, ScrewScene

__all__ = [
    "SCENES", "EXTRA_SCENE_MODULES", "Param", "Scene", "register_scene", "scene_names",
    "make_scene", "euler_zyx_kinematics",
    "EllipseScene", "StaticScene", "CircleScene", "ScrewScene", "FlipsScene",
    "CalibrationScene", "SixPositionScene", "RateTableScene",
]
