"""Atomic output folders and files, and the lossless table formatter.

format_table's contract: ``float(text) == value`` bit for bit for every finite double;
values with a decimal of <= 15 significant digits are written in that shortest form,
others with the 17 correctly rounded digits of ``"%.17e"`` (compared digit for digit).
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from splineimu.errors import OutputExistsError
from splineimu.io.files import OutputFolder, atomic_write_bytes, atomic_write_text, check_output_dir
from splineimu.io.tables import format_table


def listing(folder):
    return sorted(os.listdir(folder))


# ---------------------------------------------------------------------------------------
# OutputFolder


def test_output_folder_success(tmp_path):
    out = tmp_path / "sub" / "out"
    with OutputFolder(out) as tmp:
        assert tmp.parent == out.parent and tmp.name.startswith(".out.tmp-")
        assert not out.exists()  # nothing visible until the block ends
        (tmp / "imu0").mkdir()
        (tmp / "imu0" / "data.csv").write_text("x")
    assert listing(out.parent) == ["out"]
    assert (out / "imu0" / "data.csv").read_text() == "x"
    assert oct(out.stat().st_mode & 0o777) == oct(0o777 & ~_umask())


def _umask():
    m = os.umask(0)
    os.umask(m)
    return m


def test_output_folder_failure_leaves_nothing(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(RuntimeError, match="boom"):
        with OutputFolder(out) as tmp:
            (tmp / "half.csv").write_text("partial")
            raise RuntimeError("boom")
    assert listing(tmp_path) == []
    with pytest.raises(ValueError):
        with OutputFolder(tmp_path / "a" / "b" / "out"):
            raise ValueError
    assert listing(tmp_path) == []  # parents made for the output are gone too


def test_output_folder_refuses_non_empty_without_force(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("keep me")
    with pytest.raises(OutputExistsError) as ei:
        OutputFolder(out)  # fails at construction, before any work
    assert str(ei.value) == f"output folder '{out}' exists and is not empty; use --force to replace it"
    with pytest.raises(OutputExistsError):
        check_output_dir(out)
    assert listing(out) == ["old.txt"] and (out / "old.txt").read_text() == "keep me"
    (tmp_path / "file").write_text("f")
    with pytest.raises(OutputExistsError, match="not a folder"):
        check_output_dir(tmp_path / "file")


def test_output_folder_empty_existing_is_fine(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    with OutputFolder(out) as tmp:
        (tmp / "a").write_text("1")
    assert listing(out) == ["a"] and listing(tmp_path) == ["out"]


def test_output_folder_force_replaces(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with OutputFolder(out, force=True) as tmp:
        (tmp / "new.txt").write_text("new")
        assert (out / "old.txt").exists()  # old output untouched while working
    assert listing(out) == ["new.txt"]
    assert listing(tmp_path) == ["out"]  # the moved-aside folder is deleted


def test_output_folder_force_failure_keeps_old(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with OutputFolder(out, force=True) as tmp:
            (tmp / "new.txt").write_text("new")
            raise KeyboardInterrupt
    assert listing(out) == ["old.txt"] and listing(tmp_path) == ["out"]


def test_output_folder_something_appeared_meanwhile(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(OutputExistsError):
        with OutputFolder(out) as tmp:
            (tmp / "new.txt").write_text("new")
            out.mkdir()
            (out / "other.txt").write_text("someone else")
    assert listing(out) == ["other.txt"] and listing(tmp_path) == ["out"]


# ---------------------------------------------------------------------------------------
# single files


def test_atomic_write_replaces_and_cleans_up(tmp_path):
    p = tmp_path / "a.txt"
    atomic_write_text(p, "one\n")
    atomic_write_text(p, "two\n")
    assert p.read_text() == "two\n" and listing(tmp_path) == ["a.txt"]
    with pytest.raises(TypeError):
        atomic_write_bytes(p, "not bytes")  # fails inside the write
    assert p.read_text() == "two\n" and listing(tmp_path) == ["a.txt"]


# ---------------------------------------------------------------------------------------
# format_table


def _fields(b: bytes, sep=","):
    return [line.split(sep) for line in b.decode().splitlines()]


def test_format_table_examples():
    t = np.array([1403715524907143168, 0, -1])
    v = np.array([[0.1, -9.81, 1 / 3], [0.0, -0.0, 1e-7], [1e17, 123456.0, 2.5e-5]])
    rows = _fields(format_table(t, v))
    assert rows == [
        ["1403715524907143168", "0.1", "-9.81", "0.33333333333333331"],
        ["0", "0", "-0", "1e-07"],
        ["-1", "1e+17", "123456", "0.000025"],
    ]
    s = format_table(np.array([1305031102175304000, -1_500_000_000, 5]), np.zeros((3, 1)),
                     sep=" ", stamp="s")
    assert s == b"1305031102.175304000 0\n-1.500000000 0\n0.000000005 0\n"


def test_format_table_python_fallback_for_huge_values():
    v = np.array([[1e300, -2.0**70, 0.5]])
    assert _fields(format_table(np.array([7]), v)) == [["7", "1e+300", "-1.1805916207174113e+21", "0.5"]]


def test_format_table_rejects_bad_input():
    with pytest.raises(ValueError, match="finite"):
        format_table(np.array([0]), np.array([[np.inf]]))
    with pytest.raises(ValueError, match="integer"):
        format_table(np.array([0.5]), np.array([[1.0]]))
    with pytest.raises(ValueError, match="shape"):
        format_table(np.array([0, 1]), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="sep"):
        format_table(np.array([0]), np.zeros((1, 1)), sep=", ")


def _check_values(x):
    b = format_table(np.zeros(len(x), dtype=np.int64), np.asarray(x, dtype=float).reshape(-1, 1))
    texts = [row[1] for row in _fields(b)]
    for xi, s in zip(np.asarray(x, dtype=float).tolist(), texts):
        assert float(s) == xi and math.copysign(1, float(s)) == math.copysign(1, xi), (xi, s)
        mant = s.lstrip("-").split("e")[0].replace(".", "").lstrip("0").rstrip("0") or "0"
        if len(mant) > 15:  # the exact path: must be the digits of %.17e
            ref = ("%.16e" % abs(xi)).split("e")[0].replace(".", "").rstrip("0")
            assert mant == ref, (xi, s)
        elif abs(xi) >= 1e-300:  # (subnormals excepted) shortest: repr cannot be shorter
            r = repr(abs(xi)).split("e")[0].replace(".", "").lstrip("0").rstrip("0")
            assert len(mant) <= max(len(r), 1), (xi, s)


def test_format_table_lossless_across_magnitudes():
    rng = np.random.default_rng(7)
    n = 20000
    x = rng.uniform(-10, 10, n) * 10.0 ** rng.integers(-320, 18, n).astype(float)
    x = np.concatenate([
        x[np.isfinite(x)],
        rng.normal(size=n),
        np.round(rng.normal(size=n), 6),  # real-data-like: short decimals
        [5e-324, 2.2250738585072014e-308, 1e17, 99999999999999999.0, 8.99e18, 9.9999999999999995e-6,
         1e-5, 0.5, 1.0, 2.0**53 + 2, 1e16, 1e15 - 1, 0.1 + 0.2, 1 / 3, 2 / 3],
        # exact halfway cases of the 17th digit (round half to even): n + 0.25 / 0.75 at 1e15,
        # n + 1/8 .. 7/8 at 1e14, and the same scaled by powers of two
        rng.integers(10**15, 9 * 10**15, 500) + rng.choice([0.25, 0.75], 500),
        rng.integers(10**14, 9 * 10**14, 500) + rng.choice([0.125, 0.375, 0.625, 0.875], 500),
        (rng.integers(10**15, 9 * 10**15, 500) + 0.75) * 2.0 ** rng.integers(-60, -1, 500),
    ])
    _check_values(x)


@given(st.floats(allow_nan=False, allow_infinity=False, min_value=-8.9e18, max_value=8.9e18))
def test_format_table_lossless_hypothesis(x):
    _check_values([x])


def test_table_writer_works_in_a_forked_child(tmp_path):
    """Monte-Carlo runs fork workers after the parent has written outputs: the child must not
    wait on the parent's formatting threads (which it does not have)."""
    import multiprocessing as mp

    from splineimu.io.tables import CHUNK_ROWS, TableWriter

    t = np.arange(3 * CHUNK_ROWS, dtype=np.int64)
    v = np.random.default_rng(0).normal(size=(t.size, 2))
    with TableWriter(tmp_path / "parent.csv") as w:  # starts the pool in this process
        w.write(t, v)
    ctx = mp.get_context("fork")
    with ctx.Pool(1) as pool:
        res = pool.apply_async(_write_in_child, (str(tmp_path / "child.csv"), t, v))
        res.get(timeout=30)
    assert (tmp_path / "child.csv").read_bytes() == (tmp_path / "parent.csv").read_bytes()


def _write_in_child(path, t, v):
    from splineimu.io.tables import TableWriter

    with TableWriter(path) as w:
        w.write(t, v)
