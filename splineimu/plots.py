"""Plots people would rather look at than read (matplotlib, Agg backend, imported lazily)."""

from __future__ import annotations

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_imu(syn, path):
    """Gyro and accelerometer signals over time (measured, and ideal when noise was added)."""
    plt = _plt()
    t = (syn.t_ns - syn.t_ns[0]) / 1e9
    fig, axes = plt.subplots(2, 1, figsize=(11, 6), sharex=True, constrained_layout=True)
    for ax, meas, ideal, unit, name in (
        (axes[0], syn.gyro_rad_s, syn.ideal.gyro, "rad/s", "gyroscope"),
        (axes[1], syn.accel_m_s2, syn.ideal.specific_force, "m/s$^2$", "accelerometer"),
    ):
        for i, (ax_name, c) in enumerate(zip("xyz", ("tab:red", "tab:green", "tab:blue"))):
            ax.plot(t, meas[:, i], color=c, lw=0.6, alpha=0.8, label=f"{ax_name}")
            if syn.imu_config is not None:
                ax.plot(t, ideal[:, i], color="k", lw=0.5, alpha=0.6)
        ax.set_ylabel(f"{name} [{unit}]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", ncol=3, fontsize=8)
    axes[1].set_xlabel(f"time since {syn.t_ns[0]} ns [s]")
    title = "synthetic IMU" + ("" if syn.imu_config is None else " (black: noise-free)")
    axes[0].set_title(title)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_fit_residuals(t_s, res_pos, res_ang, path):
    """Position and angle residuals of the spline fit against the input poses."""
    plt = _plt()
    fig, axes = plt.subplots(2, 1, figsize=(11, 5), sharex=True, constrained_layout=True)
    for i, (ax_name, c) in enumerate(zip("xyz", ("tab:red", "tab:green", "tab:blue"))):
        axes[0].plot(t_s, res_pos[:, i] * 1e3, color=c, lw=0.6, label=ax_name)
        axes[1].plot(t_s, np.degrees(res_ang[:, i]), color=c, lw=0.6, label=ax_name)
    axes[0].set_ylabel("position residual [mm]")
    axes[1].set_ylabel("angle residual [deg]")
    axes[1].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", ncol=3, fontsize=8)
    axes[0].set_title("spline fit residuals (input pose - spline)")
    fig.savefig(path, dpi=110)
    plt.close(fig)
