"""Where a dead-reckoning run starts: the ground truth at the first IMU sample, or at rest, levelled."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from imukit.cli._common import CliError, note
from imukit.imu import ImuBias, ImuData
from imukit.state import NavState, Trajectory


def _bracket(truth: Trajectory, t: float, t_ns: int | None) -> tuple[int, float]:
    """Index k and fraction f with ``t = (1 − f) t_k + f t_{k+1}``; ``f == 0`` when t is a stamp of truth."""
    if t_ns is not None and truth.t_ns is not None:
        k = int(np.searchsorted(truth.t_ns, t_ns, side="right")) - 1
        if truth.t_ns[k] == t_ns:
            return k, 0.0
    else:
        k = int(np.searchsorted(truth.t, t, side="right")) - 1
        if truth.t[k] == t:
            return k, 0.0
    return k, float((t - truth.t[k]) / (truth.t[k + 1] - truth.t[k]))


def _lerp(values: np.ndarray, k: int, f: float) -> np.ndarray:
    if f == 0.0:  # a stamp of the truth: its values exactly, not a rounded blend
        return np.array(values[k])
    return np.asarray((1.0 - f) * values[k] + f * values[k + 1])


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


def from_truth(truth: Trajectory, imu: ImuData) -> tuple[NavState, ImuBias | None]:
    """The ground-truth state (and biases, when it has them) at ``imu``'s first sample: position,
    velocity and biases interpolated linearly, rotation by slerp; taken exactly at a common stamp.
    A truth without velocity (TUM) gets it from its positions' central differences."""
    t_ns = None if imu.t_ns is None else int(imu.t_ns[0])
    k, f = _bracket(truth, float(imu.t[0]), t_ns)
    velocity = truth.velocity if truth.velocity is not None else np.gradient(truth.position, truth.t, axis=0)
    if f == 0.0:
        rotation = truth.rotation[k]
    else:
        rotation = Slerp(truth.t[k : k + 2], truth.rotation[k : k + 2])([float(imu.t[0])])[0]
    state = NavState(_lerp(truth.position, k, f), _lerp(velocity, k, f), rotation)
    if truth.gyro_bias is None or truth.accel_bias is None:
        return state, None
    return state, ImuBias(_lerp(truth.gyro_bias, k, f), _lerp(truth.accel_bias, k, f))


def levelled_at_rest(imu: ImuData, static_seconds: float) -> NavState:
    """At the origin, at rest, roll and pitch from the mean specific force over the first
    ``static_seconds`` (it points up at rest), yaw zero."""
    window = imu.seconds <= static_seconds
    if window.sum() < 2:
        raise CliError(f"--static-seconds: {static_seconds} s holds fewer than 2 IMU samples")
    ax, ay, az = imu.accel[window].mean(axis=0)
    spin = float(np.linalg.norm(imu.gyro[window].mean(axis=0)))
    if spin > 0.05:
        note(f"the first {static_seconds} s do not look static (mean rate {spin:.3f} rad/s); levelling anyway")
    pitch = float(np.arctan2(-ax, np.hypot(ay, az)))
    roll = float(np.arctan2(ay, az))
    return NavState(np.zeros(3), np.zeros(3), Rotation.from_euler("ZYX", [0.0, pitch, roll]))
