"""Cost of re-timing receive-time stamps (splineimu.stamps.retime_stamps) against the fit of the
same poses.

Synthetic mocap logged on arrival (tests/fit_scenes.py ``received``: the ellipse scene, 7% of the
frames dropped, delivery delays of 0.05-0.5 periods (1-10 ms at 50 Hz), 100-270 ms stalls one
frame in 150, 0.3 mm / 0.05 deg pose noise) at 50, 100 and 200 Hz. CPU time (``time.process_time``), best of ``--reps``
interleaved repetitions in one process after a first call (which loads the compiled kernels from
numba's cache, or compiles them: reported as "first call"); the baseline is the automatic fit
(``splineimu.fit``) of the same poses at their capture times, timed in the same process.

    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/bench_stamps.py [--reps 3]
    # writes results/stamps.md
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

#: (pose rate [Hz], duration [s]) of the records timed.
CASES = ((50.0, 60.0), (100.0, 60.0), (100.0, 600.0), (200.0, 600.0))


def cpu(f):
    t0 = time.process_time()
    out = f()
    return time.process_time() - t0, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args(argv)

    from fit_scenes import received

    from splineimu import fit
    from splineimu.stamps import retime_stamps

    rows = []
    for rate, duration in CASES:
        _, tc, tr, p, q = received("ellipse", 0, duration=duration, rate=rate, delays=(0.05 / rate, 0.5 / rate))
        t_ns = np.round(tr * 1e9).astype(np.int64)
        first, rt = cpu(lambda: retime_stamps(t_ns, p, q))
        best_rt = best_fit = np.inf
        for _ in range(args.reps):
            best_rt = min(best_rt, cpu(lambda: retime_stamps(t_ns, p, q))[0])
            best_fit = min(best_fit, cpu(lambda: fit(tc - tc[0], p, q))[0])
        tn = (rt.t_ns - rt.t_ns[0]) / 1e9 + tr[0]
        right = float(np.mean(np.abs(tn - tc - np.median(tn - tc)) < 0.25 / rate))
        rows.append((rate, duration, tc.size, first, best_rt, best_fit, right))
        print(f"{rate:g} Hz {duration:g} s: {tc.size} poses, first call {first:.2f} s, re-timing {best_rt:.2f} s, "
              f"fit {best_fit:.2f} s, slots right {100 * right:.2f}%", flush=True)
    lines = ["| poses | rate | duration | re-timing CPU [s] | fit CPU [s] | re-timing / fit | first call [s] "
             "| slots right |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for rate, duration, n, first, r, f, right in rows:
        lines.append(f"| {n} | {rate:g} Hz | {duration:g} s | {r:.2f} | {f:.2f} | {r / f:.2f} | {first:.2f} | "
                     f"{100 * right:.2f}% |")
    table = "\n".join(lines)
    print(table)
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    import platform
    import subprocess

    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, capture_output=True, text=True).stdout
    (out / "stamps.md").write_text(
        "# Re-timing receive-time stamps: cost against the fit of the same poses\n\n"
        f"`NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/bench_stamps.py --reps {args.reps}` "
        f"({time.strftime('%Y-%m-%d')}, at {rev.strip() or 'an unknown commit'}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs)\n\n"
        "CPU seconds, best of the repetitions (first call: the first in the process, kernels from "
        "numba's cache). Slots right: poses whose new stamp is their capture time plus the record's "
        "constant offset (the misses are stalls at a record's very ends).\n\n" + table + "\n")


if __name__ == "__main__":
    main()
