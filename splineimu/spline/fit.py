"""Least-squares fit of a cumulative B-spline to timestamped poses.

Problem (weights ``w``, control poses ``T_i``)::

    min  sum_m w_m |Log(T(t_m)^-1 T_m)|^2  +  mu * smoothness(T_i)

- ``kind="split"``: the position part is linear (ordinary B-spline), solved directly from its
  banded normal equations; the rotation part is a Gauss-Newton / Levenberg-Marquardt problem
  on SO3 with right-perturbation updates ``R_i <- R_i Exp(delta_i)``.
- ``kind="se3"``: Gauss-Newton / LM on SE3 residuals ``[rho, phi]``, started from the split fit.

Every residual touches ``k`` consecutive control points, so the normal matrix is block banded
with ``k`` blocks of bandwidth; it is solved with a banded Cholesky factorization, never densely.
A rotation iteration is one pass over the poses (:mod:`splineimu._kernels.gauss_newton`: residuals,
gradient, the normal matrix straight into its band, the penalty in the same kernels). It starts from
a quasi-interpolant of the poses on the control grid whose weakly determined end controls are
fitted to the end segments' poses first; once the steps are small they reuse the last
factorization and the passes compute the gradient alone. The smoothness term penalizes
third differences of the control positions and second differences of the rotation increments
(Eilers & Marx's P-spline penalty); a tiny default keeps segments without data (gaps)
well-posed and bridges them smoothly. Positions fitted finer than their poses may be bridged
between the poses by second differences instead (:func:`.problem.bridge_weight`).
"""

from __future__ import annotations

import time

import numpy as np

from .. import lie
from .._kernels import gauss_newton as _gn
from ..errors import InputError, SplineImuError
from .banded import DEFAULT_SMOOTHNESS, layout, observable_layout, shifted_layout
from .checks import (
    burst_warnings,
    check_rotation_steps,
    check_stamp_clusters,
    held_poses,
    input_warnings,
    interpolated_poses,
    noise_interpolated,
    resolve_setting,
    rotation_flips,
    singular_message,
    stamp_warnings,
    validate_poses,
)
from .controls import _quat_wxyz
from .core import KINDS, Spline
from .crossval import MAX_CV_POSES, _windows
from .glitches import WARN_RESIDUAL_M, classify_residuals, dropped_warning, without_steps
from .knots import choose_knot_spacing
from .ladder import _LADDER
from .problem import _Problem, bridge_note, bridge_weight
from .report import FitReport, FitWarning, prediction_warnings
from .signals import MAX_CONTROL_TURN_RAD, max_rotation_spacing, rotation_increments
from .surrogate import LINE_GYRO_FLOOR, LINE_SHARE, prediction_at_spacing, residual_lines
from .zones import find_gaps

#: Poses (the middle ones) on which the rotation spline's bias is checked (:func:`_rotation_bias`).
BIAS_CHECK_POSES = 2000
#: The SO3 spline's bias excess (over the R3 proxy's), relative to the predicted gyro error^2,
#: from which the rotation is moved a rung finer (:func:`_rotation_bias`).
SO3_EXCESS_MOVE = 0.9
#: ... and from which the choice's rivals (the rungs of any order predicting within
#: SO3_RIVAL_SHARE of it, at most SO3_RIVALS of them) get their own excess measured, the rotation
#: moving to the one with the least error with it. Lecture ellipse, white noise, 1 kHz: k5 784
#: ms predicted 0.00029 rad/s and measured 0.00037 (an excess of 0.66x the prediction^2), k6
#: 793 ms 0.00031 and 0.00027: 1.34x and 1.45x the best fixed setting on seeds 4 and 5, now
#: 0.99x. From 0.25x it moved the ellipse's AR(1) noise at 100 Hz (seed 7, 0.99 -> 1.26x).
SO3_EXCESS_RIVALS = 0.5
SO3_RIVAL_SHARE = 0.1
SO3_RIVALS = 2


#: Poses resampled by interpolation (:func:`.checks.interpolated_poses`) are chosen and fitted
#: without the interpolated ones where the automatic choice put either knot spacing within this
#: many spacings of the poses they were made from (10 Hz poses at 20 Hz: knots of 35-280 ms, fast
#: hand-held accel 5.5-7.4x the best fixed setting, predicted 0.04x). Not coarser: at 200 Hz from
#: 100 Hz the choice is 4x or more and within the bars, and the 100 Hz poses alone read the
#: six-position scene's noise as coloured (gyro 1.01 -> 1.65x the best).
RESAMPLED_SPACINGS = 3.0


