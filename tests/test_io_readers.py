"""Readers of pose and timestamp files: TUM, EuRoC, plain stamp columns.

Every malformed input must raise :class:`InputError` whose one-line message starts with
``"<file>:<line>: "`` naming the offending line; every repair leaves one notice. Real
files from ../shared/data are checked against counts established by hand (awk) and
stated in its README.
"""

from __future__ import annotations

from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from conftest import require_shared
from hypothesis import given
from hypothesis import strategies as st

from splineimu.errors import InputError
from splineimu.io.euroc import (
    EUROC_GROUNDTRUTH_HEADER,
    EUROC_IMU_HEADER,
    read_euroc_groundtruth,
    write_euroc_groundtruth,
    write_euroc_imu,
)
from splineimu.io.poses import Gap, PoseTrack, clean_poses, find_gaps, split_at_gaps
from splineimu.io.timestamps import parse_stamps, read_timestamps
from splineimu.io.tum import read_tum, write_tum

ID = "0 0 0 1"  # identity quaternion, TUM order


def write(tmp_path: Path, text: str, name: str = "poses.txt") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def expect_error(fn, path: Path, line: int | None, *fragments):
    """Call fn, expect InputError naming ``path:line:`` and containing the fragments."""
    with pytest.raises(InputError) as ei:
        fn()
    msg = str(ei.value)
    where = f"{path}:{line}: " if line is not None else f"{path}: "
    assert msg.startswith(where), msg
    assert "\n" not in msg
    for f in fragments:
        assert f in msg, msg
    assert ei.value.line == line
    return msg


# ---------------------------------------------------------------------------------------
# exact timestamps


def test_parse_stamps_exact_decimal_text():
    t, n_rounded = parse_stamps([
        "1305031102.175304",      # TUM RGB-D style
        "1305031102.123456789",   # 9 decimals: every digit kept
        "1305031102",             # integer seconds
        "1305031102.",            # trailing point
        "1.706282470098386526e+09",  # evo's georeferenced file
        "0.000000001",
    ])
    assert t.dtype == np.int64
    assert t.tolist() == [
        1305031102175304000,
        1305031102123456789,
        1305031102000000000,
        1305031102000000000,
        1706282470098386526,
        1,
    ]
    assert n_rounded == 0
    # the float round trip this avoids would be wrong by ~100 ns
    assert int(float("1305031102.123456789") * 1e9) != 1305031102123456789


def test_parse_stamps_nanoseconds_beyond_float53():
    t, _ = parse_stamps(["1403715524907143168", "1403715524907143169"], unit="ns")
    assert t.tolist() == [1403715524907143168, 1403715524907143169]
    assert np.diff(t)[0] == 1


def test_parse_stamps_more_than_9_decimals_rounds_half_even():
    t, n = parse_stamps(["0.0000000015", "0.0000000025", "1521753105.031429052352905", "0.5"])
    assert t.tolist() == [2, 2, 1521753105031429052, 500000000]
    assert n == 3


@pytest.mark.parametrize(
    "text, unit, fragment",
    [("abc", "s", "not a number"), ("nan", "s", "not a finite"), ("inf", "s", "not a finite"),
     ("1e30", "s", "out of range"), ("9223372036.854775808", "s", "out of range"),
     ("1.5", "ns", "not an integer number of nanoseconds")],
)
def test_parse_stamps_errors_name_the_line(text, unit, fragment):
    with pytest.raises(InputError) as ei:
        parse_stamps(["1", text], unit=unit, path="f.txt", line_numbers=[7, 9])
    assert str(ei.value).startswith("f.txt:9: ") and fragment in str(ei.value)


@given(
    sec=st.integers(0, 9_223_372_035),
    frac=st.text(alphabet="0123456789", min_size=0, max_size=12),
)
def test_parse_stamps_fast_path_equals_decimal(sec, frac):
    s = f"{sec}.{frac}" if frac else str(sec)
    want = int((Decimal(s) * 10**9).to_integral_value())  # ROUND_HALF_EVEN is Decimal's default
    got, n = parse_stamps([s, "+" + s])  # "+..." always takes the Decimal path
    assert got.tolist() == [want, want]
    assert n == 2 * (len(frac) > 9 and Decimal(s) * 10**9 != want)


# ---------------------------------------------------------------------------------------
# TUM reader


