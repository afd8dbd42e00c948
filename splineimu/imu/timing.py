"""IMU sample timing: clock offset and drift, stamp noise and dropped samples.

The IMU has its own clock ``c(t) = t + offset + drift_ppm * 1e-6 * (t - t_first)`` (``t`` the
true time of the ground truth, ``t_first`` the true time of the first sample, the start of the
motion). It takes sample ``k`` when its clock reads ``first + k / rate_hz`` with
``first = c(t_first)``, so the true time of sample ``k`` is

    t_k = t_first + (k / rate_hz) / (1 + drift_ppm * 1e-6)

and the stamp written is the clock reading plus white stamp noise, rounded to integer
nanoseconds. A dropped sample keeps its index (the next one is not moved). Losses are
independent with ``drop_probability``, or, with ``drop_burst_s``, come in bursts of that mean
length: a two-state Markov chain (Gilbert) whose long-run lost fraction is ``drop_probability``.

Every effect is off by default; :class:`TimingModel` with no key set gives the plain grid of
:func:`splineimu.timegrid.uniform_stamps_ns`, bit for bit.

Examples
--------
>>> tm = TimingModel(time_offset_s=0.01, clock_drift_ppm=100.0)
>>> st = tm.sample_times(0, 1_000_000_000, 10.0, rng=1)
>>> st.true_ns[:3].tolist(), st.stamp_ns[:3].tolist()
([0, 99990001, 199980002], [10000000, 110000000, 210000000])
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ..validation import finite_float, nonnegative_float

#: Keys of the ``imu.timing`` block of a scene file.
TIMING_KEYS = ("time_offset_s", "clock_drift_ppm", "stamp_noise_s", "drop_probability", "drop_burst_s")


@dataclass(frozen=True)
class TimingModel:
    """Clock and sampling imperfections of an IMU (all off by default).

    Parameters
    ----------
    time_offset_s : float
        The IMU clock reads true time + this offset.
    clock_drift_ppm : float
        The IMU clock runs fast by this many parts per million (negative: slow); |drift| < 1e5.
    stamp_noise_s : float
        Standard deviation of white noise on the written stamps (>= 0). A realization that puts
        a stamp at or before the previous one is refused (ConfigError): keep it below a tenth of
        the sample period.
    drop_probability : float
        Probability that a sample is lost, in [0, 1).
    drop_burst_s : float
        Mean length of a burst of losses (0: independent losses).
    """

    time_offset_s: float = 0.0
    clock_drift_ppm: float = 0.0
    stamp_noise_s: float = 0.0
    drop_probability: float = 0.0
    drop_burst_s: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "time_offset_s", finite_float(self.time_offset_s, "time_offset_s"))
        drift = finite_float(self.clock_drift_ppm, "clock_drift_ppm")
        if abs(drift) >= 1e5:
            from ..errors import ConfigError

            raise ConfigError(f"`clock_drift_ppm` must be within +-1e5 ppm, got {drift:g}", option="clock_drift_ppm")
        object.__setattr__(self, "clock_drift_ppm", drift)
        object.__setattr__(self, "stamp_noise_s", nonnegative_float(self.stamp_noise_s, "stamp_noise_s"))
        p = nonnegative_float(self.drop_probability, "drop_probability")
        if p >= 1.0:
            from ..errors import ConfigError

            raise ConfigError(f"`drop_probability` must be below 1, got {p:g}", option="drop_probability")
        object.__setattr__(self, "drop_probability", p)
        object.__setattr__(self, "drop_burst_s", nonnegative_float(self.drop_burst_s, "drop_burst_s"))

    @classmethod
    def from_dict(cls, d: dict | None, doc=None, keys: tuple = ()) -> TimingModel:
        """Build from a scene file's ``timing`` mapping.

        ``doc`` (a :class:`splineimu.io.yaml.YamlDoc`) and ``keys`` (the path of the block in it)
        put the file and line into every error.
        """
        from ..errors import ConfigError

        if d is None:
            return cls()
        if not isinstance(d, dict):
            raise _error(doc, keys, "`timing` must be a mapping of " + ", ".join(TIMING_KEYS))
        for k in d:
            if k not in TIMING_KEYS:
                import difflib

                near = difflib.get_close_matches(str(k), TIMING_KEYS, n=1)
                hint = f"; did you mean `{near[0]}`?" if near else f"; known keys: {', '.join(TIMING_KEYS)}"
                raise _error(doc, keys + (k,), f"unknown key `timing.{k}`{hint}")
        try:
            return cls(**{k: d[k] for k in TIMING_KEYS if k in d})
        except ConfigError as exc:
            if doc is None:
                raise
            raise _error(doc, keys + (exc.option,), exc.problem) from None

    def to_dict(self) -> dict:
        """The keys that are set (non-zero), for report.json and scene files."""
        return {k: v for k, v in asdict(self).items() if v != 0.0}

    @property
    def is_identity(self) -> bool:
        """True when no effect is set: the samples lie on the plain grid."""
        return not self.to_dict()

    def true_times_ns(self, stamp_ns) -> np.ndarray:
        """The true times of stamps written on this clock: the inverse of the clock, for dead reckoning.

        ``t = t_first + (c - offset - t_first) / (1 + drift_ppm * 1e-6)``, with the first stamp
        standing for ``t_first`` (exact when it is sample 0; else off by ``drift`` times the time
        before it, 1 ns per 10 ms at 100 ppm). Stamp noise cannot be undone; dropped samples
        need nothing.

        Parameters
        ----------
        stamp_ns : (N,) array_like of int
            Stamps on the IMU clock [ns], increasing.

        Returns
        -------
        (N,) int64
            True times [ns].

        Examples
        --------
        >>> tm = TimingModel(time_offset_s=0.01, clock_drift_ppm=100.0)
        >>> tm.true_times_ns([10000000, 110000000, 210000000]).tolist()
        [0, 99990001, 199980002]
        """
        stamp = np.asarray(stamp_ns, dtype=np.int64).reshape(-1)
        offset_ns = int(round(self.time_offset_s * 1e9))
        if not self.clock_drift_ppm or stamp.size == 0:
            return stamp - np.int64(offset_ns)
        rel = (stamp - stamp[0]).astype(np.float64) / (1.0 + self.clock_drift_ppm * 1e-6)
        return np.int64(int(stamp[0]) - offset_ns) + np.rint(rel).astype(np.int64)

    def sample_times(self, first_ns: int, last_ns: int, rate_hz: float, rng=None) -> SampleTimes:
        """True times and written stamps of the samples taken in ``[first_ns, last_ns]`` (true time).

        Parameters
        ----------
        first_ns, last_ns : int
            True-time span of the motion (integer ns); the first sample is taken at ``first_ns``.
        rate_hz : float
            Nominal rate of the IMU clock.
        rng : numpy Generator, SeedSequence, int or None
            Source of stamp noise and losses (each from its own child stream, drawn from only
            when that effect is set).

        Returns
        -------
        SampleTimes
        """
        from ..timegrid import uniform_stamps_ns

        first_ns, last_ns = int(first_ns), int(last_ns)
        drift = self.clock_drift_ppm * 1e-6
        # clock offsets of the grid k / rate: exact integers (the same grid as without timing)
        span_clock = int(np.floor((last_ns - first_ns) * (1.0 + drift))) if drift else last_ns - first_ns
        grid = uniform_stamps_ns(0, span_clock, rate_hz)
        if drift:
            true_rel = np.rint(grid / (1.0 + drift)).astype(np.int64)
            grid = grid[true_rel <= last_ns - first_ns]
            true_rel = true_rel[: grid.size]
        else:
            true_rel = grid
        index = np.arange(grid.size, dtype=np.int64)
        true_ns = np.int64(first_ns) + true_rel
        prev_true_ns = np.concatenate([true_ns[:1], true_ns[:-1]])
        offset_ns = int(round(self.time_offset_s * 1e9))
        stamp_ns = np.int64(first_ns + offset_ns) + grid
        noise_gen, loss_gen = _child_generators(rng, 2)
        if self.stamp_noise_s > 0:
            stamp_ns = stamp_ns + np.rint(noise_gen.normal(0.0, self.stamp_noise_s * 1e9, grid.size)).astype(np.int64)
            back = np.flatnonzero(np.diff(stamp_ns) <= 0)
            if back.size:
                from ..errors import ConfigError

                period = 1.0 / float(rate_hz)
                raise ConfigError(
                    f"`stamp_noise_s` {self.stamp_noise_s:g} s at {float(rate_hz):g} Hz (period {period:g} s) puts "
                    f"{back.size} of {grid.size - 1} stamps at or before the previous one (first at sample "
                    f"{int(back[0]) + 1}); IMU stamps must increase: use at most a tenth of the period "
                    f"({period / 10:g} s)", option="stamp_noise_s")
        keep = np.ones(grid.size, dtype=bool)
        if self.drop_probability > 0:
            keep = ~_losses(grid.size, self.drop_probability, self.drop_burst_s * float(rate_hz), loss_gen)
        return SampleTimes(index[keep], true_ns[keep], stamp_ns[keep], prev_true_ns[keep], int(grid.size),
                           self.to_dict(), int(true_ns[0]), int(true_ns[-1]))


def _error(doc, keys, message):
    from ..errors import ConfigError

    if doc is None:
        return ConfigError(message, option=".".join(map(str, keys)) or None)
    return doc.error(message, *keys)


def _child_generators(rng, n: int) -> list:
    """``n`` independent generators from ``rng`` (Generator, SeedSequence, int or None).

    Child ``i`` of a seed is ``SeedSequence(entropy, spawn_key=spawn_key + (i,))`` (as in
    :mod:`splineimu.imu.noise`): the stamp noise and the losses have their own streams, so
    switching one effect on or off leaves the other's realization unchanged.
    """
    if isinstance(rng, np.random.Generator):
        return rng.spawn(n)
    ss = rng if isinstance(rng, np.random.SeedSequence) else np.random.SeedSequence(rng)
    return [np.random.Generator(np.random.PCG64(np.random.SeedSequence(ss.entropy, spawn_key=tuple(ss.spawn_key) + (i,),
                                                                       pool_size=ss.pool_size)))
            for i in range(n)]


def _losses(n: int, p: float, burst_samples: float, gen) -> np.ndarray:
    """Lost-sample mask: independent (``burst_samples <= 1``) or Gilbert bursts of that mean length."""
    if burst_samples <= 1.0:
        return gen.random(n) < p
    leave = 1.0 / burst_samples  # P(lost -> kept): mean burst length burst_samples
    enter = p * leave / (1.0 - p)  # P(kept -> lost): long-run lost fraction p
    u = gen.random(n)
    lost = np.empty(n, dtype=bool)
    state = gen.random() < p
    for i in range(n):  # a two-state chain; n is at most a few million and this runs once
        lost[i] = state
        state = (u[i] >= leave) if state else (u[i] < enter)
    return lost


@dataclass
class SampleTimes:
    """The samples an IMU with a :class:`TimingModel` delivers.

    Attributes
    ----------
    index : (M,) int64
        Sample index ``k`` on the IMU clock (gaps where samples were dropped).
    true_ns : (M,) int64
        True time of each sample (the ground-truth clock), rounded to integer ns.
    stamp_ns : (M,) int64
        The stamp the IMU writes: its clock reading plus stamp noise.
    interval_start_ns : (M,) int64
        True time of sample ``k - 1`` (taken or not): the start of the interval that a
        mean-sampling IMU averages over (the first sample's own time for ``k = 0``).
    n_taken : int
        Samples on the clock grid before losses.
    model : dict
        The timing keys that were set.
    first_true_ns, last_true_ns : int or None
        True times of the first and the last sample on the clock grid (taken or not).
    """

    index: np.ndarray
    true_ns: np.ndarray
    stamp_ns: np.ndarray
    interval_start_ns: np.ndarray
    n_taken: int
    model: dict = field(default_factory=dict)
    first_true_ns: int | None = None
    last_true_ns: int | None = None

    @property
    def n_dropped(self) -> int:
        return int(self.n_taken - self.index.size)

    def dropped_ranges(self, max_ranges: int = 1000) -> list:
        """Runs of dropped indices as ``{"first_index", "count", "t_start_ns", "t_end_ns"}``.

        The times are the true times of the kept samples around each run (the span with no
        data); a run at the start begins at the first sample's true time, a run at the end
        ends at the last sample's (both on the clock grid).
        """
        first = self.first_true_ns if self.first_true_ns is not None else (
            int(self.true_ns[0]) if self.true_ns.size else 0)
        last = self.last_true_ns if self.last_true_ns is not None else (
            int(self.true_ns[-1]) if self.true_ns.size else first)
        if self.index.size == 0:
            everything = {"first_index": 0, "count": int(self.n_taken), "t_start_ns": first, "t_end_ns": last}
            return [everything][:max_ranges] if self.n_taken else []
        # kept indices with the grid's ends as sentinels (-1 before, n_taken after)
        idx = np.concatenate([[-1], self.index, [self.n_taken]])
        t = np.concatenate([[first], self.true_ns, [last]])
        gap = np.flatnonzero(np.diff(idx) > 1)
        return [{"first_index": int(idx[i] + 1), "count": int(idx[i + 1] - idx[i] - 1),
                 "t_start_ns": int(t[i]), "t_end_ns": int(t[i + 1])} for i in gap[:max_ranges]]

    def n_dropped_runs(self) -> int:
        """Number of runs of consecutive dropped samples (at the ends included)."""
        idx = np.concatenate([[-1], self.index, [self.n_taken]])
        return int(np.count_nonzero(np.diff(idx) > 1))

    def report(self) -> dict:
        """What report.json says of the timing: model, counts, dropped runs (the first 1000 of
        ``dropped_runs_total``), and how many stamps do not increase (stamp noise can reorder)."""
        back = int(np.count_nonzero(np.diff(self.stamp_ns) <= 0)) if self.stamp_ns.size > 1 else 0
        return {"model": dict(self.model), "samples_on_clock": int(self.n_taken),
                "samples_written": int(self.index.size), "dropped": self.n_dropped,
                "dropped_runs_total": self.n_dropped_runs(), "dropped_runs": self.dropped_ranges(),
                "stamps_not_increasing": back}


__all__ = ["TimingModel", "SampleTimes", "TIMING_KEYS"]
