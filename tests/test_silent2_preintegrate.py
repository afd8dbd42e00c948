"""Preintegration of data on an IMU clock with offset and drift.

The ellipse, 10 s at 200 Hz, noise-free, preintegrated over 1 s windows (200 samples): the
position deltas differ from the ground truth's by at most 6.5e-5 m (the midpoint rule's
discretization). Its stamps written on a clock 12.3 ms ahead and read as true time gave
7.9e-2 m (1000 ppm of drift: 5.1e-2 m) and one window less, and nothing was said.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from splineimu import cli
from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, run_job
from splineimu.api.clock import StampClock, stamp_clock
from splineimu.api.preintegration import evaluate_recording
from splineimu.errors import ConfigError, InputError


def _dataset(folder, **timing):
    job = SynthesisJob(SceneInput("ellipse", duration_s=10.0), ImuOptions(rate_hz=200.0, seed=1, timing=timing or None),
                       OutputOptions(str(folder)))
    return run_job(job).out_dir


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    return evaluate_recording(_dataset(tmp_path_factory.mktemp("plain") / "d"), every=200)


@pytest.mark.parametrize("timing, uncorrected_m", [({"time_offset_s": 0.0123}, 0.0793),
                                                   ({"clock_drift_ppm": 1000.0}, 0.0511)])
def test_the_recorded_clock_is_undone(tmp_path, plain, timing, uncorrected_m):
    out = _dataset(tmp_path / "d", **timing)
    res = evaluate_recording(out, every=200)
    assert plain.error_p_m.max() == pytest.approx(6.467e-5, rel=1e-3)
    assert len(res) == len(plain) == 10
    assert res.error_p_m.max() == pytest.approx(plain.error_p_m.max(), rel=0.01)
    assert res.error_v_m_s.max() == pytest.approx(plain.error_v_m_s.max(), rel=0.01)
    assert res.t_i_ns[0] == plain.t_i_ns[0] == 0  # windows on true time, the ground truth's
    offset, drift = timing.get("time_offset_s", 0), timing.get("clock_drift_ppm", 0)
    assert res.clock_line == (f"IMU stamps corrected to true time (as recorded in {out / 'report.json'}): clock "
                              f"offset {offset:g} s, drift {drift:g} ppm")
    # the old reading, now asked for explicitly: the stamps taken for true time
    raw = evaluate_recording(out, every=200, time_offset_s=0, clock_drift_ppm=0.0)
    assert raw.clock_line == "" and raw.clock.is_identity
    assert len(raw) == 9
    assert raw.error_p_m.max() == pytest.approx(uncorrected_m, rel=0.01)


def test_the_command_says_so(tmp_path, capsys):
    out = _dataset(tmp_path / "d", time_offset_s=0.0123)
    assert cli.main(["preintegrate", str(out), "--every", "200"]) == 0
    text = capsys.readouterr().out
    assert f"IMU stamps corrected to true time (as recorded in {out / 'report.json'}): clock offset 0.0123 s, " \
           "drift 0 ppm" in text
    assert "max error: p 6.467e-05 m" in text
    assert cli.main(["preintegrate", str(out), "--every", "200", "--time-offset", "0"]) == 0
    text = capsys.readouterr().out
    assert "corrected" not in text and "max error: p 7.934e-02 m" in text
    assert cli.main(["preintegrate", str(out), "--every", "200", "--time-offset", "0.01"]) == 0
    text = capsys.readouterr().out
    assert "IMU stamps corrected to true time (as given): clock offset 0.01 s, drift 0 ppm" in text
    assert cli.main(["preintegrate", str(out), "--clock-drift-ppm", "nan"]) == 1
    assert capsys.readouterr().err == "splineimu preintegrate: error: `--clock-drift-ppm` must be finite, got nan\n"
    assert cli.main(["integrate", str(out / "mav0/imu0/data.csv"), "--clock-drift-ppm", "2e5",
                     "-o", str(tmp_path / "x.tum")]) == 1
    assert capsys.readouterr().err == ("splineimu integrate: error: `--clock-drift-ppm` must be within +-1e5 ppm, "
                                       "got 200000\n")  # as from-tum says it


def test_stamp_noise_is_noted_and_a_bad_record_refused(tmp_path, capsys):
    out = _dataset(tmp_path / "d", time_offset_s=0.0123, stamp_noise_s=1e-5)
    report = out / "report.json"
    note = f"the stamps carry white noise of 1e-05 s ({report}): only the clock's offset and drift are undone"
    res = evaluate_recording(out, every=200)
    assert res.notes[0] == note
    assert res.error_p_m.max() < 1e-3  # noise of 10 us on the stamps is left (7.9e-2 m uncorrected)
    assert cli.main(["preintegrate", str(out), "--every", "200"]) == 0
    assert f"note: {note}" in capsys.readouterr().err
    data = json.loads(report.read_text())
    data["timing"]["model"]["time_offset_s"] = "late"
    report.write_text(json.dumps(data))
    with pytest.raises(InputError) as e:
        evaluate_recording(out, every=200)
    assert str(e.value) == f"{report}: `timing.model.time_offset_s`: `time_offset_s` must be a number, got 'late'"
    assert evaluate_recording(out, every=200, time_offset_s=0.0123).clock.source == "given"


def test_one_clock_for_both_jobs():
    clock = StampClock(time_offset_s=0.0123, clock_drift_ppm=50.0, source="given")
    stamp = 12_300_000 + np.arange(0, 10**10, 5_000_000)
    np.testing.assert_array_equal(clock.true_times_ns(stamp)[:2], [0, 4_999_750])
    assert stamp_clock("nowhere.csv", 0, 0) == StampClock()
    with pytest.raises(ConfigError) as e:
        stamp_clock("nowhere.csv", time_offset_s=float("inf"))
    assert str(e.value) == "`time_offset_s` must be finite, got inf"  # the command names its flag