def test_read_tum_comments_blank_lines_and_line_numbers(tmp_path):
    p = write(tmp_path, "# header\n\n1.0 1 2 3 " + ID + "\n   \n# mid comment\n2.5 4 5 6 " + ID + "\n")
    tr = read_tum(p)
    assert tr.t_ns.tolist() == [1_000_000_000, 2_500_000_000]
    assert tr.line_numbers.tolist() == [3, 6]
    assert tr.positions.tolist() == [[1, 2, 3], [4, 5, 6]]
    assert tr.quat_xyzw.tolist() == [[0, 0, 0, 1], [0, 0, 0, 1]]
    assert tr.path == str(p) and tr.notices == []
    assert tr.velocity_world is None and tr.bias_gyro is None


def test_read_tum_crlf_commas_and_tabs(tmp_path):
    p = write(tmp_path, "1.0,1,2,3,0,0,0,1\r\n2.0, 4, 5, 6, 0, 0, 0, 1\r\n")
    assert read_tum(p).positions.tolist() == [[1, 2, 3], [4, 5, 6]]
    p = write(tmp_path, "1.0\t1 2\t3 0 0 0 1\r\n2.0 4 5 6 0 0 0 1\r\n", "tabs.txt")
    assert read_tum(p).t_ns.tolist() == [10**9, 2 * 10**9]


def test_read_tum_extra_columns_one_notice(tmp_path):
    rows = [f"{i}.0 {i} 0 0 {ID} 0.1 0.2 0.3 0.4 0.5 0.6" for i in range(4)]
    tr = read_tum(write(tmp_path, "\n".join(rows) + "\n"))
    assert tr.notices == ["ignored columns 9-14 on every line"]
    assert tr.positions[:, 0].tolist() == [0, 1, 2, 3]
    # ragged: only some lines have extras, and the extras need not be numbers
    rows = [f"0.0 0 0 0 {ID}", f"1.0 1 0 0 {ID} covariance", f"2.0 2 0 0 {ID}"]
    tr = read_tum(write(tmp_path, "\n".join(rows) + "\n", "ragged.txt"))
    assert tr.notices == ["ignored column 9 on 1 of 3 lines"]


@pytest.mark.parametrize(
    "bad_line, fragments",
    [
        ("3.0 1 2 3 0 0 1", ["expected 8 columns", "got 7"]),
        ("3.0 1 abc 3 " + ID, ["column 3 (ty) is not a number: 'abc'"]),
        ("3.0 1 2 3 0 0 nan 1", ["quaternion is not finite"]),
        ("3.0 1 inf 3 " + ID, ["position is not finite"]),
        ("3.0 1 2 3 0 0 0 0", ["quaternion has zero norm"]),
        ("x.5 1 2 3 " + ID, ["timestamp is not a number: 'x.5'"]),
        ("1.5 1 2 3 " + ID, ["timestamp 1.500000000 is earlier than 2.000000000 on line 3",
                             "sorted"]),
        ("2.0 9 2 3 " + ID, ["timestamp 2.000000000 repeats line 3 with a different pose"]),
    ],
)
def test_read_tum_malformed_line_is_named(tmp_path, bad_line, fragments):
    text = f"# t x y z qx qy qz qw\n1.0 0 0 0 {ID}\n2.0 1 2 3 {ID}\n{bad_line}\n5.0 0 0 0 {ID}\n"
    p = write(tmp_path, text)
    expect_error(lambda: read_tum(p), p, 4, *fragments)


def test_read_tum_file_level_errors(tmp_path):
    p = write(tmp_path, f"# only\n1.0 0 0 0 {ID}\n")
    expect_error(lambda: read_tum(p), p, None, "too few poses: got 1, need at least 2")
    assert len(read_tum(p, min_poses=1)) == 1
    p = write(tmp_path, f"1.0 0 0 0 {ID}\n2.0 0 0 0 {ID}\n", "two.txt")
    expect_error(lambda: read_tum(p, min_poses=3), p, None, "too few poses: got 2, need at least 3")
    p = write(tmp_path, "# nothing\n\n", "empty.txt")
    expect_error(lambda: read_tum(p), p, None, "no data rows")
    expect_error(lambda: read_tum(tmp_path / "missing.txt"), tmp_path / "missing.txt", None, "not found")


