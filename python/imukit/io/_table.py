"""A delimited text file as a header and data lines: what :func:`imukit.io.read_imu_csv` and
:func:`imukit.io.read_trajectory_csv` share (``docs/io.md``, "Any CSV").

=================  ================================================================================
delimiter          given, or detected from the first non-blank line: ``;`` if it has one, else a tab
                   if it has as many tabs as commas, else ``,`` if it has one, else white space
header lines       ``header_lines=N``: the first N non-blank lines; None: the leading lines that are
                   ``#`` lines or whose first field is not a number (an exporter's two-line header,
                   a group line over a names line). The names are the last of them; a later ``#``
                   line is a comment, unless it is the first (EuRoC's ``#timestamp [ns],…``).
                   Never guessed silently: a first line with text in the same fields as the next
                   line's is data (a text column, no header); a first line of integers only above a
                   line with decimals is pandas' ``0,1,2,…`` (or ``1,2,…``) header, taken and
                   reported as ``header``, or else refused as ambiguous
names              by exact text after stripping white space and double quotes around it
                   (``"time"``), looked up in the names line, then in
                   the other header lines (``"Time [s]"`` on a group line above ``";w;x;y;z"``)
trailing delimiter a names line or data lines ending in the delimiter (``a;b;c;``) have one empty
                   field too many: it is dropped where that makes the two agree
field counts       the header's and the data lines' (the most common count of the first 50) must
                   agree, else one error naming both, not one per line
data lines         read in blocks straight into arrays by :mod:`imukit.io._blocks` (the compiled core,
                   the reference parser for every line it defers): only the header and the first 50
                   data lines are held as text
=================  ================================================================================
"""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Sequence
from typing import Literal, NamedTuple, Union

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray, choice
from imukit._errors import FileFormatError, ParameterError
from imukit.io import _blocks as blocks
from imukit.io._blocks import Layout, Mask
from imukit.io._format import is_number
from imukit.io._lines import INT64_MAX, Problem, RowCheck, Split, integer_stamp, open_text
from imukit.io._report import BadLines

__all__ = [
    "DELIMITERS",
    "DELIMITER_NAMES",
    "TIME_UNITS",
    "Column",
    "Stamped",
    "Table",
    "TimeUnit",
    "check_columns",
    "check_header_lines",
    "detect_delimiter",
    "header_fields",
    "read_stamped",
    "read_table",
    "stamp_unit",
]

