"""Dask plumbing for batches: a local cluster or an existing scheduler, tasks, progress.

A batch maps a picklable function over run indices on Dask workers, a few runs per task. By
default a :class:`distributed.LocalCluster` with ``workers`` processes of one thread each (numba
kernels, BLAS and the text formatting of :mod:`splineimu.io.tables` run in that thread, so a
worker uses one core) and Dask's periodic housekeeping made rarer (:data:`QUIET_CONFIG`); with
``scheduler="tcp://host:port"`` an existing cluster (``dask scheduler`` + ``dask worker``,
dask-jobqueue on SLURM/PBS, Kubernetes) runs the same tasks with its own settings. Tasks are
retried on another worker when the one running them dies.
"""

from __future__ import annotations

import os
import time
from contextlib import contextmanager

#: Seconds to wait for a scheduler before giving up.
CONNECT_TIMEOUT_S = 10.0
#: Runs per Dask task at most (see :func:`chunk_size`).
MAX_CHUNK = 8
#: Dask's housekeeping made rarer on the local cluster: with one worker per core, whatever the
#: scheduler, the nannies and the workers' event loops spend is taken from the runs. Measured
#: idle: about 30 ms of CPU per second in the client process and as much in each worker.
QUIET_CONFIG = {
    "distributed.worker.profile.enabled": False,  # 100 stack samples/s of the running task
    "distributed.admin.tick.interval": "1s",  # event-loop health check, default every 20 ms
    "distributed.admin.tick.limit": "10s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.scheduler.work-stealing": False,  # equal tasks, queued on the scheduler anyway
}


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
    with dask.config.set({"distributed.worker.daemon": False, "distributed.comm.timeouts.connect":
                          f"{CONNECT_TIMEOUT_S:g}s", "distributed.logging.distributed": "error", **QUIET_CONFIG}):
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
                                   silence_logs=40, env={"SPLINEIMU_FORMAT_THREADS": "0"})
            client = Client(cluster)
        try:
            yield client
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


def chunk_sizes(n_runs: int, n_workers: int) -> list[int]:
    """Runs per task, in order: a quarter of each worker's share of the runs still to hand out,
    at most :data:`MAX_CHUNK` (a task's result and a retry stay small), down to one run per task
    at the end, so that the workers finish together (guided self-scheduling).

    Examples
    --------
    >>> chunk_sizes(1000, 2)[:3], len(chunk_sizes(1000, 2)), chunk_sizes(1000, 2)[-8:]
    ([8, 8, 8], 144, [1, 1, 1, 1, 1, 1, 1, 1])
    >>> chunk_sizes(3, 2)
    [1, 1, 1]
    """
    sizes, left = [], int(n_runs)
    while left > 0:
        sizes.append(max(1, min(MAX_CHUNK, left // (4 * max(n_workers, 1)))))
        left -= sizes[-1]
    return sizes


def run_chunk(fn, ks, *args) -> list:
    """The task: ``fn(k, *args)`` for each ``k`` of ``ks``; each result gets the wall-clock time
    (``time.time()``) at which its run ended, ``t_end``, and the worker that ran it, ``worker``."""
    import socket

    me = f"{socket.gethostname()}:{os.getpid()}"
    out = []
    for k in ks:
        res = fn(k, *args)
        res["t_end"], res["worker"] = time.time(), me
        out.append(res)
    return out


def steady_time_per_run(ends) -> float | None:
    """Wall time per run once every worker has completed its first run (which pays imports,
    compilation or cache loading): from the last of the workers' first ends to the last end,
    divided by the runs ended in between; None when fewer than two.

    Parameters
    ----------
    ends : iterable of (worker, t_end)

    Examples
    --------
    >>> steady_time_per_run([("a", 0.0), ("a", 1.0), ("b", 2.0), ("a", 2.5), ("b", 3.0), ("a", 3.5)])
    0.5
    """
    first = {}
    for w, t in ends:
        first[w] = min(first.get(w, t), t)
    if not first:
        return None
    start = max(first.values())
    after = [t for _, t in ends if t > start]
    return (max(after) - start) / len(after) if len(after) >= 2 else None


def _value(x):
    """The task that holds a batch's shared arguments."""
    return x


def map_runs(client, fn, indices, *args, progress: bool = True, on_result=None, chunk: int | None = None):
    """Run ``fn(k, *args)`` for every ``k`` of ``indices`` on the cluster; results as they complete.

    Runs go to the workers in tasks of consecutive runs (``chunk`` runs each, default
    :func:`chunk_sizes`): the scheduler, the client and the workers' event loops then handle a
    task per several runs, not per run. ``args`` go to the cluster once, as the result of a task
    that returns them: large objects such as a fitted spline travel once per worker, not once
    per run, and if the worker holding the last copy dies the task makes it again (a scattered
    copy would be lost with it, and every run waiting for it cancelled: Dask's memory manager
    keeps one copy of data no task is reading at the moment). ``on_result(result)`` is called
    for every run, task by task in the order of completion. ``fn`` should return a mapping with
    ``run`` and ``status`` (it gets ``t_end`` and ``worker``); the runs of a task lost with its workers more
    often than its retries allow are reported as such mappings with status ``failed``.

    Returns the results and the steady-state time per run (:func:`steady_time_per_run`).
    """
    import uuid

    from distributed import as_completed

    indices = list(indices)
    n_workers = len(client.nthreads())
    sizes = [chunk] * -(-len(indices) // chunk) if chunk else chunk_sizes(len(indices), n_workers)
    token = uuid.uuid4().hex[:12]  # batches sharing a scheduler must not share task keys
    shared = [a if a is None else client.submit(_value, a, key=f"splineimu-args-{token}-{i}", pure=False)
              for i, a in enumerate(args)]
    futures, i = {}, 0
    for size in sizes:  # submitted in order: the scheduler hands them out first come, first served
        ks = indices[i:i + size]
        i += size
        fut = client.submit(run_chunk, fn, ks, *shared, key=f"splineimu-runs-{token}-{ks[0]}", pure=False,
                            retries=2)
        futures[fut] = ks
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(indices), unit=" runs", desc="batch", leave=False)
    results, ends = [], []
    try:
        for fut in as_completed(list(futures)):
            try:
                res = fut.result()
            except Exception as exc:  # the task died with its worker (more often than its retries allow)
                res = [{"run": k, "status": "failed", "error": f"{type(exc).__name__}: {exc}"} for k in futures[fut]]
            for r in res:
                if "t_end" in r:
                    ends.append((r.get("worker"), r["t_end"]))
                results.append(r)
                if on_result is not None:
                    on_result(r)
            if bar is not None:
                bar.update(len(res))
    finally:
        if bar is not None:
            bar.close()
    return results, steady_time_per_run(ends)


__all__ = ["dask_client", "map_runs", "chunk_sizes", "run_chunk", "steady_time_per_run", "default_workers",
           "CONNECT_TIMEOUT_S", "MAX_CHUNK", "QUIET_CONFIG"]
