"""evo, the reference trajectory tool, reads the files imukit writes: the same stamps, positions and
quaternions, bit for bit (TUM with float seconds and with nanoseconds; EuRoC ground truth); and imukit
reads evo's TUM and KITTI files to the same bits."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
from evo.core.trajectory import PoseTrajectory3D
from evo.tools import file_interface
from scipy.spatial.transform import Rotation

import imukit as ik

from conftest import assert_quat_close

EPOCH = 1_403_636_579_758_555_392


def random_trajectory(rng: np.random.Generator, n: int, **kwargs: object) -> ik.Trajectory:
    position = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-8, 6, size=(n, 3))
    return ik.Trajectory(
        kwargs.pop("t", None), position, rng.normal(size=(n, 3)), Rotation.random(n, rng=rng), **kwargs,  # type: ignore[arg-type]
    )  # fmt: skip


def assert_same_bits(a: np.ndarray, b: np.ndarray) -> None:
    assert a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


def test_evo_reads_tum_with_float_seconds_bit_for_bit(tmp_path: Path, rng: np.random.Generator) -> None:
    t = np.cumsum(rng.uniform(1e-3, 1e-2, 500))
    traj = random_trajectory(rng, 500, t=t)
    traj.write_tum(tmp_path / "traj.txt")
    evo = file_interface.read_tum_trajectory_file(str(tmp_path / "traj.txt"))
    assert_same_bits(evo.timestamps, t)
    assert_same_bits(evo.positions_xyz, traj.position)
    assert_same_bits(evo.orientations_quat_wxyz, traj.rotation.as_quat(scalar_first=True))


def test_evo_reads_tum_with_nanoseconds_to_the_nearest_float(tmp_path: Path, rng: np.random.Generator) -> None:
    t_ns = EPOCH + np.cumsum(rng.integers(4_999_000, 5_001_000, 300))
    traj = random_trajectory(rng, 300, t_ns=t_ns)
    traj.write_tum(tmp_path / "traj.txt")
    evo = file_interface.read_tum_trajectory_file(str(tmp_path / "traj.txt"))
    # The text is exact to 1 ns; a float64 at 1.4e9 s resolves 238 ns, so evo gets the float nearest to
    # t_ns / 1e9, computed here with exact fractions, which is imukit's Trajectory.t too.
    nearest = np.array([float(Fraction(int(ns), 10**9)) for ns in t_ns])
    assert_same_bits(evo.timestamps, nearest)
    assert_same_bits(evo.timestamps, traj.t)
    assert np.abs(evo.timestamps - t_ns * 1e-9).max() <= 2.4e-7
    assert_same_bits(evo.positions_xyz, traj.position)
    assert_same_bits(evo.orientations_quat_wxyz, traj.rotation.as_quat(scalar_first=True))


def test_evo_reads_euroc_ground_truth(tmp_path: Path, rng: np.random.Generator) -> None:
    n = 400
    t_ns = EPOCH + 3168 + np.cumsum(rng.integers(4_999_680, 5_000_193, n))
    zeros = np.zeros((n, 3))
    truth = random_trajectory(rng, n, t_ns=t_ns, gyro_bias=zeros, accel_bias=zeros)
    imu = ik.ImuData(t_ns, zeros, zeros)
    ik.io.write_euroc(tmp_path, imu, truth)
    evo = file_interface.read_euroc_csv_trajectory(str(tmp_path / "state_groundtruth_estimate0" / "data.csv"))
    # evo parses the 19-digit stamp as a float (to 256 ns) and divides by 1e9: exactly that, and within 256 ns.
    assert_same_bits(evo.timestamps, t_ns.astype(np.float64) / 1e9)
    assert np.abs(evo.timestamps - truth.t).max() <= 2.6e-7
    assert_same_bits(evo.positions_xyz, truth.position)
    assert_same_bits(evo.orientations_quat_wxyz, truth.rotation.as_quat(scalar_first=True))


def test_imukit_reads_evo_written_tum_and_kitti_files(tmp_path: Path, rng: np.random.Generator) -> None:
    # The other direction: evo writes (numpy's '%.18e', 19 significant digits), imukit reads the same floats.
    t = 1.4e9 + np.cumsum(rng.uniform(1e-3, 1e-2, 200))
    traj = random_trajectory(rng, 200, t=t)
    quat_wxyz = traj.rotation.as_quat(scalar_first=True)
    evo = PoseTrajectory3D(traj.position, quat_wxyz, t)
    file_interface.write_tum_trajectory_file(str(tmp_path / "evo.txt"), evo)
    back = ik.io.read_tum(tmp_path / "evo.txt")
    assert back.t_ns is None
    assert_same_bits(back.t, t)
    assert_same_bits(back.position, traj.position)
    assert_same_bits(back.rotation.as_quat(scalar_first=True), quat_wxyz)
    file_interface.write_kitti_poses_file(str(tmp_path / "poses.txt"), evo)
    (tmp_path / "times.txt").write_text("".join(f"{x!r}\n" for x in t.tolist()))
    kitti = ik.io.read_kitti_poses(tmp_path / "poses.txt", tmp_path / "times.txt")
    assert_same_bits(kitti.t, t)
    assert_same_bits(kitti.position, traj.position)
    # Through a rotation matrix and back: the same rotation to rounding.
    assert_quat_close(kitti.rotation.as_quat(), traj.rotation.as_quat(), atol=1e-15)
