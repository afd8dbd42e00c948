"""The command line at the extremes of its inputs: output sizes, rates far from 200 Hz, Unix-ns stamps."""

from __future__ import annotations

import pytest

from splineimu.cli import main


def _table_bytes(out):
    files = [p for p in out.rglob("*") if p.suffix in (".csv", ".tum")]
    return sum(p.stat().st_size for p in files), len(files)


def test_disk_estimate_covers_what_is_written(tmp_path):
    """The free-space check must not under-count: with 450 bytes per sample estimated and up to
    ~670 written (Unix-ns stamps, a noisy sensor model, a lever arm), a run the check let through
    could fill the disk."""
    from splineimu.resources import DISK_BYTES, EXTRA_TABLE_BYTES

    common = ["scene", "ellipse", "--duration", "1", "--rate", "200", "--t0-ns", "1700000000000000000",
              "--imu", "adis16448", "--seed", "1",
              "--extrinsic", "{translation: [0.1, 0.02, 0.03], quat_xyzw: [0, 0, 0.3826834, 0.9238795]}"]
    assert main([*common, "-o", str(tmp_path / "a")]) == 0
    written, n_files = _table_bytes(tmp_path / "a")
    assert n_files == 3
    per_sample = written / 201
    assert 0.8 * DISK_BYTES < per_sample <= DISK_BYTES, per_sample  # measured 652
    vibration = ("{accel: [{freq_hz: 37, amplitude: [0.5, 0.2, 0.1]}], "
                 "gyro: [{freq_hz: 41, amplitude: [0.1, 0.1, 0.1]}]}")
    assert main([*common, "--increments", "--vibration", vibration, "-o", str(tmp_path / "b")]) == 0
    written_b, n_files = _table_bytes(tmp_path / "b")
    assert n_files == 5
    per_extra = (written_b - written) / 201 / 2
    assert 0.7 * EXTRA_TABLE_BYTES < per_extra <= EXTRA_TABLE_BYTES, per_extra


def test_disk_check_counts_the_optional_tables(tmp_path, monkeypatch):
    import splineimu.resources as res

    monkeypatch.setattr(res, "available_memory_bytes", lambda: 10**12)
    monkeypatch.setattr(res, "free_disk_bytes", lambda path: 10_000 * (res.DISK_BYTES + res.EXTRA_TABLE_BYTES))
    res.check_record_fits(10_000, rate_hz=200.0, out_dir=tmp_path, extra_tables=1)
    with pytest.raises(res.ConfigError, match="of disk at"):
        res.check_record_fits(10_000, rate_hz=200.0, out_dir=tmp_path, extra_tables=2)


