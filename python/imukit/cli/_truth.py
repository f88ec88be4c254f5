"""The ground truth at the IMU's stamps, by one rule for every command: :func:`imukit.eval.associate`
(position and velocity linear, rotation slerp, never across a truth gap longer than ``max_dt``)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imukit._errors import ParameterError
from imukit.cli._common import CliError
from imukit.eval import Association, associate
from imukit.eval._associate import span_text
from imukit.imu import ImuData
from imukit.io import reference_max_dt
from imukit.state import Trajectory


def truth_at(truth: Trajectory, imu: ImuData | NDArray[Any], *, max_dt: float | None, option: str) -> Association:
    """``truth`` at ``imu``'s stamps (or at stamps given as an array: int64 ns or float s) where
    :func:`imukit.eval.associate` pairs them with ``max_dt`` (None: by the truth's own rate,
    :func:`imukit.io.reference_max_dt`); ``.mask`` marks the stamps that have it and
    ``.n_outside_span`` / ``.n_in_gaps`` count the others. A truth without velocity gets it from its
    positions' central differences. No stamp paired: a CliError naming ``option`` (the command's
    option that sets ``max_dt``)."""
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
    try:
        return associate(stamps, truth, max_dt=max_dt)
    except ParameterError as exc:
        limit = reference_max_dt(truth) if max_dt is None else max_dt
        raise CliError(
            f"{option}: no IMU sample lies where the ground truth can be interpolated (truth "
            f"{span_text(truth.t[0], truth.t[-1])}, IMU {span_text(stamps.t[0], stamps.t[-1])}, gaps over "
            f"{limit:.4g} s not bridged)"
        ) from exc
