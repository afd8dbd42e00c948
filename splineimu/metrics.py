"""Trajectory error metrics (APE, RPE) computed with evo, so the numbers are evo's.

evo (GPLv3, https://github.com/MichaelGrupp/evo) is an optional extra of splineimu
(``pip install 'splineimu[evo]'``); it is imported only inside these functions. The steps
follow ``evo_ape tum`` / ``evo_rpe tum`` exactly: read the TUM files with
``file_interface.read_tum_trajectory_file`` (:mod:`splineimu.api.compare`), associate the reference with the estimate by
nearest time stamps (``sync.associate_trajectories(ref, est, max_diff, offset_2)``; the offset
is added to the estimate's stamps), align the estimate (Umeyama SE3 or Sim3, or origin), then
``metrics.APE`` / ``metrics.RPE``. Statistics are printed as evo prints them
(``f"{name:>10}\\t{value:.6f}"``, names sorted), under evo's title.

Pose relations (``pose_relation``), named as in evo's ``-r`` option:

==============  ===========================  ================================
splineimu       evo ``-r``                   value per pose pair
==============  ===========================  ================================
``trans``       ``trans_part``               ``|t_err|`` [m]
``rot``         ``rot_part``                 ``|R_err - I|_F`` (unit-less)
``full``        ``full``                     ``|E - I_4|_F`` (unit-less)
``angle_deg``   ``angle_deg``                rotation angle of ``R_err`` [deg]
``angle_rad``   ``angle_rad``                rotation angle of ``R_err`` [rad]
``point_distance``  ``point_distance``       ``|p_ref - p_est|`` [m]
==============  ===========================  ================================

RPE delta units: ``f`` frames, ``m`` meters travelled, ``d``/``r`` degrees/radians rotated
(all evo's), and ``s`` seconds, which splineimu turns into a whole number of frames from the
median step of the associated poses (every step within 25 % of it), so the
result is evo's ``-d N -u f``.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import ConfigError, InputError, SplineImuError
from .validation import as_quat_xyzw, as_times_s, as_vectors, finite_float, nonnegative_float, one_of, positive_float

__all__ = ["MetricResult", "CompareResult", "compare", "check_compare_options", "EVO_MISSING", "POSE_RELATIONS",
           "ALIGN_MODES", "DELTA_UNITS"]

EVO_MISSING = "splineimu compare needs evo: pip install 'splineimu[evo]'"

POSE_RELATIONS = {
    "trans": "translation_part",
    "rot": "rotation_part",
    "full": "full_transformation",
    "angle_deg": "rotation_angle_deg",
    "angle_rad": "rotation_angle_rad",
    "point_distance": "point_distance",
}
ALIGN_MODES = ("none", "se3", "sim3", "origin")
DELTA_UNITS = {"f": "frames", "m": "meters", "d": "degrees", "r": "radians", "s": "seconds"}
#: evo's statistics, in the order evo prints them (alphabetical).
STAT_NAMES = ("max", "mean", "median", "min", "rmse", "sse", "std")


def _evo():
    """Import the parts of evo we use, or raise the install hint."""
    try:
        from evo.core import metrics, sync, trajectory
        from evo.tools import file_interface
    except ImportError:
        raise SplineImuError(EVO_MISSING) from None
    except Exception as exc:  # evo refuses to import on Python < 3.11
        raise SplineImuError(f"{EVO_MISSING} ({exc})") from None
    return metrics, sync, trajectory, file_interface


@dataclass
class MetricResult:
    """One evo metric over the associated poses.

    Attributes
    ----------
    metric : {"ape", "rpe"}
    pose_relation : str
        splineimu's name (``"trans"``, ``"rot"``, ...).
    unit : str
        evo's unit string of the errors ("m", "deg", "unit-less", ...).
    title : str
        evo's title, e.g. ``"APE w.r.t. translation part (m)\\n(with SE(3) Umeyama alignment)"``.
    stats : dict[str, float]
        rmse, mean, median, std, min, max, sse.
    errors : (M,) float64
        Error per pose (APE) or per pose pair (RPE).
    timestamps_s : (M,) float64
        Estimate time stamps [s] of those errors (for RPE, the second pose of each pair).
    delta_frames : int or None
        For RPE with ``delta_unit="s"``: the frame count the seconds were turned into.
    """

    metric: str
    pose_relation: str
    unit: str
    title: str
    stats: dict
    errors: np.ndarray
    timestamps_s: np.ndarray
    delta_frames: int | None = None

    def pretty_str(self) -> str:
        """The title and statistics exactly as ``evo_ape`` / ``evo_rpe`` print them."""
        lines = [self.title, ""]
        lines += [f"{name:>10}\t{self.stats[name]:.6f}" for name in sorted(self.stats)]
        return "\n".join(lines) + "\n"

    def to_dataframe(self):
        """``pandas.DataFrame`` of the errors over time: columns ``t_s`` and ``error`` (in :attr:`unit`)."""
        import pandas as pd

        return pd.DataFrame({"t_s": self.timestamps_s, "error": self.errors})


@dataclass
class CompareResult:
    """Result of :func:`compare`.

    Attributes
    ----------
    ape, rpe : MetricResult or None
        The metrics that were asked for.
    n_associated : int
        Number of associated pose pairs.
    align : str
        Alignment mode used.
    alignment_sim3 : (4, 4) float64 or None
        ``ref_T_est`` (with scale for Sim3) applied to the estimate; None for ``align="none"``.
    timestamps_s : (n,) float64
        Associated estimate stamps [s].
    ref_positions : (n, 3) float64
        Associated reference positions [m].
    est_positions_aligned : (n, 3) float64
        Associated estimate positions after alignment [m].
    plot_path : pathlib.Path or None
        The plot :func:`splineimu.api.compare.compare_files` saved, if any.
    notes : list of str
        What the numbers rest on that they do not show (few associated poses).
    """

    ape: MetricResult | None
    rpe: MetricResult | None
    n_associated: int
    align: str
    alignment_sim3: np.ndarray | None
    timestamps_s: np.ndarray = field(repr=False)
    ref_positions: np.ndarray = field(repr=False)
    est_positions_aligned: np.ndarray = field(repr=False)
    plot_path: Path | None = None
    notes: list = field(default_factory=list)

    @property
    def results(self) -> list:
        """The metrics computed (APE first)."""
        return [r for r in (self.ape, self.rpe) if r is not None]

    def pretty_str(self) -> str:
        """Every metric as evo prints it."""
        return "\n".join(r.pretty_str() for r in self.results)

    def to_dataframe(self):
        """``pandas.DataFrame`` with one row per metric: metric, pose relation, unit and evo's statistics."""
        import pandas as pd

        return pd.DataFrame([{"metric": r.metric, "pose_relation": r.pose_relation, "unit": r.unit,
                              "delta_frames": r.delta_frames, **{k: r.stats[k] for k in STAT_NAMES}}
                             for r in self.results])