@pytest.mark.parametrize("args, span", [(["--rate", "0.001"], "10"), (["--duration", "0.001"], "0.001")])
def test_a_single_sample_record_is_refused(tmp_path, capsys, args, span):
    """--rate 0.001 over 10 s (a unit slip for kHz) wrote a one-row IMU record without a word."""
    base = {"--rate": "200", "--duration": "10"}
    base.update(dict(zip(args[::2], args[1::2])))
    rc = main(["scene", "ellipse", *[x for kv in base.items() for x in kv], "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 1 and err.count("\n") == 1, err
    assert f"gives a single IMU sample over the {span} s of motion" in err
    assert not (tmp_path / "o").exists()
    assert main(["scene", "ellipse", "--duration", "10", "--rate", "0.1", "-o", str(tmp_path / "two")]) == 0
    assert (tmp_path / "two" / "mav0" / "imu0" / "data.csv").read_text().count("\n") == 1 + 2


def _write_tum(path, t_s, angle_z_rad, sign=None):
    import numpy as np

    q = np.column_stack([np.zeros((t_s.size, 2)), np.sin(angle_z_rad / 2), np.cos(angle_z_rad / 2)])
    if sign is not None:
        q = q * sign[:, None]
    path.write_text("".join(f"{t:.9f} 1 2 3 {x!r} {y!r} {z!r} {w!r}\n" for t, (x, y, z, w) in zip(t_s, q.tolist())))
    return path


def test_a_turn_of_179_degrees_between_poses_is_refused_naming_the_file(tmp_path, capsys):
    """The fit's refusal reached the user without the file it was about."""
    import numpy as np

    t = np.arange(200) * 0.01
    poses = _write_tum(tmp_path / "jump.tum", t, 0.1 * t + np.radians(179.0) * (t >= 1.0))
    rc = main(["from-tum", str(poses), "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 1 and err.count("\n") == 1, err
    # and the line of the pose before the turn (no header: pose i is on line i + 1)
    assert err.startswith(f"splineimu from-tum: error: {poses}:100: poses 99 and 100 "), err
    assert "rotate by 179.1 deg" in err, err
    assert "Traceback" not in err and not (tmp_path / "o").exists()


def test_a_refused_turn_after_dropped_flips_names_the_input_poses(tmp_path, capsys):
    """With orientation flips dropped first, the refusal named the kept poses' positions
    ('poses 99 and 100' in a file turning 170 deg every 10 ms, half of them dropped as flips),
    which no line of the file matches; it names the input's poses and the line now."""
    import numpy as np

    from splineimu import fit
    from splineimu.errors import InputError

    t = np.arange(200) * 0.01
    angle = np.radians(170.0) * np.arange(200)
    q = np.column_stack([np.zeros((200, 2)), np.sin(angle / 2), np.cos(angle / 2)])
    with pytest.raises(InputError) as exc:
        fit(t, np.zeros((200, 3)), q)
    kept = exc.value.pose_index
    assert f"poses {kept} and " in str(exc.value) and kept >= 1
    poses = _write_tum(tmp_path / "spin.tum", t, angle)
    rc = main(["from-tum", str(poses), "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 1 and err.startswith(f"splineimu from-tum: error: {poses}:{kept + 1}: poses {kept} and "), err


def test_a_large_output_is_announced_with_its_size(tmp_path, capsys, monkeypatch):
    """A 10 kHz hour (36M samples, ~23 GB) started writing without a word about its size."""
    import splineimu.resources as res

    monkeypatch.setattr(res, "LARGE_OUTPUT_BYTES", 2002 * res.DISK_BYTES)
    assert main(["scene", "static", "--duration", "10", "--rate", "200", "-o", str(tmp_path / "a")]) == 0
    assert "note" not in capsys.readouterr().err
    assert main(["scene", "static", "--duration", "10", "--rate", "200.1", "-o", str(tmp_path / "b")]) == 0
    err = capsys.readouterr().err
    assert f"note: 2002 IMU samples: up to 1.4 MB of tables will be written to {tmp_path / 'b'}" in err, err


def test_scene_tum_streams_in_pieces_with_the_same_bytes(tmp_path, monkeypatch):
    """A scene's TUM file was evaluated whole: ~390 bytes per pose, 14 GB for a 10 kHz hour (883 MB
    for 2M poses, now 262 MB). In pieces it must keep the bytes, signs continuing across pieces."""
    import numpy as np

    import splineimu.io.tum as tum
    from splineimu.lie import quat_make_continuous
    from splineimu.scenes import make_scene
    from splineimu.timegrid import uniform_stamps_ns

    scene = make_scene("flips", duration_s=3.0, t0_ns=1_700_000_000_000_000_000)
    t_ns = uniform_stamps_ns(scene.origin_ns, scene.origin_ns + 3_000_000_000, 200.0)
    pos, quat = scene.pose(scene.t_s_from_ns(t_ns))
    whole = tum.write_tum(tmp_path / "whole.tum", t_ns, pos, quat_make_continuous(quat)).read_bytes()
    monkeypatch.setattr(tum, "SCENE_TUM_PIECE", 7)
    pieces = tum.write_scene_tum(scene, tmp_path / "pieces.tum", 200.0)
    assert pieces.read_bytes() == whole
    q = tum.read_tum(pieces).quat_xyzw
    assert q.shape == (601, 4) and np.all(np.sum(q[1:] * q[:-1], axis=1) > 0)


@pytest.mark.parametrize("progress, shown", [(None, False), (True, True), (False, False)])
def test_a_bag_shows_its_progress(tmp_path, capsys, progress, shown):
    """An hour at 200 Hz took 23 s writing its ROS bag (1.44M messages) with nothing on the screen."""
    import numpy as np

    from splineimu.io.bag import write_bag

    n = 5000
    t = np.arange(n, dtype=np.int64) * 5_000_000
    write_bag(tmp_path / "b.bag", "ros1", t, np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1)), progress=progress)
    err = capsys.readouterr().err
    assert ("bag:" in err and "messages" in err) is shown, err
    assert (tmp_path / "b.bag").stat().st_size > n * 300


def test_a_pose_file_too_large_for_memory_is_refused_before_reading(tmp_path, capsys, monkeypatch):
    """3.6M poses (331 MB) under a 1.1 GB limit ran out of memory inside the reader ("out of memory;
    try a shorter span, a lower --rate"), and without a limit the kernel kills the process without a
    word; the file is now weighed before it is read."""
    import numpy as np

    import splineimu.resources as res

    t = np.arange(300) * 0.01
    poses = _write_tum(tmp_path / "p.tum", t, 0.3 * t)
    size = poses.stat().st_size
    monkeypatch.setattr(res, "available_memory_bytes", lambda: int(res.POSE_FILE_BYTES * size / res.MEMORY_SHARE) - 1)
    rc = main(["from-tum", str(poses), "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 1 and err.count("\n") == 1, err
    assert f"error: {poses}: a pose file of {size / 1e6:.3g} MB needs about {6 * size / 1e6:.3g} MB of memory" in err
    assert not (tmp_path / "o").exists()
    monkeypatch.setattr(res, "available_memory_bytes", lambda: int(res.POSE_FILE_BYTES * size / res.MEMORY_SHARE) + 1)
    assert main(["from-tum", str(poses), "-o", str(tmp_path / "o")]) == 0


def test_a_batch_too_large_for_the_disk_is_refused_before_any_run(tmp_path, monkeypatch):
    """Each run checked only its own folder: 100 runs of a 10 kHz hour (2.5 TB) started, filled the
    disk run by run, and failed the rest."""
    import splineimu.resources as res
    from splineimu.api.batch import run_batch
    from splineimu.errors import ConfigError

    scene = tmp_path / "s.yaml"
    scene.write_text("motion: {scene: ellipse, duration_s: 2}\nimu: {rate_hz: 100, model: adis16448}\nseed: 3\n"
                     "output: {dir: out}\nvary:\n  imu.model.gyroscope_noise_density: {uniform: [1.0e-4, 2.0e-4]}\n")
    per_run = 201 * res.DISK_BYTES
    monkeypatch.setattr(res, "free_disk_bytes", lambda path: 3 * per_run - 1)
    with pytest.raises(ConfigError, match=r"3 runs of 201 IMU samples need about 0\.422 MB of disk at .*give fewer"):
        run_batch(scene, 3, tmp_path / "mc", workers=1, progress=False)
    assert not (tmp_path / "mc").exists()
    lines = []
    monkeypatch.setattr(res, "LARGE_OUTPUT_BYTES", 2 * per_run)
    result = run_batch(scene, 2, tmp_path / "mc", workers=1, progress=False, echo=lines.append)
    assert result.ok and result.ran == 2
    assert f"note: 2 runs of 201 IMU samples: up to 0.281 MB of tables will be written to {tmp_path / 'mc'}" in lines
