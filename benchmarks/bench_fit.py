"""Fit time and peak memory against input size (1e3 .. 7.2e5 poses = 1 h at 200 Hz), and the fit's
CPU time as a ratio to scipy's at 12k poses.

The poses: the "flips" scene at 200 Hz with 1 mm / 0.1 deg noise, made once and handed to the
measuring processes in a file. The baseline, timed in the same process: scipy's RotationSpline +
make_interp_spline through the same poses (an interpolating spline, which is what people reach for
instead of a fit).

- Ratio table: one process, one thread, the fit with its defaults (automatic order and knot
  spacing), the fit at the settings the defaults chose (the solve alone, without the choice) and
  scipy, interleaved; best CPU time of each over the repetitions.
- Size table: each size in a fresh process, after a warm-up fit of 3000 poses (numba cache
  load); one fit with the defaults, then scipy. "peak RSS" is the process' high-water mark right
  after the fit (before scipy runs), "before" the one after the warm-up.

    python benchmarks/bench_fit.py                # both tables (about a minute)
    python benchmarks/bench_fit.py 1000 10000     # the ratio table and these sizes
    python benchmarks/bench_fit.py --reps 9       # more repetitions for the ratio
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
RATIO_POSES = 12_000

DATA = r"""
import sys
import numpy as np
from splineimu import lie
from splineimu.scenes import make_scene
n, path = int(sys.argv[1]), sys.argv[2]
sc = make_scene("flips", duration_s=n / 200.0)
t = np.arange(n) / 200.0
k = sc.kinematics(t)
rng = np.random.default_rng(0)
p = k.position_world + 1e-3 * rng.normal(size=(n, 3))
R = k.world_R_body @ lie.so3_exp(np.radians(0.1) * rng.normal(size=(n, 3)))
np.savez(path, t=t, p=p, q=lie.matrix_to_quat_xyzw(R))
"""

COMMON = r"""
import json, resource, sys, time
import numpy as np
from splineimu import fit
from scipy.interpolate import make_interp_spline
from scipy.spatial.transform import Rotation, RotationSpline
d = np.load(sys.argv[1])
t, p, q = d["t"], d["p"], d["q"]
fit(t[:3000], p[:3000], q[:3000])  # load the numba cache outside the timing
def scipy_interp():
    RotationSpline(t, Rotation.from_quat(q))
    make_interp_spline(t, p, k=3)
def cpu(f):
    c0 = time.process_time()
    out = f()
    return time.process_time() - c0, out
"""

SIZE = COMMON + r"""
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
w0 = time.perf_counter()
c_fit, (spl, rep) = cpu(lambda: fit(t, p, q, return_report=True))
wall = time.perf_counter() - w0
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
c_base, _ = cpu(scipy_interp)
print(json.dumps(dict(n=t.size, wall=wall, cpu=c_fit, rss_mb=rss, rss0_mb=rss0, base_cpu=c_base, order=rep.order,
                      dt=rep.knot_spacing_s, pos_order=rep.position_order, pos_dt=rep.position_knot_spacing_s,
                      iters=rep.iterations)))
"""

RATIO = COMMON + r"""
reps = int(sys.argv[2])
_, (spl, rep) = cpu(lambda: fit(t, p, q, return_report=True))
given = dict(order=rep.order, knot_spacing_s=rep.knot_spacing_s, position_order=rep.position_order,
             position_knot_spacing_s=rep.position_knot_spacing_s)
best = {}
for _ in range(reps):
    for name, f in (("defaults", lambda: fit(t, p, q)), ("given", lambda: fit(t, p, q, **given)),
                    ("scipy", scipy_interp)):
        best[name] = min(best.get(name, np.inf), cpu(f)[0])
print(json.dumps(dict(n=t.size, reps=reps, **best, iters=rep.iterations, order=rep.order, dt=rep.knot_spacing_s)))
"""


def _child(code, *args):
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True,
                         env=dict(os.environ, PYTHONPATH=str(HERE.parent)), check=True)
    return (out.stdout.strip().splitlines() or [""])[-1]


def _poses(n, folder):
    path = Path(folder) / f"poses_{n}.npz"
    if not path.exists():
        _child(DATA, n, path)
    return path


def main(sizes=(1000, 10_000, 36_000, 144_000, 720_000), reps=7):
    with tempfile.TemporaryDirectory() as folder:
        r = json.loads(_child(RATIO, _poses(RATIO_POSES, folder), reps))
        print(f"Fit of {r['n']} poses against scipy, CPU time, best of {r['reps']} interleaved repetitions "
              f"(order {r['order']}, knot spacing {r['dt'] * 1e3:.1f} ms, {r['iters']} iterations):\n")
        print("| run | CPU [ms] | ratio to scipy |")
        print("| --- | ---: | ---: |")
        for name, label in (("defaults", "fit, defaults (automatic order and knot spacing)"),
                            ("given", "fit at the chosen settings (all but the knot choice)"),
                            ("scipy", "scipy RotationSpline + make_interp_spline")):
            print(f"| {label} | {r[name] * 1e3:.1f} | {r[name] / r['scipy']:.2f} |")
        print()
        rows = [json.loads(_child(SIZE, _poses(n, folder))) for n in sizes]
    print("| poses | fit wall [s] | fit CPU [s] | scipy interp CPU [s] | ratio | peak RSS [MB] | before [MB] "
          "| rotation order, spacing [ms] | position order, spacing [ms] | iterations |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in rows:
        print(f"| {r['n']} | {r['wall']:.2f} | {r['cpu']:.2f} | {r['base_cpu']:.2f} | {r['cpu'] / r['base_cpu']:.2f} | "
              f"{r['rss_mb']:.0f} | {r['rss0_mb']:.0f} | {r['order']}, {r['dt'] * 1e3:.1f} | "
              f"{r['pos_order']}, {r['pos_dt'] * 1e3:.1f} | {r['iters']} |")
    return rows


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sizes", nargs="*", type=int, help="pose counts of the size table")
    ap.add_argument("--reps", type=int, default=7, help="repetitions of the ratio table (default 7)")
    a = ap.parse_args()
    main(*([a.sizes] if a.sizes else []), reps=a.reps)
