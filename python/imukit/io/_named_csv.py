"""CSV files whose header names say what each column is: :func:`column_roles` and the detection format
that reads them with :func:`imukit.io.read_imu_csv` (``docs/io.md``, "Columns found by name").

A name is compared after dropping a unit in brackets (``Gyroscope X (deg/s)``, ``time [ns]``),
lower-casing, and turning ``. _ - /`` into spaces, so ``angular_velocity.x`` (ROS, also as
``field.angular_velocity.x`` from ``rostopic echo -p``), ``Gyroscope X (deg/s)`` (x-io) and
``gyro_x`` are one spelling:

=========  ==================================================================================
role       names (then an axis ``x``, ``y``, ``z``; each axis exactly once)
=========  ==================================================================================
``time``   ``time``, ``t``, ``timestamp``, ``stamp``, ``header stamp``, ``%time`` (one of them;
           the first of this order when several)
``gyro``   ``angular velocity``, ``gyroscope``, ``gyro``, ``gyr``, ``omega``, ``g`` (``gx``)
``accel``  ``linear acceleration``, ``accelerometer``, ``acceleration``, ``accel``, ``acc``,
           ``a`` (``ax``)
``mag``    ``magnetic field``, ``magnetometer``, ``mag``, ``m`` (``mx``); optional
=========  ==================================================================================

Units: those the names state (a bracket, ``time_ns``), read by :func:`imukit.io.read_imu_csv`
(``imukit.io._units``; it refuses a unit it does not know and x, y, z that disagree); ROS's
``header.stamp`` and ``%time`` columns of ``rostopic echo -p`` are nanoseconds, and so is an
unlabelled integer stamp above 10¹⁴ (as seconds: three million years). The magnetometer's
columns, when named, are read into ``ImuData.mag`` as they are (µT by convention).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple, TypeVar

from imukit._errors import FileFormatError
from imukit.imu import ImuData
from imukit.io._csv import read_imu_csv
from imukit.io._format import Format, Head, is_number
from imukit.io._lines import read_into
from imukit.io._report import BadLines
from imukit.io._table import Table, detect_delimiter, header_fields, read_table
from imukit.io._units import canonical, time_suffix, unit_in_name, words_and_unit

__all__ = ["ColumnRoles", "FixedLayout", "column_roles", "departure"]

_TIME = ("time", "t", "timestamp", "stamp", "header stamp", "field header stamp", "%time")
_ROS_NS = ("header stamp", "field header stamp", "%time")  # rostopic echo -p: integer nanoseconds
_VECTORS = {
    "gyro": ("angular velocity", "field angular velocity", "gyroscope", "gyro", "gyr", "omega", "g"),
    "accel": ("linear acceleration", "field linear acceleration", "accelerometer", "acceleration", "accel", "acc", "a"),
    "mag": ("magnetic field", "field magnetic field", "magnetometer", "mag", "m"),
}
_T = TypeVar("_T")


class ColumnRoles(NamedTuple):
    """What :func:`column_roles` found: 0-based ``columns`` per role (``"time"`` one, ``"gyro"``,
    ``"accel"`` and when present ``"mag"`` three, x y z), and ``"ns"`` for ROS's ``header.stamp``
    and ``%time`` columns, whose names state no unit (the units names state are
    :func:`imukit.io.read_imu_csv`'s to read)."""

    columns: dict[str, list[int]]
    time_unit: str | None


def axis_of(words: str, axes: str = "xyz") -> tuple[str, str] | None:
    """``"angular velocity x"`` → ``("angular velocity", "x")``; ``"gx"`` → ``("g", "x")``."""
    if len(words) >= 2 and words[-1] in axes and words[-2] == " ":
        return words[:-2], words[-1]
    if len(words) == 2 and words[1] in axes:
        return words[0], words[1]
    return None


def time_column(split: list[tuple[str, str]]) -> tuple[int, str | None] | None:
    """The time column among names split by :func:`words_and_unit` (``time_ns`` is ``time`` with its
    unit), and ``"ns"`` for ROS's stamps (their names state no unit), else None; None when there is
    none, or two of the best rank."""
    bare = [suffix[0] if (suffix := time_suffix(words)) else words for words, _ in split]
    times = [(_TIME.index(words), k) for k, words in enumerate(bare) if words in _TIME]
    ranks = [rank for rank, _ in times]
    if not times or ranks.count(min(ranks)) > 1:
        return None
    k = min(times)[1]
    return k, "ns" if bare[k] in _ROS_NS else None


def column_roles(names: list[str]) -> ColumnRoles | None:
    """The time, gyro, accelerometer and magnetometer columns that ``names`` (a header line's fields)
    name (module doc), or None unless one time column and the x, y, z of both gyro and accelerometer
    are each named exactly once."""
    split = [words_and_unit(name) for name in names]
    found: dict[str, dict[str, list[int]]] = {role: {} for role in _VECTORS}
    for k, (words, _) in enumerate(split):
        axis = axis_of(words)
        for role, prefixes in _VECTORS.items():
            if axis is not None and axis[0] in prefixes:
                found[role].setdefault(axis[1], []).append(k)
    columns: dict[str, list[int]] = {}
    for role, axes in found.items():
        if all(len(axes.get(a, [])) == 1 for a in "xyz"):
            columns[role] = [axes[a][0] for a in "xyz"]
        elif role != "mag":
            return None
    time = time_column(split)
    if time is None:
        return None
    return ColumnRoles({"time": [time[0]], **columns}, time[1])


class FixedLayout(NamedTuple):
    """A format that reads its columns by position (EuRoC's), as a header naming them would say it:
    ``roles`` reads a header's names (``column_roles``' or ``trajectory_columns``' rules, role →
    0-based columns), ``columns`` are the format's, ``units`` the format's unit per role that
    :mod:`imukit.io._units` knows, ``by_names`` the reader that reads such a file by its names."""

    roles: Callable[[list[str]], dict[str, list[int]] | None]
    columns: dict[str, list[int]]
    units: dict[str, str]
    by_names: str


def imu_roles(names: list[str]) -> dict[str, list[int]] | None:
    """:func:`column_roles`' columns by role, or None."""
    roles = column_roles(names)
    return None if roles is None else roles.columns


def departure(names: list[str] | None, layout: FixedLayout) -> str | None:
    """How a header whose names say what its columns hold departs from ``layout``: other columns, or a
    unit other than the layout's; None when its names say nothing the rules read, or say the layout.
    A format read by position must not read such a file: the names are the file's own account."""
    found = None if names is None else layout.roles(names)
    if names is None or found is None:
        return None
    if found != layout.columns:
        moved = [role for role in found if found[role] != layout.columns.get(role)]
        said = ", ".join(f"{role} in columns {', '.join(str(k + 1) for k in found[role])}" for role in moved)
        return f"puts {said} ({', '.join(repr(names[found[role][0]]) for role in moved)})"
    for role, unit in layout.units.items():
        for k in found[role]:
            text = unit_in_name(role, names[k])
            if text and canonical(role, text) != unit:
                return f"states {names[k]!r}, where this layout holds {unit}"
    return None


def header_names(head: Head) -> list[str] | None:
    """The fields of the first non-blank line when it is a header (its first field not a number)."""
    if not head.lines:
        return None
    first = head.lines[0][1]
    fields = header_fields(first, detect_delimiter(first))
    return None if is_number(fields[0]) else fields


def names_sniff(detect: Callable[[list[str]], object | None]) -> Callable[[Path, Head], bool]:
    """A format's sniff: the first line is a header whose names ``detect`` finds its columns in."""

    def sniff(path: Path, head: Head) -> bool:
        names = header_names(head)
        return names is not None and detect(names) is not None

    return sniff


def detected(path: str | os.PathLike[str], detect: Callable[[list[str]], _T | None], what: str) -> tuple[Table, _T]:
    """``path`` as a table with a one-line header, and what ``detect`` finds in its names; a
    FileFormatError saying ``what`` the header does not name when it finds nothing (the reader called
    directly, or the file changed since the sniff)."""
    table = read_table(path, BadLines("raise", None), None, 1)  # one header line: nothing to report
    found = detect(table.headers[0][1]) if table.headers else None
    if found is None:
        raise FileFormatError(f"{os.fspath(path)}: its header does not name {what} columns", argument="path")
    return table, found


def named_csv(path: str | os.PathLike[str], bad: BadLines) -> ImuData:
    """A CSV file read by the columns its header names (module doc), through ``read_imu_csv``."""
    _, roles = detected(path, column_roles, "time, gyro and accelerometer")
    # Units: those the names state, read by read_imu_csv, which refuses one it does not know.
    options: dict[str, Any] = {
        "time_column": roles.columns["time"][0],
        "gyro_columns": roles.columns["gyro"],
        "accel_columns": roles.columns["accel"],
        "time_unit": roles.time_unit,
        "mag_columns": roles.columns.get("mag"),
    }
    return read_into(bad, read_imu_csv, path, header_lines=1, **options)


NAMED_CSV = Format("named-csv", "imu", names_sniff(column_roles), named_csv, "CSV with named IMU columns")
