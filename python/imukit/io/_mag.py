"""A magnetometer stream put on the IMU's stamps: :func:`with_mag` (``docs/io.md`` § Magnetometer).

=====================  ===========================================================================
matching               by stamp: linear interpolation between the two magnetometer samples around
                       each IMU stamp, which is the sample itself where the stamps coincide (a
                       driver that stamps both from one reading, EuRoC-layout ``mag0/data.csv``)
refused                an IMU sample before the first or after the last magnetometer sample, or
                       inside a magnetometer gap longer than ``GAP_FACTOR`` median steps: bridging it
                       would invent a field; the error names the first such IMU sample
=====================  ===========================================================================
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray
from imukit._errors import FileFormatError
from imukit.imu import ImuData
from imukit.io._gaps import GAP_FACTOR
from imukit.io._lines import as_file_error, ns_text

__all__ = ["with_mag"]


def with_mag(imu: ImuData, t_ns: NDArray[np.int64], mag: FloatArray, where: str, hint: str) -> ImuData:
    """``imu`` (int64 stamps) with ``mag`` (K, 3) sampled at ``t_ns`` (K,), strictly increasing, matched
    to its stamps (module docs); ``where`` names the source and ``hint`` how to do without the
    magnetometer in the error."""
    assert imu.t_ns is not None  # the readers that call this stamp in nanoseconds
    stamps = imu.t_ns
    after = np.searchsorted(t_ns, stamps, side="left")  # first magnetometer sample at or after each IMU one
    exact = (after < len(t_ns)) & (t_ns[np.minimum(after, len(t_ns) - 1)] == stamps)
    inside = (stamps >= t_ns[0]) & (stamps <= t_ns[-1])
    bracket = np.zeros(len(stamps), dtype=np.int64)
    if len(t_ns) > 1:
        steps = np.diff(t_ns)
        limit = GAP_FACTOR * float(np.median(steps))
        bracket = steps[np.clip(after - 1, 0, len(steps) - 1)]
        inside &= exact | (bracket <= limit)
    bad = np.flatnonzero(~inside)
    if bad.size:
        k = int(bad[0])
        span = f"[{ns_text(int(t_ns[0]))}, {ns_text(int(t_ns[-1]))}]"
        why = (
            f"outside the magnetometer's span {span}"
            if not t_ns[0] <= stamps[k] <= t_ns[-1]
            else (f"in a gap of {int(bracket[k])} ns between magnetometer samples (over {GAP_FACTOR:g} median steps)")
        )
        raise FileFormatError(
            f"{where}: IMU sample {k} (stamp {ns_text(int(stamps[k]))}) is {why}, as are {bad.size - 1} more "
            f"of {len(stamps)}; {hint}",
            argument="path",
        )
    seconds = (t_ns - stamps[0]) * 1e-9
    at = imu.seconds
    values = np.stack([np.interp(at, seconds, mag[:, axis]) for axis in range(3)], axis=-1)
    values[exact] = mag[after[exact]]  # bit for bit where the stamps coincide
    ranges = {"gyro_range": imu.gyro_range, "accel_range": imu.accel_range}
    return as_file_error(where, lambda: ImuData(stamps, imu.gyro, imu.accel, **ranges, mag=values))
