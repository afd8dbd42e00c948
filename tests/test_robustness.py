"""Robustness of the library: one error family with file and line, outputs that never lose data,
units and formats recognised, sizes checked before allocating, the same bytes twice."""

from __future__ import annotations

import math
import os

import pytest

from splineimu.errors import ConfigError, InputError, OutputExistsError, SplineImuError
from splineimu.io.files import check_not_input, check_output_dir, check_output_file, write_output_file


def _tum(n=40, dt=0.01, t0=1700000000.0, scale=1.0, fmt="{:.9f}"):
    rows = ["# t x y z qx qy qz qw"]
    for i in range(n):
        a = 0.3 * i * dt
        rows.append(f"{fmt.format((t0 + i * dt) * scale)} {math.cos(a):.6f} {math.sin(a):.6f} 1 0 0 "
                    f"{math.sin(a / 2):.9f} {math.cos(a / 2):.9f}")
    return "\n".join(rows) + "\n"


def _gt(n=40, stamp=lambda i: str(1_400_000_000_000_000_000 + i * 10_000_000)):
    rows = ["#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []"]
    rows += [f"{stamp(i)},{i * 0.01},0,1,1,0,0,0" for i in range(n)]
    return "\n".join(rows) + "\n"


def _imu(n=40, stamp=lambda i: str(1_000_000_000 + i * 5_000_000)):
    rows = ["#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"]
    rows += [f"{stamp(i)},0.001,0,0,0,0,9.81" for i in range(n)]
    return "\n".join(rows) + "\n"


def _no_temporaries(folder):
    return [p.name for p in folder.iterdir() if ".tmp-" in p.name or ".old-" in p.name]


# ------------------------------------------------------------------ single-file outputs


def test_output_file_refuses_existing_without_force(tmp_path):
    out = tmp_path / "t.tum"
    out.write_text("precious")
    with pytest.raises(OutputExistsError, match="--force"):
        write_output_file(out, "new")
    assert out.read_text() == "precious"
    write_output_file(out, "new", force=True)
    assert out.read_text() == "new"


def test_output_file_never_onto_an_input(tmp_path):
    inp = tmp_path / "imu.csv"
    inp.write_text("data")
    (tmp_path / "sub").mkdir()
    for spelling in (inp, tmp_path / "sub" / ".." / "imu.csv"):
        with pytest.raises(ConfigError, match="is an input"):
            write_output_file(spelling, "x", force=True, inputs=[inp])
    os.link(inp, tmp_path / "hard.csv")
    with pytest.raises(ConfigError, match="is an input"):
        check_output_file(tmp_path / "hard.csv", force=True, inputs=[inp])
    assert inp.read_text() == "data"


def test_output_never_through_a_symlink(tmp_path):
    victim = tmp_path / "victim.tum"
    victim.write_text("precious")
    link = tmp_path / "link.tum"
    link.symlink_to(victim)
    with pytest.raises(ConfigError, match="symbolic link"):
        write_output_file(link, "x", force=True)
    (tmp_path / "dir").mkdir()
    (tmp_path / "dirlink").symlink_to(tmp_path / "dir")
    with pytest.raises(ConfigError, match="symbolic link"):
        check_output_dir(tmp_path / "dirlink", force=True)
    assert victim.read_text() == "precious" and link.is_symlink()


def test_output_folder_holding_an_input_is_refused(tmp_path):
    (tmp_path / "out").mkdir()
    inp = tmp_path / "out" / "poses.tum"
    inp.write_text("x")
    with pytest.raises(ConfigError, match="holds the input"):
        check_not_input(tmp_path / "out", [inp])


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    out = tmp_path / "w.csv"
    out.write_text("old")

    def pieces():
        yield b"new part"
        raise KeyboardInterrupt  # as SIGINT / SIGTERM arrive mid-write

    with pytest.raises(KeyboardInterrupt):
        write_output_file(out, pieces(), force=True)
    assert out.read_text() == "old"
    assert _no_temporaries(tmp_path) == []


