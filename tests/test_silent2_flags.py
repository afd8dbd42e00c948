"""Errors of the commands name the flag the user typed, not the library argument behind it.

`splineimu compare --t-offset nan` said "`t_offset` must be finite", `calibrate --window 0`
"`window_s` must be positive", `allan --rate nan` "`rate_hz` must be finite": names the user
never typed. The synthesis commands already named their flags; these do now too.
"""

from __future__ import annotations

import importlib.util
import json

import pytest

from splineimu import cli
from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, run_job


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    imu = ImuOptions(rate_hz=100.0, seed=1, timing={"time_offset_s": 0.01})
    job = SynthesisJob(SceneInput("static", duration_s=4.0), imu,
                       OutputOptions(str(tmp_path_factory.mktemp("rec") / "d")))
    return run_job(job).out_dir


def _error(capsys, argv):
    assert cli.main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    return err.strip()


def test_library_names_become_flags(recording, tmp_path, capsys):
    imu = str(recording / "mav0" / "imu0" / "data.csv")
    tum = str(recording / "groundtruth.tum")
    cases = [
        (["compare", tum, tum, "--t-offset", "nan"], "splineimu compare: error: `--t-offset` must be finite, got nan"),
        (["compare", tum, tum, "--t-max-diff", "-1"],
         "splineimu compare: error: `--t-max-diff` must be zero or positive, got -1.0"),
        (["allan", imu, "--rate", "nan"], "splineimu allan: error: `--rate` must be finite, got nan"),
        (["calibrate", "accel", imu, "--window", "0"],
         "splineimu calibrate: error: `--window` must be positive, got 0.0"),
        (["calibrate", "accel", imu, "--gravity-magnitude", "-1"],
         "splineimu calibrate: error: `--gravity-magnitude` must be positive, got -1.0"),
        (["integrate", imu, "--gravity", "0", "0", "nan", "-o", str(tmp_path / "x.tum")],
         "splineimu integrate: error: `--gravity` contains NaN or inf (first at index 2)"),
        (["preintegrate", str(recording), "--time-offset", "inf"],
         "splineimu preintegrate: error: `--time-offset` must be finite, got inf"),
    ]
    if importlib.util.find_spec("evo") is None:  # (compare says evo is missing before it reads a flag)
        cases = [c for c in cases if c[0][0] != "compare"]
    for argv, message in cases:
        assert _error(capsys, argv) == message


def test_a_key_of_a_file_keeps_its_name(recording, capsys):
    report = recording / "report.json"
    data = json.loads(report.read_text())
    data["timing"]["model"]["time_offset_s"] = "late"
    report.write_text(json.dumps(data))
    assert _error(capsys, ["preintegrate", str(recording)]) == (
        f"splineimu preintegrate: error: {report}: `timing.model.time_offset_s`: `time_offset_s` must be a number, "
        "got 'late'")
