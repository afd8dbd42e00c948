"""From a motion source to an output folder: stamps, ideal IMU, sensor model, files.

The three synthesis stages (STYLE.md 4) are kept apart: kinematics come from the motion
source, :func:`splineimu.imu.ideal.ideal_imu` makes the ideal measurement, and the shared
sensor model (:mod:`splineimu.imu.noise`) adds the sensor's errors. This module only wires
them together and writes the EuRoC-like output folder (DESIGN.md section 6).
"""

from __future__ import annotations

import json
import platform
from dataclasses import dataclass, field

import numpy as np

from . import __version__
from .errors import SplineImuError
from .imu.ideal import Extrinsic, IdealImu, ideal_imu
from .motion import DEFAULT_GRAVITY, MotionSource


def uniform_stamps_ns(start_ns: int, end_ns: int, rate_hz: float) -> np.ndarray:
    """Integer-nanosecond stamps ``start + round(k 1e9 / rate)`` that lie in [start, end]."""
    rate_hz = float(rate_hz)
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise SplineImuError(f"rate must be positive, got {rate_hz}")
    span = int(end_ns) - int(start_ns)
    if span < 0:
        raise SplineImuError("empty time span")
    n = int(np.floor(span * rate_hz / 1e9 + 1e-9)) + 1
    k = np.arange(n, dtype=np.int64)
    if (1e9 / rate_hz).is_integer():
        off = k * np.int64(int(1e9 / rate_hz))
    else:
        off = np.round(k.astype(np.float64) * (1e9 / rate_hz)).astype(np.int64)
    return np.int64(start_ns) + off[off <= span]


@dataclass
class Synthesis:
    """Synthesized IMU data with its exact ground truth.

    Attributes
    ----------
    t_ns : (N,) int64 stamps
    gyro_rad_s, accel_m_s2 : (N, 3) measured (noise-free when no sensor model was given)
    bias_gyro_rad_s, bias_accel_m_s2 : (N, 3) true biases
    ideal : IdealImu (noise-free measurement and sensor ground truth)
    imu_config : the ImuConfig used, or None
    seed : int or None
    applied : names of the sensor-model components applied
    """

    t_ns: np.ndarray
    gyro_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    bias_gyro_rad_s: np.ndarray
    bias_accel_m_s2: np.ndarray
    ideal: IdealImu
    imu_config: object = None
    seed: int | None = None
    applied: list = field(default_factory=list)
    gravity: tuple = DEFAULT_GRAVITY
    extrinsic: Extrinsic | None = None
    sampling: str = "point"
    delta_angle: np.ndarray | None = None
    delta_velocity: np.ndarray | None = None

    def to_dataframe(self):
        import pandas as pd

        cols = {"t_ns": self.t_ns}
        for name, arr in (("gyro", self.gyro_rad_s), ("accel", self.accel_m_s2)):
            for i, ax in enumerate("xyz"):
                cols[f"{name}_{ax}"] = arr[:, i]
        return pd.DataFrame(cols)


#: Gauss-Legendre nodes per sample interval for ``sampling="mean"``
MEAN_NODES = 8


def _interval_starts(source, t_s):
    """Start of each sample's interval (t_{k-1}; the first uses the next spacing), clamped to the source."""
    t_s = np.asarray(t_s, dtype=np.float64)
    start = np.empty_like(t_s)
    start[1:] = t_s[:-1]
    start[0] = t_s[0] - (t_s[1] - t_s[0] if t_s.size > 1 else 0.0)
    return np.maximum(start, source.t_min_s)


def mean_ideal(source, t_s, gravity, extrinsic):
    """Ideal gyro and specific force averaged over each interval ``[t_{k-1}, t_k]`` (Gauss-Legendre)."""
    a = _interval_starts(source, t_s)
    x, w = np.polynomial.legendre.leggauss(MEAN_NODES)
    h = 0.5 * (t_s - a)
    nodes = (0.5 * (t_s + a))[:, None] + h[:, None] * x[None, :]
    sub = ideal_imu(source, nodes.ravel(), gravity=gravity, extrinsic=extrinsic)
    n = t_s.size
    gyro = 0.5 * np.einsum("nkd,k->nd", sub.gyro.reshape(n, MEAN_NODES, 3), w)
    acc = 0.5 * np.einsum("nkd,k->nd", sub.specific_force.reshape(n, MEAN_NODES, 3), w)
    return gyro, acc


