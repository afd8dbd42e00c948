"""Readers of recorded IMU data: EuRoC ``imu0/data.csv`` and the static ADIS16405 ``.rda`` file.

Both return ``(t_ns, gyro_rad_s, accel_m_s2)``: int64 nanoseconds (N,), and (N, 3) float64
arrays in rad/s and m/s^2. :func:`load_recording` reads either into an :class:`ImuRecording`
(six columns, the sample rate and notes) for noise analysis.

EuRoC csv
---------
One header/comment line or more starting with ``#`` (EuRoC:
``#timestamp [ns],w_RS_S_x [rad s^-1],...,a_RS_S_z [m s^-2]``), then rows of seven
comma-separated fields: integer nanoseconds, gyro x y z [rad/s], accel x y z [m/s^2].
Blank lines are skipped. Stamps must be strictly increasing.

Static ADIS16405 recording (``.rda``)
-------------------------------------
``../shared/data/static/adis_16405_imu1.rda`` (University of Calgary, via SMAC-Group/imudata,
CC BY-NC-SA 4.0) is an R data file holding one object ``adis_16405_imu1``: a 1,000,000 x 6
matrix of class ``imu`` with columns ``Gyro. X``, ``Gyro. Y``, ``Gyro. Z``, ``Accel. X``,
``Accel. Y``, ``Accel. Z`` and an attribute ``freq = 100`` (Hz); 2.78 h of a sensor at rest.
It carries no time stamps and no units: the values are gyro in deg/s (the quantization step
is 0.05, the ADIS16405's deg/s LSB) and accelerometer in g (step 0.00333, its 3.33 mg LSB;
z reads about -1.016, i.e. z points down). :func:`read_static_rda` reads it with ``rdata``
(``rdata.conversion.convert(rdata.parser.parse_file(path))[name]``), converts the units and
makes stamps ``round(i * 1e9 / rate_hz)``.
"""

from __future__ import annotations

import functools
import io
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError
from ..validation import as_rate_hz
from .timestamps import _looks_numeric

__all__ = ["read_imu_csv", "read_imu_table", "read_static_rda", "load_recording", "ImuRecording",
           "GYRO_UNITS", "ACCEL_UNITS", "STANDARD_GRAVITY", "RECORDING_FORMATS"]

#: Largest |gyro| or |accel| value an IMU csv may hold (far beyond any sensor in any unit); 1e300 passed
#: the reader and overflowed the analyses into inf, NaN quaternions and numpy warnings.
MAX_IMU_VALUE = 1e12

#: Standard gravity [m/s^2] used to convert "g" (ISO 80000-3).
STANDARD_GRAVITY = 9.80665

#: Gyro units -> factor to rad/s.
GYRO_UNITS = {
    "rad/s": 1.0,
    "deg/s": math.pi / 180.0,
    "deg/h": math.pi / 180.0 / 3600.0,
}
#: Accelerometer units -> factor to m/s^2.
ACCEL_UNITS = {
    "m/s^2": 1.0,
    "g": STANDARD_GRAVITY,
    "mg": STANDARD_GRAVITY * 1e-3,
}


def unit_factor(unit: str, table: dict, what: str) -> float:
    """Conversion factor of ``unit`` to SI from ``table``, or InputError listing the choices."""
    key = unit.strip().replace("s2", "s^2").replace("m/s/s", "m/s^2")
    if key not in table:
        raise InputError(f"unknown {what} unit `{unit}`; choose one of {', '.join(table)}")
    return table[key]


def _check_stamps(t_ns, path, line_of_row):
    d = np.diff(t_ns)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(f"time stamps must be strictly increasing: {int(t_ns[i])} after {int(t_ns[i - 1])}",
                         path, line_of_row(i))


