"""Overlapping Allan deviation of IMU data and identification of its noise parameters.

- :mod:`.deviation`: :func:`allan_deviation` (the curves, equal to ``allantools.oadev``), cluster
  times, equivalent degrees of freedom and 95 % intervals (NIST SP 1065);
- :mod:`.fit`: :func:`fit_noise_parameters`, white noise N, random walk K and bias instability B
  in Kalibr's continuous units;
- :mod:`.report`: the Kalibr-keyed ``allan.yaml`` mapping (:func:`imu_noise_dict`) and the text table;
- :mod:`.plot`: :func:`plot_allan`;
- :mod:`.recording`: :func:`analyze_recording` and :func:`write_allan_outputs`, what
  ``splineimu allan`` runs.
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
from .plot import plot_allan
from .recording import AllanAnalysis, allan_output_paths, analyze_recording, write_allan_outputs
from .report import format_table, imu_noise_dict

__all__ = [
    "AllanResult", "NoiseFit", "AllanAnalysis", "allan_deviation", "fit_noise_parameters", "default_cluster_factors",
    "edf_oadev", "FLICKER_FLOOR", "imu_noise_dict", "format_table", "plot_allan", "analyze_recording",
    "allan_output_paths", "write_allan_outputs",
]
