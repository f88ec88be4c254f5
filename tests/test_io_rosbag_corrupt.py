"""Issue 17, item 10: a bag of every container, written valid by rosbags, then one byte flipped at many
offsets (headers, index, chunk and message data alike): reading it returns valid data or raises an imukit
exception, never a foreign one (16 % of such bags leaked 13 foreign exception types before)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit.io import ReadReport, read_rosbag

pytest.importorskip("rosbags", reason="rosbags is the optional [ros] extra")
from test_io_rosbag import EPOCH_S, IMU, POSE, Bag

CONTAINERS = ["ros1", "ros1-lz4", "ros1-bz2", "sqlite3", "mcap-file"]
# Offsets per container: every byte of a 40-message bag would take minutes, these cover it evenly.
FLIPS = 48


def _valid_bag(tmp_path: Path, kind: str) -> Path:
    bag = Bag(kind)
    n = 40
    imu = [
        (EPOCH_S * 10**9 + k * 5_000_000, bag.imu((EPOCH_S, k * 5_000_000), (0.1, 0.2, k), (0.0, 0.0, 9.8)))
        for k in range(n)
    ]
    poses = [
        (EPOCH_S * 10**9 + k * 10_000_000, bag.pose((EPOCH_S, k * 10_000_000), (k, 0.0, 1.0), (0.0, 0.0, 0.0, 1.0)))
        for k in range(n // 2)
    ]
    return bag.write(tmp_path / "valid", {"/imu0": (IMU, imu), "/pose": (POSE, poses)})


def _data_file(bag: Path) -> Path:
    """The file holding the bytes of ``bag``: itself, or the storage file of a ROS 2 bag folder."""
    return bag if bag.is_file() else next(p for p in bag.iterdir() if p.suffix in (".db3", ".mcap"))


def _check(imu: ik.ImuData, truth: ik.Trajectory | None) -> None:
    assert len(imu) >= 1 and np.all(np.isfinite(imu.gyro)) and np.all(np.isfinite(imu.accel))
    assert np.all(np.diff(imu.t_ns) > 0)
    if truth is not None:
        assert np.all(np.isfinite(truth.position)) and np.all(np.diff(truth.t_ns) > 0)


@pytest.mark.parametrize("kind", CONTAINERS)
def test_flipped_bytes_give_valid_data_or_imukit_errors(tmp_path: Path, kind: str) -> None:
    valid = _valid_bag(tmp_path, kind)
    imu, truth = read_rosbag(valid)
    assert len(imu) == 40 and truth is not None and len(truth) == 20  # the bag is valid as written
    size = _data_file(valid).stat().st_size
    offsets = np.unique(np.linspace(0, size - 1, FLIPS).astype(int))
    outcomes: dict[str, int] = {}
    for k, offset in enumerate(offsets):
        copy = tmp_path / f"flip{offset}{valid.suffix}"
        (shutil.copytree if valid.is_dir() else shutil.copyfile)(valid, copy)
        data = bytearray(_data_file(copy).read_bytes())
        data[offset] ^= 0xFF
        _data_file(copy).write_bytes(data)
        try:
            _check(*read_rosbag(copy, on_bad_line="skip" if k % 2 else "raise", report=ReadReport()))
            outcomes["read"] = outcomes.get("read", 0) + 1
        except ik.ImukitError as exc:
            assert str(exc).startswith("path: "), exc
            outcomes[type(exc).__name__] = outcomes.get(type(exc).__name__, 0) + 1
    assert sum(outcomes.values()) == len(offsets) and "FileFormatError" in outcomes, outcomes
