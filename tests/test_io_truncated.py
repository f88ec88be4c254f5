"""Issue 17, item 7: truncated and interrupted files do not read back as valid.

A last line cut mid-number is reported (``truncated``); writers write under a temporary name and rename
on success, so an interrupted ``write_euroc`` leaves no dataset behind; a ground-truth path that exists
but cannot be read (a dangling link, a folder) is an error, not ``truth=None``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit import io
from imukit.io import ReadReport

# Fixed 3 decimals, as many writers print; the check needs 8 lines before the last to judge.
ROWS = [f"14036365797{k:02d}000000,-0.099,0.140,0.025,8.100,-0.370,-2.{k:03d}" for k in range(9)]
ROWS.append("1403636579768555520,-0.097,0.120,0.027,8.300,-0.390,-9.810")


@pytest.mark.parametrize("cut", ["-9.", "-9", "-9.8"])
def test_a_last_line_cut_mid_number_is_reported(tmp_path: Path, cut: str) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join([*ROWS[:-1], ROWS[-1].replace("-9.810", cut)]))  # no final newline
    with pytest.raises(ik.FileFormatError, match=rf"line 10: the last line has no newline and its last field '{cut}'"):
        io.read_euroc_imu(path)
    report = ReadReport()
    imu = io.read_euroc_imu(path, on_bad_line="skip", report=report)
    assert len(imu) == 9 and [s.kind for s in report.skipped] == ["truncated"] and report.skipped[0].line == 10


def test_a_complete_last_line_without_newline_is_read(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(ROWS))
    assert io.read_euroc_imu(path).accel[-1, 2] == -9.81
    tum = tmp_path / "t.txt"
    lines = [f"{k}.0 0 0 0 0 0 0 1" for k in range(9)]
    tum.write_text("\n".join(lines))  # "1" and "1": as many decimals
    assert len(io.read_tum(tum)) == 9
    tum.write_text("\n".join(line + ".0" for line in lines[:-1]) + "\n8.0 0.5 0 0 0 0 0 1.")
    with pytest.raises(ik.FileFormatError, match="line 9: the last line has no newline"):
        io.read_tum(tum)
    tum.write_text("\n".join([*lines[:3], "3.0 0 0 0 0 0 0 1."]))  # too few lines to judge: read
    assert len(io.read_tum(tum)) == 4


def test_an_interrupted_euroc_write_leaves_no_dataset(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C while the IMU file is written: nothing under the final names, no temporary left."""
    t = np.arange(1000) * 0.005
    imu = ik.ImuData(t, np.zeros((1000, 3)), np.tile([0.0, 0.0, 9.81], (1000, 1)))
    folder = tmp_path / "sim"
    original = io._lines.write_rows

    def write_then_interrupt(path: object, *args: object) -> None:
        original(path, *args)  # type: ignore[arg-type]
        raise KeyboardInterrupt

    monkeypatch.setattr(io._euroc, "write_rows", write_then_interrupt)
    truth = ik.Trajectory(t, np.zeros((1000, 3)), np.zeros((1000, 3)), Rotation.identity(1000))
    with pytest.raises(KeyboardInterrupt):
        io.write_euroc(folder, imu, truth, truth_bias=ik.ImuBias())
    assert not (folder / "imu0" / "data.csv").exists()  # the ground truth was written first, the IMU never
    with pytest.raises(FileNotFoundError, match=r"no imu0/data\.csv"):
        io.read_euroc(folder)
    # A write interrupted inside write_rows leaves only its temporary, which is removed.
    monkeypatch.setattr(io._lines, "repr", lambda x: (_ for _ in ()).throw(KeyboardInterrupt()), raising=False)
    with pytest.raises(KeyboardInterrupt):
        io.write_tum(truth, tmp_path / "t.txt")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sim"]


@pytest.mark.parametrize("broken", ["dangling", "folder"])
def test_an_unreadable_ground_truth_is_an_error(tmp_path: Path, broken: str) -> None:
    t = np.arange(100) * 0.005
    io.write_euroc(tmp_path, ik.ImuData(t, np.zeros((100, 3)), np.tile([0.0, 0.0, 9.81], (100, 1))))
    truth = tmp_path / "state_groundtruth_estimate0" / "data.csv"
    truth.parent.mkdir()
    if broken == "dangling":
        os.symlink(tmp_path / "gone.csv", truth)
        expected = "a symbolic link to .*gone.csv', which does not exist"
    else:
        truth.mkdir()
        expected = "expected a regular file, got a folder"
    with pytest.raises(ik.FileFormatError, match=expected):
        io.read_euroc(tmp_path)
