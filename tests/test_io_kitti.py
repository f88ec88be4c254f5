"""KITTI poses + times: the real sequence 00 against numpy's parse and evo's reader, hand-made poses,
pairing of the two files when lines are skipped, and errors."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from evo.tools import file_interface

import imukit as ik
from euroc import DATA
from imukit.io import ReadReport, SkippedLine

from conftest import assert_quat_close

KITTI = DATA.parent / "kitti_gtsam"
POSES, TIMES = KITTI / "KITTI_00_gt_poses_evo.txt", KITTI / "KITTI_00_gt_times_evo.txt"
requires_kitti = pytest.mark.skipif(
    not POSES.exists(), reason=f"KITTI 00 poses not found at {KITTI} (team's shared/ folder, not the repo)"
)
# 90° about z: x → y. Row-major [R | p].
QUARTER_TURN = "0 -1 0 1.5 1 0 0 -2.5 0 0 1 3.25"
IDENTITY = "1 0 0 0 0 1 0 0 0 0 1 0"


@requires_kitti
def test_real_sequence_00() -> None:
    traj = ik.io.read_kitti_poses(POSES, TIMES)
    raw = np.loadtxt(POSES).reshape(-1, 3, 4)
    assert len(traj) == 4541 and traj.velocity is None and traj.t_ns is None
    np.testing.assert_array_equal(traj.t, np.loadtxt(TIMES))
    np.testing.assert_array_equal(traj.position, raw[:, :, 3])
    np.testing.assert_array_equal(traj.position[1], [-4.690294e-02, -2.839928e-02, 8.586941e-01])
    # The file's 7-digit rotation blocks are orthonormal to 2.2e-7; the rotation read is within that.
    assert np.abs(traj.rotation.as_matrix() - raw[:, :, :3]).max() < 2e-7
    # evo reads the same rotations (its matrix → quaternion and scipy's agree to rounding).
    evo = file_interface.read_kitti_poses_file(str(POSES))
    np.testing.assert_array_equal(evo.positions_xyz, traj.position)
    assert_quat_close(evo.orientations_quat_wxyz[:, [1, 2, 3, 0]], traj.rotation.as_quat(), atol=1e-14)


def test_hand_made_poses(tmp_path: Path) -> None:
    poses, times = tmp_path / "poses.txt", tmp_path / "times.txt"
    poses.write_text(f"{IDENTITY}\n\n{QUARTER_TURN}\n")
    times.write_text("0.000000e+00\n1.037359e-01\n")
    traj = ik.io.read_kitti_poses(poses, times)
    np.testing.assert_array_equal(traj.t, [0.0, 0.1037359])
    np.testing.assert_array_equal(traj.position, [[0.0, 0.0, 0.0], [1.5, -2.5, 3.25]])
    assert_quat_close(traj.rotation.as_quat(), [[0, 0, 0, 1], [0, 0, np.sqrt(0.5), np.sqrt(0.5)]], atol=2.3e-16)
    np.testing.assert_allclose(traj.rotation[1].apply([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], rtol=0, atol=4.5e-16)


def test_a_skipped_line_drops_its_partner_and_says_so(tmp_path: Path) -> None:
    poses, times = tmp_path / "poses.txt", tmp_path / "times.txt"
    pose_text = [IDENTITY, "1 0 0 0 0 1 0 0 0 0", QUARTER_TURN, IDENTITY, "2 0 0 0 0 1 0 0 0 0 1 0"]
    time_text = ["0.0", "0.1", "0.2", "x", "0.4", "0.2"]
    pose_text.append(IDENTITY)
    poses.write_text("\n".join(pose_text) + "\n")
    times.write_text("\n".join(time_text) + "\n")
    report = ReadReport()
    traj = ik.io.read_kitti_poses(poses, times, on_bad_line="skip", report=report)
    np.testing.assert_array_equal(traj.t, [0.0, 0.2])
    np.testing.assert_array_equal(traj.position[1], [1.5, -2.5, 3.25])
    p, t = str(poses), str(times)
    assert report.skipped == [
        SkippedLine(
            p, 2, "wrong column count: expected 12 fields (a 3x4 pose [R | p] row by row), got 10", pose_text[1]
        ),
        SkippedLine(p, 4, f"unpaired: its time (line 4 of {t}) is skipped", pose_text[3]),
        SkippedLine(p, 5, "not a rotation: the 3x3 block is not a rotation (|R^T R - I| = 3, det R = 2)", pose_text[4]),
        SkippedLine(p, 6, f"unpaired: its time (line 6 of {t}) is skipped", pose_text[5]),
        SkippedLine(t, 2, f"unpaired: its pose (line 2 of {p}) is skipped", "0.1"),
        SkippedLine(t, 4, "malformed: not a number in 'x'", "x"),
        SkippedLine(t, 5, f"unpaired: its pose (line 5 of {p}) is skipped", "0.4"),
        SkippedLine(t, 6, "duplicate stamp: time must increase strictly, but 0.2 follows 0.2 (line 3)", "0.2"),
    ]


def test_a_reflection_is_not_a_rotation(tmp_path: Path) -> None:
    poses, times = tmp_path / "poses.txt", tmp_path / "times.txt"
    poses.write_text("1 0 0 0 0 1 0 0 0 0 -1 0\n")
    times.write_text("0\n")
    with pytest.raises(
        ik.io.FileFormatError,
        match=rf"^path: {re.escape(str(poses))}, line 1: the 3x3 block is not a rotation "
        r"\(\|R\^T R - I\| = 0, det R = -1\)",
    ):
        ik.io.read_kitti_poses(poses, times)


@pytest.mark.parametrize(
    ("pose_text", "time_text", "where", "message"),
    [
        (f"{IDENTITY}\n{IDENTITY}\n", "0\n", "poses", r": 2 pose lines, but .*times\.txt has 1 time lines"),
        (f"{IDENTITY}\n1 0 0 0 0 1 0 0 0 0 1\n", "0\n1\n", "poses", r", line 2: expected 12 fields .*got 11$"),
        (f"{IDENTITY}\n{IDENTITY}\n", "0\n0 1\n", "times", r", line 2: expected 1 field \(a time in seconds\), got 2$"),
        (f"{IDENTITY}\n{IDENTITY}\n", "0\n0\n", "times", r", line 2: time must increase strictly, but 0 follows 0"),
        (
            f"{IDENTITY}\n{IDENTITY}\n",
            "1\n0.5\n",
            "times",
            r", line 2: time must increase strictly, but 0\.5 follows 1",
        ),
        (f"{IDENTITY}\n1 0 0 0 0 1 0 0 0 0 1 nan\n", "0\n1\n", "poses", r", line 2: non-finite value"),
        ("# only a comment\n", "\n", "poses", r": no data lines$"),
    ],
)
def test_malformed_files_name_file_and_line(
    tmp_path: Path, pose_text: str, time_text: str, where: str, message: str
) -> None:
    poses, times = tmp_path / "poses.txt", tmp_path / "times.txt"
    poses.write_text(pose_text)
    times.write_text(time_text)
    bad = poses if where == "poses" else times
    with pytest.raises(ik.io.FileFormatError, match=f"^path: {re.escape(str(bad))}{message}"):
        ik.io.read_kitti_poses(poses, times)


def test_huge_entries_are_not_a_rotation(tmp_path: Path) -> None:
    poses, times = tmp_path / "poses.txt", tmp_path / "times.txt"
    poses.write_text(f"{IDENTITY}\n1e308 0 0 0 0 1e308 0 0 0 0 1e308 0\n")
    times.write_text("0\n1\n")
    report = ReadReport()
    with np.errstate(all="raise"):  # no floating-point warning escapes either
        traj = ik.io.read_kitti_poses(poses, times, on_bad_line="skip", report=report)
    assert len(traj) == 1
    assert [(s.path, s.line, s.kind) for s in report.skipped] == [
        (str(poses), 2, "not a rotation"), (str(times), 2, "unpaired"),
    ]  # fmt: skip


def test_a_time_from_the_future_costs_its_pose_only(tmp_path: Path) -> None:
    # Pose k is a translation by k along x; time line 3 is 100 s late: only pose 3 goes, as unpaired.
    poses, times = tmp_path / "poses.txt", tmp_path / "times.txt"
    poses.write_text("".join(f"1 0 0 {k}.0 0 1 0 0 0 0 1 0\n" for k in range(6)))
    times.write_text("0.0\n0.1\n100.2\n0.3\n0.4\n0.5\n")
    report = ReadReport()
    traj = ik.io.read_kitti_poses(poses, times, on_bad_line="skip", report=report)
    assert traj.t.tolist() == [0.0, 0.1, 0.3, 0.4, 0.5]
    assert traj.position[:, 0].tolist() == [0.0, 1.0, 3.0, 4.0, 5.0]
    assert [(s.path, s.line, s.kind) for s in report.skipped] == [
        (str(times), 3, "stamp out of order"),
        (str(poses), 3, "unpaired"),
    ]
    assert report.skipped[0].reason == (
        "stamp out of order: time must increase strictly, but 100.2 comes before 0.3 (line 4)"
    )
