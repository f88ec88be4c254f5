"""KITTI odometry poses with their times file: :func:`read_kitti_poses` (``docs/io.md``)."""

from __future__ import annotations

import os

import numpy as np
from scipy.spatial.transform import Rotation

from imukit._errors import FileFormatError
from imukit.io._lines import (
    Problem,
    Rows,
    as_file_error,
    data_lines,
    increasing,
    parse_rows,
    public_reader,
    require_rows,
)
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.state import Trajectory

__all__ = ["read_kitti_poses"]

# KITTI prints 7 significant digits: its rotation blocks are orthonormal to ~2e-7 (sequence 00).
ORTHONORMAL_TOLERANCE = 1e-4


def kitti_poses(poses_path: str | os.PathLike[str], times_path: str | os.PathLike[str], bad: BadLines) -> Trajectory:
    """:func:`read_kitti_poses` reporting to ``bad``."""
    pose_lines, time_lines = list(data_lines(poses_path)), list(data_lines(times_path))
    if len(pose_lines) != len(time_lines):
        raise FileFormatError(
            f"{os.fspath(poses_path)}: {len(pose_lines)} pose lines, but {os.fspath(times_path)} has "
            f"{len(time_lines)} time lines (line k of each belong together)",
            argument="path",
        )
    poses = parse_rows(
        pose_lines,
        poses_path,
        bad,
        split=str.split,
        width=12,
        expected="fields (a 3x4 pose [R | p] row by row)",
        columns=range(12),
        check=_rotation_check,
    )
    times = parse_rows(
        time_lines, times_path, bad, split=str.split, width=1, expected="field (a time in seconds)", columns=[0]
    )
    poses, times = _pair(poses, times, pose_lines, time_lines, poses_path, times_path, bad)
    keep = increasing(times, [row[0] for row in times.values], times.texts, times_path, bad)
    poses, times = _pair(poses, times.take(keep), pose_lines, time_lines, poses_path, times_path, bad)
    require_rows(poses, poses_path, bad)
    data = np.array(poses.values, dtype=np.float64).reshape(-1, 3, 4)
    rotation = Rotation.from_matrix(data[:, :, :3])
    t = np.array(times.values, dtype=np.float64)[:, 0]
    return as_file_error(poses_path, lambda: Trajectory(t, data[:, :, 3], None, rotation))


@public_reader(kitti_poses)
def read_kitti_poses(  # type: ignore[empty-body]
    poses_path: str | os.PathLike[str],
    times_path: str | os.PathLike[str],
    *,
    on_bad_line: OnBadLine = "raise",
    report: ReadReport | None = None,
) -> Trajectory:
    """Read KITTI odometry poses (``00.txt``, evo's "kitti" format) and their ``times.txt``.

    Parameters
    ----------
    poses_path
        One pose per line: the 12 numbers of the 3×4 matrix ``[R | p]`` row by row
        (``r11 r12 r13 px r21 … r33 pz``), white-space separated. KITTI's ground truth is the pose of
        camera 0 in the frame of the first camera 0 (x right, y down, z forward), not a z-up world.
    times_path
        One time per line [s] (KITTI: since the start of the sequence); line k of each file (blank
        and ``#`` lines aside) belong together, so both must hold as many.
    on_bad_line, report
        As in :func:`imukit.io.read_euroc_imu`. Bad lines: wrong field count, text that is not a
        number, non-finite values, a rotation block that is not a rotation (``RᵀR`` off the identity
        by more than 1e-4, or ``det R ≤ 0``), and times out of order (the longest
        strictly increasing subsequence of times is kept, first of equal ones). When a
        line of one file is skipped, its partner in the other is skipped too, reported as
        ``unpaired``.

    Returns
    -------
    Trajectory
        ``t`` [s] (``t_ns`` None), ``position`` = ``p`` [m], ``rotation`` = ``R`` (the nearest
        rotation, as scipy's ``Rotation.from_matrix`` finds it), no velocity.

    Raises
    ------
    FileFormatError
        Naming the file and line for bad lines ("raise" mode); naming both files when their line
        counts differ; no data.
    """


def _pair(
    poses: Rows,
    times: Rows,
    pose_lines: list[tuple[int, str]],
    time_lines: list[tuple[int, str]],
    poses_path: str | os.PathLike[str],
    times_path: str | os.PathLike[str],
    bad: BadLines,
) -> tuple[Rows, Rows]:
    """The rows whose partner (same data-line index) in the other file is kept; the others are
    reported as unpaired."""
    index_of_pose = {number: k for k, (number, _) in enumerate(pose_lines)}
    index_of_time = {number: k for k, (number, _) in enumerate(time_lines)}
    pose_at = {index_of_pose[n]: j for j, n in enumerate(poses.lines)}
    time_at = {index_of_time[n]: j for j, n in enumerate(times.lines)}
    both = sorted(pose_at.keys() & time_at.keys())
    for k in sorted(pose_at.keys() - time_at.keys()):
        j = pose_at[k]
        detail = f"its time (line {time_lines[k][0]} of {os.fspath(times_path)}) is skipped"
        bad.bad(poses_path, poses.lines[j], "unpaired", detail, poses.texts[j])
    for k in sorted(time_at.keys() - pose_at.keys()):
        j = time_at[k]
        detail = f"its pose (line {pose_lines[k][0]} of {os.fspath(poses_path)}) is skipped"
        bad.bad(times_path, times.lines[j], "unpaired", detail, times.texts[j])
    return poses.take([pose_at[k] for k in both]), times.take([time_at[k] for k in both])


def _rotation_check(fields: list[str], row: list[float]) -> Problem | None:
    r = np.array(row, dtype=np.float64).reshape(3, 4)[:, :3]
    with np.errstate(all="ignore"):  # huge entries give inf or nan here, which the test below refuses
        off = float(np.abs(r.T @ r - np.eye(3)).max())
        det = float(np.linalg.det(r))
    if not off <= ORTHONORMAL_TOLERANCE or not det > 0.0:
        return "not a rotation", f"the 3x3 block is not a rotation (|R^T R - I| = {off:.3g}, det R = {det:.6g})"
    return None
