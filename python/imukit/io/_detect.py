"""Readers that find the format themselves: :func:`read_imu`, :func:`read_trajectory` (``docs/io.md``)."""

from __future__ import annotations

import os
from itertools import islice
from pathlib import Path
from typing import Any, Literal

from imukit._errors import FileFormatError, ParameterError
from imukit.imu import ImuData
from imukit.io import _rosbag  # rosbags itself is imported on a bag's first read
from imukit.io._euroc import GROUNDTRUTH_CSV, IMU_CSV, euroc_folder, euroc_groundtruth, euroc_imu
from imukit.io._gtsam import GTSAM_COLUMNS, gtsam_imu
from imukit.io._lines import data_lines, integer_stamp
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.io._tum import tum
from imukit.io._tumvi import MOCAP_CSV, tumvi_folder, tumvi_mocap
from imukit.state import Trajectory

__all__ = ["read_imu", "read_trajectory"]

IMU_FORMATS = "EuRoC / TUM-VI folder or imu0/data.csv, GTSAM / KITTI text, ROS bag; other layouts: read_imu_csv"
TRAJECTORY_FORMATS = "TUM, EuRoC ground truth, TUM-VI mocap (or their folders); KITTI poses: read_kitti_poses"
# The column names that put TUM-VI mocap's w first (its header), and the usual names of a w-last one.
_W_FIRST = ("q_RS_w", "qw", "q_w")
_W_LAST = ("qx", "q_x", "q_RS_x")


def read_imu(
    path: str | os.PathLike[str],
    *,
    imu_topic: str | None = None,
    groundtruth_topic: str | None = None,
    time_source: Literal["header", "record"] | None = None,
    on_bad_line: OnBadLine = "raise",
    report: ReadReport | None = None,
) -> tuple[ImuData, Trajectory | None]:
    """Read IMU samples (and ground truth where the source has it) from any supported source.

    Detection, in this order:

    1. a folder with ``metadata.yaml``: a ROS 2 bag (:func:`imukit.io.read_rosbag`);
    2. a folder with ``imu0/data.csv`` (or ``mav0/imu0/data.csv``): TUM-VI
       (:func:`imukit.io.read_tumvi`) when ``mocap0/data.csv`` is next to ``imu0/``, else EuRoC
       (:func:`imukit.io.read_euroc`);
    3. a file named ``*.bag``, ``*.mcap`` or ``*.db3`` (any case): a ROS bag;
    4. a file whose first non-blank line is ``Time dt accelX accelY accelZ omegaX omegaY omegaZ``:
       GTSAM / KITTI text (:func:`imukit.io.read_gtsam_imu`);
    5. a file whose first data line (after ``#`` lines) has 7 comma-separated fields and an integer
       first field: an EuRoC / TUM-VI ``imu0/data.csv`` (:func:`imukit.io.read_euroc_imu`).

    Anything else is a :class:`FileFormatError`: an empty file, a file with no data lines (a header
    only), a trajectory (TUM, EuRoC ground truth, TUM-VI mocap) are said to be so; otherwise the
    message lists the formats tried (other CSV layouts: :func:`imukit.io.read_imu_csv`).

    Parameters
    ----------
    path
        File or folder.
    imu_topic, groundtruth_topic, time_source
        For ROS bags only, passed to :func:`imukit.io.read_rosbag` (None: its defaults, the bag's
        only IMU / ground-truth topic and ``header.stamp`` times); given for any other source they
        are a :class:`ParameterError`, since nothing would use them.
    on_bad_line, report
        Passed to the reader chosen (see :func:`imukit.io.read_euroc_imu`).

    Returns
    -------
    imu, truth
        ``truth`` is the ground truth of a folder or bag that has one, else None.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    FileFormatError
        No format recognised, or as the reader chosen.
    ParameterError
        A bag option for a source that is not a bag, or as :func:`imukit.io.read_rosbag` (a topic
        missing, of the wrong type, or not given where the bag has several candidates).
    """
    source = Path(path)
    bag_options = {"imu_topic": imu_topic, "groundtruth_topic": groundtruth_topic, "time_source": time_source}
    given: dict[str, Any] = {name: value for name, value in bag_options.items() if value is not None}
    if (source.is_dir() and (source / "metadata.yaml").is_file()) or _rosbag.is_bag_path(source):
        return _rosbag.read_rosbag(path, **given, on_bad_line=on_bad_line, report=report)
    if not source.exists():
        raise FileNotFoundError(f"path: {os.fspath(path)} does not exist")
    if given:  # nothing but read_rosbag would use them
        name, value = next(iter(given.items()))
        raise ParameterError(
            f"{name}: {value!r} is for ROS bags, but {os.fspath(path)} is not one "
            "(a .bag, .mcap or .db3 file, or a folder with metadata.yaml)"
        )
    bad = BadLines(on_bad_line, report)
    root = _dataset_root(source)
    if root is not None:
        read = tumvi_folder if (root / MOCAP_CSV).is_file() else euroc_folder
        return bad.done(read(root, bad))
    first = _first_lines(source, IMU_FORMATS)
    if first and first[0][1].split() == GTSAM_COLUMNS:
        return bad.done((gtsam_imu(path, bad), None))
    fields = _first_data_fields(first, ",")
    if len(fields) == 7 and integer_stamp(fields[0].strip()) is not None:
        return bad.done((euroc_imu(path, bad), None))
    where = f"path: {os.fspath(path)}"
    _refuse_without_data(first, where, "IMU samples")
    trajectory = _trajectory_kind(first)
    if trajectory is not None:
        raise FileFormatError(f"{where}: this is a trajectory ({trajectory}), not IMU samples")
    raise FileFormatError(f"{where}: not an IMU format imukit knows; tried {IMU_FORMATS}")


