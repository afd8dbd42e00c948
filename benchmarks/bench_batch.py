"""Monte-Carlo batches: steady-state throughput against worker count and against one process per run,
and where the CPU time of a run goes.

    python benchmarks/bench_batch.py                 # about 3-4 minutes on the 2-core machine
    python benchmarks/bench_batch.py --quick
    python benchmarks/bench_batch.py --cpu-only      # only the CPU accounting (robust on a busy machine)

The scene is the acceptance scene of issue 17: the ellipse, 20 s at 200 Hz, adis16448 with two
varied noise densities. Figures, all from this one script run:

- runs/s in steady state (:attr:`splineimu.api.batch.BatchResult.time_per_run_s`: once every
  worker has completed its first run) of a local cluster of 1 and of 2 worker processes,
  measured alternately ``--repeat`` times so that a change in the machine's load hits both;
- the wall time of one ``splineimu run SCENE --run-index k`` process per run (what a shell loop
  does: interpreter start, imports, numba cache loading, every time);
- CPU time per run by process (``--cpu``, on by default): the same batch on a cluster whose
  scheduler, nannies and workers are separate processes (``dask scheduler`` + ``dask worker``,
  with the local cluster's settings), warm, as the difference between a batch of ``n2`` and of
  ``n1`` runs divided by ``n2 - n1`` (fixed costs per batch cancel), median of ``--repeat``.
  CPU time is what other people's jobs on a shared machine disturb least; wall-clock ratios
  are not. From it the 2-worker scaling a 2-core machine allows:
  ``2 * worker_1 / (worker_2 + client_2 + scheduler_2 + nannies_2)`` (one worker runs alone on a
  core while the rest runs on the other; two workers share both cores with the rest; a run's CPU
  time with two workers, ``worker_2``, can exceed ``worker_1`` when they compete for caches and
  memory). It assumes that one worker uses one core: true since the text formatting runs in the
  worker's thread (before, a worker formatted in two more threads, and the projection is an upper
  bound). The disk's writeback is done by kernel threads and is not counted.

Writes the table to stdout and (with ``--write``) to benchmarks/results/batch.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

SCENE = """\
motion: {scene: ellipse, duration_s: 20}
imu: {rate_hz: 200, model: adis16448}
seed: 42
output: {dir: out}
vary:
  imu.model.gyroscope_noise_density: {normal: [1.8e-4, 2.0e-5]}
  imu.model.accelerometer_noise_density: {uniform: [1.0e-3, 3.0e-3]}
