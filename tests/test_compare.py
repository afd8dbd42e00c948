"""`splineimu compare` / splineimu.metrics against evo's own evo_ape / evo_rpe."""

from __future__ import annotations

import contextlib
import io
import logging
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import require_shared

from splineimu import cli
from splineimu.api.compare import compare, compare_files
from splineimu.errors import ConfigError, InputError, SplineImuError
from splineimu.lie import matrix_to_quat_xyzw, quat_xyzw_to_matrix, so3_exp
from splineimu.metrics import EVO_MISSING
from splineimu.scenes import make_scene

pytest.importorskip("evo")


def run_evo(tool, argv):
    """Run evo_ape / evo_rpe's own CLI code in-process; return what it prints."""
    if tool == "ape":
        from evo.cli import ape as mod
        from evo.cli import ape_parser as par
    else:
        from evo.cli import rpe as mod
        from evo.cli import rpe_parser as par
    args = par.parser().parse_args(argv)
    # evo's configure_logging replaces only the first handler of the "evo" logger; under pytest
    # that may be a capture handler, so start from none (as a fresh evo_ape process does).
    lg = logging.getLogger("evo")
    saved = lg.handlers[:]
    lg.handlers.clear()
    buf = io.StringIO()
    try:
        with contextlib.redirect_stdout(buf):
            mod.run(args)
    finally:
        lg.handlers[:] = saved
    return buf.getvalue()


def write_tum(path, t, p, q):
    with open(path, "w") as fh:
        fh.write("# timestamp tx ty tz qx qy qz qw\n")
        for i in range(len(t)):
            fh.write(" ".join(repr(float(x)) for x in (t[i], *p[i], *q[i])) + "\n")
    return path


def perturbed(t, p, q, rng, *, scale=1.07, pos_noise=0.05, rot_noise=0.02, t_jitter=0.003, step=1):
    """An 'estimate': every `step`-th pose, noisy, in another frame, with scale and stamp jitter."""
    idx = np.arange(0, len(t), step)
    R = quat_xyzw_to_matrix(q[idx]) @ so3_exp(rng.normal(scale=rot_noise, size=(idx.size, 3)))
    pn = p[idx] + rng.normal(scale=pos_noise, size=(idx.size, 3))
    Rg = so3_exp(np.array([0.2, -0.4, 1.1]))
    tg = np.array([3.0, -2.0, 0.5]) + p[0]
    p_est = scale * pn @ Rg.T + tg
    R_est = Rg @ R
    return t[idx] + rng.uniform(-t_jitter, t_jitter, idx.size), p_est, matrix_to_quat_xyzw(R_est)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cmp")
    scene = make_scene("ellipse", duration_s=20.0, t0_ns=1_600_000_000_000_000_000)
    t_ns = scene.sample_times_ns(50.0)
    k = scene.kinematics(scene.t_s_from_ns(t_ns))
    t = t_ns / 1e9
    ref = write_tum(d / "ref.tum", t, k.position_world, k.quat_xyzw)
    rng = np.random.default_rng(5)
    te, pe, qe = perturbed(t, k.position_world, k.quat_xyzw, rng, step=2)
    est = write_tum(d / "est.tum", te, pe, qe)
    shifted = write_tum(d / "est_shifted.tum", te + 0.51, pe, qe)  # half a ref step off
    return {"ref": str(ref), "est": str(est), "shifted": str(shifted), "dir": d}


EVO_RELATION = {"trans": "trans_part", "rot": "rot_part", "full": "full", "angle_deg": "angle_deg",
                "angle_rad": "angle_rad", "point_distance": "point_distance"}
EVO_ALIGN = {"none": [], "se3": ["-a"], "sim3": ["-a", "-s"], "origin": ["--align_origin"]}


@pytest.mark.parametrize("align", ["none", "se3", "sim3", "origin"])
@pytest.mark.parametrize("relation", ["trans", "rot", "full", "angle_deg"])
def test_ape_equals_evo_ape(files, align, relation):
    ours = compare(files["est"], files["ref"], metric="ape", pose_relation=relation, align=align)
    theirs = run_evo("ape", ["tum", files["ref"], files["est"], "-r", EVO_RELATION[relation],
                             *EVO_ALIGN[align]])
    assert ours.ape.pretty_str() + "\n" == theirs
    assert ours.n_associated == 501


