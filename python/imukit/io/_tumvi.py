"""TUM-VI "exported" folders (EuRoC layout with motion capture): :func:`read_tumvi` (``docs/io.md``).

The IMU file is EuRoC's ``imu0/data.csv``; the ground truth is ``mocap0/data.csv``, a pose only:
``timestamp [ns], p_RS_R x, y, z [m], q_RS w, x, y, z``, read like EuRoC's ground truth.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from imukit._errors import FileFormatError
from imukit.imu import ImuData
from imukit.io._euroc import DATASET, IMU_CSV, POSE_NAMES, dataset_file, euroc_imu, mav0_root, read_stamped_csv
from imukit.io._format import Format, Head, is_number, shorten
from imukit.io._lines import as_file_error, public_reader, rotations_from_rows
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.state import Trajectory

__all__ = ["read_tumvi"]

MOCAP_HEADER = "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []"
MOCAP_CSV = Path("mocap0", "data.csv")
# The column names that put the quaternion's w first (TUM-VI's header), and the usual names of a w-last one.
_W_FIRST = ("q_RS_w", "qw", "q_w")
_W_LAST = ("qx", "q_x", "q_RS_x")


def tumvi_folder(folder: str | os.PathLike[str], bad: BadLines) -> tuple[ImuData, Trajectory | None]:
    """:func:`read_tumvi` reporting to ``bad``."""
    root = mav0_root(folder)
    mocap = root / MOCAP_CSV
    return euroc_imu(root / IMU_CSV, bad), tumvi_mocap(mocap, bad) if os.path.lexists(mocap) else None


@public_reader(tumvi_folder)
def read_tumvi(  # type: ignore[empty-body]
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


def tumvi_mocap(path: str | os.PathLike[str], bad: BadLines) -> Trajectory:
    """A TUM-VI ``mocap0/data.csv`` as a :class:`Trajectory` without velocity, reporting to ``bad``."""
    t_ns, values, lines = read_stamped_csv(
        path, bad, MOCAP_HEADER, f"TUM-VI {MOCAP_CSV.as_posix()}", quaternion=3, names=POSE_NAMES
    )
    rotation = rotations_from_rows(np.ascontiguousarray(values[:, [4, 5, 6, 3]]), lines, os.fspath(path))
    return as_file_error(path, lambda: Trajectory(None, values[:, 0:3], None, rotation, t_ns=t_ns))


def _mocap_like(path: Path, head: Head) -> bool:
    """8 comma-separated fields; read as TUM-VI mocap (w x y z) only when a header line says so."""
    if len(head.fields(",")) != 8:
        return False
    lines = head.lines or []
    header = next((text for _, text in lines if text.startswith("#") or not is_number(text.split(",")[0])), None)
    if header is None:
        raise FileFormatError(
            f"{path}: 8 comma-separated fields and no header line to tell the quaternion order; TUM-VI mocap "
            f"(w first) has '#timestamp [ns],p_RS_R_x [m],...,q_RS_w [],q_RS_x [],...': add that header, or "
            f"write t x y z qx qy qz qw separated by spaces (TUM)",
            argument="path",
        )
    names = [name.strip().lstrip("#").split(" ")[0].strip() for name in header.split(",")]
    if len(names) == 8 and names[4] in _W_FIRST:
        return True
    if len(names) == 8 and names[4] in _W_LAST:
        raise FileFormatError(
            f"{path}: the header puts the quaternion w last ({shorten(header)}); imukit reads 8 comma-separated "
            "fields as TUM-VI mocap, w first: read it with imukit.io.read_trajectory_csv(path, time_column=0, "
            "position_columns=[1, 2, 3], quaternion_columns=[4, 5, 6, 7], quaternion_order='xyzw') (the CLI: "
            "--gt-* options), or write it as TUM (t x y z qx qy qz qw, space-separated)",
            argument="path",
        )
    raise FileFormatError(
        f"{path}: the header {shorten(header)} does not name the quaternion order; TUM-VI mocap has q_RS_w "
        "(or qw) as its 5th column",
        argument="path",
    )


TUMVI_MOCAP_FOLDER = dataset_file("tumvi-mocap-folder", MOCAP_CSV, tumvi_mocap, "TUM-VI mocap")
TUMVI_FOLDER = Format("tumvi-folder", "imu", TUMVI_MOCAP_FOLDER.sniff, tumvi_folder, DATASET)
TUMVI_MOCAP = Format("tumvi-mocap", "trajectory", _mocap_like, tumvi_mocap, "TUM-VI mocap")
