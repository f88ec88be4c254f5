"""``imukit preintegrate --calibrate YAML``: the noise densities inflated until the whitened residuals
of the windows against the ground truth are consistent (:func:`imukit.noise.calibrate_from_residuals`),
written as a Kalibr imu.yaml."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from imukit.cli._allan import digits
from imukit.cli._common import CliError, note, out, wrote
from imukit.cli._truth import truth_at
from imukit.imu import ImuBias, ImuData, ImuNoise
from imukit.io import write_kalibr_imu
from imukit.noise import NoiseCalibration, calibrate_from_residuals, mean_rate_hz
from imukit.preint import PreintParams, States, concatenate, preintegrate_windows
from imukit.state import Trajectory

DENSITY_DIGITS = 4  # the factors' intervals are a few percent wide


def calibrate(
    imu: ImuData,
    truth: Trajectory | None,
    edges: NDArray[np.generic],
    noise: ImuNoise,
    scheme: str,
    max_dt: float | None,
) -> NoiseCalibration:
    """The calibration on the windows between ``edges`` whose both ends have ground truth (interpolated
    by the one rule of every command, :func:`imukit.cli._truth.truth_at`: never across a truth gap over
    ``max_dt``), each at the truth's bias at its start; prints it and what was left out."""
    if truth is None or truth.velocity is None or truth.gyro_bias is None or truth.accel_bias is None:
        raise CliError(
            "--calibrate: needs ground truth with velocity and biases at the IMU's clock (an EuRoC folder with "
            "state_groundtruth_estimate0/data.csv)"
        )
    at = truth_at(truth, edges, max_dt=max_dt, option="--max-dt")
    ok = np.flatnonzero(at.mask[:-1] & at.mask[1:])
    if ok.size == 0:
        raise CliError("--calibrate: no window has ground truth at both ends")
    k_of_edge = np.cumsum(at.mask) - 1  # row of at.reference for each kept edge
    ref = at.reference
    assert ref.velocity is not None and ref.gyro_bias is not None and ref.accel_bias is not None
    rot = ref.rotation.as_matrix()
    i, j = k_of_edge[ok], k_of_edge[ok + 1]
    gyro_bias, accel_bias = ref.gyro_bias[i], ref.accel_bias[i]
    # One integration bias (the mean), each window then corrected to its own to first order.
    params = PreintParams(noise, bias=ImuBias(gyro_bias.mean(axis=0), accel_bias.mean(axis=0)), scheme=scheme)
    record = preintegrate_windows(imu, edges, params)
    chosen = concatenate([record[int(k)] for k in ok])
    cal = calibrate_from_residuals(
        chosen,
        States(ref.position[i], ref.velocity[i], rot[i]),
        States(ref.position[j], ref.velocity[j], rot[j]),
        bias=[ImuBias(g, a) for g, a in zip(gyro_bias, accel_bias)],
    )
    left = len(edges) - 1 - ok.size
    if left:
        note(f"--calibrate: {left} of {len(edges) - 1} windows have no ground truth at both ends, left out")
    out.print(f"noise calibration ({scheme}):\n{cal}", markup=False)
    return cal


def write(path: Path, cal: NoiseCalibration, imu: ImuData, window_s: float, scheme: str) -> None:
    """The calibrated densities (4 digits; the random walks as given) as a Kalibr imu.yaml, each
    density's factor in its comment, the χ² before and after in the header."""
    noise = cal.noise
    rounded = ImuNoise(
        digits(noise.gyro_density, DENSITY_DIGITS),
        digits(noise.accel_density, DENSITY_DIGITS),
        noise.gyro_random_walk,
        noise.accel_random_walk,
    )
    lo, hi = cal.mean_interval
    header = (
        f"densities inflated by imukit preintegrate --calibrate: {len(cal.chi2_before)} windows of {window_s:g} s "
        f"({scheme}) against ground truth\n"
        f"whitened chi2 mean {cal.chi2_before.mean():.4g} before, {cal.chi2_after.mean():.4g} after "
        f"({100 * cal.confidence:g}% interval of a consistent mean: [{lo:.4g}, {hi:.4g}])"
    )
    comments = {
        "gyroscope_noise_density": f"x {cal.gyro_factor:.4g} (theta block)",
        "accelerometer_noise_density": f"x {cal.accel_factor:.4g} (v and p blocks)",
        "gyroscope_random_walk": "as given (not calibrated: the residuals are at the true bias)",
        "accelerometer_random_walk": "as given (not calibrated: the residuals are at the true bias)",
    }
    write_kalibr_imu(path, rounded, rate_hz=digits(mean_rate_hz(imu), 6), comments=comments, header=header)
    wrote("calibrated Kalibr imu.yaml", path)
