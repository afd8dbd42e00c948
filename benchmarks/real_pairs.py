"""Real ground truth against the real IMU recorded with it: the automatic fit, the best fixed
spacing and order, and scipy interpolation (RotationSpline + CubicSpline through the poses).

Each pair: poses and IMU samples on one clock (BROAD: one file; EuRoC: the flight's ground
truth and its ADIS16448). The IMU is synthesized at the real IMU's stamps; one constant time
offset and one sensor rotation are found once from the scipy reference (so that every method is
compared under the same alignment; both sources give the IMU's own pose, no lever arm); each
residual has its mean removed (bias).
Figures (RMS of the vector norm): the residual low-passed at 10 Hz (4th-order Butterworth,
zero phase), the full-band residual, and the synthesized signal's RMS above 15 Hz next to the
real IMU's.

    PYTHONPATH=$PWD python benchmarks/real_pairs.py [names...]   # writes results/real_pairs.md
    PYTHONPATH=$PWD python benchmarks/real_pairs.py broad16@14   # its poses every 14th (20 Hz)

Held-out BROAD trials (broad02 ... broad36) are read from the folders in $BROAD_DATA; EuRoC
MH_01 (``mh01``, and ``mh01e20``: every 10th pose, fitted as an estimate) from the two files named in
$EUROC_MH01 (ground truth as TUM text, IMU csv).
EuRoC's csv ground truth is read with the product's reader and the automatic fit takes the track:
the file carries IMU biases, so its rotation is fitted as an estimator's output
(``splineimu.fit``'s ``estimated_rotation``, as ``from-euroc`` does); TUM text carries none. The
resampled (euroc200r, euroc20r) and held (euroc200h, euroc20h) pairs, made as arrays, are fitted
as arrays (measurements); they take EuRoC's ground truth every other pose and resample it back
to its stamps or repeat each pose at the next one (a held pair is aligned with the original:
scipy through the staircase lags by half a pose spacing).

Data: ../shared/data (BROAD: Laidig et al., Data 6(7):72, 2021, CC BY 4.0; EuRoC: ETH ASL).
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data"
GRAVITY = np.array([0.0, 0.0, -9.81])


@dataclass
class Pair:
    name: str
    t_s: np.ndarray  # pose times (s, relative to origin)
    positions: np.ndarray
    quat_xyzw: np.ndarray
    imu_t_s: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    notes: list = field(default_factory=list)
    #: the pair the time offset and sensor rotation are found with, if not this one (poses
    #: held at later stamps: scipy through the staircase lags by half a pose spacing)
    aligned_by: Pair | None = None
    #: the poses as the product's reader gives them (origin = the first pose), when read from a
    #: pose file: the automatic fit takes the track, and with it what the file says (a EuRoC
    #: ground truth carries IMU biases: an estimator's output, splineimu.fit's estimated_rotation)
    track: object = None
    #: the automatic fit's ``estimated_rotation`` for poses given as arrays
    estimated: object = "auto"


def broad_files():
    """BROAD trial files (hdf5, or the repository's data_mat copies) in ../shared/data/broad and
    the folders of $BROAD_DATA (os.pathsep-separated), hdf5 first."""
    folders = [DATA / "broad"] + [Path(d) for d in os.environ.get("BROAD_DATA", "").split(os.pathsep) if d]
    return [p for d in folders if d.is_dir() for ext in ("hdf5", "mat") for p in sorted(d.glob(f"[0-9][0-9]_*.{ext}"))]


def load_broad(trial: str) -> Pair:
    path = next(p for p in broad_files() if p.name.startswith(f"{trial}_"))
    if path.suffix == ".mat":  # the repository's data_mat copy (MATLAB 5) of a trial: the same arrays
        from scipy.io import loadmat

        arrays = loadmat(path, squeeze_me=True)
        rate = float(arrays["sampling_rate"])
    else:
        import h5py

        with h5py.File(path, "r") as f:
            rate = float(f.attrs["sampling_rate"])
            arrays = {k: np.asarray(f[k]) for k in ("imu_gyr", "imu_acc", "opt_quat", "opt_pos")}
    gyr, acc, q_wxyz, pos = (np.asarray(arrays[k], dtype=float) for k in ("imu_gyr", "imu_acc", "opt_quat", "opt_pos"))
    t = np.arange(gyr.shape[0]) / rate
    ok = np.all(np.isfinite(q_wxyz), axis=1) & np.all(np.isfinite(pos), axis=1)
    q = q_wxyz[ok][:, [1, 2, 3, 0]]
    return Pair(f"BROAD {trial}", t[ok], pos[ok], q, t, gyr, acc,
                [f"{int((~ok).sum())} of {ok.size} mocap samples missing (gaps bridged)"])


def _euroc_csv(path):
    a = np.loadtxt(path, delimiter=",", comments="#")
    return a[:, 0].astype(np.int64), a[:, 1:]


def load_euroc(gt_name: str, label: str) -> Pair:
    from splineimu.io import read_euroc_groundtruth

    d = DATA / "euroc_V1_02_medium"
    track = read_euroc_groundtruth(d / gt_name)
    t_imu, m = _euroc_csv(d / "imu0_first40s.csv")
    origin = track.origin_ns
    return Pair(label, (track.t_ns - origin) / 1e9, track.positions, track.quat_xyzw, (t_imu - origin) / 1e9,
                m[:, 0:3], m[:, 3:6], track=track)


def load_euroc_tum(gt_tum: str, imu_csv: str, label: str) -> Pair:
    """A EuRoC flight from its ground truth as TUM text (OpenVINS' ov_data/euroc_mav) and its IMU
    csv (stamps in ns, also written as floats such as 1.40363657975856E+018: rounded to 10 us)."""
    g = np.loadtxt(gt_tum, comments="#")
    rows = [line.split(",") for line in open(imu_csv) if line[:1].isdigit()]
    m = np.array([[float(x) for x in r] for r in rows if len(r) == 7 and r[1].strip()])
    t_imu = np.round(m[:, 0] / 1e4).astype(np.int64) * 10000
    t_gt = np.round(g[:, 0] * 1e5).astype(np.int64) * 10000
    origin = int(t_gt[0])
    return Pair(label, (t_gt - origin) / 1e9, g[:, 1:4], g[:, 4:8], (t_imu - origin) / 1e9, m[:, 1:4], m[:, 4:7])


def resampled(pair: Pair, label: str, m: int = 2) -> Pair:
    """The pair's poses taken every m-th and resampled back to their stamps (positions linearly,
    rotations along the geodesic), as ground truth exported at a lower rate and written at a
    higher one is (mocap at 100 Hz written at 200 Hz)."""
    from scipy.spatial.transform import Rotation, Slerp

    n = (pair.t_s.size - 1) // m * m + 1
    t, tc = pair.t_s[:n], pair.t_s[:n:m]
    p = np.column_stack([np.interp(t, tc, pair.positions[:n:m, j]) for j in range(3)])
    q = Slerp(tc, Rotation.from_quat(pair.quat_xyzw[:n:m]))(t).as_quat()
    return Pair(label, t, p, q, pair.imu_t_s, pair.gyro, pair.accel,
                pair.notes + [f"poses every {m}th, resampled back (linear / geodesic)"])


def held(pair: Pair, label: str, m: int = 2) -> Pair:
    """The pair's poses taken every m-th and held (repeated) at the stamps between, as a logger
    writing the latest pose at m times the rate the poses come does; aligned with the pair."""
    n = (pair.t_s.size - 1) // m * m + 1
    i = np.arange(n) // m * m
    return Pair(label, pair.t_s[:n], pair.positions[i], pair.quat_xyzw[i], pair.imu_t_s, pair.gyro, pair.accel,
                pair.notes + [f"poses every {m}th, held {m}x"], aligned_by=pair)


def every(pair: Pair, label: str, m: int = 10, estimated=True) -> Pair:
    """The pair's poses every m-th (EuRoC's 200 Hz ground truth at 20 Hz), by default fitted as
    an estimator's output (as from-euroc reads OpenVINS' csv of it, which carries IMU biases);
    aligned with the pair."""
    s = slice(0, None, m)
    return Pair(label, pair.t_s[s], pair.positions[s], pair.quat_xyzw[s], pair.imu_t_s, pair.gyro, pair.accel,
                pair.notes + [f"poses every {m}th" + (", an estimate" if estimated is True else "")], aligned_by=pair,
                estimated=estimated)


def pair_named(name: str) -> Pair:
    """A pair of :data:`PAIRS`, or ``<name>@<m>``: its poses every m-th, as measurements."""
    base, _, m = name.partition("@")
    pair = PAIRS[base]()
    return pair if not m else every(pair, f"{pair.name} every {m}th pose", int(m), estimated="auto")


PAIRS = {
    "broad07": lambda: load_broad("07"),
    "broad09": lambda: load_broad("09"),
    "broad16": lambda: load_broad("16"),
    # held out: the other BROAD trials with mocap (data_hdf5 of github.com/dlaidig/broad), read
    # from the folders in $BROAD_DATA (os.pathsep-separated) when not in ../shared/data/broad
    **{f"broad{n}": (lambda n=n: load_broad(n)) for n in
       ("02", "03", "05", "10", "11", "12", "14", "15", "18", "24", "25", "27", "30", "31", "32", "33", "34", "35",
        "36",
        # their data_hdf5 blobs are absent from the repository snapshot; data_mat has them
        "01", "04", "06", "08", "21", "26", "28", "29")},
    "euroc200": lambda: load_euroc("groundtruth.csv", "EuRoC V1_02 200 Hz"),
    "euroc20": lambda: load_euroc("groundtruth_vicon2gt_20hz.csv", "EuRoC V1_02 20 Hz vicon2gt"),
    # held out, not in ../shared/data: $EUROC_MH01 = "<MH_01_easy.txt>,<imu0 data.csv>"
    "mh01": lambda: load_euroc_tum(*os.environ["EUROC_MH01"].split(","), "EuRoC MH_01 200 Hz"),
    "mh01e20": lambda: every(load_euroc_tum(*os.environ["EUROC_MH01"].split(","), ""),
                             "EuRoC MH_01 every 10th pose (20 Hz), an estimate"),
    # resampled ground truth: the 200 Hz one at 100 Hz written at 200 Hz, the 20 Hz one at 10 Hz
    # written at 20 Hz
    "euroc200r": lambda: resampled(load_euroc("groundtruth.csv", ""), "EuRoC V1_02 100 Hz resampled to 200 Hz"),
    "euroc20r": lambda: resampled(load_euroc("groundtruth_vicon2gt_20hz.csv", ""),
                                  "EuRoC V1_02 10 Hz vicon2gt resampled to 20 Hz"),
    # held ground truth: the same, each pose repeated at the stamp after it
    "euroc200h": lambda: held(load_euroc("groundtruth.csv", ""), "EuRoC V1_02 100 Hz held at 200 Hz"),
    "euroc20h": lambda: held(load_euroc("groundtruth_vicon2gt_20hz.csv", ""),
                             "EuRoC V1_02 10 Hz vicon2gt held at 20 Hz"),
}


# ---------------------------------------------------------------------------- motion
def scipy_motion(t, P, q):
    """(omega_body, alpha_body, specific_force_body) callables of scipy interpolation."""
    from scipy.interpolate import CubicSpline
    from scipy.spatial.transform import Rotation, RotationSpline

    rs = RotationSpline(t, Rotation.from_quat(q))
    cs = CubicSpline(t, P)

    def motion(tq):
        RT = np.swapaxes(rs(tq).as_matrix(), 1, 2)
        w, a = rs(tq, 1), rs(tq, 2)  # RotationSpline's derivatives are body-frame rates
        f = np.einsum("nij,nj->ni", RT, cs(tq, 2) - GRAVITY)
        return w, a, f

    return motion


def spline_motion(spl):
    def motion(tq):
        k = spl.kinematics(tq)
        RT = np.swapaxes(k.world_R_body, 1, 2)
        f = np.einsum("nij,nj->ni", RT, k.accel_world - GRAVITY)
        return k.omega_body, k.alpha_body, f

    return motion


def sensor(motion, tq, R_bs, r):
    w, a, f = motion(tq)
    fs = f + np.cross(a, r) + np.cross(w, np.cross(w, r))
    return w @ R_bs, fs @ R_bs


# ---------------------------------------------------------------------------- alignment
@dataclass
class Alignment:
    offset_s: float
    R_bs: np.ndarray
    r_bs: np.ndarray
    mask: np.ndarray  # IMU samples compared


def _kabsch(a, b):
    """R minimizing |a R - b| (rows are vectors)."""
    U, _, Vt = np.linalg.svd(a.T @ b)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


def align(pair: Pair, motion) -> Alignment:
    t = pair.t_s
    margin = 0.5
    ti = pair.imu_t_s
    ok = (ti > t[0] + margin) & (ti < t[-1] - margin)
    # away from mocap gaps (> 50 ms and 3 pose spacings without a pose)
    gaps = np.flatnonzero(np.diff(t) > max(0.05, 3.0 * float(np.median(np.diff(t)))))
    for g in gaps:
        ok &= ~((ti > t[g] - 0.1) & (ti < t[g + 1] + 0.1))
    best = None
    for step, span in ((0.005, 0.2), (0.0005, 0.006)):
        center = 0.0 if best is None else best[1]
        for dtau in center + np.arange(-span, span + step / 2, step):
            sel = ok & (ti + dtau > t[0]) & (ti + dtau < t[-1])
            w, _, _ = motion(ti[sel] + dtau)
            R = _kabsch(w, pair.gyro[sel])
            e = w @ R - pair.gyro[sel]
            e -= e.mean(axis=0)
            c = float(np.mean(e**2))
            if best is None or c < best[0]:
                best = (c, dtau, R)
    _, tau, R = best
    sel = ok & (ti + tau > t[0]) & (ti + tau < t[-1])
    # both sources give the pose of the IMU itself (EuRoC: T_BS = I; BROAD: aligned reference),
    # so no lever arm is fitted (a fitted one absorbs noise of the angular acceleration)
    return Alignment(tau, R, np.zeros(3), sel)


# ---------------------------------------------------------------------------- figures
def _butter(x, rate, cutoff, kind):
    from scipy.signal import butter, sosfiltfilt

    sos = butter(4, cutoff, btype=kind, fs=rate, output="sos")
    return sosfiltfilt(sos, x, axis=0)


def _rms(e):
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def figures(pair: Pair, al: Alignment, motion) -> dict:
    ti = pair.imu_t_s[al.mask] + al.offset_s
    rate = 1.0 / float(np.median(np.diff(pair.imu_t_s)))
    g, f = sensor(motion, ti, al.R_bs, al.r_bs)
    out = {}
    for name, s, real in (("gyro", g, pair.gyro[al.mask]), ("accel", f, pair.accel[al.mask])):
        e = s - real
        e -= e.mean(axis=0)
        out[f"{name}_full"] = _rms(e)
        out[f"{name}_lp10"] = _rms(_butter(e, rate, 10.0, "low"))
        out[f"{name}_hf15"] = _rms(_butter(s, rate, 15.0, "high"))
        out[f"{name}_hf15_real"] = _rms(_butter(real, rate, 15.0, "high"))
    return out


def evaluate(pair: Pair, fixed=True, verbose=False):
    """Figures of auto, scipy and (optionally) every fixed setting; returns a dict of rows."""
    from splineimu import fit

    ref = scipy_motion(pair.t_s, pair.positions, pair.quat_xyzw)
    by = pair.aligned_by or pair
    al = align(by, scipy_motion(by.t_s, by.positions, by.quat_xyzw))
    rows = {"scipy": figures(pair, al, ref)}
    c0 = time.process_time()
    auto_in = (pair.track,) if pair.track is not None else (pair.t_s, pair.positions, pair.quat_xyzw)
    told = {} if pair.track is not None else {"estimated_rotation": pair.estimated}
    spl, rep = fit(*auto_in, return_report=True, **told)
    rows["auto"] = figures(pair, al, spline_motion(spl))
    rows["auto"].update(fit_cpu_s=time.process_time() - c0, rotation=(rep.order, rep.knot_spacing_s),
                        position=(rep.position_order, rep.position_knot_spacing_s),
                        predicted_gyro=rep.predicted_gyro_rms_rad_s, predicted_accel=rep.predicted_accel_rms_m_s2,
                        warnings=[w.code for w in rep.warnings], dropped=len(rep.dropped_poses),
                        estimated=rep.knot_choice["rotation"]["estimated"])
    if verbose:
        print(pair.name, "auto", rows["auto"], flush=True)
    if fixed:
        h = float(np.median(np.diff(pair.t_s)))
        for k in (4, 5, 6):
            for dt in np.geomspace(0.7 * h, max(0.25, 8 * h), 10):
                s = fit(pair.t_s, pair.positions, pair.quat_xyzw, order=k, knot_spacing_s=float(dt),
                        reject_outliers=False)
                rows[f"k{k} {dt * 1e3:.1f} ms"] = figures(pair, al, spline_motion(s))
    return rows, al


def best_fixed(rows, key):
    fixed = {n: r for n, r in rows.items() if n.startswith("k")}
    name = min(fixed, key=lambda n: fixed[n][key])
    return name, fixed[name][key]


def table(results, truth="real IMU") -> str:
    lines = ["| pair | quantity | band | auto | best fixed (setting) | scipy | auto / best | auto / scipy |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for name, (rows, _) in results.items():
        a, s = rows["auto"], rows["scipy"]
        for q in ("gyro", "accel"):
            for band in ("lp10", "full"):
                key = f"{q}_{band}"
                bn, bv = best_fixed(rows, key)
                lines.append(f"| {name} | {q} | {band} | {a[key]:.4g} | {bv:.4g} ({bn}) | {s[key]:.4g} | "
                             f"{a[key] / bv:.3f} | {a[key] / s[key]:.3f} |")
            key = f"{q}_hf15"
            lines.append(f"| {name} | {q} | >15 Hz RMS | {a[key]:.4g} | {truth} {a[key + '_real']:.4g} | "
                         f"{s[key]:.4g} | | |")
    return "\n".join(lines)


def main(names):
    results = {}
    for n in names:
        pair = pair_named(n)
        results[pair.name] = evaluate(pair, verbose=True)
    text = table(results)
    auto_lines = [f"- {n}: rotation order/spacing {r['auto']['rotation']}"
                  f"{' (fitted as an estimate)' if r['auto']['estimated'] else ''}, "
                  f"position {r['auto']['position']}, "
                  f"predicted gyro {r['auto']['predicted_gyro']:.3g} rad/s, accel {r['auto']['predicted_accel']:.3g} "
                  f"m/s^2, warnings {r['auto']['warnings']}, dropped {r['auto']['dropped']}, fit CPU "
                  f"{r['auto']['fit_cpu_s']:.2f} s; alignment offset {al.offset_s * 1e3:.1f} ms"
                  for n, (r, al) in results.items()]
    print(text)
    print("\n".join(auto_lines))
    return text, auto_lines


if __name__ == "__main__":
    names = sys.argv[1:] or list(PAIRS)
    text, auto_lines = main(names)
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    (out / "real_pairs.md").write_text(
        "# Real pairs: synthesized IMU against the real IMU\n\n"
        f"`PYTHONPATH=$PWD python benchmarks/real_pairs.py {' '.join(names)}`\n\n"
        "Residual RMS (vector norm) after mean removal and one time/frame alignment; gyro in "
        "rad/s, accel in m/s^2. Best fixed: orders 4-6 x 10 spacings from 0.7x the pose spacing, one "
        "spacing for rotation and position.\n\n" + text + "\n\n" + "\n".join(auto_lines) + "\n")
