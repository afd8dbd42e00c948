"""The TUM reader refuses, by name, the files a user hands to from-tum by mistake.

A EuRoC ground-truth csv (ns stamps, ``q w x y z``) was read as TUM lines: its first 8
columns taken as ``t x y z qx qy qz qw``, the ns stamps as seconds, the rest ignored with a
notice. Stamps counted from 0 stayed small enough to pass every check; so did integer-ns TUM
stamps counted from 0, a KITTI 12-column pose file (r11 as the stamp) and a header naming the
quaternion ``qw qx qy qz``. Each is now refused before any line is read as a pose; a header
line in TUM order (without ``#``) is read.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import require_shared

from splineimu import cli
from splineimu.errors import InputError
from splineimu.io.tum import read_tum

NOT_TUM = "not a TUM trajectory (timestamp tx ty tz qx qy qz qw): the file looks like "
EUROC_GT = NOT_TUM + "a EuRoC ground-truth csv (ns, p xyz, q wxyz, ...): use `splineimu from-euroc`"
EUROC_IMU = NOT_TUM + ("a EuRoC IMU csv (ns, gyro xyz, accel xyz): it is IMU data, not poses: give it to integrate, "
                       "allan or calibrate, or as --timestamps")
CONVERT = "TUM stamps are decimal seconds: convert the column"


def _poses(n=200):
    """A 1 s turn at 200 Hz: stamps [ns from 0], positions, quaternions (x, y, z, w)."""
    t_ns = np.arange(n, dtype=np.int64) * 5_000_000
    a = 0.5 * np.arange(n) / n
    pos = np.stack([np.cos(a), np.sin(a), np.ones(n)], axis=1)
    quat = np.stack([np.zeros(n), np.zeros(n), np.sin(a / 2), np.cos(a / 2)], axis=1)
    return t_ns, pos, quat


def _euroc_gt_rows(t_ns, pos, quat):
    """17-column EuRoC ground-truth rows: ns, p, q (w x y z), v, b_w, b_a."""
    return [f"{t},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f},{q[3]:.9f},{q[0]:.9f},{q[1]:.9f},{q[2]:.9f}"
            + ",0.1,0,0,0.001,0.002,0.003,0.01,0.02,0.03" for t, p, q in zip(t_ns.tolist(), pos, quat)]


def _refused(path, expected, line=None):
    with pytest.raises(InputError) as info:
        read_tum(path)
    assert str(info.value) == f"{path}{'' if line is None else f':{line}'}: {expected}"


def _cli_error(capsys, argv):
    assert cli.main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err.strip()


# ------------------------------------------------------------------ EuRoC csv files


def test_euroc_groundtruth_counted_from_zero_is_refused(tmp_path):
    t_ns, pos, quat = _poses()
    header = ("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
              "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
              "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
              "b_a_RS_S_z [m s^-2]")
    rows = _euroc_gt_rows(t_ns, pos, quat)
    with_header, bare, eight = tmp_path / "gt.csv", tmp_path / "bare.csv", tmp_path / "gt8.csv"
    with_header.write_text(header + "\n" + "\n".join(rows) + "\n")
    bare.write_text("\n".join(rows) + "\n")
    eight.write_text("\n".join(",".join(r.split(",")[:8]) for r in rows) + "\n")
    for p in (with_header, bare, eight):  # all three were read: 200 poses over 9.95e8 "s", q taken as x y z w
        _refused(p, EUROC_GT)


def test_comma_tum_with_integer_seconds_is_still_read(tmp_path):
    p = tmp_path / "p.csv"
    p.write_text("0,0,0,1,0,0,0,1\n1,1,0,1,0,0,0,1\n2,2,0,1,0,0,0,1\n")
    tr = read_tum(p)
    assert tr.t_ns.tolist() == [0, 10**9, 2 * 10**9] and tr.positions[:, 0].tolist() == [0, 1, 2]


@pytest.mark.parametrize("name", ["groundtruth.csv", "groundtruth_vicon2gt_20hz.csv"])
def test_real_euroc_groundtruth_is_refused_by_from_tum(tmp_path, capsys, name):
    gt = require_shared("euroc_V1_02_medium", name)
    _refused(gt, EUROC_GT)
    out = tmp_path / "out"
    err = _cli_error(capsys, ["from-tum", str(gt), "-o", str(out)])
    assert err == f"splineimu from-tum: error: {gt}: {EUROC_GT}"
    assert not out.exists()


def test_euroc_imu_csv_is_refused_as_imu_data(tmp_path):
    imu = require_shared("euroc_V1_02_medium", "imu0_first40s.csv")
    _refused(imu, EUROC_IMU)
    bare = tmp_path / "imu.csv"  # no header, stamps from 0
    bare.write_text("".join(f"{i * 5_000_000},0.001,0,0,0,0,9.81\n" for i in range(50)))
    _refused(bare, EUROC_IMU)


# ------------------------------------------------------------------ stamps in another unit


def _tum_text(stamps, pos, quat):
    return "".join(f"{s} {p[0]:.6f} {p[1]:.6f} {p[2]:.6f} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n"
                   for s, p, q in zip(stamps, pos, quat))


@pytest.mark.parametrize("scale, step, every, unit", [
    (1, "5000000", "57.9 days", "nanoseconds (200 Hz)"),
    (1000, "5000", "1.39 hours", "microseconds (200 Hz)"),
])
def test_integer_stamps_counted_from_zero_in_ns_or_us_are_refused(tmp_path, scale, step, every, unit):
    t_ns, pos, quat = _poses()
    p = tmp_path / "p.tum"
    p.write_text("# timestamp tx ty tz qx qy qz qw\n" + _tum_text((t_ns // scale).tolist(), pos, quat))
    # was read as one pose every 58 days (1.4 h): nothing said
    _refused(p, f"integer stamps step by {step} (read as seconds, one pose every {every}): they look like {unit}; "
             + CONVERT, line=2)


def test_integer_ns_stamps_since_1970_are_refused(tmp_path, capsys):
    t_ns, pos, quat = _poses()
    p = tmp_path / "p.tum"
    p.write_text(_tum_text((t_ns + 1403715273262142976).tolist(), pos, quat))
    _refused(p, "stamp 1403715273262142976 read as seconds is after the year 5000: it looks like nanoseconds; "
             + CONVERT, line=1)
    err = _cli_error(capsys, ["from-tum", str(p), "-o", str(tmp_path / "out")])
    assert err.startswith(f"splineimu from-tum: error: {p}:1: stamp 1403715273262142976 read as seconds")


def test_integer_seconds_and_decimal_stamps_are_read(tmp_path):
    _, pos, quat = _poses(5)
    p = tmp_path / "p.tum"
    p.write_text(_tum_text(["0", "1", "2", "3", "4"], pos, quat))
    assert read_tum(p).t_ns.tolist() == [k * 10**9 for k in range(5)]
    p.write_text(_tum_text(["0.0", "5000000.0", "10000000.0", "15000000.0", "20000000.0"], pos, quat))
    assert read_tum(p).t_ns[1] == 5_000_000 * 10**9  # a decimal point says seconds: read as written


def test_decimal_milliseconds_counted_from_zero_get_a_notice(tmp_path):
    """A 3 s recording at 200 Hz stamped in milliseconds from 0 ("0.000 5.000 ..."): read as seconds
    (a decimal point says so), it spans 50 minutes and from-tum synthesized IMU over all of it
    with nothing said; now the reader's notice says what the stamps are in milliseconds."""
    t_ns, pos, quat = _poses(600)
    p = tmp_path / "p.tum"
    p.write_text(_tum_text([f"{t / 1e6:.3f}" for t in t_ns.tolist()], pos, quat))
    tr = read_tum(p)
    assert tr.t_ns[1] == 5 * 10**9  # read as written
    assert tr.notices == ["stamps counted from 0 step by 5 s (0.2 Hz; the poses span 49.9 min): if they are "
                          "milliseconds, the poses are 200 Hz over 3 s; TUM stamps are decimal seconds: divide the "
                          "column by 1000"]
    # seconds from 0 at 200 Hz, and the same 5 s steps since 1970 (sparse poses with an epoch): nothing
    p.write_text(_tum_text([f"{t / 1e9:.3f}" for t in t_ns.tolist()], pos, quat))
    assert read_tum(p).notices == []
    p.write_text(_tum_text([f"{1.7e9 + t / 1e6:.3f}" for t in t_ns.tolist()], pos, quat))
    assert read_tum(p).notices == []


