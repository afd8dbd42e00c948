"""Writing a synthesis to its output folder, a EuRoC / ASL dataset (DESIGN.md section 6): :func:`write_output`.

The synthesis itself (stamps, ideal IMU, sensor model) is :mod:`splineimu.pipeline`; this module
writes what it gives, piece by piece, into an :class:`~splineimu.io.files.OutputFolder`.
"""

from __future__ import annotations

import json
import platform

import numpy as np

from .. import __version__
from ..io.progress import progress_bar
from ..pipeline import TIMING_SEED_KEY, VIBRATION_SEED_KEY, SynthesisStream

__all__ = ["write_output", "PROGRESS_MIN_SAMPLES"]


def _versions():
    import numba
    import scipy

    return {"splineimu": __version__, "numpy": np.__version__, "scipy": scipy.__version__,
            "numba": numba.__version__, "python": platform.python_version()}


def write_output(syn, out_dir, *, force=False, report: dict | None = None, bag: str | None = None,
                 plot: bool = False, fit_data=None, progress: bool | None = None, rate_hz: float | None = None,
                 rostopic: str = "/imu0", bag_version: int | None = None, extra=None):
    """Write the output folder, a EuRoC / ASL dataset, atomically (DESIGN.md section 6).

    ``mav0/imu0/data.csv`` and its ``sensor.yaml``, ``mav0/state_groundtruth_estimate0/data.csv``
    (sensor pose, velocity and true biases) and its ``sensor.yaml``, ``mav0/body.yaml``
    (:mod:`splineimu.io.dataset`); at the top ``groundtruth.tum`` (body poses at the IMU
    stamps), ``imu.yaml`` (the sensor model used, Kalibr's form), ``kalibr_imu_chain.yaml``
    (OpenVINS's form) and ``report.json``; optionally a ROS bag and PNG plots.

    ``rate_hz`` is the rate written to the yaml files (the rate synthesized; default: from
    ``report["rate_hz"]``, else from the median stamp spacing); ``rostopic`` the IMU's topic
    there and in the bag; ``bag_version`` the ROS 2 bag's metadata version
    (:func:`splineimu.io.bag.write_bag`).

    With a timing model the IMU rows carry the IMU's stamps and the ground-truth rows (one per
    written sample, in the same order) the samples' true times; ``report.json`` gets a
    ``timing`` section (model, counts, dropped runs). With vibration, ``mav0/imu0/vibration.csv``
    holds it with the same columns and stamps as ``mav0/imu0/data.csv``, and ``report.json`` a
    ``vibration`` section.

    ``syn`` is a :class:`Synthesis` or a :class:`SynthesisStream`; a stream is synthesized
    and written piece by piece, in bounded memory (bags and plots need the whole record and
    collect it first). ``progress`` shows a progress bar on stderr (default: for long
    records, when stderr is a terminal).

    ``extra(tmp, report)``, when given, writes more files into the temporary folder (and may
    add to the report) just before ``report.json``: they appear atomically with the rest.
    """
    from ..io import dataset as ds
    from ..io.euroc import EUROC_GROUNDTRUTH_HEADER, EUROC_IMU_HEADER
    from ..io.files import OutputFolder
    from ..io.tables import TableWriter
    from ..io.tum import TUM_HEADER
    from ..lie import matrix_to_quat_xyzw, quat_make_continuous

    if isinstance(syn, SynthesisStream) and (bag or plot):
        syn = syn.collect()
    pieces = syn.pieces() if isinstance(syn, SynthesisStream) else iter([syn])
    n_total = len(syn) if isinstance(syn, SynthesisStream) else int(syn.t_ns.size)
    t_all = syn.t_ns
    out_report = dict(report or {})
    out_report.setdefault("versions", _versions())
    out_report["imu"] = {
        "samples": int(t_all.size),
        "first_ns": int(t_all[0]) if t_all.size else None,
        "last_ns": int(t_all[-1]) if t_all.size else None,
        "noise": "noise-free" if syn.imu_config is None else "sensor model (see imu.yaml)",
        "components_applied": None,
        "seed": syn.seed,
        "gravity_m_s2": list(map(float, syn.gravity)),
        "extrinsic_body_T_sensor": None if syn.extrinsic is None else syn.extrinsic.matrix.tolist(),
        "sampling": syn.sampling,
        "stamp_convention": ("instantaneous value at the stamp" if syn.sampling == "point" else
                             "mean over the interval [previous stamp, stamp] (stamp at the interval's end)"),
    }
    with_increments = (syn.with_increments if isinstance(syn, SynthesisStream)
                       else syn.delta_angle is not None)
    _effects_report(syn, out_report)
    with_vibration = syn.vibration_model is not None
    with OutputFolder(out_dir, force=force) as tmp:
        for name in (ds.IMU_CSV, ds.GROUNDTRUTH_CSV):
            (tmp / name).parent.mkdir(parents=True)
        files = [TableWriter(tmp / ds.IMU_CSV, EUROC_IMU_HEADER),
                 TableWriter(tmp / ds.GROUNDTRUTH_CSV, EUROC_GROUNDTRUTH_HEADER),
                 TableWriter(tmp / "groundtruth.tum", TUM_HEADER, sep=" ", stamp="s")]
        if with_increments:
            files.append(TableWriter(tmp / ds.INCREMENTS_CSV,
                                     "#timestamp [ns] (end of interval),dtheta_x [rad],dtheta_y [rad],"
                                     "dtheta_z [rad],dv_x [m s^-1],dv_y [m s^-1],dv_z [m s^-1]"))
            out_report["imu"]["increments"] = f"{ds.INCREMENTS_CSV} (exact delta-angle / delta-velocity " \
                "over [previous stamp, stamp], sensor frame at the interval start)"
        if with_vibration:
            files.append(TableWriter(tmp / ds.VIBRATION_CSV, EUROC_IMU_HEADER))
        bar = _progress_bar(n_total, progress)
        last_q = None
        applied = []
        try:
            for piece in pieces:
                t, t_true = piece.t_ns, piece.t_true_ns
                ideal = piece.ideal
                # (+ 0.0 turns -0.0 into 0.0 in the text)
                files[0].write(t, np.hstack([piece.gyro_rad_s, piece.accel_m_s2]) + 0.0)
                q = ideal.quat_xyzw
                files[1].write(t_true, np.hstack([ideal.position_world, q[:, [3, 0, 1, 2]], ideal.velocity_world,
                                             piece.bias_gyro_rad_s, piece.bias_accel_m_s2]))
                body = ideal.body
                # with the sensor at the body origin, ideal_imu already converted this rotation
                same_frame = syn.extrinsic is None or syn.extrinsic.is_identity
                qb = ideal.quat_xyzw if same_frame else matrix_to_quat_xyzw(body.world_R_body)
                if last_q is not None:  # continue the sign choice of the previous piece
                    qb = quat_make_continuous(np.vstack([last_q, qb]))[1:]
                else:
                    qb = quat_make_continuous(qb)
                last_q = qb[-1:]
                files[2].write(t_true, np.hstack([body.position_world, qb]))
                if with_increments:
                    files[3].write(t, np.hstack([piece.delta_angle, piece.delta_velocity]) + 0.0)
                if with_vibration:
                    files[-1].write(t, np.hstack([piece.vibration_gyro_rad_s, piece.vibration_accel_m_s2]) + 0.0)
                applied = piece.applied
                if bar is not None:
                    bar.update(t.size)
        except BaseException:
            for f in files:
                f.abort()
            raise
        finally:
            if bar is not None:
                bar.close()
        for f in files:
            f.close()
        out_report["imu"]["components_applied"] = list(applied)
        if rate_hz is None:
            rate_hz = out_report.get("rate_hz") or (float(1e9 / np.median(np.diff(t_all))) if t_all.size > 1
                                                    else None)
        _write_metadata(tmp, syn, rate_hz, rostopic)
        if bag:
            from ..io.bag import imu_covariances, write_bag

            name = "imu.bag" if bag == "ros1" else "bag_ros2"
            write_bag(tmp / name, bag, syn.t_ns, syn.gyro_rad_s, syn.accel_m_s2, syn.t_true_ns,
                      syn.ideal.position_world, syn.ideal.quat_xyzw, imu_topic=rostopic,
                      covariances=imu_covariances(syn.imu_config, rate_hz), version=bag_version, progress=progress)
            out_report["bag"] = name
        if plot:
            from ..plots import plot_fit_residuals, plot_imu

            plot_imu(syn, tmp / "imu.png")
            plots = ["imu.png"]
            if fit_data is not None:
                plot_fit_residuals(*fit_data, tmp / "fit_residuals.png")
                plots.append("fit_residuals.png")
            out_report["plots"] = plots
        if extra is not None:
            extra(tmp, out_report)
        (tmp / "report.json").write_text(json.dumps(out_report, indent=2, default=_json_default) + "\n")
    return out_report


