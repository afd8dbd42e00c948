"""The pure-Python path (NUMBA_DISABLE_JIT=1) must agree with the compiled one.

The Lie, spline and scene suites, the fit Jacobian checks and the doctests of the Lie and spline
modules (collected by ``--doctest-modules`` in pyproject's addopts) run again in a subprocess with
numba's jit disabled (a few seconds); the suites of the other kernels (cross-validation, Lie
batch, integration, preintegration, running median, text formatting, noise) and one test each
of the Allan and stamp-clock kernels that way are behind ``-m slow`` (about 4 min alone on the
2-core machine: the stamp test 2 min of it). The whole suite without jit takes hours there (the
other stamp-clock and Allan tests run long series through the kernels: one stamp test alone ran
over 5 min), so it is not a test.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


def _run(args, timeout):
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *args],
                          cwd=HERE.parent, env=env, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]


def test_core_suites_without_jit():
    _run(["tests/test_lie.py", "tests/test_spline.py", "tests/test_spline_imu_kernel.py", "tests/test_scenes.py",
          "tests/test_gauss_newton.py",
          "tests/test_fit.py::test_rotation_gradient_matches_finite_differences",
          "tests/test_fit.py::test_se3_gradient_matches_finite_differences",
          "splineimu/lie.py", "splineimu/spline"], timeout=900)


@pytest.mark.slow
def test_kernel_suites_without_jit():
    _run(["-m", "not slow", "tests/test_knots_kernels.py", "tests/test_lie_kernels.py", "tests/test_integrate.py",
          "tests/test_preintegration.py", "tests/test_running_median.py", "tests/test_io_writers.py",
          "tests/test_noise.py", "tests/test_allan.py::test_equals_allantools_oadev_freq",
          "tests/test_stamps.py::test_receive_stamps_are_put_back_on_the_capture_clock[ellipse-0]"], timeout=1800)