def _as_evo(traj, name):
    """An evo PoseTrajectory3D, an object with ``t_s``/``position_world``/``quat_xyzw`` (e.g.
    :class:`splineimu.integrate.Trajectory`), or a tuple ``(t_s, positions, quat_xyzw)``; TUM files
    are read by :func:`splineimu.api.compare.load_tum`."""
    _, _, trajectory, _ = _evo()
    if isinstance(traj, trajectory.PoseTrajectory3D):
        return copy.deepcopy(traj)
    if hasattr(traj, "position_world") and hasattr(traj, "quat_xyzw") and hasattr(traj, "t_s"):
        t, p, q = traj.t_s, traj.position_world, traj.quat_xyzw
    elif isinstance(traj, tuple) and len(traj) == 3:
        t, p, q = traj
    else:
        raise ConfigError(f"`{name}` must be a trajectory object or a tuple (t_s, positions, quat_xyzw) "
                          f"(TUM files: splineimu.api.compare); got {type(traj).__name__}")
    t = as_times_s(t, f"{name} t_s")
    n = t.shape[0]
    if n < 1:
        raise InputError(f"`{name}` has no poses")
    p = as_vectors(p, f"{name} positions", n)
    q = as_quat_xyzw(q, f"{name} quat_xyzw", n)
    return trajectory.PoseTrajectory3D(positions_xyz=p, orientations_quat_wxyz=q[:, [3, 0, 1, 2]],
                                       timestamps=t)