def test_read_tum_drops_exact_duplicates_with_one_notice(tmp_path):
    rows = ["1.0 0 0 0 " + ID, "1.0 0 0 0 " + ID, "2.0 1 0 0 " + ID, "3.0 2 0 0 " + ID,
            "3.0 2 0 0 " + ID, "3.0 2 0 0 " + ID, "4.0 3 0 0 " + ID]
    tr = read_tum(write(tmp_path, "\n".join(rows) + "\n"))
    assert tr.t_ns.tolist() == [k * 10**9 for k in (1, 2, 3, 4)]
    assert tr.line_numbers.tolist() == [1, 3, 4, 7]
    assert tr.notices == ["dropped 3 exact duplicate rows (lines 2, 5, 6)"]


def test_read_tum_repeated_stamp_keep_first(tmp_path):
    rows = ["1.0 0 0 0 " + ID, "2.0 1 0 0 " + ID, "2.0 1.001 0 0 " + ID, "3.0 2 0 0 " + ID]
    p = write(tmp_path, "\n".join(rows) + "\n")
    expect_error(lambda: read_tum(p), p, 3, "repeats line 2 with a different pose")
    tr = read_tum(p, repeated_stamps="first")
    assert tr.positions[:, 0].tolist() == [0, 1, 2]
    assert len(tr.notices) == 1 and "(line 3)" in tr.notices[0] and "kept the first" in tr.notices[0]


def test_read_tum_normalizes_and_makes_signs_continuous(tmp_path):
    rng = np.random.default_rng(3)
    # a smooth rotation about a tilted axis, with random sign flips and scale
    ang = np.linspace(0.0, 3.0, 40)
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    q = np.column_stack([np.sin(ang / 2)[:, None] * axis, np.cos(ang / 2)])
    sign = rng.choice([-1.0, 1.0], size=40)
    scale = rng.uniform(0.5, 2.0, size=40)
    qf = q * (sign * scale)[:, None]
    rows = [f"{i}.0 0 0 0 " + " ".join(repr(x) for x in qf[i].tolist()) for i in range(40)]
    tr = read_tum(write(tmp_path, "\n".join(rows) + "\n"))
    np.testing.assert_allclose(np.linalg.norm(tr.quat_xyzw, axis=1), 1.0, rtol=0, atol=1e-15)
    assert (np.einsum("ij,ij->i", tr.quat_xyzw[1:], tr.quat_xyzw[:-1]) > 0).all()
    # continuity keeps the first sample's sign: equal to q * sign[0]
    np.testing.assert_allclose(tr.quat_xyzw, q * sign[0], rtol=0, atol=1e-15)
    assert len(tr.notices) == 1 and tr.notices[0].startswith("normalized 40 quaternions")


def test_read_tum_decimal_rounding_notice(tmp_path):
    p = write(tmp_path, f"1.0000000004 0 0 0 {ID}\n1.0000000016 0 0 0 {ID}\n2 0 0 0 {ID}\n")
    tr = read_tum(p)
    assert tr.t_ns.tolist() == [1_000_000_000, 1_000_000_002, 2_000_000_000]
    assert tr.notices == ["rounded 2 timestamps with more than 9 decimals to the nearest ns"]


# ---------------------------------------------------------------------------------------
# TUM writer


def test_write_tum_round_trip_exact(tmp_path):
    rng = np.random.default_rng(0)
    n = 500
    t = 1_403_715_524_907_143_168 + np.cumsum(rng.integers(1, 10**7, n))
    p = rng.normal(size=(n, 3)) * np.array([1e-9, 1.0, 5.4e6])  # tiny, normal, UTM-sized
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[0] = [0.0, 0.6, 0.8, 0.0]  # short decimals stay short
    out = tmp_path / "out.tum"
    write_tum(out, t, p, q)
    lines = out.read_text().splitlines()
    assert lines[0] == "# timestamp tx ty tz qx qy qz qw"
    assert lines[1].split()[0] == f"{t[0] // 10**9}.{t[0] % 10**9:09d}"
    assert lines[1].split()[4:8] == ["0", "0.6", "0.8", "0"]
    assert len(lines[2].split()[1]) >= 17  # random values need 16-17 significant digits
    tr = read_tum(out)
    assert np.array_equal(tr.t_ns, t)
    assert np.array_equal(tr.positions, p)  # bit for bit, UTM included
    q_cont = q * np.sign(np.einsum("ij,ij->i", q, tr.quat_xyzw))[:, None]
    assert np.array_equal(tr.quat_xyzw, q_cont)
    assert not list(tmp_path.glob(".*"))  # no temp file left


