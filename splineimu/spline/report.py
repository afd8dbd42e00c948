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
        phase = (self.knot_choice or {}).get("rotation", {}).get("knot_phase", 0.0) if self.kind == "split" else 0.0
        shift = f" (from {phase * self.knot_spacing_s * 1e3:.3f} ms before the first pose)" if phase else ""
        grid = (f"rotation order {self.order}, knot spacing {self.knot_spacing_s * 1e3:.3f} ms{shift}; position order "
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
        lines += [f"note          {n}" for n in self.notes]
        for w in self.warnings:
            lines.append(f"warning       {w.message}")
        return "\n".join(lines)


def prediction_warnings(choice, t):
    """Warnings about large predicted errors, ends less accurate than the interior and gaps whose
    IMU is a guess."""
    if choice is None:
        return []
    out = []
    h = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    g, a = choice["predicted_gyro_rms_rad_s"], choice["predicted_accel_rms_m_s2"]
    if g > WARN_GYRO_RAD_S or a > WARN_ACCEL_M_S2:
        out.append(FitWarning("predicted_error_high", f"predicted error of the synthesized IMU is gyro ~{g:.3g} rad/s, "
                              f"accel ~{a:.3g} m/s^2 (above {WARN_GYRO_RAD_S:g} rad/s or {WARN_ACCEL_M_S2:g} m/s^2): "
                              "the poses are too noisy or too sparse for the motion"))
    for key, name, unit, lim in (("rotation", "gyro", "rad/s", WARN_GYRO_RAD_S),
                                 ("position", "accel", "m/s^2", WARN_ACCEL_M_S2)):
        c = choice[key]
        if c.get("predicted_rms_if_noise", 0.0) > 3.0 * c["predicted_rms"]:
            dt = 1e3 * c["knot_spacing_s"]
            what, noise = ((f"the top octave of the {key} poses was taken for motion (knots {dt:.3g} ms follow it, ",
                            "pose noise") if c["motion_limited"] else
                           (f"the {key} knots ({dt:.3g} ms) are finer than the poses (every {1e3 * h:.3g} ms) and "
                            "take their finest detail for motion (", "pose noise correlated over neighbouring poses "
                            "(as in interpolated input)"))
            out.append(FitWarning(
                "prediction_assumes_motion", f"{what}predicted {name} error ~{c['predicted_rms']:.3g} {unit}); if it "
                f"is {noise}, the {name} error is up to ~{c['predicted_rms_if_noise']:.3g} {unit} (a coarser knot "
                "spacing smooths it)"))
        if c["end_predicted_rms"] > max(3.0 * c["predicted_rms"], lim):
            z = c["end_zone_s"]
            out.append(FitWarning("ends_less_accurate", f"the first and last {z:.3f} s are less accurate ({name} "
                                  f"~{c['end_predicted_rms']:.3g} {unit} against ~{c['predicted_rms']:.3g} inside): "
                                  f"trim {z:.3f} s from each end", float(t[0]), float(t[-1])))
    # gaps: one warning per gap whose IMU error (either quantity) is far above the rest's, or not measured
    told = {}
    for key, name, unit, lim in (("rotation", "gyro", "rad/s", WARN_GYRO_RAD_S),
                                 ("position", "accel", "m/s^2", WARN_ACCEL_M_S2)):
        c = choice[key]
        for gp in c.get("gaps", []):
            e = gp["predicted_rms"]
            if e is None or e > max(3.0 * c["predicted_rms"], lim):  # (None: longer than any gap it can open)
                said = None if e is None else f"{name} ~{e:.3g} {unit} against ~{c['predicted_rms']:.3g} elsewhere"
                told.setdefault((gp["t_start_s"], gp["t_end_s"]), []).append((name, said))
    for (a, b), what in sorted(told.items()):
        known = [w for _, w in what if w is not None]
        unknown = [n for n, w in what if w is None]
        how = [", ".join(known) + ", measured by opening gaps that long where there are poses"] if known else []
        how += [f"{' and '.join(unknown)} error{'s' * (len(unknown) > 1)} not measured: no stretch of poses is that "
                "long"] if unknown else []
        out.append(FitWarning("gap_bridged", f"no poses from {a:.3f} s to {b:.3f} s ({b - a:.3f} s): the IMU there is "
                              f"the fit's guess ({'; '.join(how)})", a, b))
    return out
