"""The pure-Python path (NUMBA_DISABLE_JIT=1) must agree with the compiled one.

The Lie, spline and scene suites, the fit Jacobian checks and the doctests of the Lie and spline
modules (collected by ``--doctest-modules`` in pyproject's addopts) run again in a subprocess with
numba's jit disabled (a few seconds); the whole suite that way is behind ``-m slow``.
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
def test_whole_suite_without_jit():
    _run(["tests", "splineimu", "--deselect", "tests/test_nojit.py"], timeout=5400)