@pytest.mark.parametrize(
    "align, relation, delta, unit, extra",
    [
        ("none", "trans", 1, "f", []),
        ("se3", "trans", 10, "f", []),
        ("sim3", "trans", 2.0, "m", []),
        ("se3", "angle_deg", 5, "f", ["--all_pairs"]),
        ("origin", "rot", 20.0, "d", []),
        ("none", "full", 0.5, "r", []),
        ("sim3", "point_distance", 25, "f", []),
    ],
)
def test_rpe_equals_evo_rpe(files, align, relation, delta, unit, extra):
    ours = compare(files["est"], files["ref"], metric="rpe", pose_relation=relation, align=align,
                   delta=delta, delta_unit=unit, all_pairs=bool(extra))
    theirs = run_evo("rpe", ["tum", files["ref"], files["est"], "-r", EVO_RELATION[relation],
                             *EVO_ALIGN[align], "-d", str(delta), "-u", unit, *extra])
    assert ours.rpe.pretty_str() + "\n" == theirs
    assert ours.rpe.errors.size == ours.rpe.timestamps_s.size > 0


def test_full_precision_equals_evo_library(files):
    # beyond the printed digits: the same floats as evo's main_ape / main_rpe
    from evo.core import metrics as em
    from evo.core import sync
    from evo.main_ape import ape
    from evo.main_rpe import rpe
    from evo.tools import file_interface

    ours = compare(files["est"], files["ref"], metric="both", align="sim3", delta=5)
    for fn, kw, mine in ((ape, {}, ours.ape), (rpe, {"delta": 5, "delta_unit": em.Unit.frames}, ours.rpe)):
        r, e = sync.associate_trajectories(file_interface.read_tum_trajectory_file(files["ref"]),
                                           file_interface.read_tum_trajectory_file(files["est"]))
        res = fn(r, e, em.PoseRelation.translation_part, align=True, correct_scale=True, **kw)
        assert res.stats == mine.stats
        np.testing.assert_array_equal(res.np_arrays["error_array"], mine.errors)
    a = ours.alignment_sim3
    s = np.cbrt(np.linalg.det(a[:3, :3]))
    assert abs(s - 1 / 1.07) < 0.01  # the scale put into the estimate is recovered


def test_association_options_equal_evo(files):
    for opts, evo_opts in (
        ({"t_offset": -0.51}, ["--t_offset", "-0.51"]),
        ({"t_offset": -0.51, "t_max_diff": 0.002}, ["--t_offset", "-0.51", "--t_max_diff", "0.002"]),
    ):
        ours = compare(files["shifted"], files["ref"], align="se3", **opts)
        theirs = run_evo("ape", ["tum", files["ref"], files["shifted"], "-a", *evo_opts])
        assert ours.ape.pretty_str() + "\n" == theirs
    # fewer associations with the tighter window; none without the offset
    n = compare(files["shifted"], files["ref"], t_offset=-0.51, t_max_diff=0.002).n_associated
    assert 100 < n < 400  # stamps jitter +-3 ms
    with pytest.raises(ConfigError, match="found no matching timestamps"):
        compare(files["shifted"], files["ref"], t_max_diff=0.005)  # all 10 +- 3 ms off


