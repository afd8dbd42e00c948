"""Landmark observations of cameras moved by a motion source (global or rolling shutter).

Time bases
----------
Frame stamps ``t_ns`` are integer nanoseconds on the camera clock. The motion source runs on
the IMU clock; frame ``t_ns`` starts at source time
``t_s = (t_ns - origin_ns) / 1e9 + timeshift_cam_imu_s`` and its row ``v`` is read at
``t_s + v * line_delay_s``.

Frames
------
``t_ns = first + round(k 1e9 / rate_hz)`` for ``k = 0, 1, ...`` with ``first`` the earliest
whole nanosecond whose frame starts inside the source's range, and every frame whose last
row (``v = height``) is still inside the range: no frame is skipped.

Visibility
----------
A landmark is observed in a frame when it has positive depth and its exact (noise-free)
distorted projection is inside the image at the time its row is read; then white noise of
standard deviation ``pixel_noise_px`` is added to ``u`` and ``v``.

Rolling shutter: the row ``v`` solves ``v = proj_v(world_T_cam(t_s + v line_delay) p)``. The
residual is sampled at rows ``0 .. height`` at most :data:`RS_SAMPLE_INTERVAL_S` apart;
every sign change brackets a root, which is refined by the Illinois method (regula falsi with
halving) to :data:`ROW_TOLERANCE_PX`. For the equidistant model the residual is continuous
through zero depth (``theta = atan2(rho, Z)``), so a point that crosses behind a fisheye
camera during the readout is found and kept only if its depth is positive at its own row
time. When a landmark has several roots in one frame (an image speed above
``1 / line_delay_s`` px/s) the one on the topmost row is kept.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .landmarks import Landmarks
from .model import Camera

__all__ = ["observe", "observe_camera", "frame_stamps_ns", "Observations", "camera_rngs",
           "RS_SAMPLE_INTERVAL_S", "ROW_TOLERANCE_PX"]

#: largest time between two rows at which the rolling-shutter residual is sampled [s]
RS_SAMPLE_INTERVAL_S = 5e-3
#: a rolling-shutter row is accepted when ``|proj_v(t(v)) - v|`` is below this [px]
ROW_TOLERANCE_PX = 1e-7
#: iteration limit of the row solver (it needs 3-6 in practice)
MAX_ROW_ITERATIONS = 60
#: elements per work array (frames are processed in chunks of about this size)
_CHUNK_ELEMENTS = 1 << 21
#: spawn-key tag of the camera noise streams, apart from the IMU's noise processes
_CAMERA_STREAM_TAG = 0x43414D  # "CAM"


@dataclass(eq=False)
class Observations:
    """Landmark observations of one camera.

    Attributes
    ----------
    camera : Camera
    frame_t_ns : (F,) int64
        Every frame stamp (camera clock), also frames without observations.
    t_ns : (N,) int64
        Frame stamp of each observation (camera clock), non-decreasing.
    landmark_id : (N,) int64
    u, v : (N,) float64
        Observed pixel coordinates (exact projection + noise) [px].
    u_exact, v_exact : (N,) float64
        Noise-free projection [px].
    t_capture_s : (N,) float64
        Source time (IMU clock, seconds in the source's time base) at which the landmark
        was imaged: the frame start plus ``v_exact * line_delay_s``.

    Rows are ordered by frame, then by the landmarks' order.

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> scene = make_scene("ellipse", duration_s=0.2)
    >>> cam = Camera((300.0, 300.0, 320.0, 240.0), (640, 480), rate_hz=10.0, pixel_noise_px=0.5,
    ...              cam_T_imu=[[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0], [0, 0, 0, 1]])
    >>> obs = observe_camera(scene, cam, Landmarks.random(200, source=scene, rng=0), rng=1)
    >>> obs.frame_t_ns.tolist(), len(obs.frame(100_000_000)) == int(np.sum(obs.t_ns == 100_000_000))
    ([0, 100000000, 200000000], True)
    >>> list(obs.to_dataframe().columns)
    ['t_ns', 'landmark_id', 'u', 'v', 'u_exact', 'v_exact', 't_capture_s']
    """

    camera: Camera
    frame_t_ns: np.ndarray
    t_ns: np.ndarray
    landmark_id: np.ndarray
    u: np.ndarray
    v: np.ndarray
    u_exact: np.ndarray
    v_exact: np.ndarray
    t_capture_s: np.ndarray

    def __len__(self) -> int:
        return int(self.t_ns.shape[0])

    def frame(self, t_ns: int) -> Observations:
        """The observations of the frame stamped ``t_ns`` (empty if none)."""
        lo, hi = np.searchsorted(self.t_ns, [t_ns, t_ns + 1])
        sl = slice(int(lo), int(hi))
        return Observations(self.camera, np.array([t_ns], dtype=np.int64), self.t_ns[sl], self.landmark_id[sl],
                            self.u[sl], self.v[sl], self.u_exact[sl], self.v_exact[sl], self.t_capture_s[sl])

    def to_dataframe(self):
        """A pandas DataFrame with columns ``t_ns, landmark_id, u, v, u_exact, v_exact, t_capture_s``."""
        import pandas as pd

        return pd.DataFrame({"t_ns": self.t_ns, "landmark_id": self.landmark_id, "u": self.u, "v": self.v,
                             "u_exact": self.u_exact, "v_exact": self.v_exact, "t_capture_s": self.t_capture_s})


# ------------------------------------------------------------------------------ public entry points


def observe(source, cameras, landmarks, rng=None, *, body_T_imu=None) -> dict:
    """Observations of ``landmarks`` by each camera moved by ``source``.

    Parameters
    ----------
    source : MotionSource
        Gives ``pose(t_s) -> (positions (N, 3), quat_xyzw (N, 4))`` of ``world_T_body`` and
        the valid range ``[t_min_s, t_max_s]`` and ``origin_ns``.
    cameras : Camera, sequence of Camera, or dict name -> Camera
    landmarks : Landmarks or array_like (M, 3)
        An array gets ids ``0 .. M-1``.
    rng : numpy.random.Generator, SeedSequence, int or None
        Pixel-noise source; each camera gets its own child stream (:func:`camera_rngs`).
    body_T_imu : (4, 4) array_like, optional
        Pose of the IMU in the body frame (identity: the IMU frame is the body frame).

    Returns
    -------
    dict
        Camera name -> :class:`Observations`, in the order of ``cameras``.

    Raises
    ------
    ConfigError
        Duplicate camera names, a bad ``body_T_imu``, or a source too short for one frame.

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> scene = make_scene("ellipse", duration_s=1.0)
    >>> R = [[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0], [0, 0, 0, 1]]  # looks along body x
    >>> cam = Camera((300.0, 300.0, 320.0, 240.0), (640, 480), cam_T_imu=R, rate_hz=10.0)
    >>> lm = Landmarks.random(300, source=scene, rng=0)
    >>> obs = observe(scene, [cam], lm, rng=0)["cam0"]
    >>> obs.frame_t_ns.tolist()[:3], len(obs.frame_t_ns)
    ([0, 100000000, 200000000], 11)
    >>> bool(np.all((obs.u >= 0) & (obs.u < 640))), len(obs) > 0
    (True, True)
    """
    cams = _as_camera_list(cameras)
    lm = landmarks if isinstance(landmarks, Landmarks) else _landmarks_from_array(landmarks)
    body_T_imu = _as_transform(body_T_imu)
    gens = camera_rngs(rng, [c.name for c in cams])
    return {c.name: observe_camera(source, c, lm, g, body_T_imu=body_T_imu) for c, g in zip(cams, gens)}


def observe_camera(source, camera: Camera, landmarks: Landmarks, rng=None, *, body_T_imu=None) -> Observations:
    """Observations of one camera; see :func:`observe`.

    Parameters
    ----------
    source : MotionSource
    camera : Camera
    landmarks : Landmarks or array_like (M, 3)
    rng : numpy.random.Generator, int or None
        Used as given (no child stream is derived, unlike :func:`observe`).
    body_T_imu : (4, 4) array_like, optional

    Returns
    -------
    Observations

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> scene = make_scene("ellipse", duration_s=0.5)
    >>> cam = Camera((300.0, 300.0, 320.0, 240.0), (640, 480), rate_hz=4.0, line_delay_s=2e-5,
    ...              cam_T_imu=[[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0], [0, 0, 0, 1]])
    >>> lm = Landmarks.random(200, source=scene, rng=3)
    >>> obs = observe_camera(scene, cam, lm)
    >>> t_row = (obs.t_ns / 1e9) + obs.v_exact * cam.line_delay_s  # origin 0, no time shift
    >>> bool(np.allclose(obs.t_capture_s, t_row, atol=1e-12))
    True
    """
    lm = landmarks if isinstance(landmarks, Landmarks) else _landmarks_from_array(landmarks)
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    body_T_imu = _as_transform(body_T_imu)
    cam_T_body = camera.cam_T_imu @ _inverse(body_T_imu)
    frames_ns = frame_stamps_ns(source, camera)
    frame_s = _frame_times_s(source, camera, frames_ns)
    points = lm.position_world
    m = points.shape[0]
    parts = []
    if m and frames_ns.size:
        samples = _row_samples(camera)
        per_frame = max(1, samples.size * m * 3)
        step = max(1, _CHUNK_ELEMENTS // per_frame)
        for lo in range(0, frames_ns.size, step):
            hi = min(frames_ns.size, lo + step)
            if camera.is_global_shutter:
                parts.append(_global_shutter(source, camera, cam_T_body, points, frame_s[lo:hi], lo))
            else:
                parts.append(_rolling_shutter(source, camera, cam_T_body, points, frame_s[lo:hi], lo, samples))
    if parts:
        fi, li, u, v, tc = (np.concatenate(x) for x in zip(*parts))
    else:
        fi = li = np.zeros(0, dtype=np.int64)
        u = v = tc = np.zeros(0)
    n = fi.size
    sigma = camera.pixel_noise_px
    noise = gen.standard_normal((n, 2)) * sigma if sigma > 0 else np.zeros((n, 2))
    return Observations(camera=camera, frame_t_ns=frames_ns, t_ns=frames_ns[fi], landmark_id=lm.id[li],
                        u=u + noise[:, 0], v=v + noise[:, 1], u_exact=u, v_exact=v, t_capture_s=tc)


def frame_stamps_ns(source, camera: Camera) -> np.ndarray:
    """Frame stamps (camera clock, int64 ns) that cover ``source``'s range; see the module notes.

    Examples
    --------
    >>> from splineimu.scenes import make_scene
    >>> scene = make_scene("ellipse", duration_s=1.0)
    >>> cam = Camera((1.0, 1.0, 0.0, 0.0), (10, 10), rate_hz=3.0, timeshift_cam_imu_s=0.25)
    >>> frame_stamps_ns(scene, cam).tolist()  # t_imu = t_cam + 0.25 s must lie in [0, 1] s
    [-250000000, 83333333, 416666667, 750000000]
    >>> rs = Camera((1.0, 1.0, 0.0, 0.0), (10, 1000), rate_hz=4.0, line_delay_s=1e-4)
    >>> frame_stamps_ns(scene, rs).tolist()  # the last frame's rows end by 0.75 + 0.1 s
    [0, 250000000, 500000000, 750000000]
    """
    from ..timegrid import uniform_stamps_ns

    origin = int(source.origin_ns)
    t_min, t_max = float(source.t_min_s), float(source.t_max_s)
    ts = camera.timeshift_cam_imu_s
    readout = camera.readout_s

    def start_s(rel_ns):  # the same float expression as the frames' source times
        return float(_frame_times_rel(np.array([rel_ns]), ts)[0])

    first = math.ceil((t_min - ts) * 1e9)  # earliest whole ns whose frame starts inside the range
    while start_s(first - 1) >= t_min:
        first -= 1
    while start_s(first) < t_min:
        first += 1
    last = math.floor((t_max - readout - ts) * 1e9)  # latest whose last row is inside the range
    while start_s(last + 1) + readout <= t_max:
        last += 1
    while start_s(last) + readout > t_max:
        last -= 1
    if last < first:
        raise ConfigError(f"{camera.name}: the motion ({t_max - t_min:.9g} s) is shorter than one frame's "
                          f"readout ({readout:.9g} s)")
    return uniform_stamps_ns(origin + first, origin + last, camera.rate_hz)


def camera_rngs(rng, names) -> list:
    """One noise generator per camera name.

    An int seed or a SeedSequence ``ss`` gives camera ``name`` the child
    ``SeedSequence(ss.entropy, spawn_key=ss.spawn_key + (0x43414D, crc32(name)))``: its noise
    depends on the seed and its own name only (not on the other cameras, nor on the IMU's
    noise streams, whose spawn keys have one element). A Generator is split with
    ``Generator.spawn`` in the order of ``names``. None draws fresh entropy.

    Examples
    --------
    >>> a = camera_rngs(7, ["cam0", "cam1"]); b = camera_rngs(7, ["cam1"])
    >>> float(a[1].standard_normal()) == float(b[0].standard_normal())
    True
    """
    names = list(names)
    if isinstance(rng, np.random.Generator):
        return rng.spawn(len(names))
    if isinstance(rng, np.random.SeedSequence):
        ss = rng
    elif rng is None:
        ss = np.random.SeedSequence()
    elif isinstance(rng, (int, np.integer)) and not isinstance(rng, bool) and rng >= 0:
        ss = np.random.SeedSequence(int(rng))
    else:
        raise ConfigError(f"`rng` must be None, a non-negative int seed, a SeedSequence or a Generator, got {rng!r}")
    out = []
    for name in names:
        key = tuple(ss.spawn_key) + (_CAMERA_STREAM_TAG, zlib.crc32(str(name).encode()))
        child = np.random.SeedSequence(ss.entropy, spawn_key=key, pool_size=ss.pool_size)
        out.append(np.random.Generator(np.random.PCG64(child)))
    return out


# ------------------------------------------------------------------------------ geometry


def _frame_times_rel(rel_ns, ts):
    return np.asarray(rel_ns, dtype=np.int64).astype(np.float64) / 1e9 + ts


def _frame_times_s(source, camera, frames_ns):
    return _frame_times_rel(frames_ns - np.int64(source.origin_ns), camera.timeshift_cam_imu_s)


def _row_samples(camera) -> np.ndarray:
    if camera.is_global_shutter:
        return np.zeros(1)
    n = max(1, math.ceil(camera.readout_s / RS_SAMPLE_INTERVAL_S))
    return np.linspace(0.0, float(camera.height), n + 1)


def _cam_from_world(source, cam_T_body, t_s):
    """``cam_R_world (N, 3, 3)`` and ``cam_t_world (N, 3)`` at source times ``t_s`` (N,)."""
    from ..lie import quat_xyzw_to_matrix

    pos, quat = source.pose(np.ascontiguousarray(t_s, dtype=np.float64))
    world_R_body = quat_xyzw_to_matrix(quat)
    cam_R_world = np.matmul(cam_T_body[:3, :3], world_R_body.transpose(0, 2, 1))
    cam_t_world = cam_T_body[:3, 3] - _rotate(cam_R_world, pos)
    return cam_R_world, cam_t_world


def _rotate(R, p):
    """``R[n] @ p[n]`` for (N, 3, 3) and (N, 3): explicit sums (faster than batched matmul of 3x3)."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    return np.stack([R[:, i, 0] * x + R[:, i, 1] * y + R[:, i, 2] * z for i in range(3)], axis=1)


def _global_shutter(source, camera, cam_T_body, points, frame_s, frame0):
    R, t = _cam_from_world(source, cam_T_body, frame_s)
    p = np.matmul(points[None], R.transpose(0, 2, 1)) + t[:, None, :]
    Z = p[..., 2]
    u, v = camera._project_xyz(p[..., 0], p[..., 1], Z, extended=False)
    f, m = np.nonzero((Z > 0.0) & camera.in_image(u, v))
    tc = frame_s[f]
    return f + frame0, m, u[f, m], v[f, m], tc


def _rolling_shutter(source, camera, cam_T_body, points, frame_s, frame0, rows):
    ld = camera.line_delay_s
    t = (frame_s[:, None] + rows[None, :] * ld).reshape(-1)
    R, tr = _cam_from_world(source, cam_T_body, t)
    R = R.reshape(frame_s.size, rows.size, 3, 3)
    tr = tr.reshape(frame_s.size, rows.size, 3)
    find = _rs_brackets_numpy if _jit_disabled() else _rs_brackets_kernel
    f, s, m, res_lo, res_hi = find(camera, R, tr, points, rows)
    row, u, v, z, ok = _solve_rows(source, camera, cam_T_body, points, frame_s, f, m,
                                   rows[s], rows[s + 1], res_lo, res_hi)
    keep = ok & (z > 0.0) & camera.in_image(u, v)
    f, m, u, v, row = f[keep], m[keep], u[keep], v[keep], row[keep]
    tc = frame_s[f] + row * ld
    # several roots of one landmark in one frame: keep the topmost
    order = np.lexsort((v, m, f))
    f, m, u, v, tc = f[order], m[order], u[order], v[order], tc[order]
    first = np.ones(f.size, dtype=bool)
    first[1:] = (f[1:] != f[:-1]) | (m[1:] != m[:-1])
    return f[first] + frame0, m[first], u[first], v[first], tc[first]


def _rs_brackets_numpy(camera, R, t, points, rows):
    """Row brackets ``(frame, sample, landmark, residual at sample, at sample + 1)`` where the
    residual changes sign with positive depth at one end at least (the reference of the kernel)."""
    p = np.matmul(points[None, None], R.transpose(0, 1, 3, 2)) + t[:, :, None, :]  # (F, S, M, 3)
    _, v = camera._project_xyz(p[..., 0], p[..., 1], p[..., 2], extended=True)
    front = p[..., 2] > 0.0
    res = v - rows[None, :, None]
    a, b = res[:, :-1], res[:, 1:]
    bracket = ((a >= 0) & (b < 0)) | ((a < 0) & (b >= 0))
    bracket &= front[:, :-1] | front[:, 1:]
    f, m, s = np.nonzero(bracket.transpose(0, 2, 1))  # ordered by frame, landmark, sample
    return f, s, m, res[f, s, m], res[f, s + 1, m]


def _rs_brackets_kernel(camera, R, t, points, rows):
    from . import _kernels as _k

    code = {"none": _k.MODEL_NONE, "radtan": _k.MODEL_RADTAN, "equidistant": _k.MODEL_EQUIDISTANT}
    k = np.zeros(8)
    k[:4] = camera.intrinsics
    k[4:4 + len(camera.distortion_coeffs)] = camera.distortion_coeffs
    args = (np.ascontiguousarray(R), np.ascontiguousarray(t), np.ascontiguousarray(points), rows,
            code[camera.distortion_model], k)
    cap = max(1024, 2 * R.shape[0] * points.shape[0])
    while True:
        out = (np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap), np.empty(cap))
        n = _k.rs_brackets(*args, *out)
        if n <= cap:
            return tuple(x[:n] for x in out)
        cap = n


