"""Plain-text tables of a calibration: the phases, the estimates against a truth, the fit statistic."""

from __future__ import annotations

import numpy as np

from .result import PARAMETER_NAMES

__all__ = ["phase_table", "estimates_table", "chi2_summary"]


def phase_table(cal, unit: str) -> str:
    """One line per steady phase: time range, samples, reference, mean, tilt and note."""
    t0 = cal.phases[0].t_start_ns if cal.phases else 0
    lines = [f"{'phase':>5s}  {'t [s]':>17s}  {'samples':>7s}  {'ref':>5s}  {'mean [' + unit + ']':>36s}  note"]
    for k, p in enumerate(cal.phases):
        mean = np.array2string(p.mean, formatter={"float_kind": lambda v: f"{v:10.5f}"})
        note = p.note
        if p.tilt_rad is not None:
            d = np.degrees(p.tilt_rad)
            note = f"tilt {d[0]:+.2f} {d[1]:+.2f} deg" + (f"; {note}" if note else "")
        lines.append(f"{k:5d}  {(p.t_start_ns - t0) / 1e9:8.2f}-{(p.t_end_ns - t0) / 1e9:8.2f}  {p.samples:7d}  "
                     f"{(p.label if p.used else '-'):>5s}  {mean:>36s}  {note}")
    return "\n".join(lines)


def _columns(est, std, truth, k) -> str:
    """``estimate std [err/std]`` of parameter ``k``."""
    text = f" {est[k]:13.8f} {std[k]:9.2e}"
    return text + (f" {(est[k] - truth[k]) / std[k]:8.2f}" if truth is not None else "")


def _inside(est, std, truth) -> int:
    return int((np.abs(est - truth) <= 2 * std).sum())


def estimates_table(cal, truth=None) -> str:
    """The twelve parameters with their predicted std (and truth and error / std when known).

    ``truth`` is ``(K, b)`` or ``None``; with ``cal.nominal`` the nominal estimate is beside.
    """
    tv = None if truth is None else np.concatenate([np.asarray(truth[0]).ravel(), truth[1]])
    nom = cal.nominal
    with_err = f" {'err/std':>8s}" if tv is not None else ""
    head = f"{'param':7s}" + (f" {'truth':>13s}" if tv is not None else "")
    head += f" {'estimate':>13s} {'std':>9s}" + with_err
    if nom is not None:
        head += f"  | {'nominal':>13s} {'std':>9s}" + with_err
    lines = [head]
    for k, name in enumerate(PARAMETER_NAMES):
        row = f"{name:7s}" + (f" {tv[k]:13.8f}" if tv is not None else "") + _columns(cal.parameters, cal.std, tv, k)
        if nom is not None:
            row += "  |" + _columns(nom.parameters, nom.std, tv, k)
        lines.append(row)
    if tv is not None:
        lines.append(f"{_inside(cal.parameters, cal.std, tv)} of 12 within 2 predicted std"
                     + (f" (nominal method: {_inside(nom.parameters, nom.std, tv)} of 12)" if nom is not None else ""))
    return "\n".join(lines)


def chi2_summary(cal) -> tuple[str, bool]:
    """``(line, suspicious)``: the weighted residual sum with its p-value; suspicious when p < 1e-3."""
    from scipy.stats import chi2 as chi2_dist

    if cal.dof <= 0:
        return f"chi2 {cal.chi2:.3g} (no redundancy: {cal.dof} dof)", False
    p = float(chi2_dist.sf(cal.chi2, cal.dof))
    return f"chi2 {cal.chi2:.4g} for {cal.dof} dof (p = {p:.3g})", p < 1e-3
