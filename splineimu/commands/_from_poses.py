"""The shared body of ``from-tum`` and ``from-euroc``: read, check gaps, fit, synthesize, write."""

from __future__ import annotations

import time

import numpy as np

#: --gaps split: pieces with fewer poses are skipped (a spline of order 6 needs a few knots of data)
MIN_PIECE_POSES = 12


def add_pose_args(p, fmt_help):
    from ._common import add_imu_args, add_output_args

    p.add_argument("poses", metavar="POSES", help=fmt_help)
    add_imu_args(p)
    p.add_argument("--timestamps", metavar="FILE",
                   help="synthesize at exactly these stamps (first column, ns or decimal seconds; "
                        "e.g. a real imu0/data.csv); stamps outside the pose span are dropped")
    g = p.add_argument_group("spline")
    g.add_argument("--spline", choices=["split", "se3"], default="split",
                   help="split: R3 x SO3 (default, decoupled); se3: Lovegrove et al.'s cumulative SE3")
    g.add_argument("--order", default="auto", metavar="K",
                   help="spline order 4 (cubic) .. 6, or auto (default: the best predicted of 4, 5, 6)")
    g.add_argument("--knot-spacing", default="auto", metavar="S",
                   help="knot spacing in seconds, or auto (default: minimizes the predicted IMU error)")
    g.add_argument("--smoothness", type=float, default=None, metavar="MU",
                   help="relative weight of the smoothness penalty (default 1e-10; gaps get 1e-3)")
    g = p.add_argument_group("gaps")
    g.add_argument("--max-gap", type=float, default=None, metavar="S",
                   help="longest gap bridged silently (default 0.5 s, or 5x the median spacing if larger)")
    g.add_argument("--gaps", choices=["error", "bridge", "split"], default="error",
                   help="longer gaps: stop (default), fit through them, or write one folder per piece")
    g = p.add_argument_group("input hygiene")
    g.add_argument("--repeated-stamps", choices=["error", "first"], default="error",
                   help="a stamp repeated with a different pose: stop (default) or keep the first row")
    g.add_argument("--keep-outliers", action="store_true",
                   help="do not drop poses whose fit residual is beyond 8 robust sigmas")
    add_output_args(p)


def _parse_order(v):
    from ..errors import ConfigError

    if str(v).lower() == "auto":
        return "auto"
    try:
        k = int(v)
    except ValueError:
        raise ConfigError(f"--order must be an integer 2..8 or auto, got {v!r}") from None
    if not 2 <= k <= 8:
        raise ConfigError(f"--order must be between 2 and 8, got {k}")
    return k


def _parse_knot_spacing(v):
    from ..errors import ConfigError

    if str(v).lower() == "auto":
        return "auto"
    try:
        x = float(v)
    except ValueError:
        raise ConfigError(f"--knot-spacing must be a number of seconds or auto, got {v!r}") from None
    if not (np.isfinite(x) and x > 0):
        raise ConfigError(f"--knot-spacing must be positive, got {v!r}")
    return x


def run_from_poses(args, read) -> int:
    from ..errors import InputError
    from ..io.output import OutputFolder
    from ..io.poses import find_gaps, split_at_gaps
    from ._common import fail_fast_output, say, stderr

    t_wall = time.perf_counter()
    if not args.out:
        from pathlib import Path

        args.out = Path(args.poses).stem + "_imu"
    fail_fast_output(args)
    order = _parse_order(args.order)
    knot = _parse_knot_spacing(args.knot_spacing)
    track = read(args.poses, repeated_stamps=args.repeated_stamps)
    for note in track.notices:
        stderr(f"note: {args.poses}: {note}")
    med = float(np.median(np.diff(track.t_ns))) / 1e9
    max_gap = args.max_gap if args.max_gap is not None else max(0.5, 5.0 * med)
    gaps = find_gaps(track.t_ns, max_gap, getattr(track, "line_numbers", None))
    if gaps and args.gaps == "error":
        g = gaps[0]
        more = f" (and {len(gaps) - 1} more)" if len(gaps) > 1 else ""
        raise InputError(
            f"gap of {g.duration_s:.3f} s before this pose{more} exceeds --max-gap {max_gap:g} s; "
            "use --gaps bridge to fit through it or --gaps split to write one folder per piece",
            path=args.poses, line=g.line)
    say(f"input         {args.poses}: {track.t_ns.size} poses, {(track.t_ns[-1] - track.t_ns[0]) / 1e9:.3f} s, "
        f"median spacing {med * 1e3:.3f} ms")
    if gaps and args.gaps == "split":
        pieces = split_at_gaps(track, gaps)
        short = [p for p in pieces if p.t_ns.size < MIN_PIECE_POSES]
        pieces = [p for p in pieces if p.t_ns.size >= MIN_PIECE_POSES]
        if short:
            say(f"note: {len(short)} pieces with fewer than {MIN_PIECE_POSES} poses were skipped "
                f"({sum(p.t_ns.size for p in short)} poses)")
        if not pieces:
            raise InputError(f"no piece between gaps has {MIN_PIECE_POSES} poses or more", path=args.poses)
        reports = []
        with OutputFolder(args.out, force=args.force) as tmp:
            for i, piece in enumerate(pieces):
                sub = tmp / f"part_{i:03d}"
                say(f"piece {i}       {piece.t_ns.size} poses from {piece.t_ns[0]} ns -> {sub.name}")
                reports.append(_one(args, piece, sub, order, knot, [], max_gap, quiet=True))
        say(f"written       {args.out} ({len(pieces)} pieces, {time.perf_counter() - t_wall:.2f} s)")
        return 0
    _one(args, track, args.out, order, knot, gaps, max_gap, force=args.force)
    say(f"written       {args.out}  ({time.perf_counter() - t_wall:.2f} s)")
    return 0


