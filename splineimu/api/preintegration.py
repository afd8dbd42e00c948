"""Preintegration of a recording on disk: :func:`evaluate_recording`, the job behind ``splineimu preintegrate``.

Reads the IMU csv and the ground truth of an output folder and compares the deltas preintegrated
over windows with the true ones (:func:`splineimu.preintegration.evaluate_windows`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path

from ..errors import ConfigError
from ..io.dataset import GROUNDTRUTH_CSV, IMU_CSV, dataset_file, recorded_sampling
from ..io.euroc import read_groundtruth
from ..io.imu_csv import read_imu_csv
from ..io.timestamps import read_timestamps
from ..motion import DEFAULT_GRAVITY
from ..preintegration.windows import WindowResult, evaluate_windows, make_windows, noise_densities
from .clock import StampClock, stamp_clock

__all__ = ["RecordingWindows", "evaluate_recording"]


@dataclass
class RecordingWindows(WindowResult):
    """:class:`~splineimu.preintegration.windows.WindowResult` of a recording on disk, with the
    IMU clock its stamps were corrected for.

    Attributes
    ----------
    clock : splineimu.api.clock.StampClock
        The window bounds ``t_i_ns``, ``t_j_ns`` are true times (the ground truth's); the IMU
        stamps were mapped to them with this clock (identity: read as true time).
    """

    clock: StampClock = field(default_factory=StampClock)

    @property
    def clock_line(self) -> str:
        """One line on the clock correction (``""`` without one), for the command's summary."""
        return self.clock.line


def evaluate_recording(folder, *, imu_csv=None, groundtruth=None, every=None, stamps=None, imu=None,
                       method: str = "midpoint", covariance: str = "consistent",
                       gravity=DEFAULT_GRAVITY, sampling: str | None = None, time_offset_s: float | None = None,
                       clock_drift_ppm: float | None = None) -> RecordingWindows:
    """Preintegrate a recording's IMU over windows and compare with its ground truth.

    Parameters
    ----------
    folder : path-like
        Output folder with ``mav0/imu0/data.csv`` and ``mav0/state_groundtruth_estimate0/data.csv``
        (or the older layout without ``mav0/``).
    imu_csv, groundtruth : path-like, optional
        Other files instead of the folder's.
    every : int, optional
        Window length in IMU samples (default: about 1 s).
    stamps : path-like or (S,) int64 array_like, optional
        Window bounds instead: a file whose first column holds ns (integers) or s (decimals),
        or the stamps themselves.
    imu : path-like or str, optional
        Noise densities (IMU yaml, Kalibr chain or preset name) for the covariance and NEES;
        default ``folder/imu.yaml`` when it exists, else no NEES.
    method, covariance, gravity
        As in :func:`evaluate_windows`.
    sampling : {"point", "mean"}, optional
        Default: as recorded with the data (:func:`splineimu.io.dataset.recorded_sampling`).
    time_offset_s, clock_drift_ppm : float, optional
        The IMU clock: it reads true time + ``time_offset_s``, running fast by
        ``clock_drift_ppm``. Each defaults to what the folder's ``report.json`` records
        (``timing.model``; 0 without one); 0 turns that correction off
        (:func:`splineimu.api.clock.stamp_clock`). The IMU stamps are mapped to true time
        before the windows are cut and compared with the ground truth. Read as true time, the
        12.3 ms offset of ``examples/timing_scene.yaml`` put the ellipse's 1 s position deltas
        0.08 m off (6e-5 m corrected).

    Returns
    -------
    RecordingWindows

    Raises
    ------
    ConfigError
        A missing file, or windows that do not fit the data.
    InputError
        Unreadable files.
    """
    out = Path(folder)
    if out.is_file() and not (imu_csv and groundtruth):  # said "IMU csv not found: imu.csv/mav0/imu0/data.csv"
        raise ConfigError(f"{out} is a file, not an output folder: give the folder (OUT of splineimu scene / "
                          "from-tum), or the files with --imu-csv and --groundtruth")
    imu_path = Path(imu_csv) if imu_csv else dataset_file(out, IMU_CSV)
    gt_path = Path(groundtruth) if groundtruth else dataset_file(out, GROUNDTRUTH_CSV)
    for p, what in ((imu_path, "IMU csv"), (gt_path, "ground truth")):
        if not p.is_file():
            raise ConfigError(f"{what} not found: {p}")
    noise_spec = imu if imu else (out / "imu.yaml" if (out / "imu.yaml").is_file() else None)
    noise = noise_densities(noise_spec) if noise_spec is not None else None
    if sampling is None:
        sampling = recorded_sampling(imu_path) if imu_path.is_file() else "point"
    clock = stamp_clock(imu_path, time_offset_s, clock_drift_ppm)
    stamp_ns, gyro, accel = read_imu_csv(imu_path)
    t_ns = clock.true_times_ns(stamp_ns)
    gt = read_groundtruth(gt_path)
    if isinstance(stamps, (str, Path)):
        stamps = read_timestamps(stamps)
    windows = make_windows(t_ns, gt.t_ns, every=every, stamps_ns=stamps)
    res = evaluate_windows(t_ns, gyro, accel, gt, windows, noise=noise, method=method, covariance=covariance,
                           gravity=gravity, noise_source=str(noise_spec) if noise_spec is not None else "",
                           sampling=sampling)
    res.notes[:0] = clock.notes
    return RecordingWindows(**{f.name: getattr(res, f.name) for f in fields(WindowResult)}, clock=clock)
