"""The noise model of a recording: :func:`find_noise_model`."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from imukit._errors import FileFormatError
from imukit.imu import ImuNoise
from imukit.io._euroc import euroc_extrinsics, read_euroc_sensor
from imukit.io._kalibr import read_kalibr_imu

__all__ = ["NoNoiseModelError", "find_noise_model"]


class NoNoiseModelError(FileFormatError):
    """The recording comes with no noise model and none was given."""


def find_noise_model(path: str | Path, kalibr_yaml: str | Path | None = None) -> ImuNoise:
    """The IMU noise densities for the recording at ``path``: from ``kalibr_yaml`` (a Kalibr
    ``imu.yaml``) when given, else from the EuRoC ``imu0/sensor.yaml`` that goes with ``path``
    (:func:`imukit.io.read_euroc_sensor`: ``imu0/`` or ``mav0/imu0/`` of a folder, or beside a bare
    ``data.csv``), else :class:`NoNoiseModelError` (a :class:`imukit.FileFormatError`).

    A ``sensor.yaml`` whose ``T_BS`` is not the identity warns (``UserWarning``): the noise model
    is used, the extrinsics are not applied (the body frame is the IMU's).
    """
    if kalibr_yaml is not None:
        return read_kalibr_imu(kalibr_yaml).noise
    sensor = read_euroc_sensor(path)
    if sensor is None:
        raise NoNoiseModelError(
            f"{path} has no imu0/sensor.yaml; give the noise model as a Kalibr imu.yaml", argument="kalibr_yaml"
        )
    t_bs = euroc_extrinsics(sensor)
    if t_bs is not None and not np.array_equal(t_bs, np.eye(4)):
        warnings.warn(
            "the sensor.yaml's T_BS is not the identity; it is not applied: the body frame is the IMU's",
            UserWarning,
            stacklevel=2,
        )
    return sensor.noise