def _one(args, track, out_dir, order, knot, gaps, max_gap, force=False, quiet=False):
    from ..errors import InputError
    from ..pipeline import synthesize_stream, uniform_stamps_ns, write_output
    from ..spline.banded import DEFAULT_SMOOTHNESS
    from ..spline.fit import fit
    from ._common import load_extrinsic, say, seed_or_default

    origin = int(track.t_ns[0])
    t_s = (track.t_ns - origin).astype(np.float64) / 1e9
    n_poses = track.t_ns.size
    spl, rep = fit(t_s, track.positions, track.quat_xyzw, kind=args.spline, order=order, knot_spacing_s=knot,
                   smoothness=DEFAULT_SMOOTHNESS if args.smoothness is None else args.smoothness,
                   origin_ns=origin, reject_outliers=not args.keep_outliers, progress=n_poses > 100_000,
                   return_report=True)
    if rep.dropped_poses:
        lines = getattr(track, "line_numbers", None)
        where = [int(lines[i]) for i in rep.dropped_poses] if lines is not None else rep.dropped_poses
        rep.dropped_poses = [{"index": int(i), "line": int(w), "t_ns": int(track.t_ns[i])}
                             for i, w in zip(rep.dropped_poses, where)]
        say(f"outliers      {len(where)} poses dropped (lines {', '.join(map(str, where[:8]))}"
            f"{', ...' if len(where) > 8 else ''}); --keep-outliers keeps them")
    if args.timestamps:
        from ..io.timestamps import read_timestamps

        stamps = read_timestamps(args.timestamps)
        keep = (stamps >= track.t_ns[0]) & (stamps <= track.t_ns[-1])
        if not keep.any():
            raise InputError("no stamp lies inside the pose span "
                             f"[{track.t_ns[0]}, {track.t_ns[-1]}] ns", path=args.timestamps)
        dropped = int((~keep).sum())
        t_ns = stamps[keep]
        if dropped:
            say(f"note: {dropped} stamps of {args.timestamps} lie outside the pose span and were dropped")
    else:
        t_ns = uniform_stamps_ns(int(track.t_ns[0]), int(track.t_ns[-1]), args.rate)
    seed = seed_or_default(args.seed) if args.imu else args.seed
    syn = synthesize_stream(spl, t_ns, gravity=tuple(args.gravity), extrinsic=load_extrinsic(args.extrinsic),
                            imu_config=args.imu, seed=seed, sampling=args.sampling,
                            with_increments=args.increments)
    report = {
        "source": {"kind": "pose file", "path": str(args.poses), "poses": int(n_poses),
                   "first_ns": int(track.t_ns[0]), "last_ns": int(track.t_ns[-1]), "notices": list(track.notices)},
        "spline": rep.to_dict(),
        "gaps": {"max_gap_s": max_gap, "bridged": [
            {"start_ns": int(g.start_ns), "end_ns": int(g.end_ns), "duration_s": float(g.duration_s),
             "line": g.line} for g in gaps]},
        "rate_hz": None if args.timestamps else args.rate,
        "timestamps_file": args.timestamps,
    }
    fit_data = None
    if args.plot:
        p_fit, q_fit = spl.pose(t_s)
        from .. import lie

        ang = lie.so3_log(np.matmul(np.swapaxes(lie.quat_xyzw_to_matrix(q_fit), 1, 2),
                                    lie.quat_xyzw_to_matrix(track.quat_xyzw)))
        fit_data = (t_s, track.positions - p_fit, ang)
    out_rep = write_output(syn, out_dir, force=force, report=report, bag=args.bag, plot=args.plot,
                           fit_data=fit_data)
    if not quiet:
        say(rep.summary())
        if gaps:
            say(f"gaps          {len(gaps)} longer than {max_gap:g} s bridged (listed in report.json)")
        imu = out_rep["imu"]
        span = (imu["last_ns"] - imu["first_ns"]) / 1e9
        say(f"imu           {imu['samples']} samples over {span:.3f} s [{imu['first_ns']} .. {imu['last_ns']}] ns, "
            f"{imu['noise']}{'' if seed is None else ', seed ' + str(seed)}")
    return out_rep
