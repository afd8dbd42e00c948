"""Log-log plot of Allan-deviation curves with their 95 % bands and fitted noise lines."""

from __future__ import annotations

import numpy as np

from ..allan.deviation import FLICKER_FLOOR, AllanResult
from ..allan.fit import NoiseFit

__all__ = ["plot_allan"]


def plot_allan(result: AllanResult, fit: NoiseFit | None, path, title: str = "") -> None:
    """Log-log plot of the curves with their 95 % bands and the fitted lines, saved atomically.

    Six columns are drawn as two panels (gyro, accelerometer); other counts in one panel.
    Uses matplotlib's Agg backend (imported here).
    """
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    K = result.adev.shape[1]
    groups = [(range(0, 3), "gyroscope", "rad/s"), (range(3, 6), "accelerometer", "m/s$^2$")] if K == 6 \
        else [(range(K), "", "")]
    fig, axes = plt.subplots(1, len(groups), figsize=(6.4 * len(groups), 5.0), squeeze=False)
    import warnings

    with warnings.catch_warnings():  # a noise-free axis (all 0) has nothing to draw on a log scale
        warnings.filterwarnings("ignore", "Data has no positive values", UserWarning)
        _draw(fig, axes, groups, result, fit, K, title)
    import io

    from .files import atomic_write_bytes

    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=110)
    finally:
        plt.close(fig)
    atomic_write_bytes(Path(path), buf.getbuffer())


def _draw(fig, axes, groups, result, fit, K, title):
    colors = ["tab:red", "tab:green", "tab:blue"]
    taus = result.taus_s
    for ax, (cols, name, unit) in zip(axes[0], groups):
        for i, k in enumerate(cols):
            c = colors[i % 3] if K == 6 else f"C{i}"
            lab = result.labels[k] if result.labels else str(k)
            ax.fill_between(taus, result.adev_ci95[:, k, 0], result.adev_ci95[:, k, 1], color=c,
                            alpha=0.18, lw=0)
            ax.loglog(taus, result.adev[:, k], color=c, lw=1.6, label=lab)
            if fit is None:
                continue
            ax.loglog(taus, fit.white_line(taus)[:, k], color=c, lw=0.9, ls="--")
            ax.loglog(taus, fit.random_walk_line(taus)[:, k], color=c, lw=0.9, ls="-.")
            tb = fit.bias_instability_tau_s[k]
            ax.loglog([tb / 10.0, tb * 10.0], [FLICKER_FLOOR * fit.bias_instability[k]] * 2, color=c,
                      lw=0.9, ls=":")
            ax.plot([1.0], [fit.white_noise_density[k]], "o", color=c, ms=5)
            ax.plot([3.0], [fit.random_walk[k]], "s", color=c, ms=5,
                    mfc=c if fit.random_walk_resolved[k] else "white")
        lo = np.nanmin(result.adev_ci95[:, list(cols), 0])
        if fit is not None:
            marks = np.r_[fit.white_noise_density[list(cols)], fit.random_walk[list(cols)]]
            marks = marks[marks > 0]
            if marks.size:
                lo = min(lo, marks.min())
        hi = np.nanmax(result.adev_ci95[:, list(cols), 1][np.isfinite(result.adev_ci95[:, list(cols), 1])])
        if lo > 0.0 and 0.0 < hi < np.inf:  # else (a noise-free recording: all 0) matplotlib's own limits
            ax.set_ylim(lo / 2.0, hi * 2.0)
        ax.set_xlim(taus[0] / 1.3, taus[-1] * 1.3)
        ax.grid(True, which="major", alpha=0.5)
        ax.grid(True, which="minor", alpha=0.15)
        ax.set_xlabel(r"cluster time $\tau$ [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]" if unit else "Allan deviation")
        if name:
            ax.set_title(name)
        handles, labels = ax.get_legend_handles_labels()
        if fit is not None:
            from matplotlib.lines import Line2D

            handles += [Line2D([], [], color="k", ls="--", lw=0.9),
                        Line2D([], [], color="k", ls="-.", lw=0.9),
                        Line2D([], [], color="k", ls=":", lw=0.8),
                        Line2D([], [], color="k", marker="o", ls=""),
                        Line2D([], [], color="k", marker="s", ls="")]
            labels += ["white noise $N/\\sqrt{\\tau}$", "random walk $K\\sqrt{\\tau/3}$",
                       "0.664 B (at the minimum)", "N (at 1 s)", "K (at 3 s; open: bound)"]
        ax.legend(handles, labels, fontsize=8, loc="best")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
