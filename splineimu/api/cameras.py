"""Cameras of a synthesis job: their checks when the job is built, their observations when it runs.

Imported only by a job that names cameras (IMU-only runs never load :mod:`splineimu.camera`).

Randomness comes from the run's seed through child streams that no IMU stream uses: the
random landmarks from ``SeedSequence(seed, spawn_key=LANDMARK_SEED_KEY)``, the pixel noise of
camera ``name`` from ``SeedSequence(seed)``'s child ``(0x43414D, crc32(name))``
(:func:`splineimu.camera.camera_rngs`). The IMU noise processes use the one-element keys
``(0,) .. (7,)``, timing and vibration ``(1001,)`` and ``(1002,)``: adding cameras does not
change one IMU byte.

Examples
--------
>>> from splineimu.api import SceneInput, SynthesisJob, synthesize_to_memory
>>> cams = {"cam0": {"intrinsics": [300, 300, 320, 240], "resolution": [640, 480], "rate_hz": 10,
...                  "T_cam_imu": [[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0], [0, 0, 0, 1]]}}
>>> job = SynthesisJob(SceneInput("ellipse", duration_s=1), cameras=cams,
...                    landmarks={"random": {"count": 300}})
>>> res = synthesize_to_memory(job)
>>> res.report["cameras"]["cam0"]["frames"], res.report["landmarks"]["count"]
(11, 300)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ConfigError

__all__ = ["check_cameras", "observe_job", "write_job_cameras", "camera_line", "LANDMARK_SEED_KEY"]

#: spawn key of the random landmarks' stream (the IMU's streams use others; see the module notes)
LANDMARK_SEED_KEY = (1003,)


def _doc(job):
    return getattr(job.origin, "doc", None)


def _base_dir(job, fld):
    where = job.origin.where(fld) if job.origin is not None else None
    if isinstance(where, tuple) and where[0]:
        return Path(where[0]).parent
    return None


def _located(job, exc, fld, nested=()):
    """``exc`` at the file and line of the key it names (inside ``fld``'s value), for scene files."""
    doc = _doc(job)
    if doc is None or exc.path is not None:
        return exc
    path = job.origin.keys.get(fld, (fld,))
    line = doc.line(*path)
    named = tuple(str(exc.option or "").split("."))
    if named[:len(path)] == path and len(named) > len(path) and doc.line(*named) is not None:
        return ConfigError(exc.problem, path=doc.name, line=doc.line(*named), option=exc.option)
    for keys in nested:
        if f"`{keys[-1]}`" in exc.problem and doc.line(*path, *keys) is not None:
            line = doc.line(*path, *keys)
            break
    return ConfigError(exc.problem, path=doc.name, line=line, option=exc.option or ".".join(path))


def check_cameras(job):
    """Check and convert ``job.cameras`` and ``job.landmarks`` in place (at the job's construction).

    ``cameras`` becomes a dict name -> :class:`~splineimu.camera.Camera`; ``landmarks`` a
    :class:`~splineimu.camera.Landmarks` (a file, read now) or stays a ``{random: ...}``
    mapping whose keys are checked now and which is drawn when the job runs (its default
    geometry depends on the motion).
    """
    from ..camera import Camera, Landmarks, cameras_from_config

    if job.cameras is None:
        raise _located(job, ConfigError("`landmarks` need `cameras` to observe them", option="landmarks"),
                       "landmarks")
    cams = job.cameras
    if isinstance(cams, Camera):
        cams = [cams]
    if isinstance(cams, (list, tuple)) and all(isinstance(c, Camera) for c in cams):
        cams = {c.name: c for c in cams}
    if not (isinstance(cams, dict) and cams and all(isinstance(c, Camera) for c in cams.values())):
        keys = job.origin.keys.get("cameras", ("cameras",)) if _doc(job) is not None else ("cameras",)
        try:
            cams = cameras_from_config(cams, base_dir=_base_dir(job, "cameras"), doc=_doc(job), keys=keys)
        except ConfigError as exc:
            raise _located(job, exc, "cameras") from None
    if any(name != c.name for name, c in cams.items()):
        raise _located(job, ConfigError("`cameras`: each camera's key must be its name", option="cameras"),
                       "cameras")
    job.cameras = cams
    lm = job.landmarks
    if lm is None:
        raise _located(job, ConfigError("`cameras` need `landmarks`: {file: points.csv} or "
                                        "{random: {count: N}}", option="cameras"), "cameras")
    if isinstance(lm, Landmarks):
        return
    if isinstance(lm, dict) and isinstance(lm.get("random"), dict):
        _check_random(job, lm["random"])
        return
    job.landmarks = _landmarks(job, None, None)


def _check_random(job, spec):
    """The keys and count of ``{random: ...}``; the geometry is checked when it is drawn."""
    from ..camera import landmarks_from_config
    from ..validation import int_in_range

    if "count" in spec:
        try:
            int_in_range(spec["count"], "landmarks.random.count", 0, 10**9)
        except (ConfigError, ValueError) as exc:
            raise _located(job, ConfigError(str(getattr(exc, "problem", exc)), option="landmarks.random.count"),
                           "landmarks", [("random", "count")]) from None
    try:
        landmarks_from_config({"random": {**spec, "count": 0}}, source=None, rng=0)
    except ConfigError as exc:
        if "motion source" in exc.problem:  # its default geometry comes from the motion
            return
        raise _located(job, exc, "landmarks", [("random", k) for k in spec]) from None


def _landmarks(job, source, seed):
    from ..camera import landmarks_from_config

    value = job.landmarks
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=LANDMARK_SEED_KEY))
    spec = value.get("random") if isinstance(value, dict) else None
    nested = [("random", k) for k in spec] if isinstance(spec, dict) else [("file",)]
    try:
        return landmarks_from_config(value, source=source, rng=rng, base_dir=_base_dir(job, "landmarks"))
    except ConfigError as exc:
        raise _located(job, exc, "landmarks", nested) from None