# ------------------------------------------------------------------ KITTI


def _kitti(n=100):
    """A car turning from yaw 178 deg to 2 deg: r11 = cos(yaw) grows, so as stamps it is sorted."""
    rows = []
    for yaw in np.linspace(math.radians(178), math.radians(2), n):
        c, s = math.cos(yaw), math.sin(yaw)
        m = [[c, -s, 0, 10 * c], [s, c, 0, 10 * s], [0, 0, 1, 0]]
        rows.append(" ".join(f"{v:.6e}" for r in m for v in r))
    return "\n".join(rows) + "\n"


def test_kitti_pose_file_is_refused(tmp_path):
    p = tmp_path / "00.txt"
    p.write_text(_kitti())  # was read: 100 poses at "t" = -0.9994 .. 0.9994 s, positions (-sin, 0, 10 cos)
    _refused(p, NOT_TUM + "a KITTI pose file (12 numbers a line: the 3x4 matrix [R | t], no timestamps): write TUM "
             "lines (timestamp tx ty tz qx qy qz qw) with the frames' times (KITTI's times.txt)")


def test_tum_with_four_extra_columns_is_not_kitti(tmp_path):
    t_ns, pos, quat = _poses(5)
    rows = _tum_text([f"{t / 1e9 + 1.7e9:.9f}" for t in t_ns.tolist()], pos, quat).splitlines()
    p = tmp_path / "p.tum"
    p.write_text("".join(r + " 0.1 0.2 0.3 0.4\n" for r in rows))
    tr = read_tum(p)
    assert len(tr) == 5 and tr.notices == ["ignored columns 9-12 on every line"]


