"""Real layouts of issue 16, built here from their described shapes: a float-second `Time` CSV with
ROS-style names (`angular_velocity.x`, `linear_acceleration.x`, `magnetic_field.x`) found by
`read_imu`; a semicolon CSV with two header lines, the first ending in `;` (RepoIMU's T-stick
export); field-count mismatches named with both counts. Expected values are the numbers written."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit.io._named_csv import column_roles

ROS_NAMES = [
    "Time",
    *(f"angular_velocity.{a}" for a in "xyz"),
    *(f"linear_acceleration.{a}" for a in "xyz"),
    *(f"magnetic_field.{a}" for a in "xyz"),
]


def _values(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(n, 9)).round(6)


def test_ros_style_names_with_float_seconds_are_detected(tmp_path: Path) -> None:
    t = 1403715273.25 + np.arange(50) * 0.005
    values = _values(50, 1)
    path = tmp_path / "imu.csv"
    lines = [",".join(ROS_NAMES)] + [",".join([repr(float(s)), *map(repr, row.tolist())]) for s, row in zip(t, values)]
    path.write_text("\n".join(lines) + "\n")
    imu, truth = ik.io.read_imu(path)
    assert truth is None and imu.t_ns is None
    np.testing.assert_array_equal(imu.t, t)
    np.testing.assert_array_equal(imu.gyro, values[:, 0:3])
    np.testing.assert_array_equal(imu.accel, values[:, 3:6])


def test_column_roles_name_every_role_mag_included() -> None:
    roles = column_roles(ROS_NAMES)
    assert roles is not None
    assert roles.columns == {"time": [0], "gyro": [1, 2, 3], "accel": [4, 5, 6], "mag": [7, 8, 9]}
    assert roles.time_unit is None  # the names' units are read_imu_csv's to read
    xio = ["Time (s)", *(f"Gyroscope {a} (deg/s)" for a in "XYZ"), *(f"Accelerometer {a} (g)" for a in "XYZ")]
    roles = column_roles(xio)
    assert roles is not None and roles.columns == {"time": [0], "gyro": [1, 2, 3], "accel": [4, 5, 6]}
    roles = column_roles(["time_ns", "gx", "gy", "gz", "ax", "ay", "az"])  # a time name with its unit word
    assert roles is not None and roles.columns["time"] == [0]
    rostopic = ["%time", "field.header.stamp", *ROS_NAMES[1:7]]  # rostopic echo -p: header.stamp wins, in ns
    roles = column_roles([f"field.{n}" if "." in n and not n.startswith("field") else n for n in rostopic])
    assert roles is not None and roles.columns["time"] == [1] and roles.time_unit == "ns"
    assert column_roles(["Time", "gyro_x", "gyro_y", "ax", "ay", "az"]) is None  # no gyro z
    assert column_roles(["time", "Time (s)", "gx", "gy", "gz", "ax", "ay", "az"]) is None  # which time?


def test_rostopic_nanosecond_stamps_are_exact(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    header = "%time,field.header.stamp," + ",".join(f"field.{n}" for n in ROS_NAMES[1:7])
    rows = [
        "1403715273262142976,1403715273262142900,0.1,0.2,0.3,1,2,9.8",
        "1403715273267142976,1403715273267142900,0,0,0,0,0,9.8",
    ]
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    imu, _ = ik.io.read_imu(path)
    assert imu.t_ns is not None and imu.t_ns.tolist() == [1403715273262142900, 1403715273267142900]


REPOIMU = [  # RepoIMU T-stick: a group line ending in ';' over a names line, then 14 fields per line
    "Time [s];Orientation [];;;;Acceleration [m/s^2];;;Angular velocity [rad/s];;;Magnetic field [uT];;;",
    ";w;x;y;z;x;y;z;x;y;z;x;y;z",
]


def _repoimu(path: Path, n: int = 20) -> np.ndarray:
    rows = np.column_stack([np.arange(n) * 0.01, _values(n, 2)[:, :4], _values(n, 3)])
    path.write_text("\n".join(REPOIMU + [";".join(repr(v) for v in row.tolist()) for row in rows]) + "\n")
    return rows


def test_semicolon_csv_with_two_header_lines(tmp_path: Path) -> None:
    path = tmp_path / "TStick_Test01_Trial1.csv"
    rows = _repoimu(path)
    by_index = ik.io.read_imu_csv(path, time_column=0, gyro_columns=[8, 9, 10], accel_columns=[5, 6, 7])
    np.testing.assert_array_equal(by_index.t, rows[:, 0])
    np.testing.assert_array_equal(by_index.gyro, rows[:, 8:11])
    np.testing.assert_array_equal(by_index.accel, rows[:, 5:8])
    # the group line's name finds the time column; header_lines=2 says what detection found
    named = ik.io.read_imu_csv(path, time_column="Time [s]", gyro_columns=[8, 9, 10], accel_columns=[5, 6, 7])
    told = ik.io.read_imu_csv(path, time_column=0, gyro_columns=[8, 9, 10], accel_columns=[5, 6, 7], header_lines=2)
    for imu in (named, told):
        np.testing.assert_array_equal(imu.t, by_index.t)
        np.testing.assert_array_equal(imu.gyro, by_index.gyro)
    with pytest.raises(ik.ParameterError, match=r"^gyro_columns: 4 columns named 'x' in the header of .* \(line 2\)"):
        ik.io.read_imu_csv(path, time_column=0, gyro_columns=["x", "y", "z"], accel_columns=[5, 6, 7])


def test_trailing_delimiters_on_either_side(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    cols = {"time_column": "t", "gyro_columns": ["gx", "gy", "gz"], "accel_columns": ["ax", "ay", "az"]}
    for text in ("t;gx;gy;gz;ax;ay;az;\n0;1;2;3;4;5;6\n", "t;gx;gy;gz;ax;ay;az\n0;1;2;3;4;5;6;\n0.1;1;2;3;4;5;6;\n"):
        path.write_text(text)
        imu = ik.io.read_imu_csv(path, **cols)  # type: ignore[arg-type]
        np.testing.assert_array_equal(imu.gyro[0], [1, 2, 3])
        np.testing.assert_array_equal(imu.accel[0], [4, 5, 6])


def test_a_field_count_mismatch_names_both_counts(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    cols = {"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}
    path.write_text("t;gx;gy;gz;ax;ay;az;temp;;\n" + "0;1;2;3;4;5;6;20\n" * 3)  # two trailing ';'
    message = rf"^path: {re.escape(str(path))}: the header \(line 1\) has 10 fields, data lines 8: a trailing ';'\?"
    with pytest.raises(ik.FileFormatError, match=message):
        ik.io.read_imu_csv(path, **cols)  # type: ignore[arg-type]
    with pytest.raises(ik.FileFormatError, match=message):  # a file-level error in skip mode too
        ik.io.read_imu_csv(path, on_bad_line="skip", **cols)  # type: ignore[arg-type]
    path.write_text("t,gx,gy,gz,ax,ay,az,mx,my,mz\n" + "0,1,2,3,4,5,6\n" * 3)
    with pytest.raises(ik.FileFormatError, match=r"the header \(line 1\) has 10 fields, data lines 7 \(header_lines"):
        ik.io.read_imu_csv(path, **cols)  # type: ignore[arg-type]
    # the file read with a one-line header: the names line is the first data line, refused as such
    _repoimu(path)
    with pytest.raises(ik.FileFormatError, match=r", line 2: not a number in ';w;x;y;z"):
        ik.io.read_imu_csv(path, header_lines=1, **cols)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^header_lines: expected None or a number of lines"):
        ik.io.read_imu_csv(path, header_lines=-1, **cols)  # type: ignore[arg-type]


TF_NAMES = [
    "Time",
    "header.frame_id",
    *(f"transform.translation.{a}" for a in "xyz"),
    *(f"transform.rotation.{a}" for a in "xyzw"),
]


def _poses(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = 1403715273.0 + np.arange(n) * 0.05
    position = np.random.default_rng(4).normal(size=(n, 3)).round(6)
    xyzw = Rotation.random(n, random_state=5).as_quat()  # unit to rounding: kept bit for bit
    return t, position, xyzw


def _write_tf(path: Path, n: int = 30) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t, position, xyzw = _poses(n)
    lines = [",".join(TF_NAMES)] + [
        ",".join([repr(float(s)), "world", *map(repr, p.tolist()), *map(repr, q.tolist())])
        for s, p, q in zip(t, position, xyzw)
    ]
    path.write_text("\n".join(lines) + "\n")
    return t, position, xyzw


def test_a_transform_csv_is_read_by_its_names(tmp_path: Path) -> None:
    path = tmp_path / "vicon.csv"
    t, position, xyzw = _write_tf(path)
    detected = ik.io.read_trajectory(path)
    np.testing.assert_array_equal(detected.t, t)
    np.testing.assert_array_equal(detected.position, position)
    np.testing.assert_array_equal(detected.rotation.as_quat(), xyzw)
    assert detected.velocity is None
    named = ik.io.read_trajectory_csv(
        path,
        time_column="Time",
        position_columns=[f"transform.translation.{a}" for a in "xyz"],
        quaternion_columns=[f"transform.rotation.{a}" for a in "xyzw"],
    )
    np.testing.assert_array_equal(named.rotation.as_quat(), xyzw)
    # the same columns named w first: the order argument puts w last again
    wxyz = ik.io.read_trajectory_csv(
        path, time_column=0, position_columns=[2, 3, 4], quaternion_columns=[8, 5, 6, 7], quaternion_order="wxyz"
    )
    np.testing.assert_array_equal(wxyz.rotation.as_quat(), xyzw)


def test_read_trajectory_csv_units_errors_and_bad_lines(tmp_path: Path) -> None:
    path = tmp_path / "poses.txt"
    path.write_text("stamp_ns;x;y;z;qw;qx;qy;qz\n1000000000;1;2;3;1;0;0;0\n2000000000;4;5;6;0;0;0;0\n")
    cols = {"time_column": 0, "position_columns": [1, 2, 3], "quaternion_columns": [4, 5, 6, 7]}
    report = ik.io.ReadReport()
    traj = ik.io.read_trajectory_csv(
        path, time_unit="ns", quaternion_order="wxyz", on_bad_line="skip", report=report, **cols
    )  # type: ignore[arg-type]
    assert traj.t_ns is not None and traj.t_ns.tolist() == [10**9]
    assert [(s.line, s.reason) for s in report.skipped] == [(3, "zero quaternion: zero quaternion")]
    with pytest.raises(ik.ParameterError, match=r"^quaternion_order: expected one of \('xyzw', 'wxyz'\), got 'zyxw'"):
        ik.io.read_trajectory_csv(path, quaternion_order="zyxw", **cols)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^quaternion_columns: expected 4 column names or 0-based indices"):
        ik.io.read_trajectory_csv(path, time_column=0, position_columns=[1, 2, 3], quaternion_columns=[4, 5, 6])
    with pytest.raises(ik.ParameterError, match=r"^position_columns: no column named 'px' in the header"):
        ik.io.read_trajectory_csv(path, time_column=0, position_columns=["px", 2, 3], quaternion_columns=[4, 5, 6, 7])


XIO_HEADER = "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),Accelerometer X (g),"
XIO_HEADER += "Accelerometer Y (g),Accelerometer Z (g)"


def test_units_the_names_state_are_read_when_the_columns_are_given(tmp_path: Path) -> None:
    """x-io's names with no unit options read 1 g as 1.0 m/s² and deg/s as rad/s before 2026-12-07."""
    path = tmp_path / "sensor_data.csv"
    path.write_text(XIO_HEADER + "\n0.0,57.29577951308232,0,0,0,0,1\n0.01,0,0,0,0,0,1\n")
    columns = [f"Gyroscope {a} (deg/s)" for a in "XYZ"], [f"Accelerometer {a} (g)" for a in "XYZ"]
    for given in (
        {"gyro_columns": columns[0], "accel_columns": columns[1]},
        {"gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]},
    ):
        imu = ik.io.read_imu_csv(path, time_column=0, **given)  # type: ignore[arg-type]
        np.testing.assert_allclose(imu.gyro[0], [1.0, 0.0, 0.0], rtol=1e-15)
        np.testing.assert_array_equal(imu.accel[0], [0.0, 0.0, 9.80665])
    with pytest.warns(UserWarning, match=r"gyro_unit='rad/s' overrides the header .*'Gyroscope X \(deg/s\)' \(deg/s\)"):
        imu = ik.io.read_imu_csv(
            path, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6], gyro_unit="rad/s"
        )
    assert imu.gyro[0, 0] == 57.29577951308232  # as told