def _landmarks_source(job) -> str:
    from ..camera import Landmarks

    value = job.landmarks
    if isinstance(value, Landmarks):
        return "given"
    if isinstance(value, dict) and "random" in value:
        spec = value["random"]
        return f"random {spec.get('shape', 'shell')} (seeded from the run's seed)"
    return str(value.get("file")) if isinstance(value, dict) else "file"


def observe_job(job, source, seed):
    """Landmarks and observations of the job's cameras on ``source``; their report sections.

    Returns
    -------
    landmarks : Landmarks
    observations : dict
        Camera name -> :class:`~splineimu.camera.Observations`.
    report : dict
        ``cameras`` (per camera: frames, observations, rate, shutter, time shift, noise,
        file) and ``landmarks`` (count, source, file).
    """
    from ..camera import Landmarks, observe

    lm = job.landmarks if isinstance(job.landmarks, Landmarks) else _landmarks(job, source, seed)
    ext = job.imu.body_T_sensor
    obs = observe(source, list(job.cameras.values()), lm, rng=np.random.SeedSequence(seed),
                  body_T_imu=None if ext is None else ext.matrix)
    cams = {}
    for name, o in obs.items():
        c = o.camera
        cams[name] = {
            "frames": int(o.frame_t_ns.size), "observations": len(o), "rate_hz": float(c.rate_hz),
            "shutter": "global" if c.is_global_shutter else "rolling",
            "line_delay_s": float(c.line_delay_s), "timeshift_cam_imu_s": float(c.timeshift_cam_imu_s),
            "pixel_noise_px": float(c.pixel_noise_px), "model": f"pinhole-{c.distortion_model}",
            "first_ns": int(o.frame_t_ns[0]) if o.frame_t_ns.size else None,
            "last_ns": int(o.frame_t_ns[-1]) if o.frame_t_ns.size else None,
            "features": f"mav0/{name}/features.csv",
        }
    report = {"cameras": cams, "landmarks": {"count": len(lm), "source": _landmarks_source(job),
                                             "file": "landmarks.csv"}}
    return lm, obs, report


def write_job_cameras(tmp, landmarks, observations, plot=False) -> list:
    """Write the camera files into the output folder ``tmp``; with ``plot`` one frame per camera.

    Returns the names of the plots written (``<cam>_frame.png``).
    """
    from ..camera import plot_frame
    from ..io.camera import write_camera_outputs

    cams = [o.camera for o in observations.values()]
    write_camera_outputs(tmp, cams, observations, landmarks)
    plots = []
    if plot:
        for name, o in observations.items():
            if len(o):
                fig = plot_frame(o)
                fig.savefig(Path(tmp) / f"{name}_frame.png", dpi=100)
                plots.append(f"{name}_frame.png")
    return plots


def camera_line(report) -> str:
    """One summary line on the cameras of a run."""
    parts = [f"{name}: {c['frames']} frames, {c['observations']} observations ({c['shutter']} shutter, "
             f"{c['rate_hz']:g} Hz)" for name, c in report["cameras"].items()]
    return f"cameras       {'; '.join(parts)}; {report['landmarks']['count']} landmarks"

