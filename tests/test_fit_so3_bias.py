"""The rotation moved a rung finer when the SO3 spline's own bias far exceeds the R3 proxy's the
knot choice measured (splineimu.spline.fit._rotation_bias), against the scene's exact gyro."""

from __future__ import annotations

import pytest
from fit_scenes import scene_errors, scene_poses

from splineimu import fit, lie
from splineimu.spline.ladder import _LADDER


def _poses(seed):
    # lecture ellipse (turns about moving axes), white noise of 0.5 mm / 0.05 deg, 200 Hz, 60 s
    sc, t, p, R = scene_poses("ellipse", "white", 60.0, 200.0, seed, 0.5)
    return sc, t, p, lie.matrix_to_quat_xyzw(R)


def test_a_large_so3_excess_moves_the_rotation_a_rung_finer():
    sc, t, p, q = _poses(2)
    spl, rep = fit(t, p, q, return_report=True)
    c = rep.knot_choice["rotation"]
    was = c["moved_by_so3_bias_from_s"]  # 1017 ms, where the proxy predicted 0.67x the measured error
    assert rep.knot_spacing_s == pytest.approx(was / _LADDER, rel=0.05)
    assert c["knot_phase"] == 0.0 and spl.t0_s == 0.0
    g, _ = scene_errors(sc, spl, 60.0)
    stay = fit(t, p, q, order=rep.order, knot_spacing_s=was, position_order=rep.position_order,
               position_knot_spacing_s=rep.position_knot_spacing_s)
    g_stay, _ = scene_errors(sc, stay, 60.0)
    assert g < 0.8 * g_stay, (g, g_stay)  # measured 0.000272 against 0.00040 rad/s
    assert 1 / 3 < rep.predicted_gyro_rms_rad_s / g < 3
    assert rep.predicted_gyro_rms_rad_s == c["predicted_rms"]


def test_a_given_spacing_is_not_moved():
    sc, t, p, q = _poses(2)
    _, rep = fit(t, p, q, knot_spacing_s=1.0169, return_report=True)
    assert "moved_by_so3_bias_from_s" not in rep.knot_choice["rotation"]
    assert rep.knot_spacing_s == pytest.approx(1.0169, rel=0.01)


def test_the_standard_noise_is_not_moved():
    # 1 mm / 0.1 deg: the excess stays below the threshold (scene sweep: none of 360 cases moved)
    sc, t, p, R = scene_poses("ellipse", "white", 60.0, 200.0, 9)
    _, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    assert "moved_by_so3_bias_from_s" not in rep.knot_choice["rotation"]
