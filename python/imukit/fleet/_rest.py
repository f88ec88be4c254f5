"""Rest segments of a recording: :func:`rest_segments` (``docs/fleet.md``).

A sample is still when ``‖ω‖ < gyro`` [rad/s] and ``|‖a‖ − g| < accel`` [m/s²] — the test of the
filters' :class:`imukit.filters.RestDetection`, whose thresholds (the core's ``Default``) are used
here — and a rest segment is a run of still samples lasting at least ``duration_s``. This is the
magnitude detector of Skog et al. (2010, "Zero-velocity detection — an algorithm evaluation",
IEEE T-BME 57(11)) on single samples; a slow turn under ``gyro`` rad/s with no acceleration passes
it too, which is why the bias and noise estimates name the seconds they used.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from imukit import _core
from imukit.imu import GRAVITY, ImuData

__all__ = ["RestSegment", "rest_segments"]


class RestSegment(NamedTuple):
    """Samples ``start`` … ``stop − 1`` of a recording, all still."""

    start: int
    stop: int
    duration_s: float


def rest_segments(imu: ImuData, detection: _core.RestDetection | None = None) -> list[RestSegment]:
    """The rest segments of ``imu`` in time order (module doc); ``detection`` defaults to the core's
    ``RestDetection()`` (its ``gyro``, ``accel`` and ``duration_s`` are used)."""
    rule = detection if detection is not None else _core.RestDetection()
    g = float(np.linalg.norm(GRAVITY))
    still = (np.linalg.norm(imu.gyro, axis=1) < rule.gyro) & (
        np.abs(np.linalg.norm(imu.accel, axis=1) - g) < rule.accel
    )
    edges = np.flatnonzero(np.diff(np.concatenate(([0], still.astype(np.int8), [0]))))
    segments = []
    for start, stop in zip(edges[::2], edges[1::2]):
        duration = float(imu.seconds[stop - 1] - imu.seconds[start])
        if duration >= rule.duration_s:
            segments.append(RestSegment(int(start), int(stop), duration))
    return segments
