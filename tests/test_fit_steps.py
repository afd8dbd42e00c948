"""Steps of the tracking (the poses jump by a few cm and stay there) are told where they are and do
not steer the knot choice of the whole input."""

from __future__ import annotations

import numpy as np
import pytest

from splineimu import fit, lie
from splineimu.spline.glitches import WARN_RESIDUAL_M, without_steps

RATE_HZ = 200.0
STEPS_S = (12.3, 21.7, 33.05, 41.9, 50.45)


def _poses(steps_m, seed=2):
    """60 s of a flight-like motion (an ellipse with a vertical wobble, turning) at 200 Hz with
    0.2 mm / 0.02 deg white noise, the positions moved by ``steps_m[j]`` along a random
    direction from STEPS_S[j] on."""
    t = np.arange(0.0, 60.0, 1.0 / RATE_HZ)
    p = np.stack([2.0 * np.cos(2 * np.pi * t / 12), 1.2 * np.sin(2 * np.pi * t / 12),
                  1.0 + 0.2 * np.sin(2 * np.pi * t / 3.1) + 0.05 * np.sin(2 * np.pi * t / 0.9)], axis=1)
    zero = np.zeros_like(t)
    R = lie.so3_exp(np.stack([0.1 * np.sin(2 * np.pi * t / 2.3), zero, 2 * np.pi * t / 12], axis=1))
    rng = np.random.default_rng(seed)
    P = p + 2e-4 * rng.normal(size=p.shape)
    for ts, size in zip(STEPS_S, steps_m):
        d = rng.normal(size=3)
        P[t >= ts] += size * d / np.linalg.norm(d)
    Rn = R @ lie.so3_exp(np.radians(0.02) * rng.normal(size=p.shape))
    return t, P, lie.matrix_to_quat_xyzw(Rn)


@pytest.fixture(scope="module")
def clean():
    return fit(*_poses([0.0] * len(STEPS_S)), return_report=True)[1]


def test_steps_are_told_and_leave_the_choice_alone(clean):
    """Five steps of 3-8 cm: each told as a jump where it is, and the position knots within 10% of
    those of the same poses without them (they went coarse before the steps were taken out of
    what the choice reads)."""
    _, rep = fit(*_poses([0.03, 0.08, 0.05, 0.04, 0.06]), return_report=True)
    jumps = [(w.t_start_s, w.t_end_s) for w in rep.warnings if w.code == "unexplained_jump"]
    for ts in STEPS_S:
        assert any(a - 0.01 <= ts <= b + 0.01 for a, b in jumps), (ts, jumps)
    assert rep.position_knot_spacing_s == pytest.approx(clean.position_knot_spacing_s, rel=0.1)
    assert "unexplained_jump" not in {w.code for w in clean.warnings}


def test_without_steps_takes_each_step_off_the_poses_after_it():
    t, P, _ = _poses([0.05, 0.0, 0.0, 0.0, 0.0])
    t0, P0, _ = _poses([0.0] * 5)
    out = without_steps(t, P, np.ones(t.size), WARN_RESIDUAL_M)
    # the step is taken off to within the noise of one step (the motion's jerk and the noise
    # of the poses around it)
    assert np.max(np.abs((out - out[0]) - (P0 - P0[0]))) < 2e-3
    assert without_steps(t0, P0, np.ones(t0.size), WARN_RESIDUAL_M) is P0


def test_a_glitch_and_back_is_not_a_step():
    """A glitch (5 cm for 0.2 s, then back) is a pair of steps: dropped as before, not taken off."""
    t, P, q = _poses([0.0] * 5)
    P = P.copy()
    P[(t >= 30.0) & (t < 30.2)] += np.array([0.05, 0.0, 0.0])
    assert without_steps(t, P, np.ones(t.size), WARN_RESIDUAL_M) is P
    _, rep = fit(t, P, q, return_report=True)
    assert "outliers_dropped" in {w.code for w in rep.warnings}
    assert "unexplained_jump" not in {w.code for w in rep.warnings}


def test_the_real_files_steps_are_told():
    """OpenVINS' udel_garage trajectory jumps 3 m at its last pose, TUM RGB-D fr2_desk's mocap
    steps by 14-38 mm at four places: both were told nothing before the lone steps were read."""
    from conftest import require_shared

    from splineimu.io import read_tum

    for name, where in (("udel_garage.txt", [265.43]), ("fr2_desk_groundtruth.txt", [2.28, 62.33, 83.38, 84.42])):
        folder = "openvins_sim" if name.startswith("udel") else "tum_rgbd"
        track = read_tum(require_shared(folder, name), repeated_stamps="first")
        _, rep = fit(track, return_report=True)
        jumps = [(w.t_start_s, w.t_end_s) for w in rep.warnings if w.code == "unexplained_jump"]
        for ts in where:
            assert any(a - 0.02 <= ts <= b + 0.02 for a, b in jumps), (name, ts, jumps)


def test_box_steps_read_a_jump_and_not_smooth_motion():
    """The steps of 8-pose box means: a jump by d reads d at its pose (and -d where the poses
    come back), a quadratic in time nothing (to rounding), white noise 1/sqrt(8) of the single
    steps' (:func:`_steps`; both weigh the poses 1.5, -1.5, 0.5, -0.5, per box), and nothing
    across a gap."""
    from splineimu.spline.glitches import _box_steps, _steps

    t = np.arange(2000) / 200.0
    Y = np.c_[0.3 * t**2, 2.0 * t, np.zeros_like(t)]
    np.testing.assert_allclose(_box_steps(t, Y, 8), 0.0, atol=1e-12)
    Yg = Y.copy()
    Yg[1000:1040, 0] += 0.01
    K = _box_steps(t, Yg, 8)
    assert K[1000, 0] == pytest.approx(0.01, abs=1e-12) and K[1040, 0] == pytest.approx(-0.01, abs=1e-12)
    assert np.abs(K[:980]).max() < 1e-12 and np.abs(K[1060:]).max() < 1e-12
    E = np.random.default_rng(0).normal(scale=1e-3, size=(200_000, 3))
    te = np.arange(E.shape[0]) / 200.0
    ratio = np.std(_box_steps(te, E, 8)[20:-20]) / np.std(_steps(te, E)[5:-5])
    assert ratio == pytest.approx(1.0 / np.sqrt(8.0), rel=0.02)
    tg = np.r_[t[:1000], t[1000:] + 5.0]  # a 5 s gap: the boxes spanning it read nothing
    assert np.all(_box_steps(tg, Yg, 8)[985:1016] == 0.0)
