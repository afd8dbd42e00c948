"""Write the bundled example: the lecture ellipse seen by a motion-capture system.

100 Hz for 30 s, with 1 mm position and 0.1 deg orientation noise (white), stamped at a Unix
epoch start; this is what ``examples/ellipse_mocap.tum`` holds.

    python tools/make_example.py examples/ellipse_mocap.tum
"""

from __future__ import annotations

import sys

import numpy as np

from splineimu import lie
from splineimu.io.tum import write_tum
from splineimu.scenes import make_scene


def main(path="examples/ellipse_mocap.tum", rate_hz=100.0, duration_s=30.0, seed=2026):
    t0_ns = 1_700_000_000_000_000_000
    scene = make_scene("ellipse", duration_s=duration_s, t0_ns=t0_ns)
    t_ns = scene.sample_times_ns(rate_hz)
    k = scene.kinematics(scene.t_s_from_ns(t_ns))
    rng = np.random.default_rng(seed)
    pos = k.position_world + 1e-3 * rng.normal(size=k.position_world.shape)
    R = k.world_R_body @ lie.so3_exp(np.radians(0.1) * rng.normal(size=(t_ns.size, 3)))
    write_tum(path, t_ns, pos, lie.quat_make_continuous(lie.matrix_to_quat_xyzw(R)))
    print(f"wrote {path}: {t_ns.size} poses")


if __name__ == "__main__":
    main(*sys.argv[1:2])