@pytest.mark.parametrize(
    ("header", "expected"),
    [
        ("t,gx [dps],gy [dps],gz [dps],ax [m/s²],ay [m/s²],az [m/s²]", ([np.pi / 180, 0, 0], [0, 0, 1.0])),
        ("time_ms,gx (rad/sec),gy,gz,ax [mg],ay [mg],az [mg]", ([1.0, 0, 0], [0, 0, 9.80665e-3])),
        (
            "timestamp [us],gyro_x [deg/sec],gyro_y [deg/sec],gyro_z [deg/sec],acc_x,acc_y,acc_z",
            ([np.pi / 180, 0, 0], [0, 0, 1.0]),
        ),
    ],
)
def test_header_units_by_their_common_spellings(
    tmp_path: Path, header: str, expected: tuple[list[float], list[float]]
) -> None:
    path = tmp_path / "imu.csv"
    path.write_text(header + "\n1000,1,0,0,0,0,1\n2000,1,0,0,0,0,1\n")
    if header.startswith("t,"):  # 1000 s apart: read as seconds, which the size of the step questions
        with pytest.warns(UserWarning, match=r"median step is 1000 s \(0.001 Hz\); if they are milliseconds"):
            imu, _ = ik.io.read_imu(path)
    else:
        imu, _ = ik.io.read_imu(path)
    np.testing.assert_allclose(imu.gyro[0], expected[0], rtol=1e-15)
    np.testing.assert_allclose(imu.accel[0], expected[1], rtol=1e-15)
    step = {"t,": 1000.0, "time_ms": 1.0, "timestamp [us]": 1e-3}[
        next(k for k in ("t,", "time_ms", "timestamp [us]") if header.startswith(k))
    ]
    assert imu.t[1] - imu.t[0] == pytest.approx(step, rel=1e-12)


