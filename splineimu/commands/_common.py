"""Flags of the synthesis commands (from-tum, from-euroc, scene) and their one options builder.

Every flag here stands for one field of :mod:`splineimu.api.options` (the table
:data:`~splineimu.api.options.FLAGS`); flags not given stay ``None`` so that the options'
own defaults apply, exactly as for a scene file.
"""

from __future__ import annotations

import argparse
import sys


def add_output_args(p: argparse.ArgumentParser):
    g = p.add_argument_group("output")
    g.add_argument("-o", "--out", metavar="OUT",
                   help="output folder, a EuRoC dataset: mav0/imu0/, mav0/state_groundtruth_estimate0/, "
                        "groundtruth.tum, imu.yaml, kalibr_imu_chain.yaml, report.json")
    g.add_argument("--force", action="store_true", default=None,
                   help="replace an existing non-empty output folder")
    g.add_argument("--bag", choices=["ros1", "ros2"],
                   help="also write a ROS bag (sensor_msgs/Imu on the --rostopic, geometry_msgs/PoseStamped "
                        "ground truth); ros2: metadata version 8, read by Humble and newer")
    g.add_argument("--bag-version", type=int, choices=[8, 9],
                   help="rosbag2 metadata version of --bag ros2 (default 8; 9 for Jazzy and newer only)")
    g.add_argument("--plot", action="store_true", default=None,
                   help="also write PNG plots of the IMU signals (and fit residuals)")


def add_imu_args(p: argparse.ArgumentParser):
    g = p.add_argument_group("IMU")
    g.add_argument("--rate", type=float, metavar="HZ", help="IMU sample rate (default 200)")
    g.add_argument("--timestamps", metavar="FILE",
                   help="synthesize at exactly these stamps (first column, ns or decimal seconds; "
                        "e.g. a real imu0/data.csv); stamps outside the motion's span are dropped")
    g.add_argument("--imu", metavar="IMU.yaml",
                   help="sensor model: Kalibr imu.yaml (plus optional extra keys), a preset name "
                        "(e.g. adis16448) or an inline YAML mapping '{gyroscope_noise_density: 0.01, ...}'; "
                        "without it the output is noise-free")
    g.add_argument("--seed", type=int, help="seed of the sensor model's random streams")
    g.add_argument("--extrinsic", metavar="FILE",
                   help="YAML with body_T_sensor (T_BS 4x4, or translation + quat_xyzw), or that mapping inline")
    g.add_argument("--sampling", choices=["point", "mean"],
                   help="point: value at the stamp (default); mean: average over [previous stamp, stamp], "
                        "as an IMU's anti-alias / integrating front end gives")
    g.add_argument("--increments", action="store_true", default=None,
                   help="also write mav0/imu0/increments.csv: delta-angle and delta-velocity per interval")
    g.add_argument("--gravity", type=float, nargs=3, metavar=("GX", "GY", "GZ"),
                   help="world gravity vector [m/s^2] (default 0 0 -9.81)")
    g.add_argument("--rostopic", metavar="TOPIC",
                   help="the IMU's ROS topic in imu.yaml, kalibr_imu_chain.yaml and bags (default /imu0)")
    g = p.add_argument_group("sensor timing and vibration (off by default; ground truth stays on true time)")
    g.add_argument("--time-offset", type=float, metavar="S", help="the IMU clock reads true time + S")
    g.add_argument("--clock-drift-ppm", type=float, metavar="PPM",
                   help="the IMU clock runs fast by PPM parts per million (negative: slow)")
    g.add_argument("--stamp-noise", type=float, metavar="S", help="white noise (std, s) on the written stamps")
    g.add_argument("--drop-probability", type=float, metavar="P", help="each sample is lost with probability P")
    g.add_argument("--drop-burst", type=float, metavar="S", help="losses come in bursts of mean length S")
    g.add_argument("--vibration", metavar="FILE.yaml",
                   help="vibration added before the sensor model: a YAML file or inline mapping "
                        "'{accel: [{freq_hz: 37, amplitude: [0.5, 0, 0]}]}' (also band_hz + psd); "
                        "its contribution is written to mav0/imu0/vibration.csv")


