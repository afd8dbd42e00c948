"""The automatic fit on motions it was not tuned on: random sums of sines, exact truth.

The knot choice was tuned on the analytic scenes (ellipse, circle, screw, flips, six-position,
rate-table). This draws other motions (ZYX Euler angles and positions as sums of sines, exact
derivatives through ``splineimu.scenes.kinematics``), adds white, AR(1) (30 ms) or upsampled pose
noise (as tests/fit_scenes.py) or resamples noisy poses from half the rate (``interpolated``),
and compares the automatic fit with the best of a fixed grid (orders 4-6 x 19 spacings 5 ms-2.56
s, one spacing for rotation and position) per quantity:
gyro against the best-gyro setting, accelerometer against the best-accel one, plus the predicted
error over the measured one. Errors are RMS over [1 s, end - 1 s] at 200 Hz.

    PYTHONPATH=$PWD python benchmarks/heldout_motions.py                      # 30 cases, ~15 min
    PYTHONPATH=$PWD python benchmarks/heldout_motions.py --cache /tmp/grid    # the grid kept: ~1 min again
    PYTHONPATH=$PWD python benchmarks/heldout_motions.py --motions fasthand --kinds white --rate 20 \\
        --noise 2e-4 0.02

Motions (each drawn twice, ``--draws``): ``hand`` (angles 0.1-2.5 Hz, ~1.5 rad/s; positions
0.05-1.5 Hz, 0.3 m), ``fasthand`` (angles to 4 Hz and 4 rad/s, a slow yaw ramp; positions to
3 Hz), ``drone`` (small tilts, slow yaw, a 2 m figure of eight), ``car`` (yaw within 1.5 rad,
loops of 60 m), ``slow`` (0.02-0.3 Hz drift).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from fit_scenes import fixed_grid_errors, noise, scene_errors  # noqa: E402  (the tests' pose noise kinds)

from splineimu import fit, lie  # noqa: E402
from splineimu.scenes.base import Scene  # noqa: E402
from splineimu.scenes.kinematics import euler_zyx_kinematics, sum_of_sines  # noqa: E402

MOTIONS = ("hand", "fasthand", "drone", "car", "slow")


def _tables(motion, draw):
    """(angle sines per axis, yaw-ramp rates, position sines per axis) of a motion's draw."""
    r = np.random.default_rng(1000 + draw)

    def sines(n, fmin, fmax, rate=None, amp=None):
        rows = []
        for _ in range(n):
            w = 2 * np.pi * r.uniform(fmin, fmax)
            a = (rate / w if rate is not None else amp) * r.uniform(0.3, 1.0)
            rows.append((a, w, r.uniform(0, 2 * np.pi)))
        return tuple(rows)

    if motion == "hand":
        ang, ramp = [sines(3, 0.1, 2.5, rate=1.5) for _ in range(3)], (0.0, 0.0, 0.0)
        pos = [sines(3, 0.05, 1.5, amp=0.3) for _ in range(3)]
    elif motion == "fasthand":
        ang, ramp = [sines(4, 0.2, 4.0, rate=4.0) for _ in range(3)], (0.0, 0.0, r.uniform(-1, 1))
        pos = [sines(4, 0.1, 3.0, amp=0.15) for _ in range(3)]
    elif motion == "drone":
        ang = [sines(2, 0.2, 1.0, amp=0.12), sines(2, 0.2, 1.0, amp=0.12), sines(2, 0.02, 0.2, amp=1.0)]
        ramp = (0.0, 0.0, 0.2)
        pos = [sines(2, 0.05, 0.3, amp=2.0), sines(2, 0.05, 0.3, amp=2.0), sines(2, 0.1, 0.5, amp=0.4)]
    elif motion == "car":
        ang = [sines(2, 0.3, 2.0, amp=0.02), sines(2, 0.3, 2.0, amp=0.02), sines(3, 0.01, 0.1, amp=1.5)]
        ramp = (0.0, 0.0, 0.1)
        pos = [sines(3, 0.005, 0.05, amp=60.0), sines(3, 0.005, 0.05, amp=60.0), sines(2, 0.1, 1.0, amp=0.05)]
    elif motion == "slow":
        ang, ramp = [sines(2, 0.02, 0.3, amp=0.5) for _ in range(3)], (0.0, 0.0, 0.0)
        pos = [sines(2, 0.02, 0.3, amp=0.5) for _ in range(3)]
    else:
        raise SystemExit(f"unknown motion {motion!r}; one of {', '.join(MOTIONS)}")
    return ang, ramp, pos


class SumOfSines(Scene):
    """A motion of :func:`_tables` (not registered: a benchmark's own)."""

    name = "sum-of-sines"
    DEFAULT_DURATION_S = 60.0

    def _evaluate(self, t):
        ang_t, ramp, pos_t = self.tables
        n = t.shape[0]
        ang, rates, accs, p, v, a = (np.empty((n, 3)) for _ in range(6))
        for i in range(3):
            x, dx, ddx = sum_of_sines(t, ang_t[i])
            ang[:, i], rates[:, i], accs[:, i] = ramp[i] * t + x, ramp[i] + dx, ddx
            p[:, i], v[:, i], a[:, i] = sum_of_sines(t, pos_t[i])
        R, w, al = euler_zyx_kinematics(ang, rates, accs)
        return p, v, a, R, w, al


