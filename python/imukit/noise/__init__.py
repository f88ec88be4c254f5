"""Identification of IMU noise: Allan variance (:func:`allan_deviation`, :func:`fit_allan`,
:func:`plot_allan`, :func:`mean_rate_hz`: the rate they take; :func:`moving_seconds`: whether the
recording was still) and density inflation from
preintegration residuals against ground truth (:func:`calibrate_from_residuals`, ``docs/noise.md``
§ Calibration from residuals).

=====================  ===========================================================================
input                  a rate signal sampled at a constant ``rate`` [Hz]: a gyro at rest [rad/s] or an
                       accelerometer at rest [m/s²], ``(N,)`` or ``(N, C)`` (one column per axis)
estimator              overlapping Allan variance (IEEE Std 952; Riley, NIST SP 1065, eq. 11), or the
                       non-overlapping one; ``docs/noise.md`` § Allan variance
model                  ``σ²(τ) = N²/τ + (2 ln 2/π) B² + K² τ/3``: white noise density N [unit/√Hz],
                       bias instability B [unit], rate random walk K [unit/s/√Hz]
units                  N and K are the continuous densities of :class:`imukit.ImuNoise`
                       (``docs/conventions.md``, row 11): :func:`to_imu_noise` builds one
=====================  ===========================================================================

>>> import numpy as np, imukit as ik
>>> rng = np.random.default_rng(0)
>>> gyro = 1e-3 * np.sqrt(200.0) * rng.standard_normal(200_000)   # N = 1e-3 rad/s/√Hz at 200 Hz
>>> allan = ik.noise.allan_deviation(gyro, 200.0)
>>> round(float(allan.deviation[0] * np.sqrt(allan.taus[0])), 4)  # σ(τ) √τ = N for white noise
0.001
"""

from imukit.noise._allan import AllanDeviation, allan_deviation, mean_rate_hz
from imukit.noise._calibrate import NoiseCalibration, calibrate_from_residuals
from imukit.noise._fit import FLICKER_FACTOR, UNRESOLVED, AllanFit, fit_allan, to_imu_noise
from imukit.noise._plot import plot_allan
from imukit.noise._still import moving_seconds

__all__ = [
    "FLICKER_FACTOR",
    "UNRESOLVED",
    "AllanDeviation",
    "AllanFit",
    "NoiseCalibration",
    "allan_deviation",
    "calibrate_from_residuals",
    "fit_allan",
    "mean_rate_hz",
    "moving_seconds",
    "plot_allan",
    "to_imu_noise",
]
