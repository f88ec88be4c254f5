"""Readers that find the format themselves: :func:`read_imu`, :func:`read_trajectory` (``docs/io.md``).

Both try the formats of :mod:`imukit.io._registry` in order (:func:`imukit.io.formats`) and read the
path with the first whose sniff accepts it; the "tried …" text of an unknown path lists them.
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from imukit._errors import FileFormatError, ParameterError
from imukit.imu import ImuData
from imukit.io._csv import read_imu_csv
from imukit.io._euroc import GROUNDTRUTH_CSV, dataset_root
from imukit.io._format import Format, Head, is_number, shorten
from imukit.io._lines import integer_stamp, public_reader, read_into
from imukit.io._registry import formats, listing
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.io._tumvi import MOCAP_CSV
from imukit.state import Trajectory

__all__ = ["read_imu", "read_trajectory"]

# The bag options of read_imu, for the error when they are given for another format.
_BAG_PATHS = "a .bag, .mcap or .db3 file, or a folder with metadata.yaml"


def detect_imu(
    path: str | os.PathLike[str],
    bad: BadLines,
    *,
    imu_topic: str | None,
    groundtruth_topic: str | None,
    time_source: str | None,
    csv: Mapping[str, Any] | None,
) -> tuple[ImuData, Trajectory | None]:
    """:func:`read_imu` reporting to ``bad``."""
    source, head = Path(path), Head(Path(path))
    options = {"imu_topic": imu_topic, "groundtruth_topic": groundtruth_topic, "time_source": time_source}
    given: dict[str, Any] = {name: value for name, value in options.items() if value is not None}
    if csv is not None:
        for name, value in given.items():
            raise ParameterError(f"{value!r} is for ROS bags, not for a CSV file read by its columns", argument=name)
        known = set(inspect.signature(read_imu_csv).parameters) - {"path", "on_bad_line", "report"}
        for name in csv:  # a bare TypeError from the call would name neither csv= nor the keyword
            if name not in known:
                raise ParameterError(
                    f"{name!r} is no keyword of read_imu_csv ({', '.join(sorted(known))})", argument="csv"
                )
        return read_into(bad, read_imu_csv, path, **csv), None
    fmt = _first(source, head, "imu")
    if fmt is None and not os.path.lexists(source):
        raise FileNotFoundError(f"path: {os.fspath(path)} does not exist")
    extra = [name for name in given if fmt is None or name not in fmt.options]
    if extra:  # nothing but the ROS bag reader would use them
        raise ParameterError(
            f"{given[extra[0]]!r} is for ROS bags, but {os.fspath(path)} is not one ({_BAG_PATHS})", argument=extra[0]
        )
    if fmt is None:
        _refuse(path, head, "imu", "IMU samples")
        trajectory = _trajectory_kind(head)
        if trajectory is not None:
            raise FileFormatError(
                f"{os.fspath(path)}: this is a trajectory ({trajectory}), not IMU samples", argument="path"
            )
        raise FileFormatError(
            f"{os.fspath(path)}: not an IMU format imukit knows; tried {listing('imu')}", argument="path"
        )
    result = fmt.read(path, bad, **given)
    return result if isinstance(result, tuple) else (result, None)


@public_reader(detect_imu)
def read_imu(  # type: ignore[empty-body]
    path: str | os.PathLike[str],
    *,
    imu_topic: str | None = None,
    groundtruth_topic: str | None = None,
    time_source: Literal["header", "record"] | None = None,
    csv: Mapping[str, Any] | None = None,
    on_bad_line: OnBadLine = "raise",
    report: ReadReport | None = None,
) -> tuple[ImuData, Trajectory | None]:
    """Read IMU samples (and ground truth where the source has it) from any supported source.

    Detection: the first of :func:`imukit.io.formats` ``("imu")`` whose sniff accepts ``path``; the
    built-in ones, in this order:

    1. a folder with ``imu0/data.csv`` (or ``mav0/imu0/data.csv``): TUM-VI
       (:func:`imukit.io.read_tumvi`) when ``mocap0/data.csv`` is next to ``imu0/``, else EuRoC
       (:func:`imukit.io.read_euroc`);
    2. a file whose first data line (after ``#`` lines) has 7 comma-separated fields and an integer
       first field: an EuRoC / TUM-VI ``imu0/data.csv`` (:func:`imukit.io.read_euroc_imu`);
    3. a file whose first non-blank line is ``Time dt accelX accelY accelZ omegaX omegaY omegaZ``:
       GTSAM / KITTI text (:func:`imukit.io.read_gtsam_imu`);
    4. a folder with ``metadata.yaml`` (a ROS 2 bag), or a file named ``*.bag``, ``*.mcap`` or
       ``*.db3`` (any case): a ROS bag (:func:`imukit.io.read_rosbag`);
    5. a file whose first line names a time column and the x, y, z of gyro and accelerometer
       (``Time, angular_velocity.x, …, linear_acceleration.x, …``; ``docs/io.md``): read by
       :func:`imukit.io.read_imu_csv` with those columns and the units the names state.

    Formats added with :func:`imukit.io.register_format` come after these (or where they are put).

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
    csv
        The keyword arguments of :func:`imukit.io.read_imu_csv` (``time_column``, ``gyro_columns``,
        ``accel_columns``, units, ``delimiter``): ``path`` is a CSV file of that layout, read by it
        (no ground truth) instead of found by its format. None (default): detection.
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


def detect_trajectory(path: str | os.PathLike[str], bad: BadLines) -> Trajectory:
    """:func:`read_trajectory` reporting to ``bad``."""
    source, head = Path(path), Head(Path(path))
    fmt = _first(source, head, "trajectory")
    if fmt is None:
        root = dataset_root(source)
        if root is not None:
            raise FileFormatError(
                f"{os.fspath(path)}: a dataset folder without ground truth "
                f"(no {GROUNDTRUTH_CSV.as_posix()} nor {MOCAP_CSV.as_posix()} in {root})",
                argument="path",
            )
        _refuse(path, head, "trajectory", "a trajectory")
        raise FileFormatError(
            f"{os.fspath(path)}: not a trajectory format imukit knows; tried {listing('trajectory')}", argument="path"
        )
    if fmt.kind != "both":
        trajectory: Trajectory = fmt.read(path, bad)
        return trajectory
    truth: Trajectory | None = fmt.read(path, bad)[1]
    if truth is None:
        raise FileFormatError(f"{os.fspath(path)}: {fmt.description} without a trajectory", argument="path")
    return truth


@public_reader(detect_trajectory)
def read_trajectory(  # type: ignore[empty-body]
    path: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> Trajectory:
    """Read a trajectory (ground truth or an estimate) from a TUM, EuRoC or TUM-VI file or folder.

    Detection: the first of :func:`imukit.io.formats` ``("trajectory")`` whose sniff accepts ``path``
    (formats added with :func:`imukit.io.register_format` after the built-in ones); built in: a
    folder with ``imu0/data.csv`` (or under ``mav0/``) gives its
    ``state_groundtruth_estimate0/data.csv`` (EuRoC) or else its ``mocap0/data.csv`` (TUM-VI). A file
    is classified by its first data line (after ``#`` and blank lines): 17 comma-separated fields,
    EuRoC ground truth (:func:`imukit.io.read_euroc_groundtruth`); a first line naming a time column,
    a position's x, y, z and a quaternion's x, y, z, w (``transform.translation.x`` …
    ``transform.rotation.w``): :func:`imukit.io.read_trajectory_csv` with them; 8 comma-separated
    fields, TUM-VI mocap (``timestamp [ns], p x y z, q w x y z``) when a header line names the quaternion w first
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


def _first(source: Path, head: Head, kind: Literal["imu", "trajectory"]) -> Format | None:
    """The first format of ``kind`` whose sniff accepts ``source``."""
    return next((fmt for fmt in formats(kind) if fmt.sniff(source, head)), None)


def _not_utf8(source: Path) -> str:
    """What is wrong with a file that is not UTF-8 text: the first byte that is not, or binary data
    (only a regular file is opened: a FIFO would block, a symlink loop raise)."""
    if not source.is_file():
        return "not a text file"
    with open(source, "rb") as f:
        data = f.read(1 << 20)
    if b"\0" in data:
        return "not a text file"  # NUL bytes: binary data
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as e:
        byte, line = data[e.start], data[: e.start].count(b"\n") + 1
        return (
            f"not UTF-8 text: byte 0x{byte:02x} on line {line} (Latin-1 or Windows-1252, such as '°' from an "
            "exporter?); save it as UTF-8, or read it with read_imu_csv, which reads such a byte as text"
        )
    return "not a text file"


def _refuse(path: str | os.PathLike[str], head: Head, kind: Literal["imu", "trajectory"], expected: str) -> None:
    """The FileFormatError for a path no format accepts, when it is a folder, missing, not text, empty, or
    without data lines (a header only)."""
    where = os.fspath(path)
    source = Path(path)
    if not os.path.lexists(source):  # a symlink loop or a dangling link exists, and is refused below
        raise FileNotFoundError(f"path: {where} does not exist")
    if source.is_dir():
        raise FileFormatError(f"{where}: a folder of no known layout; tried {listing(kind)}", argument="path")
    first = head.lines
    if first is None:
        raise FileFormatError(f"{where}: {_not_utf8(source)}; tried {listing(kind)}", argument="path")
    if not first:
        raise FileFormatError(f"{where}: empty file, expected {expected}", argument="path")
    if all(text.startswith("#") for _, text in first):
        header = first[0][1]
        raise FileFormatError(
            f"{where}: no data lines, only the header {shorten(header)}, expected {expected}", argument="path"
        )


def _trajectory_kind(head: Head) -> str | None:
    """The trajectory format the first data line looks like (for an error saying so), else None."""
    comma, space = head.fields(","), head.fields(None)
    if len(comma) == 17:
        return "EuRoC ground truth, 17 comma-separated fields"
    numbers = [text.split(",") for _, text in head.lines or () if is_number(text.split(",")[0])]  # past a names line
    if len(comma) == 8 and numbers and len(numbers[0]) == 8 and integer_stamp(numbers[0][0].strip()) is not None:
        return "TUM-VI mocap or another pose CSV, 8 comma-separated fields"
    if len(comma) == 1 and len(space) == 8 and all(is_number(field) for field in space):
        return "TUM: t x y z qx qy qz qw"
    return None
