"""Settings of a calibration: one validated object for the library, the command line and files."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..errors import ConfigError
from ..validation import finite_float, nonnegative_float, positive_float

__all__ = ["CalibrationOptions"]


def _per_axis(v, name: str, allow_zero: bool = False):
    """``None`` or three positive (or with ``allow_zero`` non-negative) floats; a scalar applies to every axis."""
    if v is None:
        return None
    vals = list(v) if isinstance(v, (list, tuple)) or hasattr(v, "__array__") else [v]
    if len(vals) == 1:
        vals = vals * 3
    if len(vals) != 3:
        raise ConfigError(f"`{name}` must be one value or three (x, y, z), got {len(vals)}", option=name)
    check = nonnegative_float if allow_zero else positive_float
    return tuple(check(x, name) for x in vals)


@dataclass(frozen=True)
class CalibrationOptions:
    """How the steady phases are found, assigned and weighted (:mod:`splineimu.calibration`).

    Attributes
    ----------
    tilt_sigma_deg : float, default 0
        Standard deviation of each component of the orientation error of every position /
        mount [deg]. 0: the nominal method (references exactly along the axes); > 0: the
        tilts are marginalized with this prior and the nominal estimate is kept beside.
    noise_density : float or (3,) float, optional
        White-noise density for the weights (accelerometer m/s^2/sqrt(Hz), gyro
        rad/s/sqrt(Hz)); default: each phase's own sample standard deviation.
    window_s : float, default 0.5
        Moving window of the segmentation [s].
    threshold : float, default 1.5
        Steady when the moving standard deviation is at most ``threshold`` times the noise level.
    min_dwell_s : float, default 2
        Shortest steady phase kept [s].
    margin_s : float, optional
        Samples dropped at each end of a phase that borders motion [s]; default ``2 window_s``.
    drift_threshold : float, default 5
        Largest difference of the two half-window means, in standard deviations of it.
    max_axis_angle_deg : float, default 25
        Largest angle between a phase's mean and the nearest axis for it to be used [deg].
    random_walk : float or (3,) float, optional
        Bias random-walk density of the sensor (accelerometer m/s^3/sqrt(Hz), gyro
        rad/s^2/sqrt(Hz)) for the drift of the bias over the phases' timeline; default: estimated
        from the phases (:func:`~splineimu.calibration.drift.estimate_random_walk`); 0: no drift.

    Raises
    ------
    ConfigError
        A value out of its range (the message names the field).

    Examples
    --------
    >>> CalibrationOptions(tilt_sigma_deg=2).window_s
    0.5
    >>> CalibrationOptions(noise_density=2e-3).noise_density
    (0.002, 0.002, 0.002)
    >>> CalibrationOptions(window_s=0)
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: `window_s` must be positive, got 0
    """

    tilt_sigma_deg: float = 0.0
    noise_density: float | tuple | None = None
    window_s: float = 0.5
    threshold: float = 1.5
    min_dwell_s: float = 2.0
    margin_s: float | None = None
    drift_threshold: float = 5.0
    max_axis_angle_deg: float = 25.0
    random_walk: float | tuple | None = None

    def __post_init__(self):
        put = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 - frozen dataclass
        put("tilt_sigma_deg", nonnegative_float(self.tilt_sigma_deg, "tilt_sigma_deg"))
        put("noise_density", _per_axis(self.noise_density, "noise_density"))
        for name in ("window_s", "threshold", "min_dwell_s", "drift_threshold"):
            put(name, positive_float(getattr(self, name), name))
        if self.margin_s is not None:
            put("margin_s", nonnegative_float(self.margin_s, "margin_s"))
        ang = finite_float(self.max_axis_angle_deg, "max_axis_angle_deg")
        if not 0 < ang < 45:
            raise ConfigError(f"`max_axis_angle_deg` must be in (0, 45), got {self.max_axis_angle_deg!r}",
                              option="max_axis_angle_deg")
        put("max_axis_angle_deg", ang)
        put("random_walk", _per_axis(self.random_walk, "random_walk", allow_zero=True))

    @property
    def effective_margin_s(self) -> float:
        """``margin_s``, or its default ``2 window_s``."""
        return 2.0 * self.window_s if self.margin_s is None else self.margin_s

    @property
    def tilt_sigma_rad(self) -> float:
        return math.radians(self.tilt_sigma_deg)

    def segmentation(self) -> dict:
        """The keyword arguments of :func:`~splineimu.calibration.find_steady_phases`."""
        return {"window_s": self.window_s, "threshold": self.threshold, "min_dwell_s": self.min_dwell_s,
                "margin_s": self.margin_s, "drift_threshold": self.drift_threshold}

    @classmethod
    def merged(cls, options: CalibrationOptions | None, settings: dict, caller: str) -> CalibrationOptions:
        """``options`` (or the defaults) with the fields named in ``settings`` replaced."""
        base = cls() if options is None else options
        if not isinstance(base, cls):
            raise ConfigError(f"`options` must be a CalibrationOptions, got {type(options).__name__}")
        names = {f.name for f in dataclasses.fields(cls)}
        for k in settings:
            if k not in names:
                raise TypeError(f"{caller}() got an unexpected keyword argument {k!r}")
        return dataclasses.replace(base, **settings) if settings else base
