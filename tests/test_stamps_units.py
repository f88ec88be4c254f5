"""Issue 17, item 6: microsecond integer stamps passed as nanoseconds are refused (an epoch 11.6-47 days
after 1970 at over 20 kHz: µs epochs of 2001-2100) or warned about (over 20 kHz alone), in ImuData and in
every IMU reader, naming the argument (and the file)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit import io

# 200 Hz from 2024-01-01 in microseconds: 1.7e15, read as ns 19.7 days after 1970 at 200 kHz.
US_EPOCH = 1_704_067_200_000_000 + np.arange(400) * 5_000
REST = (np.zeros((400, 3)), np.tile([0.0, 0.0, 9.81], (400, 1)))


def test_imu_data_refuses_microsecond_epochs() -> None:
    with pytest.raises(ik.TimestampError, match=r"^t: .*start 19\.7 days after 1970.*200 Hz from 2024-01-01"):
        ik.ImuData(US_EPOCH, *REST)
    with pytest.warns(UserWarning, match=r"^t: .*median step is 5000 ns.*200 Hz"):
        ik.ImuData(US_EPOCH - US_EPOCH[0], *REST)  # relative microseconds: only the rate tells


def test_plausible_nanoseconds_pass_silently() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ik.ImuData(US_EPOCH * 1000, *REST)  # the same instants in ns
        ik.ImuData(np.arange(400) * 50_000, *REST)  # 20 kHz, relative
        ik.ImuData(10**15 + np.arange(400) * 5_000_000, *REST)  # 11.6 days of uptime at 200 Hz


def _euroc_csv(path: Path, stamps: np.ndarray) -> Path:
    rows = "".join(f"{s},0.0,0.0,0.0,0.0,0.0,9.81\n" for s in stamps.tolist())
    path.write_text("#timestamp [ns],wx,wy,wz,ax,ay,az\n" + rows)
    return path


def test_readers_refuse_microsecond_epochs_naming_the_file(tmp_path: Path) -> None:
    path = _euroc_csv(tmp_path / "data.csv", US_EPOCH)
    columns = {"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}
    for read in (
        io.read_euroc_imu,
        io.read_imu,
        lambda p: io.read_imu_csv(p, **columns, time_unit="ns"),
    ):
        with pytest.raises(ik.FileFormatError, match=rf"^path: {path}: t: integer stamps are nanoseconds"):
            read(path)
    with pytest.warns(UserWarning, match=r"time_unit='us' overrides the header of .*'timestamp \[ns\]' \(ns\)"):
        imu = io.read_imu_csv(path, **columns, time_unit="us")  # the right unit reads, the header's is named
    assert imu.t_ns is not None and imu.t_ns[1] - imu.t_ns[0] == 5_000_000
    with pytest.warns(UserWarning, match="median step is 5000 ns"):
        io.read_euroc_imu(_euroc_csv(tmp_path / "relative.csv", US_EPOCH - US_EPOCH[0] + 1))


@pytest.mark.parametrize(
    ("first", "unit", "divisor"),
    [(1.7e12, "milliseconds", 1000), (1.7e15, "microseconds", 1000000), (1.7e18, "nanoseconds", 1000000000)],
)
def test_float_stamps_beyond_the_year_5138_name_their_likely_unit(first: float, unit: str, divisor: int) -> None:
    """Float epoch milliseconds were accepted as a 0.2 Hz recording before 2026-12-07."""
    t = first + np.arange(4) * 5.0 * divisor / 1000.0
    with pytest.raises(
        ik.TimestampError, match=rf"^t: float stamps are seconds, .*look like {unit} \(2023-11-1.*t / {divisor},"
    ) as info:
        ik.ImuData(t, np.zeros((4, 3)), np.zeros((4, 3)))
    assert info.value.argument == "t"
    ik.ImuData(t / divisor, np.zeros((4, 3)), np.zeros((4, 3)))  # in seconds it is an epoch of 2023
    with pytest.warns(UserWarning, match=r"^t: float stamps are seconds, but their median step is 5 s \(0.2 Hz\)"):
        ik.ImuData(np.arange(4) * 5.0, np.zeros((4, 3)), np.zeros((4, 3)))
