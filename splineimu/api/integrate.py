"""Dead reckoning of a recording on disk: :func:`dead_reckon`, the job behind ``splineimu integrate``.

Reads an EuRoC IMU csv and the ground truth for its initial state, and integrates with
:func:`splineimu.integrate.integrate` (the strapdown equations and methods are described there).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError
from ..integrate import METHODS, SAMPLINGS, NavState, Trajectory, integrate
from ..io.dataset import groundtruth_beside, recorded_sampling
from ..io.euroc import read_groundtruth
from ..io.files import check_output_file
from ..io.imu_csv import read_imu_csv
from ..io.tum import write_tum
from ..motion import DEFAULT_GRAVITY
from ..validation import one_of
from .clock import StampClock, stamp_clock

__all__ = ["DeadReckoning", "dead_reckon", "default_groundtruth_path"]



@dataclass
class DeadReckoning:
    """A recording dead-reckoned from its ground-truth initial state (:func:`dead_reckon`).

    Attributes
    ----------
    trajectory : Trajectory
        From the first IMU sample inside the ground truth's span; ``t_s`` relative to it.
    t_ns : (N,) int64
        The true times of the trajectory's rows [ns]: the IMU stamps corrected for the clock's
        offset and drift (the stamps themselves when the clock is not modelled).
    stamp_ns : (N,) int64
        The IMU stamps of the rows as written [ns].
    clock : splineimu.api.clock.StampClock
        The IMU clock the stamps were corrected for; its ``time_offset_s``, ``clock_drift_ppm``
        (0: none) and ``source`` (``report.json``'s path, ``"given"``, ``""``: no correction)
        are also attributes here (``clock_source``).
    imu_path, groundtruth_path : pathlib.Path
    skipped_samples : int
        IMU samples before the ground truth starts (not integrated).
    final_position_error_m : float or None
        Distance to the ground truth at the last stamp; None when that lies outside it.
    integrate_time_s : float
        Wall time of the integration alone [s] (for the command's report; not a result).
    notes : list of str
        What the result depends on that the input did not say (gaps between the IMU stamps).
    """

    trajectory: Trajectory
    t_ns: np.ndarray
    imu_path: Path
    groundtruth_path: Path
    skipped_samples: int = 0
    final_position_error_m: float | None = None
    integrate_time_s: float = 0.0
    sampling: str = "point"
    notes: list = field(default_factory=list)
    stamp_ns: np.ndarray | None = None
    clock: StampClock = field(default_factory=StampClock)

    @property
    def time_offset_s(self) -> float:
        return self.clock.time_offset_s

    @property
    def clock_drift_ppm(self) -> float:
        return self.clock.clock_drift_ppm

    @property
    def clock_source(self) -> str:
        return self.clock.source

    @property
    def clock_line(self) -> str:
        """One line on the clock correction (``""`` without one), for the command's summary."""
        return self.clock.line

    @property
    def method(self) -> str:
        return self.trajectory.method

    def to_dataframe(self):
        """:meth:`Trajectory.to_dataframe` with the stamps ``t_ns`` in front."""
        df = self.trajectory.to_dataframe()
        df.insert(0, "t_ns", self.t_ns)
        return df

    def write_tum(self, path, force: bool = True, inputs=()) -> Path:
        """Write the trajectory as a TUM file (stamps exact from ``t_ns``), atomically.

        Missing parent folders are created (as every command's ``-o`` does).

        Parameters
        ----------
        path : path-like
        force : bool, default True
            Replace an existing file (the command passes its ``--force``).
        inputs : sequence of path-like
            Files that ``path`` may not be (:func:`splineimu.io.files.check_output_file`).

        Raises
        ------
        OutputExistsError
            ``path`` exists and ``force`` is False.
        ConfigError
            ``path`` is a folder, a symbolic link or an input.
        """
        out = check_output_file(path, force, inputs)
        out.parent.mkdir(parents=True, exist_ok=True)
        return write_tum(out, self.t_ns, self.trajectory.position_world, self.trajectory.quat_xyzw)


def default_groundtruth_path(imu_csv) -> Path:
    """``OUT/mav0/state_groundtruth_estimate0/data.csv`` for ``OUT/mav0/imu0/data.csv`` (and the
    same without ``mav0/``)."""
    return groundtruth_beside(imu_csv)


def dead_reckon(imu_path, init=None, method: str = "rk4", gravity=DEFAULT_GRAVITY,
                sampling: str | None = None, time_offset_s: float | None = None,
                clock_drift_ppm: float | None = None) -> DeadReckoning:
    """Dead-reckon an EuRoC IMU csv from the ground-truth state at its first covered sample.

    Parameters
    ----------
    imu_path : path-like
        EuRoC ``imu0/data.csv`` (gyro [rad/s], specific force [m/s^2]).
    init : path-like, optional
        EuRoC 17-column ground truth for the initial pose, velocity and (constant) biases;
        default :func:`default_groundtruth_path`. The state is interpolated
        (:class:`splineimu.groundtruth.GroundTruth`) to the first IMU stamp inside its span;
        earlier samples are skipped.
    method : {"euler", "midpoint", "rk4"}
    gravity : (3,) array_like
        ``g_w`` [m/s^2].
    sampling : {"point", "mean"}, optional
        How the samples were taken; default: as recorded with the data
        (:func:`splineimu.io.dataset.recorded_sampling`: ``report.json`` of the output folder,
        else point).
    time_offset_s, clock_drift_ppm : float, optional
        The IMU clock: it reads true time + ``time_offset_s``, running fast by
        ``clock_drift_ppm`` (:class:`splineimu.imu.timing.TimingModel`). Each defaults to what
        ``report.json`` of the output folder records (``timing.model``; 0 without one); 0 turns
        that correction off (:func:`splineimu.api.clock.stamp_clock`). The stamps are mapped to
        true time (:meth:`~splineimu.imu.timing.TimingModel.true_times_ns`) before the initial state is
        taken and the samples integrated, and the trajectory is written at the true times.
        Left uncorrected, the 12.3 ms offset of ``examples/timing_scene.yaml`` puts the ellipse
        1.19 m off after 10 s.

    Returns
    -------
    DeadReckoning

    Raises
    ------
    ConfigError
        Missing ground-truth file, or no IMU samples inside its span.
    InputError
        Unreadable files.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "imu.csv").write_text("".join(f"{i * 5000000},0,0,0,0,0,9.81\\n" for i in range(5)))
    >>> _ = (d / "gt.csv").write_text("0,1,2,3,1" + ",0" * 12 + "\\n40000000,1,2,3,1" + ",0" * 12 + "\\n")
    >>> r = dead_reckon(d / "imu.csv", init=d / "gt.csv", method="euler")
    >>> r.t_ns.tolist(), r.trajectory.position_world[-1].tolist(), r.final_position_error_m
    ([0, 5000000, 10000000, 15000000, 20000000], [1.0, 2.0, 3.0], 0.0)
    """
    import time

    imu_path = Path(imu_path)
    sampling = recorded_sampling(imu_path) if sampling is None else one_of(sampling, "sampling", SAMPLINGS)
    if not imu_path.is_file():
        raise InputError("IMU file not found" if not imu_path.exists() else "is a folder, expected an IMU csv",
                         path=imu_path)
    gt_path = Path(init) if init is not None else default_groundtruth_path(imu_path)
    if not gt_path.is_file():
        hint = "" if init is not None else " (the default beside the IMU file); pass --init GROUND_TRUTH"
        what = "is a folder, expected the ground-truth csv" if gt_path.is_dir() else "not found"
        raise ConfigError(f"initial-state file {what}: {gt_path}{hint}")
    one_of(method, "method", METHODS)
    clock = stamp_clock(imu_path, time_offset_s, clock_drift_ppm)
    stamp_ns, gyro, accel = read_imu_csv(imu_path)
    t_ns = clock.true_times_ns(stamp_ns)
    gt = read_groundtruth(gt_path)
    i0 = int(np.searchsorted(t_ns, gt.t_ns[0], side="left"))
    if i0 >= t_ns.shape[0] or t_ns[i0] > gt.t_ns[-1]:
        raise ConfigError(f"no IMU sample lies inside the ground truth's time span "
                          f"[{gt.t_ns[0]}, {gt.t_ns[-1]}] ns of {gt_path}")
    s = gt.state_at(t_ns[i0])
    init_state = NavState(0.0, s.position_world, s.quat_xyzw, s.velocity_world, s.bias_gyro, s.bias_accel)
    t_ns = t_ns[i0:]
    if t_ns.shape[0] < 2:
        raise ConfigError(f"fewer than 2 IMU samples inside the ground truth's time span ({gt_path})")
    t_s = (t_ns - t_ns[0]).astype(np.float64) / 1e9
    tic = time.perf_counter()
    traj = integrate(t_s, gyro[i0:], accel[i0:], init_state, method=method, gravity=gravity, sampling=sampling)
    elapsed = time.perf_counter() - tic
    err = None
    if gt.covers(t_ns[-1]):
        err = float(np.linalg.norm(traj.position_world[-1] - gt.state_at(t_ns[-1]).position_world))
    return DeadReckoning(traj, t_ns, imu_path, gt_path, skipped_samples=i0, final_position_error_m=err,
                         integrate_time_s=elapsed, sampling=sampling, notes=list(clock.notes) + _gap_notes(t_ns),
                         stamp_ns=stamp_ns[i0:], clock=clock)


def _gap_notes(t_ns) -> list:
    """A note on stamp gaps longer than 1.5 median intervals: a step across one integrates the
    motion in between from its two end samples alone (1 s missing from the ellipse: 17 m)."""
    d = np.diff(t_ns)
    med = float(np.median(d))
    gaps = np.flatnonzero(d > 1.5 * med)
    if gaps.size == 0:
        return []
    k = int(gaps[np.argmax(d[gaps])])
    return [f"{gaps.size} gap(s) in the IMU stamps longer than 1.5 sample intervals (longest {d[k] / 1e9:.6g} s "
            f"after {(t_ns[k] - t_ns[0]) / 1e9:.6g} s): the motion across a gap is integrated from its two end "
            "samples alone"]