def _lines_warning(t, res_rot, keep, dt, choice):
    """``residual_periodic`` where the rotation's residual holds spectral lines (periodic motion
    such as vibration, :func:`.surrogate.residual_lines`) whose gyro content the knots removed is
    LINE_SHARE times the predicted gyro error and LINE_GYRO_FLOOR or more; not for rotations read
    as motion."""
    rot = choice["rotation"] if choice else None
    if rot is None or rot["motion_limited"]:
        return []
    found = residual_lines(t, np.where(keep[:, None], res_rot, 0.0), dt)
    pred = choice["predicted_gyro_rms_rad_s"]
    if found is None or found[0] < max(LINE_SHARE * pred, LINE_GYRO_FLOOR):
        return []
    gyro, freqs, peak = found
    at = ", ".join(f"{x:.3g}" for x in freqs[:3]) + (" ..." if len(freqs) > 3 else "")
    return [FitWarning("residual_periodic", f"the rotation fit residual holds narrow spectral lines at {at} Hz (up to "
                       f"{peak:.0f}x the noise around them): periodic motion such as vibration, which the "
                       f"{1e3 * dt:.3g} ms rotation knots smooth away ({gyro:.3g} rad/s of gyro, {gyro / pred:.1f}x "
                       "the predicted gyro error); if it is motion (a vibrating body, or an estimator's ground truth "
                       "such as EuRoC's), --rotation-source estimate (fit: estimated_rotation=True) keeps it")]


def _poses_in(t_s, positions, quat_xyzw, origin_ns, estimated):
    """fit()'s poses from arrays or from a track (:class:`splineimu.io.PoseTrack`), with the
    origin and whether the rotations are an estimator's output (``"auto"``: a track whose file
    carries IMU biases; None: not said, and not such a track)."""
    auto = isinstance(estimated, str) and estimated == "auto"
    if not auto and not isinstance(estimated, (bool, np.bool_)):
        raise SplineImuError(f"estimated_rotation must be True, False or 'auto', got {estimated!r}")
    if hasattr(t_s, "t_ns") and hasattr(t_s, "quat_xyzw"):  # a track read from a pose file
        track = t_s
        if positions is not None or quat_xyzw is not None or origin_ns is not None:
            raise SplineImuError("a track gives the times, poses and origin: do not pass positions, quat_xyzw "
                                 "or origin_ns with it")
        if auto:
            estimated = True if getattr(track, "bias_gyro", None) is not None else None
        origin = track.origin_ns
        t = (track.t_ns - origin).astype(np.float64) / 1e9
        return t, track.positions, track.quat_xyzw, origin, None if estimated is None else bool(estimated)
    if positions is None or quat_xyzw is None:
        raise SplineImuError("fit() takes times, positions and quat_xyzw, or a track read from a pose file")
    return t_s, positions, quat_xyzw, 0 if origin_ns is None else origin_ns, None if auto else bool(estimated)


