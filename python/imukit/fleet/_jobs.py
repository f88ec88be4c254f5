"""The jobs :func:`imukit.fleet.run` knows by name (:data:`JOBS`), and ``preintegrate``.

A job is ``job(path, **options) -> JobOutput``: a plain function of one recording. ``preintegrate``
cuts the log into windows of ``window_s`` seconds (:func:`imukit.preint.regular_boundaries`),
preintegrates them (:func:`imukit.preintegrate_windows`, the noise from ``noise_yaml`` or the
EuRoC ``sensor.yaml`` beside the log: :func:`imukit.io.find_noise_model`) and returns one row per
window (:func:`imukit.preint.window_arrays`; the 9×9 covariance and 9×6 bias Jacobian flattened
row-major), for learning datasets.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from imukit.fleet._load import JobOutput, load
from imukit.fleet._report import report
from imukit.io import find_noise_model
from imukit.io._report import OnBadLine
from imukit.preint import PreintParams, preintegrate_windows, regular_boundaries, window_arrays

__all__ = ["JOBS", "preintegrate"]


def preintegrate(
    path: str | os.PathLike[str],
    *,
    window_s: float = 0.1,
    scheme: str | None = None,
    noise_yaml: str | os.PathLike[str] | None = None,
    on_bad_line: OnBadLine = "skip",
    csv: Mapping[str, Any] | None = None,
) -> JobOutput:
    """Windows of ``window_s`` seconds of the recording at ``path`` as rows (module doc)."""
    imu = load(path, on_bad_line=on_bad_line, csv=csv).imu
    noise = find_noise_model(os.fspath(path), None if noise_yaml is None else os.fspath(noise_yaml))
    params = PreintParams(noise) if scheme is None else PreintParams(noise, scheme=scheme)
    record = preintegrate_windows(imu, regular_boundaries(imu, window_s), params)
    rows = {
        name: value.reshape(len(value), -1) if value.ndim > 2 else value
        for name, value in window_arrays(record).items()
    }
    dp = np.linalg.norm(rows["dp"], axis=1)
    return JobOutput(
        {
            "windows": len(dp),
            "max_dp_m": float(dp.max()),
            "max_dv_m_s": float(np.linalg.norm(rows["dv"], axis=1).max()),
        },
        rows,
    )


JOBS: dict[str, Callable[..., JobOutput]] = {"report": report, "preintegrate": preintegrate}
"""The jobs by name, as ``imukit fleet JOB`` and :func:`imukit.fleet.run` take them."""