# ------------------------------------------------------------------ headers


def test_header_line_in_tum_order_is_read(tmp_path):
    t_ns, pos, quat = _poses(5)
    body = _tum_text([f"{1.7e9 + t / 1e9:.9f}" for t in t_ns.tolist()], pos, quat)
    plain, headed = tmp_path / "plain.tum", tmp_path / "headed.tum"
    plain.write_text(body)
    headed.write_text("timestamp tx ty tz qx qy qz qw\n" + body)  # was: ':1: column 2 (tx) is not a number'
    a, b = read_tum(plain), read_tum(headed)
    assert b.t_ns.tolist() == a.t_ns.tolist() and np.array_equal(b.positions, a.positions)
    assert np.array_equal(b.quat_xyzw, a.quat_xyzw) and b.line_numbers.tolist() == [2, 3, 4, 5, 6]
    assert b.notices == []


@pytest.mark.parametrize("header, sep", [("# timestamp x y z qw qx qy qz", " "),
                                         ("#t,x,y,z,q_w,q_x,q_y,q_z", ","),
                                         ("timestamp,tx,ty,tz,qw,qx,qy,qz", ",")])
def test_header_naming_w_first_is_refused(tmp_path, header, sep):
    t_ns, pos, quat = _poses(5)
    rows = [sep.join([f"{1.7e9 + t / 1e9:.9f}", *(f"{v:.6f}" for v in p), *(f"{v:.9f}" for v in q[[3, 0, 1, 2]])])
            for t, p, q in zip(t_ns.tolist(), pos, quat)]
    p = tmp_path / "p.tum"
    p.write_text("# ground truth\n" + header + "\n" + "\n".join(rows) + "\n")
    # the commented ones were read with q_w taken as qx: a 180 deg rotation about x for a yaw of 0-1.4 deg
    _refused(p, "the header names the quaternion w x y z; TUM lines are timestamp tx ty tz qx qy qz qw (w last): "
             "reorder the columns", line=2)


@pytest.mark.parametrize("parts", [("tum_vi", "room1_512_16_groundtruth.tum"), ("openvins_sim", "udel_gore.txt"),
                                   ("tum_rgbd", "freiburg1_xyz-groundtruth.txt"), ("misc", "georeferenced.tum"),
                                   ("openvins_sim", "tum_corridor1_512_16_okvis.txt")])
def test_real_tum_files_pass_the_layout_check(parts):
    from splineimu.io.sniff import check_tum_layout, guess_format

    p = require_shared(*parts)
    assert check_tum_layout(p) is False and guess_format(p) == "tum"
