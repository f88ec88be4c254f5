"""TUM-VI "exported" folders (EuRoC layout with motion capture): :func:`read_tumvi` (``docs/io.md``).

The IMU file is EuRoC's ``imu0/data.csv``; the ground truth is ``mocap0/data.csv``, a pose only:
``timestamp [ns], p_RS_R x, y, z [m], q_RS w, x, y, z``, read like EuRoC's ground truth.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from imukit.imu import ImuData
from imukit.io._euroc import IMU_CSV, build, euroc_imu, mav0_root, read_stamped_csv
from imukit.io._lines import rotations_from_rows
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.state import Trajectory

__all__ = ["read_tumvi"]

MOCAP_HEADER = "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []"
MOCAP_CSV = Path("mocap0", "data.csv")


def read_tumvi(
    folder: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> tuple[ImuData, Trajectory | None]:
    """Read the IMU and motion-capture poses of a TUM-VI exported folder (``dataset-room1_512_16``).

    Parameters
    ----------
    folder
        Holds ``mav0/imu0/data.csv`` (or ``imu0/data.csv`` directly) and, optionally,
        ``mocap0/data.csv`` next to ``imu0/``.
    on_bad_line, report
        As in :func:`imukit.io.read_euroc_imu`, for both files (one warning for both).

    Returns
    -------
    imu
        As :func:`imukit.io.read_euroc_imu`: exact int64 ``t_ns``, gyro [rad/s], accel [m/s²].
    truth
        The mocap poses at their own stamps (exact ``t_ns``): ``position`` ``p_RS_R`` [m] and
        ``rotation`` ``q_RS`` (scalar first in the file; normalised unless unit to 1e-15), with
        ``velocity`` and biases None; None when ``mocap0/data.csv`` is absent.

    Raises
    ------
    FileNotFoundError
        No ``imu0/data.csv``.
    FileFormatError
        As :func:`imukit.io.read_euroc_imu`; the mocap file needs 8 fields per line and no zero
        quaternion.
    """
    bad = BadLines(on_bad_line, report)
    return bad.done(tumvi_folder(folder, bad))


def tumvi_folder(folder: str | os.PathLike[str], bad: BadLines) -> tuple[ImuData, Trajectory | None]:
    """:func:`read_tumvi` reporting to ``bad``."""
    root = mav0_root(folder)
    mocap = root / MOCAP_CSV
    return euroc_imu(root / IMU_CSV, bad), tumvi_mocap(mocap, bad) if mocap.is_file() else None


def tumvi_mocap(path: str | os.PathLike[str], bad: BadLines) -> Trajectory:
    """A TUM-VI ``mocap0/data.csv`` as a :class:`Trajectory` without velocity, reporting to ``bad``."""
    t_ns, values, lines = read_stamped_csv(path, bad, MOCAP_HEADER, f"TUM-VI {MOCAP_CSV.as_posix()}", quaternion=3)
    rotation = rotations_from_rows(np.ascontiguousarray(values[:, [4, 5, 6, 3]]), lines, os.fspath(path))
    return build(path, lambda: Trajectory(None, values[:, 0:3], None, rotation, t_ns=t_ns))
