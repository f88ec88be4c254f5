"""Any delimited pose file, given its columns: :func:`read_trajectory_csv`; and the detection format
for one whose header names them (``docs/io.md``, "Any trajectory CSV").

Names are compared as in :mod:`imukit.io._named_csv` (a bracketed unit dropped, lower case,
``. _ - /`` as spaces). Detected: a time column (as there), the x, y, z of a position
(``transform.translation``, ``translation``, ``pose.position``, ``position``, ``pos``, ``p``) and
the x, y, z, w of a quaternion (``transform.rotation``, ``rotation``, ``pose.orientation``,
``orientation``, ``quaternion``, ``quat``, ``q``), each component named once, so the quaternion
order is read from the names, never guessed.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any, Literal

import numpy as np

from imukit._arrays import choice
from imukit.io._blocks import zero_quaternions
from imukit.io._format import Format
from imukit.io._lines import Problem, as_file_error, public_reader, read_into, rotations_from_rows, zero_quaternion
from imukit.io._named_csv import axis_of, detected, names_sniff, time_column
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.io._table import (
    TIME_UNITS,
    Column,
    TimeUnit,
    check_columns,
    check_header_lines,
    read_stamped,
    read_table,
    stamp_unit,
)
from imukit.io._units import resolve, words_and_unit
from imukit.state import Trajectory

__all__ = ["read_trajectory_csv", "trajectory_columns"]

QUATERNION_ORDERS = ("xyzw", "wxyz")
_POSITION = ("transform translation", "translation", "pose position", "position", "pos", "p")
_QUATERNION = ("transform rotation", "rotation", "pose orientation", "orientation", "quaternion", "quat", "q")


def trajectory_csv(
    path: str | os.PathLike[str],
    bad: BadLines,
    *,
    time_column: Column,
    position_columns: Sequence[Column],
    quaternion_columns: Sequence[Column],
    quaternion_order: str,
    time_unit: str | None,
    delimiter: str | None,
    header_lines: int | None,
) -> Trajectory:
    """:func:`read_trajectory_csv` reporting to ``bad``."""
    choice(quaternion_order, "quaternion_order", QUATERNION_ORDERS)
    if time_unit is not None:
        choice(time_unit, "time_unit", TIME_UNITS)
    header_lines = check_header_lines(header_lines)
    wanted = {"time_column": [time_column], "position_columns": position_columns}
    wanted["quaternion_columns"] = quaternion_columns
    for name, given in wanted.items():
        check_columns(given, name, {"time_column": 1, "position_columns": 3, "quaternion_columns": 4}[name])
    table = read_table(path, bad, delimiter, header_lines)
    columns = [table.column(c, name) for name, names in wanted.items() for c in names]
    stated = resolve("time", time_unit, table.headers, columns[:1], "time_unit", table.where)
    time_unit = stamp_unit(table, columns[0], stated)

    def check(fields: list[str], row: list[float]) -> Problem | None:
        return zero_quaternion(row[4:8])

    data = read_stamped(table, bad, columns, time_unit, check, zero_quaternions(4))
    quat = data.values[:, 4:8] if quaternion_order == "xyzw" else data.values[:, [5, 6, 7, 4]]
    rotation = rotations_from_rows(np.ascontiguousarray(quat), data.lines, table.where)
    return as_file_error(path, lambda: Trajectory(data.stamps, data.values[:, 1:4], None, rotation))


@public_reader(trajectory_csv)
def read_trajectory_csv(  # type: ignore[empty-body]
    path: str | os.PathLike[str],
    *,
    time_column: Column,
    position_columns: Sequence[Column],
    quaternion_columns: Sequence[Column],
    quaternion_order: Literal["xyzw", "wxyz"] = "xyzw",
    time_unit: TimeUnit | None = None,
    delimiter: str | None = None,
    header_lines: int | None = None,
    on_bad_line: OnBadLine = "raise",
    report: ReadReport | None = None,
) -> Trajectory:
    """Read poses from a delimited text file, naming its columns: a ground truth or an estimate in a
    layout of its own (a motion-capture export, ``rostopic echo -p`` of a ``TransformStamped``).

    Parameters
    ----------
    path
        The text file; header lines, trailing delimiters and field counts as
        :func:`imukit.io.read_imu_csv` reads them.
    time_column, position_columns, quaternion_columns
        The time column, the x, y, z columns of the position [m] and the four columns of the
        quaternion ``R_wb`` (body to world), each a header name or a 0-based index.
    quaternion_order
        ``"xyzw"`` (default: scalar last, ROS and scipy) or ``"wxyz"`` (scalar first, EuRoC): the
        order of ``quaternion_columns``. Quaternions unit to 1e-15 are kept bit for bit, others
        normalised.
    time_unit, delimiter, header_lines
        As in :func:`imukit.io.read_imu_csv` (``"ns"``, and integer ``"ms"`` / ``"us"``: exact
        ``t_ns``; None (default): the unit the time column's name states, else ``"ns"`` for an
        integer stamp above 10¹⁴, else ``"s"``; a given unit that contradicts the name's warns).
    on_bad_line, report
        As in :func:`imukit.io.read_euroc_imu`; a zero quaternion is a bad line too.

    Returns
    -------
    Trajectory
        ``velocity`` None (a scoring command differentiates the positions where it needs one).

    Raises
    ------
    ParameterError
        An order, unit or delimiter outside its domain, a column not in the header, not 3 position
        or 4 quaternion columns (messages start with the argument's name).
    FileFormatError
        Naming the file and line: bad lines (``"raise"`` mode), no data, a header whose field count
        differs from the data lines'.
    """


def trajectory_columns(names: list[str]) -> dict[str, Any] | None:
    """:func:`read_trajectory_csv`'s column keywords (``time_column``, ``position_columns``,
    ``quaternion_columns`` as indices, ``quaternion_order="xyzw"``, ``time_unit``: ``"ns"`` for ROS's
    stamps, else None: the unit the name states, read by the reader) from a header line's ``names``
    (module doc), or None unless each is named exactly once."""
    split = [words_and_unit(name) for name in names]
    found: dict[str, dict[str, list[int]]] = {"position": {}, "quaternion": {}}
    for k, (words, _) in enumerate(split):
        axis = axis_of(words, "xyzw")
        if axis is not None:
            for role, prefixes in (("position", _POSITION), ("quaternion", _QUATERNION)):
                if axis[0] in prefixes:
                    found[role].setdefault(axis[1], []).append(k)
    position, quaternion = found["position"], found["quaternion"]
    if not all(len(position.get(a, [])) == 1 for a in "xyz") or not all(
        len(quaternion.get(a, [])) == 1 for a in "xyzw"
    ):
        return None
    time = time_column(split)
    if time is None:
        return None
    return {
        "time_column": time[0],
        "position_columns": [position[a][0] for a in "xyz"],
        "quaternion_columns": [quaternion[a][0] for a in "xyzw"],
        "quaternion_order": "xyzw",
        "time_unit": time[1],
    }


def named_trajectory_csv(path: str | os.PathLike[str], bad: BadLines) -> Trajectory:
    """A CSV file read by the pose columns its header names (module doc), through ``read_trajectory_csv``."""
    _, options = detected(path, trajectory_columns, "time, position and quaternion")
    return read_into(bad, read_trajectory_csv, path, header_lines=1, **options)


NAMED_TRAJECTORY_CSV = Format(
    "named-trajectory-csv",
    "trajectory",
    names_sniff(trajectory_columns),
    named_trajectory_csv,
    "CSV with named pose columns",
)
