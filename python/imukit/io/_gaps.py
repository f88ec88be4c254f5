"""Steps between samples far longer than the others: :func:`find_gaps` (``docs/io.md``).

The ``imukit`` commands name the longest one on stderr or refuse the first over ``--max-gap``; as a
library function a notebook or a Dask task runs the same check.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from imukit.imu import ImuData

__all__ = ["GAP_FACTOR", "Gap", "find_gaps"]

GAP_FACTOR = 10.0
""":func:`find_gaps`' default: a step longer than this many median steps is a gap."""


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


def find_gaps(imu: ImuData, *, longer_than: float | None = None, factor: float = GAP_FACTOR) -> list[Gap]:
    """The steps between samples longer than ``longer_than`` seconds or, without it, longer than
    ``factor`` times the median step; in time order, [] for fewer than two samples.

    Integrating across a gap is the caller's choice (:class:`imukit.ImuData` refuses one with
    ``max_gap=``); this says where they are, e.g. to name the longest one:

    >>> import imukit as ik
    >>> imu = ik.ImuData([0.0, 0.01, 0.02, 0.5, 0.51], [[0.0, 0.0, 0.0]] * 5, [[0.0, 0.0, 9.81]] * 5)
    >>> [(gap.sample, round(gap.step, 6)) for gap in ik.io.find_gaps(imu)]
    [(3, 0.48)]
    >>> str(ik.io.find_gaps(imu, longer_than=0.1)[0])
    'the step into sample 3 (t = 0.5 s) is 0.48 s'
    """
    if len(imu) < 2:
        return []
    steps = np.diff(imu.t_ns) / 1e9 if imu.t_ns is not None else np.diff(imu.t)
    median = float(np.median(steps))
    limit = longer_than if longer_than is not None else factor * median
    return [Gap(int(k) + 1, float(imu.t[k + 1]), float(steps[k]), median) for k in np.flatnonzero(steps > limit)]