@pytest.mark.parametrize(
    ("header", "argument", "message"),
    [
        (
            "t,gx [deg/h],gy [deg/h],gz [deg/h],ax,ay,az",
            "gyro_unit",
            r"'gx \[deg/h\]', whose unit imukit does not read",
        ),
        ("time [min],gx,gy,gz,ax,ay,az", "time_unit", r"'time \[min\]', whose unit imukit does not read"),
        (
            "t,gx (deg/s),gy (rad/s),gz,ax,ay,az",
            "gyro_unit",
            r"states different units .*'gx \(deg/s\)' \(deg/s\), 'gy \(rad/s\)'",
        ),
    ],
)
def test_header_units_it_cannot_read_are_refused(tmp_path: Path, header: str, argument: str, message: str) -> None:
    """Before 2026-12-07 an unknown unit silently meant rad/s, m/s² or s, and only x's was looked at."""
    path = tmp_path / "imu.csv"
    path.write_text(header + "\n0,1,0,0,0,0,1\n1,1,0,0,0,0,1\n")
    for read in (
        lambda: ik.io.read_imu(path),
        lambda: ik.io.read_imu_csv(path, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6]),
    ):
        with pytest.raises(ik.ParameterError, match=message) as info:
            read()
        assert info.value.argument == argument
    if "different" not in message:  # a unit given says what the column holds
        ik.io.read_imu_csv(
            path,
            time_column=0,
            gyro_columns=[1, 2, 3],
            accel_columns=[4, 5, 6],
            **{argument: "s" if argument == "time_unit" else "rad/s"},
        )  # type: ignore[arg-type]