def read_trajectory(
    path: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> Trajectory:
    """Read a trajectory (ground truth or an estimate) from a TUM, EuRoC or TUM-VI file or folder.

    Detection: a folder with ``imu0/data.csv`` (or under ``mav0/``) gives its
    ``state_groundtruth_estimate0/data.csv`` (EuRoC) or else its ``mocap0/data.csv`` (TUM-VI). A file
    is classified by its first data line (after ``#`` and blank lines): 17 comma-separated fields,
    EuRoC ground truth (:func:`imukit.io.read_euroc_groundtruth`); 8 comma-separated fields, TUM-VI
    mocap (``timestamp [ns], p x y z, q w x y z``) when a header line names the quaternion w first
    (``q_RS_w``, ``qw``), refused without a header or with w last (``t,x,y,z,qx,qy,qz,qw``: the order
    cannot be guessed from numbers, and a wrong one is silently wrong); 8 white-space-separated
    fields, TUM (:func:`imukit.io.read_tum`). An empty file or one without data lines is said to be
    so; anything else is a :class:`FileFormatError` listing the formats tried (KITTI poses need
    their times file: :func:`imukit.io.read_kitti_poses`).

    ``on_bad_line`` and ``report`` are passed to the reader chosen.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    FileFormatError
        No format recognised, a folder without ground truth, or as the reader chosen.
    """
    source = Path(path)
    bad = BadLines(on_bad_line, report)
    root = _dataset_root(source)
    if root is not None:
        for name, read in ((GROUNDTRUTH_CSV, euroc_groundtruth), (MOCAP_CSV, tumvi_mocap)):
            if (root / name).is_file():
                return bad.done(read(root / name, bad))
        raise FileFormatError(
            f"path: {os.fspath(path)}: a dataset folder without ground truth "
            f"(no {GROUNDTRUTH_CSV.as_posix()} nor {MOCAP_CSV.as_posix()} in {root})"
        )
    first = _first_lines(source, TRAJECTORY_FORMATS)
    where = f"path: {os.fspath(path)}"
    _refuse_without_data(first, where, "a trajectory")
    comma, space = len(_first_data_fields(first, ",")), len(_first_data_fields(first, None))
    if comma == 17:
        return bad.done(euroc_groundtruth(path, bad))
    if comma == 8:
        _check_w_first(first, where)
        return bad.done(tumvi_mocap(path, bad))
    if comma == 1 and space == 8:
        return bad.done(tum(path, bad))
    raise FileFormatError(f"{where}: not a trajectory format imukit knows; tried {TRAJECTORY_FORMATS}")


def _dataset_root(source: Path) -> Path | None:
    """``source`` or its ``mav0/`` when it holds ``imu0/data.csv``, else None."""
    for root in (source, source / "mav0"):
        if source.is_dir() and (root / IMU_CSV).is_file():
            return root
    return None


def _first_lines(source: Path, formats: str) -> list[tuple[int, str]]:
    """The first two non-blank lines, and the first data line after them if it comes later (a header
    block of ``#`` lines); FileNotFoundError for a missing path, FileFormatError for a folder or a file
    that is not UTF-8 text."""
    if not source.exists():
        raise FileNotFoundError(f"path: {os.fspath(source)} does not exist")
    if source.is_dir():
        raise FileFormatError(f"path: {os.fspath(source)}: a folder of no known layout; tried {formats}")
    try:
        with open(source, encoding="utf-8-sig") as f:  # -sig: a byte order mark is not part of the first line
            first = list(islice(((n, line.strip()) for n, line in enumerate(f, 1) if line.strip()), 2))
        return first + list(islice(data_lines(source), 1))
    except UnicodeDecodeError:
        raise FileFormatError(f"path: {os.fspath(source)}: not a text file; tried {formats}") from None


def _first_data_fields(first: list[tuple[int, str]], delimiter: str | None) -> list[str]:
    """The fields of the first line that is not a ``#`` comment, [] if there is none."""
    for _, text in first:
        if not text.startswith("#"):
            return text.split(delimiter)
    return []


def _refuse_without_data(first: list[tuple[int, str]], where: str, expected: str) -> None:
    """A FileFormatError for a file with no lines, or with ``#`` lines only (a header without data)."""
    if not first:
        raise FileFormatError(f"{where}: empty file, expected {expected}")
    if all(text.startswith("#") for _, text in first):
        header = first[0][1]
        raise FileFormatError(f"{where}: no data lines, only the header {_shorten(header)}, expected {expected}")


def _trajectory_kind(first: list[tuple[int, str]]) -> str | None:
    """The trajectory format the first data line looks like (for an error saying so), else None."""
    comma, space = _first_data_fields(first, ","), _first_data_fields(first, None)
    if len(comma) == 17:
        return "EuRoC ground truth, 17 comma-separated fields"
    numbers = [text.split(",") for _, text in first if _number(text.split(",")[0])]  # past a names line
    if len(comma) == 8 and numbers and len(numbers[0]) == 8 and integer_stamp(numbers[0][0].strip()) is not None:
        return "TUM-VI mocap or another pose CSV, 8 comma-separated fields"
    if len(comma) == 1 and len(space) == 8 and all(_number(field) for field in space):
        return "TUM: t x y z qx qy qz qw"
    return None


def _check_w_first(first: list[tuple[int, str]], where: str) -> None:
    """An 8-field comma file is read as TUM-VI mocap (w x y z) only when its header says so."""
    header = next((text for _, text in first if text.startswith("#") or not _number(text.split(",")[0])), None)
    if header is None:
        raise FileFormatError(
            f"{where}: 8 comma-separated fields and no header line to tell the quaternion order; TUM-VI mocap "
            f"(w first) has '#timestamp [ns],p_RS_R_x [m],...,q_RS_w [],q_RS_x [],...': add that header, or "
            f"write t x y z qx qy qz qw separated by spaces (TUM)"
        )
    names = [name.strip().lstrip("#").split(" ")[0].strip() for name in header.split(",")]
    if len(names) == 8 and names[4] in _W_FIRST:
        return
    if len(names) == 8 and names[4] in _W_LAST:
        raise FileFormatError(
            f"{where}: the header puts the quaternion w last ({_shorten(header)}); imukit reads 8 comma-separated "
            "fields as TUM-VI mocap, w first: write the file as TUM (t x y z qx qy qz qw, space-separated)"
        )
    raise FileFormatError(
        f"{where}: the header {_shorten(header)} does not name the quaternion order; TUM-VI mocap has q_RS_w "
        "(or qw) as its 5th column"
    )


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _shorten(text: str, limit: int = 80) -> str:
    return repr(text if len(text) <= limit else text[: limit - 3] + "...")
