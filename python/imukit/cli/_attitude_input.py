"""Input of the attitude commands: IMU samples, optional magnetometer (``ImuData.mag``), reference
attitudes at the IMU's samples. BROAD trials (``.mat``, and the package's ``.npz`` excerpt with the
same keys) carry a magnetometer, and so may CSV files (``--csv-mag-columns``) and ROS bags."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray
from imukit.cli._common import CliError, err, read_imu, refuse_reader_options
from imukit.cli._truth import truth_at
from imukit.eval import Association
from imukit.imu import ImuData

BROAD_KEYS = ("imu_gyr", "imu_acc", "imu_mag", "opt_quat", "movement", "sampling_rate")


class AttitudeInput(NamedTuple):
    """``imu``; ``mag`` (N, 3), ``imu.mag``, or None; ``truth_xyzw`` (N, 4) reference ``R_wb`` at the IMU samples
    (NaN rows where there is none) or None; ``mask`` (N,) the samples to score (BROAD's movement);
    ``paired``: the association with a ground-truth trajectory (which IMU samples got a reference,
    and why the others did not), None for a reference given per sample."""

    imu: ImuData
    mag: FloatArray | None
    truth_xyzw: FloatArray | None
    mask: NDArray[np.bool_] | None
    paired: Association | None = None


def read_broad(path: str | Path) -> AttitudeInput:
    """A BROAD trial (Laidig et al. 2021): ``t = index / sampling_rate`` [s], gyro [rad/s], accel
    [m/s²], mag [µT], ``opt_quat`` w x y z (ENU, NaN during dropouts), ``movement``."""
    where = str(path)
    if Path(path).suffix.lower() == ".mat":
        from scipy.io import loadmat

        data = loadmat(where)
    else:
        with np.load(where) as npz:
            data = {key: npz[key] for key in npz.files}
    missing = [key for key in BROAD_KEYS if key not in data]
    if missing:
        raise CliError(f"path: {where}: not a BROAD trial, missing {', '.join(missing)}")
    rate = float(np.asarray(data["sampling_rate"]).item())
    gyro, accel, mag = (np.asarray(data[key], dtype=np.float64) for key in ("imu_gyr", "imu_acc", "imu_mag"))
    imu = ImuData(np.arange(len(gyro)) / rate, gyro, accel, mag=mag)
    truth = np.asarray(data["opt_quat"], dtype=np.float64)[:, [1, 2, 3, 0]]
    return AttitudeInput(imu, imu.mag, np.ascontiguousarray(truth), np.asarray(data["movement"]).ravel().astype(bool))


def read_attitude_input(args: argparse.Namespace) -> AttitudeInput:
    """``args.path``: BROAD ``.mat`` / ``.npz`` by suffix (bag options refused); anything else through
    :func:`imukit.cli._common.read_imu`."""
    path = args.path
    if Path(path).suffix.lower() in (".mat", ".npz"):
        refuse_reader_options(args, "a BROAD trial")
        with err.status(f"reading {path}"):
            return read_broad(path)
    imu, truth = read_imu(args)
    if truth is None:
        return AttitudeInput(imu, imu.mag, None, None)
    paired = truth_at(truth, imu, max_dt=args.max_dt, option="--max-dt")
    q = np.full((len(imu), 4), np.nan)  # NaN: no reference, counted by attitude_error, not scored
    q[paired.mask] = paired.reference.rotation.as_quat()
    return AttitudeInput(imu, imu.mag, q, None, paired)
