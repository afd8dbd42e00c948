"""From a motion source to synthesized IMU data: stamps, ideal IMU, sensor model.

The three synthesis stages (STYLE.md 4) are kept apart: kinematics come from the motion
source, :func:`splineimu.imu.ideal.ideal_imu` makes the ideal measurement, and the shared
sensor model (:mod:`splineimu.imu.noise`) adds the sensor's errors. This module only wires
them together; :func:`splineimu.api.output.write_output` writes the EuRoC-like output folder
(DESIGN.md section 6).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field

import numpy as np

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
