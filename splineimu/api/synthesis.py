"""Synthesis jobs: from a pose file or an analytic scene to IMU data, its ground truth and a report.

One function per job; the ``from-tum``, ``from-euroc``, ``scene`` and ``run`` commands only
build a :class:`~splineimu.api.options.SynthesisJob` and call :func:`run_job`.

- :func:`synthesize_poses`: read the pose file, check its gaps (stop, bridge, or split it into
  pieces, one output folder each), fit a spline, choose the stamps, synthesize, write.
- :func:`synthesize_scene`: the same from an analytic scene (exact derivatives).
- :func:`run_job`: either, by the job's motion input.
- :func:`synthesize_to_memory`: the same work without files; the arrays are in the result.
- :func:`prepare_motion`: the motion part alone (pose file read and fitted, or the scene made),
  to be passed as ``prepared=`` to many runs that differ only in their IMU (Monte-Carlo batches).

Examples
--------
>>> from splineimu.api import ImuOptions, SceneInput, SynthesisJob, synthesize_to_memory
>>> res = synthesize_to_memory(SynthesisJob(SceneInput("static", duration_s=1.0), ImuOptions(rate_hz=10)))
>>> res.synthesis.t_ns.size, res.synthesis.accel_m_s2[0].tolist()
(11, [0.0, 0.0, 9.81])
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError
from .options import PosesInput, SceneInput, SynthesisJob
from .report import fit_lines, fit_warnings, imu_line, poses_report, scene_report

#: --gaps split: pieces with fewer poses are skipped (a spline of order 6 needs a few knots of data)
MIN_PIECE_POSES = 12


@dataclass
class SynthesisResult:
    """What a synthesis job did.

    Attributes
    ----------
    job : SynthesisJob
    report : dict
        The content of ``report.json`` (of the first piece when the input was split).
    out_dir : pathlib.Path or None
        The output folder (None when nothing was written).
    lines : list of str
        The summary the command line prints (timings included; they are not in the report).
    notes : list of str
        Notices about the input (ignored columns, dropped stamps, ...), printed to stderr.
    fit_report : FitReport or None
        The spline fit (pose inputs).
    source : MotionSource
        The fitted spline or the scene.
    synthesis : Synthesis or None
        The arrays, from :func:`synthesize_to_memory`.
    pieces : list of SynthesisResult
        One per piece when a pose file was split at its gaps (``gaps="split"``).
    observations : dict or None
        Jobs with cameras: name -> :class:`~splineimu.camera.Observations`.
    landmarks : Landmarks or None
        Jobs with cameras: the landmarks observed.
    """

    job: SynthesisJob
    report: dict = field(default_factory=dict)
    out_dir: Path | None = None
    lines: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    fit_report: object = None
    source: object = None
    synthesis: object = None
    pieces: list = field(default_factory=list)
    observations: dict | None = None
    landmarks: object = None


@dataclass
class PreparedMotion:
    """A job's motion made ready once for many runs: the scene, or the pose file read and fitted.

    Made by :func:`prepare_motion`; runs that share it (``run_job(job, prepared=...)``) must have
    the same motion options. It is not modified by the runs, so one copy may serve many.

    Attributes
    ----------
    motion : PosesInput or SceneInput
        The options it was made from.
    scene : Scene or None
        The analytic scene (scene inputs).
    track : PoseTrack or None
        The pose file's content (pose inputs).
    gaps : list
        Gaps longer than ``max_gap_s`` (bridged, or where the file was split).
    max_gap_s : float or None
    pieces : list of (track, spline, fit_report)
        One fitted spline per piece (one piece unless ``gaps="split"``).
    split : bool
        Whether the pose file was split at its gaps.
    """

    motion: object
    scene: object = None
    track: object = None
    gaps: list = field(default_factory=list)
    max_gap_s: float | None = None
    pieces: list = field(default_factory=list)
    split: bool = False


class _Log:
    def __init__(self, result, echo):
        self.result = result
        self.echo = echo

    def line(self, text):
        self.result.lines.append(text)
        if self.echo:
            self.echo(text, False)

    def note(self, text):
        self.result.notes.append(text)
        if self.echo:
            self.echo(text, True)


def run_job(job: SynthesisJob, *, echo=None, write: bool = True, prepared: PreparedMotion | None = None
            ) -> SynthesisResult:
    """Run a synthesis job: :func:`synthesize_poses` or :func:`synthesize_scene` by its motion input.

    Parameters
    ----------
    job : SynthesisJob
    echo : callable, optional
        ``echo(text, is_note)`` is called with each summary line as the work proceeds (the
        command line prints them; notes go to stderr).
    write : bool
        Write the output folder (``job.output.dir``); without it the arrays are kept in
        :attr:`SynthesisResult.synthesis` and nothing is written.
    prepared : PreparedMotion, optional
        The motion of ``job`` already made by :func:`prepare_motion` (it is then neither read
        nor fitted again).

    Returns
    -------
    SynthesisResult

    Raises
    ------
    InputError, ConfigError, OutputExistsError
        Bad input file or options; an output folder that exists (without ``force``).
    """
    if isinstance(job.motion, PosesInput):
        return synthesize_poses(job, echo=echo, write=write, prepared=prepared)
    return synthesize_scene(job, echo=echo, write=write, prepared=prepared)


def prepare_motion(job: SynthesisJob, *, echo=None) -> PreparedMotion:
    """The motion of ``job`` made once: the scene built, or the pose file read, checked and fitted.

    Parameters
    ----------
    job : SynthesisJob
        Only its motion options are used.
    echo : callable, optional
        As in :func:`run_job` (the input summary and fit notices).

    Returns
    -------
    PreparedMotion
        To be passed as ``prepared=`` to :func:`run_job` for any job with the same motion.

    Raises
    ------
    InputError, ConfigError
        As :func:`run_job`.

    Examples
    --------
    >>> from splineimu.api import ImuOptions, SceneInput, SynthesisJob
    >>> job = SynthesisJob(SceneInput("static", duration_s=1.0), ImuOptions(rate_hz=10))
    >>> prep = prepare_motion(job)
    >>> run_job(job, write=False, prepared=prep).synthesis.t_ns.size
    11
    """
    log = _Log(SynthesisResult(job), echo)
    if isinstance(job.motion, PosesInput):
        return _prepare_poses(job, log)
    from .. import scenes

    m = job.motion
    return PreparedMotion(m, scene=scenes.make_scene(m.name, duration_s=m.duration_s, t0_ns=m.t0_ns, **m.params))


def _prepared(job, prepared):
    if prepared is not None and prepared.motion != job.motion:
        raise ConfigError("the prepared motion was made from other motion options than this job's")
    return prepared


def synthesize_to_memory(job: SynthesisJob) -> SynthesisResult:
    """:func:`run_job` without files: the result holds the :class:`~splineimu.pipeline.Synthesis`."""
    return run_job(job, write=False)


def _start(job, motion_type, echo, write):
    """Check the job's kind and its output location (fail fast); the wall clock, result and log."""
    if not isinstance(job.motion, motion_type):
        raise ConfigError(f"expected a job with {motion_type.__name__}, got {type(job.motion).__name__}")
    result = SynthesisResult(job)
    _check_output(job, write)
    return time.perf_counter(), result, _Log(result, echo)


