"""A scene's poses on a uniform grid, written as a TUM trajectory (through :func:`splineimu.io.tum.write_tum`)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["write_scene_tum"]


def write_scene_tum(scene, path, rate_hz: float) -> Path:
    """Write a scene's poses at a uniform rate as a TUM trajectory file, atomically.

    Parameters
    ----------
    scene : Scene
        Any motion source with ``origin_ns``, ``t_min_s``, ``t_max_s`` and ``pose``.
    path : str or os.PathLike
        Output file; replaced if it exists (written to a temporary file in the same
        directory, then ``os.replace``); missing parent folders are made.
    rate_hz : float
        Sample rate [Hz]. Stamps are ``origin_ns + round(t_min_s 1e9) + round(k 1e9 / rate_hz)``
        (:func:`splineimu.timegrid.uniform_stamps_ns`, the grid of :meth:`Scene.sample_times_ns`).

    Returns
    -------
    pathlib.Path
        The written path.

    Notes
    -----
    Lines are ``timestamp tx ty tz qx qy qz qw`` with the absolute timestamp printed
    exactly from integer nanoseconds as ``"%d.%09d"`` (seconds.nanoseconds) and
    quaternions made sign-continuous along time.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from splineimu.scenes import make_scene
    >>> p = write_scene_tum(make_scene("static", duration_s=1.0), pathlib.Path(tempfile.mkdtemp()) / "s.tum", 2)
    >>> print(p.read_text(), end="")
    # timestamp tx ty tz qx qy qz qw
    0.000000000 0 0 0 0 0 0 1
    0.500000000 0 0 0 0 0 0 1
    1.000000000 0 0 0 0 0 0 1
    """
    import numpy as np

    from ..io.tum import write_tum
    from ..lie import quat_make_continuous
    from ..timegrid import uniform_stamps_ns

    origin = int(scene.origin_ns)
    t_ns = uniform_stamps_ns(origin + int(round(scene.t_min_s * 1e9)), origin + int(round(scene.t_max_s * 1e9)),
                             rate_hz)
    t_s = np.clip(scene.t_s_from_ns(t_ns), scene.t_min_s, scene.t_max_s)
    pos, quat = scene.pose(t_s)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_tum(path, t_ns, pos, quat_make_continuous(quat))
