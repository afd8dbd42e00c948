r"""Six-position accelerometer and rate-table gyro calibration (bias, scale, misalignment).

The sensor model (:mod:`splineimu.imu.noise`, DESIGN.md section 3) is, for either sensor,

.. math::  y_m = K x + b + n,\qquad K = M S,

with the true quantity ``x`` (specific force or body rate), the 3x3 scale-misalignment matrix
``K`` (misalignment ``M`` after scale ``S = I + diag(s)``), the bias ``b`` and white noise ``n``:
twelve unknowns per sensor. A calibration recording holds *steady phases* (at rest, or at a
constant table rate) whose reference ``x`` is known up to the orientation of the sensor:

- six-position test (:func:`calibrate_accel`): at rest with each axis up and down,
  ``x = g u`` with ``u`` the gravity direction in the sensor, nominally ``+-e_i``;
- rate table (:func:`calibrate_gyro`): each axis along the (vertical) table axis, spun at
  ``+rate`` and ``-rate`` (and at rest), ``x = +-rate u``, ``u`` nominally ``e_i``.

Procedure
---------
1. **Segmentation** (:func:`find_steady_phases`), from the data alone. For every channel
   ``c`` (the three axes of the calibrated sensor and, when given, of the other one) the
   moving standard deviation ``s_c(k)`` over a centred window of ``window_s`` seconds is
   compared with the channel's noise level ``sigma_c``: the 25th percentile of ``s_c`` over
   the recording divided by its value for white noise, ``sqrt(chi2_{w-1}(0.25) / w)`` (a
   robust white-noise level as long as a good part of the recording is steady). A sample is
   steady when ``s_c(k) <= threshold * sigma_c + floor_c`` on every channel (default
   ``threshold = 1.5``; a window of pure white noise has ``s / sigma`` within a few percent
   of 1, so this flags a window once its signal changes by about one noise standard
   deviation), and the means of the window's two halves must agree within
   ``drift_threshold = 5`` standard deviations of their difference (a slow ramp in heavy
   noise shows there first). ``floor_c``, added to both limits, is ``1e-9 max(1, median
   |y_c|)`` or half the smallest step of quantized data, whichever is larger.
   Runs of steady samples are shrunk by ``margin_s`` (default: two windows, 1 s) at each end
   that borders motion (not at the ends of the recording), so that the slow start and end of
   a move, whose signal is still below the noise, stays out of the averages (with one window,
   consumer-grade noise of 0.015 rad/s/sqrt(Hz) let ramps bias some phase means by up to 0.6
   of their standard deviation; with two, by less than 0.01); runs shorter than
   ``min_dwell_s`` are dropped.
2. **Averaging**: each phase gives its mean ``y_p`` and, per axis, the variance of that mean,
   ``sigma_p^2 / n_p`` with ``sigma_p`` the sample standard deviation in the phase (or
   ``noise_density / sqrt(dt)`` when a white-noise density is given).
3. **Reference assignment** from the measured direction: the dominant axis ``i`` and sign of
   ``y_p`` give the nominal ``u_p = +-e_i`` (within ``max_axis_angle_deg``, default 25
   degrees, and a magnitude within [0.8, 1.25] of ``g`` or of a table rate; gyro phases
   below half the smallest rate are at rest, ``x = 0``). Phases that fit nothing are
   reported and left out.
4. **Least squares** for ``vec(K)`` and ``b``: ``y_p = a_p K u_p + b`` (``a_p = g`` or
   ``+-rate`` or 0), weighted by the inverse variances of step 2 (the rows of ``K`` and
   ``b`` decouple; the system must have rank 12, else the error lists the references
   found). The predicted covariance is the inverse of the weighted normal matrix. With the
   reference exact and no drift, this is the classical method (``method="nominal"``).
5. **Bias drift** (:mod:`~splineimu.calibration.drift`): the bias wanders as a random walk
   over the whole recording, so the phase means also differ by the drift between them; its
   covariance over the timeline of the phases used joins the white-noise variances (then the
   least squares is generalized, and ``b`` is the bias averaged over the samples of the phases
   used). The random-walk density is given (``random_walk``) or estimated from the data by
   restricted maximum likelihood. :attr:`SensorCalibration.drift_share` says how much of the
   predicted variance is drift; :attr:`SensorCalibration.drift_dominated` flags a result where
   it outweighs the white noise. The g-sensitivity of the gyro is not modelled.

Orientation error
-----------------
If a position is tilted by a small angle ``theta`` (a vector perpendicular to the nominal
``u``, components of standard deviation ``sigma``), the true reference is
``a (u + theta x u)`` and the nominal method reads ``a K (theta x u)`` as part of ``K`` and
``b``:

- six-position: a tilt of the ``+-e_i`` positions moves the other two axes' readings by
  ``g theta``, so the misalignment entries ``K_ji`` (j != i) are off by
  ``(theta_up - theta_down) / 2`` (first order; RMS ``sigma / sqrt(2)`` = 0.025 for tilt
  components of ``sigma`` = 2 degrees), the biases by about ``g sigma / 3`` (0.11 m/s^2: the
  bias of axis ``j`` is the average over all six positions, four of which are tilted across
  ``j``), and the scale factors by ``-|theta|^2 / 2`` (second order: on average
  ``-sigma^2`` = -1.2e-3);
- rate table: a tilted mount spins the sensor about ``u_i = e_i + theta x e_i``, so column
  ``i`` of ``K`` absorbs ``K (theta x e_i)``: misalignment off by ``theta`` (RMS ``sigma``),
  scale by ``-|theta|^2 / 2``; the biases are unaffected (the +rate and -rate phases cancel).

The misalignment error is fundamental: a common rotation of all positions is
indistinguishable from a rotation of ``K`` (``K u = (K Q)(Q^T u)``), and six positions
with fully unknown orientations leave 12 + 12 unknowns for 18 equations, so the norm
constraint ``|K^-1 (y - b)| = g`` alone cannot identify the 12 parameters either (it gives 6
equations for 9 identifiable parameters; multi-position methods use 9 or more positions).
What *can* be done with six positions is to treat the tilts as random, ``theta ~ N(0,
tilt_sigma^2 I_2)`` per position (per mount on the rate table), and marginalize them
(``tilt_sigma_deg`` > 0, ``method="tilt"``): with ``u = Exp(theta) u0``,
``E[y_p] = a_p c K u0_p + b`` with ``c = E[cos|theta|] ~ 1 - tilt_sigma^2``, and the tilt
adds the covariance ``a_p a_q K Sigma_u K^T`` between the phases of one position / mount,
``Sigma_u = Var(cos|theta|) u0 u0^T + E[sin^2|theta|]/2 (I - u0 u0^T)`` (about
``sigma^4`` along ``u0`` and ``sigma^2`` across it; :func:`tilt_moments`). ``K`` and ``b``
then follow by generalized least squares with that covariance (iterated, because it depends
on ``K``; only the estimated scale factors enter it, since the off-diagonal part of the
estimate carries the tilts themselves), the predicted covariance is the GLS one, and each
position's tilt is reported as its best linear prediction. This

- weights the accelerometer bias of axis ``j`` towards the positions where ``j`` is
  vertical, where a tilt acts only at second order, and removes the mean ``-sigma^2`` scale
  error (``c``);
- cannot resolve misalignment better than the tilts (the estimate stays the nominal one) but
  *states* that uncertainty: the predicted standard deviations of ``K_ji`` grow to about
  ``tilt_sigma / sqrt(2)`` (six-position) or ``tilt_sigma`` (rate table), so the 2-sigma
  intervals keep their coverage.

Measured over 100 seeds (``tests/test_calibration.py``; EuRoC ADIS16448 white noise, 10 s
phases at 200 Hz, tilt components of 2 degrees): six-position, nominal method: RMS errors
0.11 m/s^2 (bias), 0.024 (misalignment), 1.6e-3 (scale, mean -1.2e-3), 2-sigma coverage 2%
with white noise alone (27% once the drift estimate takes up part of the tilts' scatter);
tilt model: 0.0076 m/s^2, 0.024, 8.7e-4 (no mean error), coverage 96%. Rate table, nominal:
misalignment 0.034, scale 1.6e-3 (mean -1.1e-3), bias unaffected (2e-5 rad/s), coverage 26%;
tilt model: 0.034, 1.1e-3, coverage 97%. Without tilt both methods are the same; 2-sigma
coverage 96.7% (accelerometer) and 95.3% (gyro) over 100 seeds (95.6% and 95.3% without the
drift estimate, whose noise slightly widens the stated std).

With bias drift (``tests/test_calibration_drift.py``; the random walks of the presets):
EuRoC ADIS16448 (accel 3e-3 m/s^3/sqrt(Hz)) six-position 2-sigma coverage 26% with white noise
only, 95.8% with the drift model over 100 seeds (rate table 94.8%); TUM-VI BMI160 94.4% /
94.0% and the lecture's model 95.8% / 94.2% over 40 seeds.

Results
-------
:class:`AccelCalibration` / :class:`GyroCalibration` hold ``K``, ``b``, their 12x12
covariance, the derived scale factors ``s = diag(K) - 1`` and misalignment ``M = K S^-1``
(unit diagonal, the sensor-model convention ``K = M S``) with their standard deviations, the
phases used and the fit statistics. :meth:`SensorCalibration.to_config_dict` gives the
sensor-model keys (``<sensor>_scale``, ``<sensor>_misalignment``, ``<sensor>_bias``) that
:func:`splineimu.imu.config.load_imu_config` reads, and :func:`apply_calibration` corrects
data: ``x = K^-1 (y_m - b)``.

Modules
-------
:mod:`~splineimu.calibration.segmentation` (step 1), :mod:`~splineimu.calibration.estimate`
(steps 2, 3 and the entry points), :mod:`~splineimu.calibration.solve` (step 4 and the tilt
moments), :mod:`~splineimu.calibration.result` (results), :mod:`~splineimu.calibration.correct`
(using a calibration), :mod:`~splineimu.calibration.files` (the ``calibration.yaml`` mapping) and
:mod:`~splineimu.calibration.options`. Reading and writing ``calibration.yaml`` is
:mod:`splineimu.io.calibration_yaml`; :func:`splineimu.api.calibrate_file` is the job behind
``splineimu calibrate``.
"""

from __future__ import annotations

from .correct import apply_calibration, intrinsics_from_config
from .estimate import MAGNITUDE_RATIO_RANGE, calibrate_accel, calibrate_gyro
from .files import calibration_yaml_dict
from .options import CalibrationOptions
from .result import (
    PARAMETER_NAMES,
    AccelCalibration,
    GyroCalibration,
    SensorCalibration,
    SteadyPhase,
    split_scale_misalignment,
)
from .segmentation import find_steady_phases
from .solve import tilt_moments

__all__ = [
    "SteadyPhase", "SensorCalibration", "AccelCalibration", "GyroCalibration", "CalibrationOptions",
    "find_steady_phases", "calibrate_accel", "calibrate_gyro",
    "apply_calibration", "intrinsics_from_config", "split_scale_misalignment", "calibration_yaml_dict",
    "tilt_moments", "PARAMETER_NAMES",
    "MAGNITUDE_RATIO_RANGE",
]