def test_write_tum_rejects_bad_input(tmp_path):
    with pytest.raises(ValueError, match="quat_xyzw"):
        write_tum(tmp_path / "x.tum", [1, 2], np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"`positions` contains NaN or inf \(first at index \(0, 0\)\)"):
        write_tum(tmp_path / "x.tum", [1], [[np.nan, 0, 0]], [[0, 0, 0, 1]])
    assert not (tmp_path / "x.tum").exists()


# ---------------------------------------------------------------------------------------
# EuRoC


def test_read_euroc_8_columns_w_first(tmp_path):
    s = np.sqrt(0.5)
    p = write(tmp_path, f"#timestamp,x,y,z,qw,qx,qy,qz\n100,1,2,3,{s},0,0,{s}\n200,1,2,3,1,0,0,0\n",
              "gt.csv")
    tr = read_euroc_groundtruth(p)
    assert tr.t_ns.tolist() == [100, 200]
    np.testing.assert_allclose(tr.quat_xyzw, [[0, 0, s, s], [0, 0, 0, 1]], atol=1e-16)
    assert tr.velocity_world is None and tr.line_numbers.tolist() == [2, 3]


def test_read_euroc_header_without_hash_and_errors(tmp_path):
    p = write(tmp_path, "timestamp,x,y,z,qw,qx,qy,qz\n100,1,2,3,1,0,0,0\n200,1,2,3,1,0,0\n", "gt.csv")
    expect_error(lambda: read_euroc_groundtruth(p), p, 3, "expected 8 columns", "got 7")
    p = write(tmp_path, "100,1,2,3,1,0,0,0\n50,1,2,3,1,0,0,0\n", "gt2.csv")
    expect_error(lambda: read_euroc_groundtruth(p), p, 2, "earlier than")


def test_write_euroc_imu_header_and_values(tmp_path):
    rng = np.random.default_rng(1)
    t = 1403715523912140000 + np.arange(50, dtype=np.int64) * 5_000_000
    g, a = rng.normal(size=(50, 3)), rng.normal(size=(50, 3)) + [0, 0, 9.81]
    out = tmp_path / "data.csv"
    write_euroc_imu(out, t, g, a)
    text = out.read_text()
    assert text.splitlines()[0] == EUROC_IMU_HEADER
    assert EUROC_IMU_HEADER.startswith("#timestamp [ns],w_RS_S_x [rad s^-1],")
    assert np.array_equal(read_timestamps(out), t)
    vals = np.loadtxt(out, delimiter=",", comments="#")[:, 1:]
    assert np.array_equal(vals, np.hstack([g, a]))
    write_euroc_imu(out, t[:2], g[:2], a[:2], header="# custom")  # replaces atomically
    assert out.read_text().splitlines()[0] == "# custom" and len(out.read_text().splitlines()) == 3


def test_write_euroc_groundtruth_round_trip(tmp_path):
    rng = np.random.default_rng(2)
    n = 30
    t = 1403715524907143168 + np.arange(n, dtype=np.int64) * 5_000_000
    p, v, bg, ba = (rng.normal(size=(n, 3)) for _ in range(4))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 3] < 0] *= -1
    q = np.asarray(q)
    out = tmp_path / "data.csv"
    write_euroc_groundtruth(out, t, p, q, v, bg, ba)
    assert out.read_text().splitlines()[0] == EUROC_GROUNDTRUTH_HEADER
    tr = read_euroc_groundtruth(out)
    assert np.array_equal(tr.t_ns, t)
    for got, want in [(tr.positions, p), (tr.velocity_world, v), (tr.bias_gyro, bg), (tr.bias_accel, ba)]:
        assert np.array_equal(got, want)
    q_cont = q * np.sign(np.einsum("ij,ij->i", q, tr.quat_xyzw))[:, None]
    assert np.array_equal(tr.quat_xyzw, q_cont)
    # w first on disk
    first = out.read_text().splitlines()[1].split(",")
    assert float(first[4]) == q[0, 3] and float(first[5]) == q[0, 0]


# ---------------------------------------------------------------------------------------
# timestamps column


def test_read_timestamps_units_and_header(tmp_path):
    p = write(tmp_path, "#timestamp [ns],a\n100,1\n200,2\n", "a.csv")
    assert read_timestamps(p).tolist() == [100, 200]
    p = write(tmp_path, "t a\n0.5 x\n1.25 y\n", "b.txt")  # non-numeric header, seconds
    assert read_timestamps(p).tolist() == [500_000_000, 1_250_000_000]
    p = write(tmp_path, "0\n1\n2\n", "c.txt")
    with pytest.raises(InputError, match="look like seconds"):  # integers are ns, and 1 ns steps are not
        read_timestamps(p)
    assert read_timestamps(p, unit="s").tolist() == [0, 10**9, 2 * 10**9]
    p = write(tmp_path, "0\n0.005\n0.010\n", "d.txt")  # mixed: one decimal makes all seconds
    assert read_timestamps(p).tolist() == [0, 5_000_000, 10_000_000]


