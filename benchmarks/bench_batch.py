"""Monte-Carlo batches: steady-state throughput against worker count and against one process per run.

    python benchmarks/bench_batch.py                 # about 2-3 minutes on the 2-core machine
    python benchmarks/bench_batch.py --quick

The scene is the acceptance scene of issue 17: the ellipse, 20 s at 200 Hz, adis16448 with two
varied noise densities. Figures, all from this one script run:

- runs/s in steady state (:attr:`splineimu.api.batch.BatchResult.time_per_run_s`: once every
  worker has completed its first run) of a local cluster of 1 and of 2 worker processes,
  measured alternately ``--repeat`` times so that a change in the machine's load hits both;
- the wall time of one ``splineimu run SCENE --run-index k`` process per run (what a shell loop
  does: interpreter start, imports, numba cache loading, every time).

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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer runs")
    ap.add_argument("--repeat", type=int, default=2, help="alternate 1 and 2 workers this many times")
    ap.add_argument("--write", action="store_true", help="also write benchmarks/results/batch.md")
    args = ap.parse_args(argv)
    runs1, runs2, procs = (12, 20, 3) if args.quick else (30, 50, 6)
    import dask
    import numba
    import numpy

    cmd = " ".join(argv if argv is not None else sys.argv[1:])
    lines = [f"# bench_batch: python {platform.python_version()}, numpy {numpy.__version__}, "
             f"numba {numba.__version__}, dask {dask.__version__}, {os.cpu_count()} CPUs "
             f"({platform.processor() or platform.machine()})",
             f"# command: python benchmarks/{Path(__file__).name} {cmd}",
             f"# load average (1/5/15 min) at start: {_load()}"]
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "scene.yaml"
        scene.write_text(SCENE)
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
    text = "\n".join(lines) + "\n"
    print(text)
    if args.write:
        (HERE / "results").mkdir(exist_ok=True)
        (HERE / "results" / "batch.md").write_text(
            "# Monte-Carlo batches: throughput against workers and against one process per run\n\n"
            "Made with `python benchmarks/bench_batch.py --write` on the shared 2-core development machine "
            "(other people's jobs running; the load average is recorded below).\n\n```\n"
            + "\n".join(lines[:3] + [lines[3]]) + "\n```\n" + "\n".join(lines[4:]) + "\n")


if __name__ == "__main__":
    main()
