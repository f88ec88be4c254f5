"""One recording as a job reads it: :func:`load` and the job's result :class:`JobOutput`."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit.imu import ImuData
from imukit.io import ReadReport, read_imu
from imukit.io._report import KINDS, OnBadLine
from imukit.state import Trajectory

__all__ = ["JobOutput", "Recording", "load"]

Scalar = float | int | str | bool | None


class JobOutput(NamedTuple):
    """What a job returns for one recording: plain data that pickles.

    ``scalars`` become the columns of the log's row in ``summary.parquet`` (units in the names:
    ``duration_s``, ``gyro_bias_x_rad_s``); ``rows``, when the job has per-sample or per-window
    output, are equal-length columns (``(n,)`` or ``(n, k)`` arrays) of the log's part of the
    partitioned dataset.
    """

    scalars: dict[str, Scalar]
    rows: dict[str, NDArray[Any]] | None = None


class Recording(NamedTuple):
    """A recording read for a job: its samples, its ground truth if any, and the lines skipped."""

    imu: ImuData
    truth: Trajectory | None
    skipped: ReadReport


def load(
    path: str | os.PathLike[str], *, on_bad_line: OnBadLine = "skip", csv: Mapping[str, Any] | None = None
) -> Recording:
    """:func:`imukit.io.read_imu` of ``path`` with its skipped lines kept (``on_bad_line="skip"`` by
    default: a fleet report counts bad lines rather than stopping at the first)."""
    skipped = ReadReport()
    imu, truth = read_imu(path, csv=csv, on_bad_line=on_bad_line, report=skipped)
    return Recording(imu, truth, skipped)


def skipped_counts(report: ReadReport) -> dict[str, Scalar]:
    """``skipped_<kind>_lines`` for every kind of bad line the readers know (0 when none)."""
    counts = {kind: 0 for kind in KINDS}
    for line in report.skipped:
        counts[line.kind] = counts.get(line.kind, 0) + 1
    return {f"skipped_{kind.replace(' ', '_').replace('-', '_')}_lines": n for kind, n in counts.items()}


def per_axis(name: str, unit: str, values: NDArray[Any] | None) -> dict[str, Scalar]:
    """``{name}_x_{unit}`` … ``{name}_z_{unit}`` from a 3-vector (None each when ``values`` is None)."""
    return {
        f"{name}_{axis}_{unit}": (None if values is None else np.asarray(values)[k].item())
        for k, axis in enumerate("xyz")
    }
