"""Whether a recording meant for Allan variance was still: :func:`moving_seconds`.

The Allan deviation of a sensor that moves measures its motion as well as its noise (a driving car's
gyro reads its turns as "bias instability"). Still means the readings do not change beyond the noise:
each ``window_s`` window's mean gyro and accelerometer against the medians of all windows' means. A
constant bias or a tilt held throughout is still (medians), white noise averages down in the window
(a 1e-2 rad/s/√Hz gyro: 0.01 rad/s in 1 s, under the 0.05 rad/s threshold), and a turn or a change of
tilt of 3° (0.5 m/s² of the 9.81) is not.
"""

from __future__ import annotations

import numpy as np

from imukit._arrays import real_scalar
from imukit._errors import ParameterError
from imukit.imu import ImuData

__all__ = ["moving_seconds"]


def moving_seconds(imu: ImuData, *, gyro: float = 0.05, accel: float = 0.5, window_s: float = 1.0) -> float:
    """Seconds of ``imu`` in ``window_s`` windows whose mean gyro is more than ``gyro`` [rad/s], or whose
    mean accelerometer more than ``accel`` [m/s²], from the medians of every window's mean (module
    doc); 0 for a still recording, and for one shorter than two windows."""
    if not isinstance(imu, ImuData):
        raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
    gyro = real_scalar(gyro, "gyro", what="a threshold in rad/s", accept=lambda x: x > 0)
    accel = real_scalar(accel, "accel", what="a threshold in m/s²", accept=lambda x: x > 0)
    window_s = real_scalar(window_s, "window_s", what="a window in seconds", accept=lambda x: x > 0)
    if len(imu) < 2:
        return 0.0
    per = max(1, round(window_s * (len(imu) - 1) / imu.duration)) if imu.duration > 0 else 1
    count = len(imu) // per
    if count < 2:
        return 0.0
    moving = np.zeros(count, dtype=bool)
    for values, threshold in ((imu.gyro, gyro), (imu.accel, accel)):
        means = values[: count * per].reshape(count, per, 3).mean(axis=1)
        moving |= np.linalg.norm(means - np.median(means, axis=0), axis=1) > threshold
    return float(moving.sum() * per / (len(imu) - 1) * imu.duration)
