"""GTSAM / KITTI IMU text: the real KITTI 00 file (orphan first sample and its 1.92 s gap kept), the
column order (accel before omega), the dt column checked against the stamps, and bad lines."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from euroc import DATA
from imukit.io import ReadReport, SkippedLine

from conftest import assert_file_error

KITTI = DATA.parent / "kitti_gtsam"
KITTI_IMU = KITTI / "KittiEquivBiasedImu.txt"
requires_kitti = pytest.mark.skipif(
    not KITTI_IMU.exists(), reason=f"GTSAM's KITTI IMU file not found at {KITTI} (team's shared/ folder, not the repo)"
)
HEADER = "Time dt accelX accelY accelZ omegaX omegaY omegaZ"


@requires_kitti
def test_real_kitti_file() -> None:
    imu = ik.io.read_gtsam_imu(KITTI_IMU)
    raw = np.loadtxt(KITTI_IMU, skiprows=1)  # an independent parse of the same text
    assert len(imu) == 46968 == len(raw) and imu.t_ns is None
    np.testing.assert_array_equal(imu.t, raw[:, 0])
    np.testing.assert_array_equal(imu.accel, raw[:, 2:5])
    np.testing.assert_array_equal(imu.gyro, raw[:, 5:8])
    # The first line, by hand: accel then omega.
    assert imu.t[0] == 46534.47837579
    np.testing.assert_array_equal(imu.accel[0], [1.7114864219577, 0.1717911743144, 9.80533438749])
    np.testing.assert_array_equal(imu.gyro[0], [-0.0032006241515747, 0.031231284764596, -0.0063569265706488])
    # The orphan first sample is kept, and the 1.92 s gap after it is there, not closed.
    assert imu.t[1] == 46536.397971133
    assert imu.dt[0] == 46536.397971133 - 46534.47837579 and 1.9195 < imu.dt[0] < 1.9196
    assert imu.dt[1:].max() < 0.02  # ~100 Hz after it, with jitter up to 20 ms
    # The file's dt[k] is t[k] - t[k-1]: ImuData's step lengths are those (GTSAM holds sample k over the
    # step before it, imukit over the step after it: same lengths, samples shifted by one).
    np.testing.assert_allclose(imu.dt, raw[1:, 1], rtol=0, atol=2e-11)
    with pytest.raises(ik.TimestampError, match=r"^t: gap into sample 1 has dt = 1\.9195953"):
        ik.ImuData(imu.t, imu.gyro, imu.accel, max_gap=0.05)


def test_small_file_with_and_without_header(tmp_path: Path) -> None:
    rows = ["10.0 10.0 1 2 3 0.1 0.2 0.3", "10.01 0.01 4 5 6 0.4 0.5 0.6", "10.03 0.02 7 8 9 0.7 0.8 0.9"]
    for header in ([HEADER], []):
        path = tmp_path / "imu.txt"
        path.write_text("\n".join([*header, *rows]) + "\n")
        imu = ik.io.read_gtsam_imu(path)
        np.testing.assert_array_equal(imu.t, [10.0, 10.01, 10.03])
        np.testing.assert_array_equal(imu.accel, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
        np.testing.assert_array_equal(imu.gyro, [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6], [0.7, 0.8, 0.9]])


def test_dt_that_disagrees_with_the_stamps_is_an_error_in_both_modes(tmp_path: Path) -> None:
    # dt as the step AFTER each sample (the other convention): line 3 says 0.02 where t stepped 0.01.
    path = tmp_path / "imu.txt"
    path.write_text(f"{HEADER}\n10.0 0.01 1 2 3 4 5 6\n10.01 0.02 1 2 3 4 5 6\n10.03 0.01 1 2 3 4 5 6\n")
    message = (
        rf"^path: {re.escape(str(path))}, line 3: dt = 0\.02 s, but the stamps step by 0\.0099999999999\d* s since "
        r"line 2; read_gtsam_imu expects GTSAM's dt\[k\] = t\[k\] - t\[k-1\]"
    )
    for mode in ("raise", "skip"):
        with pytest.raises(ik.io.FileFormatError, match=message):
            ik.io.read_gtsam_imu(path, on_bad_line=mode, report=ReadReport())  # type: ignore[arg-type]
    # The way out the message names: read_imu_csv, which reads the stamps and ignores dt.
    imu = ik.io.read_imu_csv(path, time_column=0, gyro_columns=[5, 6, 7], accel_columns=[2, 3, 4])
    np.testing.assert_array_equal(imu.t, [10.0, 10.01, 10.03])
    np.testing.assert_array_equal(imu.gyro, [[4.0, 5.0, 6.0]] * 3)
    # Off by 1.1 µs fails, by 0.9 µs passes: the tolerance is 1 µs.
    path.write_text(f"10.0 0 1 2 3 4 5 6\n10.5 {0.5 + 1.1e-6!r} 1 2 3 4 5 6\n")
    with pytest.raises(ik.io.FileFormatError, match=r", line 2: dt = 0\.5000011 s"):
        ik.io.read_gtsam_imu(path)
    path.write_text(f"10.0 0 1 2 3 4 5 6\n10.5 {0.5 + 0.9e-6!r} 1 2 3 4 5 6\n")
    assert len(ik.io.read_gtsam_imu(path)) == 2


def test_dt_after_a_skipped_line_is_not_checked(tmp_path: Path) -> None:
    # Line 4 is skipped; line 5's dt (0.01) is the step from line 4, not from line 3: it is not checked.
    text = [
        HEADER,
        "10.0 10.0 1 2 3 4 5 6",
        "10.01 0.01 1 2 3 4 5 6",
        "10.02 0.01 1 2 x 4 5 6",
        "10.03 0.01 1 2 3 4 5 6",
    ]
    path = tmp_path / "imu.txt"
    path.write_text("\n".join(text) + "\n")
    report = ReadReport()
    imu = ik.io.read_gtsam_imu(path, on_bad_line="skip", report=report)
    np.testing.assert_array_equal(imu.t, [10.0, 10.01, 10.03])
    assert report.skipped == [SkippedLine(str(path), 4, f"malformed: not a number in {text[3]!r}", text[3])]


def test_skip_mode_reports_each_bad_line(tmp_path: Path) -> None:
    text = [
        HEADER,
        "1.0 1.0 1 2 3 4 5 6",
        "1.01 0.01 1 2 3 4 5",
        "1.01 0.01 1 2 3 4 5 inf",
        "1.02 0.02 1 2 3 4 5 6",
        "1.02 0.0 9 9 9 9 9 9",
        "1.015 -0.005 9 9 9 9 9 9",
        "1.03 0.01 7 8 9 1 2 3",
        "1.04 0.01 7 8",
    ]
    path = tmp_path / "imu.txt"
    path.write_text("\n".join(text) + "\n")
    report = ReadReport()
    imu = ik.io.read_gtsam_imu(path, on_bad_line="skip", report=report)
    np.testing.assert_array_equal(imu.t, [1.0, 1.02, 1.03])
    np.testing.assert_array_equal(imu.accel[:, 0], [1.0, 1.0, 7.0])
    p = str(path)
    count = "wrong column count: expected 8 fields 'Time dt accelX accelY accelZ omegaX omegaY omegaZ'"
    assert report.skipped == [
        SkippedLine(p, 3, f"{count}, got 7", text[2]),
        SkippedLine(p, 4, f"non-finite: non-finite value in {text[3]!r}", text[3]),
        SkippedLine(p, 6, "duplicate stamp: time must increase strictly, but 1.02 follows 1.02 (line 5)", text[5]),
        SkippedLine(p, 7, "stamp going back: time must increase strictly, but 1.015 follows 1.02 (line 5)", text[6]),
        SkippedLine(p, 9, f"{count}, got 4", text[8]),
    ]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            f"{HEADER}\n1.0 1.0 1 2 3 4 5 6\n1.01 0.01 1 2 3 4 5 6\n1.02 0.01 1 2 3",
            r", line 4: expected 8 fields .*got 5$",
        ),
        (f"{HEADER}\n", r": no data lines$"),
        (f"{HEADER}\n1.0 1.0 1 2 3 4 5 6 7\n", r", line 2: expected 8 fields 'Time dt accelX .*got 9$"),
        ("1.0 1.0 1 2 3 4 5 6\n1.01 0.01 1 2 3 four 5 6\n", r", line 2: not a number in '1\.01 0\.01 1 2 3 four 5 6'$"),
        ("1.0 1.0 1 2 3 4 5 nan\n", r", line 1: non-finite value in"),
        ("1.0 1.0 1 2 3 4 5 6\n1.0 0.0 1 2 3 4 5 6\n", r", line 2: time must increase strictly, but 1\.0 follows 1\.0"),
        ("1.0 1.0 1 2 3 4 5 6\n0.9 -0.1 1 2 3 4 5 6\n", r", line 2: time must increase strictly, but 0\.9 follows"),
        ("Time,dt,accelX,accelY,accelZ,omegaX,omegaY,omegaZ\n1.0 1 1 2 3 4 5 6\n", r", line 1: expected 8 fields"),
    ],
)
def test_malformed_files_name_file_and_line(tmp_path: Path, text: str, message: str) -> None:
    assert_file_error(tmp_path / "imu.txt", text, ik.io.read_gtsam_imu, message)


def test_byte_order_mark_before_the_header(tmp_path: Path) -> None:
    path = tmp_path / "imu.txt"
    path.write_bytes(f"\ufeff{HEADER}\n1.0 1.0 1 2 3 4 5 6\n1.01 0.01 1 2 3 4 5 6\n".encode())
    imu = ik.io.read_gtsam_imu(path)  # "raise" mode: the header must be recognised, not read as a bad line
    assert imu.t.tolist() == [1.0, 1.01]
