"""VINS-style IMU preintegration with a covariance that matches the actual sample noise.

- :mod:`.preintegrator`: :class:`Preintegrator` (midpoint or Euler steps, bias Jacobians, two
  covariance models, residual and bias correction); its docstring derives the model;
- :mod:`.deltas`: :class:`Deltas`, the exact deltas of two states or a motion source
  (:func:`exact_deltas`), their error (:func:`delta_error`) and :func:`nees`;
- :mod:`.windows`: a recording preintegrated over windows and compared with its ground truth
  (:func:`evaluate_windows`); :func:`splineimu.api.evaluate_recording` reads one from disk, what
  ``splineimu preintegrate`` runs.
"""

from __future__ import annotations

from .deltas import Deltas, ExactDeltas, delta_error, deltas_from_states, exact_deltas, nees
from .preintegrator import COVARIANCE_MODELS, METHODS, STATE_ORDER, Preintegrator
from .windows import (
    KALIBR_KEYS,
    NeesTest,
    WindowResult,
    evaluate_windows,
    make_windows,
    noise_densities,
)

__all__ = [
    "Preintegrator", "Deltas", "ExactDeltas", "exact_deltas", "deltas_from_states", "delta_error", "nees",
    "METHODS", "COVARIANCE_MODELS", "STATE_ORDER", "WindowResult", "NeesTest", "evaluate_windows",
    "make_windows", "noise_densities", "KALIBR_KEYS",
]
