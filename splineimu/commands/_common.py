"""Options and steps shared by the synthesis commands (scene, from-tum, from-euroc, run)."""

from __future__ import annotations

import argparse
import sys
import time

from ..errors import ConfigError


def add_output_args(p: argparse.ArgumentParser, required=False):
    g = p.add_argument_group("output")
    g.add_argument("-o", "--out", metavar="OUT", required=required,
                   help="output folder (EuRoC-like layout: imu0/, state_groundtruth_estimate0/, "
                        "groundtruth.tum, imu.yaml, report.json)")
    g.add_argument("--force", action="store_true", help="replace an existing non-empty output folder")
    g.add_argument("--bag", choices=["ros1", "ros2"],
                   help="also write a ROS bag (sensor_msgs/Imu on /imu0, geometry_msgs/PoseStamped ground truth)")
    g.add_argument("--plot", action="store_true", help="also write PNG plots of the IMU signals (and fit residuals)")


def add_imu_args(p: argparse.ArgumentParser, rate_default=200.0):
    g = p.add_argument_group("IMU")
    g.add_argument("--rate", type=float, default=rate_default, metavar="HZ",
                   help=f"IMU sample rate (default {rate_default:g})")
    g.add_argument("--imu", metavar="IMU.yaml",
                   help="sensor model: Kalibr imu.yaml (plus optional extra keys) or a preset name "
                        "(e.g. adis16448); without it the output is noise-free")
    g.add_argument("--seed", type=int, default=None, help="seed of the sensor model's random streams")
    g.add_argument("--extrinsic", metavar="FILE", help="YAML with body_T_sensor (T_BS 4x4, or translation + quat_xyzw)")
    g.add_argument("--sampling", choices=["point", "mean"], default="point",
                   help="point: value at the stamp (default); mean: average over [previous stamp, stamp], "
                        "as an IMU's anti-alias / integrating front end gives")
    g.add_argument("--increments", action="store_true",
                   help="also write imu0/increments.csv: delta-angle and delta-velocity per interval")
    g.add_argument("--gravity", type=float, nargs=3, default=(0.0, 0.0, -9.81), metavar=("GX", "GY", "GZ"),
                   help="world gravity vector [m/s^2] (default 0 0 -9.81)")


def load_extrinsic(path):
    if not path:
        return None
    from ..imu.ideal import Extrinsic

    return Extrinsic.from_file(path)


def seed_or_default(seed):
    """A given seed, or a fresh one that is reported so that the run can be repeated."""
    if seed is not None:
        if seed < 0:
            raise ConfigError(f"--seed must be non-negative, got {seed}")
        return int(seed)
    import numpy as np

    return int(np.random.SeedSequence().entropy % (2**63))


def say(msg=""):
    print(msg, flush=True)


def summary(out_report: dict, out_dir, t0_wall: float):
    imu = out_report["imu"]
    span_s = (imu["last_ns"] - imu["first_ns"]) / 1e9 if imu["samples"] else 0.0
    say(f"imu           {imu['samples']} samples, {span_s:.3f} s from {imu['first_ns']} ns "
        f"({imu['noise']}{'' if imu['seed'] is None else ', seed ' + str(imu['seed'])})")
    say(f"written       {out_dir}  ({time.perf_counter() - t0_wall:.2f} s)")


def fail_fast_output(args):
    from ..io.output import check_output_dir

    if args.out:
        check_output_dir(args.out, args.force)


def stderr(msg):
    print(msg, file=sys.stderr, flush=True)
