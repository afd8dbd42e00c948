"""Tracking glitches on the analytic scenes: caught, and the rest of the record as good as without.

The acceptance bar of the automatic fit for a glitch (a 5 cm, 40 ms jump of the positions and
back): either dropped or warned with its time range, and the accelerometer elsewhere <= 1.3x the
best fixed setting. Per case: 60 s (``--duration``) of one of the six moving scenes at ``--rate``
with white, AR(1) or upsampled pose noise (tests/fit_scenes.py), a glitch of ``--size`` metres for
``--length`` seconds at a time drawn in [5 s, end - 5 s] along a random direction, the automatic
fit, and its gyro and accel errors over [1 s, end - 1 s] without the second around the glitch, against the
best of the fixed grid fitted to the same poses without the glitch (benchmarks/scene_sweep.py's
grid; ``--cache`` shares its files).

    PYTHONPATH=$PWD python benchmarks/glitch_sweep.py --seeds 0-2 --jobs 2 --cache /tmp/grid
    PYTHONPATH=$PWD python benchmarks/glitch_sweep.py --duration 20 --scenes ellipse circle screw flips ...

Prints one row per case (caught: the glitch's poses dropped, or a warning whose time range
covers it) and the worst ratios.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from scene_sweep import DURATION_S, _seeds, case_arguments  # noqa: E402

BAR = 1.3


def case(args):
    """One row (dict): caught or not, auto / best fixed per quantity away from the glitch."""
    name, kind, seed, rate, size, length, cache, duration = args
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    from fit_scenes import fixed_grid_errors, scene_errors, scene_poses

    from splineimu import fit, lie

    sc, t, p, R = scene_poses(name, kind, duration, rate, seed, 1.0)
    q = lie.matrix_to_quat_xyzw(R)
    span = "" if duration == DURATION_S else f"_{duration:g}s"  # (scene_sweep.py's cache names)
    path = None if cache is None else Path(cache) / f"{name}_{kind}_{seed}_{rate:g}_1{span}.npy"
    grid = fixed_grid_errors(sc, t, p, q, duration, path)
    rng = np.random.default_rng(500 + seed)
    t0 = rng.uniform(5.0, duration - 5.0)
    d = rng.normal(size=3)
    inside = (t >= t0) & (t < t0 + length)
    pg = p.copy()
    pg[inside] += size * d / np.linalg.norm(d)
    spl, rep = fit(t, pg, q, return_report=True)
    dropped = set(np.flatnonzero(inside).tolist()) <= set(rep.dropped_poses)
    warned = sorted({w.code for w in rep.warnings
                     if w.t_start_s is not None and w.t_start_s <= t0 + length and w.t_end_s >= t0 - 1.0 / rate})
    ge, fe = scene_errors(sc, spl, duration, exclude=(t0 + 0.5 * length, 0.5))
    return {"scene": name, "kind": kind, "seed": seed, "t_s": t0, "caught": dropped or bool(warned),
            "dropped": len(rep.dropped_poses), "warned": ",".join(warned) or "-",
            "gyro": ge / grid[:, 0].min(), "accel": fe / grid[:, 1].min()}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    case_arguments(ap, seeds="noise and glitch seeds")
    ap.add_argument("--size", type=float, default=0.05, help="glitch size [m] (default 0.05)")
    ap.add_argument("--length", type=float, default=0.04, help="glitch length [s] (default 0.04)")
    ap.add_argument("--duration", type=float, default=DURATION_S, help=f"seconds of poses (default {DURATION_S:g})")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    ap.add_argument("--cache", default=None, help="folder keeping the fixed grid's errors (scene_sweep.py's)")
    args = ap.parse_args(argv)
    jobs = [(s, k, seed, args.rate, args.size, args.length, args.cache, args.duration)
            for seed in _seeds(args.seeds) for s in args.scenes for k in args.kinds]
    print(f"{args.rate:g} Hz, 1 mm / 0.1 deg pose noise, {args.duration:g} s, a {100 * args.size:g} cm, "
          f"{1e3 * args.length:g} ms glitch; auto / best fixed away from it\n")
    print("| case | glitch at [s] | caught | poses dropped | warnings over it | gyro | accel | |\n"
          "| --- | ---: | --- | ---: | --- | ---: | ---: | --- |")
    rows = []
    with ProcessPoolExecutor(args.jobs) if args.jobs > 1 else contextlib.nullcontext() as pool:
        for row in (pool.map if pool else map)(case, jobs):
            rows.append(row)
            miss = not row["caught"] or row["accel"] > BAR
            print(f"| {row['scene']} {row['kind']} {row['seed']} | {row['t_s']:.3f} | {row['caught']} | "
                  f"{row['dropped']} | {row['warned']} | {row['gyro']:.3f} | {row['accel']:.3f} | "
                  f"{'MISS' if miss else ''} |", flush=True)
    caught = sum(r["caught"] for r in rows)
    print(f"\ncaught {caught} of {len(rows)}; worst accel / best {max(r['accel'] for r in rows):.3f} "
          f"(bar {BAR}), worst gyro / best {max(r['gyro'] for r in rows):.3f}")


if __name__ == "__main__":
    main()
