"""Property-based fuzzing of every reader and of the scene-file loader (hypothesis).

Random bytes and random mutations of valid files must either be read or be refused with an
error of the splineimu family (a ValueError with the file, and the line where one applies);
nothing else may escape, and nothing may be written beside the input. The default suite runs
a few dozen examples per reader; ``pytest -m slow`` runs many more.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from splineimu.errors import SplineImuError

VALID = {
    "tum": b"# timestamp tx ty tz qx qy qz qw\n" + b"".join(
        b"1700000000.%02d0000000 %d.5 0.25 1 0 0 0.0998 0.9950\n" % (i, i) for i in range(12)),
    "euroc_gt": b"#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [],"
                b" v x, v y, v z, bw x, bw y, bw z, ba x, ba y, ba z\n" + b"".join(
        b"14037155249%02d000000,%d.5,0.25,1,0.995,0,0,0.0998,0,0,0,0,0,0,0,0,0\n" % (i * 5, i) for i in range(12)),
    "imu_csv": b"#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
               b"a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n" + b"".join(
        b"%d,0.001,-0.002,0.0005,0.01,-0.02,9.81\n" % (1000000000 + 5000000 * i) for i in range(12)),
    "imu_yaml": b"%YAML 1.1\n---\ngyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\n"
                b"accelerometer_noise_density: 2.0e-3\naccelerometer_random_walk: 3.0e-3\nupdate_rate: 200.0\n"
                b"rostopic: /imu0\n",
    "extrinsic": b"T_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.0,\n"
                 b"         0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n",
    "scene": b"motion:\n  scene: static\n  duration_s: 1\nimu:\n  rate_hz: 20\n  model: {gyroscope_noise_density: 0.01,"
             b" accelerometer_noise_density: 0.02, gyroscope_random_walk: 0.0, accelerometer_random_walk: 0.0}\n"
             b"seed: 3\noutput:\n  dir: out\n",
}
VALID["timestamps"] = VALID["imu_csv"]
VALID["yaml"] = VALID["scene"]

TOKENS = [b"nan", b"inf", b"-inf", b"-1", b"0", b"1e400", b"", b"\x00", b"\xff\xfe", b"&a", b"*a", b"[[[[", b"{",
          b":", b",", b" ", b"\n", b"\t", b"#", b"1" * 30, b"-", b".", b"e", b"null", b"~",
          b"!!python/object:os.system", b"%YAML:1.0\n", b"---\n", b"'", b'"', b"\r\n"]


@st.composite
def mutated(draw, valid: bytes):
    data = bytearray(valid)
    for _ in range(draw(st.integers(1, 6))):
        op = draw(st.sampled_from(["replace", "insert", "delete", "token", "dup_line", "truncate"]))
        pos = draw(st.integers(0, max(len(data) - 1, 0)))
        if op == "replace" and data:
            data[pos] = draw(st.integers(0, 255))
        elif op == "insert":
            data[pos:pos] = draw(st.binary(min_size=1, max_size=8))
        elif op == "delete":
            del data[pos:pos + draw(st.integers(1, 20))]
        elif op == "token":
            data[pos:pos + draw(st.integers(0, 6))] = draw(st.sampled_from(TOKENS))
        elif op == "dup_line":
            lines = bytes(data).split(b"\n")
            i = draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i])
            data = bytearray(b"\n".join(lines))
        else:
            del data[pos:]
    return bytes(data)


def _inputs(kind):
    return st.one_of(st.binary(max_size=600), mutated(VALID[kind]), mutated(VALID[kind]))


def _read(kind, path: Path):
    if kind == "tum":
        from splineimu.io.tum import read_tum

        return read_tum(path)
    if kind == "euroc_gt":
        from splineimu.io.euroc import read_euroc_groundtruth

        return read_euroc_groundtruth(path)
    if kind == "imu_csv":
        from splineimu.io.imu_csv import read_imu_table

        return read_imu_table(path)
    if kind == "timestamps":
        from splineimu.io.timestamps import read_timestamps

        return read_timestamps(path)
    if kind == "yaml":
        from splineimu.io.yaml import read_yaml

        return read_yaml(path)
    if kind == "imu_yaml":
        from splineimu.imu.config import load_imu_config
        from splineimu.io.imu_yaml import read_imu_yaml

        read_imu_yaml(path)
        return load_imu_config(str(path))
    if kind == "extrinsic":
        from splineimu.imu.ideal import Extrinsic

        return Extrinsic.from_file(path)
    if kind == "scene":
        from splineimu.api.scenefile import load_scene_file

        return load_scene_file(path)
    raise AssertionError(kind)


NAMES = {"tum": "p.tum", "euroc_gt": "gt.csv", "imu_csv": "imu.csv", "timestamps": "s.csv", "yaml": "c.yaml",
         "imu_yaml": "imu.yaml", "extrinsic": "e.yaml", "scene": "s.yaml"}


def _check(kind, data: bytes):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / NAMES[kind]
        path.write_bytes(data)
        try:
            _read(kind, path)
        except SplineImuError as exc:
            assert isinstance(exc, ValueError) and str(exc).strip(), repr(exc)
            assert "\n" not in exc.problem.strip() or len(exc.problem.splitlines()) <= 3
        assert os.listdir(d) == [path.name]  # nothing written beside the input


def _fuzz(kind, n):
    @settings(max_examples=n, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(data=_inputs(kind))
    def run(data):
        _check(kind, data)

    run()


@pytest.mark.parametrize("kind", sorted(NAMES))
def test_readers_raise_only_the_error_family(kind):
    _fuzz(kind, 30)


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(NAMES))
def test_readers_raise_only_the_error_family_long(kind):
    _fuzz(kind, 2000)


@settings(max_examples=12, suppress_health_check=[HealthCheck.too_slow])
@given(data=mutated(VALID["scene"]))
def test_scene_files_run_completely_or_leave_nothing(data):
    """A mutated scene file either writes its whole output folder or fails and leaves nothing."""
    from splineimu.api import run_job
    from splineimu.api.scenefile import load_scene_file

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "s.yaml"
        path.write_bytes(data)
        try:
            job = load_scene_file(path)
            run_job(job)
        except SplineImuError:
            assert os.listdir(d) == ["s.yaml"]
            return
        out = Path(job.output.dir)
        if out.is_dir():
            assert (out / "report.json").is_file()
        assert not [p for p in Path(d).rglob(".*") if ".tmp-" in p.name]
