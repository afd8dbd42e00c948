"""One writer per format: the whole-file writers and the piece-by-piece writers make the same bytes."""

from __future__ import annotations

import os

import numpy as np
import pytest

from splineimu.io.euroc import (
    EUROC_GROUNDTRUTH_HEADER,
    EurocGroundtruthWriter,
    EurocImuWriter,
    read_euroc_groundtruth,
    write_euroc_groundtruth,
    write_euroc_imu,
)
from splineimu.io.files import OutputFolder, staged_path
from splineimu.io.tables import CHUNK_ROWS, format_table, write_table
from splineimu.io.tum import TUM_HEADER, TumWriter, read_tum, write_tum


def _record(n, seed=0):
    rng = np.random.default_rng(seed)
    t = 1_403_715_523_912_140_000 + np.arange(n, dtype=np.int64) * 5_000_000
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    g = rng.normal(size=(n, 3))
    g[::7, 1] = -0.0  # negative zeros are written as 0
    return dict(t=t, p=rng.normal(size=(n, 3)) * 10, q=q, v=rng.normal(size=(n, 3)), g=g,
                a=rng.normal(size=(n, 3)) + [0, 0, 9.81], bg=rng.normal(size=(n, 3)) * 1e-4,
                ba=rng.normal(size=(n, 3)) * 1e-3)


def _in_pieces(n, sizes=(1, 17, CHUNK_ROWS + 3)):
    """Slices that cover range(n) in uneven pieces (one longer than a formatting chunk)."""
    out, i, k = [], 0, 0
    while i < n:
        j = min(n, i + sizes[k % len(sizes)])
        out.append(slice(i, j))
        i, k = j, k + 1
    return out


@pytest.fixture(scope="module")
def rec():
    return _record(2 * CHUNK_ROWS + 101)


def test_tum_writer_equals_write_tum(tmp_path, rec):
    n = rec["t"].size
    write_tum(tmp_path / "whole.tum", rec["t"], rec["p"], rec["q"])
    with OutputFolder(tmp_path / "out") as tmp, TumWriter(tmp / "pieces.tum") as w:
        for s in _in_pieces(n):
            w.write_poses(rec["t"][s], rec["p"][s], rec["q"][s])
    whole = (tmp_path / "whole.tum").read_bytes()
    assert (tmp_path / "out" / "pieces.tum").read_bytes() == whole
    assert whole.startswith((TUM_HEADER + "\n").encode()) and whole.count(b"\n") == n + 1
    back = read_tum(tmp_path / "whole.tum")
    np.testing.assert_array_equal(back.t_ns, rec["t"])
    np.testing.assert_array_equal(back.positions, rec["p"])


def test_euroc_imu_writer_equals_write_euroc_imu(tmp_path, rec):
    write_euroc_imu(tmp_path / "whole.csv", rec["t"], rec["g"], rec["a"])
    with EurocImuWriter(tmp_path / "pieces.csv") as w:
        for s in _in_pieces(rec["t"].size):
            w.write_samples(rec["t"][s], rec["g"][s], rec["a"][s])
    whole = (tmp_path / "whole.csv").read_bytes()
    assert (tmp_path / "pieces.csv").read_bytes() == whole
    assert b",-0," not in whole and b",-0\n" not in whole
    rows = np.loadtxt(tmp_path / "whole.csv", delimiter=",", skiprows=1, usecols=range(1, 7))
    np.testing.assert_array_equal(rows, np.hstack([rec["g"], rec["a"]]))  # lossless


def test_euroc_groundtruth_writer_equals_write_euroc_groundtruth(tmp_path, rec):
    args = (rec["p"], rec["q"], rec["v"], rec["bg"], rec["ba"])
    write_euroc_groundtruth(tmp_path / "whole.csv", rec["t"], *args)
    with EurocGroundtruthWriter(tmp_path / "pieces.csv") as w:
        for s in _in_pieces(rec["t"].size):
            w.write_states(rec["t"][s], *(a[s] for a in args))
    whole = (tmp_path / "whole.csv").read_bytes()
    assert (tmp_path / "pieces.csv").read_bytes() == whole
    assert whole.splitlines()[0].decode() == EUROC_GROUNDTRUTH_HEADER
    back = read_euroc_groundtruth(tmp_path / "whole.csv")
    np.testing.assert_array_equal(back.velocity_world, rec["v"])
    np.testing.assert_array_equal(back.bias_accel, rec["ba"])


def test_writers_check_their_arguments(tmp_path):
    with pytest.raises(ValueError, match=r"Expected `accel` to have shape \(2, 3\), got \(2, 2\)"):
        write_euroc_imu(tmp_path / "x.csv", [1, 2], np.zeros((2, 3)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="`quat_xyzw` row 0 is a zero quaternion"):
        write_euroc_groundtruth(tmp_path / "x.csv", [1], [[0, 0, 0]], [[0, 0, 0, 0]], *[np.zeros((1, 3))] * 3)
    with pytest.raises(ValueError, match="integer nanoseconds"):
        write_tum(tmp_path / "x.tum", ["a"], [[0, 0, 0]], [[0, 0, 0, 1]])
    with TumWriter(tmp_path / "w.tum") as w, pytest.raises(ValueError, match="`positions` contains NaN"):
        w.write_poses([1], [[np.nan, 0, 0]], [[0, 0, 0, 1]])
    assert sorted(os.listdir(tmp_path)) == ["w.tum"]  # the failed whole-file writes left nothing


def test_write_table_is_header_then_format_table(tmp_path):
    t = np.array([3, 4], dtype=np.int64)
    v = np.array([[1.5, -2.0], [1e-7, 1e20]])
    p = write_table(tmp_path / "t.txt", t, v, "# t a b", sep=" ", stamp="s")
    assert p.read_bytes() == b"# t a b\n" + format_table(t, v, sep=" ", stamp="s")
    write_table(p, t[:1], v[:1])  # replaces the file
    assert p.read_bytes() == b"3,1.5,-2\n"


def test_staged_path_replaces_only_on_success(tmp_path):
    target = tmp_path / "result"
    with staged_path(target) as tmp:
        tmp.mkdir()
        (tmp / "a").write_text("1")
        assert not target.exists()
    assert (target / "a").read_text() == "1"
    with pytest.raises(RuntimeError, match="interrupted"), staged_path(target) as tmp:
        tmp.mkdir()
        (tmp / "b").write_text("2")
        raise RuntimeError("interrupted")
    assert os.listdir(tmp_path) == ["result"] and os.listdir(target) == ["a"]


def test_output_folder_dot_is_the_current_folder(tmp_path, monkeypatch):
    """`-o .` in an empty folder failed with "output folder '.' exists and is not empty": the
    temporary sibling of '.' (which has no name) was made inside it. '.' and '..' now stand
    for the folders they name."""
    from splineimu.errors import OutputExistsError
    from splineimu.io.files import OutputFolder

    (tmp_path / "sub").mkdir()
    monkeypatch.chdir(tmp_path / "sub")
    with OutputFolder(".") as tmp:
        (tmp / "a.txt").write_text("new")
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["a.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sub"]  # nothing left beside it
    monkeypatch.chdir(tmp_path / "sub")  # the new folder (the old one was replaced)
    with pytest.raises(OutputExistsError):
        OutputFolder(".")
    with OutputFolder("..", force=True) as tmp:
        (tmp / "b.txt").write_text("replaced")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.txt"]