def _check_output(job, write):
    if write:
        if job.output.dir is None and job.output.tum is None:
            raise ConfigError("nothing to write: give an output folder (or, for a scene, a TUM file)",
                              option="--out")
        from ..io.files import check_not_input, check_output_dir, check_output_file

        inputs = _input_files(job)
        if job.output.dir is not None:
            check_output_dir(job.output.dir, job.output.force)
            check_not_input(job.output.dir, inputs)
        if job.output.tum is not None:
            check_output_file(job.output.tum, job.output.force, inputs, option="--tum")
            if job.output.dir is not None:  # written first, then removed (--force) or in the way of the folder
                tum, out = Path(job.output.tum).resolve(), Path(job.output.dir).resolve()
                if tum == out or out in tum.parents:
                    raise ConfigError(f"--tum '{job.output.tum}' lies in the output folder '{job.output.dir}', which "
                                      "is written as a whole: give a path outside it (OUT/groundtruth.tum holds the "
                                      "poses too)", option="--tum")


def _input_files(job) -> list:
    """The files a job reads (an output may never replace one)."""
    files = [getattr(job.motion, "path", None), job.imu.timestamps]
    files += [v for v in (job.imu.model, job.imu.extrinsic) if isinstance(v, str) and Path(v).exists()]
    return [f for f in files if f is not None]


