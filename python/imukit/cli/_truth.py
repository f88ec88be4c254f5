"""The ground truth at the IMU's stamps (:func:`imukit.eval.truth_at_imu`), its failure as an option."""

from __future__ import annotations

from typing import Any

from numpy.typing import NDArray

from imukit._errors import ParameterError
from imukit.cli._common import CliError
from imukit.eval import Association, truth_at_imu
from imukit.eval._associate import span_text
from imukit.imu import ImuData
from imukit.io import reference_max_dt
from imukit.state import Trajectory


def truth_at(truth: Trajectory, imu: ImuData | NDArray[Any], *, max_dt: float | None, option: str) -> Association:
    """:func:`imukit.eval.truth_at_imu` (``max_dt`` None: by the truth's own rate); no stamp paired: a
    CliError naming ``option`` (the command's option that sets ``max_dt``)."""
    try:
        return truth_at_imu(truth, imu, max_dt=max_dt)
    except ParameterError as exc:
        limit = reference_max_dt(truth) if max_dt is None else max_dt
        raise CliError(
            f"{option}: no IMU sample lies where the ground truth can be interpolated (truth "
            f"{span_text(truth.t[0], truth.t[-1])}, IMU {span_text(*_span(imu))}, gaps over "
            f"{limit:.4g} s not bridged)"
        ) from exc


def _span(imu: ImuData | NDArray[Any]) -> tuple[float, float]:
    """The first and last stamp [s] of ``imu`` or of stamps (int64: ns)."""
    if isinstance(imu, ImuData):
        return float(imu.t[0]), float(imu.t[-1])
    scale = 1e-9 if imu.dtype.kind in "iu" else 1.0
    return float(imu[0]) * scale, float(imu[-1]) * scale
