"""Vibration: sinusoids and band-limited random vibration added to the ideal IMU signals.

A scene's ``imu.vibration`` block lists components for the accelerometer (m/s^2) and the gyro
(rad/s), in the sensor frame::

    vibration:
      accel:
        - {freq_hz: 37.0, amplitude: [0.5, 0.0, 0.0]}         # peak amplitude per axis
        - {band_hz: [20.0, 80.0], psd: [1.0e-4, 1.0e-4, 0.0]}  # flat PSD, (unit)^2/Hz
      gyro:
        - {freq_hz: 37.0, amplitude: [0.0, 0.0, 0.01]}

Vibration is a function of true time, added before the sensor model (so scale, misalignment,
quantization and saturation apply to it) and not part of the ground-truth motion.

A sinusoid is ``A cos(2 pi f t + phi)`` with its phase drawn per axis. Random vibration of a
flat one-sided PSD ``S`` over ``[lo, hi]`` is a sum of :data:`N_TONES` cosines, one in each of
``N_TONES`` equal sub-bands at a random frequency inside it, with random phase and amplitude
``sqrt(2 S df)``: its variance is ``S (hi - lo)`` and its spectrum is flat at the sub-band
resolution; being a sum of cosines it is defined at any time, so irregular stamps (dropped
samples, clock drift) and interval means are exact. Phases and frequencies come from the
run's seed.

Interval means (``--sampling mean``) are exact: the mean of ``cos(w t + phi)`` over
``[a, b]`` is ``(sin(w b + phi) - sin(w a + phi)) / (w (b - a))``.

Examples
--------
>>> vib = VibrationModel.from_dict({"accel": [{"freq_hz": 10.0, "amplitude": [1.0, 0.0, 0.0]}]})
>>> real = vib.realize(rng=0)
>>> gyro, accel = real.evaluate([0.0, 0.05])
>>> round(float(abs(accel[0, 0] + accel[1, 0])), 12)   # half a period apart: opposite values
0.0
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._jit import jit
from ..validation import as_vector, nonnegative_float, positive_float
from .timing import _child_generators, _error

#: Cosines per random band.
N_TONES = 256
SENSORS = ("gyro", "accel")


@dataclass(frozen=True)
class Sinusoid:
    """``amplitude * cos(2 pi freq_hz t + phase)`` per axis (peak amplitude)."""

    freq_hz: float
    amplitude: tuple


@dataclass(frozen=True)
class RandomBand:
    """Band-limited random vibration with a flat one-sided PSD per axis over ``band_hz``."""

    band_hz: tuple
    psd: tuple


@dataclass(frozen=True)
class VibrationModel:
    """Vibration components of each sensor (see the module notes)."""

    gyro: tuple = ()
    accel: tuple = ()

    @classmethod
    def from_dict(cls, d: dict | None, doc=None, keys: tuple = ()) -> VibrationModel:
        """Build from a scene file's ``vibration`` mapping (errors at the yaml file and line)."""
        if d is None:
            return cls()
        if not isinstance(d, dict):
            raise _error(doc, keys, "`vibration` must be a mapping with `accel` and/or `gyro` lists")
        parts = {}
        for k, items in d.items():
            if k not in SENSORS:
                raise _error(doc, keys + (k,), f"unknown key `vibration.{k}`; known keys: accel, gyro")
            if not isinstance(items, list):
                raise _error(doc, keys + (k,), f"`vibration.{k}` must be a list of components")
            parts[k] = tuple(_component(it, doc, keys + (k, i), f"vibration.{k}[{i}]") for i, it in enumerate(items))
        return cls(**parts)

    def to_dict(self) -> dict:
        out = {}
        for s in SENSORS:
            comps = getattr(self, s)
            if comps:
                out[s] = [{"freq_hz": c.freq_hz, "amplitude": list(c.amplitude)} if isinstance(c, Sinusoid)
                          else {"band_hz": list(c.band_hz), "psd": list(c.psd)} for c in comps]
        return out

    @property
    def is_empty(self) -> bool:
        return not (self.gyro or self.accel)

    def aliasing_warnings(self, rate_hz: float, sampling: str = "point") -> list:
        """Warnings for components above the Nyquist frequency ``rate_hz / 2``: they alias.

        An IMU without an anti-aliasing filter shows such vibration at a lower frequency, and so
        does the synthesized data: this is what the user should be told, not refused. A
        sinusoid at ``f`` appears at ``|f - rate * round(f / rate)|``; the part of a random band
        above Nyquist folds into the range given. With ``sampling="mean"`` the interval mean
        attenuates a sinusoid by ``|sinc(f / rate)|``, which is stated.

        Returns
        -------
        list of dict
            ``{"code": "vibration_aliased", "message": ...}`` (report.json's warning form), one
            per aliased component.

        Examples
        --------
        >>> vib = VibrationModel.from_dict({"gyro": [{"freq_hz": 300.0, "amplitude": [0.1, 0, 0]}]})
        >>> for part in vib.aliasing_warnings(200.0)[0]["message"].split(": "):
        ...     print(part)
        vibration.gyro[0] at 300 Hz is above the Nyquist frequency 100 Hz of the 200 Hz samples
        it appears aliased at 100 Hz
        """
        rate = float(rate_hz)
        nyq = 0.5 * rate
        out = []
        for s in SENSORS:
            for i, c in enumerate(getattr(self, s)):
                label = f"vibration.{s}[{i}]"
                if isinstance(c, Sinusoid):
                    if c.freq_hz <= nyq:
                        continue
                    text = (f"{label} at {c.freq_hz:g} Hz is above the Nyquist frequency {nyq:g} Hz of the "
                            f"{rate:g} Hz samples: it appears aliased at {_fold(c.freq_hz, rate):g} Hz")
                    if sampling == "mean":
                        x = np.pi * c.freq_hz / rate
                        text += f" (the interval mean leaves {abs(np.sin(x) / x):.3g} of its amplitude)"
                else:
                    lo, hi = c.band_hz
                    if hi <= nyq:
                        continue
                    a, b = _fold_band(max(lo, nyq), hi, rate)
                    text = (f"{label}, band [{lo:g}, {hi:g}] Hz, extends above the Nyquist frequency {nyq:g} Hz "
                            f"of the {rate:g} Hz samples: its part above {nyq:g} Hz appears aliased in "
                            f"[{a:g}, {b:g}] Hz")
                out.append({"code": "vibration_aliased", "message": text})
        return out

    def realize(self, rng=None) -> VibrationRealization:
        """Draw phases (and random-band frequencies) from ``rng``: one realization for a run.

        ``rng`` is a Generator, SeedSequence, int or None; the gyro and the accelerometer draw
        from their own child streams (adding a gyro component leaves the accel's phases as
        they were).
        """
        tables = []
        for s, gen in zip(SENSORS, _child_generators(rng, len(SENSORS))):
            freq, amp, phase = [], [], []
            for c in getattr(self, s):
                if isinstance(c, Sinusoid):
                    f = np.full(1, c.freq_hz)
                    a = np.asarray(c.amplitude, dtype=np.float64)[None, :]
                else:
                    lo, hi = c.band_hz
                    df = (hi - lo) / N_TONES
                    f = lo + df * (np.arange(N_TONES) + gen.random(N_TONES))
                    a = np.repeat(np.sqrt(2.0 * np.asarray(c.psd, dtype=np.float64) * df)[None, :], N_TONES, axis=0)
                freq.append(np.repeat(f[:, None], 3, axis=1))
                amp.append(a)
                phase.append(gen.uniform(0.0, 2.0 * np.pi, (f.size, 3)))
            if freq:
                tables.append(tuple(np.ascontiguousarray(np.concatenate(x)) for x in (freq, amp, phase)))
            else:
                tables.append(None)
        return VibrationRealization(*tables)


