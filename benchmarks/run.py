"""Run every benchmark and rewrite the committed results (benchmarks/results/).

    python benchmarks/run.py            # about 5-8 minutes on the 2-core machine
    python benchmarks/run.py --quick    # smaller sizes

Each measurement runs in its own process; figures come with a baseline timed in the same
process (scipy, allantools, numpy loops) so they can be read as ratios on a noisy machine.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def _run(title, args, quick_args=()):
    env = dict(os.environ, PYTHONPATH=str(HERE.parent), NUMBA_NUM_THREADS=os.environ.get("NUMBA_NUM_THREADS", "1"))
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, *args, *quick_args], capture_output=True, text=True, env=env,
                         cwd=HERE.parent)
    el = time.perf_counter() - t0
    text = out.stdout if out.returncode == 0 else out.stdout + "\n```\n" + out.stderr[-3000:] + "\n```\n"
    print(f"{title:40s} {el:7.1f} s {'ok' if out.returncode == 0 else 'FAILED'}", flush=True)
    return f"## {title}\n\n`python {' '.join(args + list(quick_args))}` ({el:.0f} s)\n\n{text}\n", out.returncode


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    RESULTS.mkdir(exist_ok=True)
    q = ["--quick"] if args.quick else []
    sections = []
    bad = 0
    t0 = time.perf_counter()
    for title, cmd, quick in (
        ("Spline evaluation throughput and first-call cost", ["benchmarks/bench_spline.py"], []),
        ("Fit time and memory against input size", ["benchmarks/bench_fit.py"],
         ["1000", "10000", "36000"] if args.quick else []),
        ("Accuracy against cost: order, knot spacing, sampling, integration", ["benchmarks/bench_tradeoffs.py"], []),
        ("Allan deviation against allantools", ["benchmarks/bench_allan.py"], q),
        ("Preintegration throughput", ["benchmarks/bench_preintegration.py"], q),
        ("Monte-Carlo batches: workers and one process per run", ["benchmarks/bench_batch.py"], q),
    ):
        text, rc = _run(title, cmd, quick)
        bad += rc != 0
        sections.append(text)
    import numba
    import numpy

    head = (f"# splineimu benchmark results\n\nMade by `python benchmarks/run.py{' --quick' if args.quick else ''}` "
            f"in {time.perf_counter() - t0:.0f} s on {platform.machine()} with {os.cpu_count()} CPUs, "
            f"Python {platform.python_version()}, numpy {numpy.__version__}, numba {numba.__version__}. "
            "The machine is shared: read speed figures as the ratios against the baselines timed in the "
            "same process.\n\n")
    (RESULTS / "README.md").write_text(head + "\n".join(sections))
    print(f"wrote {RESULTS / 'README.md'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