def _seed(job):
    """A given seed, or (with something random: a sensor model, stamp noise, losses, vibration) a
    fresh one that is reported so that the run can be repeated."""
    imu = job.imu
    timing = imu.timing
    random_timing = timing is not None and (timing.stamp_noise_s > 0 or timing.drop_probability > 0)
    if imu.seed is not None or not (imu.imu_config is not None or random_timing or imu.vibration is not None
                                     or job.cameras is not None):
        return imu.seed
    return int(np.random.SeedSequence().entropy % (2**63))


def _fits(job, n, write, tum=False, log=None):
    """Refuse, before allocating, a record of ``n`` samples that cannot fit (memory, disk); announce
    a large output folder (a note with its size) before it is written."""
    from ..resources import LARGE_OUTPUT_BYTES, check_record_fits, output_bytes, size_text

    out = job.output
    whole = " and ".join(f for f, on in (("--bag", out.bag), ("--plot", out.plot)) if on and write) or None
    whole = whole if write else "the in-memory result"
    extra = int(bool(job.imu.increments)) + int(job.imu.vibration is not None)
    check_record_fits(n, rate_hz=job.imu.rate_hz if job.imu.timestamps is None else None, whole=whole,
                      out_dir=out.dir if write else None, tum=out.tum if tum else None, extra_tables=extra)
    if write and log is not None and output_bytes(n, extra) >= LARGE_OUTPUT_BYTES:
        log.note(f"note: {n} IMU samples: up to {size_text(output_bytes(n, extra))} of tables will be "
                 f"written to {out.dir}")


def _stamps(job, first_ns: int, last_ns: int, log, seed=None, write=True):
    """The stamps: a grid at ``rate_hz``, the given ``timestamps``, or (with a timing model) the
    :class:`~splineimu.imu.timing.SampleTimes` of the IMU's clock."""
    if job.imu.timestamps is None:  # a grid: refuse what cannot fit before allocating it
        n = int((last_ns - first_ns) * job.imu.rate_hz / 1e9) + 1
        if n < 2:  # --rate 0.001 over 600 s wrote a one-row "record" in silence
            raise job.imu._err("rate_hz", f"= {job.imu.rate_hz:g} Hz gives a single IMU sample over the "
                                          f"{(last_ns - first_ns) / 1e9:.6g} s of motion; a record needs 2 or more")
        _fits(job, n, write, log=log)
    if job.imu.timing is not None:
        from ..pipeline import TIMING_SEED_KEY, child_seed

        st = job.imu.timing.sample_times(first_ns, last_ns, job.imu.rate_hz, rng=child_seed(seed, TIMING_SEED_KEY))
        if st.index.size == 0:
            raise ConfigError("every sample was dropped: lower `drop_probability`", option="timing.drop_probability")
        log.line(f"timing        {st.n_dropped} of {st.n_taken} samples dropped; stamps on the IMU clock "
                 f"({', '.join(f'{k} {v:g}' for k, v in st.model.items())})")
        return st
    if job.imu.timestamps is None:
        from ..timegrid import uniform_stamps_ns

        return uniform_stamps_ns(first_ns, last_ns, job.imu.rate_hz)
    from ..io.timestamps import read_timestamps

    stamps = read_timestamps(job.imu.timestamps)
    keep = (stamps >= first_ns) & (stamps <= last_ns)
    if not keep.any():
        raise InputError(f"no stamp lies inside the motion's span [{first_ns}, {last_ns}] ns",
                         path=job.imu.timestamps)
    _fits(job, int(keep.sum()), write, log=log)
    dropped = int((~keep).sum())
    if dropped:
        log.line(f"note: {dropped} stamps of {job.imu.timestamps} lie outside the pose span and were dropped")
    return stamps[keep]


