"""The vectorized fast path of ``parse_stamps`` (digit strings read from their code points)
against numpy's own string-to-integer conversion and the exact Decimal path."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu.io import timestamps as ts


@pytest.mark.parametrize("seed", range(5))
def test_digit_strings_read_as_numpy_reads_them(seed):
    rng = np.random.default_rng(seed)
    digits = list("0123456789")
    strs = ["".join(rng.choice(digits, size=int(m))) for m in rng.integers(1, 19, size=300)]
    a = np.array(strs, dtype=str)
    np.testing.assert_array_equal(ts._digits_value(a), a.astype(np.int64))
    frac = np.array([s[:9] for s in strs] + [""], dtype=str)  # decimals, none at all too
    np.testing.assert_array_equal(ts._digits_value(frac, width=9), np.strings.ljust(frac, 9, "0").astype(np.int64))


def test_seconds_stamps_match_the_exact_decimal_path():
    rng = np.random.default_rng(7)
    whole = rng.integers(0, 9_200_000_000, size=500)  # below 2**63 ns
    decimals = rng.integers(0, 10, size=500)
    strs = [f"{w}" + ("" if d == 0 else "." + "".join(map(str, rng.integers(0, 10, size=d))))
            for w, d in zip(whole, decimals)]
    t_ns, n_rounded = ts.parse_stamps(strs, "s")
    assert n_rounded == 0
    assert t_ns.tolist() == [ts._slow_stamp(s, "s", None, None)[0] for s in strs]