def test_read_timestamps_must_increase(tmp_path):
    p = write(tmp_path, "# t\n100\n200\n200\n300\n", "t.txt")
    expect_error(lambda: read_timestamps(p), p, 4, "strictly increasing", "repeats", "line 3")
    p = write(tmp_path, "100,0\n300,0\n200,0\n", "u.csv")
    expect_error(lambda: read_timestamps(p), p, 3, "is earlier than", "line 2")


# ---------------------------------------------------------------------------------------
# PoseTrack, gaps


def _track(t_ns):
    n = len(t_ns)
    return PoseTrack(np.asarray(t_ns), np.arange(3 * n, dtype=float).reshape(n, 3),
                     np.tile([0.0, 0, 0, 1], (n, 1)), line_numbers=np.arange(n) + 10)


def test_find_gaps_and_split():
    ms = 1_000_000
    tr = _track([0, 10 * ms, 20 * ms, 70 * ms, 120 * ms + 1, 130 * ms])
    gaps = find_gaps(tr, 0.05)  # 50 ms exactly is not a gap, 50 ms + 1 ns is
    assert gaps == [Gap(index=4, start_ns=70 * ms, end_ns=120 * ms + 1, duration_s=0.050000001, line=14)]
    pieces = split_at_gaps(tr, gaps)
    assert [len(p) for p in pieces] == [4, 2]
    assert pieces[1].t_ns.tolist() == [120 * ms + 1, 130 * ms]
    assert pieces[1].line_numbers.tolist() == [14, 15]
    assert np.array_equal(pieces[1].positions, tr.positions[4:])
    assert split_at_gaps(tr, []) [0].t_ns.tolist() == tr.t_ns.tolist()
    assert find_gaps(tr.t_ns, 0.01)[0].line is None
    assert [g.index for g in find_gaps(tr.t_ns, 0.0099)] == [1, 2, 3, 4, 5]


def test_clean_poses_keeps_extras_in_step():
    t = [0, 1, 1, 2]
    p = np.zeros((4, 3))
    v = np.arange(12.0).reshape(4, 3)
    v[2] = v[1]
    tr = clean_poses(t, p, [[0, 0, 0, 1]] * 4, velocity_world=v, bias_gyro=v, bias_accel=v)
    assert tr.velocity_world.tolist() == [[0, 1, 2], [3, 4, 5], [9, 10, 11]]
    assert tr.notices == ["dropped 1 exact duplicate row (line 3)"]
    v2 = v.copy()
    v2[2, 0] = 99.0  # same pose, different velocity: not an exact duplicate
    with pytest.raises(InputError, match="repeats line 2"):
        clean_poses(t, p, [[0, 0, 0, 1]] * 4, velocity_world=v2)


# ---------------------------------------------------------------------------------------
# real files (../shared/data)


def test_real_fr2_desk_repeated_stamp_is_a_different_pose_and_55_gaps():
    path = require_shared("tum_rgbd", "fr2_desk_groundtruth.txt")
    # line 10862 and 10863 share the stamp 1311868229.5760 with poses ~1 mm / 0.3 deg apart
    expect_error(lambda: read_tum(path), path, 10863, "1311868229.576000000 repeats line 10862")
    tr = read_tum(path, repeated_stamps="first")
    assert len(tr) == 20957 - 1  # data lines (awk) minus the repeat
    assert tr.positions[tr.line_numbers.tolist().index(10862)].tolist() == [1.4054, 0.9615, 1.3677]
    gaps = find_gaps(tr, 0.05)
    assert len(gaps) == 55
    longest = max(gaps, key=lambda g: g.duration_s)
    assert longest.duration_s == pytest.approx(11.9872, abs=1e-9)
    assert all(tr.t_ns[g.index] - tr.t_ns[g.index - 1] > 50_000_000 for g in gaps)
    pieces = split_at_gaps(tr, gaps)
    assert len(pieces) == 56 and sum(len(p) for p in pieces) == len(tr)