class _Within:
    """A motion source seen over [first_ns, last_ns] of its range (trimmed ends)."""

    def __init__(self, source, first_ns, last_ns):
        self._source = source
        self.t_min_s = (first_ns - int(source.origin_ns)) / 1e9
        self.t_max_s = (last_ns - int(source.origin_ns)) / 1e9

    def __getattr__(self, name):
        return getattr(self._source, name)


def _vibration_warnings(job, t_ns, report, log):
    """Vibration above the Nyquist frequency aliases (as on a sensor without an anti-aliasing
    filter): kept in the data, told in report.json's warnings and on stderr."""
    if job.imu.vibration is None:
        return
    stamps = np.asarray(getattr(t_ns, "stamp_ns", t_ns))
    rate = job.imu.rate_hz
    if job.imu.timestamps is not None:
        rate = 1e9 / float(np.median(np.diff(stamps))) if stamps.size > 1 else None
    for w in job.imu.vibration.aliasing_warnings(rate, job.imu.sampling) if rate else []:
        report.setdefault("warnings", []).append(w)
        log.note(f"warning: {w['message']}")


def _synthesize(job, source, t_ns, seed, out_dir, report, write, result, force=None, fit_data=None, window=None):
    """``window``: (first, last) ns of the record within the source's range (trimmed ends), which
    the cameras keep to as well."""
    from ..pipeline import synthesize_stream
    from .output import write_output

    imu = job.imu
    syn = synthesize_stream(source, t_ns, gravity=imu.gravity, extrinsic=imu.body_T_sensor,
                            imu_config=imu.imu_config, seed=seed, sampling=imu.sampling,
                            with_increments=imu.increments, vibration=imu.vibration)
    extra = None
    if job.cameras is not None:
        from .cameras import observe_job, write_job_cameras

        seen = source if window is None else _Within(source, *window)
        result.landmarks, result.observations, cam_report = observe_job(job, seen, seed)
        report = {**report, **cam_report}

        def extra(tmp, out_report):  # the camera files, inside the same atomic output folder
            plots = write_job_cameras(tmp, result.landmarks, result.observations, plot=job.output.plot)
            if plots:
                out_report["plots"] = out_report.get("plots", []) + plots
    if write:
        result.report = write_output(syn, out_dir, force=job.output.force if force is None else force, report=report,
                                     bag=job.output.bag, plot=job.output.plot, fit_data=fit_data, extra=extra,
                                     rate_hz=None if imu.timestamps else imu.rate_hz, rostopic=imu.rostopic,
                                     bag_version=job.output.bag_version)
        result.out_dir = Path(out_dir)
    else:
        result.synthesis = syn.collect()
        result.report = report
    return result


