"""Any delimited IMU text file, given its column mapping and units: :func:`read_imu_csv` (``docs/io.md``)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Literal, Union

import numpy as np

from imukit._arrays import choice
from imukit._errors import FileFormatError, ParameterError
from imukit.imu import ImuData
from imukit.io._lines import (
    Problem,
    Split,
    all_exact,
    as_file_error,
    increasing,
    integer_stamp,
    open_text,
    parse_rows,
    public_reader,
    require_rows,
)
from imukit.io._report import BadLines, OnBadLine, ReadReport

__all__ = ["read_imu_csv"]

Column = Union[int, str]
TimeUnit = Literal["s", "ms", "us", "ns"]
# Nanoseconds per unit, for integer stamps; float stamps are divided by the unit's count per second.
_NS_PER = {"s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}
_PER_SECOND = {"s": 1.0, "ms": 1e3, "us": 1e6}
_DELIMITERS = (",", ";", "\t", " ")


def imu_csv(
    path: str | os.PathLike[str],
    bad: BadLines,
    *,
    time_column: Column,
    gyro_columns: Sequence[Column],
    accel_columns: Sequence[Column],
    time_unit: TimeUnit,
    gyro_unit: str,
    accel_unit: str,
    standard_gravity: float,
    delimiter: str | None,
) -> ImuData:
    """:func:`read_imu_csv` reporting to ``bad``."""
    choice(time_unit, "time_unit", tuple(_NS_PER))
    choice(gyro_unit, "gyro_unit", ("rad/s", "deg/s"))
    choice(accel_unit, "accel_unit", ("m/s^2", "g"))
    gravity = _gravity(standard_gravity)
    if delimiter is not None:
        choice(delimiter, "delimiter", _DELIMITERS)
    wanted = {"time_column": [time_column], "gyro_columns": gyro_columns, "accel_columns": accel_columns}
    for name, columns in wanted.items():
        _check_columns(columns, name, 1 if name == "time_column" else 3)
    return _read(path, bad, wanted, time_unit, gyro_unit == "deg/s", gravity if accel_unit == "g" else None, delimiter)


@public_reader(imu_csv)
def read_imu_csv(  # type: ignore[empty-body]
    path: str | os.PathLike[str],
    *,
    time_column: Column,
    gyro_columns: Sequence[Column],
    accel_columns: Sequence[Column],
    time_unit: TimeUnit = "s",
    gyro_unit: Literal["rad/s", "deg/s"] = "rad/s",
    accel_unit: Literal["m/s^2", "g"] = "m/s^2",
    standard_gravity: float = 9.80665,
    delimiter: str | None = None,
    on_bad_line: OnBadLine = "raise",
    report: ReadReport | None = None,
) -> ImuData:
    """Read IMU samples from a delimited text file, naming its columns and their units.

    Parameters
    ----------
    path
        The text file. Its first non-blank line is the header when it starts with ``#`` or holds text
        where the next line holds numbers (``docs/io.md``: a text column is data; pandas' ``0,1,2,…``
        header is taken and reported; other integer lines above float data are refused); a leading
        ``#`` is dropped from it, as in EuRoC's ``#timestamp [ns],…``; every data line must have as
        many fields as the header (without one, as the first data line). Later ``#`` lines and
        blank lines are skipped. UTF-8, with or without a byte order mark.
    time_column, gyro_columns, accel_columns
        The time column and the x, y, z columns of the angular rate and the specific force, each a
        header name (exact, after stripping white space) or a 0-based index. Other columns
        (magnetometer, temperature, …) are not read.
    time_unit
        ``"s"``, ``"ms"``, ``"us"`` or ``"ns"``. With ``"ns"`` every stamp must be an integer and
        becomes exact int64 ``t_ns``; with ``"ms"`` or ``"us"``, integer stamps also become exact
        ``t_ns`` (× 10⁶ or × 10³) and otherwise, like ``"s"``, float seconds
        ``t = value / 1000`` (or / 10⁶), one correctly rounded division.
    gyro_unit
        ``"rad/s"`` or ``"deg/s"`` (converted as ``value * (π / 180)``).
    accel_unit
        ``"m/s^2"`` or ``"g"`` (converted as ``value * standard_gravity``). The reading must be the
        specific force (+1 g on the up axis at rest), as imukit's accelerometer convention.
    standard_gravity
        [m/s²] per g, default the standard 9.80665 (used only with ``accel_unit="g"``).
    delimiter
        ``","``, ``";"``, ``"\\t"`` or ``" "`` (runs of spaces and tabs); None (default): ``";"`` if
        the first non-blank line has one, else ``","`` if it has one, else white space. Decimal
        commas are not read.
    on_bad_line, report
        As in :func:`imukit.io.read_euroc_imu`. Bad lines: a wrong field count, text that is not a
        number (or, with ``"ns"``, not an integer) in a column read, non-finite values, and stamps
        out of order (the longest strictly increasing subsequence of stamps is kept, first of equal ones).

    Returns
    -------
    ImuData
        gyro [rad/s], accel [m/s²] in the sensor's own axes; ``t_ns`` as described above.

    Raises
    ------
    ParameterError
        A unit, delimiter or ``standard_gravity`` outside its domain; a column name not in the header
        (the message lists the header's names), an index beyond the last column, names without a
        header line. Messages start with the argument's name.
    FileFormatError
        Naming the file and line: bad lines ("raise" mode), no data.
    """


def _read(
    path: str | os.PathLike[str],
    bad: BadLines,
    wanted: dict[str, Sequence[Column]],
    time_unit: str,
    degrees: bool,
    gravity: float | None,
    delimiter: str | None,
) -> ImuData:
    """:func:`imu_csv` with checked arguments."""
    where = os.fspath(path)
    # utf-8-sig: a byte order mark (Excel's "CSV UTF-8") would otherwise start the header's first name.
    with open_text(path) as f:
        numbered = [(n, line.strip()) for n, line in enumerate(f, start=1) if line.strip()]
    split = _splitter(delimiter if delimiter is not None else _detect(numbered[0][1] if numbered else ""))
    header: list[str] | None = None
    header_line = 0
    if numbered and _is_header(numbered, split, path, bad):
        header = [name.strip() for name in split(numbered[0][1].lstrip("#"))]
        header_line = numbered.pop(0)[0]
    numbered = [(n, text) for n, text in numbered if not text.startswith("#")]
    if not numbered:
        raise FileFormatError(f"{where}: no data lines", argument="path")
    width = len(header) if header is not None else len(split(numbered[0][1]))
    index = {
        name: [_index(c, name, header, header_line, width, where) for c in columns] for name, columns in wanted.items()
    }
    columns = index["time_column"] + index["gyro_columns"] + index["accel_columns"]
    time = columns[0]

    def check(fields: list[str], row: list[float]) -> Problem | None:
        if time_unit == "ns" and integer_stamp(fields[time].strip()) is None:
            return "malformed", f"time {fields[time].strip()!r} is not an integer number of nanoseconds (int64)"
        if gravity is not None and not all(math.isfinite(a * gravity) for a in row[4:7]):
            accel = ", ".join(map(repr, row[4:7]))
            return "non-finite", f"acceleration ({accel}) g overflows float64 in m/s^2"
        return None

    rows = parse_rows(
        numbered,
        path,
        bad,
        split=split,
        width=width,
        expected=f"fields ({'the header' if header is not None else 'the first data line'} has {width})",
        columns=columns,
        check=check,
    )
    stamps = [f[time].strip() for f in rows.fields]
    scale = _NS_PER[time_unit]
    ns = all_exact(stamps, lambda s: integer_stamp(s, scale)) if time_unit != "s" else None
    keep = increasing(rows, [row[0] for row in rows.values] if ns is None else ns, stamps, path, bad)
    rows = rows.take(keep)
    require_rows(rows, path, bad)
    data = np.array(rows.values, dtype=np.float64)
    gyro = data[:, 1:4] * (np.pi / 180.0) if degrees else data[:, 1:4]
    accel = data[:, 4:7] * gravity if gravity is not None else data[:, 4:7]
    if ns is not None:
        t_ns = np.array([ns[k] for k in keep], dtype=np.int64)
        return as_file_error(path, lambda: ImuData(t_ns, gyro, accel))
    t = data[:, 0] / _PER_SECOND[time_unit]
    return as_file_error(path, lambda: ImuData(t, gyro, accel))


def _gravity(value: object) -> float:
    try:
        g = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        g = math.nan
    if not (math.isfinite(g) and g > 0.0):
        raise ParameterError(
            f"expected a positive, finite number of m/s^2 per g, got {value!r}", argument="standard_gravity"
        )
    return g


def _check_columns(columns: object, name: str, count: int) -> None:
    """``columns`` must be ``count`` names or indices (``time_column`` arrives wrapped in a list)."""
    if isinstance(columns, (str, bytes)) or not isinstance(columns, Sequence) or len(columns) != count:
        raise ParameterError(
            f"expected {count} column names or 0-based indices (x, y, z), got {columns!r}", argument=name
        )
    for column in columns:
        if isinstance(column, bool) or not isinstance(column, (int, str)) or (isinstance(column, int) and column < 0):
            raise ParameterError(f"expected a column name or a 0-based index (int ≥ 0), got {column!r}", argument=name)


def _index(column: Column, name: str, header: list[str] | None, line: int, width: int, where: str) -> int:
    if isinstance(column, int):
        if column >= width:
            raise ParameterError(
                f"column {column} is out of range: {where} has {width} columns (0-based indices 0 to {width - 1})",
                argument=name,
            )
        return column
    if header is None:
        raise ParameterError(
            f"column {column!r} is a name, but {where} has no header line (its first line is numbers); "
            "pass 0-based indices",
            argument=name,
        )
    found = [k for k, h in enumerate(header) if h == column]
    if len(found) != 1:
        problem = "no column named" if not found else f"{len(found)} columns named"
        raise ParameterError(
            f"{problem} {column!r} in the header of {where} (line {line}), which has {', '.join(map(repr, header))}",
            argument=name,
        )
    return found[0]


def _detect(first: str) -> str:
    return ";" if ";" in first else "," if "," in first else " "


def _splitter(delimiter: str) -> Split:
    if delimiter == " ":
        return str.split
    return lambda text: text.split(delimiter)


def _is_header(numbered: list[tuple[int, str]], split: Split, path: str | os.PathLike[str], bad: BadLines) -> bool:
    """Whether the first non-blank line is a header, judged against the next line that is not a comment.

    A ``#`` line is a header. A line with text is a header unless the next line has text in the same
    fields (then the file has a text column and no header: its first sample is data). A line of integers
    only, above a line that is not, is ambiguous: ``0,1,…`` or ``1,2,…`` (the column numbers pandas
    writes) is taken as the header and reported (``header``, in the report or its warning); any other
    is refused.
    """
    (line, text), *rest = numbered
    if text.startswith("#"):
        return True
    first = split(text)
    second = next((split(t) for _, t in rest if not t.startswith("#")), None)
    kinds = [_kind(f) for f in first]
    if "text" in kinds:
        below = None if second is None else [_kind(f) for f in second]
        return below is None or below != kinds or "text" not in below or below.count("text") == len(below)
    if second is None or "float" not in {_kind(f) for f in second} or "float" in kinds:
        return False
    if [int(f) for f in first] in (list(range(len(first))), list(range(1, len(first) + 1))):
        detail = f"taken as the header: the column numbers {text!r}, above line {rest[0][0]} of other numbers"
        bad.note(path, line, "header", detail, text)
        return True
    raise FileFormatError(
        f"{os.fspath(path)}, line {line}: {text!r} is integers only while the next line is not: a header or "
        "the first sample? Start a header with '#', or write the sample's numbers with a decimal point",
        argument="path",
    )


def _kind(field: str) -> str:
    """``int``, ``float`` or ``text``: how a field reads."""
    if integer_stamp(field.strip()) is not None:
        return "int"
    try:
        float(field)
    except ValueError:
        return "text"
    return "float"