def test_real_tum_vi_room1_gaps():
    path = require_shared("tum_vi", "room1_512_16_groundtruth.tum")
    tr = read_tum(path)
    assert len(tr) == 16541 and tr.notices == []
    assert tr.t_ns[0] == 1520530308189680000
    gaps = find_gaps(tr, 0.05)
    assert len(gaps) == 7
    assert max(g.duration_s for g in gaps) == pytest.approx(1.05833, abs=1e-9)
    assert [g.line for g in gaps] == [4879, 5705, 5707, 5715, 7647, 11589, 14127]


def test_real_udel_gore_14_columns():
    path = require_shared("openvins_sim", "udel_gore.txt")
    tr = read_tum(path)
    assert len(tr) == 3445
    assert tr.notices == ["ignored columns 9-14 on every line",
                          "rounded every timestamp with more than 9 decimals to the nearest ns"]
    assert tr.t_ns[:2].tolist() == [1521753105031429052, 1521753105081429005]
    np.testing.assert_allclose(tr.quat_xyzw[0], [0.8068135119, 0.0049998380, -0.0068285521, 0.5907455709],
                               atol=1e-9)


def test_real_georeferenced_exact_values():
    path = require_shared("misc", "georeferenced.tum")
    tr = read_tum(path)
    assert len(tr) == 1000 and tr.line_numbers[0] == 3
    assert tr.t_ns[0] == 1706282470098386526
    first = path.read_text().splitlines()[2].split()
    assert tr.positions[0].tolist() == [float(x) for x in first[1:4]]  # correctly rounded
    assert tr.positions[:, 1].min() > 5e6


def test_real_euroc_17_columns():
    path = require_shared("euroc_V1_02_medium", "groundtruth.csv")
    tr = read_euroc_groundtruth(path)
    assert len(tr) == 16702 and tr.notices == [] and tr.line_numbers[0] == 2
    assert tr.t_ns[:2].tolist() == [1403715524907143168, 1403715524912143104]
    assert tr.positions[0].tolist() == [0.515356, 1.996773, 0.971104]
    q0 = np.array([0.789985, -0.205376, 0.554528, 0.161996])  # file: w=0.161996 first
    np.testing.assert_allclose(tr.quat_xyzw[0], q0 / np.linalg.norm(q0), atol=1e-15)
    assert tr.velocity_world[0].tolist() == [-0.002276, -0.009616, -0.005214]
    assert tr.bias_gyro[0].tolist() == [-0.002153, 0.020744, 0.075806]
    assert tr.bias_accel[0].tolist() == [-0.013337, 0.103464, 0.093086]
    assert EUROC_GROUNDTRUTH_HEADER == path.read_text().splitlines()[0]


def test_real_euroc_imu_timestamps():
    path = require_shared("euroc_V1_02_medium", "imu0_first40s.csv")
    t = read_timestamps(path)
    assert len(t) == 7999 and t[0] == 1403715523912140000
    assert np.all(np.diff(t) > 0)
    assert path.read_text().splitlines()[0] == EUROC_IMU_HEADER


def test_imu_csv_parallel_parts_equal_one_pass(tmp_path, monkeypatch):
    """Large files are parsed in parts cut at line boundaries by parallel threads: the same
    arrays as one pass, comments and blank lines anywhere, and errors still name the line."""
    from splineimu.io import imu_csv
    from splineimu.io.tables import format_table

    rng = np.random.default_rng(0)
    n = 5000
    t = 1_403_715_523_912_140_000 + 5_000_000 * np.arange(n, dtype=np.int64)
    v = rng.normal(size=(n, 6)) * 10.0 ** rng.integers(-8, 3, (n, 6))
    lines = format_table(t, v).decode().splitlines()
    for k in (0, 1700, 2500, 4100):  # comments and blank lines, some near the cut points
        lines.insert(k, "# comment" if k % 2 else "")
    p = tmp_path / "imu.csv"
    p.write_text("#timestamp [ns],wx,wy,wz,ax,ay,az\n" + "\n".join(lines) + "\n")
    t1, v1 = imu_csv.read_imu_table(p)
    monkeypatch.setattr(imu_csv, "PARALLEL_PARSE_BYTES", 1)
    monkeypatch.setattr(imu_csv.os, "cpu_count", lambda: 3)
    t2, v2 = imu_csv.read_imu_table(p)
    assert np.array_equal(t1, t) and np.array_equal(t2, t)
    assert v1.tobytes() == v.tobytes() and v2.tobytes() == v.tobytes()
    # a bad value in the last part: the exact reader names its line
    text = p.read_text().splitlines()
    text[4800] = text[4800].replace(",", ",x", 1)
    p.write_text("\n".join(text) + "\n")
    with pytest.raises(InputError, match=r"imu\.csv:4801: .*non-numeric"):
        imu_csv.read_imu_table(p)


