"""Overlapping Allan deviation of IMU data and identification of its noise parameters.

- :mod:`.deviation`: :func:`allan_deviation` (the curves, equal to ``allantools.oadev``), cluster
  times, equivalent degrees of freedom and 95 % intervals (NIST SP 1065);
- :mod:`.fit`: :func:`fit_noise_parameters`, white noise N, random walk K and bias instability B
  in Kalibr's continuous units;
- :mod:`.report`: the Kalibr-keyed ``allan.yaml`` mapping (:func:`imu_noise_dict`) and the text table;
- :mod:`.recording`: :class:`AllanAnalysis`, the result of one recording.

Reading a recording and writing ``allan.yaml`` / ``allan.png`` (:func:`splineimu.api.analyze_recording`,
:func:`splineimu.api.write_allan_outputs`, :func:`splineimu.api.plot_allan`) are jobs of the library API.
"""

from __future__ import annotations

from .deviation import (
    FLICKER_FLOOR,
    AllanResult,
    allan_deviation,
    default_cluster_factors,
    edf_oadev,
)
from .fit import NoiseFit, fit_noise_parameters
from .recording import AllanAnalysis
from .report import format_table, imu_noise_dict

__all__ = [
    "AllanResult", "NoiseFit", "AllanAnalysis", "allan_deviation", "fit_noise_parameters", "default_cluster_factors",
    "edf_oadev", "FLICKER_FLOOR", "imu_noise_dict", "format_table",
]
