"""The ``splineimu from-tum`` command against a plain scipy + ``np.savetxt`` script, as processes.

    python benchmarks/bench_cli.py              # about 1-2 minutes on the 2-core machine
    python benchmarks/bench_cli.py --reps 7 --write

Input: the lecture ellipse's exact poses, 60 s at 200 Hz (12 001 poses, a TUM file). Both
programs read it and write the same three files: the IMU csv (EuRoC layout), the ground-truth
csv (EuRoC columns, velocity and zero biases) and the ground truth as a TUM file.

- ours: ``splineimu from-tum POSES -o OUT`` (noise-free, automatic order and knots); it also
  writes the yaml files and report.json of its output folder.
- scipy: the script in :func:`baseline` (``python bench_cli.py --baseline POSES OUT``):
  ``np.loadtxt``, scipy ``RotationSpline`` + ``CubicSpline`` through the poses, gyro (body rate)
  and specific force at 200 Hz, ``np.savetxt`` with ``"%.17g"``.

Each is timed as a child process: its CPU time (user + system, ``RUSAGE_CHILDREN``), best of
``--reps`` interleaved repetitions (the order alternates), ``NUMBA_NUM_THREADS=1``, after one
untimed run of each (the numba cache and Python's bytecode cache are warm, as after a user's
first run; ``PYTHONDONTWRITEBYTECODE`` is removed from the children's environment). Every run
writes into a new folder.

The breakdown of our command comes from two more kinds of child runs (best of ``--reps`` for
each phase): ``python -X importtime`` (the sum of the top-level imports, lazy ones included: the
import time of the whole command, as importtime counts it) and an instrumented run
(``--phases``): the CLI's ``main`` in a fresh process with timers (CPU time) around the reader,
the fit, the synthesis (the stream's pieces) and the writer, and a count of the numba kernels
loaded from the cache (or compiled). Two more child processes give the floor that any run of
the command pays: the interpreter with numpy, scipy.linalg and numba imported, and that plus
one call of a cached kernel (numba's start-up). Writes the table to stdout and, with ``--write``, to
benchmarks/results/cli.md.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
#: the splineimu checkout timed (``--tree``; default: this one)
TREE = ROOT
RATE_HZ = 200.0
DURATION_S = 60.0
EUROC_IMU_HEADER = ("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]")
EUROC_GT_HEADER = ("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
                   "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
                   "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
                   "b_a_RS_S_z [m s^-2]")


def baseline(poses: str, out: str) -> dict:
    """The plain script: what one writes with scipy and numpy alone (its own phase CPU times returned)."""
    t0 = time.process_time()
    import numpy as np
    from scipy.interpolate import CubicSpline
    from scipy.spatial.transform import Rotation, RotationSpline

    t1 = time.process_time()
    d = np.loadtxt(poses)
    t_ns = np.round(d[:, 0] * 1e9).astype(np.int64)  # (float64 stamps: to ~0.2 us, as a plain script has them)
    t_s = (t_ns - t_ns[0]) * 1e-9
    rot = RotationSpline(t_s, Rotation.from_quat(d[:, 4:8]))
    pos = CubicSpline(t_s, d[:, 1:4])
    n = int(np.floor(t_s[-1] * RATE_HZ + 1e-9)) + 1
    k = np.arange(n)
    imu_ns = t_ns[0] + (k * 1_000_000_000) // int(RATE_HZ)
    ti = k / RATE_HZ
    R = rot(ti)
    gyro = rot(ti, 1)  # the body rate (checked against splineimu's, see _check)
    accel = R.inv().apply(pos(ti, 2) - np.array([0.0, 0.0, -9.81]))
    p, v, q = pos(ti), pos(ti, 1), R.as_quat()
    t2 = time.process_time()
    os.makedirs(f"{out}/mav0/imu0", exist_ok=True)
    os.makedirs(f"{out}/mav0/state_groundtruth_estimate0", exist_ok=True)
    np.savetxt(f"{out}/mav0/imu0/data.csv", np.column_stack([imu_ns, gyro, accel]), delimiter=",",
               fmt=["%d"] + ["%.17g"] * 6, header=EUROC_IMU_HEADER[1:], comments="#")
    gt = np.column_stack([imu_ns, p, q[:, [3, 0, 1, 2]], v, np.zeros((n, 6))])
    np.savetxt(f"{out}/mav0/state_groundtruth_estimate0/data.csv", gt, delimiter=",",
               fmt=["%d"] + ["%.17g"] * 16, header=EUROC_GT_HEADER[1:], comments="#")
    sec, frac = np.divmod(imu_ns, 1_000_000_000)
    np.savetxt(f"{out}/groundtruth.tum", np.column_stack([sec, frac, p, q]), fmt="%d.%09d" + " %.17g" * 7,
               header="timestamp tx ty tz qx qy qz qw")
    t3 = time.process_time()
    return {"imports": t1 - t0, "compute": t2 - t1, "write": t3 - t2}


def make_poses(path: Path) -> int:
    """The lecture ellipse's exact poses, 60 s at 200 Hz, stamped at a Unix epoch start."""
    from splineimu import lie
    from splineimu.io.tum import write_tum
    from splineimu.scenes import make_scene

    scene = make_scene("ellipse", duration_s=DURATION_S, t0_ns=1_700_000_000_000_000_000)
    t_ns = scene.sample_times_ns(RATE_HZ)
    k = scene.kinematics(scene.t_s_from_ns(t_ns))
    write_tum(path, t_ns, k.position_world, lie.quat_make_continuous(lie.matrix_to_quat_xyzw(k.world_R_body)))
    return int(t_ns.size)


