"""The Allan analysis of one recording (curves, fit, source); :mod:`splineimu.api.allan` reads the file
and writes ``allan.yaml`` / ``allan.png``."""

from __future__ import annotations

from dataclasses import dataclass, field

from .deviation import AllanResult
from .fit import NoiseFit
from .report import format_table, imu_noise_dict

__all__ = ["AllanAnalysis", "IMU_LABELS", "MIN_SAMPLES"]

#: Column names of a six-axis recording.
IMU_LABELS = ("gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z")


@dataclass
class AllanAnalysis:
    """Allan deviation and noise parameters of one recording.

    Attributes
    ----------
    result : AllanResult
        The six curves (gyro x y z [rad/s], accel x y z [m/s^2]) with their intervals.
    fit : NoiseFit
        N, K, B per axis.
    source : str
        The file analysed.
    notes : list of str
        What the reader assumed or found (an assumed rate, gaps).
    """

    result: AllanResult
    fit: NoiseFit
    source: str = ""
    notes: list = field(default_factory=list)

    @property
    def rate_hz(self) -> float:
        return self.result.rate_hz

    def to_dataframe(self):
        """One row per axis: the noise parameters and their intervals (:meth:`NoiseFit.to_dataframe`)."""
        return self.fit.to_dataframe()

    def noise_dict(self) -> dict:
        """The mapping written to ``allan.yaml`` (:func:`~splineimu.allan.imu_noise_dict`)."""
        return imu_noise_dict(self.result, self.fit, source=self.source)

    def format_table(self) -> str:
        """The text table ``splineimu allan`` prints."""
        return format_table(self.result, self.fit, source=self.source)


#: Fewest samples an Allan analysis accepts (its longest cluster time is a quarter of the record).
MIN_SAMPLES = 100
