"""The automatic fit's choices and warnings on every real pose file at hand: a quick check that a
change to the knot choice leaves real inputs alone (or shows which it moves).

Inputs: the pose files in ../shared/data (TUM-VI room1, TUM RGB-D fr1_xyz and fr2_desk, the
georeferenced track, OpenVINS' simulated and recorded trajectories, EuRoC MH_04 and V1_02 at 200 Hz
and 20 Hz), BROAD's mocap (07, 09, 16 and the trials in $BROAD_DATA, as arrays), and any TUM or
EuRoC files named on the command line. Each is read with the product's readers (repeated stamps:
the first kept) and fitted with the defaults (a track: what its file says about its rotations).

Per input: rotation and position order and spacing, the predicted gyro and accel errors, whether
the rotation was read as motion (an estimate, or motion-limited), the warning codes. ``--json F``
writes the rows; ``--compare F`` prints only what differs from such a file (choices to 0.1 %,
predictions to 1 %, warning codes exactly).

    PYTHONPATH=$PWD python benchmarks/real_choices.py --json /tmp/before.json
    PYTHONPATH=$PWD BROAD_DATA=/tmp/broad python benchmarks/real_choices.py --compare /tmp/before.json
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data"

TUM = ["tum_vi/room1_512_16_groundtruth.tum", "tum_rgbd/freiburg1_xyz-groundtruth.txt",
       "tum_rgbd/fr2_desk_groundtruth.txt", "misc/georeferenced.tum", "openvins_sim/udel_gore.txt",
       "openvins_sim/udel_garage.txt", "openvins_sim/tum_corridor1_512_16_okvis.txt",
       "openvins_sim/tum_magistrale1_512_16_vinsmono.txt"]
EUROC = ["euroc/MH_04_difficult_groundtruth.csv", "euroc_V1_02_medium/groundtruth.csv",
         "euroc_V1_02_medium/groundtruth_vicon2gt_20hz.csv"]


def _inputs(extra):
    """(name, loader) pairs; a loader returns the arguments of fit()."""
    from splineimu.io import read_euroc_groundtruth, read_tum
    from splineimu.io.sniff import guess_format

    def tum(path):
        return lambda: (read_tum(path, repeated_stamps="first"),)

    def euroc(path):
        return lambda: (read_euroc_groundtruth(path, repeated_stamps="first"),)

    out = [(p, tum(DATA / p)) for p in TUM if (DATA / p).exists()]
    out += [(p, euroc(DATA / p)) for p in EUROC if (DATA / p).exists()]
    sys.path.insert(0, str(HERE.parent))
    from benchmarks.real_pairs import broad_files, load_broad

    trials = sorted({f.name[:2] for f in broad_files()})

    def broad(n):
        def load():
            pair = load_broad(n)
            return pair.t_s, pair.positions, pair.quat_xyzw
        return load

    out += [(f"BROAD {n}", broad(n)) for n in trials]
    for p in extra:
        out.append((p, euroc(p) if guess_format(p) == "euroc_gt" else tum(p)))
    return out


def row(name, args):
    from splineimu import fit

    c0 = time.process_time()
    _, rep = fit(*args, return_report=True)
    cpu = time.process_time() - c0
    ch = rep.knot_choice or {}
    rot = ch.get("rotation", {})
    return {"input": name, "poses": rep.n_poses,
            "rotation": [rep.order, round(rep.knot_spacing_s, 6), float(rot.get("knot_phase", 0.0))],
            "position": [rep.position_order, round(rep.position_knot_spacing_s, 6)],
            "gyro": rep.predicted_gyro_rms_rad_s, "accel": rep.predicted_accel_rms_m_s2,
            "as_motion": bool(rot.get("estimated") or rot.get("motion_limited")),
            "warnings": sorted({w.code for w in rep.warnings}), "cpu_s": round(cpu, 3)}


def _shift(r):
    return f" (shift {r['rotation'][2]:g})" if r["rotation"][2] else ""


def _differs(a, b):
    out = []
    for key in ("rotation", "position"):
        if a[key][0] != b[key][0] or abs(a[key][1] / b[key][1] - 1.0) > 1e-3:
            out.append(f"{key} k{b[key][0]} {1e3 * b[key][1]:.2f} ms -> k{a[key][0]} {1e3 * a[key][1]:.2f} ms")
    phase = [(r["rotation"] + [0.0])[2] for r in (b, a)]  # (rows written before the grid's phase: 0)
    if phase[0] != phase[1]:
        out.append(f"rotation grid shifted by {phase[0]:g} -> {phase[1]:g} of a spacing")
    for key in ("gyro", "accel"):
        if a[key] is not None and b[key] is not None and abs(a[key] / b[key] - 1.0) > 0.01:
            out.append(f"predicted {key} {b[key]:.4g} -> {a[key]:.4g}")
    if a["warnings"] != b["warnings"]:
        out.append(f"warnings {b['warnings']} -> {a['warnings']}")
    if a["as_motion"] != b["as_motion"]:
        out.append(f"rotation read as motion {b['as_motion']} -> {a['as_motion']}")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*", help="more TUM or EuRoC ground-truth files")
    ap.add_argument("--json", help="write the rows to this file")
    ap.add_argument("--compare", help="print what differs from the rows in this file")
    args = ap.parse_args(argv)
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    before = {r["input"]: r for r in json.load(open(args.compare))} if args.compare else None
    rows = []
    if before is None:
        print("| input | poses | rotation | position | pred gyro | pred accel | as motion | warnings | CPU [s] |")
        print("| --- | ---: | --- | --- | ---: | ---: | --- | --- | ---: |")
    for name, load in _inputs(args.files):
        r = row(name, load())
        rows.append(r)
        if before is None:
            print(f"| {name} | {r['poses']} | k{r['rotation'][0]} {1e3 * r['rotation'][1]:.2f} ms{_shift(r)} | "
                  f"k{r['position'][0]} {1e3 * r['position'][1]:.2f} ms | {r['gyro']:.4g} | {r['accel']:.4g} | "
                  f"{'yes' if r['as_motion'] else '-'} | {', '.join(r['warnings']) or '-'} | {r['cpu_s']:.2f} |",
                  flush=True)
        elif name not in before:
            print(f"{name}: new")
        else:
            diff = _differs(r, before[name])
            print(f"{name}: " + ("; ".join(diff) if diff else "same"), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    if before is not None:
        print(f"{sum(1 for r in rows if r['input'] in before and not _differs(r, before[r['input']]))} of "
              f"{len(rows)} the same")


if __name__ == "__main__":
    main()
