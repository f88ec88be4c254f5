"""Steps between samples far longer than the others: :func:`find_gaps` (``docs/io.md``).

The ``imukit`` commands name the longest one on stderr or refuse the first over ``--max-gap``; as a
library function a notebook or a Dask task runs the same check. The same median step sets how far a
reference (ground truth) is interpolated: :func:`reference_max_dt`, ``REFERENCE_GAP_FACTOR`` of it,
so a 20 Hz truth and a 200 Hz one are each judged by their own rate.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from imukit._arrays import FloatArray, real_scalar
from imukit.imu import ImuData
from imukit.state import Trajectory

__all__ = ["GAP_FACTOR", "REFERENCE_GAP_FACTOR", "Gap", "find_gaps", "median_step", "reference_max_dt"]

GAP_FACTOR = 10.0
""":func:`find_gaps`' default: a step longer than this many median steps is a gap."""
REFERENCE_GAP_FACTOR = 2.5
""":func:`reference_max_dt`: a reference step longer than this many median steps is a gap (a dropped
sample (a step of 2) and a motion-capture clock's jitter stay under it; a missed second does not)."""


class Gap(NamedTuple):
    """A step between two samples that :func:`find_gaps` found."""

    sample: int
    """The sample after the step (the step is ``t[sample] - t[sample - 1]``)."""
    t: float
    """That sample's time [s]."""
    step: float
    """The step [s] (from exact ``t_ns`` when the samples have them)."""
    median: float
    """The median step of the recording [s]."""

    def __str__(self) -> str:
        return f"the step into sample {self.sample} (t = {self.t:.9g} s) is {self.step:.6g} s"


def _steps(samples: ImuData | Trajectory) -> FloatArray:
    """The steps between consecutive samples [s], from exact ``t_ns`` when the samples have them."""
    return np.diff(samples.t_ns) / 1e9 if samples.t_ns is not None else np.diff(samples.t)


def median_step(samples: ImuData | Trajectory) -> float:
    """The median step between consecutive samples of an :class:`~imukit.ImuData` or a
    :class:`~imukit.Trajectory` [s]; NaN for fewer than two samples."""
    return float(np.median(_steps(samples))) if len(samples) > 1 else float("nan")


def reference_max_dt(reference: Trajectory, *, factor: float = REFERENCE_GAP_FACTOR) -> float:
    """The longest step [s] of ``reference`` that :func:`imukit.eval.associate` interpolates across
    when not told: ``factor`` times its median step (0.125 s for a 20 Hz ground truth, 0.0125 s at
    200 Hz); ``inf`` for a one-pose reference (nothing to interpolate, only exact stamps pair)."""
    step = median_step(reference)
    return factor * step if np.isfinite(step) else float("inf")


def find_gaps(imu: ImuData | Trajectory, *, longer_than: float | None = None, factor: float = GAP_FACTOR) -> list[Gap]:
    """The steps between samples (of an :class:`~imukit.ImuData` or a :class:`~imukit.Trajectory`)
    longer than ``longer_than`` seconds or, without it, longer than ``factor`` times the median step;
    in time order, [] for fewer than two samples.

    Integrating across a gap is the caller's choice (:class:`imukit.ImuData` refuses one with
    ``max_gap=``); this says where they are, e.g. to name the longest one:

    >>> import imukit as ik
    >>> imu = ik.ImuData([0.0, 0.01, 0.02, 0.5, 0.51], [[0.0, 0.0, 0.0]] * 5, [[0.0, 0.0, 9.81]] * 5)
    >>> [(gap.sample, round(gap.step, 6)) for gap in ik.io.find_gaps(imu)]
    [(3, 0.48)]
    >>> str(ik.io.find_gaps(imu, longer_than=0.1)[0])
    'the step into sample 3 (t = 0.5 s) is 0.48 s'
    """

    def positive(x: float) -> bool:
        return math.isfinite(x) and x > 0.0

    if longer_than is not None:
        longer_than = real_scalar(
            longer_than, "longer_than", what="a positive number of seconds or None", accept=positive
        )
    factor = real_scalar(factor, "factor", what="a positive multiple of the median step", accept=positive)
    if len(imu) < 2:
        return []
    steps = _steps(imu)
    median = float(np.median(steps))
    limit = longer_than if longer_than is not None else factor * median
    return [Gap(int(k) + 1, float(imu.t[k + 1]), float(steps[k]), median) for k in np.flatnonzero(steps > limit)]
