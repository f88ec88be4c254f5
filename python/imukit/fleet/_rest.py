"""Rest segments of a recording: :func:`rest_segments` (``docs/fleet.md``).

A sample is still when ``‖ω‖ < gyro`` [rad/s] and ``|‖a‖ − g| < accel`` [m/s²] (:class:`RestRule`,
defaults 0.05 rad/s, 0.2 m/s², 1 s), and a rest segment is a run of still samples lasting at least
``duration_s``. A fleet report asks "was the unit still", a question about the raw readings, so it
keeps its own rule: the filters' :class:`imukit.filters.RestDetection` tests deviations from a
low pass to learn a bias that is itself above 0.05 rad/s. This is the magnitude detector of Skog
et al. (2010, "Zero-velocity detection — an algorithm evaluation", IEEE T-BME 57(11)) on single
samples; a slow turn under ``gyro`` rad/s with no acceleration passes it too, which is why the bias
and noise estimates name the seconds they used.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from imukit.imu import GRAVITY, ImuData

__all__ = ["RestRule", "RestSegment", "rest_segments"]


class RestRule(NamedTuple):
    """The single-sample still test of :func:`rest_segments`."""

    gyro: float = 0.05
    """[rad/s] largest ‖ω‖ of a still sample."""
    accel: float = 0.2
    """[m/s²] largest |‖a‖ − g| of a still sample."""
    duration_s: float = 1.0
    """[s] shortest rest segment."""


class RestSegment(NamedTuple):
    """Samples ``start`` … ``stop − 1`` of a recording, all still."""

    start: int
    stop: int
    duration_s: float


def rest_segments(imu: ImuData, rule: RestRule | None = None) -> list[RestSegment]:
    """The rest segments of ``imu`` in time order (module doc); ``rule`` None: ``RestRule()``."""
    rule = RestRule() if rule is None else rule
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
