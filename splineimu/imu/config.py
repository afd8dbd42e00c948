"""IMU sensor-model configuration: Kalibr ``imu.yaml`` keys plus documented extras.

One :class:`ImuConfig` holds every parameter of the sensor model of
:mod:`splineimu.imu.noise`. It reads and writes flat yaml files with the keys below (the same
names both ways), Kalibr / OpenVINS chain files (``imu0: {...}``), the EuRoC ``sensor.yaml``
and the ``allan.yaml`` written by ``splineimu allan``; packaged presets of real IMUs can be
named wherever a file is expected (:func:`load_imu_config`).

The names here come from :mod:`splineimu.imu._config` (the dataclass),
:mod:`splineimu.imu._config_values` (keys and value checks), :mod:`splineimu.imu.temperature`
and :mod:`splineimu.imu.presets`; the files are read with :mod:`splineimu.yamldoc` and written by
:func:`splineimu.io.imu_yaml.write_imu_config`.

Keys
----
A "vector" is a number (the same for the three axes) or a list of three numbers ``[x, y, z]``
in the sensor frame. Only the Kalibr keys are needed; everything else is applied only when
the file names it, and is written back only when set.

Kalibr keys (continuous-time densities; white noise and bias random walk are on whenever
they are non-zero; an absent density is zero)

=============================== =============================== =================================
key                             unit                            meaning
=============================== =============================== =================================
``gyroscope_noise_density``     rad/s/sqrt(Hz), vector >= 0     white noise; per sample
                                                                ``sigma / sqrt(dt)``
``gyroscope_random_walk``       rad/s^2/sqrt(Hz), vector >= 0   bias random walk; per step
                                                                ``sigma_b * sqrt(dt)``
``accelerometer_noise_density`` m/s^2/sqrt(Hz), vector >= 0     as above
``accelerometer_random_walk``   m/s^3/sqrt(Hz), vector >= 0     as above
``update_rate``                 Hz, > 0                         nominal sample rate (``rate_hz``
                                                                of EuRoC's sensor.yaml is read
                                                                as this)
=============================== =============================== =================================

Extra keys (``<s>`` is ``gyroscope`` or ``accelerometer``; ``<u>`` is rad/s or m/s^2)

====================================== ==================== ==========================================
key                                    unit                 meaning
====================================== ==================== ==========================================
``<s>_bias``                           <u>, vector          turn-on bias, fixed
``<s>_bias_sigma``                     <u>, vector >= 0     turn-on bias drawn from N(0, sigma^2) per
                                                            run (added to ``<s>_bias`` if both)
``<s>_scale``                          1, vector > -1       scale-factor errors ``s``:
                                                            ``S = I + diag(s)`` (1e-3 = 1000 ppm)
``<s>_misalignment``                   1, 3x3 matrix        ``M`` (applied after S). Also accepted:
                                                            6 numbers = Kalibr's lower triangle
                                                            ``[m11, m21, m22, m31, m32, m33]``, or 3
                                                            numbers = its off-diagonal part
                                                            ``[m21, m31, m32]`` with unit diagonal.
                                                            Written back as the 3x3 matrix.
``gyroscope_g_sensitivity``            rad/s per m/s^2,     ``G``: adds ``G f`` (f = true specific
                                       3x3 matrix           force) to the gyro
``<s>_bias_instability``               <u>, vector >= 0     first-order Gauss-Markov bias: its
                                                            stationary standard deviation sigma.
                                                            (Its Allan deviation peaks at
                                                            0.617 sigma near tau = 1.89 T; to mimic
                                                            an Allan-plot bias instability B,
                                                            floor 0.664 B, use sigma ~= 1.08 B.)
``<s>_bias_correlation_time``          s, vector > 0        its correlation time T (required with
                                                            ``<s>_bias_instability``)
``temperature_profile``                degC                 a number (constant), ``{start: degC,
                                                            rate: degC/s}`` (linear ramp from the
                                                            first sample) or ``{file: PATH}``: two
                                                            columns ``time [s] since the first
                                                            sample, temperature [degC]``, comma or
                                                            space separated, ``#`` comments,
                                                            linearly interpolated (held constant
                                                            outside); a relative PATH is relative
                                                            to the yaml file (written back as an
                                                            absolute path)
``temperature_reference``              degC                 temperature of zero temperature error
                                                            (default 25)
``<s>_bias_temperature_coefficient``   <u>/K, vector        bias ``+= c (T - T_ref)``
``<s>_scale_temperature_coefficient``  1/K, vector          ``s += c (T - T_ref)``
``<s>_quantization``                   <u>, vector > 0      LSB: output ``= LSB * round(x / LSB)``
``<s>_saturation``                     <u>, vector > 0      range: output clipped to ``[-r, r]``
====================================== ==================== ==========================================

OpenVINS's intrinsics (``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg``, with its ``model``)
are applied: they are read as the equivalent ``<s>_misalignment`` and
``gyroscope_g_sensitivity`` (:mod:`splineimu.imu.openvins` states the correspondence); giving
them together with those keys or a scale of the same sensor is an error.

Read but ignored: the other keys of Kalibr, OpenVINS and EuRoC files (``rostopic``,
``time_offset``, ``T_i_b``, ``T_BS``, ``sensor_type``, ``comment``, ``accelerometers``,
``gyroscopes``), the companions
``<key>_avg``, ``<key>_xyz`` and ``<key>_ci95`` of any key, and the informational ``allan`` section that
``splineimu allan`` writes. Any other key is an error with a did-you-mean.

Examples
--------
>>> cfg = ImuConfig.from_dict({"gyroscope_noise_density": 1.6968e-4, "update_rate": 200})
>>> cfg.gyroscope_noise_density.tolist(), cfg.update_rate
([0.00016968, 0.00016968, 0.00016968], 200.0)
>>> sorted(cfg.to_dict())
['accelerometer_noise_density', 'accelerometer_random_walk', 'gyroscope_noise_density', \
'gyroscope_random_walk', 'update_rate']
"""

from __future__ import annotations

from ._config import ImuConfig
from ._config_values import IGNORED_KEYS, KALIBR_KEYS, SENSORS
from .presets import list_presets, load_imu_config, load_preset
from .temperature import TemperatureProfile

__all__ = ["ImuConfig", "load_imu_config", "load_preset", "list_presets", "TemperatureProfile",
           "SENSORS", "KALIBR_KEYS", "IGNORED_KEYS"]
