"""read_imu_csv: the real x-io file in deg/s and g against its raw numbers, column names and indices, time
units (exact integer nanoseconds where possible), delimiters, bad lines and bad arguments."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from euroc import DATA
from imukit.io import ReadReport, SkippedLine

XIO = DATA.parent / "xio_fusion_example" / "sensor_data.csv"
requires_xio = pytest.mark.skipif(
    not XIO.exists(), reason=f"x-io example not found at {XIO} (team's shared/ folder, not the repo)"
)
GYRO = ["Gyroscope X (deg/s)", "Gyroscope Y (deg/s)", "Gyroscope Z (deg/s)"]
ACCEL = ["Accelerometer X (g)", "Accelerometer Y (g)", "Accelerometer Z (g)"]


@requires_xio
def test_real_xio_file_in_degrees_and_g() -> None:
    imu = ik.io.read_imu_csv(
        XIO, time_column="Time (s)", gyro_columns=GYRO, accel_columns=ACCEL, gyro_unit="deg/s", accel_unit="g"
    )
    raw = np.loadtxt(XIO, delimiter=",", skiprows=1)
    assert len(imu) == 13514 == len(raw) and imu.t_ns is None
    np.testing.assert_array_equal(imu.t, raw[:, 0])
    np.testing.assert_array_equal(imu.gyro, raw[:, 1:4] * (np.pi / 180.0))
    np.testing.assert_array_equal(imu.accel, raw[:, 4:7] * 9.80665)
    # The first row by hand: 0.01644619 deg/s, 0.9970807 g.
    assert imu.gyro[0, 0] == 0.01644619 * (np.pi / 180.0) and abs(imu.gyro[0, 0] - 2.8704e-4) < 1e-8
    assert imu.accel[0, 2] == 0.9970807 * 9.80665 and abs(imu.accel[0, 2] - 9.7780) < 1e-4
    # Indices give the same; a custom g scales linearly.
    by_index = ik.io.read_imu_csv(
        XIO, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6], gyro_unit="deg/s", accel_unit="g",
        standard_gravity=9.81,
    )  # fmt: skip
    np.testing.assert_array_equal(by_index.gyro, imu.gyro)
    np.testing.assert_array_equal(by_index.accel, raw[:, 4:7] * 9.81)


def test_integer_milliseconds_become_exact_nanoseconds(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    path.write_text("t_ms;gx;gy;gz;ax;ay;az\n1700000000000;1;2;3;4;5;6\n1700000000010;1;2;3;4;5;6\n")
    imu = ik.io.read_imu_csv(
        path, time_column="t_ms", gyro_columns=["gx", "gy", "gz"], accel_columns=["ax", "ay", "az"], time_unit="ms"
    )
    assert imu.t_ns is not None and imu.t_ns.tolist() == [1_700_000_000_000_000_000, 1_700_000_000_010_000_000]
    np.testing.assert_array_equal(imu.accel, [[4.0, 5.0, 6.0]] * 2)


def test_time_units(tmp_path: Path) -> None:
    path = tmp_path / "imu.txt"
    cols = {"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}
    path.write_text("  1500  0 0 0 0 0 9.8\n\t2500\t0 0 0 0 0 9.8\n")  # white space, integer microseconds
    imu = ik.io.read_imu_csv(path, time_unit="us", **cols)  # type: ignore[arg-type]
    assert imu.t_ns is not None and imu.t_ns.tolist() == [1_500_000, 2_500_000]
    path.write_text("1.5,0,0,0,0,0,9.8\n2.5,0,0,0,0,0,9.8\n")  # float milliseconds: one division by 1000
    imu = ik.io.read_imu_csv(path, time_unit="ms", **cols)  # type: ignore[arg-type]
    assert imu.t_ns is None and imu.t.tolist() == [1.5 / 1000, 2.5 / 1000] == [0.0015, 0.0025]
    path.write_text("1403715523912140000,0,0,0,0,0,9.8\n1403715523917140000,0,0,0,0,0,9.8\n")
    imu = ik.io.read_imu_csv(path, time_unit="ns", **cols)  # type: ignore[arg-type]
    assert imu.t_ns is not None and imu.t_ns.tolist() == [1403715523912140000, 1403715523917140000]
    path.write_text("0,0,0,0,0,0,9.8\n0.010078907,0,0,0,0,0,9.8\n")  # seconds, as x-io writes them
    assert ik.io.read_imu_csv(path, **cols).t.tolist() == [0.0, 0.010078907]  # type: ignore[arg-type]


def test_header_with_hash_extra_columns_and_comments(tmp_path: Path) -> None:
    # EuRoC's own header names work; columns in any order; columns not asked for are not parsed.
    path = tmp_path / "data.csv"
    path.write_text(
        "#timestamp [ns],temp,w_x,w_y,w_z,a_x,a_y,a_z\n# a comment\n\n"
        "1403715523912140000,n/a,0.1,0.2,0.3,9.1,9.2,9.3\n1403715523917140000,25.0,-0.1,-0.2,-0.3,-9.1,-9.2,-9.3\n"
    )
    imu = ik.io.read_imu_csv(
        path, time_column="timestamp [ns]", gyro_columns=["w_z", "w_y", "w_x"], accel_columns=[5, 6, 7],
        time_unit="ns",
    )  # fmt: skip
    np.testing.assert_array_equal(imu.gyro, [[0.3, 0.2, 0.1], [-0.3, -0.2, -0.1]])
    np.testing.assert_array_equal(imu.accel, [[9.1, 9.2, 9.3], [-9.1, -9.2, -9.3]])


def test_skip_mode_reports_each_bad_line(tmp_path: Path) -> None:
    text = [
        "time,gx,gy,gz,ax,ay,az,mag",
        "0.00,1,2,3,4,5,6,7",
        "0.01,1,2,3,4,5",
        "0.02,1,2,three,4,5,6,7",
        "0.03,1,2,3,4,5,-inf,7",
        "0.04,1,2,3,4,5,6,x",
        "0.04,9,9,9,9,9,9,9",
        "0.035,9,9,9,9,9,9,9",
        "0.05,1,2,3,4,5,6,7",
    ]
    path = tmp_path / "imu.csv"
    path.write_text("\n".join(text) + "\n")
    report = ReadReport()
    imu = ik.io.read_imu_csv(
        path, time_column="time", gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6], on_bad_line="skip", report=report
    )
    np.testing.assert_array_equal(imu.t, [0.0, 0.04, 0.05])  # line 6's unread mag column 'x' is no problem
    p = str(path)
    assert report.skipped == [
        SkippedLine(p, 3, "wrong column count: expected 8 fields (the header has 8), got 6", text[2]),
        SkippedLine(p, 4, f"malformed: not a number in {text[3]!r}", text[3]),
        SkippedLine(p, 5, f"non-finite: non-finite value in {text[4]!r}", text[4]),
        SkippedLine(p, 7, "duplicate stamp: time must increase strictly, but 0.04 follows 0.04 (line 6)", text[6]),
        SkippedLine(p, 8, "stamp going back: time must increase strictly, but 0.035 follows 0.04 (line 6)", text[7]),
    ]


COLS = {"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}


@pytest.mark.parametrize(
    ("text", "options", "message"),
    [
        (
            "0.0,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n0.2,1,2,3",
            {},
            r", line 3: expected 7 fields \(the first data line has 7\), got 4$",
        ),
        ("t,gx,gy,gz,ax,ay,az\n", {}, r": no data lines$"),
        ("", {}, r": no data lines$"),
        ("0.0,1,2,3,4,5,6\n0.1,1,2,3,4,5,6,7\n", {}, r", line 2: expected 7 fields .*got 8$"),
        ("0,1,2,3,4,5,6\n0.1,1,2,x,4,5,6\n", {}, r", line 2: not a number in '0\.1,1,2,x,4,5,6'$"),
        ("0,1,2,3,4,5,nan\n", {}, r", line 1: non-finite value in '0,1,2,3,4,5,nan'$"),
        ("0,1,2,3,4,5,6\n0,1,2,3,4,5,6\n", {}, r", line 2: time must increase strictly, but 0 follows 0 \(line 1\)$"),
        ("1.0,1,2,3,4,5,6\n0.5,1,2,3,4,5,6\n", {}, r", line 2: time must increase strictly, but 0\.5 follows 1\.0 "),
        ("1.5,1,2,3,4,5,6\n", {"time_unit": "ns"}, r", line 1: time '1\.5' is not an integer number of nanosec"),
    ],
)
def test_malformed_files_name_file_and_line(tmp_path: Path, text: str, options: dict[str, str], message: str) -> None:
    path = tmp_path / "imu.csv"
    path.write_text(text)
    with pytest.raises(ik.io.FileFormatError, match=f"^path: {re.escape(str(path))}{message}"):
        ik.io.read_imu_csv(path, **{**COLS, **options})  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"gyro_unit": "dps"}, r"^gyro_unit: expected one of \('rad/s', 'deg/s'\), got 'dps'$"),
        ({"accel_unit": "m/s2"}, r"^accel_unit: expected one of \('m/s\^2', 'g', 'mg'\), got 'm/s2'$"),
        ({"time_unit": "sec"}, r"^time_unit: expected one of \('s', 'ms', 'us', 'ns'\), got 'sec'$"),
        ({"delimiter": "|"}, r"^delimiter: expected one of \(',', ';', '\\t', ' '\), got '\|'$"),
        ({"standard_gravity": 0.0}, r"^standard_gravity: expected a positive, finite number of m/s\^2 per g, got 0\.0"),
        ({"gyro_columns": [1, 2]}, r"^gyro_columns: expected 3 column names or 0-based .*got \[1, 2\]$"),
        ({"gyro_columns": "gx"}, r"^gyro_columns: expected 3 column names or 0-based indices .*got 'gx'$"),
        ({"accel_columns": [4, 5, -6]}, r"^accel_columns: expected a column name or a 0-based index .*got -6$"),
        ({"time_column": True}, r"^time_column: expected a column name or a 0-based index \(int ≥ 0\), got True$"),
        ({"time_column": ["t"]}, r"^time_column: expected a column name or a 0-based index \(int ≥ 0\), got \['t'\]$"),
        ({"accel_columns": [4, 5, 7]}, r"^accel_columns: column 7 is out of range: .*imu\.csv has 7 columns \(0-based"),
        ({"time_column": "time"}, r"^time_column: no column named 'time' in the header of .*imu\.csv \(line 2\), "
                                  r"which has 't \[s\]', 'gx', 'gy', 'gz', 'ax', 'ay', 'az'$"),
    ],
)  # fmt: skip
def test_bad_arguments_name_the_argument(tmp_path: Path, options: dict[str, object], message: str) -> None:
    path = tmp_path / "imu.csv"
    path.write_text("\nt [s],gx,gy,gz,ax,ay,az\n0,1,2,3,4,5,6\n")
    with pytest.raises(ik.ParameterError, match=message):
        ik.io.read_imu_csv(path, **{**COLS, **options})  # type: ignore[arg-type]


def test_names_without_a_header_line(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    path.write_text("0,1,2,3,4,5,6\n")
    with pytest.raises(ik.ParameterError, match=r"^gyro_columns: column 'gx' is a name, but .*imu\.csv has no header"):
        ik.io.read_imu_csv(path, time_column=0, gyro_columns=["gx", "gy", "gz"], accel_columns=[4, 5, 6])


@pytest.mark.parametrize(
    ("text", "delimiter"),
    [
        ("t;gx;gy;gz;ax;ay;az\n0,5;1;2;3;4;5;6\n", None),  # ';' wins over the decimal comma, which is then refused
        ("t,gx,gy,gz,ax,ay,az\n0.5,1,2,3,4,5,6\n", None),
        ("t gx gy gz ax ay az\n0.5  1 2\t3 4 5 6\n", None),
        ("t\tgx\tgy\tgz\tax\tay\taz\n0.5\t1\t2\t3\t4\t5\t6\n", "\t"),
        ("t gx gy gz ax ay az\n0.5 1 2 3 4 5 6\n", " "),
    ],
)
def test_delimiters(tmp_path: Path, text: str, delimiter: str | None) -> None:
    path = tmp_path / "imu.csv"
    path.write_text(text)
    read = {"time_column": "t", "gyro_columns": ["gx", "gy", "gz"], "accel_columns": ["ax", "ay", "az"]}
    if "0,5" in text:
        with pytest.raises(ik.io.FileFormatError, match=r", line 2: not a number in '0,5;1;2;3;4;5;6'"):
            ik.io.read_imu_csv(path, **read, delimiter=delimiter)  # type: ignore[arg-type]
        return
    imu = ik.io.read_imu_csv(path, **read, delimiter=delimiter)  # type: ignore[arg-type]
    assert imu.t.tolist() == [0.5]
    np.testing.assert_array_equal(imu.gyro, [[1.0, 2.0, 3.0]])
    np.testing.assert_array_equal(imu.accel, [[4.0, 5.0, 6.0]])


def test_an_acceleration_in_g_that_overflows_is_a_bad_line(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    path.write_text("0.0,1,2,3,0,0,1\n0.01,1,2,3,0,0,1e308\n0.02,1,2,3,0,0,1\n")
    report = ReadReport()
    imu = ik.io.read_imu_csv(path, **COLS, accel_unit="g", on_bad_line="skip", report=report)  # type: ignore[arg-type]
    assert imu.t.tolist() == [0.0, 0.02]
    reason = "non-finite: acceleration (0.0, 0.0, 1e+308) g overflows float64 in m/s^2"
    assert report.skipped == [SkippedLine(str(path), 2, reason, "0.01,1,2,3,0,0,1e308")]
    # In m/s^2 the same number is finite and kept.
    assert len(ik.io.read_imu_csv(path, **COLS)) == 3  # type: ignore[arg-type]


def test_byte_order_mark_is_not_part_of_the_first_column_name(tmp_path: Path) -> None:
    # Excel's "CSV UTF-8" export: a byte order mark, then the header; "time" must still name column 0.
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbftime;gx;gy;gz;ax;ay;az\r\n0.5;1;2;3;4;5;6\r\n0.75;-1;-2;-3;-4;-5;-6\r\n")
    imu = ik.io.read_imu_csv(
        path, time_column="time", gyro_columns=["gx", "gy", "gz"], accel_columns=["ax", "ay", "az"]
    )
    assert imu.t.tolist() == [0.5, 0.75]
    assert imu.gyro.tolist() == [[1.0, 2.0, 3.0], [-1.0, -2.0, -3.0]]
    assert imu.accel.tolist() == [[4.0, 5.0, 6.0], [-4.0, -5.0, -6.0]]