def synthesize_scene(job: SynthesisJob, *, echo=None, write: bool = True, prepared: PreparedMotion | None = None
                     ) -> SynthesisResult:
    """IMU data from an analytic scene (exact derivatives); parameters as :func:`run_job`.

    With ``job.output.tum`` the scene's poses at the IMU rate are also written as a TUM file.
    """
    from ..io.tum import write_scene_tum

    t_wall, result, log = _start(job, SceneInput, echo, write)
    m = job.motion
    prepared = _prepared(job, prepared)
    scene = prepared.scene if prepared is not None else prepare_motion(job).scene
    result.source = scene
    if write and job.output.tum:
        _fits(job, int(scene.t_max_s * job.imu.rate_hz) + 1, False, tum=True)
        write_scene_tum(scene, job.output.tum, job.imu.rate_hz)
        log.line(f"poses         {job.output.tum} ({job.imu.rate_hz:g} Hz)")
    if write and job.output.dir is None:
        return result
    seed = _seed(job)
    t_ns = _stamps(job, scene.origin_ns, scene.origin_ns + int(round(scene.t_max_s * 1e9)), log, seed, write)
    report = scene_report(scene, job)
    _vibration_warnings(job, t_ns, report, log)
    _synthesize(job, scene, t_ns, seed, job.output.dir, report, write, result)
    log.line(f"scene         {m.name}, {scene.t_max_s:g} s")
    log.line(imu_line(getattr(t_ns, "stamp_ns", t_ns), job, seed))
    _camera_line(result, log)
    if write:
        log.line(f"written       {job.output.dir}  ({time.perf_counter() - t_wall:.2f} s)")
    return result


def synthesize_poses(job: SynthesisJob, *, echo=None, write: bool = True, prepared: PreparedMotion | None = None
                     ) -> SynthesisResult:
    """IMU data from a pose file through a fitted spline; parameters as :func:`run_job`.

    Gaps longer than ``max_gap_s`` stop the job (``gaps="error"``), are fitted through
    (``"bridge"``), or split the file into pieces written to ``part_000``, ``part_001``, ...
    inside the output folder (``"split"``; pieces of fewer than :data:`MIN_PIECE_POSES` poses
    are skipped). The result of each piece is in :attr:`SynthesisResult.pieces`.
    """
    t_wall, result, log = _start(job, PosesInput, echo, write)
    prep = _prepared(job, prepared) or _prepare_poses(job, log)
    gaps, max_gap = prep.gaps, prep.max_gap_s
    if not prep.split:
        _one(job, prep.pieces[0], job.output.dir, gaps, max_gap, write, result, log)
        if write:
            log.line(f"written       {job.output.dir}  ({time.perf_counter() - t_wall:.2f} s)")
        return result
    if not write:
        for piece in prep.pieces:
            result.pieces.append(_one(job, piece, None, [], max_gap, False, SynthesisResult(job), None))
        return result
    from ..io.files import OutputFolder

    with OutputFolder(job.output.dir, force=job.output.force) as tmp:
        for i, piece in enumerate(prep.pieces):
            sub = tmp / f"part_{i:03d}"
            track = piece[0]
            log.line(f"piece {i}       {track.t_ns.size} poses from {track.t_ns[0]} ns -> {sub.name}")
            res = _one(job, piece, sub, [], max_gap, True, SynthesisResult(job), None)
            res.out_dir = Path(job.output.dir) / sub.name
            result.pieces.append(res)
    result.out_dir = Path(job.output.dir)
    result.report = result.pieces[0].report
    log.line(f"written       {job.output.dir} ({len(prep.pieces)} pieces, {time.perf_counter() - t_wall:.2f} s)")
    return result


