"""Automatic knot spacing and order, for rotation and position independently.

Each part is chosen on its own R3 signal: the control positions of the position spline, and
for the rotation the accumulated body-frame increments ``theta_m = sum_{l <= m} Log(R_{l-1}^T
R_l)`` (white pose noise stays white in it, and its time derivative is the body rate). The
target is the error of the derivative the IMU sees: the accelerometer (2nd derivative of the
position) and the gyroscope (1st derivative of theta).

Method
------
1. **Blocked cross-validation** on held-out poses gives the value-optimal spacing per order
   (4, 5, 6): consecutive poses are grouped in blocks, the blocks dealt to 4 folds in turn, and
   each fold predicted by the spline fitted to the other three; the score is the mean squared
   prediction error away from the ends. The grid runs from 0.7x the median pose spacing (no
   floor at twice the pose spacing) to a quarter of the span or :data:`MAX_SPACING_S` (10 s),
   coarse steps of 1.6x and a finer step around the best. The block length comes from the
   data: a first pass with 0.1 s blocks (:data:`MIN_FIRST_BLOCK` poses at least from 20 Hz where
   the top octave holds noise), whose residual gives the noise correlation time (the
   lag where its autocorrelation falls below 0.1); blocks of 3 correlation times (1 pose for
   white noise) then keep correlated or upsampled noise of a held-out block independent of its
   training neighbours.
2. **A noise surrogate**: the residual of that fit is the pose noise times the fit's residual
   transfer, which is measured by passing a white draw through the same fit; dividing the
   residual's periodogram by it estimates the noise spectrum from about the fit's cut-off up,
   continued flat below (white, AR(1) and upsampled noise are flat there). A series with that
   spectrum is drawn. The spectrum is read from the coarser of the two cross-validated fits
   (0.1 s blocks see more of correlated noise) and continued below its cut-off from its level
   on the octave above's trend (the cut-off bin, where the measured transfer first reaches
   0.2, reads up to 3.7x low), for one octave (two where steeper than f^-2) with that octave's
   log-log slope (median over the windows, within [-2, 0]), flat beyond: the noise error is the spectrum
   times f^2 (gyro) or f^4 (accel), so a spectrum rising toward low frequency puts it below the
   cut-off. BROAD orientation noise against the real gyro is f^-2 from 12 to 40 Hz, steeper
   above (07: f^-3.8 over 31-63 Hz); the surrogate matches it within 0.8-1.35x there in BROAD
   07, 18 and 32 (0.5x in 07 with an unbounded slope, 2.6-3.5x low in 32 from the cut-off bin;
   a flat continuation missed up to 7x). White, AR(1) and upsampled noise are flat above the
   cut-off and stay flat; so does motion-limited input (step 4), whose residual is motion. A
   rotation residual uncorrelated from pose to pose and flat from twice the cut-off up is white
   noise, drawn flat at the level of the band above twice the cut-off: the octave above the
   cut-off holds motion the fit misses too and reads steeper (rate-table at 100 Hz: f^-0.49,
   the noise's gyro error read 1.2-1.33x high on every rung; six-position at 100 Hz: f^-2.1 to
   f^-2.45, twice the noise's RMS level), continued below the cut-off with that slope. Drawn
   flat, the noise part predicts the measured one within 0.93-1.03x (rate-table 100 Hz,
   fast hand-held 200 Hz).
3. **The derivative's error on a ladder** (:mod:`.ladder`) of spacings (steps of 1.25x around
   the value-optimal one, per order): signal and surrogate are fitted together; the noise part
   is the surrogate fit's derivative, the bias part the change of the signal fit's derivative
   from the rung below less the surrogate's change. That change lags the bias: a bias growing as dt^p
   changes by (1 - 1.25^-p) of itself from the rung below (0.65-0.75 measured for the gyro on
   the ellipse, six-position and rate-table scenes), and the gyro's choice landed a rung too
   coarse (1.16-1.28x the best fixed setting). Where the noise is white (its spectrum over the
   octave above the cut-off flatter than f^-1) the gyro's bias^2 is doubled
   (:data:`WHITE_BIAS_LAG`), by 1.4 where it is drawn flat (:data:`FLAT_WHITE_BIAS_LAG`: a
   surrogate read high had made up for part of the lag; noise-free, the change from the rung
   below is 0.65-1.36x the bias in squares on the scenes, its shape at neighbouring spacings
   differing), and of the rungs of the best order that predict within :data:`WHITE_TIE` of the
   best the coarsest is taken (fast hand-held: 44 and 55 ms within 0.2%, true 0.043 and 0.036
   rad/s: the bias at 55 ms read 1.5x high); coloured noise keeps the change as it is (the
   surrogate's misfit is in it too: doubled, BROAD 32 and 35 synthesized more gyro above 15 Hz
   than their real IMU measured). While the smallest error sits at an end of the ladder
   and the error falls over the two rungs before it, the ladder is walked on past that end,
   toward coarser spacings (the rotation up to its turn limit, step 5; the position up to
   :data:`WALK_MAX_S`: the hand-held accelerometer's optimum is 2-3x the value-optimal
   spacing, beyond the +-2 rungs); no position rung lies beyond it unless a value-optimal
   spacing (of any order) does (BROAD 11 position: the +2 rung, 56 ms, won on a
   lagging bias estimate, accel lp10 1.035x scipy). The (order, spacing) with the smallest
   predicted error wins (for the position, after half a rung either side of it is tried too:
   near the steep bias rise of narrow-band motion the accelerometer's error changes by 20-30%
   per rung; the flips scene got 1.25x the best fixed accel error), and that prediction is reported
   (``predicted_gyro_rms_rad_s``, ``predicted_accel_rms_m_s2``); the same profile over the
   first and last ``k`` spacings gives the noise's error at the ends, and truncation the
   motion's (:func:`splineimu.spline.zones.end_bias2`); gaps of the input's lengths opened
   where there are poses give the error inside its gaps (``gaps``). Where the noise reads as
   white, a rotation rung whose bias estimate is below its noise part (within the scatter of
   the noise realization, and lagging: the 1 kHz ellipse read 1.6e-4 rad/s for a true 2.7e-4),
   and a position rung under uncorrelated noise (the flips scene over 20 s, white noise: order 5
   at its value-optimal 106 ms read no bias, accel 1.28-1.39x the best fixed setting on 5 of 13
   seeds; now order 6 at 118 ms, at most 1.02x; 60 s scenes: mean accel ratio +0-1.5%, none
   beyond 1.07x), takes at least the bias of the nearest rung above that reads one clearly,
   scaled down as dt^(k - r) for the r-th derivative or as steeply as it grows to the next clear
   rung (:func:`.ladder._extrapolate_bias`); a best rotation rung that reads no bias at all is moved between rungs
   (:func:`.ladder._between_rungs`). The accelerometer's prediction
   adds gravity tilted by the rotation fit's own (value) error, from the same ladder at r = 0
   (slow motion: without it the circle scene predicted 0.18x the measured accel error).
4. **Low-rate or re-estimated input** (the power of the second differences falls toward the
   Nyquist frequency: the top of the band holds motion, not noise, :func:`motion_limited`) is
   searched at finer spacings, down to below the pose spacing, with a tenth of the surrogate;
   its ladder is walked only toward finer spacings, down to half the grid's floor. If the
   held-out error grows by less than :data:`NOISE_GROWTH` (12x) with blocks twice as long
   (noise: 1.5-2.8x, noise and motion mixed 6-9x, exact poses' motion mostly 24-150x), the
   error at the choice were that error white noise is reported too (``predicted_rms_if_noise``,
   warning ``prediction_assumes_motion``): an upper bound where noise and motion mix (2-5x the
   measured error on fast hand-held motion at 20 Hz). There the noise under the motion is read
   too (:func:`.surrogate.noise_under_motion`: the held-out errors at three gap lengths as noise plus motion
   growing as a power of the gap; ``noise_under_motion`` in the report) and its derivative's
   error at the choice added to the prediction, which the tenth of the surrogate missed: flips
   at 20 Hz with 0.1 deg / 1 mm noise predicted gyro 0.009 rad/s for 0.098 measured, now 0.087;
   with 0.02 deg / 0.2 mm, 0.0017 for 0.020 and accel 0.078 for 0.54, now 0.017 and 0.71; fast
   hand-held sums of sines 0.08-0.22x the measured before, 0.81-1.9x now; EuRoC V1_02's 20 Hz
   vicon2gt accel 0.018 m/s^2, now 0.128, against 0.116 low-passed against its real IMU.
   That noise is added to every candidate's prediction too and the least taken again, at a
   coarser spacing only (where it reads high, motion near the Nyquist frequency leaks into it):
   hand-held rotation at 20 Hz with 0.02 deg noise got 18 ms knots, gyro 2.6x the best fixed
   setting, now 108 ms, 1.02x (``moved_by_noise_under_motion_from_s``). The rotation only, and
   not for an estimator's output (declared or precise), whose error is no white noise: EuRoC V1_02's
   vicon2gt position would go from 25 to 44 ms, its accel below 10 Hz against the real IMU
   1.017 -> 1.034x scipy.
   A rotation more precise than measured ones (:data:`PRECISE_ROTATION_RAD`: an estimator's
   output, such as EuRoC's ground truth) is read the same way, and so is one declared an
   estimator's output (``estimated_rotation``), in blocks of one pose: its residual's correlation
   is motion's, not noise's (EuRoC V1_01/V2_01/V2_03, MH_03: lag 2-5 poses, blocks of 9-15, knots
   81-106 ms, where V1_02's gyro error below 10 Hz against its IMU is 5.4x its best; declared,
   1.8-11 ms). Such a rotation's ladder holds every rung from the value-optimal spacing down to
   below half the grid's floor, each predicted against the finest rung rather than the rung
   below: its detail is motion, which the finest fit follows best, and motion the poses sample
   too sparsely to predict leaves the rung-to-rung changes rough (EuRoC MH_01's ground truth
   every 10th pose, 20 Hz: value-optimal at 109 ms, order 6 predicted 12, 21, 17, 16 mrad/s
   from 56 to 109 ms; the walk stopped at 56 ms, gyro below 10 Hz 1.20x the best fixed setting
   against the real IMU; now 18 ms, 0.99x. At 200 Hz: V1_02 10.6 -> 1.8 ms, full-band gyro
   1.075 -> 1.018x its best; MH_01 1.8 ms as before).
   Knots finer than the poses where the top of the band reads as noise (the held-out fits
   interpolated noise correlated over neighbouring poses) are read the same way. So is (to 50
   Hz) a rotation read as noisy beside precise positions (motion-limited, or best fitted under
   :data:`PRECISE_POSITION_CV_POSES` pose spacings) whose value is best fitted at fewer than
   :data:`PRECISE_POSITION_ROTATION_CV_POSES` pose spacings: motion the poses sample too sparsely
   to predict, not noise (``read_as_noise`` keeps the first reading). BROAD's hand-held mocap
   every 14th pose (20 Hz), 14 of 15 trials: 43-412 -> 17-20 ms, gyro below 10 Hz 1.14-6.3x ->
   1.00-1.08x the best fixed setting against the real IMU; EuRoC MH_01's ground truth every 10th
   pose as TUM text: 136 -> 18 ms, 2.27 -> 0.99x; OpenVINS' 20 Hz V1_01, udel_gore, udel_arl and
   10 Hz udel_garage: 35-168 -> 18-35 ms. Rotation noise under precise positions stays noise.
5. The rotation spacing never exceeds the time in which the input turns by 135 degrees
   (:func:`max_rotation_spacing`): further apart, neighbouring control rotations near the
   opposite turn. Fast smooth rotation is best close to it (the flips scene, 17 rad/s, AR(1)
   or upsampled noise: 70-80 ms, 70-80 degrees; a 60-degree limit held it at 55 ms, gyro 1.33x
   the best fixed setting, now 0.88-1.14x); so is slow steady turning (screw scene, 0.65
   rad/s: a 90-degree limit held it at 2.4 s, gyro 1.11-1.28x the fixed fit at 2.56 s, now
   0.77-0.87x at 3.5 s). The control rotations beyond the data extrapolate the turn; the
   fit's prior on them keeps Gauss-Newton converging (``END_TURN_SIGMA_RAD``).
6. **The rotation grid's phase** (:mod:`.phase`): shifted by quarters of the spacing, and one
   segment more or less, the grid whose fit leaves the least residual (``knot_phase``).

Cost: per (order, spacing) one pass over the poses for the normal equations of all folds,
banded Cholesky solves of the control-point size and one pass for the predictions, each one
kernel call (:mod:`splineimu._kernels.cv`, compiled per order, work arrays reused); about 60
cross-validated and 35 ladder fits per choice. The grid is scored coarse to fine and stops
before its finest spacings (the costliest fits, more control points than poses) once two in a
row score worse than their coarser neighbour and 3x the best. Inputs longer than
:data:`MAX_CV_POSES` are cross-validated on evenly spread windows (the spacing is a local
property), so the choice costs the same for a minute and for an hour; each window spans
:data:`MIN_WINDOW_S` at least, so above 333 Hz the windows hold more poses (10 kHz: 120 000
a window, 30x those at 200 Hz; 20 s of ellipse at 10 kHz, one window: the fit took 3.9 s CPU
against 1.2 s with 0.4 s windows, gyro / accel 1.05x / 1.03x the best fixed setting against
14x / 10x). Measured: benchmarks/bench_knots.py (12k poses, against scipy's interpolation of
the same poses). Going further means fewer fits (candidates from tabulated transfer functions),
which moves the flat cross-validation optima by a grid step.

Where it fails: noise correlated over longer than the motion's own time scale is motion to any
method that sees only the poses (it is kept); noise whose level changes along the recording
(tracking worse during fast motion) is estimated as its average, so the fast parts get too
little smoothing; noise whose spectrum below the cut-off departs from the octave above's trend
is misjudged there, and the ladder reads the difference as bias; a coarser fit's residual that
holds motion is read as noise and smooths more than needed (EuRoC V1_02 200 Hz position 41 ms,
accel lp10 1.06x the best; BROAD 11 position: motion at 10-13 Hz, the surrogate 1.25-1.6x the
real noise from 4 to 14 Hz); the bias estimate (the change from the rung below) lags the true
bias once the fit cuts into the motion, which only the spacing limits contain; a trajectory
whose character changes (rest, then fast motion) gets one spacing per quantity for the whole of
it; smooth input sampled so sparsely that its top octave holds neither noise nor motion is
taken as noise-limited.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from ..errors import SplineImuError
from .crossval import _STEP, _correlation_lag, _search, _windows
from .ladder import _BIAS_UNREAD, _LADDER, _between_rungs, _extrapolate_bias, _ladder_errors, _walk_ladder
from .phase import choose_phase
from .signals import MAX_CONTROL_TURN_RAD, anchor_block, max_rotation_spacing, rotation_increments
from .surrogate import motion_limited, noise_surrogates, noise_under_motion, rounding_only
from .zones import end_bias2, find_gaps, gap_predictions

ORDERS = (4, 5, 6)
#: Pose noise whose spectrum over the octave above the cut-off is flatter than f^WHITE_SLOPE
#: counts as white; the gyro's bias estimate (the change from the rung below) is then multiplied
#: by WHITE_BIAS_LAG (method, step 3).
WHITE_SLOPE = -1.0
WHITE_BIAS_LAG = 2.0
#: White noise drawn flat (method, step 2) has its gyro bias^2 estimate multiplied by this
#: instead, and of its rotation rungs of the best order predicting within WHITE_TIE of the best
#: the coarsest is taken. Against the rotation noise continued with its read slope (the bias
#: doubled), over the analytic scenes' white noise, 10 seeds each: 200 Hz no miss either way
#: (worst 1.14 -> 1.08x the best fixed setting), 100 Hz 6 -> 4 cases above the bar, 0.3x / 0.5x
#: the noise 1 -> 0 / 3 -> 0, 0.5x at 100 Hz 5 -> 2, 2x 2 -> 1 (benchmarks/results/scene_sweep.md;
#: with the fit's check of the SO3 spline's own bias on the choice's rivals, fit.SO3_EXCESS_RIVALS,
#: without which the lecture ellipse at 1 kHz went 1.0 -> 1.34-1.45x on 2 of 6 seeds). 1.0 gave
#: 4 six-position misses at 200 Hz (1.21-1.28x), 1.2 two; without the tie (or with it across
#: orders: ellipse at 2x, k5 and k6 within 1%, 1.28x) the fast hand-held held-out motion went
#: 0.97 -> 1.157x.
FLAT_WHITE_BIAS_LAG = 1.4
WHITE_TIE = 0.01
#: How much better (relatively) a lower order must score in the first cross-validation pass.
_ORDER_PREFERENCE = 0.02
#: The position's walk toward coarser spacings stops here: control points at least 20 per
#: second keep motion up to 10 Hz, the band the synthesized IMU must reproduce (the walk trusts
#: a bias estimate that lags the true bias once the spacing cuts into the motion). The
#: rotation's gyro prediction holds (0.8-1.35x the real noise on BROAD, 0.9-1.05x on analytic
#: scenes): it walks on to its turn limit (step 5). A position whose value-optimal spacing is
#: already beyond this walks on too (drone and car poses at 10 Hz interpolated to 20 Hz: the
#: ladder ended at 1.56x the value-optimal 135 ms with the error still falling, accel 3.7-4.8x
#: and 1.6-1.7x the best fixed setting, predicted 1.0x; now 0.73-0.91x and 0.48-0.75x).
WALK_MAX_S = 0.05
#: Motion-limited input whose held-out error grows by less than this with blocks twice as long
#: may hold noise in its top octave (method, step 4). Measured at 20 Hz: noise 1.5-2.8x; noise
#: and motion mixed 5.9-9.2x (0.2 mm / 0.02 deg on fast hand-held motion: predicted 0.2x the
#: measured gyro and 0.13x the accel, told nothing below 5x); exact poses 24-150x, but 9.3x for
#: hand-held rotation near the Nyquist frequency, whose prediction is 0.25x the measured (told
#: too). EuRoC's and OpenVINS' 200 Hz and 20 Hz ground truth: the same warnings with 5 or 12.
NOISE_GROWTH = 12.0
#: The least first cross-validation block [poses] where the top octave holds noise, and the
#: most time it may span [s]: noise drawn at half the rate and interpolated is partly predicted
#: from a neighbour left in by 2-pose blocks (0.1 s at 20 Hz), which then interpolated it (slow
#: motion at 20 Hz: gyro 13-21x, accel 59-80x the best fixed setting). Not longer (exact poses
#: at 10 Hz, aliased motion read as noise: fast hand-held gyro 0.41 -> 1.9 rad/s), nor where the
#: top octave is rounding (exact ellipse positions at 20 Hz: ends' accel 0.2 -> 11 m/s^2).
MIN_FIRST_BLOCK = 4
MIN_FIRST_BLOCK_S = 0.2
#: Standard gravity [m/s^2], for the accelerometer error an orientation error causes.
GRAVITY_M_S2 = 9.81
#: The coarsest knot spacing tried (and a quarter of the span): slow or still motion (a rate
#: table, a circle at 0.4 rad/s, a parked sensor) is best fitted that smooth; the circle scene's
#: best fixed spacing is 2.5 s or more. The grid's coarse steps are laid out up to _GRID_TOP_S
#: and continued beyond it in the same steps.
MAX_SPACING_S = 10.0
_GRID_TOP_S = 2.0
#: A rotation held out at the value-optimal spacing to better than PRECISE_ROTATION_RAD (RMS),
#: best fitted at fewer than PRECISE_CV_POSES pose spacings, whose residual over the octave above
#: that fit's cut-off falls steeper than f^PRECISE_SLOPE, is read as motion-limited (method, step
#: 4): an estimator's output, not a measurement. EuRoC's ground truth (Vicon or a laser tracker
#: fused with the IMU) holds 5-7e-5 rad there, falling as f^-2.5 to f^-5.8, best at 1.7-2.6 pose
#: spacings, and its rotation's fine detail is the vehicle's vibration, coherent with its real IMU:
#: MH_01 (200 Hz, against its ADIS16448) at the noise reading's 13 ms knots gave a full-band gyro
#: error 1.21x the best fixed setting (3.5 ms) and lp10 1.03x scipy; read as motion (1.8 ms),
#: 1.06x and 1.00x. Mocap orientation is noisier (BROAD 2.3e-4-1.9e-3 rad, TUM-VI 5e-3, TUM RGB-D
#: 1.7e-3 and more); white noise reads flat (f^-0.5 to f^1) and AR(1) noise f^-1.2 to f^-1.6
#: (flips scene with 0.002 deg AR(1) noise: best at 2.7 pose spacings, 2.1x the best fixed
#: setting if read as motion).
PRECISE_ROTATION_RAD = 1e-4
PRECISE_CV_POSES = 3.0
PRECISE_SLOPE = -2.0
#: Positions best fitted (value-optimal) at fewer than this many pose spacings, or motion-limited,
#: are precise for the motion they hold: a rotation read as noisy beside them is read again as
#: motion where its own value-optimal spacing is under PRECISE_POSITION_ROTATION_CV_POSES (step 4).
#: BROAD's mocap and EuRoC MH_01's ground truth at 20 Hz: 0.9-1.7 pose spacings where the positions
#: read as noisy; sums of sines at 20 Hz, 0.2-1 mm white or AR(1) noise: 3.3-21 (upsampled: 0.9).
PRECISE_POSITION_CV_POSES = 2.0
#: BROAD's hand-held rotation at 20-41 Hz: 0.9-3.4 pose spacings (a bound of 3 left 10 every 14th pose and 15
#: every 10th noise: gyro 5.7x, 11x the best fixed setting; now 1.04x, 1.07x); noise under precise positions 7-16.
PRECISE_POSITION_ROTATION_CV_POSES = 4.0
#: ... up to this pose rate (Hz; its cases are 10-41 Hz): faster poses sample hand-held turns densely
#: (BROAD 04 at 286 Hz, fast hand-held AR(1) at 100 Hz: read as motion, gyro 1.45x and 2.8x best).
PRECISE_POSITION_MAX_RATE_HZ = 50.0


def _best(table, orders):
    best = {k: min((v, dt) for (kk, dt), v in table.items() if kk == k) for k in orders}
    k_best = min(orders, key=lambda k: best[k][0] * (1.0 - _ORDER_PREFERENCE * (k - min(orders))))
    return k_best, best[k_best][1], best


def choose_signal(t, X, w, r, orders=ORDERS, dt_fixed=None, dt_max=np.inf, increments=False, as_motion=False,
                  grid_phase=True):
    """Order and spacing (at most ``dt_max``) for an ordinary B-spline fit of signal X (N, 3)
    (or, with ``increments``, of the sums of X (N - 1, 3)) whose r-th derivative matters;
    returns a dict (see :func:`choose_knot_spacing`). ``as_motion``: X is known to hold motion to
    the top of its band (an estimator's output): read as motion-limited input, in blocks of one pose.
    ``grid_phase``: for the rotation (r = 1), where its grid sits against the motion is chosen too
    (step 6); otherwise it starts on the first pose."""
    orders = tuple(int(k) for k in orders)
    windows = _windows(t, X, w, increments)
    h = float(np.median(np.diff(t)))
    span = min(wd.t[-1] - wd.t[0] for wd in windows)
    lo = 0.7 * h
    hi = max(min(span / 4.0, MAX_SPACING_S, dt_max), lo * 1.01)
    if dt_fixed is not None:  # a given spacing is kept (only the order is chosen): the range takes it in
        if span / float(dt_fixed) < 2:
            raise SplineImuError(f"a knot spacing of {float(dt_fixed):g} s leaves fewer than 2 spacings over the "
                                 f"{span:g} s the order is chosen on: give the order too")
        lo, hi = min(lo, float(dt_fixed)), max(hi, float(dt_fixed))
    if dt_fixed is None:
        # steps of about _STEP up to _GRID_TOP_S, continued in the same steps beyond it
        top = max(min(hi, _GRID_TOP_S), lo * 1.01)
        grid = np.geomspace(lo, top, max(int(np.ceil(np.log(top / lo) / np.log(_STEP))) + 1, 2))
        if hi > top:
            step = grid[1] / grid[0]
            grid = np.r_[grid, np.geomspace(top, hi, int(np.ceil(np.log(hi / top) / np.log(step))) + 1)[1:]]
    else:
        grid = np.array([float(dt_fixed)])
    # 1. cross-validation with 0.1 s blocks (or MIN_FIRST_BLOCK), then with blocks of 3 noise
    # correlation times
    limited = dt_fixed is None and (as_motion or all(motion_limited(wd.X) for wd in windows))
    estimate = as_motion  # an estimator's output (declared, or found precise below)

    @cache
    def noisy():  # the top of the band holds noise: neither motion nor rounding (exact input)
        return not limited and not all(rounding_only(wd.X) for wd in windows)

    block = first_block = max(int(round(0.1 / h)), 1)
    if (dt_fixed is None and block < MIN_FIRST_BLOCK and MIN_FIRST_BLOCK * h <= MIN_FIRST_BLOCK_S * (1 + 1e-9)
            and noisy()):
        block = first_block = MIN_FIRST_BLOCK
    k_first = 4 if 4 in orders else orders[0]
    table = _search(windows, (k_first,), grid, block, lo, hi)
    k0, dt0, _ = _best(table, (k_first,))
    # (the residual's correlation is the noise's, unless all of it is motion)
    lag = 1 if as_motion else _correlation_lag(np.vstack([wd.residual(k0, dt0) for wd in windows]))
    # the second pass looks within 4x of the first choice (leaks of correlated noise through
    # 0.1 s blocks move it by less)
    near = grid[(grid >= dt0 / 4.0) & (grid <= dt0 * 4.0)] if grid.size > 1 else grid
    if (1 if lag <= 1 else 3 * lag) != block:
        block = 1 if lag <= 1 else 3 * lag
        table = _search(windows, orders, near, block, lo, hi)
    else:
        table.update(_search(windows, tuple(k for k in orders if k != k_first), near, block, lo, hi))
    # 2. per order, the derivative's error on a ladder around the value-optimal spacing, with a
    # surrogate of the pose noise (spectrum from the residual) propagated through the same fits
    k_cv, dt_cvb = _best(table, orders)[:2]
    # the derivative's noise error is the noise spectrum times f^(2r): where that spectrum rises
    # toward low frequency the error sits below the cut-off, so the spectrum is read from the
    # coarser value-optimal fit and followed below (not for motion-limited input, whose
    # residual is motion)
    follow = not limited
    k_s, dt_s = (k0, dt0) if follow and dt0 > dt_cvb else (k_cv, dt_cvb)
    want_flat = r == 1 and follow  # the rotation's value error (below) takes the flat continuation

    def precise(slope):
        # a rotation more precise than measured ones, whose residual is no white or AR(1) noise
        # and whose value-optimal fit nearly interpolates: motion to the top of the band
        return (r == 1 and dt_fixed is None and follow and dt_cvb < PRECISE_CV_POSES * h and slope < PRECISE_SLOPE
                and table[(k_cv, dt_cvb)] < PRECISE_ROTATION_RAD**2 and noisy())

    def white(slope):  # uncorrelated: drawn flat where flat above twice the cut-off (noise_surrogates;
        # steeper than f^-1 above the cut-off, six-position at 100 Hz read knots of 373 ms, gyro
        # 1.6-1.7x the best fixed setting on 4 of 10 seeds)
        return r == 1 and follow and lag <= 1 and not precise(slope)

    noises, flat, slope, flat_white = noise_surrogates(windows, k_s, dt_s, follow=follow, also_flat=want_flat,
                                                       white=white)
    if precise(slope):
        limited = estimate = True  # (an estimator's output: its error is no white noise)
        noises, flat, slope, flat_white = noise_surrogates(windows, k_cv, dt_cvb, follow=False, also_flat=False)
    # the gyro's bias estimate lags; for white noise it is corrected (WHITE_BIAS_LAG)
    white_noise = r == 1 and slope > WHITE_SLOPE
    bias_lag = (FLAT_WHITE_BIAS_LAG if flat_white else WHITE_BIAS_LAG) if white_noise else 1.0
    # rungs reading less bias than noise take a floor from the rungs above (step 3): the gyro's under
    # white noise, the position's under uncorrelated noise
    floor_bias = white_noise or (r == 2 and follow and lag <= 1 and slope > WHITE_SLOPE)
    if limited:
        # the residual is mostly motion the fit missed, not noise: look at finer spacings
        noises = [0.1 * nz for nz in noises]
    rows = []
    cands = []  # (predicted error, order, spacing, noise variance, end profiles, value-optimal spacing)

    def consider(k, dts, var, bias2, ends, dt_cv):
        # candidates (order k, spacings dts with their errors) into rows and cands
        pred = np.sqrt(var + bias2)
        for j, dt in enumerate(dts):
            rows.append({"order": k, "knot_spacing_s": float(dt), "predicted_rms": float(pred[j]),
                         "predicted_noise_rms": float(np.sqrt(var[j])), "cv_knot_spacing_s": float(dt_cv)})
            cands.append((float(pred[j]), k, float(dt), float(var[j]), ends[j], float(dt_cv)))

    def least():  # the first candidate of the least predicted error (None: none)
        best = None
        for c in cands:
            if best is None or c[0] < best[0]:
                best = c
        return best

    # the position's walk stops at WALK_MAX_S (its bias estimate lags) unless a value-optimal
    # spacing (of any order: the flips scene, AR(1) noise, 30 s: order 4's 53 ms, order 6's 34 ms,
    # order 6 held below the cap, order 4 at 104 ms chosen, accel 1.57x the best fixed setting,
    # order 6 at 113 ms) is beyond it; the rotation's goes on
    cv_spacings = [min((v, dt) for (kk, dt), v in table.items() if kk == k)[1] for k in orders]
    walk_cap = WALK_MAX_S if r == 2 and max(cv_spacings) < WALK_MAX_S else np.inf
    ladders = {}
    unread = set()  # (order, spacing) of the rungs that read no bias (for _between_rungs)
    for k, dt_cv in zip(orders, cv_spacings):
        # motion-limited input is walked only toward finer spacings, and may go below the grid
        # (toward interpolation); the rung below the first one kept is its reference
        lo_k = lo * (0.5 if limited else 1.0)
        if dt_fixed is None and limited and estimate and r == 1:
            # an estimator's rotation: every rung down to the reference below lo_k, each read
            # against that finest rung (its detail is motion, which the finest follows best;
            # method, step 4)
            below = int(np.floor(np.log(dt_cv / lo_k) / np.log(_LADDER) + 1e-9)) + 1
            ladder = dt_cv * _LADDER ** np.arange(-below, 1)
            var, bias2, ends = _ladder_errors(windows, k, ladder, noises, r, bias_lag, finest=True)
        else:
            steps = np.arange(-1, 1) if dt_fixed is not None else (np.arange(-4, 1) if limited else np.arange(-2, 3))
            ladder = dt_cv * _LADDER ** steps
            # no rung beyond the walk's cap either, unless the value-optimal spacing is beyond it
            hi_k = min(hi, walk_cap) if dt_fixed is None else hi
            ok = (ladder >= lo_k * 0.99) & (ladder <= hi_k * (1.0 + 1e-9))
            first = max(int(np.argmax(ok)) - 1, 0)
            ladder = np.r_[ladder[first], ladder[first + 1:][ok[first + 1:]]]
            if dt_fixed is None:
                top = ladder[-1] if limited else max(ladder[-1], hi_k)
                ladder, var, bias2, ends = _walk_ladder(windows, k, ladder, noises, r, lo_k, top, bias_lag)
            else:
                var, bias2, ends = _ladder_errors(windows, k, ladder, noises, r, bias_lag)
        ladders[k] = ladder
        unread.update((k, float(dt)) for dt, v, b in zip(ladder[1:], var, bias2) if b <= v * _BIAS_UNREAD)
        if floor_bias:  # (coloured noise's estimate holds the surrogate's misfit too)
            bias2 = _extrapolate_bias(ladder[1:], var, bias2, k - r)
        consider(k, ladder[1:], var, bias2, ends, dt_cv)
    best = least()
    if best is None:
        raise SplineImuError("no knot spacing could be evaluated (too few poses for the orders?)")
    if dt_fixed is None and r == 2:
        # half a rung either side of the best, within the rungs tried (each against its own rung
        # below): near a steep rise of the bias the error changes by 20-30% per rung
        k, dt, dt_cv = best[1], best[2], best[5]
        half = dt * _LADDER ** np.array([-1.5, -0.5, 0.5])
        var, bias2, ends = _ladder_errors(windows, k, half, noises, r, bias_lag)
        inside = (half[1:] >= ladders[k][1] * 0.999) & (half[1:] <= ladders[k][-1] * 1.001)
        consider(k, half[1:][inside], var[inside], bias2[inside], [e for e, i in zip(ends, inside) if i], dt_cv)
        best = least()
    if flat_white and dt_fixed is None:  # of rungs that tie, the coarsest (FLAT_WHITE_BIAS_LAG)
        best = max((c for c in cands if c[1] == best[1] and c[0] <= best[0] * (1.0 + WHITE_TIE)), key=lambda c: c[2])
    if dt_fixed is None and r == 1 and (best[1], best[2]) in unread:
        best = _between_rungs(best, ladders[best[1]], rows, windows, noises, r, bias_lag)
    den = max(sum(wd.n_scored for wd in windows), 1)

    @cache
    def unit():  # unit white noise (the same draw at every call)
        rng = np.random.default_rng(11)
        return [rng.normal(size=wd.X.shape) for wd in windows]

    def held_out(k, dt_cv, blk, noise=None):  # mean squared held-out error of the signal (or of noise)
        noise = noise or [None] * len(windows)
        return sum(wd.score(k, dt_cv, wd.folds(blk), nz)[0] for wd, nz in zip(windows, noise)) / den

    def under_motion(k, dt_cv):
        # the prediction took the top of the band for motion (a tenth of the surrogate). Held-out
        # blocks twice as long tell: motion's error grows steeply with the gap, noise's barely.
        # Where it may be noise: (held-out errors, the noise under the motion's sigma), else None.
        # (interpolated noise is read in blocks as long as the first pass's: shorter ones leave
        # part of each held-out pose's noise in its neighbours)
        b = block if limited else max(block, first_block)
        held = [table[(k, dt_cv)] if b == block else held_out(k, dt_cv, b)] + [held_out(k, dt_cv, m * b)
                                                                              for m in (2, 3)]
        if not 1.0 / 3.0 < held[1] / max(held[0], 1e-300) < NOISE_GROWTH:
            return None
        # the held-out errors at three gap lengths as noise plus motion growing as a power of the
        # gap, the noise part through the leave-out gain of white noise
        gain = held_out(k, dt_cv, b, unit())
        return held, (np.sqrt(noise_under_motion(held, b) / gain) if gain > 0 else 0.0)

    def unit_var(k, dts):  # the derivative's error of unit white noise at spacings dts (increasing)
        return _ladder_errors(windows, k, np.r_[dts[0] / _LADDER, dts], unit(), r)[0]

    # knots finer than the poses where the top octave reads as noise (the held-out fits took
    # interpolated noise for motion: car and drone at 20 Hz, predicted 0.03-0.05x): read alike
    mixed = limited or (dt_fixed is None and best[2] < h and noisy())
    reading = under_motion(best[1], best[5]) if mixed else None
    moved_from = None
    unit_vars = {}  # (order, spacing): unit white noise's derivative error (the re-ranking's)
    if reading is not None and reading[1] > 0 and dt_fixed is None and r == 1 and not estimate:
        # that noise was left out of the candidates' predictions (a tenth of the surrogate): with
        # it added to each, the least is taken again (hand-held motion at 20 Hz, 0.2 mm / 0.02
        # deg: 18 ms rotation knots, gyro 2.6x the best fixed setting, predicted 0.0018 before
        # the noise was added). The rotation only: EuRoC V1_02's vicon2gt position as arrays
        # went from 25 to 44 ms, accel below 10 Hz against its real IMU 1.017 -> 1.034x scipy
        # (fast hand-held positions at 20 Hz gained, 1.2-2.6 -> 0.9-1.8x the best fixed setting)
        # (coarser spacings only: where that noise reads high, motion near the Nyquist frequency
        # leaks into it, and a lower order at the same spacing follows that motion worse; fast
        # hand-held at 20 Hz, k5 -> k4 at 18 ms, gyro 1.71 -> 1.96x the best fixed setting)
        every = [best] + [c for c in cands if c[2] > best[2] * (1.0 + 1e-6)]
        for kk in sorted({c[1] for c in every}):
            dts = np.array(sorted({c[2] for c in every if c[1] == kk}))
            unit_vars.update({(kk, d): float(v) for d, v in zip(dts.tolist(), unit_var(kk, dts))})
        sig2 = reading[1] ** 2
        least_mixed = min(every, key=lambda c: c[0] ** 2 + unit_vars[(c[1], c[2])] * sig2)
        if (least_mixed[1], least_mixed[2]) != (best[1], best[2]):
            moved_from = best[2]
            if (least_mixed[1], least_mixed[5]) != (best[1], best[5]):  # its own held-out errors
                reading = under_motion(least_mixed[1], least_mixed[5]) or reading
            best = least_mixed
    pred, k, dt, var, ends, dt_cv = best
    # the first and last k knot spacings see one-sided data: their noise part on its own, and
    # the motion the one-sided fit misses (measured by truncation, zones.end_bias2)
    zone = k * dt
    (t_a, e_a), (t_b, e_b) = ends[0], ends[-1]
    head = t_a <= t_a[0] + zone
    tail = t_b >= t_b[-1] - zone
    extra = end_bias2(windows, noises, k, dt, r, zone)
    end_rms = float(np.sqrt(max(np.mean(e_a[head]), np.mean(e_b[tail])) + pred**2 - var + extra))
    gaps = gap_predictions(windows, noises, k, dt, r, zone, find_gaps(t, w), pred)
    out = {
        "order": k, "knot_spacing_s": dt, "cv_knot_spacing_s": dt_cv,
        "block_poses": int(block), "noise_correlation_poses": int(lag), "motion_limited": bool(limited),
        "noise_slope": float(slope) if np.isfinite(slope) else None, "bias_correction": bias_lag,
        "predicted_rms": pred, "predicted_noise_rms": float(np.sqrt(var)),
        "cv_rms": float(np.sqrt(table[(k, dt_cv)])), "end_zone_s": float(zone), "end_predicted_rms": end_rms,
        "gaps": [{"t_start_s": a, "t_end_s": b, "predicted_rms": e} for a, b, e in gaps],
        "candidates": rows,
    }
    if r == 1:  # where the grid sits against the turns (step 6)
        phase = (0.0, dt) if dt_fixed or not grid_phase else choose_phase(windows, noises, k, dt, t[0], t[-1])
        out["knot_phase"], out["knot_spacing_s"] = phase
        # the rotation's own (value) error at the choice: it tilts gravity into the accelerometer.
        # The value weighs the noise far below the cut-off alike, where the continuation's slope
        # (read where motion the fit misses adds to the residual) overstated white noise 3x (rate
        # table, six-position scenes); it is continued flat here
        v0, b0, _ = _ladder_errors(windows, k, np.array([dt / _LADDER, dt]), noises if flat is None else flat, 0)
        out["value_rms"] = float(np.sqrt(v0[0] + b0[0]))
    if moved_from is not None:
        out["moved_by_noise_under_motion_from_s"] = float(moved_from)
    if reading is not None:
        held, sigma = reading
        # the error at the choice were the held-out error white noise (an upper bound where noise
        # and motion mix), and the noise under the motion's error added to the prediction; the
        # fits are linear: a noise of standard deviation s gives s^2 times unit noise's error
        vu = unit_vars[(k, dt)] if (k, dt) in unit_vars else unit_var(k, np.array([dt]))[0]
        out["predicted_rms_if_noise"] = float(np.sqrt(vu * held[0] / 3.0))
        for key in ("predicted_rms", "end_predicted_rms", "predicted_noise_rms"):
            out[key] = float(np.sqrt(out[key] ** 2 + vu * sigma**2))
        out["noise_under_motion"] = float(sigma)
    return out


def choose_knot_spacing(t, P, R, w=None, rotation_order="auto", position_order="auto",
                        rotation_dt=None, position_dt=None, max_turn_rad=MAX_CONTROL_TURN_RAD,
                        estimated_rotation=None, grid_phase=True):
    """Choose order and knot spacing of rotation and position from the poses.

    Parameters
    ----------
    t : (N,) seconds, increasing
    P : (N, 3) positions
    R : (N, 3, 3) rotations
    w : (N,) weights, optional (0 = left out)
    rotation_order, position_order : int or "auto"
    rotation_dt, position_dt : float, optional
        Fixed spacings (only the order, if "auto", is then chosen).
    max_turn_rad : float
        The most the input may turn in one rotation knot spacing (step 5).
    estimated_rotation : bool or None
        True: the rotation is an estimator's output that fused an IMU, its detail is motion to
        the top of the band (``as_motion`` of :func:`choose_signal`). False: measurements, read
        as such. None (not said): measurements, whose top octave is read again as motion where
        the positions' is and the rotation's value is best fitted nearly through its poses
        (step 4; ``read_as_noise`` in the result then keeps the first reading).
    grid_phase : bool
        Choose where the rotation's grid sits against the motion (step 6; ``knot_phase``, the
        spacing before the first pose its grid starts). False: on the first pose, as an se3
        spline's one grid of both parts does (12 fits fewer).

    Returns
    -------
    dict with ``rotation`` and ``position`` (each: ``order``, ``knot_spacing_s``,
    ``predicted_rms`` of the gyro [rad/s] or accel [m/s^2], the cross-validation table),
    ``predicted_gyro_rms_rad_s``, ``predicted_accel_rms_m_s2``, ``method``.
    """
    w = np.ones(t.size) if w is None else np.asarray(w, dtype=np.float64)
    ro = ORDERS if rotation_order == "auto" else (int(rotation_order),)
    po = ORDERS if position_order == "auto" else (int(position_order),)
    inc = rotation_increments(R)
    block = anchor_block(t, inc)
    X, turn = rotation_increments(R, block, inc), max_rotation_spacing(t, R, max_turn_rad)
    rot = choose_signal(t, X, w, 1, ro, rotation_dt, turn, increments=True, as_motion=bool(estimated_rotation),
                        grid_phase=grid_phase)
    rot["estimated"] = bool(estimated_rotation)
    pos = choose_signal(t, np.ascontiguousarray(P), w, 2, po, position_dt)
    h = float(np.median(np.diff(t)))
    if (rotation_dt is None and estimated_rotation is None and not rot["motion_limited"]
            and np.count_nonzero(w > 0) >= 64 and h * PRECISE_POSITION_MAX_RATE_HZ > 1.0 - 1e-6
            and (pos["motion_limited"] or pos["cv_knot_spacing_s"] < PRECISE_POSITION_CV_POSES * h)
            and rot["cv_knot_spacing_s"] < PRECISE_POSITION_ROTATION_CV_POSES * h
            and not all(rounding_only(wd.X) for wd in _windows(t, X, w, increments=True))):
        # the positions are precise for their motion (motion-limited, or best fitted nearly
        # through the poses), and so is the rotation's value: its top octave is motion too,
        # unless it is rounding (exact poses; method, step 4)
        read = {key: rot[key] for key in ("order", "knot_spacing_s", "predicted_rms")}
        rot = choose_signal(t, X, w, 1, ro, None, turn, increments=True, as_motion=True, grid_phase=grid_phase)
        rot["estimated"], rot["read_as_noise"] = False, read
    rot["anchor_poses"] = block  # (the SO3 bias check develops its rotations alike)
    # an orientation error dtheta (isotropic) turns the specific force f by f x dtheta: RMS
    # sqrt(2/3) |f| |dtheta|, with |f| ~ g (slow motion, where it is the accelerometer's main error)
    tilt = float(np.sqrt(2.0 / 3.0) * GRAVITY_M_S2 * rot["value_rms"])
    return {
        "rotation": rot, "position": pos,
        "predicted_gyro_rms_rad_s": rot["predicted_rms"],
        "predicted_accel_rms_m_s2": float(np.hypot(pos["predicted_rms"], tilt)),
        "accel_from_orientation_rms_m_s2": tilt,
        "position_noise_m": pos["cv_rms"] / np.sqrt(3.0),
        "angle_noise_rad": rot["cv_rms"] / np.sqrt(3.0),
        "method": "blocked cross-validation on held-out poses (rotation and position separately)",
    }
