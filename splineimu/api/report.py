"""What a synthesis job reports: the ``report.json`` sections of its input, and its summary lines.

:func:`splineimu.api.output.write_output` adds the ``imu`` and ``versions`` sections. Nothing
here depends on the wall clock: the same job gives the same ``report.json`` bytes (timings are
printed, not written).
"""

from __future__ import annotations

#: FitReport keys that are not written to report.json (they differ from run to run).
UNREPEATABLE_KEYS = ("time_s",)


def spline_report(fit_report) -> dict:
    """The fit report as written to ``report.json`` (without timings)."""
    return {k: v for k, v in fit_report.to_dict().items() if k not in UNREPEATABLE_KEYS}


def poses_report(job, track, fit_report, gaps, max_gap_s) -> dict:
    """``source``, ``spline``, ``gaps``, ``rate_hz`` and ``timestamps_file`` of a pose-file job."""
    return {
        "source": {"kind": "pose file", "path": str(job.motion.path), "poses": int(track.t_ns.size),
                   "first_ns": int(track.t_ns[0]), "last_ns": int(track.t_ns[-1]), "notices": list(track.notices)},
        "spline": spline_report(fit_report),
        "gaps": {"max_gap_s": max_gap_s, "bridged": [
            {"start_ns": int(g.start_ns), "end_ns": int(g.end_ns), "duration_s": float(g.duration_s),
             "line": g.line} for g in gaps]},
        "rate_hz": None if job.imu.timestamps else job.imu.rate_hz,
        "timestamps_file": job.imu.timestamps,
        "warnings": fit_warnings(fit_report),
    }


def fit_warnings(fit_report) -> list:
    """The fit's warnings as report.json lists them: ``{code, message, t_start_ns, t_end_ns}``."""
    return list(fit_report.to_dict().get("warnings", []))


def scene_report(scene, job) -> dict:
    """``source`` and ``rate_hz`` (and ``timestamps_file`` when given) of a scene job."""
    rep = {"source": {"kind": "analytic scene", **scene.describe()}, "rate_hz": job.imu.rate_hz, "warnings": []}
    if job.imu.timestamps:
        rep["rate_hz"] = None
        rep["timestamps_file"] = job.imu.timestamps
    return rep


def fit_lines(fit_report, gaps, max_gap_s) -> list[str]:
    """Summary lines of a spline fit (and of the gaps it bridged)."""
    lines = fit_report.summary().splitlines()
    if gaps:
        lines.append(f"gaps          {len(gaps)} longer than {max_gap_s:g} s bridged (listed in report.json)")
    return lines


def imu_line(t_ns, job, seed, detailed: bool = False) -> str:
    """One line on the synthesized samples: count, span, noise and seed."""
    n = int(t_ns.size)
    first, last = (int(t_ns[0]), int(t_ns[-1])) if n else (None, None)
    span = (last - first) / 1e9 if n else 0.0
    noise = "noise-free" if job.imu.imu_config is None else "sensor model (see imu.yaml)"
    seed_text = "" if seed is None else f", seed {seed}"
    if detailed:
        return f"imu           {n} samples over {span:.3f} s [{first} .. {last}] ns, {noise}{seed_text}"
    return f"imu           {n} samples, {span:.3f} s from {first} ns ({noise}{seed_text})"


__all__ = ["spline_report", "poses_report", "scene_report", "fit_lines", "imu_line", "UNREPEATABLE_KEYS"]