def _effects_report(syn, out_report):
    """The ``timing`` and ``vibration`` sections of report.json (only when they are modelled)."""
    if syn.sample_times is not None:
        out_report["timing"] = {
            **syn.sample_times.report(), "seed_key": list(TIMING_SEED_KEY),
            "stamps": "mav0/imu0/data.csv: the IMU clock's reading (true time + offset + drift) plus stamp noise",
            "ground_truth": "one row per written sample, in the same order, at its true time"}
    if syn.vibration_model is not None:
        out_report["vibration"] = {
            "model": syn.vibration_model.to_dict(), "seed_key": list(VIBRATION_SEED_KEY),
            "file": "mav0/imu0/vibration.csv (added before the sensor model; not part of the ground truth)"}


#: records at least this long get a progress bar (when stderr is a terminal)
PROGRESS_MIN_SAMPLES = 1_000_000


def _progress_bar(n, progress):
    return progress_bar(n, progress, PROGRESS_MIN_SAMPLES, " samples", "writing")


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    return str(o)


def _write_metadata(tmp, syn, rate_hz, rostopic):
    """``imu.yaml`` (Kalibr), ``kalibr_imu_chain.yaml`` (OpenVINS) and the EuRoC ``sensor.yaml``
    / ``body.yaml`` files, all with the rate synthesized; for noise-free data the noise keys at zero.
    ``sensor.yaml`` holds one number per noise key, as EuRoC's: the largest of the three axes."""
    from ..imu.config import KALIBR_KEYS, ImuConfig
    from ..io import dataset as ds
    from ..io.files import atomic_write_text
    from ..io.imu_yaml import kalibr_imu_chain_text, write_imu_config

    cfg = syn.imu_config
    header = (None if cfg is not None
              else "noise-free synthesis: no sensor model was given (use --imu IMU.yaml or a preset)")
    sampling = f"samples: {syn.sampling} (see report.json)"
    write_imu_config(cfg if cfg is not None else ImuConfig(), tmp / "imu.yaml", header=header, rostopic=rostopic,
                     update_rate=rate_hz)
    T_BS = np.eye(4) if syn.extrinsic is None else syn.extrinsic.matrix
    if rate_hz is not None:
        atomic_write_text(tmp / "kalibr_imu_chain.yaml", kalibr_imu_chain_text(
            cfg, update_rate=rate_hz, rostopic=rostopic, body_T_imu=T_BS,
            header=["IMU intrinsics and noise in OpenVINS's form (splineimu); " + sampling]))
    noise = {}
    for key in KALIBR_KEYS:
        v = np.zeros(3) if cfg is None else getattr(cfg, key)
        noise[key] = float(np.max(v))
    values = {"rate_hz": None if rate_hz is None else float(rate_hz), **noise}
    values = {k: v for k, v in values.items() if v is not None}
    what = "noise-free" if cfg is None else (cfg.source or "sensor model")
    atomic_write_text(tmp / ds.IMU_SENSOR_YAML, ds.sensor_yaml_text(
        "imu", f"splineimu synthetic IMU ({what}); {sampling}", T_BS, values,
        header=["IMU sensor definition (splineimu). T_BS: the IMU's pose in the body frame."]))
    atomic_write_text(tmp / ds.GROUNDTRUTH_SENSOR_YAML, ds.sensor_yaml_text(
        "visual-inertial", "Exact ground truth of the IMU (splineimu): pose, velocity and true biases of "
        "the imu0 frame.", T_BS))
    atomic_write_text(tmp / ds.BODY_YAML, ds.body_yaml_text(
        "Body frame: the frame of the input poses (groundtruth.tum); imu0 sits at T_BS in it."))
