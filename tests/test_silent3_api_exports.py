"""splineimu.api exports every result object of the jobs it exports, lazily."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys

import pytest

import splineimu.api as api


@pytest.mark.parametrize("module", ["synthesis", "scenefile", "batch", "calibration", "integrate",
                                    "preintegration", "clock", "allan"])
def test_result_classes_of_each_job_module_are_exported(module):
    mod = importlib.import_module(f"splineimu.api.{module}")
    classes = [n for n in mod.__all__ if inspect.isclass(getattr(mod, n))]
    assert classes, module
    for name in classes:
        assert name in api.__all__, f"splineimu.api.{name} is missing"
        assert getattr(api, name) is getattr(mod, name)


def test_recording_windows_and_stamp_clock_from_the_package():
    from splineimu.api import RecordingWindows, StampClock, stamp_clock
    from splineimu.api.clock import StampClock as ClockClass
    from splineimu.api.preintegration import RecordingWindows as WindowsClass

    assert RecordingWindows is WindowsClass and StampClock is ClockClass
    clock = StampClock(time_offset_s=0.01, source="given")
    assert clock.true_times_ns([10_000_000, 15_000_000]).tolist() == [0, 5_000_000]
    assert RecordingWindows.__dataclass_fields__["clock"].default_factory is StampClock
    assert callable(stamp_clock) and {"RecordingWindows", "StampClock", "AllanAnalysis"} <= set(dir(api))


def test_new_exports_stay_lazy():
    code = ("import sys, splineimu.api as a; n = 'numpy' in sys.modules; "
            "print(n, 'StampClock' in a.__all__, 'splineimu.api.clock' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "True", "False"]
