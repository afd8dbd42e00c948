"""From a motion source to an output folder: stamps, ideal IMU, sensor model, files.

The three synthesis stages (STYLE.md 4) are kept apart: kinematics come from the motion
source, :func:`splineimu.imu.ideal.ideal_imu` makes the ideal measurement, and the shared
sensor model (:mod:`splineimu.imu.noise`) adds the sensor's errors. This module only wires
them together and writes the EuRoC-like output folder (DESIGN.md section 6).
"""

from __future__ import annotations

import json
import platform
import sys
from dataclasses import dataclass, field

import numpy as np

from . import __version__
from .errors import SplineImuError
from .imu.ideal import Extrinsic, IdealImu, ideal_imu
from .motion import DEFAULT_GRAVITY, MotionSource


@dataclass
class Synthesis:
    """Synthesized IMU data with its exact ground truth.

    Attributes
    ----------
    t_ns : (N,) int64 stamps
    gyro_rad_s, accel_m_s2 : (N, 3) measured (noise-free when no sensor model was given)
    bias_gyro_rad_s, bias_accel_m_s2 : (N, 3) true biases
    ideal : IdealImu (noise-free measurement and sensor ground truth, at the true times)
    imu_config : the ImuConfig used, or None
    seed : int or None
    applied : names of the sensor-model components applied
    true_ns : (N,) int64 or None
        True times of the samples (the ground truth's clock) when the IMU has a timing model;
        None: the stamps are the true times.
    vibration_gyro_rad_s, vibration_accel_m_s2 : (N, 3) or None
        The vibration added before the sensor model (interval means for ``sampling="mean"``).
    sample_times : SampleTimes or None
        The timing realization (dropped samples, ...).
    vibration_model : VibrationModel or None
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
    true_ns: np.ndarray | None = None
    vibration_gyro_rad_s: np.ndarray | None = None
    vibration_accel_m_s2: np.ndarray | None = None
    sample_times: object = None
    vibration_model: object = None

    @property
    def t_true_ns(self) -> np.ndarray:
        """True times of the samples (the stamps when there is no timing model)."""
        return self.t_ns if self.true_ns is None else self.true_ns

    def to_dataframe(self):
        import pandas as pd

        cols = {"t_ns": self.t_ns}
        for name, arr in (("gyro", self.gyro_rad_s), ("accel", self.accel_m_s2)):
            for i, ax in enumerate("xyz"):
                cols[f"{name}_{ax}"] = arr[:, i]
        return pd.DataFrame(cols)


#: Gauss-Legendre nodes per sample interval for ``sampling="mean"``
MEAN_NODES = 8


def _interval_starts(source, t_s, prev_s=None):
    """Start of each sample's interval (t_{k-1}, with ``prev_s`` the sample before ``t_s[0]``;
    without it the first interval uses the next spacing), clamped to the source."""
    t_s = np.asarray(t_s, dtype=np.float64)
    start = np.empty_like(t_s)
    start[1:] = t_s[:-1]
    if prev_s is not None:
        start[0] = prev_s
    else:
        start[0] = t_s[0] - (t_s[1] - t_s[0] if t_s.size > 1 else 0.0)
    return np.maximum(start, source.t_min_s)


def mean_ideal(source, t_s, gravity, extrinsic, a):
    """Ideal gyro and specific force averaged over each interval ``[a_k, t_k]`` (Gauss-Legendre)."""
    x, w = np.polynomial.legendre.leggauss(MEAN_NODES)
    h = 0.5 * (t_s - a)
    nodes = (0.5 * (t_s + a))[:, None] + h[:, None] * x[None, :]
    sub = ideal_imu(source, nodes.ravel(), gravity=gravity, extrinsic=extrinsic)
    n = t_s.size
    gyro = 0.5 * np.einsum("nkd,k->nd", sub.gyro.reshape(n, MEAN_NODES, 3), w)
    acc = 0.5 * np.einsum("nkd,k->nd", sub.specific_force.reshape(n, MEAN_NODES, 3), w)
    return gyro, acc


def increments(source, t_s, gravity, extrinsic, ideal_at_stamps, a):
    """Exact delta-angle ``Log(R_s(a_k)^T R_s(t_k))`` and delta-velocity
    ``R_s(a_k)^T (v_s(t_k) - v_s(a_k) - g dt)`` of the sensor over each interval ``[a_k, t_k]``."""
    from .lie import quat_xyzw_to_matrix, so3_log

    prev = ideal_imu(source, a, gravity=gravity, extrinsic=extrinsic)
    R0 = quat_xyzw_to_matrix(prev.quat_xyzw)
    R1 = quat_xyzw_to_matrix(ideal_at_stamps.quat_xyzw)
    dtheta = so3_log(np.matmul(np.swapaxes(R0, 1, 2), R1))
    g = np.asarray(gravity, dtype=np.float64)
    dv_w = ideal_at_stamps.velocity_world - prev.velocity_world - g * (t_s - a)[:, None]
    return dtheta, np.einsum("nji,nj->ni", R0, dv_w), t_s - a


#: Child keys of the run's seed for the timing's and the vibration's draws: apart from the
#: sensor model's streams (children 0..7), so those stay the same with or without them.
TIMING_SEED_KEY = (1001,)
VIBRATION_SEED_KEY = (1002,)


def child_seed(seed, key) -> np.random.SeedSequence:
    """``SeedSequence(seed, spawn_key=key)``: the stream of one effect of a run (fresh entropy for None)."""
    return np.random.SeedSequence(seed, spawn_key=tuple(key))


#: Samples per piece when a record is synthesized and written piece by piece: the memory in
#: use stays bounded (a few MB per array) however long the record, and it is reused from
#: piece to piece instead of being touched fresh.
CHUNK_SAMPLES = 1 << 16


class SynthesisStream:
    """A synthesis produced piece by piece (:func:`synthesize_stream`).

    Iterating :meth:`pieces` yields :class:`Synthesis` objects for consecutive runs of at most
    ``chunk_samples`` stamps; put together they are bit-identical to :func:`synthesize` on the
    whole record (the sensor model carries its state across pieces, see
    :meth:`splineimu.imu.noise.SensorModel.stream`). :func:`write_output` streams them to disk.

    Attributes
    ----------
    t_ns : (N,) int64
        All stamps (as written).
    true_ns : (N,) int64
        The samples' true times (``t_ns`` itself without a timing model).
    imu_config : ImuConfig or None
    seed, gravity, extrinsic, sampling, with_increments, sample_times, vibration_model :
        As given to :func:`synthesize_stream`.
    """

    def __init__(self, source, t_ns, *, gravity, extrinsic, imu_config, seed, temperature_c, sampling,
                 with_increments, chunk_samples, vibration=None):
        if sampling not in ("point", "mean"):
            raise SplineImuError(f"sampling must be 'point' or 'mean', got {sampling!r}")
        self.source = source
        # a SampleTimes exists only once its module is loaded: plain stamps do not import it
        timing = sys.modules.get(f"{__package__}.imu.timing")
        self.sample_times = t_ns if timing is not None and isinstance(t_ns, timing.SampleTimes) else None
        if self.sample_times is None:
            self.t_ns = self.true_ns = np.asarray(t_ns, dtype=np.int64)
        else:
            self.t_ns, self.true_ns = self.sample_times.stamp_ns, self.sample_times.true_ns
        self.vibration_model = None if vibration is None or vibration.is_empty else vibration
        self._vibration = None
        if self.vibration_model is not None:
            self._vibration = self.vibration_model.realize(child_seed(seed, VIBRATION_SEED_KEY))
        self.gravity = tuple(gravity)
        self.extrinsic = extrinsic
        self.seed = seed
        self.sampling = sampling
        self.with_increments = bool(with_increments)
        self.chunk_samples = max(1, int(chunk_samples))
        self.temperature_c = temperature_c
        self.imu_config = None
        self._model = None
        if imu_config is not None:
            from .imu.config import load_imu_config
            from .imu.noise import SensorModel

            self.imu_config = load_imu_config(imu_config)
            self._model = SensorModel(self.imu_config)

    def __len__(self) -> int:
        return int(self.t_ns.size)

    def pieces(self):
        """Yield the :class:`Synthesis` of each run of at most ``chunk_samples`` stamps, in order."""
        src = self.source
        t_all = src.t_s_from_ns(self.true_ns)
        starts = None if self.sample_times is None else src.t_s_from_ns(self.sample_times.interval_start_ns)
        n = t_all.size
        stream = None
        if self._model is not None:
            stream = self._model.stream(self.seed, self._model.white_noise_interval(t_all))
        temp = self.temperature_c
        temp_is_series = temp is not None and np.ndim(temp) == 1
        prev = None
        for a in range(0, n, self.chunk_samples):
            b = min(a + self.chunk_samples, n)
            t_s = t_all[a:b]
            # the interval before each sample: from the previous sample on the clock (taken or not)
            start = None
            if self.sampling == "mean" or self.with_increments:
                start = (_interval_starts(src, t_s, prev) if starts is None
                         else np.maximum(starts[a:b], src.t_min_s))
            ideal = ideal_imu(src, t_s, gravity=self.gravity, extrinsic=self.extrinsic)
            if self.sampling == "mean":
                gyro0, acc0 = mean_ideal(src, t_s, self.gravity, self.extrinsic, start)
            else:
                gyro0, acc0 = ideal.gyro, ideal.specific_force
            vib = None
            if self._vibration is not None:  # a function of true time, before the sensor model
                vib = self._vibration.evaluate(t_s, start if self.sampling == "mean" else None)
                gyro_in, acc_in = gyro0 + vib[0], acc0 + vib[1]
            else:
                gyro_in, acc_in = gyro0, acc0
            if stream is None:
                zeros = np.zeros_like(ideal.gyro)
                syn = Synthesis(self.t_ns[a:b], gyro_in.copy(), acc_in.copy(), zeros, zeros.copy(), ideal,
                                None, self.seed, [], self.gravity, self.extrinsic)
            else:
                T = None if temp is None else (np.asarray(temp)[a:b] if temp_is_series else temp)
                meas = stream.apply(t_s, gyro_in, acc_in, temperature_c=T)
                syn = Synthesis(self.t_ns[a:b], meas.gyro, meas.accel, meas.bias_gyro, meas.bias_accel, ideal,
                                self.imu_config, self.seed, list(meas.applied), self.gravity, self.extrinsic)
            syn.sampling = self.sampling
            if self.sample_times is not None:
                syn.true_ns, syn.sample_times = self.true_ns[a:b], self.sample_times
            if vib is not None:
                syn.vibration_gyro_rad_s, syn.vibration_accel_m_s2 = vib
                syn.vibration_model = self.vibration_model
            if self.with_increments:
                dth, dv, dt = increments(src, t_s, self.gravity, self.extrinsic, ideal, start)
                # sensor errors (bias, noise, scale, ...) integrated over the interval: (measured - true) dt
                syn.delta_angle = dth + (syn.gyro_rad_s - gyro0) * dt[:, None]
                syn.delta_velocity = dv + (syn.accel_m_s2 - acc0) * dt[:, None]
            prev = float(t_s[-1])
            yield syn

    def collect(self) -> Synthesis:
        """The whole record as one :class:`Synthesis` (one piece: memory grows with N)."""
        times = self.t_ns if self.sample_times is None else self.sample_times
        whole = SynthesisStream(self.source, times, gravity=self.gravity, extrinsic=self.extrinsic,
                                imu_config=self.imu_config, seed=self.seed, temperature_c=self.temperature_c,
                                sampling=self.sampling, with_increments=self.with_increments,
                                chunk_samples=max(1, self.t_ns.size), vibration=self.vibration_model)
        return next(whole.pieces())


def synthesize_stream(source: MotionSource, t_ns, *, gravity=DEFAULT_GRAVITY, extrinsic: Extrinsic | None = None,
                      imu_config=None, seed=None, temperature_c=None, sampling="point",
                      with_increments=False, chunk_samples: int = CHUNK_SAMPLES, vibration=None) -> SynthesisStream:
    """:func:`synthesize`, made piece by piece when iterated (bounded memory for long records).

    Parameters are those of :func:`synthesize`, plus ``chunk_samples`` (stamps per piece).
    Nothing is computed until :meth:`SynthesisStream.pieces` is iterated (or
    :func:`write_output` writes the stream).
    """
    return SynthesisStream(source, t_ns, gravity=gravity, extrinsic=extrinsic, imu_config=imu_config, seed=seed,
                           temperature_c=temperature_c, sampling=sampling, with_increments=with_increments,
                           chunk_samples=chunk_samples, vibration=vibration)


def synthesize(source: MotionSource, t_ns, *, gravity=DEFAULT_GRAVITY, extrinsic: Extrinsic | None = None,
               imu_config=None, seed=None, temperature_c=None, sampling="point",
               with_increments=False, vibration=None) -> Synthesis:
    """IMU samples of ``source`` at integer-nanosecond stamps ``t_ns``.

    Parameters
    ----------
    source : MotionSource
    t_ns : (N,) int64 or SampleTimes
        Sample stamps (absolute; the source's ``origin_ns`` is subtracted exactly), or the
        :class:`~splineimu.imu.timing.SampleTimes` of an IMU with a timing model: then each
        sample is taken at its true time (``true_ns``; for ``"mean"`` over the interval from
        the previous sample on the IMU's clock, dropped or not) and stamped ``stamp_ns``.
    gravity : (3,) world gravity [m/s^2]
    extrinsic : Extrinsic, optional
        ``body_T_sensor``.
    imu_config : ImuConfig, path, preset name or None
        Sensor model; None gives noise-free data.
    seed : int, optional
        Seed of the sensor model's random streams (and, from the child
        :data:`VIBRATION_SEED_KEY`, of the vibration's phases).
    temperature_c : float or (N,) array, optional
        Sensor temperature (overrides the configuration's profile).
    sampling : {"point", "mean"}
        ``"point"``: the instantaneous value at each stamp. ``"mean"``: the average over the
        interval ending at the stamp, ``[t_{k-1}, t_k]``, as an IMU's anti-alias filter /
        integrating front end gives (8-point Gauss-Legendre per interval).
    with_increments : bool
        Also compute delta-angle and delta-velocity per interval (exact, coning and sculling
        included), plus the sensor errors integrated over the interval.
    vibration : VibrationModel, optional
        Vibration added to the ideal signals before the sensor model, as a function of true
        time (interval means for ``"mean"``); kept in ``vibration_gyro_rad_s`` /
        ``vibration_accel_m_s2``.

    See Also
    --------
    synthesize_stream : the same, piece by piece.
    """
    return synthesize_stream(source, t_ns, gravity=gravity, extrinsic=extrinsic, imu_config=imu_config, seed=seed,
                             temperature_c=temperature_c, sampling=sampling,
                             with_increments=with_increments, vibration=vibration).collect()


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
    from .io import dataset as ds
    from .io.euroc import EUROC_GROUNDTRUTH_HEADER, EUROC_IMU_HEADER
    from .io.files import OutputFolder
    from .io.tables import TableWriter
    from .io.tum import TUM_HEADER
    from .lie import matrix_to_quat_xyzw, quat_make_continuous

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
            from .io.bag import imu_covariances, write_bag

            name = "imu.bag" if bag == "ros1" else "bag_ros2"
            write_bag(tmp / name, bag, syn.t_ns, syn.gyro_rad_s, syn.accel_m_s2, syn.t_true_ns,
                      syn.ideal.position_world, syn.ideal.quat_xyzw, imu_topic=rostopic,
                      covariances=imu_covariances(syn.imu_config, rate_hz), version=bag_version)
            out_report["bag"] = name
        if plot:
            from .plots import plot_fit_residuals, plot_imu

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
    if progress is False or (progress is None and n < PROGRESS_MIN_SAMPLES):
        return None
    from tqdm import tqdm

    return tqdm(total=n, unit=" samples", unit_scale=True, desc="writing", leave=False,
                disable=None if progress is None else False)


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
    from .imu.config import KALIBR_KEYS, ImuConfig
    from .io import dataset as ds
    from .io.files import atomic_write_text
    from .io.imu_yaml import kalibr_imu_chain_text

    cfg = syn.imu_config
    header = (None if cfg is not None
              else "noise-free synthesis: no sensor model was given (use --imu IMU.yaml or a preset)")
    sampling = f"samples: {syn.sampling} (see report.json)"
    (cfg if cfg is not None else ImuConfig()).to_yaml(tmp / "imu.yaml", header=header, rostopic=rostopic,
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
