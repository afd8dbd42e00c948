"""What a fit did and what to watch out for: :class:`FitReport` and :class:`FitWarning`."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

#: Predicted errors above these are warned about (rad/s, m/s^2).
WARN_GYRO_RAD_S = 0.1
WARN_ACCEL_M_S2 = 1.0


@dataclass
class FitWarning:
    """A problem of a fit worth telling the user: machine-readable ``code``, one-line ``message``,
    and the time range (seconds in the fit's time base) where it is local."""

    code: str
    message: str
    t_start_s: float | None = None
    t_end_s: float | None = None

    def to_dict(self, origin_ns: int = 0) -> dict:
        """``code``, ``message`` and, where local, ``t_start_ns`` / ``t_end_ns`` (integer ns)."""
        d = {"code": self.code, "message": self.message}
        if self.t_start_s is not None:
            d["t_start_ns"] = int(origin_ns) + int(round(self.t_start_s * 1e9))
            d["t_end_ns"] = int(origin_ns) + int(round(self.t_end_s * 1e9))
        return d


@dataclass
class FitReport:
    """What a fit did: layout of both grids, residuals, predicted errors, warnings (SI units).

    ``order`` and ``knot_spacing_s`` are the rotation grid's (for ``kind="se3"`` the only grid);
    ``position_order`` and ``position_knot_spacing_s`` the position grid's.
    """

    kind: str
    order: int
    knot_spacing_s: float
    knot_spacing_source: str
    n_poses: int
    n_control: int
    span_s: tuple
    residual_position_rms_m: float
    residual_position_max_m: float
    residual_angle_rms_rad: float
    residual_angle_max_rad: float
    iterations: int
    converged: bool
    time_s: float
    smoothness: float
    position_order: int = 0
    position_knot_spacing_s: float = 0.0
    n_position_control: int = 0
    predicted_gyro_rms_rad_s: float | None = None
    predicted_accel_rms_m_s2: float | None = None
    dropped_poses: list = field(default_factory=list)
    knot_choice: dict | None = None
    sparse_control_points: int = 0
    warnings: list = field(default_factory=list)
    origin_ns: int = 0
    notes: list = field(default_factory=list)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["span_s"] = list(self.span_s)
        d["warnings"] = [w.to_dict(self.origin_ns) for w in self.warnings]
        return d

    def summary(self) -> str:
        grid = (f"rotation order {self.order}, knot spacing {self.knot_spacing_s * 1e3:.3f} ms; position order "
                f"{self.position_order}, knot spacing {self.position_knot_spacing_s * 1e3:.3f} ms"
                if self.kind == "split" else f"order {self.order}, knot spacing {self.knot_spacing_s * 1e3:.3f} ms")
        lines = [
            f"spline        {self.kind}, {grid} ({self.knot_spacing_source}), "
            + (f"{self.n_control} control rotations, {self.n_position_control} control positions"
               if self.kind == "split" else f"{self.n_control} control poses"),
            f"fit residual  position rms {self.residual_position_rms_m * 1e3:.4f} mm "
            f"(max {self.residual_position_max_m * 1e3:.4f} mm), angle rms "
            f"{np.degrees(self.residual_angle_rms_rad):.5f} deg "
            f"(max {np.degrees(self.residual_angle_max_rad):.5f} deg)",
        ]
        if self.predicted_gyro_rms_rad_s is not None:
            lines.append(f"predicted     gyro error ~{self.predicted_gyro_rms_rad_s:.2e} rad/s, accel error "
                         f"~{self.predicted_accel_rms_m_s2:.2e} m/s^2")
        for w in self.warnings:
            lines.append(f"warning       {w.message}")
        return "\n".join(lines)
