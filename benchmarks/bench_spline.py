"""Spline evaluation cost: gyro + specific force (``Spline.imu``), one thread, CPU time.

Three measurements, each against a baseline timed in the same process, the cases interleaved
(every repetition runs each case in turn; the best of 5 repetitions counts):

1. One sample: ``spl.imu(t)`` at a float ``t`` (the one-sample path) for both kinds at orders 4
   and 6, against calling a trivial compiled function (``f(x) = x``, numba) in the same
   loop over the same 256 float times; the vectorized path at N = 1 for reference.
2. Throughput at N = 1 .. 1e6 (uniform random times, and the same times sorted) for both
   kinds at orders 4 and 6, with a scipy baseline (RotationSpline for the rotation + CubicSpline
   for the position, second derivative and rotation applied: the same gyro + specific force)
   on the split spline's poses at its knots. Ratios: se3 / split and split / scipy.
3. First call in a fresh process: import, building a spline, the first ``imu(array)`` (1000
   times: the vectorized kernel) and the first ``imu(float)``, with numba's cache disabled
   (compilation) and warm (cache load).

    python benchmarks/bench_spline.py            # writes benchmarks/results/spline.md
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

SIZES = [1, 10, 100, 1000, 10_000, 100_000, 1_000_000]
CASES = [("split", 4), ("split", 6), ("se3", 4), ("se3", 6)]
REPEAT = 5


def cpu_per_call(fn, min_time):
    """CPU seconds per call of ``fn``, over as many calls as take ``min_time``."""
    n = 0
    t0 = time.process_time()
    while True:
        fn()
        n += 1
        el = time.process_time() - t0
        if el >= min_time:
            return el / n


def interleaved_best(cases, min_time=0.04, repeat=REPEAT):
    """Best CPU seconds per call of each case (name -> function), the cases run in turn."""
    for fn in cases.values():
        fn()
    best = dict.fromkeys(cases, np.inf)
    for _ in range(repeat):
        for name, fn in cases.items():
            best[name] = min(best[name], cpu_per_call(fn, min_time))
    return best


def make_spline(kind, order, n_ctrl=2000, dt=0.01):
    from splineimu import Spline, lie

    rng = np.random.default_rng(0)
    pos = np.cumsum(rng.normal(size=(n_ctrl, 3)) * 0.01, axis=0)
    R = lie.so3_exp(np.cumsum(rng.normal(size=(n_ctrl, 3)) * 0.02, axis=0))
    return Spline.from_control_points(0.0, dt, pos, lie.matrix_to_quat_xyzw(R), kind=kind, order=order)


def common_range(splines):
    """The time range where every spline is valid (higher orders end earlier)."""
    return max(s.t_min_s for s in splines.values()), min(s.t_max_s for s in splines.values())


def scipy_baseline(spl):
    from scipy.interpolate import CubicSpline
    from scipy.spatial.transform import Rotation, RotationSpline

    tk = spl.t_min_s + np.arange(spl.n_segments + 1) * spl.dt_s
    p, q = spl.pose(tk)
    rs = RotationSpline(tk, Rotation.from_quat(q))
    cs = CubicSpline(tk, p)
    g = np.array([0, 0, -9.81])

    def run(t):
        rot = rs(t)
        gyro = rs(t, 1)  # RotationSpline's first derivative is the body-frame rate
        acc = cs(t, 2)
        return gyro, rot.inv().apply(acc - g)

    return run


def one_sample(splines):
    """Seconds per call: the one-sample path of each spline, the trivial compiled function, and
    the vectorized path at N = 1 (split, order 4)."""
    from splineimu._jit import jit

    @jit
    def trivial(x):
        return x

    spl0 = splines[("split", 4)]
    ts = [float(x) for x in np.random.default_rng(2).uniform(*common_range(splines), 256)]

    def loop_trivial():
        for x in ts:
            trivial(x)

    def loop_imu(spl):
        def run():
            for x in ts:
                spl.imu(x)
        return run

    arrays = [np.array([x]) for x in ts]

    def loop_array():
        for a in arrays:
            spl0.imu(a)

    cases = {"trivial": loop_trivial, **{c: loop_imu(splines[c]) for c in CASES}, "array": loop_array}
    return {k: v / len(ts) for k, v in interleaved_best(cases, min_time=0.02, repeat=15).items()}


def throughput(splines, base):
    """Samples per second of each case and of scipy at every size, unsorted and sorted times."""
    rng = np.random.default_rng(1)
    rates = {}
    for n in SIZES:
        t = rng.uniform(*common_range(splines), n)
        ts = np.sort(t)
        cases = {}
        for c in CASES:
            spl = splines[c]
            cases[c + ("unsorted",)] = lambda spl=spl: spl.imu(t)
            cases[c + ("sorted",)] = lambda spl=spl: spl.imu(ts)
        cases[("scipy", 4, "unsorted")] = lambda: base(t)
        cases[("scipy", 4, "sorted")] = lambda: base(ts)
        best = interleaved_best(cases)
        for key, sec in best.items():
            rates[key + (n,)] = n / sec
        print(f"N = {n:>8d}: " + "  ".join(f"{k[0]} k={k[1]} {k[2][0]} {n / s:.2e}/s" for k, s in best.items()),
              flush=True)
    return rates


FIRST_CALL = """
import sys, time
c = time.process_time
t0 = c()
import numpy as np
import splineimu
from benchmarks.bench_spline import make_spline
t1 = c()
s = make_spline(sys.argv[1], 4, 50)
t2 = c()
s.imu(np.linspace(s.t_min_s, s.t_max_s, 1000))
t3 = c()
s.imu(0.5 * (s.t_min_s + s.t_max_s))
t4 = c()
print(t1 - t0, t2 - t1, t3 - t2, t4 - t3)
"""


def first_call_times():
    """CPU seconds of a fresh process per kind and cache state: import, build, first imu(array),
    first imu(float); and the wall time of ``splineimu --help``."""
    env = dict(os.environ, PYTHONPATH=str(HERE.parent))
    out = {}
    for kind in ("split", "se3"):
        for label, extra in (("compile (cache disabled)", {"SPLINEIMU_NO_CACHE": "1"}), ("cache load (warm)", {})):
            run = [sys.executable, "-c", FIRST_CALL, kind]
            if not extra:  # fill the cache first
                subprocess.run(run, env=env, capture_output=True, check=True)
            res = subprocess.run(run, env=dict(env, **extra), capture_output=True, text=True, check=True)
            out[(kind, label)] = [float(x) for x in res.stdout.split()]
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "splineimu", "--help"], env=env, capture_output=True, check=True)
    return out, time.perf_counter() - t0


def main():
    import numba

    from splineimu.spline.core import FEW_SAMPLES

    numba.set_num_threads(1)
    splines = {c: make_spline(*c) for c in CASES}
    base = scipy_baseline(splines[("split", 4)])
    one = one_sample(splines)
    triv = one["trivial"]
    print(f"one sample: trivial numba call {1e6 * triv:.3f} us; "
          + "; ".join(f"{k} k={o} {1e6 * one[(k, o)]:.3f} us = {one[(k, o)] / triv:.2f}x" for k, o in CASES),
          flush=True)
    rates = throughput(splines, base)
    first, cli = first_call_times()
    load = os.getloadavg()

    lines = [
        "# Spline evaluation cost (gyro + specific force, `Spline.imu`, one thread)",
        "",
        "Made by `python benchmarks/bench_spline.py` on the project's 2-core machine "
        f"(numba {numba.__version__}, numpy {np.__version__}; load average {load[0]:.1f} at the end, "
        "the machine is shared). CPU time (`time.process_time`), the cases interleaved, best of "
        f"{REPEAT} (15 for one sample) repetitions; ratios are between figures of the same run.",
        "",
        "## One sample (`spl.imu(t)` at a float `t`)",
        "",
        "A loop over 256 float times calling each; per call, and as a multiple of calling a trivial "
        "compiled function (`f(x) = x`, numba) in the same loop.",
        "",
        "| case | per call [us] | x trivial call |",
        "| --- | ---: | ---: |",
        f"| trivial numba function | {1e6 * triv:.3f} | 1.00 |",
    ]
    lines += [f"| {k} order {o}, `imu(float)` | {1e6 * one[(k, o)]:.3f} | {one[(k, o)] / triv:.2f} |" for k, o in CASES]
    lines += [f"| split order 4, `imu(array of 1)` | {1e6 * one['array']:.3f} | {one['array'] / triv:.2f} |", ""]
    lines += [
        "## Throughput [samples/s]",
        "",
        "Uniform random times (unsorted) and the same times sorted (IMU stamps are). Up to N = "
        f"{FEW_SAMPLES} `imu` takes its few-sample path (sample by sample), above it the vectorized "
        "kernels. scipy: RotationSpline + CubicSpline on the split order-4 spline's poses at its knots.",
        "",
        "| N | " + " | ".join(f"{k} {o} {s}" for k, o in CASES + [("scipy", 4)] for s in ("unsorted", "sorted"))
        + " |",
        "| ---: |" + " ---: |" * (2 * len(CASES) + 2),
    ]
    for n in SIZES:
        lines.append(f"| {n} | " + " | ".join(f"{rates[(k, o, s, n)]:.3e}" for k, o in CASES + [("scipy", 4)]
                                               for s in ("unsorted", "sorted")) + " |")
    lines += [
        "",
        "## Ratios of throughput (unsorted / sorted times)",
        "",
        "| N | se3 / split, order 4 | se3 / split, order 6 | split / scipy, order 4 |",
        "| ---: | ---: | ---: | ---: |",
    ]

    def ratio(a, b, n):
        return " / ".join(f"{rates[a + (s, n)] / rates[b + (s, n)]:.2f}" for s in ("unsorted", "sorted"))

    for n in SIZES:
        lines.append(f"| {n} | {ratio(('se3', 4), ('split', 4), n)} | {ratio(('se3', 6), ('split', 6), n)} "
                     f"| {ratio(('split', 4), ('scipy', 4), n)} |")
    lines += [
        "",
        "## First call (fresh process, CPU seconds)",
        "",
        "`import splineimu` is lazy; building the first spline imports numba and compiles or loads the "
        "Lie kernels it uses; then the first call of each `imu` path compiles or loads its kernel.",
        "",
        "| kind | numba cache | import splineimu | build a spline | first `imu(array of 1000)` | first `imu(float)` |",
        "| --- | --- | ---: | ---: | ---: | ---: |",
    ]
    for (kind, label), v in first.items():
        lines.append(f"| {kind} | {label} | " + " | ".join(f"{x:.2f}" for x in v) + " |")
    lines += ["", f"`splineimu --help`: {cli:.2f} s wall time.", ""]
    out = HERE / "results" / "spline.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines))
    print(out.read_text())


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    main()