def _fold(f: float, rate: float) -> float:
    """The frequency in ``[0, rate / 2]`` at which a tone at ``f`` appears when sampled at ``rate``."""
    return float(abs(f - rate * np.round(f / rate)))


def _fold_band(lo: float, hi: float, rate: float) -> tuple:
    """The range in ``[0, rate / 2]`` that ``[lo, hi]`` folds into.

    Folding is monotone between multiples of Nyquist and the folded pieces meet at the images
    of those multiples (0 or Nyquist), so the image is the range spanned by the images of the
    ends and of the multiples inside.
    """
    nyq = 0.5 * rate
    if hi - lo >= rate:
        return 0.0, nyq
    edges = [k * nyq for k in range(int(np.floor(lo / nyq)) + 1, int(np.ceil(hi / nyq)))]
    images = [_fold(f, rate) for f in (lo, hi, *edges)]
    return min(images), max(images)


def _component(item, doc, keys, label):
    from ..errors import ConfigError

    if not isinstance(item, dict):
        raise _error(doc, keys, f"`{label}` must be {{freq_hz, amplitude}} or {{band_hz, psd}}")
    try:
        if set(item) == {"freq_hz", "amplitude"}:
            amp = as_vector(item["amplitude"], f"{label}.amplitude")
            return Sinusoid(positive_float(item["freq_hz"], f"{label}.freq_hz"), tuple(float(x) for x in amp))
        if set(item) == {"band_hz", "psd"}:
            band = item["band_hz"]
            if not (isinstance(band, list) and len(band) == 2):
                raise ConfigError(f"`{label}.band_hz` must be [low, high] in Hz")
            lo = nonnegative_float(band[0], f"{label}.band_hz[0]")
            hi = positive_float(band[1], f"{label}.band_hz[1]")
            if not hi > lo:
                raise ConfigError(f"`{label}.band_hz` must have high > low, got [{lo:g}, {hi:g}]")
            psd = as_vector(item["psd"], f"{label}.psd")
            if (psd < 0).any():
                raise ConfigError(f"`{label}.psd` must be zero or positive, got {psd.tolist()}")
            return RandomBand((lo, hi), tuple(float(x) for x in psd))
    except (ConfigError, ValueError) as exc:
        if doc is None:
            raise
        raise _error(doc, keys, getattr(exc, "problem", str(exc))) from None
    raise _error(doc, keys, f"`{label}` must have exactly the keys freq_hz, amplitude (a sinusoid) "
                            f"or band_hz, psd (random vibration), got {sorted(item)}")


