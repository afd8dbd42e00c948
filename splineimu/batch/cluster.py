"""Dask plumbing for batches: a local cluster or an existing scheduler, tasks, progress.

A batch maps a picklable function over run indices on Dask workers. By default a
:class:`distributed.LocalCluster` with ``workers`` processes of one thread each (numba kernels
and BLAS then do not compete for cores); with ``scheduler="tcp://host:port"`` an existing
cluster (``dask scheduler`` + ``dask worker``, dask-jobqueue on SLURM/PBS, Kubernetes) runs
the same tasks. Tasks are retried on another worker when the one running them dies.
"""

from __future__ import annotations

import os
import time
from contextlib import contextmanager

#: Seconds to wait for a scheduler before giving up.
CONNECT_TIMEOUT_S = 10.0


def default_workers() -> int:
    """One worker per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None):
    """A :class:`distributed.Client` on a new local cluster or on ``scheduler``; closed on exit.

    Raises
    ------
    ConfigError
        The scheduler cannot be reached within :data:`CONNECT_TIMEOUT_S` seconds, or Dask
        (``distributed``) is not installed.
    """
    from ..errors import ConfigError

    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - a dependency of the package
        raise ConfigError("batches need Dask: pip install 'dask[distributed]'") from None
    cluster = None
    with dask.config.set({"distributed.worker.daemon": False, "distributed.admin.tick.limit": "10s",
                          "distributed.comm.timeouts.connect": f"{CONNECT_TIMEOUT_S:g}s",
                          "distributed.logging.distributed": "error"}):
        if scheduler:
            try:
                client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
            except (OSError, TimeoutError) as exc:
                raise ConfigError(f"cannot reach the Dask scheduler at {scheduler} within {CONNECT_TIMEOUT_S:g} s "
                                  f"({type(exc).__name__}); start one with `dask scheduler` or drop --scheduler "
                                  "to use a local cluster", option="--scheduler") from None
        else:
            n = default_workers() if workers is None else int(workers)
            if n < 1:
                raise ConfigError(f"--workers must be at least 1, got {n}", option="--workers")
            env = {"OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
                   "NUMBA_NUM_THREADS": "1"}
            os.environ.update({k: os.environ.get(k, v) for k, v in env.items()})
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                                   silence_logs=40)
            client = Client(cluster)
        try:
            yield client
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


def map_runs(client, fn, indices, *args, progress: bool = True, on_result=None):
    """Run ``fn(k, *args)`` for every ``k`` of ``indices`` on the cluster; results as they complete.

    ``args`` are scattered once (broadcast to every worker) so large objects such as a fitted
    spline travel once per worker, not once per run. ``on_result(result)`` is called in the
    order of completion. ``fn`` should return a mapping with ``run`` and ``status``; a task lost
    with its workers more often than its retries allow is reported as such a mapping with status
    ``failed``. Returns the results and the steady-state time per run: once every worker has
    completed its first run (which pays imports, compilation or cache loading), the wall time
    to the last completion divided by the runs completed in between (None when too few runs).
    """
    import uuid

    from distributed import as_completed

    shared = [a if a is None else client.scatter(a, broadcast=True) for a in args]
    token = uuid.uuid4().hex[:12]  # batches sharing a scheduler must not share task keys
    futures = {client.submit(fn, k, *shared, key=f"splineimu-run-{token}-{k}", pure=False, retries=2): k
               for k in indices}
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(futures), unit=" runs", desc="batch", leave=False)
    results, stamps = [], []
    try:
        for fut in as_completed(list(futures)):
            try:
                res = fut.result()
            except Exception as exc:  # the task died with its worker (more often than its retries allow)
                res = {"run": futures[fut], "status": "failed", "error": f"{type(exc).__name__}: {exc}"}
            stamps.append(time.perf_counter())
            results.append(res)
            if on_result is not None:
                on_result(res)
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    first = min(max(len(client.nthreads()), 1), len(stamps)) - 1  # every worker past its first run
    steady = (stamps[-1] - stamps[first]) / (len(stamps) - 1 - first) if len(stamps) - first > 2 else None
    return results, steady


__all__ = ["dask_client", "map_runs", "default_workers", "CONNECT_TIMEOUT_S"]