#: the floor of any run: the interpreter with the libraries every command imports, and numba's
#: start-up on the first call of a kernel from the cache
FLOOR = "import numpy, scipy.linalg, numba"
FLOOR_KERNEL = FLOOR + "; from splineimu import lie; lie.quat_xyzw_to_matrix(numpy.array([[0.0, 0.0, 0.0, 1.0]]))"


def _env() -> dict:
    # bytecode is written and used, as in an installed package (pip compiles it): with
    # PYTHONDONTWRITEBYTECODE set and no __pycache__ (a fresh checkout), every run of the
    # command would compile each splineimu module from source (0.1-0.15 s of CPU, measured)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return dict(env, PYTHONPATH=str(TREE), NUMBA_NUM_THREADS="1")


def ours_cmd(poses, out) -> list:
    return [sys.executable, "-m", "splineimu", "from-tum", str(poses), "-o", str(out)]


def baseline_cmd(poses, out) -> list:
    return [sys.executable, str(Path(__file__).resolve()), "--baseline", str(poses), str(out)]


def child_cpu(cmd) -> tuple[float, str]:
    """CPU time (user + system) of one child process, and its stdout."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    # run in the timed tree: ``python -m`` puts the working directory before PYTHONPATH
    res = subprocess.run(cmd, env=_env(), capture_output=True, text=True, cwd=TREE)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{res.stderr[-3000:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), res.stdout


def import_time(cmd) -> float:
    """Seconds of imports as ``-X importtime`` counts them (the sum of the top-level imports)."""
    res = subprocess.run([cmd[0], "-X", "importtime", *cmd[1:]], env=_env(), capture_output=True, text=True,
                         cwd=TREE)
    total = 0
    for line in res.stderr.splitlines():
        if not line.startswith("import time:") or "[us]" in line:
            continue
        _, cum, name = line.split("|")
        if not name.startswith("  "):  # top level: one space after the bar
            total += int(cum)
    return total / 1e6


def phases(poses: str, out: str) -> dict:
    """Run the CLI in this (fresh) process with CPU timers around its phases."""
    import contextlib

    try:  # the command imports with the cyclic garbage collector paused: so do these imports
        from splineimu.commands._common import start_up
    except ImportError:  # a tree from before it
        start_up = contextlib.nullcontext
    acc = {"read": 0.0, "fit": 0.0, "synthesis": 0.0, "write_output": 0.0, "numba_dispatch": 0.0}
    loads = []
    with start_up():
        main = _instrumented(acc, loads)
    t_main = time.process_time()
    rc = main(["from-tum", poses, "-o", out, "--force"])
    t_end = time.process_time()
    assert rc == 0
    return {**acc, "total": t_end, "main": t_end - t_main,
            "numba_kernels": len(loads), "numba_compiled": [n for n, miss in loads if miss]}


def _instrumented(acc, loads):
    """The CLI's ``main`` with timers (CPU seconds into ``acc``) and numba's loads counted."""
    from numba.core import dispatcher

    cpu = time.process_time

    def timed(key, f):
        def wrapper(*a, **k):
            t = cpu()
            try:
                return f(*a, **k)
            finally:
                acc[key] += cpu() - t
        return wrapper

    compile_for_args = dispatcher.Dispatcher._compile_for_args

    def counted(self, *a, **k):
        misses = sum(self._cache_misses.values())
        t = cpu()
        try:
            return compile_for_args(self, *a, **k)
        finally:
            acc["numba_dispatch"] += cpu() - t
            loads.append((self.py_func.__module__ + "." + self.py_func.__qualname__,
                          sum(self._cache_misses.values()) > misses))

    dispatcher.Dispatcher._compile_for_args = counted
    import splineimu.api.output as ao
    import splineimu.io.tum as tum
    import splineimu.pipeline as pl
    import splineimu.spline.fit as sf
    from splineimu import cli

    tum.read_tum = timed("read", tum.read_tum)
    sf.fit = timed("fit", sf.fit)
    ao.write_output = timed("write_output", ao.write_output)
    pieces = pl.SynthesisStream.pieces

    def timed_pieces(self):
        it = pieces(self)
        while True:
            t = cpu()
            try:
                piece = next(it)
            except StopIteration:
                acc["synthesis"] += cpu() - t
                return
            acc["synthesis"] += cpu() - t
            yield piece

    pl.SynthesisStream.pieces = timed_pieces
    return cli.main


def _check(poses, out_ours, out_base) -> float:
    """Largest gyro difference of the two IMU files (the baseline computes the same signals)."""
    import numpy as np

    a = np.loadtxt(Path(out_ours) / "mav0/imu0/data.csv", delimiter=",")
    b = np.loadtxt(Path(out_base) / "mav0/imu0/data.csv", delimiter=",")
    return float(np.max(np.abs(a[:, 1:4] - b[:, 1:4])))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reps", type=int, default=5, help="interleaved repetitions (best of)")
    ap.add_argument("--write", action="store_true", help="write benchmarks/results/cli.md")
    ap.add_argument("--tree", type=Path, default=ROOT,
                    help="time the splineimu of another checkout (e.g. an older commit), default this one")
    ap.add_argument("--baseline", nargs=2, metavar=("POSES", "OUT"), help=argparse.SUPPRESS)
    ap.add_argument("--phases", nargs=2, metavar=("POSES", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.baseline:
        print(json.dumps(baseline(*args.baseline)))
        return
    if args.phases:
        print(json.dumps(phases(*args.phases)))
        return
    global TREE
    TREE = args.tree.resolve()
    load0 = os.getloadavg()
    sys.path.insert(0, str(TREE))
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        poses = tmp / "exact.tum"
        n = make_poses(poses)
        child_cpu(ours_cmd(poses, tmp / "ours"))  # untimed: fills the numba cache if needed
        child_cpu(baseline_cmd(poses, tmp / "scipy"))
        gyro_diff = _check(poses, tmp / "ours", tmp / "scipy")
        t_ours, t_base, base_ph, ph, imp_ours, imp_base, floor, floor_kernel = [], [], [], [], [], [], [], []
        for r in range(args.reps):  # every run writes into a new folder (nothing to replace)
            for which in ((0, 1) if r % 2 == 0 else (1, 0)):
                if which == 0:
                    t_ours.append(child_cpu(ours_cmd(poses, tmp / f"ours{r}"))[0])
                else:
                    t, text = child_cpu(baseline_cmd(poses, tmp / f"scipy{r}"))
                    t_base.append(t)
                    base_ph.append(json.loads(text))
            text = child_cpu([sys.executable, str(Path(__file__).resolve()), "--phases", str(poses),
                              str(tmp / f"phases{r}")])[1]
            ph.append(json.loads(text.splitlines()[-1]))  # after the command's own summary
            floor.append(child_cpu([sys.executable, "-c", FLOOR])[0])
            floor_kernel.append(child_cpu([sys.executable, "-c", FLOOR_KERNEL])[0])
            imp_ours.append(import_time(ours_cmd(poses, tmp / f"imp_ours{r}")))
            imp_base.append(import_time(baseline_cmd(poses, tmp / f"imp_scipy{r}")))
    load1 = os.getloadavg()
    text = report(n, args.reps, t_ours, t_base, base_ph, ph, imp_ours, imp_base, (floor, floor_kernel), gyro_diff,
                  load0, load1)
    print(text)
    if args.write:
        (HERE / "results" / "cli.md").write_text(text)


def _describe(tree) -> str:
    res = subprocess.run(["git", "-C", str(tree), "log", "-1", "--format=%h %s"], capture_output=True, text=True)
    return f"{tree} ({res.stdout.strip()[:90]})" if res.returncode == 0 else str(tree)


def report(n, reps, t_ours, t_base, base_ph, ph, imp_ours, imp_base, floors, gyro_diff, load0, load1) -> str:
    import numba
    import numpy as np
    import scipy

    best = min
    o, b = best(t_ours), best(t_base)

    def phase(key):
        return best(p[key] for p in ph)

    syn, wo = phase("synthesis"), phase("write_output")
    writing = best(p["write_output"] - p["synthesis"] for p in ph)
    other = best(p["main"] - p["read"] - p["fit"] - p["write_output"] for p in ph)
    compiled = sorted({k for p in ph for k in p["numba_compiled"]})
    lines = [
        "# `splineimu from-tum` against a plain scipy + np.savetxt script",
        "",
        "```",
        f"# bench_cli: python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"numba {numba.__version__}, {os.cpu_count()} CPUs ({platform.machine()})",
        f"# command: python benchmarks/bench_cli.py {' '.join(sys.argv[1:])}",
        f"# splineimu timed: {_describe(TREE)}",
        f"# load average (1/5/15 min) at start: {'/'.join(f'{x:.1f}' for x in load0)}, "
        f"at end: {'/'.join(f'{x:.1f}' for x in load1)}",
        "```",
        "",
        f"{n} exact poses of the lecture ellipse (60 s at 200 Hz) -> IMU csv, ground-truth csv, TUM file. "
        f"CPU time (user + system) of the child process, best of {reps} interleaved repetitions, "
        "NUMBA_NUM_THREADS=1, numba cache warm.",
        "",
        "| program | CPU [s] | ratio |",
        "|---|---:|---:|",
        f"| `splineimu from-tum` | {o:.3f} | {o / b:.2f} |",
        f"| scipy + np.savetxt script | {b:.3f} | 1.00 |",
        "",
        f"- every repetition [s]: ours {', '.join(f'{x:.2f}' for x in t_ours)}; "
        f"scipy {', '.join(f'{x:.2f}' for x in t_base)}",
        f"- largest gyro difference of the two IMU files: {gyro_diff:.1e} rad/s (the same signals)",
        "",
        "Breakdown (CPU seconds, best of the repetitions for each figure; the instrumented run is a fresh "
        "process like the timed ones):",
        "",
        "| part | ours | scipy script |",
        "|---|---:|---:|",
        f"| imports (`-X importtime`, top-level sum, lazy imports included) | {best(imp_ours):.3f} "
        f"| {best(imp_base):.3f} |",
        f"| start-up before `main()` (interpreter, site, numba, `splineimu.cli`) | "
        f"{best(p['total'] - p['main'] for p in ph):.3f} | - |",
        f"| read the pose file | {phase('read'):.3f} | (in compute) |",
        f"| fit | {phase('fit'):.3f} | (in compute) |",
        f"| synthesis (gyro, specific force, ground truth) | {syn:.3f} | {best(p['compute'] for p in base_ph):.3f} "
        "(read + splines + evaluation) |",
        f"| writing (files, yaml, report.json; `write_output` less synthesis) | {writing:.3f} "
        f"| {best(p['write'] for p in base_ph):.3f} |",
        f"| the rest of `main()` (options, stamps, report, lazy imports) | {other:.3f} | - |",
        f"| of all the above: numba dispatch (cache loads: {ph[-1]['numba_kernels']} kernels) | "
        f"{phase('numba_dispatch'):.3f} | - |",
        f"| floor: `python -c '{FLOOR}'` | {best(floors[0]):.3f} | - |",
        f"| floor + the first call of a cached kernel (numba's start-up) | {best(floors[1]):.3f} | - |",
        f"| whole instrumented process | {phase('total'):.3f} | "
        f"{best(p['imports'] + p['compute'] + p['write'] for p in base_ph):.3f} (in-script timers) |",
        "",
        f"- kernels compiled (not loaded from the cache) in the timed runs: {', '.join(compiled) or 'none'}",
        f"- write_output including synthesis: {wo:.3f} s",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
