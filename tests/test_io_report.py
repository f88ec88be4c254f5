"""on_bad_line="skip": every bad line is reported with its number and reason, every valid sample is kept
(bit for bit, whatever garbage surrounds it), and a skip without a report is one warning at the caller."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit.io import ReadReport, SkippedLine, SkippedLinesWarning

HEADER = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"  # noqa: E501
# Line numbers in comments; the valid samples are lines 2, 6 and 9.
EUROC_IMU = [
    HEADER,
    "1403715523912140000,0.1,0.2,0.3,9.1,9.2,9.3",
    "1403715523917140000,1,2,3,4,5",
    "1403715523922140000,1,2,x,4,5,6",
    "1403715523927140000,1,2,nan,4,5,6",
    "1403715523932140000,-0.1,-0.2,-0.3,-9.1,-9.2,-9.3",
    "1403715523932140000,9,9,9,9,9,9",
    "1403715523927140000,1,2,3,4,5,6",
    "1403715523937140000,1e-05,0.0,-0.0,1.5,2.5,3.5",
    "1403715523.94,1,2,3,4,5,6",
    "1403715523942140000,1,2,3,4",
]


def expected_euroc_skips(path: str) -> list[SkippedLine]:
    def skip(line: int, reason: str) -> SkippedLine:
        return SkippedLine(path, line, reason, EUROC_IMU[line - 1])

    fields = "expected 7 comma-separated fields (EuRoC imu0/data.csv)"
    return [
        skip(3, f"wrong column count: {fields}, got 6"),
        skip(4, f"malformed: not a number in {EUROC_IMU[3]!r}"),
        skip(5, f"non-finite: non-finite value in {EUROC_IMU[4]!r}"),
        skip(
            7,
            "duplicate stamp: time must increase strictly, but 1403715523932140000 follows 1403715523932140000 "
            "(line 6)",
        ),
        skip(
            8,
            "stamp going back: time must increase strictly, but 1403715523927140000 follows 1403715523932140000 "
            "(line 6)",
        ),
        skip(10, "malformed: timestamp '1403715523.94' is not an integer number of nanoseconds (int64)"),
        skip(11, f"wrong column count: {fields}, got 5"),
    ]


def test_euroc_imu_skip_keeps_every_valid_sample_and_reports_each_bad_line(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU) + "\n")
    report = ReadReport()
    imu = ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    assert imu.t_ns is not None
    assert imu.t_ns.tolist() == [1403715523912140000, 1403715523932140000, 1403715523937140000]
    np.testing.assert_array_equal(imu.gyro, [[0.1, 0.2, 0.3], [-0.1, -0.2, -0.3], [1e-05, 0.0, -0.0]])
    np.testing.assert_array_equal(imu.accel, [[9.1, 9.2, 9.3], [-9.1, -9.2, -9.3], [1.5, 2.5, 3.5]])
    assert report.skipped == expected_euroc_skips(str(path))
    assert len(report) == 7 and report
    assert report.summary() == (
        f"7 lines skipped in {path}: 2 wrong column counts, 2 malformed, 1 non-finite, 1 duplicate stamp, "
        "1 stamp going back"
    )
    assert [s.kind for s in report.skipped] == [
        "wrong column count", "malformed", "non-finite", "duplicate stamp", "stamp going back", "malformed",
        "wrong column count",
    ]  # fmt: skip


def test_raise_mode_stops_at_the_first_bad_line(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU) + "\n")
    with pytest.raises(ik.io.FileFormatError, match=rf"^path: {re.escape(str(path))}, line 3: expected 7 comma"):
        ik.io.read_euroc_imu(path)
    with pytest.raises(ik.io.FileFormatError, match=r", line 3: "):
        ik.io.read_euroc_imu(path, on_bad_line="raise", report=ReadReport())


def test_skip_without_a_report_warns_once_at_the_caller(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU) + "\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        imu = ik.io.read_euroc_imu(path, on_bad_line="skip")
    assert len(imu) == 3
    assert [type(w.message) for w in caught] == [SkippedLinesWarning]
    assert str(caught[0].message) == ReadReport.summary(_report(expected_euroc_skips(str(path))))
    assert caught[0].filename == __file__  # stacklevel points at this call, not into imukit


def test_a_clean_file_neither_warns_nor_reports(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(EUROC_IMU[:2]) + "\n")
    report = ReadReport()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
        ik.io.read_euroc_imu(path, on_bad_line="skip")
    assert not report and len(report) == 0 and report.summary() == "no lines skipped"


def test_folder_read_reports_both_files_in_one_report(tmp_path: Path) -> None:
    (tmp_path / "imu0").mkdir()
    (tmp_path / "imu0" / "data.csv").write_text("\n".join(EUROC_IMU) + "\n")
    gt = tmp_path / "state_groundtruth_estimate0" / "data.csv"
    gt.parent.mkdir()
    good = "1403715524907143168,0.5,2.0,0.9,1,0,0,0,0,0,0,0,0,0,0,0,0"
    zero = "1403715524912143104,0.5,2.0,0.9,0,0,0,0,0,0,0,0,0,0,0,0,0"
    gt.write_text(f"#h\n{good}\n{zero}\n")
    report = ReadReport()
    imu, truth = ik.io.read_euroc(tmp_path, on_bad_line="skip", report=report)
    assert len(imu) == 3 and truth is not None and len(truth) == 1
    assert report.skipped == [
        *expected_euroc_skips(str(tmp_path / "imu0" / "data.csv")),
        SkippedLine(str(gt), 3, "zero quaternion: zero quaternion", zero),
    ]
    assert report.summary().startswith(f"8 lines skipped in {tmp_path / 'imu0' / 'data.csv'}, {gt}: ")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ik.io.read_euroc(tmp_path, on_bad_line="skip")
    assert len(caught) == 1 and str(caught[0].message).startswith("8 lines skipped in ")


def test_nothing_valid_left_is_an_error_that_counts_the_skips(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text(f"{HEADER}\n1,2,3\n1403715523922140000,1,2,x,4,5,6\n")
    with pytest.raises(
        ik.io.FileFormatError,
        match=rf"^path: {re.escape(str(path))}: no data lines \(2 lines skipped: 1 wrong column count, 1 malformed\)$",
    ):
        ik.io.read_euroc_imu(path, on_bad_line="skip", report=ReadReport())


def test_garbage_between_valid_lines_costs_no_sample(tmp_path: Path, rng: np.random.Generator) -> None:
    # A written trajectory with junk lines spliced in at random places reads back bit for bit.
    n = 300
    t_ns = 1_403_636_579_758_555_392 + np.cumsum(rng.integers(4_999_000, 5_001_000, n))
    truth = ik.Trajectory(None, rng.normal(size=(n, 3)), None, Rotation.random(n, rng=rng), t_ns=t_ns)
    path = tmp_path / "traj.txt"
    truth.write_tum(path)
    lines = path.read_text().splitlines()
    junk = ["0.5 1 2", "x y z 1 2 3 4 5", "1.0 inf 0 0 0 0 0 1", lines[0], "1.0 0 0 0 0 0 0 0"]
    where = sorted(rng.choice(np.arange(1, n), size=40, replace=False).tolist())
    out: list[str] = []
    bad_lines = []
    for k, line in enumerate(lines):
        out.append(line)
        if where and k == where[0]:
            where.pop(0)
            out.append(junk[k % len(junk)])
            bad_lines.append(len(out))
    path.write_text("\n".join(out) + "\n")
    report = ReadReport()
    back = ik.io.read_tum(path, on_bad_line="skip", report=report)
    assert back.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, t_ns)
    np.testing.assert_array_equal(back.position, truth.position)
    np.testing.assert_array_equal(back.rotation.as_quat(), truth.rotation.as_quat())
    assert [s.line for s in report.skipped] == bad_lines
    assert {s.kind for s in report.skipped} <= {
        "wrong column count", "malformed", "non-finite", "stamp going back", "zero quaternion",
    }  # fmt: skip


def test_tum_skip_reports_exactly(tmp_path: Path) -> None:
    text = [
        "# t x y z qx qy qz qw",
        "1.000000000 0 0 0 0 0 0 1",
        "1.000000000 9 9 9 0 0 0 1",
        "1.100000000 1 0 0 0 0 0 0",
        "1.200000000 2 0 0 0 0 0 1",
        "1.100000000 3 0 0 0 0 0 1",
        "1.300000000 4 0 0",
    ]
    path = tmp_path / "t.txt"
    path.write_text("\n".join(text) + "\n")
    report = ReadReport()
    traj = ik.io.read_tum(path, on_bad_line="skip", report=report)
    assert traj.t_ns is not None and traj.t_ns.tolist() == [1_000_000_000, 1_200_000_000]
    np.testing.assert_array_equal(traj.position[:, 0], [0.0, 2.0])
    p = str(path)
    assert report.skipped == [
        SkippedLine(p, 3, "duplicate stamp: time must increase strictly, but 1.000000000 follows 1.000000000 "
                    "(line 2)", text[2]),
        SkippedLine(p, 4, "zero quaternion: zero quaternion", text[3]),
        SkippedLine(p, 6, "stamp going back: time must increase strictly, but 1.100000000 follows 1.200000000 "
                    "(line 5)", text[5]),
        SkippedLine(p, 7, "wrong column count: expected 8 fields 'timestamp tx ty tz qx qy qz qw', got 4", text[6]),
    ]  # fmt: skip


def test_report_str_lists_lines_and_caps_the_list() -> None:
    report = _report([SkippedLine("f.csv", k, "malformed: not a number in 'x'", "x") for k in range(1, 26)])
    lines = str(report).splitlines()
    assert lines[0] == "25 lines skipped in f.csv: 25 malformed"
    assert lines[1] == "  f.csv, line 1: malformed: not a number in 'x'"
    assert len(lines) == 22 and lines[-1] == "  … and 5 more"
    one = _report([SkippedLine("f.csv", 4, "zero quaternion: zero quaternion", "0 0 0 0")])
    assert one.summary() == "1 line skipped in f.csv: 1 zero quaternion"


def test_options_are_checked(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text(EUROC_IMU[1] + "\n")
    with pytest.raises(ik.ParameterError, match=r"^on_bad_line: expected 'raise' or 'skip', got 'ignore'"):
        ik.io.read_euroc_imu(path, on_bad_line="ignore")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"^report: expected an imukit\.io\.ReadReport or None, got list"):
        ik.io.read_tum(path, report=[])  # type: ignore[arg-type]


def _report(skipped: list[SkippedLine]) -> ReadReport:
    report = ReadReport()
    report.skipped.extend(skipped)
    return report


def test_bytes_that_are_not_utf8_and_huge_stamps_are_bad_lines(tmp_path: Path) -> None:
    # A Latin-1 byte in one line, a 25-digit stamp in another: each is one bad line, not a crash.
    path = tmp_path / "data.csv"
    lines = [EUROC_IMU[1].encode(), b"1403715523917140000,0.1,\xb00.2,0.3,9.1,9.2,9.3", b"9" * 25 + b",1,2,3,4,5,6"]
    lines.append(b"9" * 5000 + b",1,2,3,4,5,6")  # past int()'s 4300-digit limit
    path.write_bytes(b"\n".join(lines) + b"\n")
    report = ReadReport()
    imu = ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    assert len(imu) == 1
    assert [(s.line, s.kind) for s in report.skipped] == [(2, "malformed"), (3, "malformed"), (4, "malformed")]
    assert report.skipped[0].reason == "malformed: not a number in '1403715523917140000,0.1,\\udcb00.2,0.3,9.1,9.2,9.3'"
    assert report.skipped[1].reason.startswith("malformed: timestamp '9999999999999999999999999' is not an integer")
