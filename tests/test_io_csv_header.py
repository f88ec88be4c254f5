"""Issue 17, item 3: read_imu_csv never guesses a header silently: a text column in a headerless file is
data, pandas' column-number header is taken as the header and reported, other all-integer first lines
above float data are refused."""

from __future__ import annotations

from pathlib import Path

import pytest

import imukit as ik
from imukit import io

COLUMNS = {"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}
DATA = "0.0,0.1,0.2,0.3,0.4,0.5,9.8\n0.01,0.1,0.2,0.3,0.4,0.5,9.8\n0.02,0.1,0.2,0.3,0.4,0.5,9.8\n"


def _read(tmp_path: Path, text: str) -> tuple[ik.ImuData, io.ReadReport]:
    path = tmp_path / "imu.csv"
    path.write_text(text)
    report = io.ReadReport()
    return io.read_imu_csv(path, **COLUMNS, report=report), report


@pytest.mark.parametrize("header", ["0,1,2,3,4,5,6", "1,2,3,4,5,6,7"])
def test_pandas_column_numbers_are_the_header_and_reported(tmp_path: Path, header: str) -> None:
    imu, report = _read(tmp_path, f"{header}\n{DATA}")
    assert len(imu) == 3 and imu.t[0] == 0.0  # no fabricated sample with gyro (1, 2, 3)
    assert [(s.line, s.kind, s.text) for s in report.skipped] == [(1, "header", header)]
    with pytest.warns(io.SkippedLinesWarning, match="1 header"):
        io.read_imu_csv(tmp_path / "imu.csv", **COLUMNS)


def test_a_text_column_without_header_keeps_the_first_sample(tmp_path: Path) -> None:
    text = "".join(line + ",imuA\n" for line in DATA.splitlines())
    imu, report = _read(tmp_path, text)
    assert len(imu) == 3 and imu.t[0] == 0.0 and not report


def test_other_integer_first_lines_above_float_data_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ik.FileFormatError, match=r"line 1: '5,1,2,3,4,5,6' is integers only while the next"):
        _read(tmp_path, "5,1,2,3,4,5,6\n" + DATA)


@pytest.mark.parametrize(
    ("first", "rows"),
    [("t,wx,wy,wz,ax,ay,az", 3), ("#0,1,2,3,4,5,6", 3), ("0,0,0,0,0,0,9", 4)],
    ids=["names", "hash-numbers", "integer-sample"],
)
def test_unambiguous_first_lines(tmp_path: Path, first: str, rows: int) -> None:
    """Names and ``#`` lines are headers; an integer sample above integer samples is data."""
    data = DATA if rows == 3 else "1,0,0,0,0,0,9\n2,0,0,0,0,0,9\n3,0,0,0,0,0,9\n"
    imu, report = _read(tmp_path, f"{first}\n{data}")
    assert len(imu) == rows and not report
