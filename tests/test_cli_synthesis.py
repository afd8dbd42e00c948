"""End-to-end: scene / from-tum / from-euroc through the command line."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import require_shared

from splineimu.cli import main
from splineimu.scenes import make_scene


def run_cli(*argv):
    return main([str(a) for a in argv])


def read_imu(path):
    from splineimu.io.imu_csv import read_imu_csv

    return read_imu_csv(path)


@pytest.fixture(scope="module")
def ellipse_tum(tmp_path_factory):
    d = tmp_path_factory.mktemp("ell")
    path = d / "ellipse.tum"
    assert run_cli("scene", "ellipse", "--duration", 12, "--rate", 100, "--t0-ns", 1_403_636_579_758_555_392,
                   "--tum", path) == 0
    return path


def test_scene_writes_the_output_layout(tmp_path, capsys):
    out = tmp_path / "out"
    assert run_cli("scene", "ellipse", "-o", out, "--duration", 5, "--rate", 200) == 0
    for f in ("mav0/imu0/data.csv", "mav0/state_groundtruth_estimate0/data.csv", "groundtruth.tum", "imu.yaml",
              "report.json"):
        assert (out / f).is_file(), f
    t_ns, gyro, acc = read_imu(out / "mav0" / "imu0" / "data.csv")
    assert t_ns.size == 1001 and t_ns[1] - t_ns[0] == 5_000_000
    g0, f0 = make_scene("ellipse", duration_s=5).imu(t_ns / 1e9)
    np.testing.assert_allclose(gyro, g0, atol=1e-15)
    np.testing.assert_allclose(acc, f0, atol=1e-13)
    rep = json.loads((out / "report.json").read_text())
    assert rep["imu"]["noise"] == "noise-free" and rep["source"]["name"] == "ellipse"
    assert "written" in capsys.readouterr().out


def test_static_scene_reads_plus_g(tmp_path):
    out = tmp_path / "s"
    assert run_cli("scene", "static", "-o", out, "--duration", 1) == 0
    _, gyro, acc = read_imu(out / "mav0" / "imu0" / "data.csv")
    assert np.all(gyro == 0) and np.allclose(acc, [0, 0, 9.81], atol=1e-15)


def test_from_tum_reproduces_the_scene(ellipse_tum, tmp_path, capsys):
    out = tmp_path / "out"
    assert run_cli("from-tum", ellipse_tum, "-o", out, "--rate", 200) == 0
    t_ns, gyro, acc = read_imu(out / "mav0" / "imu0" / "data.csv")
    origin = 1_403_636_579_758_555_392
    assert t_ns[0] == origin and (t_ns[-1] - origin) == 12_000_000_000
    g0, f0 = make_scene("ellipse", duration_s=12).imu((t_ns - origin) / 1e9)
    inner = slice(100, -100)
    assert np.sqrt(np.mean((gyro - g0)[inner] ** 2)) < 1e-4
    assert np.sqrt(np.mean((acc - f0)[inner] ** 2)) < 1e-2
    printed = capsys.readouterr().out
    assert "knot spacing" in printed and "fit residual" in printed
    rep = json.loads((out / "report.json").read_text())
    assert rep["spline"]["knot_spacing_source"] == "auto" and rep["spline"]["n_poses"] == 1201


def test_position_grid_given_apart_from_the_rotation(ellipse_tum, tmp_path):
    """--position-knot-spacing fixes the position grid while the rotation's is chosen (and
    --knot-spacing with --position-knot-spacing auto the reverse), as the library's fit does."""
    from splineimu import fit
    from splineimu.io import read_tum

    track = read_tum(ellipse_tum)
    for flags, kw, source in (
            (["--position-knot-spacing", 0.08, "--position-order", 4], {"position_knot_spacing_s": 0.08,
                                                                        "position_order": 4},
             "rotation auto, position given"),
            (["--knot-spacing", 0.05, "--position-knot-spacing", "auto"], {"knot_spacing_s": 0.05,
                                                                           "position_knot_spacing_s": "auto"},
             "rotation given, position auto")):
        out = tmp_path / source.replace(" ", "_").replace(",", "")
        assert run_cli("from-tum", ellipse_tum, "-o", out, *flags) == 0
        sp = json.loads((out / "report.json").read_text())["spline"]
        _, want = fit(track, return_report=True, **kw)
        assert sp["knot_spacing_source"] == source
        assert (sp["order"], sp["knot_spacing_s"]) == (want.order, pytest.approx(want.knot_spacing_s, rel=1e-12))
        assert (sp["position_order"], sp["position_knot_spacing_s"]) == (
            want.position_order, pytest.approx(want.position_knot_spacing_s, rel=1e-12))
        given = kw.get("position_knot_spacing_s"), kw.get("knot_spacing_s")
        if given[0] == 0.08:
            assert sp["position_knot_spacing_s"] == pytest.approx(0.08) and sp["position_order"] == 4
            assert sp["knot_spacing_s"] != pytest.approx(0.08)
        else:
            assert sp["knot_spacing_s"] == pytest.approx(0.05)
            assert sp["position_knot_spacing_s"] != pytest.approx(0.05)


