"""The ground truth at the IMU's stamps, by one rule for every caller: :func:`truth_at_imu`."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imukit.eval._associate import Association, associate
from imukit.imu import ImuData
from imukit.state import Trajectory


def truth_at_imu(truth: Trajectory, imu: ImuData | NDArray[Any], *, max_dt: float | None = None) -> Association:
    """``truth`` at ``imu``'s stamps (or at stamps given as an array: int64 ns or float s) where
    :func:`associate` pairs them (position and velocity linear, rotation slerp, never across a truth
    gap longer than ``max_dt`` [s]; None: by the truth's own rate, :func:`imukit.io.reference_max_dt`);
    ``.mask`` marks the stamps that have it and ``.n_outside_span`` / ``.n_in_gaps`` count the others.
    A truth without velocity gets it from its positions' central differences. No stamp paired: the
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
    at = (imu.t if imu.t_ns is None else imu.t_ns) if isinstance(imu, ImuData) else imu
    stamps = Trajectory(at, np.zeros((len(at), 3)), None, Rotation.identity(len(at)))  # int64: ns
    return associate(stamps, truth, max_dt=max_dt)