def test_synthesis_refuses_output_onto_its_input(tmp_path):
    from splineimu.api import OutputOptions, PosesInput, SynthesisJob, run_job

    poses = tmp_path / "p.tum"
    poses.write_text(_tum())
    job = SynthesisJob(PosesInput(str(poses)), output=OutputOptions(str(poses), force=True))
    with pytest.raises(ConfigError, match="input"):
        run_job(job)
    assert poses.read_text() == _tum()


# ------------------------------------------------------------------ long lines, units, formats


def test_long_line_refused_without_reading_it(tmp_path):
    from splineimu.io.imu_csv import read_imu_table
    from splineimu.io.timestamps import MAX_LINE_BYTES, read_timestamps
    from splineimu.io.tum import read_tum

    p = tmp_path / "big.txt"
    with open(p, "wb") as f:
        f.write(b"1 0 0 0 0 0 0 1\n2 ")
        f.write(b"5" * (3 * MAX_LINE_BYTES))
    for reader in (read_tum, read_timestamps, read_imu_table):
        with pytest.raises(InputError, match=r"big\.txt:2: line longer than"):
            reader(p)


@pytest.mark.parametrize("scale, fmt, unit", [(1e3, "{:.3f}", "milliseconds"), (1e6, "{:.0f}", "microseconds"),
                                              (1e9, "{:.0f}", "nanoseconds")])
def test_tum_stamps_in_another_unit(tmp_path, scale, fmt, unit):
    from splineimu.io.tum import read_tum

    p = tmp_path / "p.tum"
    p.write_text(_tum(scale=scale, fmt=fmt))
    with pytest.raises(InputError, match=rf"p\.tum:2: .*looks like {unit}.*TUM stamps are decimal seconds"):
        read_tum(p)


def test_euroc_stamps_in_seconds(tmp_path):
    from splineimu.io.euroc import read_euroc_groundtruth
    from splineimu.io.imu_csv import read_imu_table
    from splineimu.io.timestamps import read_timestamps

    gt = tmp_path / "gt.csv"
    gt.write_text(_gt(stamp=lambda i: str(1400000000 + i)))
    with pytest.raises(InputError, match="step by 1 ns .*look like seconds.*integer nanoseconds"):
        read_euroc_groundtruth(gt)
    imu = tmp_path / "imu.csv"
    imu.write_text(_imu(stamp=lambda i: str(1400000000000 + 5 * i)))
    with pytest.raises(InputError, match="look like milliseconds"):
        read_imu_table(imu)
    st = tmp_path / "s.csv"
    st.write_text("0\n1\n2\n3\n")
    with pytest.raises(InputError, match="look like seconds.*decimal point"):
        read_timestamps(st)
    assert read_timestamps(st, unit="s").tolist() == [0, 1_000_000_000, 2_000_000_000, 3_000_000_000]


def test_wrong_reader_names_the_likely_format(tmp_path):
    from splineimu.io.euroc import read_euroc_groundtruth
    from splineimu.io.imu_csv import read_imu_table
    from splineimu.io.tum import read_tum

    tum, gt, imu = tmp_path / "p.tum", tmp_path / "gt.csv", tmp_path / "imu.csv"
    tum.write_text(_tum())
    gt.write_text(_gt())
    imu.write_text(_imu())
    with pytest.raises(InputError, match="looks like a TUM trajectory.*from-tum"):
        read_euroc_groundtruth(tum)
    with pytest.raises(InputError, match="looks like a EuRoC ground-truth csv.*from-euroc"):
        read_tum(gt)
    for reader in (read_tum, read_euroc_groundtruth):
        with pytest.raises(InputError, match="looks like a EuRoC IMU csv.*not poses"):
            reader(imu)
    with pytest.raises(InputError, match="looks like a EuRoC ground-truth"):
        read_imu_table(gt)


def test_compare_refuses_nan_with_its_line(tmp_path):
    pytest.importorskip("evo")
    from splineimu.api.compare import compare_files

    a, b = tmp_path / "a.tum", tmp_path / "b.tum"
    a.write_text(_tum().replace(" 1 0 0 ", " nan 0 0 ", 1))
    b.write_text(_tum())
    with pytest.raises(InputError, match=r"a\.tum:2:"):
        compare_files(a, b)


