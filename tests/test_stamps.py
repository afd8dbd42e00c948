"""Receive-time stamps put back on the capture clock (splineimu.stamps): synthetic delivery
delays, stalls and dropped frames on analytic motion with exact truth."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from fit_scenes import received, scene_errors

from splineimu import fit, lie
from splineimu._kernels.stamps import assign_slots
from splineimu.errors import InputError
from splineimu.scenes import make_scene
from splineimu.stamps import _monotone, retime_stamps

RATE = 50.0


def slots_right(rt, tc, tr, rate=RATE):
    """Share of the poses whose new stamp is their capture time plus the record's constant offset."""
    tn = (rt.t_ns - rt.t_ns[0]) / 1e9 + tr[0]
    off = np.median(tn - tc)
    return float(np.mean(np.abs(tn - tc - off) < 0.25 / rate))


@pytest.mark.parametrize("name,seed", [("ellipse", 0), ("screw", 1)])
def test_receive_stamps_are_put_back_on_the_capture_clock(name, seed):
    """Every slot found; the fitted IMU as good as from the capture times (from the receive times
    the accel error is 30-600x it)."""
    sc, tc, tr, p, q = received(name, seed)
    rt = retime_stamps(np.round(tr * 1e9).astype(np.int64), p, q)
    assert slots_right(rt, tc, tr) == 1.0
    assert abs(rt.period_s * RATE - 1.0) < 3e-5  # (the least delay read to ~1 ms over 30 s)
    assert rt.dropped_frames == int(round((tc[-1] - tc[0]) * RATE)) + 1 - tc.size
    assert rt.moved > 0 and np.all(np.diff(rt.t_ns) > 0)
    tn = (rt.t_ns - rt.t_ns[0]) / 1e9
    (_, a_capture), (_, a_received), (_, a_retimed) = (scene_errors(sc, fit(x - x[0], p, q), 30.0)
                                                      for x in (tc, tr, tn))
    assert a_received > 20 * a_capture
    assert a_retimed < 1.1 * a_capture, (a_capture, a_retimed)


def test_queued_stalls_do_not_hide_the_clock():
    """100 Hz with 1-10 ms delays: the stalls' queues (delivered 0.1 ms apart) pull the median
    interval to 9.71 ms, and the clock was searched within 2% of it: 9.7087 ms, a quarter of the
    slots right, told doubtful. The phases of the poses delivered in turn find 10 ms."""
    rate = 100.0
    _, tc, tr, p, q = received("ellipse", 2, rate=rate)
    rt = retime_stamps(np.round(tr * 1e9).astype(np.int64), p, q)
    assert abs(rt.period_s * rate - 1.0) < 3e-5
    assert slots_right(rt, tc, tr, rate) == 1.0 and not rt.doubtful


def test_delays_over_whole_periods():
    """200 Hz with 1-10 ms delays (up to two periods): the phases cover the whole circle, and the
    offset read as the least phase around their circular mean forced 6% of the poses a slot early;
    the phase after the widest gap puts every slot right (the re-timing is told doubtful: its
    median delay is over a period)."""
    rate = 200.0
    _, tc, tr, p, q = received("ellipse", 0, rate=rate)
    rt = retime_stamps(np.round(tr * 1e9).astype(np.int64), p, q)
    assert slots_right(rt, tc, tr, rate) == 1.0 and rt.doubtful


def test_clocks_ranked_on_the_record_ends(monkeypatch):
    """A record longer than RANK_POSES: the clocks are ranked on its first and last poses, the one
    kept assigns all of it (every slot right, as when ranked on the whole record)."""
    import splineimu.stamps as st

    _, tc, tr, p, q = received("screw", 1)
    monkeypatch.setattr(st, "RANK_POSES", 600)  # (12 s at each end; 8 s: a clock 0.25% long won)
    rt = retime_stamps(np.round(tr * 1e9).astype(np.int64), p, q)
    assert tc.size > 1000 and slots_right(rt, tc, tr) == 1.0
    assert abs(rt.period_s * RATE - 1.0) < 3e-5


def test_drops_alone_and_exact_stamps():
    """Frames dropped but no delay: the stamps come back as they were, the drops counted."""
    sc, tc, tr, p, q = received("ellipse", 3, stalls=False, jitter=False)
    t_ns = np.round(tc * 1e9).astype(np.int64) + 1_600_000_000_000_000_000  # Unix nanoseconds
    rt = retime_stamps(t_ns, p, q)
    assert np.max(np.abs(rt.t_ns - t_ns)) < 1000  # ns
    assert rt.dropped_frames == int(round((tc[-1] - tc[0]) * RATE)) + 1 - tc.size
    assert rt.moved == 0 and np.max(np.abs(rt.delay_s)) < 1e-6


def test_variable_rate_stamps_are_refused():
    """Poses at random intervals (no capture clock) are not forced onto one."""
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.uniform(0.01, 0.03, 1500))
    k = make_scene("ellipse", duration_s=float(t[-1]) + 1).kinematics(t)
    with pytest.raises(InputError, match="no steady capture clock"):
        retime_stamps(np.round(t * 1e9).astype(np.int64), k.position_world,
                      lie.matrix_to_quat_xyzw(k.world_R_body), path="poses.txt")


