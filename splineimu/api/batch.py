"""Monte-Carlo batches: ``runs`` seeded variants of one scene file, on a Dask cluster.

:func:`run_batch` reads the scene file (its ``vary:`` block checked before any work), makes the
motion once (a pose file is read and fitted in this process; the spline is shipped to every
worker once), and runs each run ``k`` on a worker: the job of
:meth:`splineimu.api.scenefile.SceneFile.job` written to ``OUT/runs/NNNNN`` (five digits), the
same bytes ``splineimu run SCENE.yaml --run-index k`` writes. Each run folder appears atomically
(temporary folder, then rename), so a killed batch leaves only complete runs and ``resume`` runs
only the missing ones. ``OUT/runs.csv`` lists every run: index, seed, the drawn values at full
precision (``repr``), status and error.

Durability is per batch, not per run: workers do not flush each file to the disk (an ``fsync``
waits for the disk, a few ms per file, and the waits of all workers queue on it); the batch
calls :func:`os.sync` once at its end, then writes ``runs.csv``. What a crash can lose:

- a killed batch (SIGKILL, Ctrl-C, a dead worker or client): nothing that was complete. The
  operating system still writes the page cache to the disk, so every run folder present is
  complete; ``resume`` runs the others.
- a power loss or an operating-system crash: also the runs finished in the last seconds (the
  kernel writes dirty pages back within about 30 s), whose folders may hold empty or cut files.
  ``resume`` trusts the runs that the last ``runs.csv`` lists as ``ok`` (it was written after
  the sync) and checks the other folders (every file non-empty, ``report.json`` readable): a
  folder that fails is run again. A run folder cut in the middle of a file, with every file
  non-empty, would go unnoticed; after a power loss, ``--force`` is the safe choice.

With ``scheduler`` on other machines the sync is the client machine's; a shared file system's
own guarantees apply to what the workers wrote.

Examples
--------
>>> run_name(7)
'00007'
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

#: Run folders are OUT/runs/NNNNN.
RUN_DIGITS = 5
#: What OUT/batch.json records about the scene, so that --resume continues the same batch.
MANIFEST = "batch.json"


def run_name(k: int) -> str:
    """The folder name of run ``k`` (``00000`` ...)."""
    return f"{int(k):0{RUN_DIGITS}d}"


@dataclass
class BatchResult:
    """What a batch did.

    Attributes
    ----------
    out_dir : pathlib.Path
    rows : list of dict
        One per run in run order: ``run``, ``seed``, one entry per varied key, ``status``
        (``ok``, ``failed`` or ``missing``), ``error`` (the content of ``runs.csv``).
    keys : list of str
        The varied keys.
    ran : int
        Runs completed by this call.
    skipped : int
        Runs already complete before it (``resume``).
    failed : int
    workers : int
        Workers of the cluster.
    time_per_run_s : float or None
        Steady-state wall time per run: once every worker has completed its first run, the time
        to the last completion divided by the runs completed in between (None with few runs).
    worker_time_per_run_s : float or None
        Mean time one run took inside its worker.
    wall_s : float
        The whole batch, cluster start included.
    """

    out_dir: Path
    rows: list = field(default_factory=list)
    keys: list = field(default_factory=list)
    ran: int = 0
    skipped: int = 0
    failed: int = 0
    workers: int = 0
    time_per_run_s: float | None = None
    worker_time_per_run_s: float | None = None
    wall_s: float = 0.0

    @property
    def ok(self) -> bool:
        """Every run complete."""
        return all(r["status"] == "ok" for r in self.rows)

    def to_dataframe(self):
        """The rows as a :class:`pandas.DataFrame` (the content of ``runs.csv``, values unformatted)."""
        import pandas as pd

        return pd.DataFrame(self.rows)

    def summary(self) -> list[str]:
        """Lines for the command line: runs done, failed, time per run."""
        n = len(self.rows)
        lines = [f"runs          {self.ran} done, {self.skipped} already complete, {self.failed} failed "
                 f"(of {n}) -> {self.out_dir / 'runs'}"]
        if self.time_per_run_s:
            lines.append(f"time per run  {self.time_per_run_s:.3f} s in steady state with {self.workers} workers "
                         f"({1.0 / self.time_per_run_s:.2f} runs/s); {self.worker_time_per_run_s:.3f} s in a worker")
        lines.append(f"wall time     {self.wall_s:.1f} s; table {self.out_dir / 'runs.csv'}")
        for r in self.rows:
            if r["status"] == "failed":
                lines.append(f"failed run {r['run']}: {r['error']}")
        return lines


def run_one(k: int, scene, runs_dir: str, prepared=None) -> dict:
    """Run ``k`` of a batch on a worker: build its job, synthesize, write ``runs_dir/NNNNN``
    (without flushing the files to the disk: :func:`run_batch` syncs at its end).

    Returns ``{"run", "status", "error", "time_s"}``; errors of the run are returned, not raised
    (a worker that dies is handled by Dask, which runs the task again elsewhere).
    """
    from ..errors import OutputExistsError, SplineImuError
    from ..io.files import deferred_sync
    from .synthesis import run_job

    t0 = time.perf_counter()
    out = Path(runs_dir) / run_name(k)
    row = {"run": int(k), "status": "ok", "error": ""}
    if not out.is_dir():
        try:
            with deferred_sync():  # the batch syncs once at its end
                run_job(scene.job(k, out_dir=out), prepared=prepared)
        except OutputExistsError:
            if not out.is_dir():  # pragma: no cover - a file of that name
                raise
        except SplineImuError as exc:
            row.update(status="failed", error=str(exc))
        except Exception as exc:  # a bug: reported with the run rather than retried
            row.update(status="failed", error=f"{type(exc).__name__}: {exc}")
    row["time_s"] = time.perf_counter() - t0
    return row


def _format(v) -> str:
    if isinstance(v, float):
        return repr(v)
    return v if isinstance(v, str) else json.dumps(v)


def write_runs_csv(path, rows, keys) -> Path:
    """Write ``runs.csv`` atomically: ``run``, ``seed``, the varied keys (``repr`` of floats), ``status``, ``error``."""
    from ..io.files import atomic_write_text

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["run", "seed", *keys, "status", "error"])
    for r in rows:
        w.writerow([r["run"], r["seed"], *(_format(r[k]) for k in keys), r["status"], r["error"]])
    return atomic_write_text(path, buf.getvalue())


def _manifest(scene, path: Path) -> dict:
    return {"scene_file": str(path), "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
            "seed": scene.seed, "vary": {k: d.to_dict() for k, d in scene.vary.items()}}


def _prepare_out(out: Path, manifest: dict, resume: bool, force: bool):
    """Check OUT before any work: new, or (``resume``) a batch of the same scene file, or (``force``) replaced."""
    from ..errors import ConfigError, OutputExistsError

    if resume and force:
        raise ConfigError("--resume continues a batch, --force replaces it: give one of them", option="--resume")
    exists = out.exists() and (not out.is_dir() or any(out.iterdir()))
    if not exists or force:
        return
    if not resume:
        raise OutputExistsError(f"{out} exists; --resume runs its missing runs, --force replaces it", path=out)
    try:
        old = json.loads((out / MANIFEST).read_text())
    except (OSError, ValueError):
        raise ConfigError(f"{out} is not a batch folder (no readable {MANIFEST}); cannot resume it",
                          option="--resume") from None
    if old.get("sha256") != manifest["sha256"]:
        raise ConfigError(f"{out} was made from another scene file ({old.get('scene_file')}, different content); "
                          "use --force to replace it or another OUT", option="--resume")


def _check_disk(out: Path, scene, prepared, n_runs: int, echo) -> None:
    """Refuse a batch whose run folders cannot fit on the disk (each run checked only its own: a
    batch filled the disk run by run), and announce a large one; from the nominal run's samples."""
    from ..errors import ConfigError
    from ..resources import LARGE_OUTPUT_BYTES, free_disk_bytes, output_bytes, size_text

    if prepared is None or n_runs == 0:
        return  # the span varies from run to run
    job = scene.job()
    if job.imu.timestamps is not None:
        return  # the stamps come from a file
    if prepared.scene is not None:
        span_s = prepared.scene.t_max_s - prepared.scene.t_min_s
    else:
        span_s = sum(float(p[0].t_ns[-1] - p[0].t_ns[0]) / 1e9 for p in prepared.pieces)
    n = int(span_s * job.imu.rate_hz) + 1
    need = n_runs * output_bytes(n, int(bool(job.imu.increments)) + int(job.imu.vibration is not None))
    free = free_disk_bytes(out)
    what = f"{n_runs} runs of {n} IMU samples"
    if free is not None and need > free:
        raise ConfigError(f"{what} need about {size_text(need)} of disk at '{out}', {size_text(free)} are free; "
                          "give fewer --runs, a shorter span or a lower rate, or another OUT", option="--runs")
    if need >= LARGE_OUTPUT_BYTES and echo:
        echo(f"note: {what}: up to {size_text(need)} of tables will be written to {out}")


