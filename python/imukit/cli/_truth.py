"""The ground truth at the IMU's stamps (:func:`imukit.eval.truth_at_imu`), its failure as an option."""

from __future__ import annotations

from imukit._errors import ParameterError
from imukit.cli._common import CliError
from imukit.eval import Association, truth_at_imu
from imukit.imu import ImuData
from imukit.state import Trajectory


def truth_at(truth: Trajectory, imu: ImuData, *, max_dt: float, option: str) -> Association:
    """:func:`imukit.eval.truth_at_imu`; no sample paired: a CliError naming ``option`` (the command's
    option that sets ``max_dt``)."""
    try:
        return truth_at_imu(truth, imu, max_dt=max_dt)
    except ParameterError as exc:
        raise CliError(
            f"{option}: no IMU sample lies where the ground truth can be interpolated (truth "
            f"{truth.t[0]:.9g} … {truth.t[-1]:.9g} s, IMU {imu.t[0]:.9g} … {imu.t[-1]:.9g} s, gaps over "
            f"{max_dt:g} s not bridged)"
        ) from exc
