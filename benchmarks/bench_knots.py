"""Cost of the automatic knot choice (order and spacing of rotation and position) against the
whole fit and against scipy interpolation of the same poses.

The "flips" scene with 1 mm / 0.1 deg pose noise at 200 Hz, as in bench_fit.py. CPU time
(``time.process_time``), best of ``--reps`` interleaved repetitions in one process with a warm
JIT; the baseline is scipy's RotationSpline + CubicSpline through the same poses.

    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/bench_knots.py [sizes...] [--reps 5]
    # writes results/knots.md
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def poses(n):
    from splineimu import lie
    from splineimu.scenes import make_scene

    t = np.arange(n) / 200.0
    k = make_scene("flips", duration_s=n / 200.0).kinematics(t)
    rng = np.random.default_rng(0)
    p = k.position_world + 1e-3 * rng.normal(size=(n, 3))
    R = k.world_R_body @ lie.so3_exp(np.radians(0.1) * rng.normal(size=(n, 3)))
    return t, p, R, lie.matrix_to_quat_xyzw(R)


def measure(n, reps=5):
    from scipy.interpolate import CubicSpline
    from scipy.spatial.transform import Rotation, RotationSpline

    from splineimu import fit
    from splineimu.spline.knots import choose_knot_spacing

    t, p, R, q = poses(n)
    w = np.ones(n)
    fit(t[:3000], p[:3000], q[:3000])  # compile or load the kernels outside the timing
    best = {"choice": np.inf, "fit": np.inf, "scipy": np.inf}
    for _ in range(reps):
        c0 = time.process_time()
        choice = choose_knot_spacing(t, p, R, w)
        c1 = time.process_time()
        fit(t, p, q)
        c2 = time.process_time()
        RotationSpline(t, Rotation.from_quat(q))
        CubicSpline(t, p)
        c3 = time.process_time()
        for key, v in (("choice", c1 - c0), ("fit", c2 - c1), ("scipy", c3 - c2)):
            best[key] = min(best[key], v)
    rot, pos = choice["rotation"], choice["position"]
    return dict(n=n, **best, rot=(rot["order"], rot["knot_spacing_s"]), pos=(pos["order"], pos["knot_spacing_s"]))


def main(sizes=(1000, 12_000, 48_000), reps=5):
    rows = [measure(n, reps) for n in sizes]
    lines = ["| poses | choice CPU [ms] | fit CPU [ms] | scipy interp CPU [ms] | choice / scipy | fit / scipy "
             "| rotation order, spacing [ms] | position order, spacing [ms] |",
             "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        lines.append(f"| {r['n']} | {r['choice'] * 1e3:.1f} | {r['fit'] * 1e3:.1f} | {r['scipy'] * 1e3:.1f} | "
                     f"{r['choice'] / r['scipy']:.2f} | {r['fit'] / r['scipy']:.2f} | {r['rot'][0]}, "
                     f"{r['rot'][1] * 1e3:.1f} | {r['pos'][0]}, {r['pos'][1] * 1e3:.1f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    args = sys.argv[1:]
    reps = 5
    if "--reps" in args:
        i = args.index("--reps")
        reps = int(args[i + 1])
        del args[i: i + 2]
    sizes = [int(a) for a in args] or [1000, 12_000, 48_000]
    text = main(sizes, reps)
    print(text)
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "knots.md").write_text(
        "# Cost of the automatic knot choice\n\n"
        f"`NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/bench_knots.py {' '.join(map(str, sizes))} "
        f"--reps {reps}`\n\n"
        "CPU time, best of the repetitions, flips scene with 1 mm / 0.1 deg noise at 200 Hz; the fit includes "
        "the choice. Shared machine: read the ratios.\n\n" + text + "\n")
