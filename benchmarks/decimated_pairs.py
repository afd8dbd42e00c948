"""20 Hz re-estimated ground truth without its IMU: a 200 Hz EuRoC ground truth taken every 10th
pose, against the IMU synthesized from all of its poses.

A stand-in for the vicon2gt files of flights whose IMU is not at hand (the shared data hold
V1_02's, with its IMU: ``real_pairs.py euroc20``). The reference is the automatic fit of the
200 Hz poses, sampled at their stamps (1 s in from each end, noise-free): below 10 Hz it is what
the 20 Hz poses can at best give back, so the table says how each method interpolates them
(auto, the best fixed spacing and order, scipy's RotationSpline + CubicSpline), not how close to
a real IMU they come. Where the 200 Hz fit is itself doubtful the reference is too (MH_0x: its
tracking jumps; V2_01: its positions fitted at 104 ms while the 20 Hz ones read as motion).

    PYTHONPATH=$PWD python benchmarks/decimated_pairs.py DIR [flights...]

DIR holds EuRoC ground-truth csv files, e.g. ``V1_03_difficult.csv`` (the 17-column
state_groundtruth_estimate0 layout, as OpenVINS' ov_data/euroc_mav ships them); prints the
table of ``real_pairs.py`` for each flight (default: every ``*.csv`` in DIR).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from benchmarks.real_pairs import Pair, evaluate, sensor, spline_motion, table  # noqa: E402


def decimated_pair(path: Path, m: int = 10) -> Pair:
    """The flight's poses every m-th (read with the product's reader, fitted as the file says:
    EuRoC's ground truth carries IMU biases) and, as its "IMU", the 200 Hz fit's body rate and
    specific force at the 200 Hz stamps."""
    from splineimu import fit
    from splineimu.io import read_euroc_groundtruth

    full = read_euroc_groundtruth(path)
    t = (full.t_ns - full.origin_ns) / 1e9
    ti = t[(t > t[0] + 1.0) & (t < t[-1] - 1.0)]
    gyro, accel = sensor(spline_motion(fit(full)), ti, np.eye(3), np.zeros(3))
    s = slice(0, None, m)
    sub = full.subset(s)
    return Pair(f"{path.stem} every {m}th pose", t[s], full.positions[s], full.quat_xyzw[s], ti, gyro, accel,
                [f"poses every {m}th; IMU synthesized from all of them"], track=sub)


def main(folder, names):
    paths = [Path(folder) / f"{n}.csv" for n in names] or sorted(Path(folder).glob("*.csv"))
    results = {}
    for p in paths:
        pair = decimated_pair(p)
        results[pair.name] = evaluate(pair)
    print(table(results, truth="reference"))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
