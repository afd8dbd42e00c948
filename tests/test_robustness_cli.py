"""The command line as a user meets it: exit codes, one short message, no traceback, and
signals that leave nothing half-written (subprocesses)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent


def _default_sigint():
    # a shell starts background jobs with SIGINT ignored, and the children inherit that (Python
    # then installs no KeyboardInterrupt handler): the user's Ctrl-C reaches a foreground program
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.Popen([sys.executable, "-m", "splineimu", *args], cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)


def _run(args, cwd):
    p = _start(args, cwd)
    out, err = p.communicate(timeout=300)
    return p.returncode, out, err


def _leftovers(d: Path):
    return sorted(str(p.relative_to(d)) for p in d.rglob(".*") if ".tmp-" in p.name or ".old-" in p.name)


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 128 + signal.SIGTERM), (signal.SIGINT, 130)])
def test_signal_during_a_long_write_leaves_nothing(tmp_path, sig, code):
    (tmp_path / "X").mkdir()
    (tmp_path / "X" / "keep.txt").write_text("before")
    p = _start(["scene", "static", "--duration", "30000", "--imu", "adis16448", "--seed", "1", "-o", "X", "--force"],
               tmp_path)
    deadline = time.monotonic() + 240
    while not list(tmp_path.glob(".X.tmp-*/**/imu0/data.csv")) and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert p.poll() is None, "finished before the signal could be sent"
    os.kill(p.pid, sig)
    out, err = p.communicate(timeout=120)
    assert p.returncode == code
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("note: ")]  # the 4.2 GB output's size
    assert "Traceback" not in err and len(lines) == 1, err
    assert _leftovers(tmp_path) == []
    assert [q.name for q in (tmp_path / "X").iterdir()] == ["keep.txt"]  # what was there is untouched


@pytest.mark.parametrize("args, words", [
    (["run", "deep.yaml"], "deep.yaml"),
    (["scene", "static", "--duration", "1", "-o", "f.txt/out"], "f.txt"),
    (["integrate", "imu.csv", "--init", "gt.csv", "-o", "imu.csv", "--force"], "input"),
    (["integrate", "imu.csv", "--init", "gt.csv", "-o", "old.tum"], "--force"),
    (["from-euroc", "p.tum", "-o", "out"], "from-tum"),
])
def test_user_errors_are_one_line_without_traceback(tmp_path, args, words):
    (tmp_path / "deep.yaml").write_text("a: " + "[" * 5000 + "]" * 5000 + "\n")
    (tmp_path / "f.txt").write_text("x")
    (tmp_path / "old.tum").write_text("precious")
    imu = "".join(f"{1000000000 + i * 5000000},0,0,0,0,0,9.81\n" for i in range(50))
    (tmp_path / "imu.csv").write_text(imu)
    (tmp_path / "gt.csv").write_text("".join(f"{1000000000 + i * 50000000},0,0,0,1" + ",0" * 12 + "\n"
                                             for i in range(5)))
    (tmp_path / "p.tum").write_text("".join(f"{1700000000 + i * 0.01:.2f} 0 0 0 0 0 0 1\n" for i in range(50)))
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    rc, out, err = _run(args, tmp_path)
    lines = err.strip().splitlines()
    assert rc == 1 and "Traceback" not in err and len(lines) == 1, err
    assert words in lines[0]
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