def test_delta_in_seconds_is_frames(files):
    ours = compare(files["est"], files["ref"], metric="rpe", delta=1.0, delta_unit="s")
    assert ours.rpe.delta_frames == 25  # est poses every 40 ms
    theirs = run_evo("rpe", ["tum", files["ref"], files["est"], "-d", "25", "-u", "f"])
    assert ours.rpe.pretty_str() + "\n" == theirs
    d = files["dir"]
    t = np.r_[np.arange(10) * 0.1, 1.0 + np.arange(10) * 0.3]
    p, q = np.zeros((20, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (20, 1))
    p[:, 0] = t
    uneven = write_tum(d / "uneven.tum", t, p, q)
    with pytest.raises(ConfigError, match="evenly spaced"):
        compare(str(uneven), str(uneven), metric="rpe", delta=1.0, delta_unit="s")


def test_cli_matches_evo_executables(files, capsys):
    """The whole chain: `splineimu compare` output vs the evo_ape / evo_rpe programs."""
    rc = cli.main(["compare", files["est"], files["ref"], "--metric", "both", "--align", "sim3",
                   "--pose-relation", "angle_deg", "--delta", "3", "--delta-unit", "m"])
    assert rc == 0
    ours = capsys.readouterr().out
    bindir = Path(sys.executable).parent
    outs = []
    for tool, extra in (("evo_ape", []), ("evo_rpe", ["-d", "3", "-u", "m"])):
        exe = bindir / tool
        if not exe.exists():
            pytest.skip(f"{exe} not found")
        proc = subprocess.run([str(exe), "tum", files["ref"], files["est"], "-a", "-s", "-r", "angle_deg",
                               *extra, "--no_warnings"], capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr
        outs.append(proc.stdout)
    assert ours == "".join(outs)


def test_plot(files, tmp_path, capsys):
    png = tmp_path / "cmp.png"
    assert cli.main(["compare", files["est"], files["ref"], "--metric", "both", "--align", "se3",
                     "--plot", str(png)]) == 0
    assert "plot saved to" in capsys.readouterr().out
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_compare_files_with_plot_and_tables(files, tmp_path):
    png = tmp_path / "c.png"
    r = compare_files(Path(files["est"]), Path(files["ref"]), plot=png, metric="both", align="se3",
                      delta=1.0, delta_unit="s")
    b = compare(files["est"], files["ref"], metric="both", align="se3", delta=1.0, delta_unit="s")
    assert r.ape.stats == b.ape.stats and r.rpe.stats == b.rpe.stats
    assert r.plot_path == png and png.read_bytes()[:4] == b"\x89PNG" and b.plot_path is None
    df = r.to_dataframe()
    assert df["metric"].tolist() == ["ape", "rpe"] and df["delta_frames"].tolist()[1] == r.rpe.delta_frames
    assert df.loc[0, "rmse"] == r.ape.stats["rmse"] and df.loc[1, "max"] == r.rpe.stats["max"]
    errs = r.rpe.to_dataframe()
    assert list(errs.columns) == ["t_s", "error"] and errs["error"].max() == r.rpe.stats["max"]


def test_trajectory_objects_and_tuples(files):
    # in-memory input: integrate-like objects or tuples give the same numbers as the files
    from evo.tools import file_interface

    tr = file_interface.read_tum_trajectory_file(files["est"])
    rf = file_interface.read_tum_trajectory_file(files["ref"])
    est = (tr.timestamps, tr.positions_xyz, tr.orientations_quat_wxyz[:, [1, 2, 3, 0]])
    ref = (rf.timestamps, rf.positions_xyz, rf.orientations_quat_wxyz[:, [1, 2, 3, 0]])
    a = compare(est, ref, metric="both", align="se3")
    b = compare(files["est"], files["ref"], metric="both", align="se3")
    assert a.ape.stats == b.ape.stats and a.rpe.stats == b.rpe.stats
    # known answer: a constant 0.1 m offset, unaligned
    t = np.arange(10.0)
    p = np.c_[t, np.zeros(10), np.zeros(10)]
    q = np.tile([0.0, 0.0, 0.0, 1.0], (10, 1))
    r = compare((t, p + [0.0, 0.1, 0.0], q), (t, p, q), metric="both")
    assert abs(r.ape.stats["rmse"] - 0.1) < 1e-15 and r.rpe.stats["max"] < 1e-15


def test_errors(files, tmp_path, capsys, monkeypatch):
    with pytest.raises(InputError, match="no such file"):
        compare(str(tmp_path / "missing.tum"), files["ref"])
    bad = tmp_path / "bad.tum"
    bad.write_text("1.0 2 3\n")
    with pytest.raises(InputError, match=r"bad.tum:1: expected 8 columns \(timestamp tx ty tz qx qy qz qw\), got 3"):
        compare(str(bad), files["ref"])
    assert cli.main(["compare", str(bad), files["ref"]]) == 1
    err = capsys.readouterr().err
    assert err.startswith("splineimu compare: error: ") and err.count("\n") == 1
    with pytest.raises(ConfigError, match="produced an empty index list"):
        compare(files["est"], files["ref"], metric="rpe", delta=1e6, delta_unit="m")
    with pytest.raises(ConfigError, match="whole number"):
        compare(files["est"], files["ref"], metric="rpe", delta=1.5, delta_unit="f")
    with pytest.raises(ConfigError, match="`align` must be one of none, se3, sim3, origin, got 'umeyama'"):
        compare(files["est"], files["ref"], align="umeyama")
    # evo missing -> the install hint
    for mod in [m for m in sys.modules if m == "evo" or m.startswith("evo.")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.setitem(sys.modules, "evo", None)
    with pytest.raises(SplineImuError) as exc:
        compare(files["est"], files["ref"])
    assert str(exc.value) == EVO_MISSING == "splineimu compare needs evo: pip install 'splineimu[evo]'"


@pytest.mark.parametrize("name", ["misc/georeferenced.tum", "tum_rgbd/freiburg1_xyz-groundtruth.txt"])
def test_real_trajectories_equal_evo(name, tmp_path):
    """Real reference files (evo's georeferenced test data: UTM-sized coordinates; TUM RGB-D fr1_xyz,
    CC BY 4.0) against a perturbed copy, for every alignment."""
    ref = require_shared(*name.split("/"))
    from evo.tools import file_interface

    tr = file_interface.read_tum_trajectory_file(str(ref))
    rng = np.random.default_rng(11)
    t, p, q = perturbed(tr.timestamps, tr.positions_xyz, tr.orientations_quat_wxyz[:, [1, 2, 3, 0]], rng,
                        pos_noise=0.01, t_jitter=0.002)
    est = write_tum(tmp_path / "est.tum", t, p, q)
    for align in ("none", "se3", "sim3", "origin"):
        ours = compare(str(est), str(ref), metric="both", align=align, delta=2)
        theirs = run_evo("ape", ["tum", str(ref), str(est), *EVO_ALIGN[align]])
        theirs += run_evo("rpe", ["tum", str(ref), str(est), *EVO_ALIGN[align], "-d", "2"])
        assert ours.pretty_str() + "\n" == theirs


def test_nan_time_offset_is_refused_by_name(tmp_path):
    """--t-offset nan reached evo and was reported as 'found no matching timestamps'."""
    from splineimu.metrics import check_compare_options

    with pytest.raises(ConfigError, match="`t_offset` must be finite, got nan"):
        check_compare_options(t_offset=float("nan"))
    ref = tmp_path / "ref.tum"
    ref.write_text("".join(f"{i}.0 {i} 0 0 0 0 0 1\n" for i in range(5)))
    with pytest.raises(ConfigError, match="t_offset"):
        compare_files(ref, ref, t_offset=float("nan"))


def test_a_euroc_csv_given_to_compare_is_named(tmp_path):
    """A EuRoC ground truth or IMU csv given to compare got evo's 'TUM trajectory files must
    have 8 entries per row' only; the message now says what the file looks like and what to give."""
    gt = tmp_path / "data.csv"
    gt.write_text("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w []\n"
                  + "".join(f"{i * 5000000},0,0,0,1,0,0,0" + ",0" * 9 + "\n" for i in range(5)))
    ref = tmp_path / "ref.tum"
    ref.write_text("".join(f"{i}.0 {i} 0 0 0 0 0 1\n" for i in range(5)))
    with pytest.raises(InputError) as e:
        compare_files(gt, ref)
    assert str(e.value).endswith("the file looks like a EuRoC ground-truth csv (ns, p xyz, q wxyz, ...): "
                                 "compare reads TUM trajectories, e.g. OUT/groundtruth.tum")


def test_plot_is_written_in_the_format_its_name_gives(tmp_path):
    """--plot out.pdf wrote PNG bytes under the .pdf name; the suffix now picks the format
    (PNG without one) and an unknown suffix is refused."""
    ref = tmp_path / "ref.tum"
    ref.write_text("".join(f"{i}.0 {i} 0 0 0 0 0 1\n" for i in range(5)))
    heads = {"a.pdf": b"%PDF", "a.png": b"\x89PNG", "a": b"\x89PNG"}
    for name, magic in heads.items():
        compare_files(ref, ref, plot=tmp_path / name)
        assert (tmp_path / name).read_bytes()[:4] == magic, name
    assert b"<svg" in compare_files(ref, ref, plot=tmp_path / "a.svg").plot_path.read_bytes()[:400]
    with pytest.raises(ConfigError, match=r"cannot write a plot as '\.txt'"):
        compare_files(ref, ref, plot=tmp_path / "a.txt")
    assert not (tmp_path / "a.txt").exists()


def test_few_associated_poses_are_noted(tmp_path, capsys):
    """An estimate stamped in milliseconds against a reference in seconds associated 1 of 399
    poses (stamp 0) and printed that one pair's APE as the result, without a word. (Integer
    nanoseconds counted from 0, the first case of this, are now refused by the TUM reader.)"""
    ref = tmp_path / "ref.tum"
    est = tmp_path / "est.tum"
    ref.write_text("".join(f"{i * 0.005:.3f} {i * 0.01} 0 0 0 0 0 1\n" for i in range(399)))
    est.write_text("".join(f"{i * 5_000_000} {i * 0.01 + 0.5} 0 0 0 0 0 1\n" for i in range(399)))  # 0.5 m off
    with pytest.raises(InputError, match=r"est\.tum:1: integer stamps step by 5000000 .* look like nanoseconds"):
        compare_files(est, ref)
    est.write_text("".join(f"{i * 5}.000 {i * 0.01 + 0.5} 0 0 0 0 0 1\n" for i in range(399)))  # ms, 0.5 m off
    r = compare_files(est, ref)
    assert r.n_associated == 1 and r.ape.stats["rmse"] == 0.5
    # the reader says what the estimate's stamps are in milliseconds; the association, how few it paired
    assert r.notes == [f"{est}: stamps counted from 0 step by 5 s (0.2 Hz; the poses span 33.2 min): if they are "
                       "milliseconds, the poses are 200 Hz over 1.99 s; TUM stamps are decimal seconds: divide the "
                       "column by 1000",
                       "only 1 of 399 estimated and 399 reference poses were associated: the stamps span "
                       "[0, 1990] s (estimate) and [0, 1.99] s (reference); check their units and --t-max-diff"]
    assert cli.main(["compare", str(est), str(ref)]) == 0
    err = capsys.readouterr().err
    assert err.startswith(f"note: {est}: stamps counted from 0") and "note: only 1 of 399 estimated" in err
    assert compare_files(ref, ref).notes == []


def test_zero_quaternion_and_empty_tum_are_named(tmp_path):
    """evo reads a [0, 0, 0, 0] quaternion (it gave 5.8 deg of rotation APE, silently) and
    answers a header-only file with 'TUM trajectory files must have 8 entries per row'."""
    ref = tmp_path / "ref.tum"
    ref.write_text("".join(f"{i}.0 {i} 0 0 0 0 0 1\n" for i in range(5)))
    zq = tmp_path / "zq.tum"
    zq.write_text("".join(f"{i}.0 {i} 0 0 0 0 0 {0 if i == 2 else 1}\n" for i in range(5)))
    with pytest.raises(InputError) as e:
        compare_files(zq, ref, pose_relation="angle_deg")
    assert str(e.value) == f"{zq}:3: quaternion has zero norm: [0, 0, 0, 0]"
    empty = tmp_path / "empty.tum"
    empty.write_text("# timestamp tx ty tz qx qy qz qw\n")
    with pytest.raises(InputError) as e:
        compare_files(empty, ref)
    assert str(e.value) == f"{empty}: no data rows (only comments, blank lines or a header)"


def test_a_folder_given_as_a_trajectory_is_named_a_folder(tmp_path):
    """A folder given to compare was reported as 'no such file'."""
    with pytest.raises(InputError) as e:
        compare_files(tmp_path, tmp_path)
    assert str(e.value) == f"{tmp_path}: is a folder, expected a TUM file"