@jit(nogil=True)
def _cos_sum(t, a, freq, amp, phase, out):
    """out[n, j] = sum_i amp[i, j] * mean of cos(2 pi freq[i, j] s + phase[i, j]) over s in [a_n, t_n].

    The mean is ``cos(w m + phi) sin(w h) / (w h)`` with midpoint ``m`` and half-width ``h``
    (no cancellation for short intervals; the point value at ``h = 0``).
    """
    two_pi = 2.0 * np.pi
    for n in range(t.size):
        m = 0.5 * (t[n] + a[n])
        h = 0.5 * (t[n] - a[n])
        for j in range(3):
            acc = 0.0
            for i in range(freq.shape[0]):
                w = two_pi * freq[i, j]
                x = w * h
                sinc = 1.0 - x * x / 6.0 if abs(x) < 1e-4 else np.sin(x) / x
                acc += amp[i, j] * np.cos(w * m + phase[i, j]) * sinc
            out[n, j] = acc


@dataclass
class VibrationRealization:
    """One drawn realization: :meth:`evaluate` at true times (seconds, the motion's time base)."""

    gyro_table: tuple | None = None
    accel_table: tuple | None = None

    def evaluate(self, t_s, interval_start_s=None):
        """Vibration (gyro [rad/s], accel [m/s^2]), each (N, 3), at ``t_s``.

        With ``interval_start_s`` the mean over ``[interval_start_s, t_s]`` is returned
        (``--sampling mean``); where the interval is empty the point value.
        """
        t = np.ascontiguousarray(t_s, dtype=np.float64).reshape(-1)
        a = t if interval_start_s is None else np.ascontiguousarray(interval_start_s, dtype=np.float64).reshape(-1)
        out = []
        for table in (self.gyro_table, self.accel_table):
            v = np.zeros((t.size, 3))
            if table is not None:
                _cos_sum(t, a, table[0], table[1], table[2], v)
            out.append(v)
        return out[0], out[1]


__all__ = ["VibrationModel", "VibrationRealization", "Sinusoid", "RandomBand", "N_TONES"]