def fit(t_s, positions=None, quat_xyzw=None, kind="split", order="auto", knot_spacing_s="auto", *,
        position_order=None, position_knot_spacing_s=None, weights=None, smoothness=DEFAULT_SMOOTHNESS,
        origin_ns=None, max_iter=200, reject_outliers=True, estimated_rotation="auto", progress=False,
        return_report=False):
    """Least-squares B-spline through timestamped poses ``world_T_body``.

    Parameters
    ----------
    t_s : (N,) array_like, or :class:`splineimu.io.PoseTrack`
        Strictly increasing pose times, seconds since ``origin_ns``. Or a track read from a pose
        file (:func:`splineimu.io.read_tum`, :func:`splineimu.io.read_euroc_groundtruth`): its
        times (from its first stamp, the origin), positions and rotations, and what the file says
        about its rotations (``estimated_rotation``); ``positions`` and ``quat_xyzw`` are not given then.
    positions : (N, 3) array_like
    quat_xyzw : (N, 4) array_like
        Any sign, not necessarily unit (normalized; a zero quaternion is an error).
    kind : {"split", "se3"}
    order : int or "auto"
        Spline order (4 = cubic) of the rotation (and, unless ``position_order`` is given, of
        the position). ``"auto"`` (default) chooses among 4, 5 and 6 from the data.
    knot_spacing_s : float or "auto"
        Knot spacing [s] of the rotation (and, unless ``position_knot_spacing_s`` is given, of
        the position); ``"auto"`` chooses it from the data (:mod:`splineimu.spline.knots`),
        for rotation and position independently. Poses resampled by interpolation (every m-th
        carrying the data) are then chosen and fitted without the interpolated ones where the
        spacings come within :data:`RESAMPLED_SPACINGS` of the data's (warning ``poses_interpolated``).
        An automatic fit's reported settings, given back, fit nearly but not exactly the same
        spline: the automatic fit also places the rotation grid (``knot_phase`` in the report's
        ``knot_choice``) and weighs the data by the noise levels it read (lecture ellipse, 1 mm /
        0.1 deg: gyro within 2e-4 rad/s of it, against a predicted error of 1e-3).
    position_order, position_knot_spacing_s : int / float / "auto", optional
        The position grid's own settings (``kind="split"`` only).
    weights : (N,) array_like, optional
        Relative per-pose weights (their scale does not matter; 0 drops a pose from the data term).
    smoothness : float
        Relative weight of the P-spline difference penalty (see module notes).
    origin_ns : int, optional
        Integer-nanosecond origin of the time base (0; a track's first stamp).
    max_iter : int
        Gauss-Newton iterations of the rotation at most: typical fits converge in 4-6; knots
        finer than the poses (low-rate input) took 104 on 1 Hz poses. Not converging warns
        (``fit_not_converged``).
    reject_outliers : bool
        After the first fit, drop runs of poses that jump away from the motion and back
        (tracking glitches, :mod:`splineimu.spline.checks`) and fit again, the automatic
        knot choice made again without them; the report lists them (``dropped_poses``) and
        warns. Before the fit, orientation flips and held poses (a pose repeated exactly at
        later stamps while the input moves, :func:`.checks.held_poses`) are dropped alike.
    estimated_rotation : bool or "auto"
        The rotations are an estimator's output that fused an IMU (EuRoC's
        ``state_groundtruth_estimate0``, vicon2gt: files that carry IMU biases), not
        measurements: their detail up to the Nyquist frequency is the vehicle's motion as that
        IMU saw it, and the automatic rotation spacing keeps it (read as motion-limited input,
        :mod:`splineimu.spline.knots` step 4). Measured against the real IMU, EuRoC's MAV: read
        as pose noise, V1_01/V2_01/V2_03's ground truth got ~100 ms rotation knots, where V1_02's
        gyro error below 10 Hz is 5.4x its best; the positions are smoothed as measurements.
        ``"auto"`` (default): True for a track whose file carries IMU biases (EuRoC's 17-column
        ground truth, vicon2gt); else measurements, whose top octave is read as motion where the
        positions' is and the rotation's value is best fitted nearly through its poses (low-rate
        precise poses of fast rotation: ``read_as_noise`` in the rotation's knot choice keeps the
        first reading). False: measurements, never so read. Arrays say nothing of where they
        come from: pass True for EuRoC's ground truth given as arrays (or TUM text), or fit the
        track.
    progress : bool
        Show a progress bar for long fits.
    return_report : bool
        Return ``(spline, FitReport)`` instead of the spline alone.

    Returns
    -------
    Spline, or (Spline, FitReport)
        The spline covers exactly ``[t_s[0], t_s[-1]]``.

    Raises
    ------
    InputError
        Bad shapes, unsorted or non-finite input, fewer than 3 poses of positive weight, consecutive
        poses rotating by more than 90 degrees.
    SplineImuError
        Bad settings.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 2, 201)
    >>> pos = np.c_[np.sin(t), np.cos(t), t]
    >>> quat = np.c_[np.zeros((201, 2)), np.sin(t / 2), np.cos(t / 2)]
    >>> spl = fit(t, pos, quat, knot_spacing_s=0.05)
    >>> bool(np.abs(spl.angular_velocity_body([1.0])[0] - [0, 0, 1]).max() < 1e-6)
    True
    """
    t0_wall = time.perf_counter()
    t_s, positions, quat_xyzw, origin_ns, estimated_rotation = _poses_in(t_s, positions, quat_xyzw, origin_ns,
                                                                         estimated_rotation)
    kind = str(kind).lower()
    if kind not in KINDS:
        raise SplineImuError(f"spline kind must be one of {KINDS}, got {kind!r}")
    r_order = resolve_setting(order, "order", "order")
    r_dt = resolve_setting(knot_spacing_s, "knot spacing", "dt")
    p_order = r_order if position_order is None else resolve_setting(position_order, "position order", "order")
    p_dt = (r_dt if position_knot_spacing_s is None
            else resolve_setting(position_knot_spacing_s, "position knot spacing", "dt"))
    if kind == "se3" and (position_order is not None or position_knot_spacing_s is not None):
        raise SplineImuError("position_order and position_knot_spacing_s need kind='split'")
    if not (smoothness >= 0 and np.isfinite(smoothness)):  # -1 and NaN failed as a "singular" fit
        raise SplineImuError(f"smoothness must be finite and >= 0, got {smoothness!r}")
    if not (max_iter >= 1 and max_iter == int(max_iter)):  # 0 returned the initial guess
        raise SplineImuError(f"max_iter must be a positive integer, got {max_iter!r}")
    t, P, R, w = validate_poses(t_s, positions, quat_xyzw, weights)
    for dt in {r_dt, p_dt} - {"auto"}:  # 1e-300 s asked numpy for 1e300 segments (a bare ValueError)
        if t.size > 1 and (t[-1] - t[0]) / dt > 100.0 * t.size:
            raise SplineImuError(f"knot spacing {dt:g} s is too fine: {(t[-1] - t[0]) / dt:.3g} segments for "
                                 f"{t.size} poses (at most 100 per pose)")
    q = _quat_wxyz(quat_xyzw)
    # orientation flips (away and back by more than 90 degrees) and held poses (repeated at later
    # stamps) are dropped before anything else
    flips = rotation_flips(t, R) if reject_outliers else np.zeros(t.size, dtype=bool)
    t_in, early_warnings = t, dropped_warning(t, flips, "an orientation flip")
    held = held_poses(P, q) if reject_outliers else None
    if held is not None:
        k, i = int(np.count_nonzero(held)), np.flatnonzero(held)
        early_warnings.append(FitWarning(
            "poses_held", f"{k} of {t.size} poses repeat the pose before them exactly at a later stamp while the "
            "input moves (held by a logger that writes the latest pose faster than poses come, or logged twice): "
            "dropped, each pose kept at its first stamp", float(t[i[0]]), float(t[i[-1]])))
    early = flips if held is None else flips | held  # the poses dropped before the fit
    if early.any():
        t, P, R, q, w = (a[~early] for a in (t, P, R, q, w))
    # fitted about the first position (exactly, nearby floats): georeferenced input (UTM, 5e6 m)
    # rounds at 1e-9 m, where the SE3 steps stop (it took 60-90 iterations instead of 5)
    offset = P[0].copy()
    P = P - offset
    if np.count_nonzero(w) < 3:  # fewer leave the position's quadratic (the penalty's null space) free
        raise InputError(f"too few poses to fit: got {np.count_nonzero(w)} with a positive weight, need at least 3")
    gap_warnings = check_rotation_steps(t, R, np.flatnonzero(~early))
    given = (r_order, r_dt, p_order, p_dt)
    theta = np.zeros((t.size, 3))  # accumulated body-frame increments (signals.rotation_signal)
    _gn.quat_increments(q, theta[1:])
    np.cumsum(theta, axis=0, out=theta)
    chosen_on = slice(None)  # the poses the knot choice sees
    if "auto" in given:
        check_stamp_clusters(t)
    # (a split spline's position grid may be given while its rotation grid is chosen, or the reverse)
    source = {(True, True): "auto", (False, False): "given", (True, False): "rotation auto, position given",
              (False, True): "rotation given, position auto"}[r_dt == "auto", p_dt == "auto"]

    # the choice reads the positions without the steps of their tracking (the fit follows them)
    P_chosen = without_steps(t, P, w, WARN_RESIDUAL_M) if "auto" in given else P

    off_poses = {}  # the order of each grid moved half a spacing off the poses (observable_layout)

    def seen(lay, k, key):
        lay, moved = observable_layout(t, lay, k)
        if moved:
            off_poses[key] = k
        else:
            off_poses.pop(key, None)
        return lay

    def settings(wts, turn=MAX_CONTROL_TURN_RAD):
        """The knot choice (None if all is given), the (order, layout) of rotation and position,
        and the noise levels that weigh them."""
        ro, rdt, po, pdt = given
        ch = None
        if "auto" in given:
            on = chosen_on
            # (a split spline's rotation grid may start before the first pose: .phase; an se3
            # spline's one grid starts on it)
            ch = choose_knot_spacing(t[on], P_chosen[on], R[on], wts[on], ro, po, None if rdt == "auto" else rdt,
                                     None if pdt == "auto" else pdt, turn, estimated_rotation, kind == "split")
            ro, rdt = ch["rotation"]["order"], ch["rotation"]["knot_spacing_s"]
            po, pdt = ch["position"]["order"], ch["position"]["knot_spacing_s"]
        if kind == "se3":
            # one grid: the finer spacing, the position's order (the accelerometer's)
            rdt = pdt = min(rdt, pdt)
            ro = po = max(ro, po)
        phase = ch["rotation"]["knot_phase"] if ch is not None else 0.0
        lay_r = seen(shifted_layout(t[0], t[-1], rdt, ro, phase), ro, "rotation")
        lay_p = layout(t[0], t[-1], pdt, po)
        lay_p = seen(lay_p, po, "position") if kind == "split" else lay_p  # (se3: one grid, the rotation's)
        if kind == "se3" and ch is not None:  # the predictions moved to that spacing: the
            # interior's, and the noise it adds to the ends' and gaps' (and the end zones of the grid)
            for key, r in (("rotation", 1), ("position", 2)):
                c = ch[key]
                new = prediction_at_spacing(c, rdt, r)
                add = max(new**2 - c["predicted_rms"] ** 2, 0.0)
                c["end_predicted_rms"] = float(np.sqrt(c["end_predicted_rms"] ** 2 + add))
                for gap in c["gaps"]:
                    if gap["predicted_rms"] is not None:
                        gap["predicted_rms"] = float(np.sqrt(gap["predicted_rms"] ** 2 + add))
                c["predicted_rms"], c["end_zone_s"] = new, float(ro * lay_r[1])
            ch["predicted_gyro_rms_rad_s"] = ch["rotation"]["predicted_rms"]
            ch["predicted_accel_rms_m_s2"] = float(np.hypot(ch["position"]["predicted_rms"],
                                                            ch["accel_from_orientation_rms_m_s2"]))
        sig = (1e-3, 1e-3) if ch is None else tuple(max(ch[key]["cv_rms"] / np.sqrt(3.0), 1e-6)
                                                    for key in ("rotation", "position"))
        return ch, ro, lay_r, po, lay_p, sig

    choice, r_order, lay_r, p_order, lay_p, (sig_r, sig_p) = settings(w)
    resampled = interpolated_poses(t, P, theta) if choice is not None else None
    noise_only = False  # (the noise interpolated, the motion not)
    if resampled is None and choice is not None:
        resampled = noise_interpolated(t, P, theta)
        noise_only = resampled is not None
    if resampled is not None:
        m, between = resampled
        h = float(np.median(np.diff(t)))
        auto = [lay[1] for lay, dt in ((lay_r, given[1]), (lay_p, given[3])) if dt == "auto"]
        if auto and min(auto) < RESAMPLED_SPACINGS * m * h:  # (a given spacing is fitted as given)
            # knots that close to the poses the others were interpolated from bend at them: the
            # held-out fits took the interpolation for motion. Chosen and fitted without those
            w_all = w
            w = np.where(between, 0.0, w)
            chosen_on = np.flatnonzero(~between)
            choice, r_order, lay_r, p_order, lay_p, (sig_r, sig_p) = settings(w)
            if noise_only:  # (the poses between hold the motion too: fitted, at the knots chosen without them)
                w = w_all
            nb = np.count_nonzero(between)
            gap_warnings.append(FitWarning(
                "noise_interpolated", f"the pose noise of {nb} of {t.size} poses is interpolated from their "
                f"neighbours' (noise drawn at {1.0 / (m * h):.3g} Hz and resampled to {1.0 / h:.3g} Hz?): the knots "
                f"are chosen on the other {t.size - nb}, which show that noise as it is, and the fit follows all "
                "poses") if noise_only else FitWarning(
                "poses_interpolated", f"{nb} of {t.size} poses lie on the straight line through "
                f"their neighbours (a trajectory resampled from {1.0 / (m * h):.3g} Hz to {1.0 / h:.3g} Hz?): the "
                f"fit follows the other {t.size - nb}, and no motion above "
                f"{0.5 / (m * h):.3g} Hz is in the input"))

    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(desc="fit (Gauss-Newton)", unit="it", leave=False)  # 4-6 iterations typically, up to max_iter

    def tick(_it):
        if bar is not None:
            bar.update(1)

    def problems(wts):
        args = (float(smoothness), 1.0 / sig_r**2, 1.0 / sig_p**2, None if choice is None else sig_r)
        bridge, held = bridge_weight(choice, kind, given[3], lay_p, t, P, wts, p_order, sig_p, args[0])
        pos = _Problem(t, P, R, q, wts, p_order, *lay_p[:3], *args, bridge=bridge)
        if choice is not None:  # (the report's knot choice says whether the poses were bridged so)
            choice["position"].update(bridge_smoothness=pos.bridge_weight if pos.bridge.any() else 0.0,
                                      bridge_heldout_ratio=held)
        return _Problem(t, P, R, q, wts, r_order, *lay_r[:3], *args), pos

    probs = problems(w)
    Rc0 = probs[0].initial_rotations()
    gap_warnings += stamp_warnings(t, P, theta)
    dropped = np.zeros(t.size, dtype=bool)
    warnings = []
    for attempt in range(2):
        Rc, Pc, res_pos, res_rot, iters, conv = _solve(probs, Rc0, kind, max_iter, tick, smoothness)
        if not conv and given[1] == "auto" and lay_r[1] > max_rotation_spacing(t, R, np.pi / 2):
            # stalled with knots turning over 90 degrees (the ends extrapolate the turn through
            # noise; six-position scene, 1 deg noise, 113 degrees): choose again within 90
            choice, r_order, lay_r, p_order, lay_p, (sig_r, sig_p) = settings(probs[0].w, np.pi / 2)
            probs = problems(probs[0].w)
            Rc, Pc, res_pos, res_rot, iters, conv = _solve(probs, probs[0].initial_rotations(), kind, max_iter, tick,
                                                           smoothness)
        if attempt == 1:
            break
        drop, warnings = classify_residuals(t, P, theta, res_pos, res_rot, probs[0].w)
        if not (reject_outliers and drop.any()):
            break
        dropped = drop
        w2 = w.copy()
        w2[drop] = 0.0
        if choice is not None:
            # the glitch steered the choice too (its jump read as noise or motion): choose again
            choice, r_order, lay_r2, p_order, lay_p, (sig_r, sig_p) = settings(w2)
            Rc0 = Rc if lay_r2 == lay_r else None
            lay_r = lay_r2
        else:
            Rc0 = Rc
        probs = problems(w2)
        if Rc0 is None:
            Rc0 = probs[0].initial_rotations()
    if dropped.any():
        # the residual bursts of the first fit that were glitches are gone; re-check the rest
        _, warnings = classify_residuals(t, P, theta, res_pos, res_rot, probs[0].w)
        warnings = dropped_warning(t, dropped) + warnings
    if choice is not None and kind == "split":
        moved = _rotation_bias(choice, probs[0], Rc, max_iter, may_move=given[1] == "auto")
        if moved is not None:  # the SO3 spline's own bias moved the rotation: fit again there
            r_order, finer = moved
            lay_r = seen(layout(t[0], t[-1], finer, r_order), r_order, "rotation")
            probs = problems(probs[0].w)
            Rc, Pc, res_pos, res_rot, more, conv = _solve(probs, probs[0].initial_rotations(), kind, max_iter, tick,
                                                          smoothness)
            iters += more
    if choice is not None and kind == "split" and "rotation" in off_poses:  # (where the grid now sits)
        choice["rotation"]["knot_phase"] = round(float((t[0] - lay_r[0]) / lay_r[1]), 9)
    if kind == "se3":
        spl = Spline(lay_r[0], lay_r[1], Pc + offset, Rc, kind, r_order, origin_ns)
    else:
        spl = Spline(lay_r[0], lay_r[1], Pc + offset, Rc, kind, r_order, origin_ns, position_t0_s=lay_p[0],
                     position_dt_s=lay_p[1], position_order=p_order)
    if bar is not None:
        bar.close()
    keep = ~dropped & (w > 0)  # the poses the fit followed: neither dropped nor given weight 0
    ep = np.linalg.norm(res_pos[keep], axis=1)
    ea = np.linalg.norm(res_rot[keep], axis=1)
    pred_g = choice["predicted_gyro_rms_rad_s"] if choice else None
    pred_a = choice["predicted_accel_rms_m_s2"] if choice else None
    on = chosen_on  # (resampled poses: their rate and top octave are those of the poses carrying the data)
    spacings = {"rotation": lay_r[1], "position": lay_p[1]}
    warnings = (prediction_warnings(choice, t) + early_warnings + gap_warnings + warnings
                + input_warnings(t[on], P[on], theta[on], res_pos[on], res_rot[on], keep[on], choice, spacings))
    warnings += _lines_warning(t[on], res_rot[on], keep[on], lay_r[1], choice)
    warnings += burst_warnings(t[on], res_pos[on], res_rot[on], keep[on], choice, spacings, warnings)
    if p_order < 3:  # the CLI refuses it; here a spline for poses alone may be what is wanted
        warnings.append(FitWarning("order_too_low", f"position order {p_order} is piecewise linear: no acceleration "
                                   "between knots, so the accelerometer reads gravity alone; use order 3 or more"))
    if not conv:
        why = ("; no step lowered the cost any more, as when the knots are too coarse for the turns between them: try "
               "a finer knot spacing" if iters < max_iter else  # Levenberg-Marquardt gave up: more would not help
               " (more iterations: fit(max_iter=...); or a coarser knot spacing)")
        # a gap spanning many knots leaves controls that only the smoothness penalty holds, too weakly
        # conditioned to settle (BROAD 07 with 20 s left out, 28 ms knots: steps of radians there to the end)
        long_gaps = [(a, b) for a, b in find_gaps(t, keep.astype(float)) if b - a > 4 * r_order * lay_r[1]]
        if long_gaps:
            a, b = max(long_gaps, key=lambda g: g[1] - g[0])
            why = (f": the {b - a:.3g} s without poses from {a:.3f} s to {b:.3f} s spans {(b - a) / lay_r[1]:.0f} "
                   "knot spacings, whose controls only the smoothness penalty holds; split the input there "
                   "(--gaps split, PosesInput(gaps=\"split\"))")
        warnings.append(FitWarning("fit_not_converged", f"the rotation fit stopped after {iters} iterations without "
                                   f"converging: the spline may not be the least-squares one{why}"))
    report = FitReport(
        kind=kind, order=r_order, knot_spacing_s=lay_r[1], knot_spacing_source=source, n_poses=int(t_in.size),
        n_control=lay_r[3], span_s=(float(t[0]), float(t[-1])),
        residual_position_rms_m=float(np.sqrt(np.mean(ep**2))), residual_position_max_m=float(ep.max()),
        residual_angle_rms_rad=float(np.sqrt(np.mean(ea**2))), residual_angle_max_rad=float(ea.max()),
        iterations=iters, converged=bool(conv), time_s=time.perf_counter() - t0_wall,
        smoothness=float(smoothness), position_order=p_order, position_knot_spacing_s=lay_p[1],
        n_position_control=lay_p[3], predicted_gyro_rms_rad_s=pred_g, predicted_accel_rms_m_s2=pred_a,
        dropped_poses=sorted(np.flatnonzero(early).tolist() + np.flatnonzero(~early)[dropped].tolist()),
        knot_choice=choice,
        sparse_control_points=probs[0].n_sparse, warnings=warnings, origin_ns=int(origin_ns),
        notes=[f"{key if kind == 'split' else 'the'} grid moved half a knot spacing off the poses: at order "
               f"{k} its knots on them leave its finest control mode unseen (the IMU between poses would follow "
               "the pose noise)" for key, k in off_poses.items()] + bridge_note(choice),
    )
    spl.fit_report = report
    return (spl, report) if return_report else spl