def _jit_disabled() -> bool:
    import numba

    return bool(numba.config.DISABLE_JIT)


def _solve_rows(source, camera, cam_T_body, points, frame_s, f, m, a, b, fa, fb):
    """Illinois iteration on ``g(row) = proj_v(t(row)) - row`` in the brackets ``[a, b]``.

    Returns ``(row, u, v, depth, converged)``, the last four at the solution. A bracket around
    a jump (zero depth of a pinhole camera) does not converge to a small residual and is
    reported as not converged.
    """
    ld = camera.line_delay_s
    n = f.size
    row, u, v, z = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    done = np.zeros(n, dtype=bool)
    a, b, fa, fb = (np.array(x, dtype=np.float64) for x in (a, b, fa, fb))
    active = np.arange(n)
    started = np.zeros(n, dtype=bool)
    for _ in range(MAX_ROW_ITERATIONS):
        if active.size == 0:
            break
        aa, bb, fa_, fb_ = a[active], b[active], fa[active], fb[active]
        finite = np.isfinite(fa_) & np.isfinite(fb_) & (fa_ != fb_)
        with np.errstate(invalid="ignore", divide="ignore"):
            c = np.where(finite, (aa * fb_ - bb * fa_) / (fb_ - fa_), 0.5 * (aa + bb))
        c = np.clip(c, np.minimum(aa, bb), np.maximum(aa, bb))
        R, tr = _cam_from_world(source, cam_T_body, frame_s[f[active]] + c * ld)
        p = _rotate(R, points[m[active]]) + tr
        uc, vc = camera._project_xyz(p[:, 0], p[:, 1], p[:, 2], extended=True)
        fc = vc - c
        conv = np.abs(fc) <= ROW_TOLERANCE_PX
        stuck = np.abs(bb - aa) <= 1e-12 * max(1.0, float(camera.height))
        hit = active[conv]
        row[hit], u[hit], v[hit], z[hit] = c[conv], uc[conv], vc[conv], p[conv, 2]
        done[hit] = True
        # The new point c becomes b; a is the end kept (the old a when c has b's sign, else
        # the old b). Keeping the old a means keeping one end twice in a row after the first
        # step (Illinois): halve its residual so that the next secant moves past the root.
        same_as_b = np.signbit(fc) == np.signbit(fb_)
        new_a = np.where(same_as_b, aa, bb)
        new_fa = np.where(same_as_b, fa_, fb_)
        new_fa = np.where(same_as_b & started[active], new_fa * 0.5, new_fa)
        started[active] = True
        a[active], fa[active], b[active], fb[active] = new_a, new_fa, c, fc
        active = active[~conv & ~stuck & np.isfinite(c)]
    return row, u, v, z, done