def test_integer_stamps_named_by_index_follow_the_name_or_their_size(tmp_path: Path) -> None:
    """``time_column=0`` of ``time_ns`` integers read them as seconds (1.4e9 Hz…) before 2026-12-07."""
    path = tmp_path / "imu.csv"
    path.write_text("time_ns,gx,gy,gz,ax,ay,az\n1403715523912140000,0,0,0,0,0,9.8\n1403715523917140000,0,0,0,0,0,9.8\n")
    imu = ik.io.read_imu_csv(path, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6])
    assert imu.t_ns is not None and int(imu.t_ns[1] - imu.t_ns[0]) == 5_000_000
    path.write_text("t,gx,gy,gz,ax,ay,az\n1403715523912140000,0,0,0,0,0,9.8\n1403715523917140000,0,0,0,0,0,9.8\n")
    imu = ik.io.read_imu_csv(path, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6])
    assert imu.t_ns is not None and int(imu.t_ns[1] - imu.t_ns[0]) == 5_000_000


def test_tab_separated_names_with_spaces(tmp_path: Path) -> None:
    """x-io's export with tabs was "not an IMU format" (split at the spaces in its names) before
    2026-12-07; it reads as the comma file does."""
    rows = "0.0,57.29577951308232,0,0,0,0,1\n0.01,0,0,0,0,0,1\n"
    comma, tab = tmp_path / "x.csv", tmp_path / "x.tsv"
    comma.write_text(XIO_HEADER + "\n" + rows)
    tab.write_text((XIO_HEADER + "\n" + rows).replace(",", "\t"))
    a, b = ik.io.read_imu(comma)[0], ik.io.read_imu(tab)[0]
    np.testing.assert_array_equal(b.gyro, a.gyro)
    np.testing.assert_array_equal(b.accel, a.accel)
    np.testing.assert_array_equal(b.accel[0], [0.0, 0.0, 9.80665])