def test_slot_assignment_is_the_least_cost_one():
    """The dynamic programme's delays against every assignment of a short record (N = 7, up to 2
    periods of delay): the same least cost and delays."""
    rng = np.random.default_rng(2)
    h, S, prior = 0.02, 3, 0.5
    m = _monotone(np.array([0, 1, 3, 3, 4, 6, 7]))
    Y = np.cumsum(rng.normal(size=(7, 6)), axis=0)
    scales = np.array([30.0, 10.0])

    def cost(s):
        n = m - np.asarray(s)
        if np.any(np.diff(n) <= 0):
            return np.inf
        tt = n * h
        c = prior * np.sum(s)
        for i in range(1, 6):
            d1, d2 = tt[i] - tt[i - 1], tt[i + 1] - tt[i]
            a = 2.0 * ((Y[i + 1] - Y[i]) / d2 - (Y[i] - Y[i - 1]) / d1) / (d1 + d2)
            c += sum(2.0 * (np.sqrt(1.0 + np.sum(a[3 * j:3 * j + 3] ** 2) / scales[j] ** 2) - 1.0) for j in range(2))
        return c

    costs = {s: cost(s) for s in itertools.product(range(S), repeat=7)}
    best = min(costs, key=costs.get)
    s, c = assign_slots(m, Y, scales, h, S, prior, np.zeros((7, S, S), dtype=np.int8))
    assert c == pytest.approx(costs[best], rel=1e-12)
    assert tuple(s) == best


def test_from_tum_retimes_receive_stamps(tmp_path, capsys):
    """The command line: receive-time stamps are told as jittered; with --retime-stamps the poses
    go back on their clock (the notice in report.json) and the warning is gone."""
    from splineimu.cli import main

    _, tc, tr, p, q = received("ellipse", 0, duration=20.0)
    src = tmp_path / "received.tum"
    np.savetxt(src, np.column_stack([1.6e9 + tr, p, q]), fmt="%.9f")

    def run(*extra):
        out = tmp_path / f"out{len(extra)}"
        assert main(["from-tum", str(src), "-o", str(out), "--rate", "100", *extra]) == 0
        return json.loads((out / "report.json").read_text())

    codes = [w["code"] for w in run()["warnings"]]
    assert "timestamps_jittered" in codes and "--retime-stamps" in capsys.readouterr().err
    rep = run("--retime-stamps")
    assert "timestamps_jittered" not in [w["code"] for w in rep["warnings"]]
    (note,) = [n for n in rep["source"]["notices"] if n.startswith("stamps re-timed")]
    assert "20.00" in note and f"{int(round((tc[-1] - tc[0]) * RATE)) + 1 - tc.size} dropped frames" in note


def test_doubtful_retiming_is_told():
    """A median delay over DOUBTFUL_DELAY of a period is told in the summary."""
    from splineimu.stamps import DOUBTFUL_DELAY, Retiming

    def rt(delay):
        return Retiming(t_ns=np.arange(4), period_s=0.02, coherence=0.5, dropped_frames=0, moved=0,
                        delay_s=np.full(4, delay))

    assert not rt(0.5 * DOUBTFUL_DELAY * 0.02).doubtful and "doubtful" not in rt(0.005).summary()
    assert rt(1.1 * DOUBTFUL_DELAY * 0.02).doubtful and "doubtful" in rt(0.015).summary()


def test_scene_file_and_command_line_carry_the_option(tmp_path):
    """``retime_stamps: true`` in a scene file is the job's option and its command line's flag."""
    from splineimu.api.scenefile import load_scene_file

    (tmp_path / "poses.tum").write_text("0 0 0 0 0 0 0 1\n")
    f = tmp_path / "job.yaml"
    f.write_text("motion:\n  poses: poses.tum\n  retime_stamps: true\nimu:\n  rate_hz: 100\noutput:\n  dir: out\n")
    job = load_scene_file(f)
    assert job.motion.retime_stamps is True and "--retime-stamps" in job.to_argv()
    f.write_text("motion:\n  poses: poses.tum\nimu:\n  rate_hz: 100\noutput:\n  dir: out\n")
    assert load_scene_file(f).motion.retime_stamps is False


def test_doubtful_retiming_is_a_warning(tmp_path):
    """Delays spread over 1.7 periods (no least delay most poses share): the re-timing is told
    doubtful, as a warning in report.json."""
    from splineimu.cli import main

    _, tc, tr, p, q = received("ellipse", 1, duration=20.0, stalls=False, delays=(0.001, 0.035))
    src = tmp_path / "received.tum"
    np.savetxt(src, np.column_stack([1.6e9 + tr, p, q]), fmt="%.9f")
    out = tmp_path / "out"
    assert main(["from-tum", str(src), "-o", str(out), "--rate", "100", "--retime-stamps"]) == 0
    rep = json.loads((out / "report.json").read_text())
    (w,) = [w for w in rep["warnings"] if w["code"] == "stamps_retime_doubtful"]
    assert "median" in w["message"] and "doubtful" in w["message"]