def add_pose_args(p: argparse.ArgumentParser, fmt_help: str):
    p.add_argument("poses", metavar="POSES", help=fmt_help)
    add_imu_args(p)
    g = p.add_argument_group("spline")
    g.add_argument("--spline", choices=["split", "se3"],
                   help="split: R3 x SO3 (default, decoupled); se3: Lovegrove et al.'s cumulative SE3")
    g.add_argument("--order", metavar="K",
                   help="spline order 3 .. 8 (4 is cubic), or auto (default: the best predicted of 4, 5, 6); "
                        "of the rotation, and of the position unless --position-order is given")
    g.add_argument("--knot-spacing", metavar="S",
                   help="knot spacing in seconds, or auto (default: minimizes the predicted IMU error); of the "
                        "rotation, and of the position unless --position-knot-spacing is given")
    g.add_argument("--position-order", metavar="K", help="the position's own spline order (split spline), or auto")
    g.add_argument("--position-knot-spacing", metavar="S",
                   help="the position's own knot spacing in seconds (split spline), or auto; e.g. "
                        "--position-knot-spacing 0.02 with the rotation's still chosen")
    g.add_argument("--smoothness", type=float, metavar="MU",
                   help="relative weight of the smoothness penalty (default 1e-10; gaps get 1e-3)")
    g.add_argument("--rotation-source", choices=["auto", "estimate", "measurement"],
                   help="the rotations are an estimator's output that fused an IMU (estimate: their detail is "
                        "the vehicle's motion and is kept) or measurements (their detail may be noise); auto "
                        "(default): estimate when the file carries IMU biases (EuRoC, vicon2gt), else "
                        "measurements whose finest detail is kept where the positions' is motion")
    g.add_argument("--trim-ends", metavar="S",
                   help="leave S seconds at each end of the poses out of the IMU record, or auto: the fit's "
                        "end zones (k knot spacings), which see one-sided data (default 0)")
    g = p.add_argument_group("gaps")
    g.add_argument("--max-gap", type=float, metavar="S",
                   help="longest gap bridged silently (default 0.5 s, or 5x the median spacing if larger)")
    g.add_argument("--gaps", choices=["error", "bridge", "split"],
                   help="longer gaps: stop (default), fit through them, or write one folder per piece")
    g = p.add_argument_group("input hygiene")
    g.add_argument("--repeated-stamps", choices=["error", "first"],
                   help="a stamp repeated with a different pose: stop (default) or keep the first row")
    g.add_argument("--retime-stamps", action="store_true", default=None,
                   help="the stamps are receive times (delivery jitter, stalls, dropped frames): put the poses "
                        "back on the capture clock fitted to them before the fit")
    g.add_argument("--keep-outliers", action="store_true", default=None,
                   help="do not drop poses whose fit residual is beyond 8 robust sigmas")
    add_output_args(p)


def _given(args, *fields, group="") -> dict:
    """``{field: value}`` of the option ``fields`` whose flags were given; a field's flag is
    ``FLAGS[group + field]`` (``knot_spacing_s``: ``--knot-spacing``, parsed as ``knot_spacing``)."""
    from ..api.argv import FLAGS

    dest = {f: FLAGS[group + f].lstrip("-").replace("-", "_") for f in fields}
    return {f: getattr(args, d) for f, d in dest.items() if getattr(args, d, None) is not None}


def _params(items) -> dict:
    from ..errors import ConfigError

    params = {}
    for it in items or ():
        if "=" not in it:
            raise ConfigError(f"--param expects KEY=VALUE, got {it!r}", option="--param")
        k, v = it.split("=", 1)
        params[k.strip()] = v.strip()
    return params


def options_from_args(args, motion: str):
    """The :class:`~splineimu.api.options.SynthesisJob` of parsed flags.

    ``motion`` is ``"tum"``, ``"euroc"`` (a pose file of that format) or ``"scene"``. Errors
    name the flag.
    """
    from pathlib import Path

    from ..api.argv import SPLINE_FIELDS
    from ..api.options import FlagOrigin, ImuOptions, OutputOptions, PosesInput, SceneInput, SplineOptions, SynthesisJob
    from ..errors import ConfigError

    o = FlagOrigin()
    if args.timestamps is not None and args.rate is not None:  # the rate was ignored in silence
        raise ConfigError("--rate and --timestamps are both given: the samples are at the file's stamps; drop --rate",
                          option="--rate")
    if motion == "scene":
        source = SceneInput(args.name, **_given(args, "duration_s", "t0_ns"), params=_params(args.param), origin=o)
    else:
        spline = SplineOptions(**_given(args, *SPLINE_FIELDS), origin=o)
        source = PosesInput(args.poses, motion, **_given(args, "repeated_stamps", "retime_stamps", "max_gap_s", "gaps"),
                            spline=spline, origin=o)
        if args.out is None:
            args.out = Path(args.poses).stem + "_imu"
    imu = ImuOptions(**_given(args, "rate_hz", "timestamps", "model", "extrinsic", "gravity", "sampling", "increments",
                              "seed", "vibration", "rostopic"),
                     timing=_given(args, "time_offset_s", "clock_drift_ppm", "stamp_noise_s", "drop_probability",
                                   "drop_burst_s", group="timing.") or None, origin=o)
    output = OutputOptions(**_given(args, "dir", "force", "bag", "plot", "tum", "bag_version"), origin=o)
    return SynthesisJob(source, imu, output)


def echo(text: str, note: bool = False):
    print(text, file=sys.stderr if note else sys.stdout, flush=True)


def run_synthesis(job) -> int:
    """Run a job, printing its summary as it goes."""
    from ..api.synthesis import run_job

    run_job(job, echo=echo)
    return 0


def say(msg=""):
    print(msg, flush=True)


def stderr(msg):
    print(msg, file=sys.stderr, flush=True)
