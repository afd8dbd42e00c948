"""Sampling modes: interval means and exact delta-angle / delta-velocity increments."""

from __future__ import annotations

import numpy as np
from scipy.integrate import quad

from splineimu import lie
from splineimu.pipeline import synthesize
from splineimu.scenes import make_scene
from splineimu.timegrid import uniform_stamps_ns


def test_mean_sampling_is_the_interval_average():
    scene = make_scene("flips", duration_s=2.0)
    t_ns = uniform_stamps_ns(0, 2_000_000_000, 100)
    syn = synthesize(scene, t_ns, sampling="mean")
    t = t_ns / 1e9
    for k in (1, 57, 150):
        for axis in range(3):
            ref = quad(lambda s: scene.imu([s])[0][0, axis], t[k - 1], t[k], epsabs=1e-13, epsrel=1e-13)[0] / 0.01
            assert abs(syn.gyro_rad_s[k, axis] - ref) < 1e-9 * max(1.0, abs(ref))
            ref = quad(lambda s: scene.imu([s])[1][0, axis], t[k - 1], t[k], epsabs=1e-13, epsrel=1e-13)[0] / 0.01
            assert abs(syn.accel_m_s2[k, axis] - ref) < 1e-9 * max(1.0, abs(ref))
    point = synthesize(scene, t_ns)
    assert np.abs(point.gyro_rad_s - syn.gyro_rad_s).max() > 1e-3  # the modes really differ


def test_increments_integrate_to_the_exact_trajectory():
    scene = make_scene("flips", duration_s=3.0)
    t_ns = uniform_stamps_ns(0, 3_000_000_000, 200)
    syn = synthesize(scene, t_ns, with_increments=True)
    k = scene.kinematics(t_ns / 1e9)
    R = k.world_R_body[0].copy()
    v = k.velocity_world[0].copy()
    g = np.array([0, 0, -9.81])
    for i in range(1, t_ns.size):
        v = v + R @ syn.delta_velocity[i] + g * 0.005
        R = R @ lie.so3_exp(syn.delta_angle[i])
    np.testing.assert_allclose(R, k.world_R_body[-1], atol=1e-10)
    np.testing.assert_allclose(v, k.velocity_world[-1], atol=1e-9)


def test_increments_carry_the_sensor_errors():
    scene = make_scene("static", duration_s=2.0)
    t_ns = uniform_stamps_ns(0, 2_000_000_000, 100)
    cfg = {"gyroscope_bias": [0.01, 0.0, 0.0]}
    syn = synthesize(scene, t_ns, imu_config=cfg, seed=1, with_increments=True)
    np.testing.assert_allclose(syn.delta_angle[1:, 0], 0.01 * 0.01, rtol=1e-12)
