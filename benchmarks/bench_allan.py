"""Speed of the Allan deviation against allantools, and of the 3 h static pipeline.

Run:  python benchmarks/bench_allan.py [--quick] [--threads N]

Measures, in one process:
1. first call of :func:`splineimu.allan.allan_deviation` (numba cache load or compile);
2. ``allan_deviation`` on 6 axes of white + random-walk data for N = 3 .. 2.16e6 samples at the
   default cluster times (~10 per decade, up to N/4), best of a few repeats, against
   ``allantools.oadev(..., data_type="freq")`` column by column at the same taus (the results
   are checked equal to 1e-9 relative);
3. the issue-4 pipeline: 3 h x 200 Hz static generation with the EuRoC ADIS16448 model
   (:class:`splineimu.imu.noise.SensorModel`), Allan deviation of the 6 axes, and the fit.

Prints a markdown table (the committed results are in bench_allan.md next to this file).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np


def best_of(fn, repeats):
    best = float("inf")
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="skip the 2.16e6 row of the comparison")
    ap.add_argument("--threads", type=int, help="threads of allan_deviation (default: the CPUs)")
    args = ap.parse_args(argv)

    import allantools
    import numba

    from splineimu.allan import allan_deviation, default_cluster_factors, fit_noise_parameters
    from splineimu.imu.noise import SensorModel

    rate = 200.0
    rng = np.random.default_rng(0)
    print(f"# bench_allan: python {platform.python_version()}, numpy {np.__version__}, "
          f"numba {numba.__version__}, allantools {allantools.__version__}, {os.cpu_count()} CPUs, "
          f"threads {args.threads or os.cpu_count()}")
    cmd = " ".join(argv if argv is not None else sys.argv[1:])
    print(f"# command: python benchmarks/bench_allan.py {cmd}")
    print()

    t0 = time.perf_counter()
    allan_deviation(rng.standard_normal((100, 6)), rate)
    print(f"first call (numba cache load or compile + scipy import): {time.perf_counter() - t0:.3f} s")
    print()

    sizes = [3, 1_000, 10_000, 100_000, 1_000_000] + ([] if args.quick else [2_160_000])
    print("| N (x 6 axes) | taus | splineimu [s] | allantools [s] | ratio | max rel. diff |")
    print("|---:|---:|---:|---:|---:|---:|")
    for n in sizes:
        data = 0.01 * rng.standard_normal((n, 6)) + np.cumsum(1e-4 * rng.standard_normal((n, 6)), axis=0)
        data[:, 5] += 9.81
        m = default_cluster_factors(n)
        taus = m / rate
        reps = 5 if n <= 100_000 else 2
        ours, r = best_of(lambda: allan_deviation(data, rate, taus=taus, threads=args.threads), reps)

        def theirs_fn():
            return [allantools.oadev(data[:, k], rate=rate, data_type="freq", taus=taus)[1] for k in range(6)]

        theirs, ref = best_of(theirs_fn, reps)
        diff = max(float(np.max(np.abs(r.adev[:, k] / ref[k] - 1.0))) for k in range(6))
        assert diff < 1e-9, diff
        print(f"| {n:,} | {m.size} | {ours:.4f} | {theirs:.4f} | {theirs / ours:.1f} | {diff:.1e} |")
    print()

    n = int(3 * 3600 * rate)
    t = np.arange(n) / rate
    g = np.zeros((n, 3))
    a = np.zeros((n, 3))
    a[:, 2] = 9.81
    model = SensorModel("adis16448")
    model.apply(t[:10], g[:10], a[:10], rng=0)  # warm
    gen, meas = best_of(lambda: model.apply(t, g, a, rng=1), 2)
    data = np.hstack([meas.gyro, meas.accel])
    ana, r = best_of(lambda: allan_deviation(data, rate, threads=args.threads), 2)
    fit_t, _ = best_of(lambda: fit_noise_parameters(r), 2)
    print("| 3 h x 200 Hz static, 6 axes (2.16e6 samples) | time [s] |")
    print("|---|---:|")
    print(f"| generation (SensorModel, adis16448) | {gen:.3f} |")
    print(f"| Allan deviation ({r.taus_s.size} taus) | {ana:.3f} |")
    print(f"| noise fit | {fit_t:.3f} |")
    print(f"| total | {gen + ana + fit_t:.3f} |")
    print()
    cli_end_to_end()


def cli_end_to_end():
    """The commands a user runs, each in a fresh process (numba cache warm), best of 2."""
    import subprocess
    import tempfile

    exe = [sys.executable, "-m", "splineimu.cli"]
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "static")
        cmds = [("splineimu scene static --duration 10800 --imu adis16448 -o OUT",
                 exe + ["scene", "static", "--duration", "10800", "--imu", "adis16448", "-o", out, "--force"]),
                ("splineimu allan OUT/mav0/imu0/data.csv",
                 exe + ["allan", os.path.join(out, "mav0", "imu0", "data.csv")])]
        times = []
        for _, cmd in cmds:
            best = np.inf
            for _ in range(2):
                t0 = time.perf_counter()
                subprocess.run(cmd, check=True, capture_output=True)
                best = min(best, time.perf_counter() - t0)
            times.append(best)
        size = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(out) for f in fs)
    print(f"| command line, 3 h x 200 Hz static (output folder {size / 1e6:.0f} MB) | wall [s] |")
    print("|---|---:|")
    for (name, _), t in zip(cmds, times):
        print(f"| `{name}` | {t:.2f} |")
    print(f"| total | {sum(times):.2f} |")


if __name__ == "__main__":
    main()
