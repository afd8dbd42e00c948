"""Vibration above the IMU's Nyquist frequency: kept (a sensor without an anti-aliasing filter
aliases too) and told, with the frequency, the Nyquist frequency and where it appears."""

from __future__ import annotations

import json

import numpy as np
import pytest

from splineimu import cli
from splineimu.api import ImuOptions, OutputOptions, SceneInput, SynthesisJob, run_job
from splineimu.imu.vibration import VibrationModel, _fold_band

VIB = {"accel": [{"freq_hz": 237.0, "amplitude": [0.5, 0.0, 0.0]},
                 {"band_hz": [60.0, 150.0], "psd": [1e-4, 1e-4, 4e-4]}],
       "gyro": [{"freq_hz": 37.0, "amplitude": [0.0, 0.0, 0.01]}]}
MSG_237 = ("vibration.accel[0] at 237 Hz is above the Nyquist frequency 100 Hz of the 200 Hz samples: it appears "
           "aliased at 37 Hz")
MSG_BAND = ("vibration.accel[1], band [60, 150] Hz, extends above the Nyquist frequency 100 Hz of the 200 Hz "
            "samples: its part above 100 Hz appears aliased in [50, 100] Hz")


def test_aliased_vibration_is_written_and_reported(tmp_path, capsys):
    (tmp_path / "vib.yaml").write_text(json.dumps(VIB))
    out = tmp_path / "o"
    assert cli.main(["scene", "ellipse", "--duration", "4", "--vibration", str(tmp_path / "vib.yaml"), "--seed", "3",
                     "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.splitlines() == [f"warning: {MSG_237}", f"warning: {MSG_BAND}"]  # the 37 Hz gyro tone: no warning
    rep = json.loads((out / "report.json").read_text())
    assert rep["warnings"] == [{"code": "vibration_aliased", "message": MSG_237},
                               {"code": "vibration_aliased", "message": MSG_BAND}]
    # the data do alias: the 237 Hz accel tone is a 37 Hz tone of the same amplitude in vibration.csv
    vib = np.loadtxt(out / "mav0" / "imu0" / "vibration.csv", delimiter=",", comments="#")
    n = 800  # 4 s at 200 Hz: 0.25 Hz bins, 37 Hz on bin 148
    spec = np.abs(np.fft.rfft(vib[:n, 4])) * 2 / n  # accel x: the tone and the band
    assert spec[148] == pytest.approx(0.5, abs=0.03)


def test_mean_sampling_states_the_attenuation_and_a_low_rate_warns_too():
    model = VibrationModel.from_dict({"gyro": [{"freq_hz": 150.0, "amplitude": [0.1, 0.0, 0.0]}]})
    (w,) = model.aliasing_warnings(200.0, "mean")
    # mean over 5 ms of a 150 Hz tone: |sin(0.75 pi) / (0.75 pi)| = 0.300
    assert w["message"] == ("vibration.gyro[0] at 150 Hz is above the Nyquist frequency 100 Hz of the 200 Hz samples: "
                            "it appears aliased at 50 Hz (the interval mean leaves 0.3 of its amplitude)")
    assert model.aliasing_warnings(400.0) == []  # 150 Hz < 200 Hz: nothing to say
    assert model.aliasing_warnings(300.0) == []  # exactly at Nyquist: not above it
    job = SynthesisJob(SceneInput("static", duration_s=1.0), ImuOptions(rate_hz=100.0, seed=1, vibration=VIB),
                       OutputOptions(None))
    res = run_job(job, write=False)
    assert [n.split(" is above")[0].split(",")[0] for n in res.notes] == [
        "warning: vibration.accel[0] at 237 Hz", "warning: vibration.accel[1]"]  # 37 Hz < Nyquist 50 Hz
    assert res.notes[0].endswith("Nyquist frequency 50 Hz of the 100 Hz samples: it appears aliased at 37 Hz")
    assert res.report["warnings"][1]["message"].endswith("its part above 50 Hz appears aliased in [0, 50] Hz")


@pytest.mark.parametrize("band, rate, image", [((100, 150), 200, (50, 100)), ((150, 250), 200, (0, 50)),
                                               ((250, 350), 200, (50, 100)), ((180, 210), 200, (0, 20)),
                                               ((100, 250), 200, (0, 100)), ((60, 90), 100, (10, 40))])
def test_band_images(band, rate, image):
    assert _fold_band(*band, rate) == pytest.approx(image, abs=1e-12)