def test_allan_refuses_a_too_short_record_and_bad_density(tmp_path):
    from splineimu.allan.deviation import default_cluster_factors
    from splineimu.api.allan import analyze_recording

    p = tmp_path / "imu.csv"
    p.write_text(_imu(10))
    with pytest.raises(InputError, match="too few for an Allan analysis"):
        analyze_recording(p)
    with pytest.raises(ConfigError, match="points_per_decade"):
        default_cluster_factors(1000, 0)


# ------------------------------------------------------------------ resources


def test_record_too_large_is_refused_before_allocating(monkeypatch):
    import splineimu.resources as res
    from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, run_job
    from splineimu.resources import check_record_fits

    check_record_fits(10_000, rate_hz=200.0)
    monkeypatch.setattr(res, "available_memory_bytes", lambda: 3 * 10**9)  # as under `ulimit -v 3000000`
    job = SynthesisJob(SceneInput("static", duration_s=500000), ImuOptions(rate_hz=1000), OutputOptions("never"))
    need = r"500000001 IMU samples \(500000 s at 1000 Hz\) need about 24 GB of memory, 3 GB"
    with pytest.raises(ConfigError, match=need):
        run_job(job)
    with pytest.raises(ConfigError, match="whole record is held in memory for --bag"):
        check_record_fits(10**10, rate_hz=1000.0, whole="--bag")
    assert not os.path.exists("never")


def test_disk_space_is_checked(tmp_path, monkeypatch):
    import splineimu.resources as res

    monkeypatch.setattr(res, "free_disk_bytes", lambda path: 1000)
    monkeypatch.setattr(res, "available_memory_bytes", lambda: 10**12)
    with pytest.raises(ConfigError, match="of disk at"):
        res.check_record_fits(10_000, rate_hz=200.0, out_dir=tmp_path / "out")


# ------------------------------------------------------------------ one failure shape


def test_cli_turns_os_errors_into_one_line(tmp_path, capsys):
    from splineimu.cli import main

    (tmp_path / "f.txt").write_text("x")
    rc = main(["scene", "static", "--duration", "1", "--rate", "10", "-o", str(tmp_path / "f.txt" / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1 and "f.txt" in err[0] and "Traceback" not in err[0]
    rc = main(["scene", "static", "--duration", "1", "--rate", "10", "-o", str(tmp_path / ("x" * 300))])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1 and "too long" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.txt"]


def test_every_library_error_is_a_value_error_of_the_family(tmp_path):
    from splineimu.io.tum import read_tum

    p = tmp_path / "p.tum"
    p.write_text("1 2 3\n")
    with pytest.raises(SplineImuError) as info:
        read_tum(p)
    assert isinstance(info.value, ValueError) and info.value.path == str(p) and info.value.line == 1


# ------------------------------------------------------------------ deterministic bytes


def _folder_bytes(d):
    return {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("kind", ["scene", "poses"])
def test_same_job_twice_gives_the_same_bytes(tmp_path, kind):
    from splineimu.api import ImuOptions, OutputOptions, PosesInput, SceneInput, SynthesisJob, run_job

    poses = tmp_path / "p.tum"
    poses.write_text(_tum(200))
    motion = SceneInput("ellipse", duration_s=1.0) if kind == "scene" else PosesInput("p.tum")
    cwd = os.getcwd()
    os.chdir(tmp_path)  # relative paths, as a user types them
    try:
        for out in ("a", "b"):
            run_job(SynthesisJob(motion, ImuOptions(rate_hz=100, model="adis16448", seed=5), OutputOptions(out)))
    finally:
        os.chdir(cwd)
    a, b = _folder_bytes(tmp_path / "a"), _folder_bytes(tmp_path / "b")
    assert a.keys() == b.keys() and "report.json" in a
    assert [k for k in a if a[k] != b[k]] == []
    assert str(tmp_path).encode() not in a["report.json"]
