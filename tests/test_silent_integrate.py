"""Dead reckoning of data on an IMU clock with offset and drift, and its output location.

The ellipse, 10 s at 200 Hz, noise-free: dead-reckoned against its own ground truth it ends
3e-8 m off. Taking the stamps of a clock 12.3 ms ahead for true time put it 1.19 m off
(1000 ppm of drift: 0.07 m), and nothing was said (the last stamp lay past the ground truth,
so not even the final error was printed).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from splineimu import cli
from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, run_job
from splineimu.api.integrate import dead_reckon
from splineimu.errors import InputError
from splineimu.imu.timing import TimingModel
from splineimu.scenes import make_scene


def _dataset(tmp_path, name, **timing):
    job = SynthesisJob(SceneInput("ellipse", duration_s=10.0), ImuOptions(rate_hz=200.0, seed=1, timing=timing or None),
                       OutputOptions(str(tmp_path / name)))
    return run_job(job).out_dir / "mav0" / "imu0" / "data.csv"


def _error_at_true_time(res):
    """Position error [m] of each row against the scene at the row's stated time ``t_ns``."""
    scene = make_scene("ellipse", duration_s=10.0)
    k = scene.kinematics(scene.t_s_from_ns(res.t_ns))
    return np.linalg.norm(res.trajectory.position_world - k.position_world, axis=1)


def test_true_times_invert_the_clock():
    tm = TimingModel(time_offset_s=0.0123, clock_drift_ppm=50.0)
    st = tm.sample_times(5_000_000_000, 65_000_000_000, 200.0)
    np.testing.assert_array_equal(tm.true_times_ns(st.stamp_ns), st.true_ns)
    np.testing.assert_array_equal(TimingModel(time_offset_s=-0.5).true_times_ns([1_000_000_000]), [1_500_000_000])


@pytest.mark.parametrize("timing, uncorrected_m", [({"time_offset_s": 0.0123}, 1.19),
                                                   ({"time_offset_s": 0.0123, "clock_drift_ppm": 50.0}, 1.19),
                                                   ({"clock_drift_ppm": 1000.0}, 0.073)])
def test_the_recorded_clock_is_undone(tmp_path, timing, uncorrected_m):
    imu = _dataset(tmp_path, "d", **timing)
    res = dead_reckon(imu)
    err = _error_at_true_time(res)
    assert err.max() < 1e-7  # as without a clock model (3e-8 m)
    assert res.final_position_error_m < 1e-7
    assert res.t_ns[0] == 0 and res.stamp_ns[0] == int(round(timing.get("time_offset_s", 0.0) * 1e9))
    assert res.time_offset_s == timing.get("time_offset_s", 0.0)
    assert res.clock_drift_ppm == timing.get("clock_drift_ppm", 0.0)
    report = imu.parent.parent.parent / "report.json"
    assert res.clock_line == (f"IMU stamps corrected to true time (as recorded in {report}): clock offset "
                              f"{res.time_offset_s:g} s, drift {res.clock_drift_ppm:g} ppm")
    # the old reading, now asked for explicitly: the stamps taken for true time
    raw = dead_reckon(imu, time_offset_s=0.0, clock_drift_ppm=0.0)
    np.testing.assert_array_equal(raw.t_ns, raw.stamp_ns)
    assert raw.clock_line == ""
    ok = raw.t_ns <= 10_000_000_000
    assert _error_at_true_time_clipped(raw, ok)[-1] == pytest.approx(uncorrected_m, abs=0.01)


def _error_at_true_time_clipped(res, ok):
    scene = make_scene("ellipse", duration_s=10.0)
    k = scene.kinematics(scene.t_s_from_ns(res.t_ns[ok]))
    return np.linalg.norm(res.trajectory.position_world[ok] - k.position_world, axis=1)


def test_the_command_says_so_and_writes_true_times(tmp_path, capsys):
    imu = _dataset(tmp_path, "d", time_offset_s=0.0123)
    out = tmp_path / "dr.tum"
    assert cli.main(["integrate", str(imu), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "IMU stamps corrected to true time (as recorded in" in text and "clock offset 0.0123 s, drift 0 ppm" in text
    assert "final position differs from the ground truth by 2.9" in text and "e-08 m" in text
    first = out.read_text().splitlines()[1]
    assert first.startswith("0.000000000 ")  # true time, as groundtruth.tum
    assert cli.main(["integrate", str(imu), "--time-offset", "0.01", "-o", str(tmp_path / "g.tum")]) == 0
    text = capsys.readouterr().out
    assert "(as given): clock offset 0.01 s" in text
    assert (tmp_path / "g.tum").read_text().splitlines()[1].startswith("0.002300000 ")


def test_stamp_noise_is_noted_and_a_bad_record_refused(tmp_path):
    imu = _dataset(tmp_path, "d", time_offset_s=0.0123, stamp_noise_s=1e-5)
    res = dead_reckon(imu)
    report = imu.parent.parent.parent / "report.json"
    assert res.notes == [f"the stamps carry white noise of 1e-05 s ({report}): only the clock's offset and "
                         "drift are undone"]
    k = res.skipped_samples + np.arange(5)  # (a first stamp moved before the ground truth is skipped)
    assert np.abs(res.t_ns[:5] - k * 5_000_000).max() < 100_000  # noise of 10 us left
    data = json.loads(report.read_text())
    data["timing"]["model"]["clock_drift_ppm"] = "fast"
    report.write_text(json.dumps(data))
    with pytest.raises(InputError) as e:
        dead_reckon(imu)
    assert str(e.value) == f"{report}: `timing.model.clock_drift_ppm`: `clock_drift_ppm` must be a number, got 'fast'"
    assert dead_reckon(imu, clock_drift_ppm=0.0).clock_drift_ppm == 0.0  # a flag overrides the record


def test_a_missing_output_folder_is_created_as_by_the_other_commands(tmp_path, capsys):
    """`integrate -o new/x.tum` was refused ('output folder does not exist') where scene,
    from-tum and preintegrate create the folder."""
    imu = _dataset(tmp_path, "d")
    out = tmp_path / "new" / "sub" / "dr.tum"
    assert cli.main(["integrate", str(imu), "-o", str(out)]) == 0
    assert f"-> {out}" in capsys.readouterr().out
    lines = out.read_text().splitlines()
    assert len(lines) == 2002 and lines[1].startswith("0.000000000 ")
    assert sorted(p.name for p in out.parent.iterdir()) == ["dr.tum"]  # no temporary file left
    before = out.read_bytes()
    assert cli.main(["integrate", str(imu), "--method", "euler", "-o", str(out)]) == 1  # no silent overwrite
    assert capsys.readouterr().err.strip() == f"splineimu integrate: error: output file '{out}' exists; use --force " \
        "to replace it"
    assert out.read_bytes() == before
    assert cli.main(["integrate", str(imu), "--method", "euler", "--force", "-o", str(out)]) == 0
    assert out.read_bytes() != before
    (tmp_path / "afile").write_text("")
    assert cli.main(["integrate", str(imu), "-o", str(tmp_path / "afile" / "x.tum")]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "afile" in err and "Traceback" not in err
