"""Where a dead-reckoning run starts: the ground truth at the first IMU sample, or at rest, levelled."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from imukit.cli._common import CliError, note
from imukit.cli._truth import truth_at
from imukit.imu import GRAVITY, ImuBias, ImuData
from imukit.state import NavState, Trajectory


def trim_to_truth(imu: ImuData, truth: Trajectory) -> ImuData:
    """``imu`` from its first sample inside the ground truth's span (the truth must cover the start)."""
    first = int(np.searchsorted(imu.t, truth.t[0], side="left"))
    if imu.t_ns is not None and truth.t_ns is not None:
        first = int(np.searchsorted(imu.t_ns, truth.t_ns[0], side="left"))
    if first >= len(imu) - 1 or imu.t[first] > truth.t[-1]:
        raise CliError(
            f"PATH: the ground truth ({truth.t[0]:.3f} … {truth.t[-1]:.3f} s) does not overlap the IMU samples "
            f"({imu.t[0]:.3f} … {imu.t[-1]:.3f} s)"
        )
    if first:
        note(f"skipped the first {first} IMU samples ({imu.t[first] - imu.t[0]:.3f} s), before the ground truth starts")
    return imu[first:]


def from_truth(truth: Trajectory, imu: ImuData, *, max_dt: float | None) -> tuple[NavState, ImuBias | None]:
    """The ground-truth state (and biases, when it has them) at ``imu``'s first sample, by the rule of
    :func:`imukit.cli._truth.truth_at`: position, velocity and biases linear, rotation slerp, exact at
    a common stamp, not across a truth gap over ``max_dt`` [s] (None: by the truth's rate; then a
    CliError). A truth without velocity (TUM) gets it from its positions' central differences."""
    first = truth_at(truth, imu[:1], max_dt=max_dt, option="--max-dt").reference
    velocity = np.zeros(3) if first.velocity is None else first.velocity[0]  # None: a one-pose truth
    state = NavState(first.position[0], velocity, first.rotation[0])
    if first.gyro_bias is None or first.accel_bias is None:
        return state, None
    return state, ImuBias(first.gyro_bias[0], first.accel_bias[0])


# A start is "not static" when over the levelling window any of these is exceeded (stated in
# `imukit integrate --help`). Spreads, not the mean rate: a gyro bias (EuRoC's z: 0.08 rad/s) moves the
# mean but not the spread; the mean rate only above what no MEMS bias reaches.
STATIC_GYRO_STD = 0.1  # [rad/s] standard deviation of any gyro axis
STATIC_ACCEL_RMS = 0.5  # [m/s^2] RMS of |accel| - 9.81 (rotor vibration at rest: ~0.16 on EuRoC)
STATIC_MEAN_RATE = 0.3  # [rad/s] norm of the mean rate
_G = float(np.linalg.norm(GRAVITY))


def levelled_at_rest(imu: ImuData, static_seconds: float) -> NavState:
    """At the origin, at rest, roll and pitch from the mean specific force over the first
    ``static_seconds`` (it points up at rest), yaw zero. A note when that window does not look static
    (the thresholds above)."""
    window = imu.seconds <= static_seconds
    if window.sum() < 2:
        raise CliError(f"--static-seconds: {static_seconds} s holds fewer than 2 IMU samples")
    accel, gyro = imu.accel[window], imu.gyro[window]
    spread = float(gyro.std(axis=0).max())
    shake = float(np.sqrt(np.mean((np.linalg.norm(accel, axis=1) - _G) ** 2)))
    spin = float(np.linalg.norm(gyro.mean(axis=0)))
    signs = [
        f"gyro std {spread:.3f} rad/s > {STATIC_GYRO_STD:g}" if spread > STATIC_GYRO_STD else "",
        f"RMS of |accel| - {_G:g} {shake:.3f} m/s^2 > {STATIC_ACCEL_RMS:g}" if shake > STATIC_ACCEL_RMS else "",
        f"mean rate {spin:.3f} rad/s > {STATIC_MEAN_RATE:g}" if spin > STATIC_MEAN_RATE else "",
    ]
    if any(signs):
        note(f"the first {static_seconds} s do not look static ({'; '.join(filter(None, signs))}); levelling anyway")
    ax, ay, az = accel.mean(axis=0)
    pitch = float(np.arctan2(-ax, np.hypot(ay, az)))
    roll = float(np.arctan2(ay, az))
    return NavState(np.zeros(3), np.zeros(3), Rotation.from_euler("ZYX", [0.0, pitch, roll]))
