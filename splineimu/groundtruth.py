"""Ground-truth navigation states and their interpolation between stamps.

One implementation for every job that needs the true state at an instant that may fall between
two ground-truth rows: dead reckoning (:func:`splineimu.api.dead_reckon`, the initial
state) and preintegration (:func:`splineimu.api.evaluate_recording`, both ends of
every window).

Between stamps ``t_a < t < t_b`` with ``u = (t - t_a) / (t_b - t_a)``, position, velocity and
biases are interpolated linearly, ``x = (1 - u) x_a + u x_b``, and the rotation along the
geodesic, ``R = R_a Exp(u Log(R_a^T R_b))`` (slerp). At a stamp the stored row is returned as it
is. The file reader is :func:`splineimu.io.euroc.read_groundtruth`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError, RangeError
from .lie import matrix_to_quat_xyzw, quat_xyzw_to_matrix, so3_exp, so3_log
from .validation import as_quat_xyzw, as_stamps_ns, as_vectors

__all__ = ["GroundTruth", "GroundTruthState"]


@dataclass
class GroundTruthState:
    """The true state at one instant.

    Attributes
    ----------
    t_ns : int
    position_world : (3,) float64 [m]
    quat_xyzw : (4,) float64
        ``world_R_body``.
    world_R_body : (3, 3) float64
        The same rotation as a matrix (the interpolated one, not a conversion of the quaternion).
    velocity_world : (3,) float64 [m/s]
    bias_gyro : (3,) float64 [rad/s]
    bias_accel : (3,) float64 [m/s^2]
    """

    t_ns: int
    position_world: np.ndarray
    quat_xyzw: np.ndarray
    world_R_body: np.ndarray
    velocity_world: np.ndarray
    bias_gyro: np.ndarray
    bias_accel: np.ndarray


class GroundTruth:
    """Ground-truth states at strictly increasing stamps (EuRoC ``state_groundtruth_estimate0``).

    Parameters
    ----------
    t_ns : (M,) int64
        Strictly increasing stamps [ns].
    position_world, velocity_world, bias_gyro, bias_accel : (M, 3) array_like
        [m], [m/s], [rad/s], [m/s^2].
    quat_xyzw : (M, 4) array_like
        ``world_R_body``.
    path : str, optional
        Where the rows came from (for messages).

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, a zero quaternion or stamps that do not increase.

    Examples
    --------
    >>> gt = GroundTruth([0, 10], [[0, 0, 0], [1, 0, 0]], [[0, 0, 0, 1], [0, 0, 1, 0]],
    ...                  [[0, 0, 0], [0, 0, 0]], [[0, 0, 0]] * 2, [[0, 0, 0]] * 2)
    >>> s = gt.state_at(5)
    >>> s.position_world.tolist(), s.quat_xyzw.round(6).tolist()
    ([0.5, 0.0, 0.0], [0.0, 0.0, 0.707107, 0.707107])
    """

    def __init__(self, t_ns, position_world, quat_xyzw, velocity_world, bias_gyro, bias_accel, path=""):
        self.t_ns = as_stamps_ns(t_ns, "t_ns")
        n = self.t_ns.shape[0]
        if n < 1:
            raise InputError("the ground truth has no rows", path=path or None)
        self.position_world = as_vectors(position_world, "position_world", n)
        self.quat_xyzw = as_quat_xyzw(quat_xyzw, "quat_xyzw", n)
        self.velocity_world = as_vectors(velocity_world, "velocity_world", n)
        self.bias_gyro = as_vectors(bias_gyro, "bias_gyro", n)
        self.bias_accel = as_vectors(bias_accel, "bias_accel", n)
        self.world_R_body = quat_xyzw_to_matrix(self.quat_xyzw)
        self.path = str(path)

    @classmethod
    def from_track(cls, track) -> GroundTruth:
        """From a :class:`splineimu.io.poses.PoseTrack` with velocity and biases (17 EuRoC columns).

        Raises
        ------
        InputError
            The track has no velocity and biases.
        """
        if track.velocity_world is None:
            raise InputError("expected the 17-column EuRoC ground truth (ns, p xyz, q wxyz, v xyz, "
                             "b_w xyz, b_a xyz) for velocity and biases", path=track.path or None)
        return cls(track.t_ns, track.positions, track.quat_xyzw, track.velocity_world, track.bias_gyro,
                   track.bias_accel, path=track.path)

    def __len__(self) -> int:
        return int(self.t_ns.shape[0])

    def covers(self, t_ns) -> bool:
        """Whether ``t_ns`` lies inside ``[t_ns[0], t_ns[-1]]``."""
        return bool(self.t_ns[0] <= t_ns <= self.t_ns[-1])

    def state_at(self, t_ns) -> GroundTruthState:
        """The state at ``t_ns``: the stored row at a stamp, interpolated between stamps.

        Raises
        ------
        RangeError
            ``t_ns`` outside the ground truth's span.
        """
        t_ns = int(t_ns)
        ts = self.t_ns
        if not self.covers(t_ns):
            raise RangeError(f"time {t_ns} ns is outside the ground truth [{ts[0]}, {ts[-1]}] ns",
                             path=self.path or None)
        j = int(np.searchsorted(ts, t_ns, side="right")) - 1
        if ts[j] == t_ns:
            return GroundTruthState(t_ns, self.position_world[j].copy(), self.quat_xyzw[j].copy(),
                                    self.world_R_body[j].copy(), self.velocity_world[j].copy(),
                                    self.bias_gyro[j].copy(), self.bias_accel[j].copy())
        u = float(t_ns - ts[j]) / float(ts[j + 1] - ts[j])

        def lerp(x):
            return (1.0 - u) * x[j] + u * x[j + 1]

        R0, R1 = self.world_R_body[j], self.world_R_body[j + 1]
        R = R0 @ so3_exp(u * so3_log(R0.T @ R1))
        return GroundTruthState(t_ns, lerp(self.position_world), matrix_to_quat_xyzw(R), R,
                                lerp(self.velocity_world), lerp(self.bias_gyro), lerp(self.bias_accel))