def _title(metric_obj, align: str) -> str:
    """evo's title for the alignment modes splineimu offers (as evo's main_ape/main_rpe)."""
    title = str(metric_obj)
    if align == "se3":
        title += "\n(with SE(3) Umeyama alignment)"
    elif align == "sim3":
        title += "\n(with Sim(3) Umeyama alignment)"
    elif align == "none":
        title += "\n(not aligned)"
    else:
        title += "\n(with origin alignment)"
    return title


def _frames_from_seconds(timestamps, delta_s) -> int:
    if timestamps.shape[0] < 2:
        raise ConfigError("RPE needs at least 2 associated poses")
    dt = np.diff(timestamps)
    step = float(np.median(dt))
    if step <= 0.0 or np.max(np.abs(dt - step)) > 0.25 * step:
        raise ConfigError(f"--delta-unit s needs evenly spaced poses (steps range {dt.min():.6g} to "
                          f"{dt.max():.6g} s); use --delta-unit f or m")
    frames = int(round(delta_s / step))
    if frames < 1:
        raise ConfigError(f"delta {delta_s} s is less than one pose step ({step:.6g} s)")
    return frames


def check_compare_options(metric: str = "ape", pose_relation: str = "trans", align: str = "none",
                          delta: float = 1.0, delta_unit: str = "f", t_max_diff: float = 0.01,
                          t_offset: float = 0.0) -> tuple:
    """The checks of :func:`compare`'s options; returns ``(delta, t_max_diff)`` as floats.

    Raises
    ------
    ConfigError
        A bad option.
    """
    one_of(metric, "metric", ("ape", "rpe", "both"))
    one_of(pose_relation, "pose_relation", tuple(POSE_RELATIONS))
    one_of(align, "align", ALIGN_MODES)
    one_of(delta_unit, "delta_unit", tuple(DELTA_UNITS))
    delta = positive_float(delta, "delta")
    if delta_unit == "f" and float(delta) != int(delta):
        raise ConfigError(f"RPE delta in frames must be a whole number, got {delta}", option="delta")
    finite_float(t_offset, "t_offset")  # NaN associated nothing and was reported as "no matching timestamps"
    return delta, nonnegative_float(t_max_diff, "t_max_diff")


