"""Reports of an Allan analysis: the Kalibr-keyed ``allan.yaml`` mapping and the text table."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from .deviation import AllanResult
from .fit import NoiseFit

__all__ = ["imu_noise_dict", "format_table", "allan_yaml_header"]


def _r6(v) -> float:
    """Round to 6 significant digits (the estimates are not better than 1e-3 anyway)."""
    return float(f"{float(v):.6g}")


def _floats(a):
    return [_r6(v) for v in np.asarray(a, dtype=np.float64).ravel()]


def _pairs(a):
    return [[_r6(lo), _r6(hi)] for lo, hi in np.asarray(a, dtype=np.float64).reshape(-1, 2)]


def imu_noise_dict(result: AllanResult, fit: NoiseFit, source: str = "") -> dict:
    """Kalibr-keyed mapping of a six-axis fit (gyro x y z, accel x y z), as ``allan.yaml`` holds it.

    Each Kalibr key holds the three per-axis values, ``<key>_avg`` their mean and
    ``<key>_ci95`` one ``[low, high]`` pair per axis; ``update_rate`` is the data's rate. The
    ``allan`` section (bias instability, resolution flags, record length) is informational:
    :class:`splineimu.imu.config.ImuConfig` reads the file and ignores it.

    Raises
    ------
    InputError
        If the fit does not have six axes.
    """
    if fit.white_noise_density.shape != (6,):
        raise InputError("expected a six-axis fit (gyro xyz, accel xyz), "
                         f"got {fit.white_noise_density.shape[0]} axes")
    d: dict = {}
    sl = {"gyroscope": slice(0, 3), "accelerometer": slice(3, 6)}
    for sensor in ("gyroscope", "accelerometer"):
        for key, val, ci in (("noise_density", fit.white_noise_density, fit.white_noise_density_ci95),
                             ("random_walk", fit.random_walk, fit.random_walk_ci95)):
            v = val[sl[sensor]]
            d[f"{sensor}_{key}"] = _floats(v)
            d[f"{sensor}_{key}_avg"] = _r6(np.mean(v))
            d[f"{sensor}_{key}_ci95"] = _pairs(ci[sl[sensor]])
    d["update_rate"] = float(result.rate_hz)
    info: dict = {
        "source": str(source),
        "n_samples": int(result.n_samples),
        "duration_s": float(result.duration_s),
        "cluster_times": int(result.taus_s.size),
        "method": "overlapping Allan deviation; N on the -1/2 line at 1 s, K on the +1/2 line at 3 s, "
                  "B = curve minimum / 0.664; 95% chi-square intervals (NIST SP 1065 EDF)",
    }
    for sensor in ("gyroscope", "accelerometer"):
        s = sl[sensor]
        info[f"{sensor}_random_walk_resolved"] = [bool(v) for v in fit.random_walk_resolved[s]]
        info[f"{sensor}_bias_instability"] = _floats(fit.bias_instability[s])
        info[f"{sensor}_bias_instability_ci95"] = _pairs(fit.bias_instability_ci95[s])
        info[f"{sensor}_bias_instability_tau_s"] = _floats(fit.bias_instability_tau_s[s])
        info[f"{sensor}_bias_instability_resolved"] = [bool(v) for v in fit.bias_instability_resolved[s]]
    d["allan"] = info
    return d


def allan_yaml_header(result: AllanResult, source: str = "") -> list:
    """The comment lines at the top of ``allan.yaml``."""
    return [
        f"# splineimu allan: noise parameters identified from {source}",
        f"# {result.n_samples} samples at {result.rate_hz:.6g} Hz ({result.duration_s:.1f} s).",
        "# Each Kalibr key holds [x, y, z]; <key>_avg is their mean, <key>_ci95 the 95% interval",
        "# per axis.",
        "# Units: gyro noise rad/s/sqrt(Hz), gyro walk rad/s^2/sqrt(Hz), accel noise m/s^2/sqrt(Hz),",
        "# accel walk m/s^3/sqrt(Hz). Usable as `--imu` (the `allan` section is informational).",
    ]


def _fmt_ci(v, ci, mark=""):
    hi = "inf" if not math.isfinite(ci[1]) else f"{ci[1]:.3e}"
    return f"{v:.3e}{mark:1s} [{ci[0]:.3e}, {hi}]"


def format_table(result: AllanResult, fit: NoiseFit, source: str = "") -> str:
    """The text table of N, K and B per axis with their 95 % intervals (what ``splineimu allan`` prints).

    Examples
    --------
    >>> from splineimu.allan import allan_deviation, fit_noise_parameters
    >>> r = allan_deviation(np.random.default_rng(0).standard_normal(20_000), 100.0, labels=["x"])
    >>> print(format_table(r, fit_noise_parameters(r)).splitlines()[0])
      20000 samples at 100 Hz (200.0 s); 35 cluster times 0.01 s .. 50 s
    """
    lines = []
    if source:
        lines.append(f"Allan deviation of {source}")
    lines.append(f"  {result.n_samples} samples at {result.rate_hz:.6g} Hz ({result.duration_s:.1f} s); "
                 f"{result.taus_s.size} cluster times {result.taus_s[0]:.3g} s .. {result.taus_s[-1]:.4g} s")
    w = 37
    lines.append(f"{'axis':8s}  {'white noise N [95% CI]':{w}s}  {'random walk K [95% CI]':{w}s}  "
                 f"{'bias instability B [95% CI]':{w}s}  tau_B [s]")
    any_k = any_b = False
    for k in range(result.adev.shape[1]):
        km = "" if fit.random_walk_resolved[k] else "*"
        bm = "" if fit.bias_instability_resolved[k] else "~"
        any_k |= bool(km)
        any_b |= bool(bm)
        n_txt = _fmt_ci(fit.white_noise_density[k], fit.white_noise_density_ci95[k])
        k_txt = _fmt_ci(fit.random_walk[k], fit.random_walk_ci95[k], km)
        b_txt = _fmt_ci(fit.bias_instability[k], fit.bias_instability_ci95[k], bm)
        lines.append(f"{result.labels[k]:8s}  {n_txt:{w}s}  {k_txt:{w}s}  {b_txt:{w}s}"
                     f"  {fit.bias_instability_tau_s[k]:.4g}")
    if result.adev.shape[1] == 6:
        lines.append("units: gyro N rad/s/sqrt(Hz), K rad/s^2/sqrt(Hz), B rad/s; "
                     "accel N m/s^2/sqrt(Hz), K m/s^3/sqrt(Hz), B m/s^2")
    if any_k:
        lines.append("* random walk not resolved (not significant at 95%): the value is its 95% upper bound")
    if any_b:
        lines.append("~ no flat region (the minimum is the white / random-walk crossover): "
                     "B is an upper bound")
    return "\n".join(lines)
