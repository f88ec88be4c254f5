"""Real data: EuRoC V1_02_medium gyro, bias-corrected with the ground-truth bias, integrated from
the ground-truth attitude, stays within 1° of the ground truth over the whole 38 s overlap."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

import imukit as ik

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "euroc_v1_02_medium"

# The ground-truth gyro bias at the start of the overlap (first data row), rad/s.
GT_BIAS_AT_START = np.array([-0.002153, 0.020744, 0.075806])

pytestmark = pytest.mark.skipif(
    not (DATA / "imu0_data_first40s.csv").exists(),
    reason=f"EuRoC excerpt not found at {DATA} (it lives in the team's shared/ folder, not in the repo)",
)


def _load() -> tuple[np.ndarray, np.ndarray, Rotation, np.ndarray]:
    imu = np.loadtxt(DATA / "imu0_data_first40s.csv", delimiter=",", comments="#", dtype=np.float64)
    gt = np.loadtxt(DATA / "state_groundtruth_estimate0_data.csv", delimiter=",", comments="#", dtype=np.float64)
    # Timestamps are int64 ns; float64 cannot hold them exactly, so re-read the first column.
    t_imu = np.loadtxt(DATA / "imu0_data_first40s.csv", delimiter=",", comments="#", usecols=0, dtype=np.int64)
    t_gt = np.loadtxt(
        DATA / "state_groundtruth_estimate0_data.csv", delimiter=",", comments="#", usecols=0, dtype=np.int64
    )
    keep = (t_imu >= t_gt[0]) & (t_imu <= t_gt[-1])
    t_imu, gyro = t_imu[keep], imu[keep, 1:4]
    origin = t_imu[0]
    gt_s = (t_gt - origin) * 1e-9
    imu_s = (t_imu - origin) * 1e-9
    truth = Slerp(gt_s, Rotation.from_quat(gt[:, 4:8], scalar_first=True))(imu_s)
    bias = np.stack([np.interp(imu_s, gt_s, gt[:, 11 + i]) for i in range(3)], axis=-1)
    return t_imu, gyro - bias, truth, imu_s


@pytest.mark.parametrize("scheme", ["midpoint", "rk4", "magnus"])
def test_euroc_attitude_error_under_one_degree(scheme: str) -> None:
    t_ns, gyro, truth, seconds = _load()
    assert seconds[-1] > 38.0  # the whole overlap is used
    estimate = ik.integrate_attitude(t_ns, gyro, initial=truth[0], scheme=scheme)
    error_deg = np.degrees((truth.inv() * estimate).magnitude())
    assert error_deg.max() < 1.0, f"{scheme}: max error {error_deg.max():.3f}° at {seconds[error_deg.argmax()]:.1f} s"
    # and the test can fail: without the bias correction the error is several degrees
    raw = ik.integrate_attitude(t_ns, gyro + GT_BIAS_AT_START, initial=truth[0], scheme=scheme)
    assert np.degrees((truth.inv() * raw).magnitude()).max() > 5.0
