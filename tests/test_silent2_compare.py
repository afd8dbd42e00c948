"""`splineimu compare` reads the TUM files the other commands read (tabs, runs of spaces).

evo's reader refuses any row not separated by single spaces ("TUM trajectory files must
have 8 entries per row and no trailing delimiter ..."), so a tab-separated trajectory that
from-tum reads was refused by compare. The files are now read by splineimu's TUM reader
and handed to evo as trajectory objects, with the values evo's own reader gives.
"""

from __future__ import annotations

import numpy as np
import pytest

from splineimu import cli
from splineimu.api.compare import compare_files, load_tum
from splineimu.errors import InputError

pytest.importorskip("evo")


def _write(path, sep, t, p, q, extra=""):
    rows = (sep.join(repr(float(x)) for x in (t[i], *p[i], *q[i])) + extra for i in range(len(t)))
    path.write_text("# timestamp tx ty tz qx qy qz qw\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture
def poses():
    rng = np.random.default_rng(3)
    t = 1_600_000_000.0 + np.arange(200) * 0.05 + rng.uniform(-1e-3, 1e-3, 200)
    p = np.c_[np.cos(t - t[0]), np.sin(t - t[0]), 0.1 * (t - t[0])]
    half = 0.5 * (t - t[0])
    q = np.c_[np.zeros(200), np.zeros(200), np.sin(half), np.cos(half)]
    return t, p, q


def test_tabs_and_runs_of_spaces_are_read_as_evo_reads_single_spaces(tmp_path, poses, capsys):
    from evo.tools import file_interface

    t, p, q = poses
    ref = _write(tmp_path / "ref.tum", " ", t, p, q)
    est = _write(tmp_path / "est.tum", " ", t, p + [0.0, 0.3, 0.4], q)
    tab = _write(tmp_path / "est_tab.tum", "\t", t, p + [0.0, 0.3, 0.4], q)
    spaced = _write(tmp_path / "ref_spaced.tum", "   ", t, p, q)
    theirs = file_interface.read_tum_trajectory_file(str(ref))
    with pytest.raises(Exception, match="TUM trajectory files must have 8 entries per row"):
        file_interface.read_tum_trajectory_file(str(tab))  # what compare answered
    ours = load_tum(spaced)
    np.testing.assert_array_equal(ours.timestamps, theirs.timestamps)
    np.testing.assert_array_equal(ours.positions_xyz, theirs.positions_xyz)
    np.testing.assert_array_equal(ours.orientations_quat_wxyz, theirs.orientations_quat_wxyz)
    a = compare_files(tab, spaced, metric="both", align="none")
    b = compare_files(est, ref, metric="both", align="none")
    assert a.ape.stats == b.ape.stats and a.rpe.stats == b.rpe.stats
    assert a.ape.stats["rmse"] == pytest.approx(0.5, abs=1e-12) and a.n_associated == 200
    assert cli.main(["compare", str(tab), str(spaced)]) == 0
    assert "      rmse\t0.500000" in capsys.readouterr().out


def test_reader_notices_and_negative_stamps(tmp_path):
    ref = tmp_path / "ref.tum"
    ref.write_text("-0.5\t0 0 0\t0 0 0 1\n-0.5\t0 0 0\t0 0 0 1\n0.25 1 0 0 0 0 0 1\n1.0 2 0 0 0 0 0 1\n")
    assert load_tum(ref).timestamps.tolist() == [-0.5, 0.25, 1.0]
    r = compare_files(ref, ref)
    assert r.notes == [f"{ref}: dropped 1 exact duplicate row (line 2)"] * 2
    bad = tmp_path / "bad.tum"
    bad.write_text("0.0\t0 0 0 0 0 0 1\n0.1\t0 0 nan 0 0 0 1\n")
    with pytest.raises(InputError) as e:
        compare_files(bad, ref)
    assert str(e.value).startswith(f"{bad}:2: ")
