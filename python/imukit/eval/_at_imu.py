"""The ground truth at the IMU's stamps, by one rule for every caller: :func:`truth_at_imu`."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from imukit.eval._associate import Association, associate
from imukit.imu import ImuData
from imukit.state import Trajectory


def truth_at_imu(truth: Trajectory, imu: ImuData, *, max_dt: float = 0.02) -> Association:
    """``truth`` at ``imu``'s stamps where :func:`associate` pairs them (position and velocity linear,
    rotation slerp, never across a truth gap longer than ``max_dt`` [s]); ``.mask`` marks the IMU
    samples that have it and ``.n_outside_span`` / ``.n_in_gaps`` count the others. A truth without
    velocity gets it from its positions' central differences. No sample paired: the
    :class:`imukit.ParameterError` of :func:`associate`."""
    if truth.velocity is None and len(truth) > 1:
        velocity = np.gradient(truth.position, truth.t, axis=0)
        t = None if truth.t_ns is not None else truth.t
        truth = Trajectory(
            t,
            truth.position,
            velocity,
            truth.rotation,
            t_ns=truth.t_ns,
            gyro_bias=truth.gyro_bias,
            accel_bias=truth.accel_bias,
        )
    n = len(imu)
    stamps = Trajectory(
        None if imu.t_ns is not None else imu.t, np.zeros((n, 3)), None, Rotation.identity(n), t_ns=imu.t_ns
    )
    return associate(stamps, truth, max_dt=max_dt)
