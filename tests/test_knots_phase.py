"""The rotation knot grid's phase (splineimu.spline.phase): layouts, the choice on rough and
smooth motion against the truth, and what the spline and report say."""

from __future__ import annotations

import pytest
from fit_scenes import scene_errors, scene_poses

from splineimu import fit, lie
from splineimu.spline.banded import grid_layout, layout, shifted_layout
from splineimu.spline.phase import PHASES


@pytest.mark.parametrize("origin", [-0.37, 0.0, 0.2, 5.0, -1e3])
@pytest.mark.parametrize("dt", [0.01, 0.3, 2.9])
def test_grid_layout_covers_the_span_on_the_grid(origin, dt):
    t_first, t_last = 1.1, 61.7
    t0, h, nseg, ncontrol = grid_layout(t_first, t_last, origin, dt, 5)
    assert h == dt and ncontrol == nseg + 4
    # the last grid knot at or before the first pose (to the rounding of the grid's times)
    assert t0 <= t_first + 1e-9 * dt and t_first < t0 + dt * (1 + 1e-9)
    assert t0 + nseg * dt >= t_last - 1e-9 * dt and t0 + (nseg - 1) * dt < t_last
    m = (t0 - origin) / dt
    assert abs(m - round(m)) < 1e-6  # on the grid through the origin


def test_shifted_layout():
    assert shifted_layout(0.0, 60.0, 0.55, 6, 0.0) == layout(0.0, 60.0, 0.55, 6)
    t0, dt, nseg, n = layout(0.0, 60.0, 0.55, 6)
    for phase in PHASES[1:]:
        s0, sdt, snseg, sn = shifted_layout(0.0, 60.0, 0.55, 6, phase)
        assert sdt == dt and snseg == nseg + 1 and sn == n + 1
        assert s0 == pytest.approx(-phase * dt, abs=1e-12)


def _fit(name, noise, seed, rate=200.0, **kw):
    sc, t, p, R = scene_poses(name, noise, 60.0, rate, seed)
    q = lie.matrix_to_quat_xyzw(R)
    spl, rep = fit(t, p, q, return_report=True, **kw)
    return sc, (t, p, q), spl, rep


def test_rough_motion_gets_the_grid_that_follows_its_turns():
    # rate-table scene (turns about fixed axes), noise drawn at 100 Hz and interpolated to
    # 200 Hz, seed 5: the grid on the first pose gives 0.00320 rad/s, the chosen one 0.00305
    sc, (t, p, q), spl, rep = _fit("rate-table", "upsampled", 5)
    phase = rep.knot_choice["rotation"]["knot_phase"]
    assert phase in PHASES[1:]
    # the rotation grid starts before the first pose, the spline covers the poses' span exactly
    assert spl.t0_s == pytest.approx(-phase * spl.dt_s, abs=1e-12)
    assert spl.position_t0_s == 0.0
    assert (spl.t_min_s, spl.t_max_s) == (0.0, 60.0)
    assert rep.n_control == spl.n_control == round(60.0 / spl.dt_s) + rep.order
    assert "before the first pose" in rep.summary()
    g, _ = scene_errors(sc, spl, 60.0)
    on_pose = fit(t, p, q, order=rep.order, knot_spacing_s=rep.knot_spacing_s, position_order=rep.position_order,
                  position_knot_spacing_s=rep.position_knot_spacing_s)
    g0, _ = scene_errors(sc, on_pose, 60.0)
    assert g < 0.98 * g0, (g, g0)
    # the predicted error is the interior's at that spacing (within the acceptance's factor 3)
    assert 1 / 3 < rep.predicted_gyro_rms_rad_s / g < 3


def test_smooth_motion_keeps_the_grid_on_the_first_pose():
    # lecture ellipse, AR(1) noise: the residuals over the grids spread as the noise's do (their
    # ranking there is not the gyro's), so the grid stays
    _, _, spl, rep = _fit("ellipse", "ar1", 5)
    assert rep.knot_choice["rotation"]["knot_phase"] == 0.0
    assert spl.t0_s == 0.0 and "before the first pose" not in rep.summary()


def test_se3_and_given_spacings_keep_the_grid_on_the_first_pose():
    sc, (t, p, q), spl, rep = _fit("rate-table", "upsampled", 5, kind="se3")
    assert rep.knot_choice["rotation"]["knot_phase"] == 0.0
    # (the grid's end t0 + n dt rounds: within 1e-15 relative of the last pose)
    assert spl.t0_s == 0.0 and spl.t_min_s == 0.0 and spl.t_max_s == pytest.approx(60.0, rel=1e-15, abs=0.0)
    spl, rep = fit(t, p, q, knot_spacing_s=0.5, return_report=True)
    assert rep.knot_choice["rotation"]["knot_phase"] == 0.0 and spl.t0_s == 0.0
