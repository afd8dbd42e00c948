"""Fit time and peak memory against input size (1e3 .. 7.2e5 poses = 1 h at 200 Hz).

Each size runs in a fresh process (so the peak RSS is that fit's), on the "flips" scene with
1 mm / 0.1 deg pose noise, with the automatic knot spacing and order. A baseline in the same
process: scipy's RotationSpline + make_interp_spline through the same poses (an interpolating
spline, which is what people reach for instead of a fit).

    python benchmarks/bench_fit.py            # prints a markdown table
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

CHILD = r"""
import json, resource, sys, time
import numpy as np
from splineimu import fit, lie
from splineimu.scenes import make_scene
n = int(sys.argv[1])
sc = make_scene("flips", duration_s=n / 200.0)
t = np.arange(n) / 200.0
k = sc.kinematics(t)
rng = np.random.default_rng(0)
p = k.position_world + 1e-3 * rng.normal(size=(n, 3))
R = k.world_R_body @ lie.so3_exp(np.radians(0.1) * rng.normal(size=(n, 3)))
q = lie.matrix_to_quat_xyzw(R)
fit(t[:3000], p[:3000], q[:3000])  # load the numba cache outside the timing
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
w0, c0 = time.perf_counter(), time.process_time()
spl, rep = fit(t, p, q, return_report=True)
w1, c1 = time.perf_counter(), time.process_time()
from scipy.interpolate import make_interp_spline
from scipy.spatial.transform import Rotation, RotationSpline
b0 = time.process_time()
RotationSpline(t, Rotation.from_quat(q)); make_interp_spline(t, p, k=3)
b1 = time.process_time()
print(json.dumps(dict(n=n, wall=w1 - w0, cpu=c1 - c0, rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      base_cpu=b1 - b0, order=rep.order, dt=rep.knot_spacing_s, pos_order=rep.position_order,
                      pos_dt=rep.position_knot_spacing_s, iters=rep.iterations)))
"""


def main(sizes=(1000, 10_000, 36_000, 144_000, 720_000)):
    rows = []
    for n in sizes:
        out = subprocess.run([sys.executable, "-c", CHILD, str(n)], capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=str(HERE.parent)), check=True)
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    print("| poses | fit wall [s] | fit CPU [s] | peak RSS [MB] | scipy interp CPU [s] | rotation order, spacing [ms] "
          "| position order, spacing [ms] |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in rows:
        print(f"| {r['n']} | {r['wall']:.2f} | {r['cpu']:.2f} | {r['rss_mb']:.0f} | {r['base_cpu']:.2f} | "
              f"{r['order']}, {r['dt'] * 1e3:.1f} | {r['pos_order']}, {r['pos_dt'] * 1e3:.1f} |")
    return rows


if __name__ == "__main__":
    sizes = [int(a) for a in sys.argv[1:]] or None
    main(*(sizes and [sizes] or []))
