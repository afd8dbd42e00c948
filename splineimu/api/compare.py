"""Comparing trajectories on disk: :func:`compare`, :func:`compare_files`, the job behind ``splineimu compare``.

TUM files are read with splineimu's TUM reader (:func:`splineimu.io.tum.read_tum`, the one
every command uses) and handed to evo as trajectory objects (:func:`load_tum`); the metrics
are :func:`splineimu.metrics.compare` (evo's APE and RPE, see :mod:`splineimu.metrics`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError
from ..io.files import staged_path
from ..io.tum import read_tum
from ..metrics import CompareResult, _evo, check_compare_options
from ..metrics import compare as compare_trajectories

__all__ = ["compare", "compare_files", "plot_compare", "load_tum"]


def load_tum(path):
    """Read a TUM file into an evo ``PoseTrajectory3D`` with :func:`splineimu.io.tum.read_tum`.

    Every TUM file the other commands read is read: columns separated by spaces, tabs or
    several of them (evo's own reader refuses all but single spaces), commas, extra columns.
    The values are evo's: stamps are the decimal text's nearest float (as evo's reader reads
    them, to the ns), positions as written, quaternions normalized only when their norm is
    off by more than 4 ulp (evo normalizes when it makes rotation matrices either way).

    Returns
    -------
    evo.core.trajectory.PoseTrajectory3D
        (:func:`compare` passes on the reader's notices, e.g. dropped duplicate rows.)

    Raises
    ------
    InputError
        Missing or malformed file, naming the line (non-finite value, zero quaternion,
        unsorted or ambiguous repeated stamps, another format).
    """
    return _read_tum(path)[0]


def _read_tum(path):
    """``(PoseTrajectory3D, notices)`` of a TUM file (:func:`load_tum`)."""
    _, _, trajectory, _ = _evo()
    p = Path(path)
    if not p.is_file():
        raise InputError("is a folder, expected a TUM file" if p.is_dir() else "no such file", path=p)
    from ..io.sniff import format_hint

    hint = format_hint(p, "tum", use=_USE)
    if hint is not None:  # the TUM reader takes a EuRoC csv's first 8 columns (ns stamps as seconds)
        raise InputError(f"not a TUM trajectory (timestamp tx ty tz qx qy qz qw); {hint}", path=p)
    track = read_tum(p, min_poses=1, repeated_stamps="first")
    t_s = np.array([float(f"{'-' if t < 0 else ''}{abs(t) // 10**9}.{abs(t) % 10**9:09d}")
                    for t in track.t_ns.tolist()], dtype=np.float64)  # as float(text): evo's stamps
    traj = trajectory.PoseTrajectory3D(np.array(track.positions), track.quat_xyzw[:, [3, 0, 1, 2]], t_s)
    return traj, [f"{p}: {n}" for n in track.notices]


_USE = "compare reads TUM trajectories, e.g. OUT/groundtruth.tum"


def compare(est, ref, *, metric: str = "ape", pose_relation: str = "trans", align: str = "none",
            delta: float = 1.0, delta_unit: str = "f", all_pairs: bool = False,
            t_max_diff: float = 0.01, t_offset: float = 0.0) -> CompareResult:
    """:func:`splineimu.metrics.compare` (APE and/or RPE by evo) of trajectories or TUM files.

    Parameters
    ----------
    est, ref : str, os.PathLike, Trajectory-like or tuple
        TUM files (read by :func:`load_tum`), or what :func:`splineimu.metrics.compare` takes.
    metric, pose_relation, align, delta, delta_unit, all_pairs, t_max_diff, t_offset
        As :func:`splineimu.metrics.compare`.

    Returns
    -------
    CompareResult

    Raises
    ------
    SplineImuError
        evo is not installed.
    InputError
        Missing or malformed TUM file.
    ConfigError
        As :func:`splineimu.metrics.compare`.
    """
    _evo()
    # before any file is read
    check_compare_options(metric, pose_relation, align, delta, delta_unit, t_max_diff, t_offset)
    est, ref = (_read_tum(x) if isinstance(x, (str, Path)) else (x, []) for x in (est, ref))
    (est, est_notices), (ref, ref_notices) = est, ref
    res = compare_trajectories(est, ref, metric=metric, pose_relation=pose_relation, align=align, delta=delta,
                               delta_unit=delta_unit, all_pairs=all_pairs, t_max_diff=t_max_diff, t_offset=t_offset)
    res.notes[:0] = est_notices + ref_notices
    return res


def compare_files(est_path, ref_path, *, plot=None, **options) -> CompareResult:
    """APE / RPE of an estimated TUM file against a reference TUM file (what ``splineimu compare`` runs).

    Parameters
    ----------
    est_path, ref_path : path-like
        TUM files (note the order: estimate first, unlike evo's command line).
    plot : path-like, optional
        Also save :func:`plot_compare`'s figure there (:attr:`CompareResult.plot_path`).
    **options
        ``metric``, ``pose_relation``, ``align``, ``delta``, ``delta_unit``, ``all_pairs``,
        ``t_max_diff``, ``t_offset`` of :func:`compare`.

    Returns
    -------
    CompareResult

    Raises
    ------
    SplineImuError, InputError, ConfigError
        As :func:`compare`.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "ref.tum").write_text("".join(f"{i}.0 {i} 0 0 0 0 0 1\\n" for i in range(5)))
    >>> _ = (d / "est.tum").write_text("".join(f"{i}.0 {i} 0.5 0 0 0 0 1\\n" for i in range(5)))
    >>> r = compare_files(d / "est.tum", d / "ref.tum", metric="both")
    >>> round(float(r.ape.stats["max"]), 6), r.to_dataframe()["metric"].tolist()
    (0.5, ['ape', 'rpe'])
    """
    res = compare(Path(est_path), Path(ref_path), **options)
    if plot is not None:
        res.plot_path = plot_compare(res, plot)
    return res


def plot_compare(result: CompareResult, path) -> Path:
    """Save a PNG: reference and aligned estimate (x-y), and the error(s) over time.

    The figure is rendered by matplotlib's Agg canvas without pyplot, so no display is needed.
    """
    from matplotlib.figure import Figure  # no pyplot: no GUI backend, no global state

    res = result.results
    fig = Figure(figsize=(6.0 + 5.0 * len(res), 5.0), layout="constrained")
    axes = fig.subplots(1, 1 + len(res), squeeze=False)[0]
    ax = axes[0]
    ax.plot(result.est_positions_aligned[:, 0], result.est_positions_aligned[:, 1], "C0", lw=1.2,
            label=f"estimate ({'not aligned' if result.align == 'none' else result.align + ' aligned'})")
    ax.plot(result.ref_positions[:, 0], result.ref_positions[:, 1], "k--", lw=0.8, label="reference")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best", fontsize="small")
    ax.set_title(f"{result.n_associated} associated poses")
    t0 = result.timestamps_s[0] if result.timestamps_s.size else 0.0
    for ax, r in zip(axes[1:], res):
        ax.plot(r.timestamps_s - t0, r.errors, "C1", lw=1.0, label=r.metric.upper())
        for name, style in (("rmse", "C3-"), ("median", "C2--"), ("mean", "C4:")):
            ax.axhline(r.stats[name], color=style[:2], ls=style[2:], lw=1.0,
                       label=f"{name} {r.stats[name]:.6g}")
        ax.set_xlabel("t (s)")
        ax.set_ylabel(f"{r.metric.upper()} ({r.unit})")
        ax.set_title(r.title, fontsize="small")
        ax.legend(loc="best", fontsize="small")
    out = Path(path)
    fmt = out.suffix[1:].lower() or "png"  # the name's format (plot.pdf was PNG bytes), PNG without a suffix
    if fmt not in fig.canvas.get_supported_filetypes():
        raise ConfigError(f"cannot write a plot as '.{fmt}' ({out}); give .png, .pdf or .svg", option="--plot")
    with staged_path(out) as tmp:  # a failure or an interrupt leaves what was there
        fig.savefig(tmp, dpi=110, format=fmt)
    return out