def _prepare_poses(job, log) -> PreparedMotion:
    """Read the pose file, check its gaps, split it if asked, fit one spline per piece."""
    from ..io.poses import find_gaps, split_at_gaps

    m = job.motion
    track = _read(m)
    if m.retime_stamps:  # receive times: the poses back on their capture clock
        from dataclasses import replace

        from ..stamps import retime_stamps

        rt = retime_stamps(track.t_ns, track.positions, track.quat_xyzw, path=m.path)
        track = replace(track, t_ns=rt.t_ns, notices=[*track.notices, rt.summary()])
        doubt = rt.summary() if rt.doubtful else None  # (a warning of every piece's fit)
    else:
        doubt = None
    for note in track.notices:
        log.note(f"note: {m.path}: {note}")
    med = float(np.median(np.diff(track.t_ns))) / 1e9
    max_gap = m.max_gap_s if m.max_gap_s is not None else max(0.5, 5.0 * med)
    gaps = find_gaps(track.t_ns, max_gap, getattr(track, "line_numbers", None))
    if gaps and m.gaps == "error":
        g = gaps[0]
        more = f" (and {len(gaps) - 1} more)" if len(gaps) > 1 else ""
        raise InputError(
            f"gap of {g.duration_s:.3f} s before this pose{more} exceeds --max-gap {max_gap:g} s; "
            "use --gaps bridge to fit through it or --gaps split to write one folder per piece",
            path=m.path, line=g.line)
    log.line(f"input         {m.path}: {track.t_ns.size} poses, {(track.t_ns[-1] - track.t_ns[0]) / 1e9:.3f} s, "
             f"median spacing {med * 1e3:.3f} ms")
    prep = PreparedMotion(m, track=track, gaps=gaps, max_gap_s=max_gap, split=bool(gaps and m.gaps == "split"))
    if not prep.split:
        prep.pieces.append((track, *_fit(job, track, log, doubt)))
        return prep
    pieces = split_at_gaps(track, gaps)
    short = [p for p in pieces if p.t_ns.size < MIN_PIECE_POSES]
    pieces = [p for p in pieces if p.t_ns.size >= MIN_PIECE_POSES]
    if short:
        log.line(f"note: {len(short)} pieces with fewer than {MIN_PIECE_POSES} poses were skipped "
                 f"({sum(p.t_ns.size for p in short)} poses)")
    if not pieces:
        raise InputError(f"no piece between gaps has {MIN_PIECE_POSES} poses or more", path=m.path)
    prep.pieces = [(p, *_fit(job, p, _Log(SynthesisResult(job), None), doubt)) for p in pieces]
    return prep


def _read(m: PosesInput):
    if m.format == "tum":
        from ..io.tum import read_tum
        from ..resources import check_pose_file_fits

        check_pose_file_fits(m.path)  # not the kernel's out-of-memory kill, without a word
        return read_tum(m.path, repeated_stamps=m.repeated_stamps)
    from ..io.euroc import read_euroc_groundtruth

    return read_euroc_groundtruth(m.path, repeated_stamps=m.repeated_stamps)


def _fit(job, track, log, retime_doubt=None):
    """The spline of one piece of a pose file and its fit report (dropped poses with their lines);
    ``retime_doubt``: the summary of a doubtful re-timing of its stamps, told as a warning."""
    from ..spline.fit import fit

    sp = job.motion.spline
    try:
        spl, rep = fit(track, **sp.fit_kwargs(), progress=track.t_ns.size > 100_000, return_report=True)
    except InputError as exc:  # the fit's refusals (a turn of 90 deg or more between poses) name the file
        if exc.path is not None or job.motion.path is None:
            raise
        at = getattr(exc, "pose_index", None)  # and the line of the pose they name
        line = None if at is None else int(track.line_numbers[at])
        raise InputError(exc.problem, path=job.motion.path, line=line) from None
    if rep.knot_choice is not None and rep.knot_choice["rotation"].get("estimated"):
        why = "the file carries IMU biases" if sp.rotation_source == "auto" else "as told"
        log.line(f"rotation      an estimator's output ({why}): its detail is kept as motion")
    elif rep.knot_choice is not None and "read_as_noise" in rep.knot_choice["rotation"]:
        first = rep.knot_choice["rotation"]["read_as_noise"]
        log.line(f"rotation      its finest detail read as motion, as the positions' is (read as noise: "
                 f"{1e3 * first['knot_spacing_s']:.3g} ms knots); --rotation-source measurement keeps that")
    trim = sp.trim_s(rep)
    if trim > 0.0 and rep.knot_choice is not None:  # trimmed ends are not in the record: nothing to warn
        zone = max(c["end_zone_s"] for c in (rep.knot_choice["rotation"], rep.knot_choice["position"]))
        if trim >= 0.99 * zone:
            rep.warnings = [w for w in rep.warnings if w.code != "ends_less_accurate"]
    if retime_doubt is not None:
        from ..spline.report import FitWarning

        rep.warnings.append(FitWarning("stamps_retime_doubtful", retime_doubt))
    for w in fit_warnings(rep):  # also in report.json and in the fit summary
        log.note(f"warning: {w['message']}")
    if rep.dropped_poses:
        lines = getattr(track, "line_numbers", None)
        where = [int(lines[i]) for i in rep.dropped_poses] if lines is not None else rep.dropped_poses
        rep.dropped_poses = [{"index": int(i), "line": int(w), "t_ns": int(track.t_ns[i])}
                             for i, w in zip(rep.dropped_poses, where)]
        log.line(f"outliers      {len(where)} poses dropped (lines {', '.join(map(str, where[:8]))}"
                 f"{', ...' if len(where) > 8 else ''}); --keep-outliers keeps them")
    return spl, rep


