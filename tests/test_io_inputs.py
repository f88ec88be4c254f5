"""Issue 17, items 13 and 15: what a reader is handed instead of a readable regular file, and arguments of
the wrong kind, end in imukit exceptions naming the path (or the argument), never hang."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

import imukit as ik
from imukit import io

READERS: dict[str, Callable[[Path], object]] = {
    "read_tum": io.read_tum,
    "read_euroc_imu": io.read_euroc_imu,
    "read_euroc_groundtruth": io.read_euroc_groundtruth,
    "read_gtsam_imu": io.read_gtsam_imu,
    "read_kalibr_imu": io.read_kalibr_imu,
    "read_imu_csv": lambda p: io.read_imu_csv(p, time_column=0, gyro_columns=[1, 2, 3], accel_columns=[4, 5, 6]),
    "read_imu": io.read_imu,
    "read_trajectory": io.read_trajectory,
}


def _folder(tmp_path: Path) -> Path:
    (tmp_path / "folder.txt").mkdir()
    return tmp_path / "folder.txt"


def _loop(tmp_path: Path) -> Path:
    os.symlink(tmp_path / "b.txt", tmp_path / "a.txt")
    os.symlink(tmp_path / "a.txt", tmp_path / "b.txt")
    return tmp_path / "a.txt"


def _fifo(tmp_path: Path) -> Path:
    os.mkfifo(tmp_path / "fifo.txt")
    return tmp_path / "fifo.txt"


@pytest.mark.parametrize("reader", sorted(READERS))
@pytest.mark.parametrize(
    ("make", "expected"),
    [
        (_folder, "expected a regular file, got a folder|not a file|no .* in"),
        (_loop, "cannot be opened as a file \\(Too many levels of symbolic links\\)"),
        (_fifo, "expected a regular file, got a FIFO"),
    ],
    ids=["folder", "symlink-loop", "fifo"],
)
def test_a_path_that_is_no_regular_file_is_refused(
    tmp_path: Path, reader: str, make: Callable[[Path], Path], expected: str
) -> None:
    path = make(tmp_path)
    if reader in ("read_imu", "read_trajectory"):  # detection names what it found instead
        expected = "a folder of no known layout|not a text file|Too many levels of symbolic links"
    with pytest.raises(ik.ImukitError, match=expected) as caught:
        READERS[reader](path)
    assert caught.value.argument in ("path", None, "folder")


def test_a_fifo_does_not_hang_a_reader(tmp_path: Path) -> None:
    """In a child process with a 60 s bound (a blocking open would wait for a writer forever)."""
    fifo = _fifo(tmp_path)
    code = f"import imukit.io as io\ntry:\n    io.read_tum({str(fifo)!r})\nexcept Exception as e:\n    print(type(e).__name__)"  # noqa: E501
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert run.stdout.strip() == "FileFormatError"


def test_report_of_the_wrong_type_is_a_parameter_error(tmp_path: Path) -> None:
    path = tmp_path / "t.txt"
    path.write_text("1 0 0 0 0 0 0 1\n")
    for report in ([], {}, "report"):
        with pytest.raises(ik.ParameterError, match=r"^report: expected an imukit\.io\.ReadReport or None"):
            io.read_tum(path, report=report)  # type: ignore[arg-type]


def test_nanosecond_steps_in_a_tum_file_name_the_file(tmp_path: Path) -> None:
    """1-ns steps are exact nanoseconds the data types refuse (median step under 1 µs): the file is named."""
    path = tmp_path / "t.txt"
    path.write_text("".join(f"1.{k:09d} 0 0 0 0 0 0 1\n" for k in range(10)))
    with pytest.raises(ik.FileFormatError, match=rf"^path: {path}: t_ns: .*median step is 1\.0 ns"):
        io.read_tum(path)


@pytest.mark.parametrize("crlf", [False, True])
def test_a_header_without_hash_is_a_header(tmp_path: Path, crlf: bool) -> None:
    """An 8-field mocap CSV and an EuRoC CSV whose header lacks EuRoC's ``#`` read as with it (issue 17,
    item 13: ``read_trajectory`` failed on line 1, "not a number")."""
    end = "\r\n" if crlf else "\n"
    mocap = tmp_path / "mocap.csv"
    mocap.write_text(
        end.join(["timestamp,x,y,z,qw,qx,qy,qz", *(f"{k}000000000,{k},0,0,1,0,0,0" for k in range(5))]) + end
    )
    trajectory = io.read_trajectory(mocap)
    assert trajectory.t_ns.tolist() == [k * 10**9 for k in range(5)]  # type: ignore[union-attr]
    imu = tmp_path / "data.csv"
    imu.write_text("timestamp,wx,wy,wz,ax,ay,az\n" + "".join(f"{k}000000000,0,0,0,0,0,9.81\n" for k in range(1, 5)))
    assert len(io.read_euroc_imu(imu)) == 4
    tum = tmp_path / "t.txt"
    tum.write_text("nan 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n")  # a word that is a number: a bad line, no header
    with pytest.raises(ik.FileFormatError, match="line 1: non-finite value"):
        io.read_tum(tum)
