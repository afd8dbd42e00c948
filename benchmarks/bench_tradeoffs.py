"""Accuracy against cost of every knob: spline order and knot spacing (clean and noisy input),
sampling mode and integration method (round trip), with a Pareto plot.

Input: the lecture ellipse (DESIGN.md section 4), 60 s at 200 Hz, exact poses and poses with
1 mm / 0.1 deg noise. Errors are RMS over the interior [1, 59] s against the exact derivatives.

    python benchmarks/bench_tradeoffs.py       # prints tables, writes results/pareto.png
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def _rms(e):
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def spline_tradeoffs():
    from splineimu import fit, lie
    from splineimu.scenes import make_scene

    sc = make_scene("ellipse", duration_s=60.0)
    t = np.arange(0, 60.0 + 1e-9, 0.005)
    k = sc.kinematics(t)
    rng = np.random.default_rng(0)
    noisy_p = k.position_world + 1e-3 * rng.normal(size=k.position_world.shape)
    noisy_q = lie.matrix_to_quat_xyzw(k.world_R_body @ lie.so3_exp(np.radians(0.1) * rng.normal(size=(t.size, 3))))
    inputs = {"clean": (k.position_world, k.quat_xyzw), "noisy": (noisy_p, noisy_q)}
    te = np.arange(1.0, 59.0, 0.005)
    g0, f0 = sc.imu(te)
    rows = []
    fit(t[:2000], k.position_world[:2000], k.quat_xyzw[:2000])  # warm
    for name, (p, q) in inputs.items():
        for order in (4, 5, 6):
            for ks in ("auto", 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5):
                c0 = time.process_time()
                spl, rep = fit(t, p, q, order=order, knot_spacing_s=ks, return_report=True)
                cfit = time.process_time() - c0
                c0 = time.process_time()
                g, f = spl.imu(te)
                ceval = time.process_time() - c0
                rows.append(dict(input=name, order=order, knot=ks, dt=rep.knot_spacing_s, fit_s=cfit,
                                 eval_s=ceval, gyro=_rms(g - g0), accel=_rms(f - f0)))
        c0 = time.process_time()
        spl, rep = fit(t, p, q, return_report=True)
        cfit = time.process_time() - c0
        g, f = spl.imu(te)
        rows.append(dict(input=name, order=f"auto ({rep.order})", knot="auto", dt=rep.knot_spacing_s, fit_s=cfit,
                         eval_s=0.0, gyro=_rms(g - g0), accel=_rms(f - f0)))
    return rows


def roundtrip_tradeoffs():
    """60 s noise-free ellipse at 200 Hz: sampling mode x integration method."""
    from splineimu.integrate import NavState, integrate
    from splineimu.pipeline import synthesize
    from splineimu.scenes import make_scene
    from splineimu.timegrid import uniform_stamps_ns

    sc = make_scene("ellipse", duration_s=60.0)
    t_ns = uniform_stamps_ns(0, 60_000_000_000, 200)
    t = t_ns / 1e9
    truth = sc.kinematics(t)
    rows = []
    for sampling in ("point", "mean"):
        syn = synthesize(sc, t_ns, sampling=sampling)
        init = NavState.from_motion(sc, t[0])
        for method in ("euler", "midpoint", "rk4"):
            c0 = time.process_time()
            tr = integrate(t, syn.gyro_rad_s, syn.accel_m_s2, init, method=method)
            cs = time.process_time() - c0
            err = np.linalg.norm(tr.position_world - truth.position_world, axis=1)
            rows.append(dict(sampling=sampling, method=method, final_m=float(err[-1]),
                             rms_m=float(np.sqrt(np.mean(err**2))), cpu_s=cs, rate=t.size / max(cs, 1e-9)))
    return rows


def pareto_plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    for ax, name in zip(axes, ("clean", "noisy")):
        for order, marker in ((4, "o"), (5, "s"), (6, "^")):
            sel = [r for r in rows if r["input"] == name and r["order"] == order and r["knot"] != "auto"]
            ax.loglog([r["fit_s"] + r["eval_s"] for r in sel], [r["accel"] for r in sel], marker, ls="-",
                      label=f"order {order}")
            for r in sel:
                ax.annotate(f"{r['dt'] * 1e3:.0f}", (r["fit_s"] + r["eval_s"], r["accel"]), fontsize=6)
        auto = [r for r in rows if r["input"] == name and str(r["order"]).startswith("auto")]
        ax.loglog([r["fit_s"] for r in auto], [r["accel"] for r in auto], "k*", ms=14, label="auto (order, spacing)")
        ax.set_title(f"{name} poses: accelerometer error vs cost (labels: knot spacing [ms])")
        ax.set_xlabel("fit + evaluation CPU time [s]")
        ax.set_ylabel("accel RMS error [m/s$^2$]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    rows = spline_tradeoffs()
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    pareto_plot(rows, out / "pareto.png")
    print("## Spline order and knot spacing (ellipse, 60 s, 200 Hz poses)\n")
    print("| input | order | knot spacing | fit CPU [s] | gyro RMS [rad/s] | accel RMS [m/s^2] |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for r in rows:
        ks = f"auto ({r['dt'] * 1e3:.1f} ms)" if r["knot"] == "auto" else f"{r['dt'] * 1e3:.1f} ms"
        print(f"| {r['input']} | {r['order']} | {ks} | {r['fit_s']:.3f} | {r['gyro']:.2e} | {r['accel']:.2e} |")
    print("\n## Round trip: sampling mode x integration method (noise-free ellipse, 60 s, 200 Hz)\n")
    print("| sampling | method | final position error [m] | RMS position error [m] | CPU [s] | samples/s |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for r in roundtrip_tradeoffs():
        print(f"| {r['sampling']} | {r['method']} | {r['final_m']:.2e} | {r['rms_m']:.2e} | {r['cpu_s']:.3f} | "
              f"{r['rate']:.2e} |")
    print("\n![pareto](pareto.png)")


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    main()
