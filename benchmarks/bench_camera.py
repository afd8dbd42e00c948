"""Camera observations per second: landmarks x cameras on the analytic ellipse and on a spline.

Two cameras as in issue 18's acceptance set-up: cam0 pinhole-radtan global shutter (EuRoC's
intrinsics, 20 Hz, +5 ms time shift) and cam1 equidistant rolling shutter (TUM-VI's
intrinsics, 20 Hz, 30 us per row, -3 ms time shift), landmarks in a shell around the
trajectory, 20 s of motion. Sizes 1 .. 10,000 landmarks. Baseline in the same process: the
global-shutter camera done with OpenCV (poses per frame, ``cv2.projectPoints`` of every
landmark, depth and image-bounds mask), when OpenCV is installed. Also the first call in a
fresh process (compiling the row-search kernel, or loading it from numba's cache) and the
import cost of ``splineimu`` with and without the camera package.

    python benchmarks/bench_camera.py            # writes benchmarks/results/camera.md
    python benchmarks/bench_camera.py --quick
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

CAM_T_IMU = [[0.0, -1.0, 0.0, 0.05], [0.0, 0.0, -1.0, -0.01], [1.0, 0.0, 0.0, 0.02], [0.0, 0.0, 0.0, 1.0]]
CAM_T_IMU_SIDE = [[1.0, 0.0, 0.0, -0.05], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]


def cameras():
    from splineimu.camera import Camera

    cam0 = Camera((458.654, 457.296, 367.215, 248.375), (752, 480), "radtan",
                  (-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05), cam_T_imu=CAM_T_IMU, rate_hz=20.0,
                  timeshift_cam_imu_s=0.005, pixel_noise_px=1.0, name="cam0")
    cam1 = Camera((190.978, 190.973, 254.932, 256.897), (512, 512), "equidistant",
                  (0.00348239, 0.00071503, -0.00205324, 0.00020294), cam_T_imu=CAM_T_IMU_SIDE, rate_hz=20.0,
                  timeshift_cam_imu_s=-0.003, line_delay_s=3e-5, pixel_noise_px=1.0, name="cam1")
    return cam0, cam1


def spline_source(scene):
    """A cubic split spline whose control poses are the scene's poses every 0.05 s."""
    from splineimu import Spline

    dt = 0.05
    t = np.arange(-dt, scene.t_max_s + 3 * dt, dt)
    pos, quat = scene.pose(np.clip(t, scene.t_min_s, scene.t_max_s))
    return Spline.from_control_points(t[0], dt, pos, quat, kind="split", order=4)


def best_time(fn, repeat=3):
    out = fn()
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def opencv_global_shutter(source, cam, points):
    """The same observations of a global-shutter camera with OpenCV (None without OpenCV)."""
    try:
        import cv2
    except ImportError:
        return None
    from splineimu.camera.observations import _cam_from_world, _frame_times_s, frame_stamps_ns

    def run():
        frames = frame_stamps_ns(source, cam)
        R, t = _cam_from_world(source, cam.cam_T_imu, _frame_times_s(source, cam, frames))
        K, D = cam.camera_matrix, np.array(cam.distortion_coeffs)
        n = 0
        for Rf, tf in zip(R, t):
            rvec, _ = cv2.Rodrigues(Rf)
            uv, _ = cv2.projectPoints(points.reshape(-1, 1, 3), rvec, tf, K, D)
            uv = uv.reshape(-1, 2)
            n += int(np.count_nonzero((points @ Rf[2] + tf[2] > 0) & cam.in_image(uv[:, 0], uv[:, 1])))
        return n

    return run


