"""The fit's running median (spline/glitches.py) against scipy.ndimage's median_filter."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import median_filter

from splineimu._kernels.median import running_median
from splineimu.spline import glitches


@pytest.mark.parametrize("n", [1, 2, 3, 10, 200, 2001])
@pytest.mark.parametrize("size", [1, 3, 5, 201, 4001])
def test_kernel_equals_median_filter(n, size):
    rng = np.random.default_rng(n * 7919 + size)
    for x in (rng.normal(size=n), rng.integers(0, 4, size=n).astype(np.float64),  # many ties
              np.cumsum(rng.exponential(size=n))):  # increasing: every value enters at the top
        out = np.empty(n)
        running_median(x, size, out)
        np.testing.assert_array_equal(out, median_filter(x, size=size, mode="nearest"))


def test_checks_running_median_both_paths(monkeypatch):
    rng = np.random.default_rng(3)
    x = np.abs(rng.standard_cauchy(5000))
    want = median_filter(x, size=201, mode="mirror")  # the ends mirrored
    np.testing.assert_array_equal(glitches._running_median(x, 200.7), want)  # width -> odd size 201
    monkeypatch.setattr(glitches, "KERNEL_MEDIAN_MAX_WORK", 0)  # long inputs: scipy's
    np.testing.assert_array_equal(glitches._running_median(x, 200.7), want)
    assert glitches._running_median(np.arange(4.0), 1.0).tolist() == [1.0, 1.0, 2.0, 2.0]  # size at least 3, mirrored


def test_the_local_level_at_the_ends_is_not_the_end_value():
    """A small first residual must not set the level of the first half window."""
    x = np.ones(1001)
    x[0] = 1e-3
    assert glitches._running_median(x, 201.0)[:100].min() == 1.0