def _rotation_bias(choice, rot, Rc_fit, max_iter, may_move=False):
    """Put the rotation spline's own bias into the predicted gyro error. The choice measures bias
    on the accumulated increments (an R3 spline); the cumulative SO3 spline of turns about moving
    axes has more (lecture ellipse at 0.5-1 s knots: 2-11x, predicted 0.2-0.7x the measured
    error). The gyro's change from a fit a ladder rung finer, on SO3 and on the increments, holds
    the same noise change: the excess of the first over the second is added to the bias. Both on
    the middle :data:`BIAS_CHECK_POSES` poses (at least 40 knot spacings).

    With ``may_move`` (an automatic spacing), an excess of at least :data:`SO3_EXCESS_MOVE` times
    the predicted error^2 moves the rotation to the ladder's rung below where that rung's
    prediction, plus the excess scaled down as the bias (dt^(k - 1)), is the smaller; from
    :data:`SO3_EXCESS_RIVALS` times, the rival rungs (of any order) with their own measured
    excess are candidates too. Returns the (order, spacing) moved to (else None), the choice
    updated. Lecture ellipse, white noise of 0.5 mm / 0.05 deg,
    200 Hz: k6 ~1017 ms, predicted 0.67x the measured gyro error, 1.22-1.42x the best fixed
    setting on 9 of 10 seeds; moved to ~814 ms, 0.96-0.99x. At 1 mm / 0.1 deg (200 and 100 Hz,
    6 scenes x 3 noise kinds x 10 seeds) it moves nothing; with a threshold of 0.25 it moved 7
    of those 360, 3 for the worse (ellipse AR(1) at 100 Hz 0.99 -> 1.26x)."""
    c = choice["rotation"]
    k, dt = rot.order, c["knot_spacing_s"]
    block = c.get("anchor_poses", 1)
    excess = _so3_excess(rot, k, dt, Rc_fit, max_iter, block)
    pred = c["predicted_rms"]
    if excess is None or not excess > 0:
        return None
    new = float(np.sqrt(pred**2 + excess))
    c["end_predicted_rms"] = float(np.sqrt(c["end_predicted_rms"] ** 2 - pred**2 + new**2))
    c["predicted_rms"] = choice["predicted_gyro_rms_rad_s"] = new
    if not may_move:
        return None
    def at(r, spacing):  # whether candidate row r is the rung of order k at that spacing
        return r["order"] == k and abs(np.log(r["knot_spacing_s"] / spacing)) < 0.05

    best, row = new, None
    below = [r for r in c["candidates"] if at(r, dt / _LADDER)]
    if below and excess >= SO3_EXCESS_MOVE * pred**2:
        row_f = below[0]
        moved = float(np.sqrt(row_f["predicted_rms"] ** 2 + excess * (row_f["knot_spacing_s"] / dt) ** (2 * (k - 1))))
        if moved < best:
            best, row = moved, row_f
    if excess >= SO3_EXCESS_RIVALS * pred**2:
        rivals = sorted((r for r in c["candidates"] if r["predicted_rms"] <= pred * (1.0 + SO3_RIVAL_SHARE)
                         and not at(r, dt)),
                        key=lambda r: r["predicted_rms"])[:SO3_RIVALS]
        for r in rivals:
            e = _so3_excess(rot, r["order"], r["knot_spacing_s"], None, max_iter, block)
            total = float(np.sqrt(r["predicted_rms"] ** 2 + max(e if e is not None else np.inf, 0.0)))
            if total < best:
                best, row = total, r
    if row is None:
        return None
    dt_f = row["knot_spacing_s"]
    c["end_predicted_rms"] = float(np.sqrt(max(c["end_predicted_rms"] ** 2 - new**2 + best**2, best**2)))
    c.update(order=row["order"], knot_spacing_s=dt_f, knot_phase=0.0, predicted_noise_rms=row["predicted_noise_rms"],
             moved_by_so3_bias_from_s=dt, end_zone_s=row["order"] * dt_f)
    c["predicted_rms"] = choice["predicted_gyro_rms_rad_s"] = best
    return row["order"], dt_f


