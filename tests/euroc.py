"""EuRoC V1_02_medium excerpt from the team's shared/ folder, with ground truth interpolated to the
IMU stamps. Tests using it skip with a reason when the folder is absent (a user's fresh clone)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "euroc_v1_02_medium"
IMU_CSV = DATA / "imu0_data_first40s.csv"
GT_CSV = DATA / "state_groundtruth_estimate0_data.csv"

requires_euroc = pytest.mark.skipif(
    not IMU_CSV.exists(),
    reason=f"EuRoC excerpt not found at {DATA} (it lives in the team's shared/ folder, not in the repo)",
)


@dataclass(frozen=True)
class Euroc:
    """IMU samples inside the ground-truth span, and ground truth at those stamps."""

    t_ns: np.ndarray  # (N,) int64
    seconds: np.ndarray  # (N,) since the first kept sample
    gyro: np.ndarray  # (N, 3) rad/s
    accel: np.ndarray  # (N, 3) m/s²
    position: np.ndarray  # (N, 3) m, world
    velocity: np.ndarray  # (N, 3) m/s, world
    rotation: Rotation  # (N,) R_wb
    gyro_bias: np.ndarray  # (N, 3)
    accel_bias: np.ndarray  # (N, 3)


def load() -> Euroc:
    imu = np.loadtxt(IMU_CSV, delimiter=",", comments="#")
    gt = np.loadtxt(GT_CSV, delimiter=",", comments="#")
    # float64 cannot hold 19-digit nanosecond stamps exactly: read the first column as int64.
    t_imu = np.loadtxt(IMU_CSV, delimiter=",", comments="#", usecols=0, dtype=np.int64)
    t_gt = np.loadtxt(GT_CSV, delimiter=",", comments="#", usecols=0, dtype=np.int64)
    keep = (t_imu >= t_gt[0]) & (t_imu <= t_gt[-1])
    t_imu, imu = t_imu[keep], imu[keep]
    seconds = (t_imu - t_imu[0]) * 1e-9
    gt_s = (t_gt - t_imu[0]) * 1e-9

    def interp(cols: slice) -> np.ndarray:
        return np.stack([np.interp(seconds, gt_s, c) for c in gt[:, cols].T], axis=-1)

    rotation = Slerp(gt_s, Rotation.from_quat(gt[:, 4:8], scalar_first=True))(seconds)
    return Euroc(
        t_imu,
        seconds,
        imu[:, 1:4],
        imu[:, 4:7],
        interp(slice(1, 4)),
        interp(slice(8, 11)),
        rotation,
        interp(slice(11, 14)),
        interp(slice(14, 17)),
    )
