"""The IMU sensor model: one model, applied identically to every motion source.

Given the ideal body rate ``w`` and specific force ``f`` at sample times ``t_k`` (the output
of the ideal-measurement stage), :meth:`SensorModel.apply` returns what the sensor reports::

    w_m = M_g S_g(T) w + G f + b_g + n_g
    f_m = M_a S_a(T) f + b_a + n_a

then quantization and saturation, per axis. ``S(T) = I + diag(s + c_s (T - T_ref))`` are the
scale factors, ``M`` the misalignment / non-orthogonality, ``G`` the gyro's g-sensitivity.
The bias is the sum of the configured terms::

    b(t_k) = b_turn_on + w_k + g_k + c_b (T_k - T_ref)

- random walk ``w_0 = 0``, ``w_k = w_{k-1} + sigma_b sqrt(t_k - t_{k-1}) xi`` (the *actual*
  sample intervals, so irregular real stamps are handled exactly);
- first-order Gauss-Markov ``g``, stationary from the first sample, exact discretization
  ``g_k = exp(-dt/T_c) g_{k-1} + sigma sqrt(1 - exp(-2 dt/T_c)) xi``;
- white noise ``n = sigma / sqrt(dt_w) xi`` with ``dt_w`` the *median* sample interval (the
  sensor integrates over its nominal period; stamp jitter does not change its noise);
- quantization ``x -> LSB * round(x / LSB)`` (round half to even), then saturation
  ``x -> clip(x, -r, r)`` (so a saturated sample reads exactly the range).

``xi`` are independent standard normals. Only configured terms are evaluated: a term that the
configuration does not name draws no numbers and costs nothing. Units and keys:
:mod:`splineimu.imu.config`.

Reproducibility
---------------
``rng`` (an int seed, a :class:`numpy.random.SeedSequence`, a :class:`numpy.random.Generator`
or None) is turned into one child generator (PCG64) per noise process, in this fixed order
(:data:`NOISE_PROCESSES`)::

    0 gyroscope.white_noise       4 accelerometer.white_noise
    1 gyroscope.bias_random_walk  5 accelerometer.bias_random_walk
    2 gyroscope.turn_on_bias      6 accelerometer.turn_on_bias
    3 gyroscope.gauss_markov      7 accelerometer.gauss_markov

Child ``i`` of a seed / SeedSequence ``ss`` is ``SeedSequence(ss.entropy,
spawn_key=ss.spawn_key + (i,))`` (what ``ss.spawn`` would give first, but without mutating
``ss``), so the same seed gives the same bytes on every call, a process's stream does not
depend on which other processes are on, and changing the accelerometer's parameters leaves
the gyro's realization bit-identical. New processes will only be appended. A Generator is
split with ``Generator.spawn(8)`` (its spawn counter advances: two calls differ). With
``rng=None`` fresh entropy is drawn and returned in :attr:`ImuMeasurement.seed_entropy`, so
the run can be repeated with ``rng=np.random.SeedSequence(entropy)``. Bytes are stable for a
given NumPy version (NumPy does not promise stream compatibility across versions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._kernels import noise as _k
from ..errors import ConfigError, InputError
from ..validation import as_float_array, as_seed, as_times_s, as_vectors
from .config import SENSORS, ImuConfig, load_imu_config

__all__ = ["SensorModel", "SensorStream", "ImuMeasurement", "NOISE_PROCESSES", "DEFAULT_TEMPERATURE_REFERENCE_C"]

#: Noise processes in the order their child generators are derived (append-only).
NOISE_PROCESSES = (
    "gyroscope.white_noise", "gyroscope.bias_random_walk", "gyroscope.turn_on_bias", "gyroscope.gauss_markov",
    "accelerometer.white_noise", "accelerometer.bias_random_walk", "accelerometer.turn_on_bias",
    "accelerometer.gauss_markov",
)

#: Temperature at which temperature errors vanish when the configuration gives none [degC].
DEFAULT_TEMPERATURE_REFERENCE_C = 25.0


@dataclass
class ImuMeasurement:
    """Output of :meth:`SensorModel.apply`.

    Attributes
    ----------
    t_s : (N,) float64
        Sample times [s] (as given).
    gyro : (N, 3) float64
        Measured body rate [rad/s].
    accel : (N, 3) float64
        Measured specific force [m/s^2].
    bias_gyro, bias_accel : (N, 3) float64
        True bias at every sample (turn-on + random walk + Gauss-Markov + temperature terms),
        the ground truth an estimator's bias states should track.
    applied : list of str
        Components applied, e.g. ``["gyroscope.white_noise", "gyroscope.bias_random_walk", ...]``.
    temperature_c : (N,) float64 or None
        Sensor temperature used [degC], if any.
    dt_white_s : float
        Interval used to discretize the white noise (median sample interval) [s].
    seed_entropy : int or None
        Entropy of the root SeedSequence (None when a Generator was passed).
    """

    t_s: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    bias_gyro: np.ndarray
    bias_accel: np.ndarray
    applied: list = field(default_factory=list)
    temperature_c: np.ndarray | None = None
    dt_white_s: float = float("nan")
    seed_entropy: int | None = None

    def to_dataframe(self):
        """:class:`pandas.DataFrame` with ``t_s``, ``gyro_{x,y,z}_rad_s``, ``accel_{x,y,z}_m_s2``,
        ``bias_gyro_*``, ``bias_accel_*`` (and ``temperature_c``)."""
        import pandas as pd

        cols = {"t_s": self.t_s}
        for name, arr, unit in (("gyro", self.gyro, "rad_s"), ("accel", self.accel, "m_s2"),
                                ("bias_gyro", self.bias_gyro, "rad_s"),
                                ("bias_accel", self.bias_accel, "m_s2")):
            for i, ax in enumerate("xyz"):
                cols[f"{name}_{ax}_{unit}"] = arr[:, i]
        if self.temperature_c is not None:
            cols["temperature_c"] = self.temperature_c
        return pd.DataFrame(cols)


class _Streams:
    """Lazily derived child generators, one per entry of :data:`NOISE_PROCESSES`."""

    def __init__(self, rng):
        self._gens = {}
        self._spawned = None
        self.entropy = None
        if isinstance(rng, np.random.Generator):
            self._spawned = rng.spawn(len(NOISE_PROCESSES))
            return
        if isinstance(rng, np.random.SeedSequence):
            ss = rng
        elif rng is None:
            ss = np.random.SeedSequence()
        elif isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
            ss = np.random.SeedSequence(as_seed(int(rng), "rng"))
        else:
            raise ConfigError(f"`rng` must be None, an int seed, a SeedSequence or a Generator, got {rng!r}")
        self._ss = ss
        self.entropy = ss.entropy

    def __call__(self, process: str) -> np.random.Generator:
        i = NOISE_PROCESSES.index(process)
        if self._spawned is not None:
            return self._spawned[i]
        g = self._gens.get(i)
        if g is None:
            ss = self._ss
            child = np.random.SeedSequence(ss.entropy, spawn_key=tuple(ss.spawn_key) + (i,),
                                           pool_size=ss.pool_size)
            g = self._gens[i] = np.random.Generator(np.random.PCG64(child))
        return g


class SensorModel:
    """The IMU error model of :mod:`splineimu.imu.noise` for one configuration.

    Parameters
    ----------
    config : ImuConfig, or anything :func:`~splineimu.imu.config.load_imu_config` takes
        (yaml path, preset name, mapping).

    Examples
    --------
    >>> model = SensorModel({"gyroscope_noise_density": 0.01, "accelerometer_random_walk": 1e-3})
    >>> t = np.arange(1000) / 200.0
    >>> m = model.apply(t, np.zeros((1000, 3)), np.tile([0, 0, 9.81], (1000, 1)), rng=7)
    >>> m.applied
    ['gyroscope.white_noise', 'accelerometer.bias_random_walk']
    >>> bool(np.all(m.bias_gyro == 0)), m.gyro.shape
    (True, (1000, 3))
    """

    def __init__(self, config):
        self.config: ImuConfig = load_imu_config(config)

    def components(self, temperature_given: bool = False) -> list[str]:
        """Names of the components :meth:`apply` will apply (in application order)."""
        out = []
        cfg = self.config
        has_t = temperature_given or cfg.temperature_profile is not None
        for s in SENSORS:
            p = cfg.sensor(s)
            names = [
                ("scale", p["scale"] is not None),
                ("scale_temperature", p["scale_temperature_coefficient"] is not None and has_t),
                ("misalignment", p["misalignment"] is not None),
                ("g_sensitivity", p["g_sensitivity"] is not None),
                ("turn_on_bias", p["bias"] is not None or p["bias_sigma"] is not None),
                ("bias_random_walk", bool(np.any(p["random_walk"] > 0))),
                ("gauss_markov", p["bias_instability"] is not None),
                ("bias_temperature", p["bias_temperature_coefficient"] is not None and has_t),
                ("white_noise", bool(np.any(p["noise_density"] > 0))),
                ("quantization", p["quantization"] is not None),
                ("saturation", p["saturation"] is not None),
            ]
            out += [f"{s}.{n}" for n, on in names if on]
        return out

    def _temperature(self, t, temperature_c, t_first=None):
        cfg = self.config
        if temperature_c is not None:
            if np.ndim(temperature_c) == 0:
                temperature_c = np.full(t.shape, as_float_array(temperature_c, "temperature_c")[0])
            return as_float_array(temperature_c, "temperature_c", t.shape)
        if cfg.temperature_profile is not None:
            return cfg.temperature_profile(t, t_first)
        return None

    def apply(self, t_s, gyro, accel, rng=None, temperature_c=None) -> ImuMeasurement:
        """Turn ideal measurements into sensor output.

        Parameters
        ----------
        t_s : (N,) array_like
            Strictly increasing sample times [s].
        gyro : (N, 3) array_like
            True body rate in the sensor frame [rad/s].
        accel : (N, 3) array_like
            True specific force in the sensor frame [m/s^2] (a level IMU at rest: (0, 0, 9.81)).
        rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
            Seed (see "Reproducibility" in the module docstring).
        temperature_c : float or (N,) array_like, optional
            Sensor temperature [degC]; overrides the configuration's ``temperature_profile``.

        Returns
        -------
        ImuMeasurement

        Raises
        ------
        InputError
            Wrong shapes, non-finite values, non-increasing times.
        ConfigError
            Temperature coefficients without any temperature; a single sample with white
            noise but no ``update_rate``; a bad ``rng``.
        """
        t = _as_times(t_s)
        return self.stream(rng, self.white_noise_interval(t)).apply(t, gyro, accel, temperature_c)

    def white_noise_interval(self, t_s) -> float:
        """The interval that discretizes the white noise of a record sampled at ``t_s``: the
        median sample interval, or ``1 / update_rate`` for a single sample (NaN without one)."""
        t = np.asarray(t_s, dtype=np.float64)
        if t.size > 1:
            return float(np.median(np.diff(t)))
        return 1.0 / self.config.update_rate if self.config.update_rate else float("nan")

    def stream(self, rng=None, dt_white_s: float | None = None) -> SensorStream:
        """The model applied to a long record piece by piece, with the same numbers as
        :meth:`apply` on the whole record.

        Parameters
        ----------
        rng : as for :meth:`apply`
        dt_white_s : float, optional
            Interval that discretizes the white noise: the median sample interval of the
            *whole* record (default ``1 / update_rate``).

        Returns
        -------
        SensorStream
            Call its :meth:`SensorStream.apply` with consecutive pieces of the record.

        Examples
        --------
        >>> model = SensorModel({"gyroscope_noise_density": 0.01, "gyroscope_random_walk": 1e-3})
        >>> t = np.arange(1000) / 200.0
        >>> w, f = np.zeros((1000, 3)), np.tile([0, 0, 9.81], (1000, 1))
        >>> whole = model.apply(t, w, f, rng=7)
        >>> st = model.stream(rng=7, dt_white_s=float(np.median(np.diff(t))))
        >>> parts = [st.apply(t[a:a + 300], w[a:a + 300], f[a:a + 300]) for a in range(0, 1000, 300)]
        >>> bool(np.array_equal(np.vstack([m.gyro for m in parts]), whole.gyro))
        True
        """
        if dt_white_s is None:
            dt_white_s = 1.0 / self.config.update_rate if self.config.update_rate else float("nan")
        return SensorStream(self, rng, float(dt_white_s))

    def _sensor(self, s, x, f_true, t, dt, dt_white, T, streams, applied, state, first):
        cfg = self.config
        p = cfg.sensor(s)
        n = x.shape[0]
        t_ref = cfg.temperature_reference if cfg.temperature_reference is not None \
            else DEFAULT_TEMPERATURE_REFERENCE_C
        needs_t = (p["bias_temperature_coefficient"] is not None
                   or p["scale_temperature_coefficient"] is not None)
        if needs_t and T is None:
            where = cfg.source + ": " if cfg.source else ""
            raise ConfigError(f"{where}`{s}_*_temperature_coefficient` needs a temperature: "
                              "set `temperature_profile` or pass `temperature_c`")

        def mark(name):
            applied.append(f"{s}.{name}")

        # ---- intrinsics: M S(T) x (+ G f)
        y = x
        if p["scale"] is not None or p["scale_temperature_coefficient"] is not None:
            factor = np.ones(3)
            if p["scale"] is not None:
                factor = factor + p["scale"]
                mark("scale")
            if p["scale_temperature_coefficient"] is not None:
                dT = (T - t_ref)[:, None]
                factor = factor[None, :] + p["scale_temperature_coefficient"][None, :] * dT
                mark("scale_temperature")
            y = y * factor
        if p["misalignment"] is not None:
            y = y @ p["misalignment"].T
            mark("misalignment")
        if p["g_sensitivity"] is not None:
            y = y + f_true @ p["g_sensitivity"].T
            mark("g_sensitivity")

        # ---- bias
        bias = np.zeros((n, 3))
        if p["bias"] is not None or p["bias_sigma"] is not None:
            if first:
                b0 = np.zeros(3)
                if p["bias"] is not None:
                    b0 += p["bias"]
                if p["bias_sigma"] is not None:
                    b0 += p["bias_sigma"] * streams(f"{s}.turn_on_bias").standard_normal(3)
                state["turn_on"] = b0
            bias += state["turn_on"]
            mark("turn_on_bias")
        if np.any(p["random_walk"] > 0):
            # the first piece starts the walk at its first sample (N - 1 steps), later pieces
            # take a step per sample from the previous piece's last one
            z = streams(f"{s}.bias_random_walk").standard_normal((dt.size, 3))
            _k.random_walk_add(z, np.ascontiguousarray(p["random_walk"]), np.sqrt(dt), bias, state["walk"])
            mark("bias_random_walk")
        if p["bias_instability"] is not None:
            z = streams(f"{s}.gauss_markov").standard_normal((n, 3))
            _k.gauss_markov_add(z, np.ascontiguousarray(p["bias_instability"]),
                                np.ascontiguousarray(p["bias_correlation_time"]), dt, bias,
                                state["gauss_markov"], first)
            mark("gauss_markov")
        if p["bias_temperature_coefficient"] is not None:
            bias += p["bias_temperature_coefficient"][None, :] * (T - t_ref)[:, None]
            mark("bias_temperature")

        meas = y + bias  # a new array: the caller's input is never modified

        # ---- white noise
        if np.any(p["noise_density"] > 0):
            if not math.isfinite(dt_white):
                raise ConfigError("a single sample needs `update_rate` to discretize the white noise")
            z = streams(f"{s}.white_noise").standard_normal((n, 3))
            _k.add_scaled_noise(meas, np.ascontiguousarray(p["noise_density"] / math.sqrt(dt_white)), z)
            mark("white_noise")

        # ---- output stage
        if p["quantization"] is not None:
            q = p["quantization"]
            meas = np.rint(meas / q) * q
            mark("quantization")
        if p["saturation"] is not None:
            r = p["saturation"]
            np.clip(meas, -r, r, out=meas)
            mark("saturation")
        return meas, bias


def _as_samples(x, n, name):
    """(kept for splineimu.calibration, which imports it: use validation.as_vectors)"""
    return as_vectors(x, name, n)


def _as_times(t_s):
    t = as_times_s(t_s)
    if t.size == 0:
        raise InputError("Expected `t_s` to have shape (N,) with N >= 1, got (0,)")
    return t


class SensorStream:
    """:class:`SensorModel` applied to consecutive pieces of one record (see
    :meth:`SensorModel.stream`).

    The bias processes carry their state from piece to piece and every noise process draws
    its numbers in the same order as for the whole record, so the pieces put together are
    bit-identical to one :meth:`SensorModel.apply` call: long records are processed in
    bounded memory.
    """

    def __init__(self, model: SensorModel, rng, dt_white_s: float):
        self.model = model
        self.dt_white_s = dt_white_s
        self._streams = _Streams(rng)
        self._prev_t = None
        self._t_first = None
        self._state = {s: {"walk": np.zeros(3), "gauss_markov": np.zeros(3), "turn_on": None} for s in SENSORS}

    @property
    def seed_entropy(self):
        return self._streams.entropy

    def apply(self, t_s, gyro, accel, temperature_c=None) -> ImuMeasurement:
        """Sensor output for the next piece; arguments as for :meth:`SensorModel.apply`
        (``t_s`` must continue after the previous piece)."""
        t = _as_times(t_s)
        n = t.size
        g = as_vectors(gyro, "gyro", n)
        a = as_vectors(accel, "accel", n)
        first = self._prev_t is None
        dt = np.diff(t) if first else np.diff(t, prepend=self._prev_t)
        if np.any(dt <= 0):
            i = int(np.flatnonzero(dt <= 0)[0]) + (1 if first else 0)
            before = t[i - 1] if i > 0 else self._prev_t
            raise InputError(f"`t_s` must be strictly increasing: t_s[{i}] = {t[i]!r} after {before!r}")
        dt = np.ascontiguousarray(dt)
        if n > 1 and not math.isfinite(self.dt_white_s):
            self.dt_white_s = float(np.median(dt))
        if first:
            self._t_first = float(t[0])
        T = self.model._temperature(t, temperature_c, self._t_first)
        applied: list[str] = []
        out = {}
        for s in SENSORS:
            x = g if s == "gyroscope" else a
            out[s] = self.model._sensor(s, x, a, t, dt, self.dt_white_s, T, self._streams, applied,
                                        self._state[s], first)
        self._prev_t = float(t[-1])
        return ImuMeasurement(t_s=t, gyro=out["gyroscope"][0], accel=out["accelerometer"][0],
                              bias_gyro=out["gyroscope"][1], bias_accel=out["accelerometer"][1],
                              applied=applied, temperature_c=T, dt_white_s=self.dt_white_s,
                              seed_entropy=self._streams.entropy)