def first_call_times():
    code = ("import time; t=time.perf_counter();"
            "from splineimu.scenes import make_scene; from splineimu.camera import Landmarks, observe;"
            "from benchmarks.bench_camera import cameras; s=make_scene('ellipse', duration_s=1.0);"
            "observe(s, cameras(), Landmarks.random(100, source=s, rng=0), rng=0);"
            "print(time.perf_counter()-t)")
    env = dict(os.environ, PYTHONPATH=str(HERE.parent))

    def once(extra):
        out = subprocess.run([sys.executable, "-c", code], env=dict(env, **extra), capture_output=True, text=True,
                             check=True, cwd=HERE.parent)
        return float(out.stdout.strip())

    cold = once({"SPLINEIMU_NO_CACHE": "1"})
    once({})  # fill the cache
    warm = once({})
    imp = ("import time, sys; t=time.perf_counter(); import splineimu, splineimu.scenes, splineimu.motion; "
           "a=time.perf_counter()-t; c=any(m.startswith('splineimu.camera') for m in sys.modules); "
           "t=time.perf_counter(); import splineimu.camera; print(a, c, time.perf_counter()-t)")
    a, loaded, b = subprocess.run([sys.executable, "-c", imp], env=env, capture_output=True, text=True,
                                  check=True).stdout.split()
    return cold, warm, float(a), loaded == "True", float(b)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="5 s of motion, fewer sizes")
    args = ap.parse_args(argv)
    import numba

    from splineimu.camera import Landmarks, observe
    from splineimu.scenes import make_scene

    numba.set_num_threads(1)
    duration = 5.0 if args.quick else 20.0
    sizes = [1, 100, 1000] if args.quick else [1, 100, 1000, 10_000]
    scene = make_scene("ellipse", duration_s=duration)
    sources = {"ellipse (analytic)": scene, "cubic split spline": spline_source(scene)}
    cam0, cam1 = cameras()
    rows = []
    for src_name, source in sources.items():
        for m in sizes:
            lm = Landmarks.random(m, source=scene, radii_m=(3.0, 30.0), rng=1)
            for label, cams in (("cam0 radtan global", [cam0]), ("cam1 equidistant rolling", [cam1]),
                                ("both", [cam0, cam1])):
                d, obs = best_time(lambda cams=cams, lm=lm, source=source: observe(source, cams, lm, rng=0))
                n = sum(len(o) for o in obs.values())
                frames = sum(o.frame_t_ns.size for o in obs.values())
                row = dict(source=src_name, m=m, cams=label, n=n, frames=frames, s=d, rate=n / d,
                           pairs=m * frames / d)
                if label.startswith("cam0"):
                    base = opencv_global_shutter(source, cam0, lm.position_world)
                    if base is not None:
                        b, nb = best_time(base)
                        assert nb == n, (nb, n)
                        row.update(cv_s=b, ratio=b / d)
                rows.append(row)
                extra = f"  OpenCV {row['cv_s']:8.4f} s  x{row['ratio']:5.1f}" if "cv_s" in row else ""
                print(f"{src_name:20s} M={m:>6d} {label:25s} {n:>9d} obs in {frames:5d} frames  {d:8.4f} s "
                      f"{n / d:10.3e} obs/s{extra}", flush=True)
    cold, warm, imp, loaded, imp_cam = first_call_times()
    load = os.getloadavg()
    lines = [
        "# Camera observations per second",
        "",
        f"Made by `python benchmarks/bench_camera.py{' --quick' if args.quick else ''}` on {platform.machine()} with "
        f"{os.cpu_count()} CPUs shared with other work (load average {load[0]:.1f} at the end), one thread, "
        f"Python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}. "
        f"{duration:g} s of motion; landmarks uniform in a shell of radii 3-30 m around the trajectory's centre; "
        "pixel noise 1 px. cam0: EuRoC radtan, 752x480, global shutter, 20 Hz. cam1: TUM-VI equidistant, "
        "512x512, rolling shutter 30 us/row (15 ms readout), 20 Hz. Times are the best of 3 runs of "
        "`observe(...)` (frames, poses, visibility, row solve, noise). Wall times grow with the machine's load: "
        "read the OpenCV column (timed in the same process) as the ratio.",
        "",
        "| source | landmarks | cameras | observations | frames | seconds | observations/s "
        "| landmark-frames/s | OpenCV global shutter [s] | speed-up vs OpenCV |",
        "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        cv = f"{r['cv_s']:.4f} | x{r['ratio']:.1f}" if "cv_s" in r else "- | -"
        lines.append(f"| {r['source']} | {r['m']} | {r['cams']} | {r['n']} | {r['frames']} | {r['s']:.4f} "
                     f"| {r['rate']:.3e} | {r['pairs']:.3e} | {cv} |")
    lines += [
        "",
        "The OpenCV baseline does the global-shutter camera's work per frame with `cv2.projectPoints` on "
        "every landmark (same poses, same visibility rule, same count of observations, no noise).",
        "",
        "| first call / import (fresh process) | seconds |",
        "| --- | ---: |",
        "| import + observe 100 landmarks x 2 cameras, compiling every kernel it uses (numba cache off) "
        f"| {cold:.2f} |",
        f"| the same with numba's cache warm | {warm:.2f} |",
        f"| `import splineimu, splineimu.scenes, splineimu.motion` | {imp:.3f} |",
        f"| ... loads `splineimu.camera` | {'yes' if loaded else 'no'} |",
        f"| `import splineimu.camera` on top | {imp_cam:.3f} |",
        "",
    ]
    out = HERE / "results" / "camera.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines))
    print(out.read_text())


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    main()