def increments(source, t_s, gravity, extrinsic, ideal_at_stamps):
    """Exact delta-angle ``Log(R_s(t_{k-1})^T R_s(t_k))`` and delta-velocity
    ``R_s(t_{k-1})^T (v_s(t_k) - v_s(t_{k-1}) - g dt)`` of the sensor over each interval."""
    from .lie import quat_xyzw_to_matrix, so3_log

    a = _interval_starts(source, t_s)
    prev = ideal_imu(source, a, gravity=gravity, extrinsic=extrinsic)
    R0 = quat_xyzw_to_matrix(prev.quat_xyzw)
    R1 = quat_xyzw_to_matrix(ideal_at_stamps.quat_xyzw)
    dtheta = so3_log(np.matmul(np.swapaxes(R0, 1, 2), R1))
    g = np.asarray(gravity, dtype=np.float64)
    dv_w = ideal_at_stamps.velocity_world - prev.velocity_world - g * (t_s - a)[:, None]
    return dtheta, np.einsum("nji,nj->ni", R0, dv_w), t_s - a


def synthesize(source: MotionSource, t_ns, *, gravity=DEFAULT_GRAVITY, extrinsic: Extrinsic | None = None,
               imu_config=None, seed=None, temperature_c=None, sampling="point",
               with_increments=False) -> Synthesis:
    """IMU samples of ``source`` at integer-nanosecond stamps ``t_ns``.

    Parameters
    ----------
    source : MotionSource
    t_ns : (N,) int64
        Sample stamps (absolute; the source's ``origin_ns`` is subtracted exactly).
    gravity : (3,) world gravity [m/s^2]
    extrinsic : Extrinsic, optional
        ``body_T_sensor``.
    imu_config : ImuConfig, path, preset name or None
        Sensor model; None gives noise-free data.
    seed : int, optional
        Seed of the sensor model's random streams.
    sampling : {"point", "mean"}
        ``"point"``: the instantaneous value at each stamp. ``"mean"``: the average over the
        interval ending at the stamp, ``[t_{k-1}, t_k]``, as an IMU's anti-alias filter /
        integrating front end gives (8-point Gauss-Legendre per interval).
    with_increments : bool
        Also compute delta-angle and delta-velocity per interval (exact, coning and sculling
        included), plus the sensor errors integrated over the interval.
    """
    if sampling not in ("point", "mean"):
        raise SplineImuError(f"sampling must be 'point' or 'mean', got {sampling!r}")
    t_ns = np.asarray(t_ns, dtype=np.int64)
    t_s = source.t_s_from_ns(t_ns)
    ideal = ideal_imu(source, t_s, gravity=gravity, extrinsic=extrinsic)
    if sampling == "mean":
        gyro0, acc0 = mean_ideal(source, t_s, gravity, extrinsic)
    else:
        gyro0, acc0 = ideal.gyro, ideal.specific_force
    zeros = np.zeros_like(ideal.gyro)
    if imu_config is None:
        syn = Synthesis(t_ns, gyro0.copy(), acc0.copy(), zeros, zeros.copy(), ideal,
                        None, seed, [], tuple(gravity), extrinsic)
    else:
        from .imu.config import load_imu_config
        from .imu.noise import SensorModel

        cfg = load_imu_config(imu_config)
        meas = SensorModel(cfg).apply(t_s, gyro0, acc0, rng=seed, temperature_c=temperature_c)
        syn = Synthesis(t_ns, meas.gyro, meas.accel, meas.bias_gyro, meas.bias_accel, ideal, cfg, seed,
                        list(getattr(meas, "applied", [])), tuple(gravity), extrinsic)
    syn.sampling = sampling
    if with_increments:
        dth, dv, dt = increments(source, t_s, gravity, extrinsic, ideal)
        # sensor errors (bias, noise, scale, ...) integrated over the interval: (measured - true) dt
        syn.delta_angle = dth + (syn.gyro_rad_s - gyro0) * dt[:, None]
        syn.delta_velocity = dv + (syn.accel_m_s2 - acc0) * dt[:, None]
    return syn


def _versions():
    import numba
    import scipy

    return {"splineimu": __version__, "numpy": np.__version__, "scipy": scipy.__version__,
            "numba": numba.__version__, "python": platform.python_version()}


