"""Spline evaluation throughput: gyro + specific force in one pass, one thread.

Sizes N = 1 .. 1e6 for both kinds and orders 4 and 6, with a scipy baseline
(RotationSpline for the rotation + CubicSpline for the position, second derivative and
rotation applied, i.e. the same gyro + specific force) timed in the same process, so every
figure can be read as a ratio. Also the first-call time: compiling the kernel (cache
disabled, in a fresh process) and loading it from numba's cache (fresh process, warm cache).

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


def best_time(fn, min_time=0.3, repeat=5):
    fn()
    best = np.inf
    for _ in range(repeat):
        n = 0
        t0 = time.perf_counter()
        while True:
            fn()
            n += 1
            el = time.perf_counter() - t0
            if el >= min_time / repeat:
                break
        best = min(best, el / n)
    return best


def make_spline(kind, order, n_ctrl=2000, dt=0.01):
    from splineimu import Spline, lie

    rng = np.random.default_rng(0)
    pos = np.cumsum(rng.normal(size=(n_ctrl, 3)) * 0.01, axis=0)
    R = lie.so3_exp(np.cumsum(rng.normal(size=(n_ctrl, 3)) * 0.02, axis=0))
    return Spline.from_control_points(0.0, dt, pos, lie.matrix_to_quat_xyzw(R), kind=kind, order=order)


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


def first_call_times():
    code = (
        "import time; t=time.perf_counter();"
        "from benchmarks.bench_spline import make_spline; import numpy as np;"
        "s=make_spline('split',4,50); s.imu(np.linspace(s.t_min_s,s.t_max_s,10));"
        "print(time.perf_counter()-t)"
    )
    env = dict(os.environ, PYTHONPATH=str(HERE.parent))
    cold = subprocess.run([sys.executable, "-c", code], env=dict(env, SPLINEIMU_NO_CACHE="1"),
                          capture_output=True, text=True, check=True).stdout.strip()
    subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, check=True)  # fill the cache
    warm = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          check=True).stdout.strip()
    cli0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "splineimu", "--help"], env=env, capture_output=True, check=True)
    cli = time.perf_counter() - cli0
    return float(cold), float(warm), cli


def main():
    import numba

    numba.set_num_threads(1)
    rows = []
    sizes = [1, 10, 100, 1000, 10_000, 100_000, 1_000_000]
    rng = np.random.default_rng(1)
    for kind in ("split", "se3"):
        for order in (4, 6):
            spl = make_spline(kind, order)
            base = scipy_baseline(spl) if (kind, order) == ("split", 4) else None
            for n in sizes:
                t = rng.uniform(spl.t_min_s, spl.t_max_s, n)  # unsorted
                ts = np.sort(t)  # the same times, sorted (IMU stamps are)
                d_u = best_time(lambda: spl.imu(t))
                d_s = best_time(lambda: spl.imu(ts))
                row = {"kind": kind, "order": order, "N": n, "ours_rate": n / d_u, "ours_sorted_rate": n / d_s}
                line = f"{kind:5s} k={order} N={n:>8d}  unsorted {n / d_u:10.3e} /s  sorted {n / d_s:10.3e} /s"
                if base is not None:
                    b_u = best_time(lambda: base(t))
                    b_s = best_time(lambda: base(ts))
                    row.update(scipy_rate=n / b_u, scipy_sorted_rate=n / b_s, ratio=b_u / d_u, ratio_sorted=b_s / d_s)
                    line += f"   scipy {n / b_u:10.3e} / {n / b_s:10.3e}   x{b_u / d_u:5.1f} / x{b_s / d_s:5.1f}"
                rows.append(row)
                print(line, flush=True)
    cold, warm, cli = first_call_times()
    out = HERE / "results" / "spline.md"
    out.parent.mkdir(exist_ok=True)
    lines = [
        "# Spline evaluation throughput (gyro + specific force, one thread)",
        "",
        "Made by `python benchmarks/bench_spline.py` on the project's 2-core machine "
        f"(numba {numba.__version__}, numpy {np.__version__}). Rates are samples/s; the scipy baseline "
        "(RotationSpline + CubicSpline, same outputs) is timed in the same process.",
        "",
        "Both are given the same query times: unsorted (uniform random) and the same times sorted.",
        "",
        "| kind | order | N | splineimu unsorted [1/s] | splineimu sorted [1/s] | scipy unsorted [1/s] "
        "| scipy sorted [1/s] | speed-up unsorted | speed-up sorted |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        sc = (f"{r['scipy_rate']:.3e} | {r['scipy_sorted_rate']:.3e} | x{r['ratio']:.1f} | x{r['ratio_sorted']:.1f}"
              if "scipy_rate" in r else "- | - | - | -")
        lines.append(f"| {r['kind']} | {r['order']} | {r['N']} | {r['ours_rate']:.3e} | {r['ours_sorted_rate']:.3e} "
                     f"| {sc} |")
    lines += [
        "",
        "| first call (fresh process: import + build + evaluate) | seconds |",
        "| --- | ---: |",
        f"| compile (numba cache disabled) | {cold:.2f} |",
        f"| cache load (warm numba cache) | {warm:.2f} |",
        f"| `splineimu --help` | {cli:.2f} |",
        "",
    ]
    out.write_text("\n".join(lines))
    print(out.read_text())


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    main()