def _durable_ok(out: Path) -> set:
    """The runs the last ``runs.csv`` lists as ``ok`` (it is written after :func:`os.sync`)."""
    try:
        with open(out / "runs.csv", newline="") as f:
            return {int(r["run"]) for r in csv.DictReader(f) if r.get("status") == "ok"}
    except (OSError, ValueError, KeyError, csv.Error):
        return set()


def run_folder_looks_complete(folder: Path) -> bool:
    """Whether a run folder survived a power loss: every file non-empty, ``report.json`` readable.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "report.json").write_text("{}"); _ = (d / "data.csv").write_text("")
    >>> run_folder_looks_complete(d)
    False
    """
    try:
        json.loads((folder / "report.json").read_text())
        return all(p.stat().st_size > 0 for p in folder.rglob("*") if p.is_file())
    except (OSError, ValueError):
        return False


def _sync():
    """Flush everything written to the disk (the batch's durability point; see the module docstring)."""
    import os

    if hasattr(os, "sync"):
        os.sync()


def _clear_temporaries(runs_dir: Path):
    """Remove the temporary folders of runs that were killed while writing."""
    import shutil

    for p in runs_dir.glob(".*.tmp-*"):
        shutil.rmtree(p, ignore_errors=True)


def run_batch(scene_file, runs: int, out_dir, *, workers: int | None = None, scheduler: str | None = None,
              resume: bool = False, force: bool = False, progress: bool = True, echo=None) -> BatchResult:
    """Run ``runs`` seeded variants of a scene file on a Dask cluster.

    Parameters
    ----------
    scene_file : str or os.PathLike
        A scene file with a ``seed`` and, usually, a ``vary:`` block
        (:class:`splineimu.api.scenefile.SceneFile`).
    runs : int
        Runs ``0 .. runs - 1``.
    out_dir : str or os.PathLike
        ``OUT``: ``OUT/runs/NNNNN/`` per run, ``OUT/runs.csv``, ``OUT/batch.json``. With
        ``scheduler`` it must be reachable by the workers at the same path.
    workers : int, optional
        Worker processes of the local cluster (one thread each); default one per core.
    scheduler : str, optional
        Address of an existing Dask scheduler (``tcp://host:port``) instead of a local cluster.
    resume : bool
        Continue the batch in ``OUT``: run only the runs without a complete folder (see the
        module docstring for what is checked).
    force : bool
        Replace an existing ``OUT``.
    progress : bool
        Show a progress bar on stderr.
    echo : callable, optional
        ``echo(text)`` for a line on the cluster once it is up.

    Returns
    -------
    BatchResult

    Raises
    ------
    ConfigError
        A bad scene file or ``vary:`` block (file, line and key), no ``seed``, an unreachable
        scheduler: before anything is written.
    OutputExistsError
        ``OUT`` exists without ``resume`` or ``force``.
    """
    import shutil

    from ..batch.cluster import dask_client, map_runs
    from ..io.files import atomic_write_text
    from ..validation import int_in_range
    from .scenefile import SceneFile
    from .synthesis import prepare_motion

    t_wall = time.perf_counter()
    runs = int_in_range(runs, "--runs", 1, 10**RUN_DIGITS)
    path = Path(scene_file).resolve()
    scene = SceneFile.read(path)
    keys = list(scene.vary)
    rows = [{"run": k, "seed": scene.run_seed(k), **scene.values(k), "status": "missing", "error": ""}
            for k in range(runs)]
    out = Path(out_dir).resolve()
    manifest = _manifest(scene, path)
    _prepare_out(out, manifest, resume, force)
    result = BatchResult(out, rows, keys)
    with dask_client(workers, scheduler) as client:
        # the motion is the same in every run unless a varied key is under `motion`
        prepared = None if scene.varies_motion else prepare_motion(scene.job())
        result.workers = len(client.nthreads())
        if echo:
            echo(f"cluster       {result.workers} workers"
                 f"{' at ' + scheduler if scheduler else ' (local, one thread each)'}")
        _check_disk(out, scene, prepared, sum(not (out / "runs" / run_name(k)).is_dir() for k in range(runs)),
                    echo)
        if force and out.exists():
            shutil.rmtree(out) if out.is_dir() else out.unlink()
        runs_dir = out / "runs"
        runs_dir.mkdir(parents=True, exist_ok=True)
        atomic_write_text(out / MANIFEST, json.dumps(manifest, indent=1) + "\n")
        _clear_temporaries(runs_dir)
        durable = _durable_ok(out) if resume else set()
        todo = []
        for k in range(runs):
            folder = runs_dir / run_name(k)
            if folder.is_dir() and not (k in durable or run_folder_looks_complete(folder)):
                shutil.rmtree(folder)  # cut by a power loss: run it again
            if folder.is_dir():
                rows[k]["status"] = "ok"
                result.skipped += 1
            else:
                todo.append(k)
        times = []

        def done(res):
            rows[res["run"]].update(status=res["status"], error=res.get("error", ""))
            if res.get("time_s") is not None:
                times.append(res["time_s"])

        try:
            _, steady = map_runs(client, run_one, todo, scene, str(runs_dir), prepared, progress=progress,
                                 on_result=done)
        finally:
            _clear_temporaries(runs_dir)
            _sync()
            write_runs_csv(out / "runs.csv", rows, keys)
    result.ran = sum(1 for k in todo if rows[k]["status"] == "ok")
    result.failed = sum(1 for r in rows if r["status"] == "failed")
    result.time_per_run_s = steady
    result.worker_time_per_run_s = math.fsum(times) / len(times) if times else None
    result.wall_s = time.perf_counter() - t_wall
    return result


__all__ = ["run_batch", "run_one", "BatchResult", "write_runs_csv", "run_folder_looks_complete", "run_name",
           "RUN_DIGITS"]