def compare(est, ref, *, metric: str = "ape", pose_relation: str = "trans", align: str = "none",
            delta: float = 1.0, delta_unit: str = "f", all_pairs: bool = False,
            t_max_diff: float = 0.01, t_offset: float = 0.0) -> CompareResult:
    """APE and/or RPE of an estimated trajectory against a reference, computed by evo.

    Parameters
    ----------
    est, ref : Trajectory-like or tuple
        evo ``PoseTrajectory3D``, objects with ``t_s``, ``position_world``, ``quat_xyzw``, or
        tuples ``(t_s, positions (N, 3), quat_xyzw (N, 4))``
        (:func:`splineimu.api.compare.compare` also takes TUM files).
    metric : {"ape", "rpe", "both"}
    pose_relation : {"trans", "rot", "full", "angle_deg", "angle_rad", "point_distance"}
        See the module notes for evo's equivalents.
    align : {"none", "se3", "sim3", "origin"}
        evo's (no option), ``-a``, ``-a -s`` and ``--align_origin``.
    delta, delta_unit : float, {"f", "m", "d", "r", "s"}
        RPE pose-pair spacing (evo's ``-d``, ``-u``; ``s`` = seconds, see module notes).
    all_pairs : bool
        RPE over all pairs with that spacing instead of consecutive ones (evo's ``--all_pairs``).
    t_max_diff : float
        Largest stamp difference [s] for associating poses (evo's ``--t_max_diff``).
    t_offset : float
        Constant offset [s] added to the estimate's stamps for association (``--t_offset``).

    Returns
    -------
    CompareResult

    Raises
    ------
    SplineImuError
        evo is not installed.
    InputError
        A trajectory without poses.
    ConfigError
        Bad options, no associated stamps, or an RPE delta that gives no pose pairs.

    Notes
    -----
    The alignment is estimated once on the associated poses and used for both metrics, as
    ``evo_ape`` and ``evo_rpe`` each do. RPE is invariant to a rigid alignment but not to
    the scale of a Sim3 alignment.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(10.0)
    >>> p = np.c_[t, np.zeros(10), np.zeros(10)]
    >>> q = np.tile([0.0, 0.0, 0.0, 1.0], (10, 1))
    >>> r = compare((t, p + [0.0, 0.1, 0.0], q), (t, p, q))
    >>> round(r.ape.stats["rmse"], 6)
    0.1
    """
    metrics, sync, _, _ = _evo()
    delta, t_max_diff = check_compare_options(metric, pose_relation, align, delta, delta_unit, t_max_diff,
                                              t_offset)
    relation = getattr(metrics.PoseRelation, POSE_RELATIONS[pose_relation])

    traj_est = _as_evo(est, "est")
    traj_ref = _as_evo(ref, "ref")
    spans = [(t.num_poses, float(t.timestamps[0]), float(t.timestamps[-1])) for t in (traj_est, traj_ref)]
    try:
        traj_ref, traj_est = sync.associate_trajectories(
            traj_ref, traj_est, max_diff=float(t_max_diff), offset_2=float(t_offset))
    except sync.SyncException as exc:
        raise ConfigError(str(exc)) from None

    alignment = None
    if align in ("se3", "sim3"):
        try:
            r, t, s = traj_est.align(traj_ref, correct_scale=(align == "sim3"))
        except Exception as exc:  # evo's GeometryException: degenerate input for Umeyama
            raise ConfigError(f"alignment failed: {exc}") from None
        alignment = np.eye(4)
        alignment[:3, :3] = s * r
        alignment[:3, 3] = t
    elif align == "origin":
        alignment = np.asarray(traj_est.align_origin(traj_ref), dtype=np.float64)

    ape_res = rpe_res = None
    if metric in ("ape", "both"):
        m = metrics.APE(relation)
        m.process_data((traj_ref, traj_est))
        ape_res = MetricResult("ape", pose_relation, m.unit.value, _title(m, align),
                               dict(m.get_all_statistics()), np.asarray(m.error, dtype=np.float64),
                               np.asarray(traj_est.timestamps, dtype=np.float64).copy())
    if metric in ("rpe", "both"):
        frames = None
        if delta_unit == "s":
            frames = _frames_from_seconds(np.asarray(traj_est.timestamps), float(delta))
            d, unit = frames, metrics.Unit.frames
        else:
            unit = getattr(metrics.Unit, DELTA_UNITS[delta_unit])
            d = int(delta) if delta_unit == "f" else float(delta)
        try:
            m = metrics.RPE(relation, d, unit, 0.1, all_pairs, False)
            m.process_data((traj_ref, traj_est))
        except Exception as exc:  # evo's MetricsException / FilterException
            raise ConfigError(f"RPE: {exc}") from None
        rpe_res = MetricResult("rpe", pose_relation, m.unit.value, _title(m, align),
                               dict(m.get_all_statistics()), np.asarray(m.error, dtype=np.float64),
                               np.asarray(traj_est.timestamps, dtype=np.float64)[m.delta_ids].copy(),
                               delta_frames=frames)
    return CompareResult(
        ape=ape_res, rpe=rpe_res, n_associated=int(traj_est.num_poses), align=align,
        alignment_sim3=alignment, timestamps_s=np.asarray(traj_est.timestamps, dtype=np.float64).copy(),
        ref_positions=np.array(traj_ref.positions_xyz, dtype=np.float64),
        est_positions_aligned=np.array(traj_est.positions_xyz, dtype=np.float64),
        notes=_association_notes(int(traj_est.num_poses), spans, t_offset),
    )


def _association_notes(n: int, spans, t_offset: float) -> list:
    """A note when fewer than half the poses of the shorter trajectory were associated (stamps in
    ns against s gave 1 of 399 poses and an APE of exactly 0, in silence)."""
    (n_est, e0, e1), (n_ref, r0, r1) = spans
    if n >= 0.5 * min(n_est, n_ref):
        return []
    return [f"only {n} of {n_est} estimated and {n_ref} reference poses were associated: the stamps span "
            f"[{e0 + t_offset:.9g}, {e1 + t_offset:.9g}] s (estimate{' + --t-offset' if t_offset else ''}) and "
            f"[{r0:.9g}, {r1:.9g}] s (reference); check their units and --t-max-diff"]
