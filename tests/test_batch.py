"""Monte-Carlo batches on a real Dask cluster (worker processes on loopback).

The acceptance batch (24 runs of a 20 s, 200 Hz scene with two varied noise densities) runs
once per module on a local cluster of two workers; the other tests compare their bytes with it.
Tests that start extra processes (an external ``dask scheduler`` + ``dask worker``, a batch
killed with SIGKILL) are marked slow.
"""

from __future__ import annotations

import csv
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from splineimu.api.batch import run_batch, run_name
from splineimu.cli import main
from splineimu.errors import ConfigError, OutputExistsError

pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
RUNS = 24
GYRO = (1.8e-4, 2.0e-5)  # normal: mean, std
ACCEL = (1.0e-3, 3.0e-3)  # uniform: low, high

SCENE = f"""\
motion: {{scene: ellipse, duration_s: 20}}
imu:
  rate_hz: 200
  model: adis16448
seed: 42
output: {{dir: out}}
vary:
  imu.model.gyroscope_noise_density: {{normal: [{GYRO[0]}, {GYRO[1]}]}}
  imu.model.accelerometer_noise_density: {{uniform: [{ACCEL[0]}, {ACCEL[1]}]}}
"""


def _files(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _same_runs(a: Path, b: Path, runs):
    for k in runs:
        fa, fb = _files(a / "runs" / run_name(k)), _files(b / "runs" / run_name(k))
        assert sorted(fa) == sorted(fb), k
        for name in fa:
            assert fa[name] == fb[name], f"run {k}: {name} differs"


def _rows(out: Path) -> list[dict]:
    with open(out / "runs.csv", newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("scene") / "scene.yaml"
    p.write_text(SCENE)
    return p


@pytest.fixture(scope="module")
def batch(scene, tmp_path_factory):
    out = tmp_path_factory.mktemp("batch") / "mc"
    result = run_batch(scene, RUNS, out, workers=2, progress=False)
    return out, result


@pytest.fixture(scope="module")
def one_worker():
    """The address of a cluster of one worker process (what `dask scheduler` + `dask worker` make)."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        yield cluster.scheduler_address


def test_batch_writes_every_run_and_its_draws(batch):
    out, result = batch
    assert result.ok and result.ran == RUNS and result.failed == 0 and result.workers == 2
    assert sorted(p.name for p in (out / "runs").iterdir()) == [run_name(k) for k in range(RUNS)]
    rows = _rows(out)
    assert [int(r["run"]) for r in rows] == list(range(RUNS))
    assert {r["status"] for r in rows} == {"ok"}
    gyro = np.array([float(r["imu.model.gyroscope_noise_density"]) for r in rows])
    accel = np.array([float(r["imu.model.accelerometer_noise_density"]) for r in rows])
    assert len(set(gyro)) == RUNS and len(set(accel)) == RUNS and len({r["seed"] for r in rows}) == RUNS
    assert np.all((accel >= ACCEL[0]) & (accel < ACCEL[1]))
    assert abs(gyro.mean() - GYRO[0]) < 4 * GYRO[1] / math.sqrt(RUNS)
    assert np.all(gyro > 0)
    for r in rows:  # full precision: the text is the float's repr, and imu.yaml holds the same value
        k = int(r["run"])
        assert repr(float(r["imu.model.gyroscope_noise_density"])) == r["imu.model.gyroscope_noise_density"]
        text = (out / "runs" / run_name(k) / "imu.yaml").read_text()
        assert f"gyroscope_noise_density: {r['imu.model.gyroscope_noise_density']}\n" in text
        assert f"accelerometer_noise_density: {r['imu.model.accelerometer_noise_density']}\n" in text
        assert f'"seed": {r["seed"]}' in (out / "runs" / run_name(k) / "report.json").read_text()


def test_run_index_writes_the_same_bytes_as_the_batch(batch, scene, tmp_path, capsys):
    out, _ = batch
    assert main(["run", str(scene), "--run-index", "7", "-o", str(tmp_path / "r7")]) == 0
    mine, theirs = _files(tmp_path / "r7"), _files(out / "runs" / "00007")
    assert sorted(mine) == sorted(theirs) and "mav0/imu0/data.csv" in mine
    for name in mine:
        assert mine[name] == theirs[name], name


def test_run_without_index_uses_nominal_values(scene, tmp_path):
    from splineimu.api import load_scene_file

    cfg = load_scene_file(scene).imu.imu_config
    assert cfg.gyroscope_noise_density.tolist() == [GYRO[0]] * 3
    assert cfg.accelerometer_noise_density.tolist() == [0.5 * (ACCEL[0] + ACCEL[1])] * 3


def test_one_worker_gives_the_same_bytes(batch, scene, tmp_path, one_worker):
    out, _ = batch
    result = run_batch(scene, 4, tmp_path / "one", scheduler=one_worker, progress=False)
    assert result.ok and result.workers == 1
    _same_runs(out, tmp_path / "one", range(4))
    assert _rows(tmp_path / "one") == _rows(out)[:4]


def test_a_failing_run_is_reported_and_the_others_complete(tmp_path, one_worker):
    # std 5x the mean: about 42 % of the draws are negative, which the sensor model refuses
    scene = tmp_path / "s.yaml"
    scene.write_text(SCENE.replace(f"normal: [{GYRO[0]}, {GYRO[1]}]", "normal: [1.0e-4, 5.0e-4]")
                     .replace("duration_s: 20", "duration_s: 2"))
    out = tmp_path / "mc"
    result = run_batch(scene, 6, out, scheduler=one_worker, progress=False)
    rows = _rows(out)
    bad = [r for r in rows if float(r["imu.model.gyroscope_noise_density"]) < 0]
    assert bad and len(bad) < 6 and not result.ok and result.failed == len(bad)
    for r in rows:
        done = (out / "runs" / run_name(int(r["run"]))).is_dir()
        assert (r["status"] == "ok") == done == (r not in bad)
    assert all("gyroscope_noise_density" in r["error"] and "s.yaml:" in r["error"] for r in bad)
    # the command's exit code says so
    assert main(["batch", str(scene), "--runs", "6", "-o", str(out), "--resume", "--scheduler", one_worker]) == 1


def _write_bad(tmp_path, old, new) -> Path:
    p = tmp_path / "bad.yaml"
    assert old in SCENE
    p.write_text(SCENE.replace(old, new))
    return p


@pytest.mark.parametrize("old, new, line, words", [
    ("imu.model.gyroscope_noise_density", "imu.model.gyro_density", 8, ["vary.imu.model.gyro_density", "unknown"]),
    ("imu.model.gyroscope_noise_density", "imu.sample_rate", 8, ["imu.sample_rate", "unknown key"]),
    ("imu.model.gyroscope_noise_density", "imu.rate_hz.x", 8, ["imu.rate_hz.x", "not a key of the scene format"]),
    ("imu.model.gyroscope_noise_density", "seed", 8, ["seed", "cannot be varied"]),
    (f"uniform: [{ACCEL[0]}, {ACCEL[1]}]", f"uniform: [{ACCEL[1]}, {ACCEL[0]}]", 9, ["uniform", "high > low"]),
    (f"normal: [{GYRO[0]}, {GYRO[1]}]", "gauss: [1, 2]", 8, ["unknown distribution `gauss`"]),
    (f"normal: [{GYRO[0]}, {GYRO[1]}]", "normal: [1]", 8, ["[mean, std]"]),
])
def test_bad_vary_blocks_fail_before_any_work(tmp_path, capsys, old, new, line, words):
    bad = _write_bad(tmp_path, old, new)
    out = tmp_path / "mc"
    with pytest.raises(ConfigError) as err:
        run_batch(bad, 3, out, workers=1, progress=False)
    assert err.value.path.endswith("bad.yaml") and err.value.line == line
    for w in words:
        assert w in str(err.value)
    assert main(["batch", str(bad), "--runs", "3", "-o", str(out)]) == 1
    msg = capsys.readouterr().err
    assert f"bad.yaml:{line}:" in msg and "Traceback" not in msg and msg.count("\n") <= 3
    assert main(["run", str(bad)]) == 1
    assert not out.exists()


def test_unreachable_scheduler_fails_cleanly(scene, tmp_path, monkeypatch, capsys):
    from splineimu.batch import cluster

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 2.0)
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "mc"
    assert main(["batch", str(scene), "--runs", "3", "-o", str(out), "--scheduler", f"tcp://127.0.0.1:{port}"]) == 1
    msg = capsys.readouterr().err
    assert "cannot reach the Dask scheduler" in msg and "Traceback" not in msg
    assert not out.exists()


def test_existing_out_needs_resume_or_force(batch, scene, tmp_path):
    out, _ = batch
    with pytest.raises(OutputExistsError):
        run_batch(scene, RUNS, out, workers=1, progress=False)
    other = tmp_path / "other.yaml"
    other.write_text(SCENE.replace("seed: 42", "seed: 43"))
    with pytest.raises(ConfigError, match="another scene file"):
        run_batch(other, RUNS, out, workers=1, resume=True, progress=False)
    with pytest.raises(ConfigError, match="--resume"):
        run_batch(scene, RUNS, out, resume=True, force=True, progress=False)


def test_pose_file_batch_fits_once_and_matches_run_index(tmp_path, one_worker):
    shutil.copy(ROOT / "examples" / "ellipse_mocap.tum", tmp_path / "poses.tum")
    scene = tmp_path / "mocap.yaml"
    scene.write_text("motion: {poses: poses.tum}\nimu: {rate_hz: 100, model: adis16448, "
                     "extrinsic: {translation: [0.1, 0, 0], quat_xyzw: [0, 0, 0, 1]}}\n"
                     "seed: 7\noutput: {dir: out}\n"
                     "vary:\n  imu.extrinsic.translation.1: {choice: [0.0, 0.05]}\n"
                     "  imu.model.accelerometer_random_walk: {uniform: [1.0e-4, 2.0e-4]}\n")
    from splineimu.api.scenefile import SceneFile

    sf = SceneFile.read(scene)
    assert not sf.varies_motion
    assert sf.job(2).imu.body_T_sensor.body_t_sensor.tolist() == [0.1, sf.values(2)["imu.extrinsic.translation.1"], 0]
    result = run_batch(scene, 3, tmp_path / "mc", scheduler=one_worker, progress=False)
    assert result.ok
    assert main(["run", str(scene), "--run-index", "2", "-o", str(tmp_path / "r2")]) == 0
    mine, theirs = _files(tmp_path / "r2"), _files(tmp_path / "mc" / "runs" / "00002")
    assert sorted(mine) == sorted(theirs)
    for name in mine:
        assert mine[name] == theirs[name], name


def test_batch_runs_do_not_fsync_each_file_but_the_batch_syncs_once(batch, scene, tmp_path, monkeypatch, one_worker):
    import splineimu.api.batch as api_batch
    from splineimu.api.scenefile import SceneFile

    calls = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (calls.append(fd), real_fsync(fd))[1])
    api_batch.run_one(3, SceneFile.read(scene), str(tmp_path / "runs"))
    assert calls == []  # a run of a batch: no fsync (the batch syncs at its end)
    _same_runs(batch[0], tmp_path, [3])
    assert main(["run", str(scene), "--run-index", "3", "-o", str(tmp_path / "single")]) == 0
    assert len(calls) >= 4  # a single run still flushes its files one by one
    syncs = []
    monkeypatch.setattr(api_batch, "_sync", lambda: syncs.append(1))
    assert run_batch(scene, 2, tmp_path / "mc", scheduler=one_worker, progress=False).ok
    assert syncs == [1]


def test_resume_reruns_a_folder_cut_by_a_power_loss(batch, scene, tmp_path, one_worker):
    out, _ = batch
    mine = tmp_path / "mc"
    shutil.copytree(out, mine)
    runs = 8
    # what a power loss can leave of runs not yet on the disk: empty files in a renamed folder
    (mine / "runs" / "00005" / "mav0" / "imu0" / "data.csv").write_bytes(b"")
    (mine / "runs" / "00006" / "report.json").write_bytes(b"")
    rows = _rows(mine)
    rows[5]["status"] = rows[6]["status"] = "missing"  # runs.csv is written after the sync
    with open(mine / "runs.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    stamp = (mine / "runs" / "00004" / "report.json").stat().st_mtime_ns
    result = run_batch(scene, runs, mine, scheduler=one_worker, resume=True, progress=False)
    assert result.ok and result.ran == 2 and result.skipped == runs - 2
    _same_runs(out, mine, range(runs))
    assert (mine / "runs" / "00004" / "report.json").stat().st_mtime_ns == stamp


def test_chunks_balance_and_steady_state():
    from splineimu.batch.cluster import MAX_CHUNK, chunk_sizes, steady_time_per_run

    assert chunk_sizes(1, 8) == [1] and max(chunk_sizes(10**5, 2)) == MAX_CHUNK
    for n, w in [(24, 2), (30, 1), (50, 2), (7, 3), (10**4, 4)]:
        sizes = chunk_sizes(n, w)
        assert sum(sizes) == n and sizes == sorted(sizes, reverse=True)
        assert sizes[-min(n, 4 * w):] == [1] * min(n, 4 * w)  # the workers end together
        assert len(sizes) <= n // MAX_CHUNK + 4 * w * MAX_CHUNK
    # the steady state starts once the slowest worker to start has ended its first run (at 1.5 here)
    ends = [("c", 5.0), ("a", 0.0), ("a", 1.0), ("b", 1.2), ("a", 1.4), ("c", 1.5), ("b", 2.0), ("a", 3.0)]
    assert steady_time_per_run(ends) == pytest.approx((5.0 - 1.5) / 3)
    assert steady_time_per_run([("a", 0.0), ("a", 1.0)]) is None and steady_time_per_run([]) is None


# --- slow: extra processes ------------------------------------------------------------------------

def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(ROOT / "tests"), env.get("PYTHONPATH", "")])
    return env


def _kill(procs):
    for p in procs:
        if p.poll() is None:
            p.terminate()
    for p in procs:
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def die_once(k, marker):
    """A task that kills its worker process the first time run 2 is tried."""
    flag = Path(marker) / "died"
    if k == 2 and not flag.exists():
        flag.write_text("x")
        os._exit(1)
    return {"run": k, "status": "ok"}


@pytest.mark.slow
def test_external_scheduler_gives_the_same_bytes_and_survives_a_dead_worker(batch, scene, tmp_path):
    out, _ = batch
    dask = Path(sys.executable).with_name("dask")
    if not dask.exists():
        pytest.skip("no `dask` command beside this Python")
    file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1",
                               "--port", "0", "--scheduler-file", str(file), "--no-dashboard"],
                              env=_env(), cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(300):
            if file.exists() and file.stat().st_size:
                break
            time.sleep(0.1)
        import json

        address = json.loads(file.read_text())["address"]
        procs.append(subprocess.Popen([str(dask), "worker", address, "--nworkers", "2",
                                       "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"],
                                      env=_env(), cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client

        with Client(address, timeout=30) as c:
            c.wait_for_workers(2, timeout=60)
        result = run_batch(scene, 6, tmp_path / "ext", scheduler=address, progress=False)
        assert result.ok and result.workers == 2
        _same_runs(out, tmp_path / "ext", range(6))
        from splineimu.batch.cluster import dask_client, map_runs

        with dask_client(scheduler=address) as client:
            results, _ = map_runs(client, die_once, range(6), str(tmp_path), progress=False, chunk=3)
        assert (tmp_path / "died").exists()
        assert sorted(r["run"] for r in results if r["status"] == "ok") == list(range(6)), results
    finally:
        _kill(procs)


@pytest.mark.slow
def test_sigkill_then_resume_completes_with_the_same_bytes(batch, scene, tmp_path):
    out, _ = batch
    mine = tmp_path / "mc"
    argv = ["batch", str(scene), "--runs", str(RUNS), "-o", str(mine), "--workers", "2"]
    proc = subprocess.Popen([sys.executable, "-m", "splineimu", *argv], env=_env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and proc.poll() is None:
            if (mine / "runs").is_dir() and sum(p.name.isdigit() for p in (mine / "runs").iterdir()) >= RUNS // 3:
                break
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait()
    time.sleep(3)  # its worker processes notice and stop
    complete = sorted(p for p in (mine / "runs").iterdir() if p.name.isdigit())
    assert RUNS // 3 <= len(complete) < RUNS
    for p in complete:  # only complete run folders
        assert sorted(_files(p)) == sorted(_files(out / "runs" / p.name))
    stamps = {p.name: (p.stat().st_mtime_ns, (p / "mav0" / "imu0" / "data.csv").stat().st_mtime_ns) for p in complete}
    result = run_batch(scene, RUNS, mine, workers=2, resume=True, progress=False)
    assert result.ok and result.skipped >= len(complete) and result.ran == RUNS - result.skipped
    _same_runs(out, mine, range(RUNS))
    assert _rows(mine) == _rows(out)
    for name, st in stamps.items():
        p = mine / "runs" / name
        assert (p.stat().st_mtime_ns, (p / "mav0" / "imu0" / "data.csv").stat().st_mtime_ns) == st
    assert not [p for p in (mine / "runs").iterdir() if not p.name.isdigit()]