Column = Union[int, str]
TimeUnit = Literal["s", "ms", "us", "ns"]
DELIMITERS = (",", ";", "\t", " ")
DELIMITER_NAMES = {"comma": ",", "semicolon": ";", "tab": "\t", "space": " "}  # as the CLI spells them
TIME_UNITS = ("s", "ms", "us", "ns")
# Nanoseconds per unit, for integer stamps; float stamps are divided by the unit's count per second.
_NS_PER = {"s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}
_PER_SECOND = {"s": 1.0, "ms": 1e3, "us": 1e6}
_SAMPLE = 50  # data lines whose most common field count is the data's width


class Table(NamedTuple):
    """A delimited text file's header, and the layout of its data lines (:func:`read_table`)."""

    where: str
    lines: list[tuple[int, str]]
    """``(line number, stripped text)`` of the first data lines (those the layout was judged on)."""
    split: Split
    """A data line into its fields (a trailing delimiter dropped where the file has one)."""
    headers: list[tuple[int, list[str]]]
    """``(line number, names)`` of each header line, the names line last; [] without a header."""
    width: int
    """The fields of a data line."""
    delimiter: str
    data_from: int
    """The line number the data starts on (after the header)."""
    trailing: bool
    """Whether data lines end in the delimiter, an empty field dropped."""

    def column(self, column: Column, name: str) -> int:
        """The 0-based index of ``column`` (an index, or a header name), or a ParameterError naming the
        argument ``name``: an index past the last column, a name not in the header (listing its names)."""
        if isinstance(column, int):
            if column >= self.width:
                raise ParameterError(
                    f"column {column} is out of range: {self.where} has {self.width} columns (0-based indices 0 to "
                    f"{self.width - 1})",
                    argument=name,
                )
            return column
        if not self.headers:
            raise ParameterError(
                f"column {column!r} is a name, but {self.where} has no header line (its first line is numbers); "
                "pass 0-based indices",
                argument=name,
            )
        for line, names in reversed(self.headers):
            found = [k for k, h in enumerate(names) if h == column]
            if len(found) == 1 and found[0] < self.width:
                return found[0]
            if found:
                raise ParameterError(
                    f"{len(found)} columns named {column!r} in the header of {self.where} (line {line}); pass a "
                    "0-based index",
                    argument=name,
                )
        line, names = self.headers[-1]
        raise ParameterError(
            f"no column named {column!r} in the header of {self.where} (line {line}), which has "
            f"{', '.join(map(repr, names))}",
            argument=name,
        )

    def layout(self, columns: Sequence[int], time_unit: str, check: RowCheck | None, suspect: Mask | None) -> Layout:
        """The layout :func:`imukit.io._blocks.read_table` reads the data lines by: ``columns``, the time
        column first, its stamps integers (required for ``"ns"``) unless ``time_unit`` is ``"s"``."""
        origin = "the header" if self.headers else "the first data line"
        return Layout(
            None if self.delimiter == " " else self.delimiter,
            self.width,
            f"fields ({origin} has {self.width})",
            columns,
            columns[0],
            "float" if time_unit == "s" else "integer",
            integer_stamp,
            time_unit == "ns",
            check,
            suspect,
            self.data_from,
            self.trailing,
        )


class Stamped(NamedTuple):
    """The rows of a :class:`Table` that :func:`read_stamped` kept, in time order."""

    values: FloatArray
    """``(N, len(columns))`` floats of the columns read, the time column first."""
    stamps: NDArray[np.int64] | FloatArray
    """Exact int64 nanoseconds, or float seconds (what ``ImuData`` and ``Trajectory`` take as ``t``)."""
    lines: NDArray[np.int64]


def read_stamped(
    table: Table,
    bad: BadLines,
    columns: Sequence[int],
    time_unit: str,
    check: RowCheck | None = None,
    suspect: Mask | None = None,
) -> Stamped:
    """The data lines whose ``columns`` (the time column first) are finite numbers and pass ``check``
    (``suspect``: the rows it may refuse, vectorised), stamps strictly increasing
    (:func:`imukit.io._lines.increasing`), read in blocks by :mod:`imukit.io._blocks`. ``time_unit``
    ``"ns"``: integer stamps, exact ``t_ns``; ``"ms"`` / ``"us"``: exact ``t_ns`` when every stamp is an
    integer (and its nanoseconds within int64), else like ``"s"`` float seconds, one correctly rounded
    division by the unit's count per second."""
    choice(time_unit, "time_unit", TIME_UNITS)
    time = columns[0]

    def stamp_check(fields: list[str], row: list[float]) -> Problem | None:
        if time_unit == "ns" and integer_stamp(fields[time].strip()) is None:
            return "malformed", f"time {fields[time].strip()!r} is not an integer number of nanoseconds (int64)"
        return None if check is None else check(fields, row)

    layout = table.layout(columns, time_unit, stamp_check, suspect)
    rows = blocks.read_table(table.where, bad, layout)
    scale = _NS_PER[time_unit]
    ns = rows.stamps if time_unit != "s" else None
    ns = ns if ns is not None and bool(np.all(np.abs(ns) <= INT64_MAX // scale)) else None
    rows = blocks.increasing_table(rows, rows.values[:, 0] if ns is None else ns, table.where, bad, layout)
    if not len(rows.lines):
        raise FileFormatError(f"{table.where}: no data lines{bad.skipped_in(table.where)}", argument="path")
    if ns is not None and rows.stamps is not None:
        return Stamped(rows.values, rows.stamps * np.int64(scale), rows.lines)
    return Stamped(rows.values, rows.values[:, 0] / _PER_SECOND[time_unit], rows.lines)


def check_columns(columns: object, name: str, count: int) -> None:
    """``columns`` must be ``count`` header names or 0-based indices (a single column arrives wrapped in
    a list), else a ParameterError naming ``name``."""
    if isinstance(columns, (str, bytes)) or not isinstance(columns, Sequence) or len(columns) != count:
        what = {1: "one", 3: "x, y, z", 4: "a quaternion's"}.get(count, str(count))
        raise ParameterError(
            f"expected {count} column names or 0-based indices ({what}), got {columns!r}", argument=name
        )
    for column in columns:
        if isinstance(column, bool) or not isinstance(column, (int, str)) or (isinstance(column, int) and column < 0):
            raise ParameterError(f"expected a column name or a 0-based index (int ≥ 0), got {column!r}", argument=name)


def check_header_lines(value: object) -> int | None:
    """``header_lines`` as given: None or an int ≥ 0, else a ParameterError."""
    if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 0):
        raise ParameterError(f"expected None or a number of lines (int ≥ 0), got {value!r}", argument="header_lines")
    return value


def read_table(path: str | os.PathLike[str], bad: BadLines, delimiter: str | None, header_lines: int | None) -> Table:
    """``path`` split into header and data lines (module doc); a header taken from integers is noted in
    ``bad``. FileFormatError: no data lines, an ambiguous first line, or a header whose field count
    differs from the data lines'."""
    if delimiter is not None:
        delimiter = DELIMITER_NAMES.get(delimiter, delimiter) if isinstance(delimiter, str) else delimiter
        choice(delimiter, "delimiter", DELIMITERS)
    where = os.fspath(path)
    numbered = _head(path, delimiter, header_lines)
    d = delimiter if delimiter is not None else detect_delimiter(numbered[0][1] if numbered else "")
    plain = str.split if d == " " else (lambda text: text.split(d))
    count = header_lines if header_lines is not None else _leading_header(numbered, plain, where, bad)
    head, body = numbered[:count], numbered[count:]
    data = [(n, text) for n, text in body if not text.startswith("#")]
    if not data:
        raise FileFormatError(f"{where}: no data lines", argument="path")
    named = [(n, text) for k, (n, text) in enumerate(head) if k == 0 or not text.startswith("#")]
    headers = [(n, header_fields(text.lstrip("#"), d)) for n, text in named]
    widths = Counter(len(plain(text)) for _, text in data[:_SAMPLE])
    start = head[-1][0] + 1 if head else 1

    def table(headers: list[tuple[int, list[str]]], width: int, trailing: bool = False) -> Table:
        split = (lambda text: _drop_trailing(plain(text), d, text)) if trailing else plain
        return Table(where, data[:_SAMPLE], split, headers, width, d, start, trailing)

    if not headers:
        return table([], len(plain(data[0][1])))
    line, names = headers[-1]
    width = widths.most_common(1)[0][0]
    if d != " " and names[-1] == "" and len(names) == width + 1:  # `a;b;c;` over `1;2;3`
        headers[-1] = (line, names[:-1])
        return table(headers, width)
    if d != " " and len(names) == width - 1 and all(text.endswith(d) for _, text in data[:_SAMPLE]):
        return table(headers, len(names), trailing=True)
    if len(names) != width:
        trailing = d != " " and (named[-1][1].endswith(d) or data[0][1].endswith(d))
        raise FileFormatError(
            f"{where}: the header (line {line}) has {len(names)} fields, data lines {width}"
            + (f": a trailing {d!r}?" if trailing else "")
            + " (header_lines= says how many lines the header has)",
            argument="path",
        )
    return table(headers, width)


def _head(path: str | os.PathLike[str], delimiter: str | None, header_lines: int | None) -> list[tuple[int, str]]:
    """``(line number, stripped text)`` of the leading non-blank lines of ``path``: enough to judge its
    header and layout by (module doc), a header of ``header_lines`` lines (None: up to the first line whose
    first field is a number) and :data:`_SAMPLE` data lines after it; the whole file only when it has no more."""
    numbered: list[tuple[int, str]] = []
    data = numbers = 0
    with open_text(path) as f:
        for n, line in enumerate(f, start=1):
            text = line.strip()
            if not text:
                continue
            numbered.append((n, text))
            d = delimiter if delimiter is not None else detect_delimiter(numbered[0][1])
            if not text.startswith("#"):
                data += 1
                fields = text.split() if d == " " else text.split(d)
                numbers += is_number(fields[0])
            if data > (header_lines or 0) + _SAMPLE + 1 and (header_lines is not None or numbers > _SAMPLE + 1):
                break
    return numbered


def _leading_header(numbered: list[tuple[int, str]], split: Split, where: str, bad: BadLines) -> int:
    """How many leading lines are header: ``#`` lines, or lines whose first field is not a number, each
    first line judged against the next line (module doc). When every line would be header, the first
    alone (its data lines' numbers are unreadable, e.g. decimal commas, and each is reported as such)."""
    data = [(n, text) for n, text in numbered if not text.startswith("#")]
    if data and data[0] == numbered[0] and len(data) > 1:
        (line, text), (_, below) = data[0], data[1]
        kinds, below_kinds = [_kind(f) for f in split(text)], [_kind(f) for f in split(below)]
        if "text" in kinds and kinds == below_kinds and kinds.count("text") < len(kinds):
            return 0  # a text column (a sensor name): the first line is a sample like the next
        if set(kinds) == {"int"} and "float" in below_kinds:
            if [int(f) for f in split(text)] not in (list(range(len(kinds))), list(range(1, len(kinds) + 1))):
                raise FileFormatError(
                    f"{where}, line {line}: {text!r} is integers only while the next line is not: a header or the "
                    "first sample? Start a header with '#', or write the sample's numbers with a decimal point",
                    argument="path",
                )
            detail = f"taken as the header: the column numbers {text!r}, above line {data[1][0]} of other numbers"
            bad.note(where, line, "header", detail, text)
            return 1
    for k, (_, text) in enumerate(numbered):
        if not text.startswith("#") and is_number(split(text)[0] if split(text) else ""):
            return k
    return min(len(numbered), 1)


def header_fields(text: str, d: str) -> list[str]:
    """The names of a header line split at the delimiter ``d`` (``" "``: runs of white space), each
    stripped and unquoted: the one rule of every reader that looks at header names."""
    return [_unquoted(name.strip()) for name in (text.split() if d == " " else text.split(d))]


def _unquoted(name: str) -> str:
    """A header name without the double quotes around it (R's ``write.csv``, spreadsheet exports)."""
    return name[1:-1].strip() if len(name) >= 2 and name[0] == name[-1] == '"' else name


def _kind(field: str) -> str:
    """``int``, ``float`` or ``text``: how a field reads."""
    if integer_stamp(field.strip()) is not None:
        return "int"
    return "float" if is_number(field.strip()) else "text"


def _drop_trailing(fields: list[str], d: str, text: str) -> list[str]:
    return fields[:-1] if text.endswith(d) else fields


def detect_delimiter(first: str) -> str:
    """The delimiter of a file whose first non-blank line is ``first`` (module doc): ``;``, else a tab
    when there are at least as many tabs as commas (names with spaces stay whole: x-io's
    ``Time (s)<TAB>Gyroscope X (deg/s)``), else ``,``, else runs of white space."""
    if ";" in first:
        return ";"
    tabs, commas = first.count("\t"), first.count(",")
    return "\t" if tabs and tabs >= commas else "," if commas else " "


_NS_STAMP = 1e14  # an unlabelled integer stamp above this is nanoseconds (as seconds: 3 million years)


def stamp_unit(table: Table, column: int, unit: str | None) -> str:
    """``unit``, or when it is None (neither given nor stated by the header): ``"ns"`` for an integer
    first stamp above 10¹⁴, else ``"s"``."""
    if unit is not None:
        return unit
    first = table.split(table.lines[0][1])[column].strip()
    return "ns" if first.isdigit() and float(first) > _NS_STAMP else "s"
