"""Grids whose finest control mode the poses cannot see are moved half a spacing off them."""

from __future__ import annotations

import numpy as np
import pytest
from fit_scenes import scene_errors, scene_poses
from hypothesis import given, settings
from hypothesis import strategies as st

from splineimu import fit, lie
from splineimu.spline.banded import grid_layout, layout, observable_layout, segments
from splineimu.spline.basis import basis_values


def _alternating_rms(t, lay, order):
    u = segments(t, lay[0], lay[1])[1]
    return float(np.sqrt(np.mean((basis_values(order, u) @ (-1.0) ** np.arange(order)) ** 2)))


@pytest.mark.parametrize("order", [3, 4, 5, 6, 7])
def test_poses_on_the_unseen_phase_move_the_grid_half_a_spacing(order):
    t = np.arange(201) * 0.05
    on_knots = layout(t[0], t[-1], 0.05, order)
    midway = grid_layout(t[0], t[-1], t[0] - 0.025, 0.05, order)
    # odd orders: the alternating mode is zero at the knots; even orders: midway between them
    unseen, seen = (on_knots, midway) if order % 2 else (midway, on_knots)
    assert _alternating_rms(t, unseen, order) < 1e-12 and _alternating_rms(t, seen, order) > 0.05
    lay, moved = observable_layout(t, unseen, order)
    assert moved and lay[1] == pytest.approx(0.05) and lay[0] <= t[0] and lay[0] + lay[2] * lay[1] >= t[-1] - 1e-12
    assert _alternating_rms(t, lay, order) > 0.05
    assert observable_layout(t, seen, order) == (seen, False)
    # knots that drift against the poses, and grids coarser than 1.5 pose spacings, are left
    drifting = layout(t[0], t[-1], 0.048, order)
    assert observable_layout(t, drifting, order) == (drifting, False)
    assert observable_layout(t, layout(t[0], t[-1], 0.1, order), order)[1] is False


def _stamped_as_doubles(t):
    """Stamps as EuRoC's: Unix seconds held in a double, written in ns (+-128 ns of jitter)."""
    t_ns = np.round((np.float64(1403715524.907143) + t) * 1e9).astype(np.int64)
    assert len(np.unique(np.diff(t_ns))) > 1
    return (t_ns - t_ns[0]) / 1e9


@pytest.mark.parametrize("kind", ["split", "se3"])
def test_odd_orders_with_knots_at_the_pose_rate_follow_the_motion(kind):
    """The flips scene at 20 Hz (0.01 mm / 0.001 deg noise), stamps jittered by their double
    rounding, knots given at the pose spacing: orders 5 and 7 had their knots on the poses, whose
    +-128 ns barely showed the alternating mode (gyro 0.027 and 0.021 rad/s, 1.6x and 1.8x the
    worse of the even orders beside them); moved half a spacing, 0.0041 and 0.0013, within theirs."""
    sc, t, p, R = scene_poses("flips", "white", 20.0, 20.0, seed=1, scale=0.01)
    t = _stamped_as_doubles(t)
    q = lie.matrix_to_quat_xyzw(R)
    err = {k: scene_errors(sc, fit(t, p, q, kind=kind, order=k, knot_spacing_s=0.05), 20.0) for k in range(4, 9)}
    for k in (5, 7):
        assert err[k][0] <= max(err[k - 1][0], err[k + 1][0]), (k, err)
        assert err[k][1] <= 1.3 * max(err[k - 1][1], err[k + 1][1]), (k, err)
    _, rep = fit(t, p, q, kind=kind, order=5, knot_spacing_s=0.05, return_report=True)
    assert len(rep.notes) == (2 if kind == "split" else 1) and "half a knot spacing" in rep.notes[0]
    assert "note          " in rep.summary()
    assert fit(t, p, q, kind=kind, order=4, knot_spacing_s=0.05, return_report=True)[1].notes == []


def test_a_chosen_rotation_grid_moved_off_the_poses_reports_where_it_sits(monkeypatch):
    """The automatic choice's rotation grid (its ``knot_phase``: spacings before the first pose)
    moved half a spacing off the poses: the report and summary give the grid the spline has."""
    import splineimu.spline.fit as fit_module

    real = fit_module.choose_knot_spacing

    def odd_on_the_poses(*args, **kwargs):
        ch = real(*args, **kwargs)
        ch["rotation"].update(order=5, knot_spacing_s=0.05, knot_phase=0.0)
        return ch

    monkeypatch.setattr(fit_module, "choose_knot_spacing", odd_on_the_poses)
    monkeypatch.setattr(fit_module, "_rotation_bias", lambda *a, **k: None)  # (keeps that grid)
    sc, t, p, R = scene_poses("ellipse", "white", 20.0, 20.0, seed=1, scale=0.01)
    t = _stamped_as_doubles(t)
    spl, rep = fit(t, p, lie.matrix_to_quat_xyzw(R), return_report=True)
    phase = rep.knot_choice["rotation"]["knot_phase"]
    assert rep.order == 5 and any("rotation grid moved" in n for n in rep.notes), rep.notes
    assert phase == pytest.approx(0.5, abs=1e-6) and spl.t0_s == pytest.approx(t[0] - phase * spl.dt_s, abs=1e-12)
    assert f"from {phase * spl.dt_s * 1e3:.3f} ms before the first pose" in rep.summary()


@settings(max_examples=60, deadline=None)
@given(order=st.integers(3, 8), n=st.integers(20, 400), h=st.floats(1e-3, 1.0), frac=st.sampled_from([1.0, 0.5, 1 / 3]),
       phase=st.floats(0.0, 1.0), jitter=st.floats(0.0, 1e-6))
def test_observable_layout_keeps_the_grid_and_its_span(order, n, h, frac, phase, jitter):
    """Whatever the poses' phase against the knots, the layout returned covers the poses with the
    same spacing, and a moved one shows the alternating mode at the poses."""
    rng = np.random.default_rng(n)
    t = 12.3 + np.arange(n) * h + jitter * h * rng.uniform(-1, 1, n)
    dt = frac * h
    lay = grid_layout(t[0], t[-1], t[0] - phase * dt, dt, order)
    out, moved = observable_layout(t, lay, order)
    assert out[1] == lay[1] and out[0] <= t[0] + 1e-12 and out[0] + out[2] * out[1] >= t[-1] - 1e-9 * t[-1]
    assert out[3] == out[2] + order - 1
    if moved:
        assert out[0] == pytest.approx(lay[0] - 0.5 * dt) or out[0] == pytest.approx(lay[0] + 0.5 * dt)
        assert _alternating_rms(t, out, order) > _alternating_rms(t, lay, order)
