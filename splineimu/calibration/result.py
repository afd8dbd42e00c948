"""Results of a calibration: the steady phases and the estimated intrinsics with their covariance.

``K = M S`` (misalignment ``M`` with unit diagonal after scale ``S = I + diag(s)``) and the
bias ``b``; :attr:`SensorCalibration.covariance` is the 12x12 covariance of ``(K row-major,
b)`` in the order of :data:`PARAMETER_NAMES`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError

__all__ = ["PARAMETER_NAMES", "SteadyPhase", "SensorCalibration", "AccelCalibration", "GyroCalibration",
           "split_scale_misalignment"]

#: Likelihood-ratio statistic above which an estimated drift is significant (1% for a variance on
#: its boundary, the mixture of chi2_0 and chi2_1).
DRIFT_SIGNIFICANCE = 5.41

#: Names of the twelve estimated parameters, in the order of :attr:`SensorCalibration.covariance`.
PARAMETER_NAMES = tuple([f"K[{i},{j}]" for i in range(3) for j in range(3)] + [f"b[{i}]" for i in range(3)])


@dataclass
class SteadyPhase:
    """One steady phase (rest or constant rate) found in a recording.

    Attributes
    ----------
    start, stop : int
        Sample indices ``[start, stop)``.
    t_start_ns, t_end_ns : int
        Stamps of the first and last sample.
    samples : int
    mean : (3,) float64
        Mean of the calibrated sensor over the phase.
    std : (3,) float64
        Sample standard deviation per axis (ddof 1).
    var_mean : (3,) float64
        Variance of the mean used as its weight (``sigma^2 / n``).
    magnitude : float
        Reference magnitude ``a`` (``g``, ``+-rate`` or 0); NaN when unused.
    direction : (3,) float64
        Nominal unit direction ``u`` of the reference (zeros when unused or at rest).
    label : str
        ``"+x"``, ``"-z"`` (gravity or rate axis), ``"rest"``, or ``""``.
    group : int
        Orientation group (one tilt per group; -1 for none).
    used : bool
    note : str
        Why a phase was left out.
    tilt_rad : (2,) float64 or None
        Best linear prediction of the tilt of the phase's position / mount
        (``method="tilt"``) [rad], about the two axes other than the nominal one, in the order
        x, y, z (``u = Exp(theta) u0``).
    """

    start: int
    stop: int
    t_start_ns: int
    t_end_ns: int
    samples: int
    mean: np.ndarray
    std: np.ndarray
    var_mean: np.ndarray = field(default_factory=lambda: np.zeros(3))
    magnitude: float = float("nan")
    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    label: str = ""
    group: int = -1
    used: bool = False
    note: str = ""
    tilt_rad: np.ndarray | None = None

    def to_dict(self) -> dict:
        d = {
            "t_start_ns": int(self.t_start_ns), "t_end_ns": int(self.t_end_ns), "samples": int(self.samples),
            "mean": self.mean.tolist(), "std": self.std.tolist(), "reference": self.label or None,
            "used": bool(self.used),
        }
        if self.used:
            d["reference_value"] = (self.magnitude * self.direction).tolist()
        if self.tilt_rad is not None:
            d["tilt_deg"] = np.degrees(self.tilt_rad).tolist()
        if self.note:
            d["note"] = self.note
        return d



def split_scale_misalignment(K):
    """``K = M S`` with ``S = diag(1 + s)`` and a unit-diagonal ``M``.

    Returns
    -------
    scale : (3,) ``s = diag(K) - 1``
    misalignment : (3, 3) ``M = K S^-1``

    Examples
    --------
    >>> s, M = split_scale_misalignment([[1.01, 0.002, 0], [0, 0.99, 0], [0.001, 0, 1.0]])
    >>> s.round(6).tolist(), float(M[0, 1].round(9))
    ([0.01, -0.01, 0.0], 0.002020202)
    """
    K = np.asarray(K, dtype=np.float64)
    d = np.diag(K).copy()
    if np.any(np.abs(d) < 1e-12):
        raise ConfigError(f"scale-misalignment matrix has a zero diagonal entry: {d.tolist()}")
    return d - 1.0, K / d[None, :]



@dataclass
class SensorCalibration:
    """Estimated scale-misalignment matrix and bias of one sensor, with predicted uncertainty.

    Attributes
    ----------
    sensor : {"accelerometer", "gyroscope"}
    K : (3, 3) float64
        Scale-misalignment matrix ``M S`` (model ``y_m = K x + b``).
    bias : (3,) float64
    covariance : (12, 12) float64
        Covariance of ``(K row-major, b)`` (order :data:`PARAMETER_NAMES`).
    method : {"nominal", "tilt"}
        Exact nominal references, or random tilts marginalized (module docstring).
    tilt_sigma_rad : float
        Standard deviation of each tilt component assumed (0 for ``"nominal"``).
    phases : list of SteadyPhase
        Every steady phase found, used or not.
    chi2 : float
        Weighted sum of squared residuals of the phase means.
    dof : int
        ``3 * (phases used) - 12``.
    noise_level : (3,) float64
        White-noise standard deviation per sample, pooled over the phases used.
    noise_density : (3,) float64
        The same as a continuous density ``noise_level * sqrt(dt)``.
    segmentation : dict
        The segmentation settings and the per-channel noise level it used.
    nominal : SensorCalibration or None
        The classical (nominal-reference) estimate when ``method == "tilt"``.
    random_walk : (3,) float64
        Bias random-walk density used for the drift over the phases' timeline (zeros: none).
    random_walk_source : {"given", "estimated", "none"}
    random_walk_lr : float
        Likelihood-ratio statistic of the estimated drift against none (inf when given); above
        :data:`DRIFT_SIGNIFICANCE` the drift is significant.
    white_covariance : (12, 12) float64 or None
        :attr:`covariance` without the drift term (white noise and tilts only).
    """

    sensor: str
    K: np.ndarray
    bias: np.ndarray
    covariance: np.ndarray
    method: str
    tilt_sigma_rad: float
    phases: list
    chi2: float
    dof: int
    noise_level: np.ndarray
    noise_density: np.ndarray
    segmentation: dict = field(default_factory=dict)
    nominal: SensorCalibration | None = None
    random_walk: np.ndarray = field(default_factory=lambda: np.zeros(3))
    random_walk_source: str = "none"
    random_walk_lr: float = 0.0
    white_covariance: np.ndarray | None = None

    # ---------------------------------------------------------------- derived values
    @property
    def parameters(self) -> np.ndarray:
        """``(K row-major, b)`` (12,)."""
        return np.concatenate([self.K.ravel(), self.bias])

    @property
    def std(self) -> np.ndarray:
        """Predicted standard deviations of :attr:`parameters` (12,)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    @property
    def drift_share(self) -> float:
        """Largest share of a parameter's predicted variance that is due to the bias drift (0 to 1)."""
        if self.white_covariance is None:
            return 0.0
        total = np.diag(self.covariance)
        white = np.clip(np.diag(self.white_covariance), 0.0, None)
        ok = total > 0
        return float(np.max(1.0 - white[ok] / total[ok], initial=0.0))

    @property
    def drift_dominated(self) -> bool:
        """The bias drift, significant in the data (or given), sets the uncertainty of some parameter."""
        return self.drift_share > 0.5 and self.random_walk_lr > DRIFT_SIGNIFICANCE

    @property
    def K_std(self) -> np.ndarray:
        return self.std[:9].reshape(3, 3)

    @property
    def bias_std(self) -> np.ndarray:
        return self.std[9:]

    @property
    def scale(self) -> np.ndarray:
        """Scale-factor errors ``s = diag(K) - 1`` (3,)."""
        return split_scale_misalignment(self.K)[0]

    @property
    def misalignment(self) -> np.ndarray:
        """Unit-diagonal misalignment ``M = K diag(K)^-1`` (3, 3)."""
        return split_scale_misalignment(self.K)[1]

    def _derived_cov(self):
        """Covariance of ``(s (3), M row-major (9), b (3))`` by first-order propagation."""
        K = self.K
        d = np.diag(K)
        Jd = np.zeros((15, 12))
        for j in range(3):
            Jd[j, 4 * j] = 1.0
        for i in range(3):
            for j in range(3):
                r = 3 + 3 * i + j
                if i == j:
                    continue  # unit diagonal: no uncertainty
                Jd[r, 3 * i + j] = 1.0 / d[j]
                Jd[r, 4 * j] = -K[i, j] / d[j] ** 2
        Jd[12:, 9:] = np.eye(3)
        return Jd @ self.covariance @ Jd.T

    @property
    def scale_std(self) -> np.ndarray:
        return np.sqrt(np.diag(self._derived_cov())[:3])

    @property
    def misalignment_std(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self._derived_cov())[3:12], 0.0, None)).reshape(3, 3)

    # ---------------------------------------------------------------- use
    def correct(self, y) -> np.ndarray:
        """Corrected samples ``x = K^-1 (y - b)``, (N, 3) -> (N, 3)."""
        y = np.asarray(y, dtype=np.float64)
        return np.linalg.solve(self.K, (y - self.bias).T).T

    def to_config_dict(self) -> dict:
        """The sensor-model keys ``<sensor>_scale``, ``<sensor>_misalignment``, ``<sensor>_bias``."""
        s = self.sensor
        return {f"{s}_scale": self.scale.tolist(), f"{s}_misalignment": self.misalignment.tolist(),
                f"{s}_bias": self.bias.tolist()}

    def std_dict(self) -> dict:
        """Predicted standard deviations under the same keys as :meth:`to_config_dict`."""
        s = self.sensor
        return {f"{s}_scale": self.scale_std.tolist(), f"{s}_misalignment": self.misalignment_std.tolist(),
                f"{s}_bias": self.bias_std.tolist()}

    def to_imu_config(self):
        """An :class:`~splineimu.imu.config.ImuConfig` with the estimated intrinsics."""
        from ..imu.config import ImuConfig

        return ImuConfig.from_dict(self.to_config_dict(), source=f"{self.sensor} calibration")

    def to_dict(self) -> dict:
        """Plain mapping (numbers and lists) of everything: estimates, standard deviations, phases."""
        d = {
            "sensor": self.sensor,
            "method": self.method,
            **self._reference_dict(),
            "estimates": self.to_config_dict(),
            "std": self.std_dict(),
            "K": self.K.tolist(),
            "K_std": self.K_std.tolist(),
            "bias": self.bias.tolist(),
            "bias_std": self.bias_std.tolist(),
            "covariance_order": list(PARAMETER_NAMES),
            "covariance": self.covariance.tolist(),
            "tilt_sigma_deg": math.degrees(self.tilt_sigma_rad),
            "chi2": float(self.chi2),
            "dof": int(self.dof),
            "noise_density_estimate": self.noise_density.tolist(),
            "random_walk": self.random_walk.tolist(),
            "random_walk_source": self.random_walk_source,
            "drift_share": self.drift_share,
            "drift_lr_statistic": float(self.random_walk_lr),
            "segmentation": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.segmentation.items()},
            "phases": [p.to_dict() for p in self.phases],
        }
        if self.nominal is not None:
            n = self.nominal
            d["nominal_method"] = {"K": n.K.tolist(), "K_std": n.K_std.tolist(), "bias": n.bias.tolist(),
                                   "bias_std": n.bias_std.tolist(), "chi2": float(n.chi2), "dof": int(n.dof)}
        return d

    def _reference_dict(self) -> dict:  # pragma: no cover - overridden
        return {}


@dataclass
class AccelCalibration(SensorCalibration):
    """:class:`SensorCalibration` of the accelerometer; ``gravity_m_s2`` is the reference ``g``."""

    gravity_m_s2: float = 9.81

    def _reference_dict(self):
        return {"gravity_m_s2": float(self.gravity_m_s2)}


@dataclass
class GyroCalibration(SensorCalibration):
    """:class:`SensorCalibration` of the gyro; ``rates_rad_s`` are the table rate magnitudes."""

    rates_rad_s: tuple = ()

    def _reference_dict(self):
        return {"rates_rad_s": [float(r) for r in self.rates_rad_s]}
