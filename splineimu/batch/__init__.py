"""Monte-Carlo batches: seeded variants of one scene on a Dask cluster.

:func:`run_batch` (in :mod:`splineimu.batch.runner`) runs them; :mod:`splineimu.batch.vary`
reads the ``vary:`` block and draws each run's values; :mod:`splineimu.batch.cluster` holds
the Dask plumbing. Names are imported lazily (``import splineimu.batch`` imports no Dask).
"""

from __future__ import annotations

_NAMES = ("run_batch", "BatchResult")


def __getattr__(name):
    if name in _NAMES:
        from . import runner

        return getattr(runner, name)
    raise AttributeError(f"module 'splineimu.batch' has no attribute {name!r}")


__all__ = list(_NAMES)