def _one(job, piece, out_dir, gaps, max_gap, write, result, log):
    """Stamps, synthesis and output of one fitted piece ``(track, spline, fit_report)`` (``log`` None: quiet)."""
    quiet = log is None
    log = log or _Log(result, None)
    track, spl, rep = piece
    result.source, result.fit_report = spl, rep
    seed = _seed(job)
    sp = job.motion.spline
    trim = sp.trim_s(rep)
    trim_ns = int(round(trim * 1e9))
    if trim > 0.0 and job.imu.timestamps is None:  # the first sample on the untrimmed record's grid
        trim_ns = int(round(np.ceil(trim * job.imu.rate_hz - 1e-9) * 1e9 / job.imu.rate_hz))
    first, last = int(track.t_ns[0]) + trim_ns, int(track.t_ns[-1]) - int(round(trim * 1e9))
    if last <= first:
        raise sp._err("trim_ends_s", f"= {trim:.6g} s at each end leaves nothing of the "
                                     f"{(track.t_ns[-1] - track.t_ns[0]) / 1e9:.6g} s of poses")
    t_ns = _stamps(job, first, last, log, seed, write)
    t_s = (track.t_ns - int(track.t_ns[0])).astype(np.float64) / 1e9
    fit_data = _fit_residuals(spl, t_s, track) if (write and job.output.plot) else None
    report = poses_report(job, track, rep, gaps, max_gap)
    report["spline"]["trimmed_ends_s"] = trim
    _vibration_warnings(job, t_ns, report, log)
    _synthesize(job, spl, t_ns, seed, out_dir, report, write, result, force=job.output.force if not quiet else False,
                fit_data=fit_data, window=(first, last) if trim > 0.0 else None)
    if not quiet:
        for text in fit_lines(rep, gaps, max_gap):
            log.line(text)
        if trim > 0.0:
            why = "auto: the fit's end zones" if sp.trim_ends_s == "auto" else "as asked"
            log.line(f"trimmed       {trim:.3f} s at each end of the poses left out of the record ({why})")
        log.line(imu_line(getattr(t_ns, "stamp_ns", t_ns), job, seed, detailed=True))
        _camera_line(result, log)
    return result


def _camera_line(result, log):
    if result.observations is not None:
        from .cameras import camera_line

        log.line(camera_line(result.report))


def _fit_residuals(spl, t_s, track):
    from .. import lie

    p_fit, q_fit = spl.pose(t_s)
    ang = lie.so3_log(np.matmul(np.swapaxes(lie.quat_xyzw_to_matrix(q_fit), 1, 2),
                                lie.quat_xyzw_to_matrix(track.quat_xyzw)))
    return t_s, track.positions - p_fit, ang


__all__ = ["SynthesisResult", "PreparedMotion", "prepare_motion", "run_job",
           "synthesize_poses", "synthesize_scene", "synthesize_to_memory",
           "MIN_PIECE_POSES"]
