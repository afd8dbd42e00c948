"""Start-up of the commands that run a synthesis job: their imports with the garbage collector paused."""

from __future__ import annotations

import contextlib
import gc
import importlib

#: What a pose-file command (from-tum, from-euroc) runs, imported by :func:`start_up`.
POSE_JOB_MODULES = ("splineimu.api.synthesis", "splineimu.io.poses", "splineimu.spline.fit", "splineimu.pipeline")


@contextlib.contextmanager
def start_up(*modules):
    """Build a command's job and import ``modules`` with Python's cyclic garbage collector paused.

    numpy, numba and splineimu leave some 10^5 long-lived objects behind on import, and the
    collector's passes over them while they are made (0.03-0.035 s of CPU in a ``from-tum``
    run, measured) free nothing. They are moved to the permanent generation afterwards
    (``gc.freeze``): later collections traverse only what the job itself allocates.
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
        for name in modules:
            importlib.import_module(name)
    finally:
        gc.freeze()
        if enabled:
            gc.enable()
