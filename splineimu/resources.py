"""Will it fit? Memory and disk estimates checked before a synthesis allocates anything.

A record of N samples costs, per sample, about :data:`STREAM_BYTES` of memory when it is
streamed to disk (the stamp arrays are whole), :data:`WHOLE_BYTES` when it is held whole (a
ROS bag or the plots need the whole record), :data:`TUM_BYTES` for a scene's TUM file, and
:data:`DISK_BYTES` of disk for the output folder's text tables (plus :data:`EXTRA_TABLE_BYTES` for
each optional IMU-shaped table: increments, vibration). :func:`check_record_fits`
compares these with what the process can still allocate (the free memory of the machine and
the address-space limit of the process, ``ulimit -v``) and with the free space where the
output goes, and refuses with the numbers and the way out.

Examples
--------
>>> check_record_fits(1000, rate_hz=200.0)
>>> check_record_fits(10**12, rate_hz=1000.0)
Traceback (most recent call last):
...
splineimu.errors.ConfigError: 1000000000000 IMU samples (1e+09 s at 1000 Hz) need about ...
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from .errors import ConfigError

#: memory per sample while streaming (stamps as int64 and as float seconds, and their grid's temporaries)
STREAM_BYTES = 48
#: memory per sample held whole (IMU, ground truth with rotation matrices, noise, bag messages)
WHOLE_BYTES = 1000
#: memory per sample of a scene's poses written as a TUM file (streamed like the record: 19 measured;
#: 390 when the poses were held whole)
TUM_BYTES = STREAM_BYTES
#: disk per sample: imu0/data.csv, state_groundtruth_estimate0/data.csv and groundtruth.tum
#: (measured up to 133 + 351 + 154 bytes with a noisy sensor model and a lever arm, 12 more per
#: table with Unix-ns stamps; 450 let a run start that then filled the disk)
DISK_BYTES = 700
#: disk per sample of each optional IMU-shaped table (increments.csv, vibration.csv: up to 147 + 12)
EXTRA_TABLE_BYTES = 160
#: outputs from this size on are announced before they are written (a note with the size)
LARGE_OUTPUT_BYTES = 2 * 10**9
#: memory per byte of a TUM pose file, read and fitted: measured 6.0 (1 kHz mocap, 92-byte lines,
#: 3.6M poses: 4.4 to read, then the fit) to 10.4 (noise-free 155-byte lines, fine knots)
POSE_FILE_BYTES = 6
#: the share of the available memory a record may use
MEMORY_SHARE = 0.8

__all__ = ["available_memory_bytes", "free_disk_bytes", "check_record_fits", "check_pose_file_fits", "STREAM_BYTES",
           "WHOLE_BYTES", "TUM_BYTES", "DISK_BYTES", "EXTRA_TABLE_BYTES", "LARGE_OUTPUT_BYTES", "POSE_FILE_BYTES",
           "output_bytes", "size_text"]


def _meminfo_available() -> int | None:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _address_space_left() -> int | None:
    try:
        import resource
    except ImportError:  # pragma: no cover - not POSIX
        return None
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return None
    used = 0
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmSize:"):
                    used = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        pass
    return max(soft - used, 0)


def available_memory_bytes() -> int | None:
    """Bytes this process can still allocate: the machine's available memory, bounded by the
    address-space limit (``ulimit -v``) minus what the process already maps; None if unknown."""
    values = [v for v in (_meminfo_available(), _address_space_left()) if v is not None]
    return min(values) if values else None


def free_disk_bytes(path) -> int | None:
    """Free bytes on the filesystem that ``path`` (or its nearest existing parent) is on."""
    p = Path(path).absolute()
    for q in (p, *p.parents):
        if q.exists():
            try:
                return shutil.disk_usage(q).free
            except OSError:
                return None
    return None


def size_text(n: float) -> str:
    """``n`` bytes as ``'2.52 TB'``, ``'25.2 GB'`` or ``'331 MB'``."""
    if n >= 1e12:
        return f"{n / 1e12:.3g} TB"
    return f"{n / 1e9:.3g} GB" if n >= 1e9 else f"{n / 1e6:.3g} MB"


_gb = size_text


def output_bytes(n_samples: int, extra_tables: int = 0) -> int:
    """Disk an output folder of ``n_samples`` takes: its three tables and ``extra_tables`` more
    (an upper estimate, :data:`DISK_BYTES` and :data:`EXTRA_TABLE_BYTES` per sample)."""
    return int(n_samples) * (DISK_BYTES + extra_tables * EXTRA_TABLE_BYTES)


def check_record_fits(n_samples: int, *, rate_hz: float | None = None, whole: str | None = None,
                      out_dir=None, tum=None, extra_tables: int = 0) -> None:
    """Refuse a record that cannot fit, before anything is allocated.

    Parameters
    ----------
    n_samples : int
        Samples of the record.
    rate_hz : float, optional
        Their rate, for the message.
    whole : str, optional
        What the record is held whole for, e.g. ``"--bag"`` (None: it is streamed).
    out_dir : path-like, optional
        The output folder (its free disk space is checked).
    tum : path-like, optional
        A TUM file of the poses (its disk space is checked).
    extra_tables : int, default 0
        Optional IMU-shaped tables written besides the three (increments, vibration).

    Raises
    ------
    ConfigError
        With the sample count, the memory or disk it needs, what is available and the way out.
    """
    n = int(n_samples)
    span = f" ({n / rate_hz:.6g} s at {rate_hz:g} Hz)" if rate_hz else ""
    what = f"{n} IMU samples{span}"
    way = "use a shorter span (--duration), a lower --rate, or split the recording"
    per = WHOLE_BYTES if whole else TUM_BYTES if tum else STREAM_BYTES
    need = n * per
    avail = available_memory_bytes()
    if avail is not None and need > MEMORY_SHARE * avail:
        held = f"; the whole record is held in memory for {whole}" if whole else ""
        raise ConfigError(f"{what} need about {_gb(need)} of memory, {_gb(avail)} are available{held}; {way}")
    if n_samples * STREAM_BYTES > 2**62:  # absurd even with unlimited memory
        raise ConfigError(f"{what} are too many; {way}")
    for target, need_disk in ((out_dir, output_bytes(n, extra_tables)), (tum, n * (DISK_BYTES // 4))):
        if target is None:
            continue
        free = free_disk_bytes(target)
        if free is not None and need_disk > free:
            raise ConfigError(f"{what} need about {_gb(need_disk)} of disk at '{target}', {_gb(free)} are free; "
                              f"{way}, or choose another output")


def check_pose_file_fits(path) -> None:
    """Refuse, before reading it, a TUM pose file too large to read and fit in the available memory.

    It would otherwise end in a MemoryError, or with no limit set, in the kernel's out-of-memory
    kill without a word (an hour at 10 kHz is a 5.6 GB file, about 34 GB to read and fit).
    The estimate, :data:`POSE_FILE_BYTES` per byte of the file, is the lower end of what was
    measured; a missing or unreadable file is left to the reader.

    Raises
    ------
    ConfigError
        With the file, its size, the memory it needs, what is available and the way out.

    Examples
    --------
    >>> check_pose_file_fits("no such file")
    """
    try:
        size = Path(path).stat().st_size
    except OSError:
        return
    avail = available_memory_bytes()
    need = POSE_FILE_BYTES * size
    if avail is not None and need > MEMORY_SHARE * avail:
        raise ConfigError(f"{path}: a pose file of {_gb(size)} needs about {_gb(need)} of memory to read and fit, "
                          f"{_gb(avail)} are available; split the file (or decimate it to a lower rate)")