def test_imu_csv_stamp_beyond_int64_is_named_without_a_pandas_warning(tmp_path):
    """A stamp like 1e30 made pandas' fast parser print 'invalid value encountered in cast'
    before the exact parser named the line; the cast is now a failure of the fast path."""
    import warnings

    from splineimu.io.imu_csv import read_imu_csv

    p = tmp_path / "imu.csv"
    p.write_text("#t,gx,gy,gz,ax,ay,az\n1000000000,0,0,0,0,0,9.8\n1e30,0,0,0,0,0,9.8\n3000000000,0,0,0,0,0,9.8\n")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(InputError, match=r"imu\.csv:3: time stamp must be integer nanoseconds"):
            read_imu_csv(p)
    assert not [w for w in seen if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in seen]


def test_groundtruth_errors_do_not_call_the_file_imu_data(tmp_path):
    """EuRoC's ground-truth header names its bias columns b_w_RS_S_x and b_a_RS_S_x: the format
    guess matched the IMU's w_RS_S / a_RS_S first, and every error in a ground truth ended with
    'the file looks like a EuRoC IMU csv ... it is IMU data, not poses'."""
    from splineimu.io.euroc import EUROC_GROUNDTRUTH_HEADER
    from splineimu.io.sniff import guess_format

    rows = [f"{i * 5000000},0,0,0,1,0,0,0" + ",0" * 9 for i in range(5)]
    rows[1] = "5000000,0,0,0,0,0,0,0" + ",0" * 9
    p = tmp_path / "gt.csv"
    p.write_text("\n".join([EUROC_GROUNDTRUTH_HEADER, *rows]) + "\n")
    assert guess_format(p) == "euroc_gt"
    with pytest.raises(InputError) as e:
        read_euroc_groundtruth(p)
    assert str(e.value) == f"{p}:3: quaternion has zero norm: [0, 0, 0, 0]"


def test_too_few_columns_names_only_the_columns_expected(tmp_path):
    """A short row of a ground truth read as 8 columns listed all 17 EuRoC names after
    'expected 8 columns'."""
    p = tmp_path / "gt.csv"
    p.write_text("0,1,2,3,1,0,0,0\n5000000,1,2,3\n")
    with pytest.raises(InputError) as e:
        read_euroc_groundtruth(p)
    msg = str(e.value)
    assert "expected 8 columns (timestamp p_RS_R_x p_RS_R_y p_RS_R_z q_RS_w q_RS_x q_RS_y q_RS_z), got 4" in msg
    assert "v_RS_R_x" not in msg and msg.startswith(f"{p}:2:")


@pytest.mark.parametrize("text", ["", "# only a comment\n", "%YAML:1.0\n---\n"])
def test_an_empty_imu_yaml_is_not_an_ideal_sensor(tmp_path, text):
    """An empty (or truncated to its comments) IMU yaml was read as a sensor with no noise:
    `scene --imu empty.yaml` wrote noise-free data and `calibrate --truth` compared with K = I."""
    from splineimu.errors import ConfigError
    from splineimu.imu.presets import load_imu_config

    p = tmp_path / "imu.yaml"
    p.write_text(text)
    with pytest.raises(ConfigError) as e:
        load_imu_config(p)
    assert str(e.value) == f"{p}: holds no IMU parameters (empty); for a noise-free sensor give the preset `ideal`"
    assert float(load_imu_config("ideal").gyroscope_noise_density[0]) == 0.0


def test_a_repeated_yaml_key_is_refused(tmp_path):
    """PyYAML keeps the last of two equal keys: a scene file with `motion:` twice ran the second
    motion, and an imu.yaml with a density twice used the second one, without a word."""
    from splineimu.errors import ConfigError
    from splineimu.imu.presets import load_imu_config
    from splineimu.yamldoc import parse_yaml

    p = tmp_path / "imu.yaml"
    p.write_text("gyroscope_noise_density: 0.1\naccelerometer_noise_density: 0.2\ngyroscope_noise_density: 0.3\n")
    with pytest.raises(ConfigError) as e:
        load_imu_config(p)
    assert str(e.value) == f"{p}:3: key `gyroscope_noise_density` repeats the one on line 1"
    with pytest.raises(ConfigError, match=r"s.yaml:4: key `scene` repeats the one on line 2"):
        parse_yaml("motion:\n  scene: static\n  duration_s: 1\n  scene: ellipse\n", "s.yaml")
    doc = parse_yaml("a: &x {b: 1}\nc:\n  <<: *x\n  d: 2\ne: {b: 1}\nf: {b: 2}\n", "m.yaml")  # merges, equal keys
    assert doc.data["c"] == {"b": 1, "d": 2} and doc.data["f"] == {"b": 2}  # in different mappings are fine


