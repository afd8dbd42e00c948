"""The library API of synthesis: options objects and one function per job.

Build a :class:`SynthesisJob` (in Python, from command-line flags, or from a scene file with
:func:`load_scene_file`; all three give the same object) and run it::

    from splineimu.api import ImuOptions, OutputOptions, PosesInput, SynthesisJob, run_job

    job = SynthesisJob(PosesInput("poses.tum"), ImuOptions(rate_hz=400, model="adis16448", seed=1),
                       OutputOptions("out"))
    result = run_job(job)            # writes out/, returns the report and the fit report
    arrays = synthesize_to_memory(job).synthesis   # or keep the data in memory

The jobs that read or write files are here too: :func:`analyze_recording` (``splineimu allan``),
:func:`calibrate_file`, :func:`dead_reckon`, :func:`evaluate_recording`, :func:`compare_files`,
with their result objects, and :func:`stamp_clock` (the IMU clock a recording was stamped on).

Names are imported lazily (``import splineimu.api`` does not import numpy).
"""

from __future__ import annotations

import importlib

_NAMES = {
    "options": ("ImuOptions", "SplineOptions", "PosesInput", "SceneInput", "OutputOptions", "SynthesisJob"),
    "synthesis": ("SynthesisResult", "PreparedMotion", "prepare_motion", "run_job", "synthesize_poses",
                  "synthesize_scene", "synthesize_to_memory"),
    "scenefile": ("load_scene_file", "SceneFile"),
    "batch": ("run_batch", "BatchResult"),
    "calibration": ("calibrate_file", "CalibrationRun"),
    "integrate": ("dead_reckon", "DeadReckoning"),
    "preintegration": ("evaluate_recording", "RecordingWindows"),
    "clock": ("stamp_clock", "StampClock"),
    "compare": ("compare_files", "plot_compare"),
    "allan": ("analyze_recording", "AllanAnalysis", "allan_output_paths", "write_allan_outputs", "plot_allan"),
}
_WHERE = {name: mod for mod, names in _NAMES.items() for name in names}


def __getattr__(name):
    mod = _WHERE.get(name)
    if mod is None:
        raise AttributeError(f"module 'splineimu.api' has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{mod}"), name)


def __dir__():
    return sorted(list(globals()) + list(_WHERE))


__all__ = sorted(_WHERE)
