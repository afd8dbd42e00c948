"""The IMU clock of a recording on disk: stamps written on an offset or drifting clock, read at true time.

``splineimu scene --time-offset S --clock-drift-ppm PPM`` writes the IMU stamps on the IMU's
own clock and the ground truth on true time, and records the clock in ``report.json``
(``timing.model``). Every job that reads the IMU against the ground truth (dead reckoning,
:func:`splineimu.api.dead_reckon`; preintegration, :func:`splineimu.api.evaluate_recording`)
maps the stamps to true time first through :func:`stamp_clock`: read as true time, the 12.3 ms
offset of ``examples/timing_scene.yaml`` put the dead-reckoned ellipse 1.19 m off after 10 s
and its 1 s preintegrated position deltas 0.08 m off, in silence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError, InputError
from ..io.dataset import recorded_timing
from ..validation import finite_float

__all__ = ["StampClock", "stamp_clock"]

_KEYS = ("time_offset_s", "clock_drift_ppm")


@dataclass(frozen=True)
class StampClock:
    """The IMU clock a recording's stamps were corrected for (:func:`stamp_clock`).

    Attributes
    ----------
    time_offset_s : float
        The clock reads true time + this offset (0: none).
    clock_drift_ppm : float
        The clock runs fast by this many parts per million (0: none).
    source : str
        Where the values came from: ``report.json``'s path, ``"given"``, the path followed by
        ``" and as given"``, or ``""`` when nothing is corrected.
    notes : tuple of str
        What the correction cannot undo (white noise on the stamps).

    Examples
    --------
    >>> clock = StampClock(time_offset_s=0.01, source="given")
    >>> clock.true_times_ns([10000000, 15000000]).tolist()
    [0, 5000000]
    >>> clock.line
    'IMU stamps corrected to true time (as given): clock offset 0.01 s, drift 0 ppm'
    """

    time_offset_s: float = 0.0
    clock_drift_ppm: float = 0.0
    source: str = ""
    notes: tuple = ()

    @property
    def is_identity(self) -> bool:
        """True when the stamps are read as true time."""
        return not (self.time_offset_s or self.clock_drift_ppm)

    def true_times_ns(self, stamp_ns) -> np.ndarray:
        """(N,) int64 true times of stamps on this clock
        (:meth:`splineimu.imu.timing.TimingModel.true_times_ns`)."""
        from ..imu.timing import TimingModel

        return TimingModel(time_offset_s=self.time_offset_s,
                           clock_drift_ppm=self.clock_drift_ppm).true_times_ns(stamp_ns)

    @property
    def line(self) -> str:
        """One line on the correction for a command's summary (``""`` without one)."""
        if self.is_identity:
            return ""
        where = "as given" if self.source == "given" else f"as recorded in {self.source}"
        return (f"IMU stamps corrected to true time ({where}): clock offset {self.time_offset_s:g} s, "
                f"drift {self.clock_drift_ppm:g} ppm")


def stamp_clock(imu_csv, time_offset_s: float | None = None, clock_drift_ppm: float | None = None) -> StampClock:
    """The IMU clock of a recording: the values given, else those ``report.json`` records.

    Parameters
    ----------
    imu_csv : path-like
        The recording's IMU csv; its output folder's ``report.json`` (``timing.model``,
        :func:`splineimu.io.dataset.recorded_timing`) gives each value not given.
    time_offset_s, clock_drift_ppm : float, optional
        The IMU clock reads true time + ``time_offset_s`` and runs fast by ``clock_drift_ppm``
        (:class:`splineimu.imu.timing.TimingModel`); 0 turns that part of the correction off.
        Both given: ``report.json`` is not read.

    Returns
    -------
    StampClock
        With a note when ``report.json`` records white noise on the stamps (not undone).

    Raises
    ------
    ConfigError
        A given value that is not finite, or a drift of 1e5 ppm or more.
    InputError
        ``report.json`` cannot be read, or records a clock that is not one.

    Examples
    --------
    >>> stamp_clock("imu.csv", time_offset_s=0.0123, clock_drift_ppm=0).line
    'IMU stamps corrected to true time (as given): clock offset 0.0123 s, drift 0 ppm'
    >>> stamp_clock("imu.csv", time_offset_s=0, clock_drift_ppm=float("nan"))
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: `clock_drift_ppm` must be finite, got nan
    """
    from ..imu.timing import TimingModel

    given = {k: finite_float(v, k) for k, v in zip(_KEYS, (time_offset_s, clock_drift_ppm)) if v is not None}
    recorded, report = ({}, None) if len(given) == 2 else recorded_timing(imu_csv)
    values = {k: given.get(k, recorded.get(k, 0.0)) for k in _KEYS}
    try:
        clock = TimingModel(**values)
    except ConfigError as exc:
        if exc.option in given:
            raise
        raise InputError(f"`timing.model.{exc.option}`: {exc.problem}", path=report) from None
    notes = ()
    noise = recorded.get("stamp_noise_s")
    if noise:
        notes = (f"the stamps carry white noise of {noise:g} s ({report}): only the clock's offset and "
                 "drift are undone",)
    if clock.is_identity:
        return StampClock(notes=notes)
    from_report = any(recorded.get(k) for k in _KEYS if k not in given)
    source = str(report) if from_report else "given"
    if from_report and any(given.values()):
        source += " and as given"
    return StampClock(clock.time_offset_s, clock.clock_drift_ppm, source, notes)

