"""Plot of one frame's observations (matplotlib is imported only when called)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_frame"]


def plot_frame(observations, t_ns=None, ax=None):
    """Draw the observations of one frame in image coordinates.

    Parameters
    ----------
    observations : Observations
    t_ns : int, optional
        Frame stamp (camera clock); default: the frame with the most observations.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure (not attached to pyplot) when None.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig.savefig(path)`` writes it.

    Notes
    -----
    Observed (noisy) coordinates are dots, exact projections rings; the image rectangle is
    ``[0, width] x [0, height]`` with ``v`` growing downwards.

    Examples
    --------
    >>> from splineimu.camera import Camera, Landmarks, observe
    >>> from splineimu.scenes import make_scene
    >>> scene = make_scene("ellipse", duration_s=0.5)
    >>> cam = Camera((300.0, 300.0, 320.0, 240.0), (640, 480), rate_hz=4.0, pixel_noise_px=1.0,
    ...              cam_T_imu=[[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0], [0, 0, 0, 1]])
    >>> obs = observe(scene, [cam], Landmarks.random(400, source=scene, rng=0), rng=0)["cam0"]
    >>> fig = plot_frame(obs)
    >>> [float(x) for x in fig.axes[0].get_xlim()]
    [0.0, 640.0]
    """
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6.4, 6.4 * observations.camera.height / observations.camera.width + 0.6))
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    if t_ns is None:
        if len(observations):
            stamps, counts = np.unique(observations.t_ns, return_counts=True)
            t_ns = int(stamps[np.argmax(counts)])
        else:
            t_ns = int(observations.frame_t_ns[0]) if observations.frame_t_ns.size else 0
    one = observations.frame(int(t_ns))
    cam = observations.camera
    ax.scatter(one.u_exact, one.v_exact, s=28, facecolors="none", edgecolors="tab:blue", linewidths=0.8,
               label="exact projection")
    ax.scatter(one.u, one.v, s=6, color="tab:red", label="observed")
    ax.set_xlim(0.0, float(cam.width))
    ax.set_ylim(float(cam.height), 0.0)
    ax.set_aspect("equal")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    shutter = "global shutter" if cam.is_global_shutter else f"rolling shutter, {cam.line_delay_s * 1e6:.3g} us/row"
    ax.set_title(f"{cam.name} at {t_ns} ns: {len(one)} landmarks ({cam.distortion_model}, {shutter})", fontsize=9)
    ax.legend(loc="upper right", fontsize=7)
    return fig