def _parse_slow(path):
    """Line-by-line parser: exact messages with line numbers (used when the fast path fails)."""
    t, v, lines = [], [], []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for lineno, raw in enumerate(fh, 1):
            s = raw.strip()
            if not s or s.startswith("#"):
                continue
            parts = [p.strip() for p in s.split(",")]
            if len(parts) == 8 and not parts[-1]:  # a trailing comma
                parts.pop()
            if not t and len(parts) == 7 and not any(_looks_numeric(p) for p in parts):
                continue  # a header without '#' (timestamp,wx,wy,...)
            if len(parts) != 7:
                raise InputError("expected 7 comma-separated fields (t_ns, gyro xyz, accel xyz), "
                                 f"got {len(parts)}", path, lineno)
            if "_" in s:  # Python's int() and float() take 1_000 as 1000; a csv number has no underscore
                raise InputError(f"non-numeric value in {s!r}", path, lineno)
            try:
                tn = int(parts[0])
            except ValueError:
                raise InputError(f"time stamp must be integer nanoseconds, got {parts[0]!r}",
                                 path, lineno) from None
            if not -(2**63) <= tn < 2**63:
                raise InputError(f"time stamp {parts[0]} ns does not fit a 64-bit integer (after the year 2262)",
                                 path, lineno)
            try:
                vals = [float(p) for p in parts[1:]]
            except ValueError:
                raise InputError(f"non-numeric value in {s!r}", path, lineno) from None
            if not all(math.isfinite(x) for x in vals):
                raise InputError(f"non-finite value in {s!r}", path, lineno)
            t.append(tn)
            v.append(vals)
            lines.append(lineno)
    return np.asarray(t, dtype=np.int64), np.asarray(v, dtype=np.float64).reshape(-1, 6), lines


def read_imu_csv(path):
    """Read an EuRoC-format IMU csv.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    t_ns : (N,) int64
    gyro : (N, 3) float64 [rad/s]
    accel : (N, 3) float64 [m/s^2]

    Raises
    ------
    InputError
        Missing file, wrong field count, non-integer stamp, non-numeric value, non-increasing
        stamps, no data: the message names the file and line.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "imu.csv")
    >>> _ = open(p, "w").write("#timestamp [ns],wx,wy,wz,ax,ay,az\\n1000,0,0,0.1,0,0,9.81\\n")
    >>> t, g, a = read_imu_csv(p)
    >>> t.tolist(), g[0].tolist(), a[0].tolist()
    ([1000], [0.0, 0.0, 0.1], [0.0, 0.0, 9.81])
    """
    t_ns, vals = read_imu_table(path)
    return t_ns, np.ascontiguousarray(vals[:, :3]), np.ascontiguousarray(vals[:, 3:])


def read_imu_table(path):
    """:func:`read_imu_csv`, returning ``(t_ns (N,), values (N, 6))`` with the gyro in columns
    0-2 and the accelerometer in 3-5 (one array, no further copies)."""
    from .timestamps import check_line_lengths

    path = Path(path)
    if not path.is_file():
        raise InputError("file not found" if not path.exists() else "is a folder, expected a file", path)
    check_line_lengths(path)
    try:
        return _read_imu_table(path)
    except InputError as exc:
        from .sniff import add_format_hint

        raise add_format_hint(exc, path, "euroc_imu") from None


def _read_imu_table(path):
    from .sniff import check_ns_spacing

    try:
        with warnings.catch_warnings():
            # a lossy cast in pandas (a stamp beyond int64) is a failure too, not a printed warning
            warnings.simplefilter("error", RuntimeWarning)
            t_ns, vals = _read_fast(path)
    except Exception:  # noqa: BLE001 - any failure: the exact parser finds and names the line
        t_ns = vals = None
    lines = None
    if t_ns is None:
        t_ns, vals, lines = _parse_slow(path)
    if t_ns.size == 0:
        raise InputError("no IMU samples (expected rows 't_ns, gx, gy, gz, ax, ay, az')", path)

    def line_of_row(i):
        if lines is not None:
            return lines[i]
        return _line_of_data_row(path, i)

    _check_stamps(t_ns, path, line_of_row)
    big = np.abs(vals) > MAX_IMU_VALUE
    if big.any():
        i, j = (int(x[0]) for x in np.nonzero(big))
        raise InputError(f"value {vals[i, j]:g} (column {j + 2}) is beyond {MAX_IMU_VALUE:g} in magnitude: no IMU "
                         "reads that (a unit or column mix-up?)", path, line_of_row(i))
    check_ns_spacing(t_ns, path=path, advice="an EuRoC IMU csv has integer nanoseconds: convert the column")
    return t_ns, vals


