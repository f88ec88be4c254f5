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

Units from the bracket: time ``ns`` / ``ms`` / ``us`` (else seconds; ROS's ``header.stamp`` and
``%time`` columns of ``rostopic echo -p`` are nanoseconds, and so is an unlabelled integer stamp
above 10¹⁴, which as seconds would be three million years), gyro ``deg/s`` (``°/s``, ``dps``; else
rad/s), accel ``g`` (else m/s²). The magnetometer's columns, when named, are read into
``ImuData.mag`` as they are (µT by convention).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple, TypeVar

from imukit._errors import FileFormatError
from imukit.imu import ImuData
from imukit.io._csv import read_imu_csv
from imukit.io._format import Format, Head, is_number
from imukit.io._lines import read_into
from imukit.io._report import BadLines
from imukit.io._table import Table, read_table

__all__ = ["ColumnRoles", "column_roles"]

_TIME = ("time", "t", "timestamp", "stamp", "header stamp", "field header stamp", "%time")
_ROS_NS = ("header stamp", "field header stamp", "%time")  # rostopic echo -p: integer nanoseconds
_VECTORS = {
    "gyro": ("angular velocity", "field angular velocity", "gyroscope", "gyro", "gyr", "omega", "g"),
    "accel": ("linear acceleration", "field linear acceleration", "accelerometer", "acceleration", "accel", "acc", "a"),
    "mag": ("magnetic field", "field magnetic field", "magnetometer", "mag", "m"),
}
_TIME_UNITS = {"ns": "ns", "nsec": "ns", "ms": "ms", "us": "us", "µs": "us", "s": "s", "sec": "s"}
_DEGREES = ("deg/s", "°/s", "dps", "deg s^-1")
_UNIT = re.compile(r"\s*[\[(]([^\])]*)[\])]\s*$")
_T = TypeVar("_T")
_NS_STAMP = 1e14  # an unlabelled integer stamp above this is nanoseconds (as seconds: 3 million years)


class ColumnRoles(NamedTuple):
    """What :func:`column_roles` found: 0-based ``columns`` per role (``"time"`` one, ``"gyro"``,
    ``"accel"`` and when present ``"mag"`` three, x y z) and the units the names state."""

    columns: dict[str, list[int]]
    time_unit: str | None  # "ns", "ms", "us", "s", or None when the name does not say
    gyro_unit: str  # "rad/s" or "deg/s"
    accel_unit: str  # "m/s^2" or "g"


def words_and_unit(name: str) -> tuple[str, str]:
    """``name`` as (its words, its bracketed unit): ``"Gyroscope X (deg/s)"`` → ``("gyroscope x", "deg/s")``."""
    unit = _UNIT.search(name)
    bare = name[: unit.start()] if unit else name
    words = re.sub(r"[._\-/\s]+", " ", bare.strip().lstrip("#").lower()).strip()
    return words, (unit[1].strip().lower() if unit else "")


def axis_of(words: str, axes: str = "xyz") -> tuple[str, str] | None:
    """``"angular velocity x"`` → ``("angular velocity", "x")``; ``"gx"`` → ``("g", "x")``."""
    if len(words) >= 2 and words[-1] in axes and words[-2] == " ":
        return words[:-2], words[-1]
    if len(words) == 2 and words[1] in axes:
        return words[0], words[1]
    return None


def time_column(split: list[tuple[str, str]]) -> tuple[int, str | None] | None:
    """The time column among names split by :func:`words_and_unit`, and its unit when the name says
    it; None when there is none, or two of the best rank."""
    times = [(_TIME.index(words), k) for k, (words, _) in enumerate(split) if words in _TIME]
    ranks = [rank for rank, _ in times]
    if not times or ranks.count(min(ranks)) > 1:
        return None
    k = min(times)[1]
    words, unit = split[k]
    return k, _TIME_UNITS.get(unit, "ns" if words in _ROS_NS else None)


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
    columns = {"time": [time[0]], **columns}
    gyro = "deg/s" if split[columns["gyro"][0]][1] in _DEGREES else "rad/s"
    accel = "g" if split[columns["accel"][0]][1] == "g" else "m/s^2"
    return ColumnRoles(columns, time[1], gyro, accel)


def header_names(head: Head) -> list[str] | None:
    """The fields of the first non-blank line when it is a header (its first field not a number)."""
    if not head.lines:
        return None
    first = head.lines[0][1]
    fields = first.split(";" if ";" in first else "," if "," in first else None)
    return None if is_number(fields[0]) else fields


def stamp_unit(table: Table, column: int, unit: str | None) -> str:
    """``unit``, or when the name did not say: ``"ns"`` for an integer first stamp above 10¹⁴, else ``"s"``."""
    if unit is not None:
        return unit
    first = table.split(table.lines[0][1])[column].strip()
    return "ns" if first.isdigit() and float(first) > _NS_STAMP else "s"


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
    table, roles = detected(path, column_roles, "time, gyro and accelerometer")
    time_unit = stamp_unit(table, roles.columns["time"][0], roles.time_unit)
    options: dict[str, Any] = {
        "time_column": roles.columns["time"][0],
        "gyro_columns": roles.columns["gyro"],
        "accel_columns": roles.columns["accel"],
        "time_unit": time_unit,
        "gyro_unit": roles.gyro_unit,
        "accel_unit": roles.accel_unit,
        "mag_columns": roles.columns.get("mag"),
    }
    return read_into(bad, read_imu_csv, path, header_lines=1, **options)


NAMED_CSV = Format("named-csv", "imu", names_sniff(column_roles), named_csv, "CSV with named IMU columns")
