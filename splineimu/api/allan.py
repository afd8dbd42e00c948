"""Allan analysis of a recorded file, what ``splineimu allan`` runs: read, compute the curves, fit,
write ``allan.yaml`` / ``allan.png``."""

from __future__ import annotations

from pathlib import Path

from ..allan.deviation import allan_deviation
from ..allan.fit import fit_noise_parameters
from ..allan.recording import IMU_LABELS, MIN_SAMPLES, AllanAnalysis
from ..allan.report import allan_yaml_header
from ..errors import ConfigError, InputError, OutputExistsError
from ..io.allan_plot import plot_allan
from ..io.files import check_output_file
from ..io.imu_csv import load_recording
from ..io.yaml import write_yaml

__all__ = ["AllanAnalysis", "analyze_recording", "allan_output_paths", "write_allan_outputs", "plot_allan"]


def analyze_recording(path, fmt=None, rate_hz=None, gyro_unit=None, accel_unit=None,
                      points_per_decade: float = 10.0) -> AllanAnalysis:
    """Overlapping Allan deviation and noise parameters of all six axes of a static recording.

    Parameters
    ----------
    path : path-like
        EuRoC IMU csv or ``.rda`` matrix; see :func:`splineimu.io.imu_csv.load_recording` for
        ``fmt``, ``rate_hz``, ``gyro_unit`` and ``accel_unit``.
    points_per_decade : float
        Density of the log-spaced cluster times.

    Returns
    -------
    AllanAnalysis

    Raises
    ------
    InputError, ConfigError
        Unreadable file or bad options.

    Examples
    --------
    >>> import tempfile, os, numpy as np
    >>> p = os.path.join(tempfile.mkdtemp(), "imu.csv")
    >>> y = np.random.default_rng(0).standard_normal((2000, 6)) * 0.01
    >>> _ = open(p, "w").write("".join(f"{i * 10_000_000}," + ",".join(map(repr, r)) + "\\n"
    ...                                for i, r in enumerate(y.tolist())))
    >>> a = analyze_recording(p)
    >>> a.rate_hz, a.result.labels[0], a.to_dataframe().shape
    (100.0, 'gyro x', (6, 13))
    """
    rec = load_recording(path, fmt, rate_hz, gyro_unit, accel_unit)
    n = len(rec.values)
    if n < MIN_SAMPLES:
        raise InputError(f"{n} samples ({n / rec.rate_hz:.3g} s) are too few for an Allan analysis (at least "
                         f"{MIN_SAMPLES}); record a static IMU for minutes (white noise) to hours (bias instability)",
                         path=path)
    result = allan_deviation(rec.values, rec.rate_hz, points_per_decade=points_per_decade,
                             labels=list(IMU_LABELS))
    return AllanAnalysis(result, fit_noise_parameters(result), source=str(path), notes=list(rec.notes))


def allan_output_paths(out_dir, plot: bool = False, force: bool = False, inputs=()) -> list:
    """``[out_dir/allan.yaml (, out_dir/allan.png)]``, checked before any work is done.

    Raises
    ------
    ConfigError
        ``out_dir`` exists and is not a folder; a target is a symbolic link, a folder or one of
        ``inputs`` (the files the analysis reads).
    OutputExistsError
        A target exists and ``force`` is false.
    """
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ConfigError(f"-o {out_dir}: exists and is not a directory")
    targets = [out_dir / "allan.yaml"] + ([out_dir / "allan.png"] if plot else [])
    existing = [str(p) for p in targets if p.exists() or p.is_symlink()]
    if existing and not force:
        raise OutputExistsError(f"{', '.join(existing)} exist(s); use --force to overwrite")
    for p in targets:
        check_output_file(p, True, inputs=inputs)
    return targets


def write_allan_outputs(analysis: AllanAnalysis, out_dir, plot: bool = False, force: bool = False) -> list:
    """Write ``out_dir/allan.yaml`` (Kalibr keys, usable as ``--imu``) and with ``plot`` ``allan.png``.

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    ConfigError, OutputExistsError
        As :func:`allan_output_paths`.
    """
    targets = allan_output_paths(out_dir, plot, force)
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    result = analysis.result
    write_yaml(targets[0], analysis.noise_dict(), allan_yaml_header(result, analysis.source), opencv=True)
    if plot:
        plot_allan(result, analysis.fit, targets[1],
                   title=f"{Path(analysis.source).name}: {result.duration_s / 3600:.2f} h at {result.rate_hz:.6g} Hz")
    return targets
