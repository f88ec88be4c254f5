"""Issue 17, item 5: ``--out`` (and ``--plot``, ``--yaml``) never overwrite a file the command reads."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit import io
from imukit.cli import main


def _recording(folder: Path) -> Path:
    """A 2 s, 200 Hz IMU CSV at rest (gyro columns 1-3, accel 4-6), returned with its bytes untouched."""
    t = np.arange(400) / 200.0
    accel = np.tile([0.0, 0.0, 9.81], (400, 1))
    path = folder / "imu.csv"
    io.write_euroc(folder / "set", ik.ImuData(t, np.zeros((400, 3)), accel))
    path.write_bytes((folder / "set" / "imu0" / "data.csv").read_bytes())
    return path


@pytest.mark.parametrize("command", ["filter", "integrate"])
@pytest.mark.parametrize("spelling", ["same", "relative", "symlink", "hardlink"])
def test_out_resolving_to_an_input_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], command: str, spelling: str
) -> None:
    csv = _recording(tmp_path)
    tum = tmp_path / "imu.txt"  # the suffix the commands write; the input is this file under a TUM name
    tum.write_bytes(csv.read_bytes())
    (tmp_path / "sub").mkdir()
    monkeypatch.chdir(tmp_path / "sub")
    source, target = str(tum), str(tum)
    if spelling == "relative":
        source, target = str(tum), "../sub/../imu.txt"
    elif spelling == "symlink":
        os.symlink(tum, tmp_path / "link.txt")
        target = str(tmp_path / "link.txt")
    elif spelling == "hardlink":
        os.link(tum, tmp_path / "hard.txt")
        target = str(tmp_path / "hard.txt")
    before = Path(target).read_bytes()
    assert main([command, source, "--out", target]) == 1
    message = capsys.readouterr().err
    assert message.startswith("imukit: error: --out: ") and "refusing to overwrite" in message, message
    assert Path(target).read_bytes() == before


def test_out_onto_a_file_read_inside_an_input_folder_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _recording(tmp_path)
    target = tmp_path / "set" / "imu0" / "data.csv"
    before = target.read_bytes()
    assert main(["filter", str(tmp_path / "set"), "--out", str(target)]) == 1
    assert "is a file inside the input folder" in capsys.readouterr().err and target.read_bytes() == before


def test_out_beside_the_input_is_written(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The check refuses inputs only: a result in the input folder is written, and written again."""
    _recording(tmp_path)
    for _ in range(2):
        assert main(["integrate", str(tmp_path / "set"), "--out", str(tmp_path / "set" / "traj.txt")]) == 0
        assert len(io.read_tum(tmp_path / "set" / "traj.txt")) == 400