def _so3_excess(rot, k, dt, Rc_fit, max_iter, block=1):
    """The SO3 spline's gyro bias^2 beyond the R3 proxy's at order k, spacing dt (see
    :func:`_rotation_bias`), on the middle poses; None where it cannot be measured."""
    n = min(rot.t.size, MAX_CV_POSES, max(BIAS_CHECK_POSES, int(40 * dt / np.median(np.diff(rot.t)))))
    sl = slice((rot.t.size - n) // 2, (rot.t.size - n) // 2 + n)
    t, w = rot.t[sl], rot.w[sl]
    (wd,) = _windows(t, rotation_increments(rot.R[sl], block), w, True)
    idx = wd.scored_index
    if idx.size < 2 or (t[-1] - t[0]) / dt < 3 * k:
        return
    gyro = []
    for h in (dt, dt / _LADDER):
        lay = layout(t[0], t[-1], h, k)
        if Rc_fit is not None and n == rot.t.size and lay[:3] == (rot.t0, rot.dt, rot.nseg):
            Rc = Rc_fit  # the check covers every pose: this is the fit itself
        else:
            sub = _Problem(t, rot.P[sl], rot.R[sl], rot.q[sl], w, k, *lay[:3], rot.smoothness, rot.w_rot, rot.w_pos,
                           rot.noise_rad)
            Rc, _, _, conv = sub.solve_rotations(sub.initial_rotations(), max_iter=max_iter)
            if not conv:
                return
        gyro.append(Spline(lay[0], lay[1], np.zeros((Rc.shape[0], 3)), Rc, "split", k).angular_velocity_body(t[idx]))
    d_r3 = wd.derivative(k, dt, wd.zero, 1, 1)[0][idx]  # a copy: the next call reuses the buffer
    d_r3 -= wd.derivative(k, dt / _LADDER, wd.zero, 1, 1)[0][idx]
    return float(np.mean(np.sum((gyro[0] - gyro[1]) ** 2, axis=1)) - np.mean(np.sum(d_r3**2, axis=1)))


def _solve(probs, Rc, kind, max_iter, tick, smoothness):
    rot, pos = probs
    try:
        if kind == "se3":
            Pc = rot.solve_positions()
            Rc, res_rot, iters, conv = rot.solve_rotations(Rc, max_iter=max_iter, progress=tick)
            Rc, Pc, res6, it2, conv = rot.solve_se3(Rc, Pc, max_iter=max_iter, progress=tick)
            iters += it2
            spl = Spline(rot.t0, rot.dt, Pc, Rc, kind, rot.order)
            p_fit, q_fit = spl.pose(rot.t)
            res_pos = rot.P - p_fit
            res_rot = lie.so3_log(np.matmul(np.swapaxes(lie.quat_xyzw_to_matrix(q_fit), 1, 2), rot.R))
        else:
            Pc = pos.solve_positions()
            res_pos = pos.position_residuals(Pc)
            Rc, res_rot, iters, conv = rot.solve_rotations(Rc, max_iter=max_iter, progress=tick)
    except np.linalg.LinAlgError:
        raise SplineImuError(singular_message(rot.t, rot.w, min(rot.dt, pos.dt), smoothness)) from None
    return Rc, Pc, res_pos, res_rot, iters, conv