def test_same_seed_same_bytes_and_noise_model_file(ellipse_tum, tmp_path):
    outs = []
    for i, seed in enumerate((7, 7, 8)):
        out = tmp_path / f"o{i}"
        assert run_cli("from-tum", ellipse_tum, "-o", out, "--imu", "adis16448", "--seed", seed,
                       "--knot-spacing", 0.05, "--order", 4) == 0
        outs.append((out / "mav0" / "imu0" / "data.csv").read_bytes())
    assert outs[0] == outs[1] and outs[0] != outs[2]
    assert "gyroscope_noise_density" in (tmp_path / "o0" / "imu.yaml").read_text()


def test_existing_output_is_not_overwritten_without_force(ellipse_tum, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    assert run_cli("from-tum", ellipse_tum, "-o", out) == 1
    assert "--force" in capsys.readouterr().err
    assert (out / "keep.txt").read_text() == "mine"
    assert run_cli("from-tum", ellipse_tum, "-o", out, "--force", "--knot-spacing", 0.1) == 0
    assert not (out / "keep.txt").exists() and (out / "mav0" / "imu0" / "data.csv").exists()


BAD_FILES = {
    "nan": ("0.0 0 0 0 0 0 0 1\n0.1 nan 0 0 0 0 0 1\n0.2 0 0 0 0 0 0 1\n", 2),
    "unsorted": ("0.0 0 0 0 0 0 0 1\n0.2 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1\n", 3),
    "zero_quat": ("0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 0\n0.2 0 0 0 0 0 0 1\n", 2),
    "malformed": ("0.0 0 0 0 0 0 0 1\n0.1 0 0 0 abc 0 0 1\n0.2 0 0 0 0 0 0 1\n", 2),
    "short_line": ("0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n0.2 0 0 0 0 0 0 1\n", 2),
    "repeated_stamp": ("0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n", 3),
    "too_few": ("0.0 0 0 0 0 0 0 1\n", None),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_input_fails_cleanly(case, tmp_path):
    text, line = BAD_FILES[case]
    src = tmp_path / f"{case}.txt"
    src.write_text(text)
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "splineimu", "from-tum", str(src), "-o", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1, proc.stderr
    err = proc.stderr.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    assert f"{case}.txt" in err
    if line is not None:
        assert f":{line}:" in err, err
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == [src.name]  # no temp folders left


def _gappy_tum(path):
    t = np.concatenate([np.arange(0, 5, 0.01), np.arange(6.2, 10, 0.01)])
    k = make_scene("ellipse", duration_s=10).kinematics(t)
    with open(path, "w") as fh:
        for ti, p, q in zip(t, k.position_world, k.quat_xyzw):
            fh.write(f"{ti:.6f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {q[0]:.12f} {q[1]:.12f} {q[2]:.12f} {q[3]:.12f}\n")
    return path


def test_gaps_error_bridge_split(tmp_path, capsys):
    src = _gappy_tum(tmp_path / "gappy.tum")
    assert run_cli("from-tum", src, "-o", tmp_path / "a") == 1
    err = capsys.readouterr().err
    assert "gappy.tum:501:" in err and "--gaps bridge" in err and "1.2" in err
    assert run_cli("from-tum", src, "-o", tmp_path / "b", "--gaps", "bridge") == 0
    rep = json.loads((tmp_path / "b" / "report.json").read_text())
    assert len(rep["gaps"]["bridged"]) == 1 and abs(rep["gaps"]["bridged"][0]["duration_s"] - 1.21) < 1e-9
    assert run_cli("from-tum", src, "-o", tmp_path / "c", "--gaps", "split") == 0
    parts = sorted(p.name for p in (tmp_path / "c").iterdir())
    assert parts == ["part_000", "part_001"]
    t0, _, _ = read_imu(tmp_path / "c" / "part_001" / "mav0" / "imu0" / "data.csv")
    assert t0[0] == 6_200_000_000


def test_timestamps_file_and_extrinsic(ellipse_tum, tmp_path):
    origin = 1_403_636_579_758_555_392
    stamps = origin + np.array([-5, 0, 1_234_567, 5_000_000_001, 12_000_000_000, 12_000_000_001])
    ts = tmp_path / "stamps.csv"
    ts.write_text("#timestamp [ns]\n" + "\n".join(str(s) for s in stamps) + "\n")
    ext = tmp_path / "ext.yaml"
    ext.write_text("translation: [0.1, -0.05, 0.02]\nquat_xyzw: [0, 0, 0.7071067811865476, 0.7071067811865476]\n")
    out = tmp_path / "out"
    assert run_cli("from-tum", ellipse_tum, "-o", out, "--timestamps", ts, "--extrinsic", ext) == 0
    t_ns, gyro, _ = read_imu(out / "mav0" / "imu0" / "data.csv")
    np.testing.assert_array_equal(t_ns, stamps[1:5])
    # the sensor is yawed by +90 deg: w_s = R_bs^T w_b
    g0 = make_scene("ellipse", duration_s=12).imu((t_ns - origin) / 1e9)[0]
    np.testing.assert_allclose(gyro[:, 0], g0[:, 1], atol=1e-4)
    np.testing.assert_allclose(gyro[:, 1], -g0[:, 0], atol=1e-4)


# ------------------------------------------------------------------------ real data
def test_real_euroc_gyro_matches_at_least_as_well_as_finite_differences(tmp_path):
    """EuRoC V1_02: synthesize at the real IMU's stamps; compare with the real gyro minus the
    ground truth's bias, both low-passed at 10 Hz, against central differences of the poses."""
    from scipy.signal import butter, sosfiltfilt

    from splineimu import lie
    from splineimu.io.euroc import read_euroc_groundtruth

    gt = require_shared("euroc_V1_02_medium", "groundtruth.csv")
    imu = require_shared("euroc_V1_02_medium", "imu0_first40s.csv")
    out = tmp_path / "out"
    assert run_cli("from-euroc", gt, "-o", out, "--timestamps", imu) == 0
    t_ns, gyro, _ = read_imu(out / "mav0" / "imu0" / "data.csv")
    rt, rg, _ = read_imu(imu)
    sel = np.isin(rt, t_ns)
    real_t, real_g = rt[sel], rg[sel]
    np.testing.assert_array_equal(real_t, t_ns)
    track = read_euroc_groundtruth(gt)
    tg = (track.t_ns - t_ns[0]) / 1e9
    ti = (t_ns - t_ns[0]) / 1e9
    bias = np.column_stack([np.interp(ti, tg, track.bias_gyro[:, i]) for i in range(3)])
    # central differences of the ground truth, interpolated to the IMU stamps
    R = lie.quat_xyzw_to_matrix(track.quat_xyzw)
    w_fd = lie.so3_log(np.swapaxes(R[:-2], 1, 2) @ R[2:]) / (tg[2:] - tg[:-2])[:, None]
    fd = np.column_stack([np.interp(ti, tg[1:-1], w_fd[:, i]) for i in range(3)])
    sos = butter(4, 10.0, fs=200.0, output="sos")
    lp = lambda x: sosfiltfilt(sos, x, axis=0)  # noqa: E731
    ref = lp(real_g - bias)
    inner = slice(400, -400)
    err_ours = np.sqrt(np.mean((lp(gyro) - ref)[inner] ** 2))
    err_fd = np.sqrt(np.mean((lp(fd) - ref)[inner] ** 2))
    assert err_ours <= err_fd, (err_ours, err_fd)
    # the ground truth carries IMU biases: an estimator's output, its rotation read as motion
    spline = json.loads((out / "report.json").read_text())["spline"]
    assert spline["knot_choice"]["rotation"]["estimated"] is True


def test_real_tum_rgbd_with_repeated_stamp_and_gaps(tmp_path, capsys):
    src = require_shared("tum_rgbd", "fr2_desk_groundtruth.txt")
    assert run_cli("from-tum", src, "-o", tmp_path / "a") == 1
    assert "fr2_desk_groundtruth.txt:10863: timestamp" in capsys.readouterr().err  # repeated, other pose
    assert run_cli("from-tum", src, "-o", tmp_path / "a", "--repeated-stamps", "first") == 1
    assert "--gaps" in capsys.readouterr().err
    assert run_cli("from-tum", src, "-o", tmp_path / "b", "--gaps", "split", "--rate", 100,
                   "--repeated-stamps", "first") == 0
    assert len(list((tmp_path / "b").iterdir())) >= 2


def test_real_tum_vi_gaps_up_to_one_second(tmp_path):
    src = require_shared("tum_vi", "room1_512_16_groundtruth.tum")
    assert run_cli("from-tum", src, "-o", tmp_path / "a") == 1
    assert run_cli("from-tum", src, "-o", tmp_path / "b", "--max-gap", 1.1, "--rate", 100) == 0
    _, gyro, acc = read_imu(tmp_path / "b" / "mav0" / "imu0" / "data.csv")
    assert np.all(np.isfinite(gyro)) and np.abs(gyro).max() < 20 and np.abs(acc).max() < 100


def test_real_openvins_14_columns_and_utm_coordinates(tmp_path, capsys):
    src = require_shared("openvins_sim", "udel_gore.txt")
    assert run_cli("from-tum", src, "-o", tmp_path / "a", "--gaps", "bridge") == 0
    assert "ignored" in capsys.readouterr().err
    geo = require_shared("misc", "georeferenced.tum")
    assert run_cli("from-tum", geo, "-o", tmp_path / "b", "--gaps", "bridge", "--rate", 50) == 0
    rep = json.loads((tmp_path / "b" / "report.json").read_text())
    assert rep["spline"]["residual_position_rms_m"] < 1.0
    _, gyro, acc = read_imu(tmp_path / "b" / "mav0" / "imu0" / "data.csv")
    assert np.all(np.isfinite(acc)) and np.abs(acc).max() < 50


@pytest.mark.parametrize("sampling, increments", [("point", False), ("mean", True)])
def test_streamed_output_equals_the_whole_record_byte_for_byte(tmp_path, sampling, increments):
    """write_output of a SynthesisStream in small pieces (noise processes, quaternion signs
    and interval starts continuing across pieces) writes the same bytes as of one Synthesis."""
    from splineimu.api.output import write_output
    from splineimu.imu.ideal import Extrinsic
    from splineimu.pipeline import synthesize, synthesize_stream
    from splineimu.timegrid import uniform_stamps_ns

    scene = make_scene("flips", duration_s=6.0, t0_ns=1_700_000_000_123_456_789)
    t_ns = uniform_stamps_ns(scene.origin_ns, scene.origin_ns + 6_000_000_000, 400.0)
    ext = Extrinsic.from_matrix(np.array([[0.0, -1, 0, 0.01], [1, 0, 0, -0.02], [0, 0, 1, 0.03], [0, 0, 0, 1]]))
    cfg = {"gyroscope_noise_density": 1e-3, "gyroscope_random_walk": 1e-5, "gyroscope_bias_sigma": 1e-3,
           "gyroscope_bias_instability": 1e-4, "gyroscope_bias_correlation_time": 3.0,
           "accelerometer_noise_density": 1e-2, "accelerometer_random_walk": 1e-4,
           "accelerometer_quantization": 1e-3, "update_rate": 400.0}
    kw = dict(extrinsic=ext, imu_config=cfg, seed=5, sampling=sampling, with_increments=increments)
    write_output(synthesize(scene, t_ns, **kw), tmp_path / "whole", report={})
    write_output(synthesize_stream(scene, t_ns, chunk_samples=333, **kw), tmp_path / "pieces", report={})
    names = sorted(p.relative_to(tmp_path / "whole") for p in (tmp_path / "whole").rglob("*") if p.is_file())
    assert len(names) == 9 + increments
    for name in names:
        if name.name == "report.json":
            a, b = (json.loads((tmp_path / d / name).read_text()) for d in ("whole", "pieces"))
            assert a["imu"] == b["imu"]
            continue
        assert (tmp_path / "whole" / name).read_bytes() == (tmp_path / "pieces" / name).read_bytes(), name


def test_output_files_get_the_usual_permissions(tmp_path):
    """Every file of an output folder (and allan's) is created with mode 0666 & ~umask, as
    any other tool's output: temporary-file helpers default to 0600, which hid them from
    other users and containers."""
    import os

    old = os.umask(0o022)
    try:
        assert main(["scene", "static", "--duration", "2", "-o", str(tmp_path / "out"), "--imu", "adis16448"]) == 0
        assert main(["allan", str(tmp_path / "out" / "mav0" / "imu0" / "data.csv"), "-o", str(tmp_path / "al"),
                     "--plot"]) == 0
    finally:
        os.umask(old)
    files = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert len(files) == 11
    for p in files:
        assert p.stat().st_mode & 0o777 == 0o644, p


def test_a_run_imports_only_what_its_command_uses(ellipse_tum, tmp_path):
    # a fresh process: from-tum without plots, bags, vibration or a timing model loads none of
    # their modules, nor the flags of the other commands (compare's pull in metrics)
    code = (
        "import sys\n"
        "from splineimu.cli import main\n"
        f"assert main(['from-tum', {str(ellipse_tum)!r}, '-o', {str(tmp_path / 'o')!r}]) == 0\n"
        "heavy = ('pandas', 'matplotlib', 'rosbags', 'dask', 'distributed', 'tqdm', 'scipy.ndimage',\n"
        "         'splineimu.metrics', 'splineimu.imu.vibration', 'splineimu.imu.timing', 'splineimu.plots',\n"
        "         'splineimu.io.bag')\n"
        "print(sorted(m for m in heavy if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[-2] == "[]"


def test_every_command_keeps_its_flags(capsys):
    from splineimu.cli import build_parser

    full = build_parser()
    only = build_parser("compare")
    argv = ["compare", "a.tum", "b.tum", "--metric", "rpe", "--align", "se3"]
    assert vars(full.parse_args(argv)) == vars(only.parse_args(argv))
    with pytest.raises(SystemExit):  # the other commands are listed, without their flags
        only.parse_args(["from-tum", "p.tum", "--rate", "100"])
    assert "from-tum" in only.format_help() and "compare" in only.format_help()


def test_help_and_version_import_no_numpy():
    code = ("import sys, contextlib, io\nfrom splineimu.cli import main\n"
            "for argv in (['--help'], ['--version'], []):\n"
            "    with contextlib.redirect_stdout(io.StringIO()):\n"
            "        try:\n            main(argv)\n        except SystemExit:\n            pass\n"
            "print('numpy' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"


def test_help_examples_name_existing_presets():
    """from-euroc's help example used `--imu euroc`, which is no preset (the run stopped with
    'no IMU preset named `euroc`'); every `--imu NAME` without a file suffix in the commands'
    help must be a packaged preset."""
    import re

    from splineimu.cli import _commands
    from splineimu.imu.presets import list_presets

    names = {m.group(1) for mod in _commands()
             for m in re.finditer(r"--imu ([A-Za-z0-9_./]+)", getattr(mod, "DESCRIPTION", ""))
             if "." not in m.group(1) and "/" not in m.group(1)}
    assert names and names <= set(list_presets()), names - set(list_presets())


def test_a_misspelt_scene_is_named_before_the_missing_output(tmp_path, capsys):
    """`splineimu scene elipse` (no -o) said 'nothing to write' and hid the misspelt name."""
    assert main(["scene", "elipse"]) == 1
    err = capsys.readouterr().err
    assert "got 'elipse'; did you mean 'ellipse'?" in err and "nothing to write" not in err
    assert main(["scene", "ellipse"]) == 1
    assert "nothing to write" in capsys.readouterr().err


def test_order_2_is_refused_for_synthesis(capsys):
    """--order 2 (accepted, though the help said 4 .. 6) fitted a piecewise-linear position spline:
    the ellipse's accelerometer read gravity alone (a_x 1e-8 for -1.48 m/s^2) and the predicted
    accel error was 7e-6 m/s^2."""
    from splineimu.api.options import SplineOptions
    from splineimu.errors import ConfigError

    with pytest.raises(ConfigError, match="2 \\(piecewise linear\\) has no acceleration"):
        SplineOptions(order=2)
    assert SplineOptions(order=3).order == 3 and SplineOptions(order=8).order == 8
    assert main(["from-tum", "poses.tum", "--order", "2", "-o", "never"]) == 1
    assert "`--order` 2 (piecewise linear) has no acceleration" in capsys.readouterr().err


def test_rate_and_timestamps_together_are_refused(tmp_path, capsys):
    """--rate 50 with --timestamps was ignored in silence (the samples follow the file), on the
    command line and in a scene file alike."""
    from splineimu.api.scenefile import load_scene_file
    from splineimu.errors import ConfigError

    stamps = tmp_path / "stamps.txt"
    stamps.write_text("".join(f"{i * 5_000_000}\n" for i in range(20)))
    assert main(["scene", "static", "--timestamps", str(stamps), "--rate", "50", "-o", str(tmp_path / "o")]) == 1
    assert "--rate and --timestamps are both given" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    f = tmp_path / "s.yaml"
    f.write_text(f"motion: {{scene: static, duration_s: 1}}\nimu: {{rate_hz: 50, timestamps: {stamps}}}\n"
                 "output: {dir: o}\n")
    with pytest.raises(ConfigError, match=r"s.yaml:2: `imu.rate_hz` and `imu.timestamps` are both given"):
        load_scene_file(f)
    assert main(["scene", "static", "--timestamps", str(stamps), "-o", str(tmp_path / "o")]) == 0


def test_tum_file_inside_the_output_folder_is_refused(tmp_path, capsys):
    """`scene -o OUT --tum OUT/poses.tum` wrote the TUM file first: without --force the folder
    was then refused for being non-empty (leaving OUT/poses.tum behind), with --force the
    folder replaced it and the TUM file was gone, in silence."""
    out = tmp_path / "out"
    for extra in ([], ["--force"]):
        assert main(["scene", "static", "--duration", "1", "-o", str(out), "--tum", str(out / "poses.tum"),
                     *extra]) == 1
        assert "lies in the output folder" in capsys.readouterr().err
        assert not out.exists()
    assert main(["scene", "static", "--duration", "1", "-o", str(out), "--tum", str(tmp_path / "poses.tum")]) == 0
    assert (tmp_path / "poses.tum").is_file() and (out / "groundtruth.tum").is_file()


def test_trim_ends_leaves_the_one_sided_ends_out(tmp_path, capsys):
    """--trim-ends auto: the record starts and ends the fit's end zones (k knot spacings) inside
    the poses, on the untrimmed record's grid, and the ends warning is gone with the ends.
    Exact ellipse poses at 2 Hz: accel error over the whole record 0.63 m/s^2 (the ends 2.4),
    trimmed 0.031 m/s^2."""
    sc = make_scene("ellipse", duration_s=60.0, t0_ns=1_700_000_000_000_000_000)
    path = tmp_path / "ell2.tum"
    assert run_cli("scene", "ellipse", "--duration", 60, "--rate", 2, "--t0-ns", sc.origin_ns, "--tum", path) == 0
    errs = {}
    for trim in ("0", "auto"):
        out = tmp_path / f"out{trim}"
        assert run_cli("from-tum", path, "-o", out, "--trim-ends", trim) == 0
        rep = json.loads((out / "report.json").read_text())
        codes = [w["code"] for w in rep["warnings"]]
        t_ns, _, f = read_imu(out / "mav0/imu0/data.csv")
        errs[trim] = float(np.sqrt(np.mean(np.sum((f - sc.imu(sc.t_s_from_ns(t_ns))[1]) ** 2, axis=1))))
        if trim == "0":
            assert "ends_less_accurate" in codes and t_ns[0] == sc.origin_ns
            continue
        zone = max(rep["spline"]["knot_choice"][key]["end_zone_s"] for key in ("rotation", "position"))
        assert rep["spline"]["trimmed_ends_s"] >= zone * 0.99 and "ends_less_accurate" not in codes, rep["warnings"]
        first = (t_ns[0] - sc.origin_ns) / 1e9
        assert zone * 0.99 <= first <= rep["spline"]["trimmed_ends_s"] + 0.005  # on the 200 Hz grid from t0:
        assert (t_ns[0] - sc.origin_ns) % 5_000_000 == 0
        assert (sc.origin_ns + 60_000_000_000 - t_ns[-1]) / 1e9 >= zone * 0.99
        assert "trimmed" in capsys.readouterr().out
    assert errs["auto"] < 0.2 * errs["0"], errs
    assert run_cli("from-tum", path, "-o", tmp_path / "none", "--trim-ends", 31) == 1
    assert "`--trim-ends` = 31 s at each end leaves nothing of the 60 s of poses" in capsys.readouterr().err


def test_rotation_source_flag_reaches_the_fit(tmp_path, ellipse_tum, capsys):
    """A TUM file carries no biases: its rotation is a measurement unless told otherwise."""
    for flag, estimated in ((), False), (("--rotation-source", "estimate"), True):
        out = tmp_path / f"out{int(estimated)}"
        assert run_cli("from-tum", ellipse_tum, "-o", out, *flag) == 0
        choice = json.loads((out / "report.json").read_text())["spline"]["knot_choice"]["rotation"]
        assert choice["estimated"] is estimated and choice["motion_limited"] is estimated
        assert ("an estimator's output (as told)" in capsys.readouterr().out) is estimated
