"""How well the knot choice's ladder predicts the gyro error, rung by rung, on an analytic scene.

For one scene, pose-noise kind, rate and seed (tests/fit_scenes.py, 60 s, 1 mm / 0.1 deg), the
automatic fit's rotation candidates (every (order, spacing) rung of its ladder) against the truth:

- ``pred``: the rung's predicted gyro error; ``true``: the gyro error of the fit at that rung
  (RMS over [1 s, 59 s] against the scene's exact rate);
- ``noise est`` / ``noise``: the predicted noise part against sqrt(true^2 - bias^2);
- ``bias est`` / ``bias``: the predicted bias part (sqrt(pred^2 - noise est^2)) against the gyro
  error of the same fit to the exact poses;
- ``proxy bias``: the bias of the signal the choice fits for the rotation (an ordinary B-spline
  through the accumulated body-frame increments of the exact poses, against the same fit at an
  eighth of the spacing), and ``SO3 / proxy``: how much more bias the cumulative SO3 spline has.
  Turns about moving axes give the SO3 spline more bias than its proxy (lecture ellipse at
  0.8-1.6 s: 1.1-2.4x); turns about fixed axes (rate-table) do not (1.00).

    PYTHONPATH=$PWD python benchmarks/ladder_accuracy.py rate-table white --rate 100 --seed 1
    PYTHONPATH=$PWD python benchmarks/ladder_accuracy.py ellipse ar1 --orders 5 6

No timing; prints a table.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from fit_scenes import gyro_error, scene_poses  # noqa: E402

from splineimu import fit, lie  # noqa: E402
from splineimu.spline.crossval import _windows  # noqa: E402
from splineimu.spline.signals import anchor_block, rotation_increments  # noqa: E402

DURATION_S = 60.0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("kind", choices=["white", "ar1", "upsampled"])
    ap.add_argument("--rate", type=float, default=200.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--scale", type=float, default=1.0, help="pose noise in units of 1 mm / 0.1 deg")
    ap.add_argument("--orders", nargs="+", type=int, default=[4, 5, 6])
    args = ap.parse_args(argv)
    sc, t, p, R = scene_poses(args.scene, args.kind, DURATION_S, args.rate, args.seed, args.scale)
    q = lie.matrix_to_quat_xyzw(R)
    exact = sc.kinematics(t)
    q_exact = lie.matrix_to_quat_xyzw(exact.world_R_body)
    inside = (t > 1.0) & (t < DURATION_S - 1.0)
    error = gyro_error(sc, DURATION_S)

    def at(k, dt, P, Q):  # the rotation at (k, dt); the position grid coarse (it does not touch the gyro)
        return fit(t, P, Q, order=k, knot_spacing_s=dt, position_order=4, position_knot_spacing_s=10.0,
                   reject_outliers=False)

    block = anchor_block(t, rotation_increments(R))  # (as the choice develops the noisy rotations)
    (proxy,) = _windows(t, rotation_increments(exact.world_R_body, block), np.ones(t.size), True)
    spl, rep = fit(t, p, q, return_report=True)
    c = rep.knot_choice["rotation"]
    print(f"{args.scene} {args.kind}, {args.rate:g} Hz, seed {args.seed}, {args.scale:g} x 1 mm / 0.1 deg: auto "
          f"k{rep.order} {1e3 * rep.knot_spacing_s:.1f} ms, gyro {error(spl):.5f} rad/s (predicted "
          f"{rep.predicted_gyro_rms_rad_s:.5f}); noise slope {c['noise_slope']}, bias correction "
          f"{c['bias_correction']}, value-optimal {1e3 * c['cv_knot_spacing_s']:.1f} ms\n")
    print("| rung | pred | true | pred/true | noise est | noise | bias est | bias | proxy bias | SO3 / proxy |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for row in sorted(c["candidates"], key=lambda r: (r["order"], r["knot_spacing_s"])):
        k, dt = row["order"], row["knot_spacing_s"]
        if k not in args.orders:
            continue
        total = error(at(k, dt, p, q))
        bias = error(at(k, dt, exact.position_world, q_exact))
        noise = float(np.sqrt(max(total**2 - bias**2, 0.0)))
        d = proxy.derivative(k, dt, proxy.zero, 1, 1)[0][inside].copy()
        ref = proxy.derivative(k, dt / 8.0, proxy.zero, 1, 1)[0][inside]
        pb = float(np.sqrt(np.mean(np.sum((d - ref) ** 2, axis=1))))
        pred, pn = row["predicted_rms"], row["predicted_noise_rms"]
        bias_est = float(np.sqrt(max(pred**2 - pn**2, 0.0)))
        print(f"| k{k} {1e3 * dt:.1f} ms | {pred:.5f} | {total:.5f} | {pred / total:.2f} | {pn:.5f} | {noise:.5f} | "
              f"{bias_est:.5f} | {bias:.5f} | {pb:.5f} | {bias / pb if pb > 0 else float('nan'):.2f} |")


if __name__ == "__main__":
    main()