def test_quoted_header_names(tmp_path: Path) -> None:
    """R's ``write.csv`` quotes the names: ``"timestamp"`` was neither detected nor found by name
    (only as ``'"timestamp"'``) before 2026-12-07."""
    path = tmp_path / "r.csv"
    path.write_text(
        '"timestamp","gyro_x","gyro_y","gyro_z","accel_x","accel_y","accel_z"\n0,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n'
    )
    detected = ik.io.read_imu(path)[0]
    named = ik.io.read_imu_csv(
        path, time_column="timestamp", gyro_columns=["gyro_x", "gyro_y", "gyro_z"], accel_columns=[4, 5, 6]
    )
    for imu in (detected, named):
        np.testing.assert_array_equal(imu.gyro[0], [1, 2, 3])
        np.testing.assert_array_equal(imu.accel[0], [4, 5, 6])


def test_a_latin1_file_is_named_as_such(tmp_path: Path) -> None:
    """A Windows exporter's ``°/s`` in Latin-1 was "not a text file" before 2026-12-07."""
    path = tmp_path / "imu.csv"
    path.write_bytes("t,gx (°/s),gy (°/s),gz (°/s),ax,ay,az\n0,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n".encode("latin-1"))
    with pytest.raises(ik.FileFormatError, match=r"not UTF-8 text: byte 0xb0 on line 1 \(Latin-1"):
        ik.io.read_imu(path)
    imu = ik.io.read_imu_csv(path, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6], gyro_unit="deg/s")
    np.testing.assert_allclose(imu.gyro[0], np.radians([1, 2, 3]), rtol=1e-15)


