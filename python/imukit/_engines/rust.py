"""The Rust engine: one native call (``_core.preint_windows_record``, reading the samples and the
options by attribute name) fills every array of the record."""

from __future__ import annotations

import numpy as np

from imukit import _core
from imukit._engines._windows import Windows, record
from imukit._preint_record import Preintegration, PreintParams
from imukit.imu import ImuData


def preintegrate_windows(imu: ImuData, windows: Windows, params: PreintParams, threads: int | None) -> Preintegration:
    """Every window of ``windows`` in one call, in parallel on ``threads`` threads (None: the process-wide pool)."""
    arrays = _core.preint_windows_record(
        imu,
        np.ascontiguousarray(windows.offsets),
        params,
        threads,
    )
    return record(arrays, windows, params)
