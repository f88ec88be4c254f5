"""The jobs :func:`imukit.fleet.run` knows by name (:data:`JOBS`): ``filter``, ``integrate``,
``preintegrate`` (``report``: :mod:`imukit.fleet._report`; ``evaluate``: :mod:`imukit.fleet._score`).

A job is ``job(path, **options) -> JobOutput``: a plain function of one recording. ``preintegrate``
cuts the log into windows of ``window_s`` seconds (:func:`imukit.preint.regular_boundaries`),
preintegrates them (:func:`imukit.preintegrate_windows`, the noise from ``noise_yaml`` or the
EuRoC ``sensor.yaml`` beside the log: :func:`imukit.io.find_noise_model`) and returns one row per
window (:func:`imukit.preint.window_arrays`; the 9×9 covariance and 9×6 bias Jacobian flattened
row-major), for learning datasets.

``filter`` (:func:`attitude`) runs an attitude filter (``method``: ``"robust"`` (default), ``"mahony"`` or
``"madgwick"``, default options; 9D where the log has a magnetometer, ``imukit.ImuData.mag``) over the
log; its rows are ``t_s``, ``q_xyzw`` (``R_wb``) and ``gyro_bias_rad_s`` per sample and, where the
log has ground truth, the errors against it (:func:`imukit.eval.attitude_error` with the truth at
the IMU's stamps, :func:`imukit.eval.truth_at_imu`; a constant heading offset removed, as 6D filters
cannot observe heading): ``total_error_deg``, ``heading_error_deg``, ``inclination_error_deg`` per sample (NaN where
the truth has none) and their RMSE as scalars.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from imukit._arrays import flag
from imukit._errors import ParameterError
from imukit.eval import attitude_error, truth_at_imu
from imukit.filters import Madgwick, Mahony, Robust, in_world
from imukit.fleet._load import JobOutput, Scalar, load, per_axis
from imukit.fleet._report import report
from imukit.fleet._score import evaluate, scores
from imukit.imu import ImuBias
from imukit.io import find_noise_model
from imukit.io._report import OnBadLine
from imukit.preint import PreintParams, preintegrate_windows, regular_boundaries, window_arrays
from imukit.strapdown import integrate

__all__ = ["FILTERS", "JOBS", "attitude", "dead_reckoning", "preintegrate"]

FILTERS = {"mahony": Mahony, "madgwick": Madgwick, "robust": Robust}
"""The filters the ``filter`` job runs, by ``method`` name."""


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


def attitude(
    path: str | os.PathLike[str],
    *,
    method: str = "robust",
    world: str = "ENU",
    max_dt: float | None = None,
    on_bad_line: OnBadLine = "skip",
    csv: Mapping[str, Any] | None = None,
) -> JobOutput:
    """The ``filter`` job: attitude of the recording at ``path`` and its error against the log's ground
    truth (module doc); ``max_dt`` [s]: the longest truth gap interpolated across (None: by the truth's own
    rate, :func:`imukit.io.reference_max_dt`)."""
    if method not in FILTERS:
        raise ParameterError(f"expected one of {', '.join(FILTERS)}, got {method!r}", argument="method")
    imu, truth, _ = load(path, on_bad_line=on_bad_line, csv=csv)
    result = FILTERS[method](world=world).run(imu, mag=imu.mag)
    rows = {"t_s": imu.t, "q_xyzw": result.rotation.as_quat(), "gyro_bias_rad_s": result.gyro_bias}
    scalars: dict[str, Scalar] = {
        "samples": len(imu),
        **per_axis("final_gyro_bias", "rad_s", result.gyro_bias[-1]),
    }
    if truth is not None:
        paired = truth_at_imu(truth, imu, max_dt=max_dt)
        reference = np.full((len(imu), 4), np.nan)  # NaN: no truth there, not scored
        reference[paired.mask] = paired.reference.rotation.as_quat()
        error = attitude_error(result.rotation, in_world(reference, world), world=world, align_heading=True)
        rmse = error.rmse(degrees=True)
        scalars |= {
            "rmse_total_deg": rmse.total,
            "rmse_heading_deg": rmse.heading,
            "rmse_inclination_deg": rmse.inclination,
            "scored_samples": rmse.n_samples,
        }
        rows |= {f"{name}_error_deg": np.degrees(getattr(error, name)) for name in ("total", "heading", "inclination")}
    return JobOutput(scalars, rows)


def dead_reckoning(
    path: str | os.PathLike[str],
    *,
    scheme: str | None = None,
    bias_from_truth: bool = False,
    rpe_delta_s: float = 1.0,
    max_dt: float | None = None,
    on_bad_line: OnBadLine = "skip",
    csv: Mapping[str, Any] | None = None,
) -> JobOutput:
    """The ``integrate`` job: dead reckoning of the recording at ``path`` from its ground truth's state
    at the first IMU sample inside it (with the truth's biases when ``bias_from_truth``), scored
    against that truth without alignment (:func:`imukit.fleet._score.scores`: ATE, RPE over
    ``rpe_delta_s`` seconds). Rows: ``t_s``, ``position_m``, ``velocity_m_s``, ``q_xyzw``."""
    imu, truth, _ = load(path, on_bad_line=on_bad_line, csv=csv)
    if truth is None:
        raise ParameterError(f"{os.fspath(path)} has no ground truth to start from and score against", argument="path")
    paired = truth_at_imu(truth, imu, max_dt=max_dt)
    first = int(np.argmax(paired.mask))  # the first IMU sample the truth covers
    start = paired.reference.state(0)
    bias = None
    if flag(bias_from_truth, "bias_from_truth"):
        if paired.reference.gyro_bias is None or paired.reference.accel_bias is None:
            raise ParameterError(f"{os.fspath(path)}: the ground truth has no biases", argument="bias_from_truth")
        bias = ImuBias(paired.reference.gyro_bias[0], paired.reference.accel_bias[0])
    samples = imu[first:]
    if scheme is None:
        trajectory = integrate(samples, initial=start, bias=bias)
    else:
        trajectory = integrate(samples, initial=start, bias=bias, scheme=scheme)
    scored, _ = scores(trajectory, truth, align="none", rpe_delta_s=rpe_delta_s, max_dt=max_dt)
    scalars: dict[str, Scalar] = {"samples": len(samples), **scored}
    rows = {"t_s": trajectory.t, "position_m": trajectory.position, "q_xyzw": trajectory.rotation.as_quat()}
    if trajectory.velocity is not None:
        rows["velocity_m_s"] = trajectory.velocity
    return JobOutput(scalars, rows)


JOBS: dict[str, Callable[..., JobOutput]] = {
    "report": report,
    "filter": attitude,
    "integrate": dead_reckoning,
    "evaluate": evaluate,
    "preintegrate": preintegrate,
}
"""The jobs by name, as ``imukit fleet JOB`` and :func:`imukit.fleet.run` take them."""