def test_delimiters_by_name(tmp_path: Path) -> None:
    """``delimiter="tab"`` was refused though the CLI spells it so (before 2026-12-07)."""
    path = tmp_path / "imu.tsv"
    path.write_text("t\tgx\tgy\tgz\tax\tay\taz\n0\t1\t2\t3\t4\t5\t6\n0.01\t1\t2\t3\t4\t5\t6\n")
    columns = {"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}
    by_name = ik.io.read_imu_csv(path, delimiter="tab", **columns)  # type: ignore[arg-type]
    assert by_name == ik.io.read_imu_csv(path, delimiter="\t", **columns)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^delimiter: expected one of"):
        ik.io.read_imu_csv(path, delimiter="tabs", **columns)  # type: ignore[arg-type]


def test_read_imu_csv_options_are_checked_by_name(tmp_path: Path) -> None:
    """``read_imu(path, csv={"time_col": 0})`` was a bare TypeError (before 2026-12-07)."""
    path = tmp_path / "imu.csv"
    path.write_text("t,gx,gy,gz,ax,ay,az\n0,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n")
    with pytest.raises(ik.ParameterError, match=r"^csv: 'time_col' is no keyword of read_imu_csv \(accel_columns") as e:
        ik.io.read_imu(path, csv={"time_col": 0})
    assert e.value.argument == "csv"
    imu, _ = ik.io.read_imu(path, csv={"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]})
    np.testing.assert_array_equal(imu.gyro[0], [1, 2, 3])


def _stamped(path: Path, header: str, stamps: np.ndarray, values: np.ndarray) -> Path:
    rows = [",".join([str(int(s)), *map(repr, row.tolist())]) for s, row in zip(stamps, values)]
    path.write_text("\n".join([header, *rows]) + "\n")
    return path


EUROC_STAMPS = 1403715523000000000 + np.arange(20) * 5_000_000


@pytest.mark.parametrize(
    ("header", "scale"),
    [
        # accelerometer first: read by position, gyro and accel were swapped
        (
            "#timestamp [ns],accel_x [m/s^2],accel_y [m/s^2],accel_z [m/s^2],"
            "gyro_x [rad/s],gyro_y [rad/s],gyro_z [rad/s]",
            None,
        ),
        # EuRoC's order in other units: read by position, deg/s as rad/s and g as m/s²
        (
            "#timestamp [ns],gyro_x [deg/s],gyro_y [deg/s],gyro_z [deg/s],acc_x [g],acc_y [g],acc_z [g]",
            (np.pi / 180, 9.80665),
        ),
    ],
)
def test_a_hash_header_naming_other_columns_is_read_by_its_names(
    tmp_path: Path, header: str, scale: tuple | None
) -> None:
    """A 7-field file with integer stamps is EuRoC's layout only when its header does not say otherwise."""
    values = _values(20, 7)[:, :6] + [0, 0, 0, 0, 0, 9.81]
    gyro, accel = values[:, :3], values[:, 3:]
    written = np.hstack([accel, gyro]) if scale is None else np.hstack([gyro / scale[0], accel / scale[1]])
    path = _stamped(tmp_path / "imu.csv", header, EUROC_STAMPS, written)
    imu, _ = ik.io.read_imu(path)
    np.testing.assert_array_equal(imu.t_ns, EUROC_STAMPS)
    np.testing.assert_allclose(imu.gyro, gyro, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(imu.accel, accel, rtol=1e-14, atol=1e-14)
    # Asked for EuRoC's layout by name, the file's own header is not overruled.
    with pytest.raises(ik.FileFormatError, match=r"^path: .*its header (puts|states).*read_imu") as raised:
        ik.io.read_euroc_imu(path)
    assert raised.value.argument == "path"


def test_a_header_naming_euroc_columns_is_still_read_by_position(tmp_path: Path) -> None:
    values = _values(20, 8)[:, :6]
    for header in (
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
        "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]",  # EuRoC's own: no role names the rules read
        "#timestamp [ns],gx [rad/s],gy,gz,ax,ay,az [m/s^2]",  # EuRoC's order and units, by name
    ):
        path = _stamped(tmp_path / "imu.csv", header, EUROC_STAMPS, values)
        by_position = ik.io.read_euroc_imu(path)
        np.testing.assert_array_equal(by_position.gyro, values[:, :3])
        np.testing.assert_array_equal(ik.io.read_imu(path)[0].accel, values[:, 3:])


def test_a_ground_truth_header_with_the_quaternion_first_is_read_by_its_names(tmp_path: Path) -> None:
    rotation = Rotation.random(20, rng=3)
    position, rest = _values(20, 9)[:, :3], np.zeros((20, 9))
    header = "#timestamp,q_w,q_x,q_y,q_z,p_x,p_y,p_z," + ",".join(f"{v}_{a}" for v in ("v", "bw", "ba") for a in "xyz")
    path = _stamped(
        tmp_path / "gt.csv", header, EUROC_STAMPS, np.hstack([rotation.as_quat(scalar_first=True), position, rest])
    )
    truth = ik.io.read_trajectory(path)
    np.testing.assert_array_equal(truth.position, position)
    assert (truth.rotation.inv() * rotation).magnitude().max() < 1e-15
    with pytest.raises(ik.FileFormatError, match=r"^path: .*puts position in columns 6, 7, 8.*read_trajectory"):
        ik.io.read_euroc_groundtruth(path)


@pytest.mark.parametrize("delimiter", [",", ";", "\t"])
def test_a_spreadsheets_empty_rows_are_blank_lines(tmp_path: Path, delimiter: str) -> None:
    """Excel writes the empty rows of a sheet as delimiters alone (``,,,,,,``): no value, no sample,
    as a blank line (a bad line before 2026-12-07, which refused the file); a row with one value
    left is still a bad line, not dropped."""
    values = _values(4, 11)[:, :6]
    rows = [delimiter.join(map(repr, [0.01 * k, *values[k].tolist()])) for k in range(4)]
    empty = delimiter * 6
    header = delimiter.join(["t", "gx", "gy", "gz", "ax", "ay", "az"])
    path = tmp_path / "sheet.csv"
    path.write_text("\n".join([header, rows[0], rows[1], empty, rows[2], rows[3], empty, empty[:3]]) + "\n")
    imu, _ = ik.io.read_imu(path)
    np.testing.assert_array_equal(imu.t, [0.0, 0.01, 0.02, 0.03])
    np.testing.assert_array_equal(imu.gyro, values[:, :3])
    stamped = _stamped(tmp_path / "imu0.csv", "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z", EUROC_STAMPS[:4], values)
    stamped.write_text(stamped.read_text() + ",,,,,,\n")
    np.testing.assert_array_equal(ik.io.read_euroc_imu(stamped).t_ns, EUROC_STAMPS[:4])
    path.write_text("\n".join([header, rows[0], rows[1], "0.015" + empty]) + "\n")
    with pytest.raises(ik.FileFormatError, match="line 4"):
        ik.io.read_imu(path)