def test_imu_csv_stamps_are_exact_or_refused(tmp_path):
    """EuRoC-size stamps written with '.0' were read through a float by the fast parser
    (1403715273267142976.0 -> ...142912 ns, 200.003 Hz) and a stamp beyond int64 ended in an
    OverflowError traceback; '1_000' was read as 1000 (Python's float()). A trailing comma and
    a header line without '#' are read."""
    from splineimu.io.imu_csv import read_imu_csv

    def csv(name, rows):
        p = tmp_path / name
        p.write_text("".join(r + "\n" for r in rows))
        return p

    t0 = 1403715273262142976
    dec = r"dec.csv:1: time stamp must be integer nanoseconds, got '1403715273262142976\.0'"
    with pytest.raises(InputError, match=dec):
        read_imu_csv(csv("dec.csv", [f"{t0 + i * 5_000_000}.0,0,0,0,0,0,9.81" for i in range(3)]))
    with pytest.raises(InputError, match=r"big.csv:3: time stamp 9223372036859775807 ns does not fit a 64-bit"):
        read_imu_csv(csv("big.csv", [f"{2**63 - 1 - 5_000_000 + i * 5_000_000},0,0,0,0,0,9.81" for i in range(3)]))
    with pytest.raises(InputError, match=r"us.csv:2: non-numeric value in '5000000,1_000,0,0,0,0,9.81'"):
        read_imu_csv(csv("us.csv", ["0,0,0,0,0,0,9.81", "5000000,1_000,0,0,0,0,9.81"]))
    t, g, a = read_imu_csv(csv("ok.csv", ["timestamp,wx,wy,wz,ax,ay,az"]
                                + [f"{t0 + i * 5_000_000},0,0,0.5,0,0,9.81," for i in range(3)]))
    assert t.tolist() == [t0, t0 + 5_000_000, t0 + 10_000_000] and g[:, 2].tolist() == [0.5] * 3


def test_absurd_imu_values_are_refused_with_their_line(tmp_path):
    """A finite 1e300 passed the IMU reader: allan printed inf and numpy warnings, preintegrate
    "`quat_xyzw` row 0 is not a valid quaternion (norm nan)", integrate "`positions` contains
    NaN or inf"; no file or line was named."""
    from splineimu.io.imu_csv import MAX_IMU_VALUE, read_imu_csv

    p = tmp_path / "imu.csv"
    rows = [f"{i * 5_000_000},0,0,0,0,0,9.81" for i in range(6)]
    rows[3] = "15000000,0,0,0,0,-1e300,9.81"
    p.write_text("#t,gx,gy,gz,ax,ay,az\n" + "\n".join(rows) + "\n")
    with pytest.raises(InputError) as e:
        read_imu_csv(p)
    assert str(e.value) == (f"{p}:5: value -1e+300 (column 6) is beyond 1e+12 in magnitude: no IMU reads that "
                            "(a unit or column mix-up?)")
    rows[3] = f"15000000,0,0,{MAX_IMU_VALUE},0,0,9.81"  # the bound itself is read
    p.write_text("\n".join(rows) + "\n")
    assert read_imu_csv(p)[1][3, 2] == MAX_IMU_VALUE


def test_a_quaternion_with_huge_components_is_normalized_not_zero(tmp_path):
    """qw = 1e300 (finite) squared to inf: the norm was inf, the quaternion became 0 and the
    run stopped with "`quat_xyzw` row 0 is not a valid quaternion (norm 0)" (no file, no line)
    after a numpy overflow warning."""
    import warnings

    p = tmp_path / "poses.tum"
    p.write_text("".join(f"{i}.0 0 0 0 0 0 1e300 1e300\n" for i in range(3)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tr = read_tum(p)
    np.testing.assert_allclose(tr.quat_xyzw, np.tile([0.0, 0.0, 2**-0.5, 2**-0.5], (3, 1)), rtol=0, atol=1e-15)
    assert any("worst: 1.41421e+300 on line 1" in n for n in tr.notices)