#: files above this size are parsed in parallel parts (one per CPU, at most 4)
PARALLEL_PARSE_BYTES = 16 << 20


class _ByteRange(io.RawIOBase):
    """A read-only file over ``mm[start:end]`` (an mmap), for parsing one part of a file."""

    def __init__(self, mm, start, end):
        self.mm, self.pos, self.end = mm, start, end

    def readable(self):
        return True

    def readinto(self, buf):
        n = min(len(buf), self.end - self.pos)
        buf[:n] = self.mm[self.pos:self.pos + n]
        self.pos += n
        return n


@functools.cache
def _pandas_rounds_last_ulp() -> bool:
    import pandas as pd

    major, minor = (int(x) for x in pd.__version__.split(".")[:2])
    return (major, minor) < (3, 1)


def _read_fast(path):
    """pandas' C parser; large files in parts at line boundaries, parsed by parallel threads
    (the parser releases the GIL: 0.93 s -> 0.42 s for 300 MB on 2 CPUs, measured). Returns
    ``(None, None)`` or raises when the file is not a clean 7-column table."""
    import pandas as pd

    kw = dict(comment="#", header=None, skip_blank_lines=True, engine="c", low_memory=False,
              # column 0 inferred: forced to int64, pandas took "1403715273262142976.0" or "1e9" as a float
              # and cast it (to ...142912 ns) in silence; inferred, only all-integer text is int64
              dtype={1: np.float64, 2: np.float64, 3: np.float64, 4: np.float64, 5: np.float64, 6: np.float64})
    if _pandas_rounds_last_ulp():
        kw["float_precision"] = "round_trip"  # pandas < 3.1 parses some decimals 1 ulp off
    size = path.stat().st_size
    parts = min(os.cpu_count() or 1, 4) if size >= PARALLEL_PARSE_BYTES else 1
    if parts == 1:
        frames = [pd.read_csv(path, **kw)]
    else:
        import mmap
        from concurrent.futures import ThreadPoolExecutor

        with open(path, "rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            cuts = [0] + [mm.find(b"\n", size * i // parts) + 1 for i in range(1, parts)] + [size]
            if any(c <= 0 for c in cuts[1:-1]):
                return None, None

            def part(i):
                if cuts[i + 1] <= cuts[i]:
                    return pd.DataFrame(np.empty((0, 7)))
                return pd.read_csv(io.BufferedReader(_ByteRange(mm, cuts[i], cuts[i + 1]), 1 << 20), **kw)

            with ThreadPoolExecutor(max_workers=parts) as pool:
                frames = list(pool.map(part, range(parts)))
    if any(f.shape[1] != 7 or f[0].dtype != np.int64 for f in frames if len(f)):
        return None, None
    frames = [f for f in frames if len(f)]
    n = sum(len(f) for f in frames)
    vals = np.empty((n, 6))
    t_ns = np.empty(n, dtype=np.int64)
    a = 0
    for f in frames:
        b = a + len(f)
        for i in range(6):
            vals[a:b, i] = f[i + 1].to_numpy()
        t_ns[a:b] = f[0].to_numpy(dtype=np.int64)
        a = b
    if not np.all(np.isfinite(vals)):
        return None, None
    return t_ns, vals


def _line_of_data_row(path, row):
    """1-based line number of the ``row``-th data row (0-based) of a csv with # comments."""
    k = -1
    with open(path, encoding="utf-8", errors="replace") as fh:
        for lineno, raw in enumerate(fh, 1):
            s = raw.strip()
            if not s or s.startswith("#"):
                continue
            k += 1
            if k == row:
                return lineno
    return None


def read_static_rda(path, rate_hz: float = 100.0, gyro_unit: str = "deg/s", accel_unit: str = "g",
                    name: str | None = None):
    """Read a static IMU recording stored as an R matrix (the ADIS16405 ``.rda`` file).

    Parameters
    ----------
    path : path-like
        ``.rda`` file with one 6-column matrix (gyro x y z, accel x y z).
    rate_hz : float
        Sample rate; the file has no stamps (its ``freq`` attribute says 100 Hz).
    gyro_unit : {"deg/s", "rad/s", "deg/h"}
    accel_unit : {"g", "m/s^2", "mg"}
    name : str, optional
        Object to read (default: the only object in the file).

    Returns
    -------
    t_ns : (N,) int64, ``round(i * 1e9 / rate_hz)``
    gyro : (N, 3) float64 [rad/s]
    accel : (N, 3) float64 [m/s^2]

    Raises
    ------
    InputError
        Missing file, not an R data file, no or several objects, not 6 columns, non-finite.

    Notes
    -----
    Needs the ``rdata`` package (``pip install rdata``). Loading the 1e6 x 6 file takes about
    1.5 s.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", path)
    gf = unit_factor(gyro_unit, GYRO_UNITS, "gyro")
    af = unit_factor(accel_unit, ACCEL_UNITS, "accelerometer")
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise InputError(f"rate must be a positive number [Hz], got {rate_hz!r}", path)
    try:
        import rdata
    except ImportError:  # pragma: no cover - depends on the environment
        raise InputError("reading .rda files needs the `rdata` package (pip install rdata)", path) from None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "Missing constructor for R class 'imu'"
            objs = rdata.conversion.convert(rdata.parser.parse_file(path))
    except Exception as exc:  # noqa: BLE001 - rdata raises many types
        raise InputError(f"cannot read R data file: {exc}", path) from None
    if name is None:
        if len(objs) != 1:
            raise InputError(f"expected one object in the file, found {sorted(objs)}; pass `name`", path)
        name = next(iter(objs))
    if name not in objs:
        raise InputError(f"no object `{name}` in the file (has {sorted(objs)})", path)
    arr = np.asarray(getattr(objs[name], "values", objs[name]), dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise InputError(f"expected a matrix with 6 columns (gyro xyz, accel xyz), got shape {arr.shape}",
                         path)
    if not np.all(np.isfinite(arr)):
        row = int(np.flatnonzero(~np.all(np.isfinite(arr), axis=1))[0])
        raise InputError(f"non-finite value in row {row + 1}", path)
    n = arr.shape[0]
    t_ns = np.round(np.arange(n, dtype=np.float64) * (1e9 / rate_hz)).astype(np.int64)
    gyro = np.ascontiguousarray(arr[:, :3] * gf)
    accel = np.ascontiguousarray(arr[:, 3:] * af)
    return t_ns, gyro, accel


#: Formats :func:`load_recording` reads.
RECORDING_FORMATS = ("euroc", "rda")


@dataclass
class ImuRecording:
    """Six-axis IMU samples read for analysis.

    Attributes
    ----------
    values : (N, 6) float64
        Gyro [rad/s] in columns 0-2, accelerometer [m/s^2] in columns 3-5.
    rate_hz : float
        Sample rate (given, or from the median stamp interval).
    path : pathlib.Path
    format : {"euroc", "rda"}
    notes : list of str
        What was assumed or found (an assumed rate, gaps in the stamps).
    """

    values: np.ndarray
    rate_hz: float
    path: Path
    format: str
    notes: list = field(default_factory=list)

    @property
    def gyro_rad_s(self) -> np.ndarray:
        """(N, 3) view of the gyro columns."""
        return self.values[:, :3]

    @property
    def accel_m_s2(self) -> np.ndarray:
        """(N, 3) view of the accelerometer columns."""
        return self.values[:, 3:]


def load_recording(path, fmt=None, rate_hz=None, gyro_unit=None, accel_unit=None) -> ImuRecording:
    """Read an EuRoC IMU csv or an ``.rda`` matrix for noise analysis.

    Parameters
    ----------
    path : path-like
    fmt : {"euroc", "rda"}, optional
        Default: ``"rda"`` for ``.rda`` / ``.rdata`` files, else ``"euroc"``.
    rate_hz : float, optional
        Sample rate; default the csv stamps' median interval, 100 Hz for ``.rda`` (no stamps).
    gyro_unit : {"rad/s", "deg/s", "deg/h"}, optional
        Unit of the gyro columns (default rad/s for csv, deg/s for rda).
    accel_unit : {"m/s^2", "g", "mg"}, optional
        Unit of the accelerometer columns (default m/s^2 for csv, g for rda).

    Returns
    -------
    ImuRecording
        Values in SI units.

    Raises
    ------
    InputError
        Unreadable file, fewer than 3 samples, unknown unit.
    ConfigError
        Bad rate or format.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "imu.csv")
    >>> rows = "".join(f"{i * 5000000},0,0,1,0,0,9.81\\n" for i in range(4))
    >>> _ = open(p, "w").write("#timestamp [ns],wx,wy,wz,ax,ay,az\\n" + rows)
    >>> rec = load_recording(p, gyro_unit="deg/s")
    >>> rec.rate_hz, round(float(rec.gyro_rad_s[0, 2]), 6), rec.notes
    (200.0, 0.017453, [])
    """
    path = Path(path)
    if fmt is None:
        fmt = "rda" if path.suffix.lower() in (".rda", ".rdata") else "euroc"
    if fmt not in RECORDING_FORMATS:
        raise ConfigError(f"unknown recording format {fmt!r}; expected one of {', '.join(RECORDING_FORMATS)}",
                          option="format")
    notes = []
    if rate_hz is not None:
        rate_hz = as_rate_hz(rate_hz)
    if fmt == "rda":
        rate = 100.0 if rate_hz is None else rate_hz
        _, gyro, accel = read_static_rda(path, rate_hz=rate, gyro_unit=gyro_unit or "deg/s",
                                         accel_unit=accel_unit or "g")
        notes.append(f"no stamps in an .rda file: {rate:g} Hz assumed; units gyro {gyro_unit or 'deg/s'}, "
                     f"accel {accel_unit or 'g'}")
        return ImuRecording(np.hstack([gyro, accel]), rate, path, fmt, notes)
    t_ns, data = read_imu_table(path)
    if gyro_unit:
        data[:, :3] *= unit_factor(gyro_unit, GYRO_UNITS, "gyro")
    if accel_unit:
        data[:, 3:] *= unit_factor(accel_unit, ACCEL_UNITS, "accelerometer")
    if t_ns.size < 3:
        raise InputError(f"need at least 3 samples for an Allan deviation, got {t_ns.size}", path)
    d = np.diff(t_ns)
    med = float(np.median(d))
    rate = 1e9 / med if rate_hz is None else rate_hz
    if rate_hz is not None and abs(rate_hz * med / 1e9 - 1.0) > 0.01:
        notes.append(f"the rate given, {rate_hz:g} Hz, is not the stamps' {1e9 / med:.6g} Hz (median interval): "
                     "the cluster times and noise values follow the rate given")
    gaps = int(np.count_nonzero(d > 1.5 * med))
    if gaps:
        notes.append(f"{gaps} gap(s) longer than 1.5 sample intervals (longest {d.max() / 1e9:.3g} s): "
                     "the Allan deviation assumes even sampling")
    return ImuRecording(data, rate, path, fmt, notes)