def write_output(syn: Synthesis, out_dir, *, force=False, report: dict | None = None, bag: str | None = None,
                 plot: bool = False, fit_data=None):
    """Write the EuRoC-like output folder atomically (DESIGN.md section 6).

    ``imu0/data.csv``, ``state_groundtruth_estimate0/data.csv`` (sensor pose, velocity and true
    biases), ``groundtruth.tum`` (body poses at the IMU stamps), ``imu.yaml`` (the sensor
    model used), ``report.json``; optionally a ROS bag and PNG plots.
    """
    from .io.euroc import write_euroc_groundtruth, write_euroc_imu
    from .io.output import OutputFolder
    from .io.tum import write_tum

    out_report = dict(report or {})
    out_report.setdefault("versions", _versions())
    out_report["imu"] = {
        "samples": int(syn.t_ns.size),
        "first_ns": int(syn.t_ns[0]) if syn.t_ns.size else None,
        "last_ns": int(syn.t_ns[-1]) if syn.t_ns.size else None,
        "noise": "noise-free" if syn.imu_config is None else "sensor model (see imu.yaml)",
        "components_applied": syn.applied,
        "seed": syn.seed,
        "gravity_m_s2": list(map(float, syn.gravity)),
        "extrinsic_body_T_sensor": None if syn.extrinsic is None else syn.extrinsic.matrix.tolist(),
        "sampling": syn.sampling,
        "stamp_convention": ("instantaneous value at the stamp" if syn.sampling == "point" else
                             "mean over the interval [previous stamp, stamp] (stamp at the interval's end)"),
    }
    with OutputFolder(out_dir, force=force) as tmp:
        (tmp / "imu0").mkdir()
        (tmp / "state_groundtruth_estimate0").mkdir()
        # (+ 0.0 turns -0.0 into 0.0 in the text)
        write_euroc_imu(tmp / "imu0" / "data.csv", syn.t_ns, syn.gyro_rad_s + 0.0, syn.accel_m_s2 + 0.0)
        if syn.delta_angle is not None:
            from .io.output import atomic_write_bytes, format_table

            head = ("#timestamp [ns] (end of interval),dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],"
                    "dv_x [m s^-1],dv_y [m s^-1],dv_z [m s^-1]\n")
            body = format_table(syn.t_ns, np.hstack([syn.delta_angle, syn.delta_velocity]) + 0.0)
            atomic_write_bytes(tmp / "imu0" / "increments.csv", head.encode() + body)
            out_report["imu"]["increments"] = "imu0/increments.csv (exact delta-angle / delta-velocity " \
                "over [previous stamp, stamp], sensor frame at the interval start)"
        write_euroc_groundtruth(tmp / "state_groundtruth_estimate0" / "data.csv", syn.t_ns,
                                syn.ideal.position_world, syn.ideal.quat_xyzw, syn.ideal.velocity_world,
                                syn.bias_gyro_rad_s, syn.bias_accel_m_s2)
        from .lie import matrix_to_quat_xyzw, quat_make_continuous

        body = syn.ideal.body
        write_tum(tmp / "groundtruth.tum", syn.t_ns, body.position_world,
                  quat_make_continuous(matrix_to_quat_xyzw(body.world_R_body)))
        _write_imu_yaml(tmp / "imu.yaml", syn)
        if bag:
            from .io.bag import write_bag

            name = "imu.bag" if bag == "ros1" else "bag_ros2"
            write_bag(tmp / name, bag, syn.t_ns, syn.gyro_rad_s, syn.accel_m_s2, syn.t_ns,
                      syn.ideal.position_world, syn.ideal.quat_xyzw)
            out_report["bag"] = name
        if plot:
            from .plots import plot_fit_residuals, plot_imu

            plot_imu(syn, tmp / "imu.png")
            files = ["imu.png"]
            if fit_data is not None:
                plot_fit_residuals(*fit_data, tmp / "fit_residuals.png")
                files.append("fit_residuals.png")
            out_report["plots"] = files
        (tmp / "report.json").write_text(json.dumps(out_report, indent=2, default=_json_default) + "\n")
    return out_report


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    return str(o)


def _write_imu_yaml(path, syn: Synthesis):
    if syn.imu_config is not None:
        syn.imu_config.to_yaml(path)
        return
    rate = float(1e9 / np.median(np.diff(syn.t_ns))) if syn.t_ns.size > 1 else 0.0
    text = (
        "# noise-free synthesis: no sensor model was given (use --imu IMU.yaml or a preset)\n"
        "gyroscope_noise_density: 0.0\n"
        "gyroscope_random_walk: 0.0\n"
        "accelerometer_noise_density: 0.0\n"
        "accelerometer_random_walk: 0.0\n"
        f"update_rate: {rate:.12g}\n"
    )
    with open(path, "w") as fh:
        fh.write(text)