def _interpolated(scene, t, pos_noise_m, angle_noise_rad, rng):
    """Positions and quaternions at ``t`` from noisy poses at every other instant: positions
    interpolated linearly, rotations along the geodesic (as an exported trajectory resampled
    to a higher rate)."""
    coarse = t[::2]
    k = scene.kinematics(coarse)
    pc = k.position_world + pos_noise_m * rng.normal(size=(coarse.size, 3))
    Rc = k.world_R_body @ lie.so3_exp(angle_noise_rad * rng.normal(size=(coarse.size, 3)))
    p = np.column_stack([np.interp(t, coarse, pc[:, j]) for j in range(3)])
    i = np.minimum(np.searchsorted(coarse, t, side="right") - 1, coarse.size - 2)
    u = ((t - coarse[i]) / (coarse[i + 1] - coarse[i]))[:, None]
    step = lie.so3_log(np.swapaxes(Rc[i], 1, 2) @ Rc[i + 1])
    return p, lie.matrix_to_quat_xyzw(Rc[i] @ lie.so3_exp(u * step))


def case(motion, draw, kind, rate, pos_noise_m, angle_noise_deg, duration=60.0, seed=1, cache=None):
    """One row: auto / best fixed per quantity, predicted / measured, the choice and warnings."""
    scene = SumOfSines(duration_s=duration)
    scene.tables = _tables(motion, draw)
    t = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    rng = np.random.default_rng(seed)
    if kind == "interpolated":  # poses (motion and white noise) at half the rate, interpolated
        p, q = _interpolated(scene, t, pos_noise_m, np.radians(angle_noise_deg), rng)
    else:
        k = scene.kinematics(t)
        p = k.position_world + noise(kind, t.size, rate, pos_noise_m, rng)
        R = k.world_R_body @ lie.so3_exp(noise(kind, t.size, rate, np.radians(angle_noise_deg), rng))
        q = lie.matrix_to_quat_xyzw(R)
    path = None if cache is None else (Path(cache) / f"{motion}{draw}_{kind}_{rate:g}_{pos_noise_m:g}_"
                                       f"{angle_noise_deg:g}_{duration:g}_{seed}.npy")
    grid = fixed_grid_errors(scene, t, p, q, duration, path)
    spl, rep = fit(t, p, q, return_report=True)
    g, a = scene_errors(scene, spl, duration)
    return {"case": f"{motion}{draw} {kind}", "gyro/best": g / grid[:, 0].min(),
            "accel/best": a / grid[:, 1].min(), "pred/meas gyro": rep.predicted_gyro_rms_rad_s / g,
            "pred/meas accel": rep.predicted_accel_rms_m_s2 / a,
            "rotation": f"k{rep.order} {1e3 * rep.knot_spacing_s:.0f} ms",
            "position": f"k{rep.position_order} {1e3 * rep.position_knot_spacing_s:.0f} ms",
            "warnings": ", ".join(sorted({w.code for w in rep.warnings})) or "-"}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--motions", nargs="+", default=list(MOTIONS), choices=MOTIONS)
    ap.add_argument("--draws", nargs="+", type=int, default=[1, 2])
    ap.add_argument("--kinds", nargs="+", default=["white", "ar1", "upsampled"],
                    choices=["white", "ar1", "upsampled", "interpolated"],
                    help="pose noise: white, AR(1) 30 ms, drawn at half the rate and interpolated (upsampled), or "
                         "whole poses at half the rate with white noise, interpolated (interpolated)")
    ap.add_argument("--rate", type=float, default=200.0, help="pose rate [Hz] (default 200)")
    ap.add_argument("--duration", type=float, default=60.0, help="seconds of poses (default 60)")
    ap.add_argument("--noise", nargs=2, type=float, default=[1e-3, 0.1], metavar=("M", "DEG"),
                    help="pose noise per axis: position [m] and angle [deg] (default 1e-3 0.1)")
    ap.add_argument("--cache", default=None,
                    help="folder keeping the fixed grid's errors between runs (they do not depend on the choice)")
    args = ap.parse_args(argv)
    keys = ["case", "gyro/best", "accel/best", "pred/meas gyro", "pred/meas accel", "rotation", "position", "warnings"]
    print(f"{args.rate:g} Hz, {args.noise[0]:g} m / {args.noise[1]:g} deg pose noise, {args.duration:g} s\n")
    print("| " + " | ".join(keys) + " |\n|" + " --- |" * len(keys))
    for motion in args.motions:
        for draw in args.draws:
            for kind in args.kinds:
                row = case(motion, draw, kind, args.rate, *args.noise, duration=args.duration, cache=args.cache)
                print("| " + " | ".join(f"{row[k]:.3f}" if isinstance(row[k], float) else row[k] for k in keys) + " |",
                      flush=True)


if __name__ == "__main__":
    main()