"""


def _load() -> str:
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def _batch(scene, runs, workers, tmp) -> float:
    from splineimu.api.batch import run_batch

    out = Path(tempfile.mkdtemp(dir=tmp)) / "mc"
    res = run_batch(scene, runs, out, workers=workers, progress=False)
    assert res.ok and res.workers == workers, res.summary()
    return res.time_per_run_s


def _processes(scene, n, tmp) -> list[float]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    times = []
    for k in range(n + 1):  # the first one fills the numba cache if needed: not counted
        out = Path(tempfile.mkdtemp(dir=tmp)) / "run"
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "splineimu", "run", str(scene), "--run-index", str(k), "-o", str(out)],
                       check=True, env=env, stdout=subprocess.DEVNULL)
        if k:
            times.append(time.perf_counter() - t0)
    return times


def _quiet_env(cluster) -> dict:
    """The local cluster's settings (thread counts, Dask configuration) as environment variables
    for ``dask scheduler`` and ``dask worker`` processes."""
    env = {"OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1",
           "SPLINEIMU_FORMAT_THREADS": "0"}
    for key, value in getattr(cluster, "QUIET_CONFIG", {}).items():
        env["DASK_" + "__".join(part.upper().replace("-", "_") for part in key.split("."))] = str(value)
    return env


def _cpu_s(proc) -> float:
    t = proc.cpu_times()
    return t.user + t.system


def _cpu_accounting(scene, workers, sizes, repeat, tmp) -> dict:
    """CPU seconds per run of each process role (see the module docstring) and the idle rates."""
    import json

    import psutil
    from distributed import Client

    from splineimu.api.batch import run_batch
    from splineimu.batch import cluster

    dask = Path(sys.executable).with_name("dask")
    env = dict(os.environ, PYTHONPATH=str(ROOT), **_quiet_env(cluster))
    file = Path(tempfile.mkdtemp(dir=tmp)) / "scheduler.json"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env, "cwd": tmp}
    procs = [subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0", "--scheduler-file",
                               str(file), "--no-dashboard"], **quiet)]
    try:
        for _ in range(600):
            if file.exists() and file.stat().st_size:
                break
            time.sleep(0.1)
        address = json.loads(file.read_text())["address"]
        procs.append(subprocess.Popen([str(dask), "worker", address, "--nworkers", str(workers), "--nthreads", "1",
                                       "--host", "127.0.0.1", "--no-dashboard"], **quiet))
        with Client(address, timeout=60) as c:
            c.wait_for_workers(workers, timeout=120)
        roles = {"client": [psutil.Process()], "scheduler": [psutil.Process(procs[0].pid)],
                 "nannies": [psutil.Process(procs[1].pid)],
                 "workers": psutil.Process(procs[1].pid).children(recursive=True)}

        def snap():
            return time.perf_counter(), {r: sum(_cpu_s(p) for p in ps) for r, ps in roles.items()}

        run_batch(scene, 4 * workers, Path(tempfile.mkdtemp(dir=tmp)) / "warm", scheduler=address, progress=False)
        (w0, a), _, (w1, b) = snap(), time.sleep(3.0), snap()
        idle = {r: (b[r] - a[r]) / (w1 - w0) for r in roles}
        per = {n: [] for n in sizes}
        in_worker = []
        for _ in range(repeat):
            for n in sizes:
                w0, a = snap()
                res = run_batch(scene, n, Path(tempfile.mkdtemp(dir=tmp)) / "mc", scheduler=address, progress=False)
                w1, b = snap()
                assert res.ok and res.workers == workers, res.summary()
                per[n].append({"wall": w1 - w0, **{r: b[r] - a[r] for r in roles}})
                in_worker.append(res.worker_time_per_run_s)
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    n1, n2 = sizes
    out = {r: (statistics.median(x[r] for x in per[n2]) - statistics.median(x[r] for x in per[n1])) / (n2 - n1)
           for r in ["wall", *roles]}
    out["idle"] = idle
    out["in_worker_wall"] = statistics.median(in_worker)
    return out


def _cpu_lines(acc, sizes, repeat) -> list[str]:
    roles = ["workers", "client", "scheduler", "nannies"]
    lines = ["", f"CPU time per run [ms] (warm cluster, ({sizes[1]}-run batch - {sizes[0]}-run batch) / "
                 f"{sizes[1] - sizes[0]}, median of {repeat}; idle: CPU ms per second with no batch running)", "",
             "| workers | " + " | ".join(roles) + " | wall per run | wall of a run in its worker | projected 2/1 |",
             "|---:|" + "---:|" * (len(roles) + 3)]
    for w, a in acc.items():
        other = a["client"] + a["scheduler"] + a["nannies"]
        proj = 2 * acc[1]["workers"] / (a["workers"] + other) if w == 2 and 1 in acc else float("nan")
        lines.append(f"| {w} | " + " | ".join(f"{1e3 * a[r]:.1f}" for r in roles)
                     + f" | {1e3 * a['wall']:.1f} | {1e3 * a['in_worker_wall']:.1f} | {proj:.2f} |")
        lines.append(f"| {w}, idle [ms/s] | " + " | ".join(f"{1e3 * a['idle'][r]:.1f}" for r in roles) + " | | | |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer runs")
    ap.add_argument("--repeat", type=int, default=2, help="alternate 1 and 2 workers this many times")
    ap.add_argument("--write", action="store_true", help="also write benchmarks/results/batch.md")
    ap.add_argument("--no-cpu", dest="cpu", action="store_false", help="skip the CPU accounting")
    ap.add_argument("--cpu-only", action="store_true", help="only the CPU accounting")
    ap.add_argument("--src", metavar="DIR", help="measure the package of another checkout (before/after comparisons)")
    args = ap.parse_args(argv)
    if args.src:
        global ROOT
        ROOT = Path(args.src).resolve()
        sys.path.insert(0, str(ROOT))
    runs1, runs2, procs = (12, 20, 3) if args.quick else (30, 50, 6)
    sizes = (8, 24) if args.quick else (10, 40)
    import dask
    import numba
    import numpy

    cmd = " ".join(argv if argv is not None else sys.argv[1:])
    lines = [f"# bench_batch: python {platform.python_version()}, numpy {numpy.__version__}, "
             f"numba {numba.__version__}, dask {dask.__version__}, {os.cpu_count()} CPUs "
             f"({platform.processor() or platform.machine()})",
             f"# command: python benchmarks/{Path(__file__).name} {cmd}",
             f"# load average (1/5/15 min) at start: {_load()}"]
    acc = {}
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "scene.yaml"
        scene.write_text(SCENE)
        if args.cpu or args.cpu_only:
            for w in (1, 2):
                acc[w] = _cpu_accounting(scene, w, sizes, args.repeat, tmp)
            lines.append(f"# load average after the CPU accounting: {_load()}")
        if args.cpu_only:
            text = "\n".join(lines + _cpu_lines(acc, sizes, args.repeat)) + "\n"
            print(text)
            return
        one, two = [], []
        for _ in range(args.repeat):
            one.append(_batch(scene, runs1, 1, tmp))
            two.append(_batch(scene, runs2, 2, tmp))
        proc = _processes(scene, procs, tmp)
    lines.append(f"# load average at end: {_load()}")
    t1, t2, tp = statistics.median(one), statistics.median(two), statistics.median(proc)
    lines += ["", "| setting | runs | time per run [s] | runs/s | ratio |", "|---|---:|---:|---:|---:|",
              f"| one `splineimu run` process per run | {procs} | {tp:.3f} | {1 / tp:.2f} | 1.00 |",
              f"| batch, 1 worker (steady state) | {runs1} x {args.repeat} | {t1:.3f} | {1 / t1:.2f} "
              f"| {t1 / tp:.3f} |",
              f"| batch, 2 workers (steady state) | {runs2} x {args.repeat} | {t2:.3f} | {1 / t2:.2f} "
              f"| {t2 / tp:.3f} |",
              "",
              f"- 2 workers / 1 worker throughput: **{t1 / t2:.2f}x** (each repeat: "
              f"{', '.join(f'{a / b:.2f}' for a, b in zip(one, two))}; acceptance >= 1.6)",
              f"- 1 worker per run / separate process per run: **{t1 / tp:.2f}** (acceptance <= 0.5)",
              f"- separate processes [s]: {', '.join(f'{t:.2f}' for t in proc)}",
              f"- 1 worker [s/run]: {', '.join(f'{t:.3f}' for t in one)}; 2 workers [s/run]: "
              f"{', '.join(f'{t:.3f}' for t in two)}"]
    if acc:
        lines += _cpu_lines(acc, sizes, args.repeat)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.write:
        head = lines.index("")
        (HERE / "results").mkdir(exist_ok=True)
        (HERE / "results" / "batch.md").write_text(
            "# Monte-Carlo batches: throughput against workers and against one process per run\n\n"
            "Made with `python benchmarks/bench_batch.py --write` on the shared 2-core development machine "
            "(other people's jobs running; the load average is recorded below).\n\n```\n"
            + "\n".join(lines[:head]) + "\n```\n" + "\n".join(lines[head:]) + "\n")


if __name__ == "__main__":
    main()
