"""The rotation ladder's bias readings against a real IMU: how much of each rung-to-rung change
is motion.

The knot choice reads the rotation's bias at each rung of its ladder as the change of the fit's
gyro from the rung below, less the change the noise surrogate makes (spline/ladder.py). With a
real IMU recorded with the poses that change can be split: the part of it that correlates with
the real gyro is motion the coarser knots smooth away, the rest is pose noise (it is in no IMU).
Per rung of the chosen order (fits at the ladder's spacings, alignment as benchmarks/real_pairs.py):

- ``|d|``: RMS of the change of the synthesized gyro from the rung below;
- ``motion``: its part along the real gyro's residual, sqrt(beta) |d| with beta = <d, e> / <d, d>
  (e: real gyro less the rung's synthesized gyro, means removed);
- ``read bias``: what the ladder read (from the report: sqrt(predicted^2 - noise part^2));
- ``noise / drawn``: the rest of the change, (1 - beta) |d|^2, over the noise surrogate's part of
  it (|d|^2 less the bias read): above 1 the surrogate holds too little noise there, and the
  excess is read as bias.

    BROAD_DATA=<folders> PYTHONPATH=$PWD python benchmarks/rung_split.py broad29 broad07

Pair names as benchmarks/real_pairs.py. Prints one table per pair.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import real_pairs as rp  # noqa: E402


def split(pair):
    """Rows (dict) per rung of the chosen rotation order, and the report."""
    from splineimu import fit

    al = rp.align(pair, rp.scipy_motion(pair.t_s, pair.positions, pair.quat_xyzw))
    spl, rep = fit(pair.t_s, pair.positions, pair.quat_xyzw, return_report=True, estimated_rotation=pair.estimated)
    k = rep.order
    ti = pair.imu_t_s[al.mask] + al.offset_s
    real = pair.gyro[al.mask]
    rungs = sorted((c for c in rep.knot_choice["rotation"]["candidates"] if c["order"] == k),
                   key=lambda c: c["knot_spacing_s"])
    gyro = []
    for c in rungs:
        s = fit(pair.t_s, pair.positions, pair.quat_xyzw, order=k, knot_spacing_s=c["knot_spacing_s"],
                reject_outliers=False)
        gyro.append(rp.sensor(rp.spline_motion(s), ti, al.R_bs, al.r_bs)[0])
    rows = []
    for (a, ga), (c, gb) in zip(zip(rungs, gyro), list(zip(rungs, gyro))[1:]):
        d = ga - gb
        d = d - d.mean(axis=0)
        e = real - gb
        e = e - e.mean(axis=0)
        dd = float(np.mean(np.sum(d * d, axis=1)))
        beta = float(np.mean(np.sum(d * e, axis=1))) / dd
        read2 = max(c["predicted_rms"] ** 2 - c["predicted_noise_rms"] ** 2, 0.0)
        drawn = dd - read2
        rows.append({"from_s": a["knot_spacing_s"], "to_s": c["knot_spacing_s"], "change": np.sqrt(dd),
                     "motion": np.sqrt(max(beta, 0.0) * dd), "read_bias": np.sqrt(read2),
                     "noise_over_drawn": (1.0 - beta) * dd / drawn if drawn > 0 else np.inf,
                     "error_vs_imu": rp._rms(e)})
    return rows, rep


def main(names):
    for name in names:
        pair = rp.pair_named(name)
        rows, rep = split(pair)
        print(f"\n{pair.name}: rotation k{rep.order} {rep.knot_spacing_s * 1e3:.1f} ms chosen, noise slope read "
              f"{rep.knot_choice['rotation']['noise_slope']:.2f}\n")
        print("| rung [ms] | \\|d\\| [rad/s] | motion | read bias | noise / drawn | gyro error vs real IMU |")
        print("| --- | ---: | ---: | ---: | ---: | ---: |")
        for r in rows:
            print(f"| {r['from_s'] * 1e3:.1f} -> {r['to_s'] * 1e3:.1f} | {r['change']:.4f} | {r['motion']:.4f} | "
                  f"{r['read_bias']:.4f} | {r['noise_over_drawn']:.2f} | {r['error_vs_imu']:.4f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