# ------------------------------------------------------------------------------ argument helpers


def _as_camera_list(cameras) -> list:
    if isinstance(cameras, Camera):
        cams = [cameras]
    elif isinstance(cameras, dict):
        cams = []
        for name, cam in cameras.items():
            if not isinstance(cam, Camera):
                raise ConfigError(f"cameras[{name!r}] must be a Camera, got {type(cam).__name__}")
            if cam.name != name:
                raise ConfigError(f"cameras[{name!r}] is named {cam.name!r}")
            cams.append(cam)
    else:
        cams = list(cameras)
        for i, cam in enumerate(cams):
            if not isinstance(cam, Camera):
                raise ConfigError(f"cameras[{i}] must be a Camera, got {type(cam).__name__}")
    names = [c.name for c in cams]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise ConfigError(f"camera names must be unique, got {sorted(dup)} more than once")
    return cams


def _landmarks_from_array(points) -> Landmarks:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ConfigError(f"Expected `landmarks` to have shape (M, 3), got {p.shape}")
    return Landmarks(np.arange(p.shape[0], dtype=np.int64), p)


def _as_transform(T) -> np.ndarray:
    if T is None:
        return np.eye(4)
    from .model import _transform

    return _transform(T, "body_T_imu", "")


def _inverse(T):
    from .model import _inverse as inv

    return inv(T)
