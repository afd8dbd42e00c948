"""``splineimu compare``: APE / RPE of a TUM trajectory against a reference, with evo."""

from __future__ import annotations

import sys

NAME = "compare"
HELP = "APE / RPE of an estimated TUM trajectory against a reference (needs evo)"
ORDER = 60
DESCRIPTION = """\
Absolute and relative pose error of EST against REF (both TUM files), computed with evo
(optional extra: pip install 'splineimu[evo]'). The statistics are evo's and are printed as
evo_ape / evo_rpe print them; the same options give the same numbers as

  evo_ape tum REF EST [-r trans_part|rot_part|full] [-a [-s] | --align_origin]
  evo_rpe tum REF EST ... -d DELTA -u f|m|d|r

Note the argument order: splineimu takes EST first, evo takes REF first.
Poses are associated by nearest time stamp (--t-max-diff, --t-offset added to EST's stamps).
--delta-unit s turns seconds into a whole number of frames (evenly spaced poses only).
"""

#: compare_files' arguments -> flags, for its errors.
FLAGS = {"t_offset": "--t-offset", "t_max_diff": "--t-max-diff", "delta": "--delta", "delta_unit": "--delta-unit",
         "metric": "--metric", "pose_relation": "--pose-relation", "align": "--align", "all_pairs": "--all-pairs"}


def add_arguments(parser) -> None:
    from ..metrics import ALIGN_MODES, DELTA_UNITS, POSE_RELATIONS

    parser.add_argument("est", metavar="EST", help="estimated trajectory (TUM)")
    parser.add_argument("ref", metavar="REF", help="reference trajectory (TUM)")
    parser.add_argument("--metric", choices=("ape", "rpe", "both"), default="ape",
                        help="which error (default: ape)")
    parser.add_argument("--pose-relation", choices=tuple(POSE_RELATIONS), default="trans",
                        help="trans = evo's trans_part (m), rot = rot_part, full = full "
                             "transformation, angle_deg / angle_rad, point_distance (default: trans)")
    parser.add_argument("--align", choices=ALIGN_MODES, default="none",
                        help="alignment of EST to REF: none, se3 (evo -a), sim3 (evo -a -s), "
                             "origin (evo --align_origin) (default: none)")
    parser.add_argument("--delta", type=float, default=1.0, help="RPE pair spacing (default: 1)")
    parser.add_argument("--delta-unit", choices=tuple(DELTA_UNITS), default="f",
                        help="unit of --delta: f frames, m meters, d degrees, r radians, s seconds "
                             "(default: f)")
    parser.add_argument("--all-pairs", action="store_true",
                        help="RPE over all pairs at that spacing, not only consecutive ones")
    parser.add_argument("--t-max-diff", type=float, default=0.01, metavar="S",
                        help="largest stamp difference for associating poses [s] (default: 0.01)")
    parser.add_argument("--t-offset", type=float, default=0.0, metavar="S",
                        help="constant offset added to EST's stamps [s] (default: 0)")
    parser.add_argument("--plot", metavar="FILE.png", default=None,
                        help="save a plot: trajectories (x-y) and errors over time")
    parser.add_argument("--force", action="store_true", help="replace an existing --plot file")


def run(args) -> int:
    from ..api.compare import compare_files
    from ..io.files import check_output_file
    from ._flags import flag_names

    if args.plot is not None:
        check_output_file(args.plot, args.force, inputs=[args.est, args.ref], option="--plot")

    with flag_names(FLAGS):
        res = compare_files(args.est, args.ref, plot=args.plot, metric=args.metric, pose_relation=args.pose_relation,
                            align=args.align, delta=args.delta, delta_unit=args.delta_unit, all_pairs=args.all_pairs,
                            t_max_diff=args.t_max_diff, t_offset=args.t_offset)
    for note in res.notes:
        print(f"note: {note}", file=sys.stderr)
    for r in res.results:
        if r.delta_frames is not None:
            print(f"(delta {args.delta:g} s = {r.delta_frames} frames)")
        print(r.pretty_str())
    if res.plot_path is not None:
        print(f"plot saved to {res.plot_path}")
    return 0
