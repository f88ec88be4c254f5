"""Any delimited IMU text file, given its column mapping and units: :func:`read_imu_csv` (``docs/io.md``)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray, choice, real_scalar
from imukit.imu import ImuData
from imukit.io._lines import Problem, as_file_error, public_reader
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
from imukit.io._units import resolve

__all__ = ["read_imu_csv"]


def imu_csv(
    path: str | os.PathLike[str],
    bad: BadLines,
    *,
    time_column: Column,
    gyro_columns: Sequence[Column],
    accel_columns: Sequence[Column],
    time_unit: TimeUnit | None,
    gyro_unit: str | None,
    accel_unit: str | None,
    standard_gravity: float,
    delimiter: str | None,
    header_lines: int | None,
    mag_columns: Sequence[Column] | None = None,
) -> ImuData:
    """:func:`read_imu_csv` reporting to ``bad``."""
    for value, name, domain in (
        (time_unit, "time_unit", TIME_UNITS),
        (gyro_unit, "gyro_unit", ("rad/s", "deg/s")),
        (accel_unit, "accel_unit", ("m/s^2", "g", "mg")),
    ):
        if value is not None:
            choice(value, name, domain)
    gravity = _gravity(standard_gravity)
    header_lines = check_header_lines(header_lines)
    wanted = {"time_column": [time_column], "gyro_columns": gyro_columns, "accel_columns": accel_columns}
    if mag_columns is not None:
        wanted["mag_columns"] = mag_columns
    for name, columns in wanted.items():
        check_columns(columns, name, 1 if name == "time_column" else 3)
    given = {"time": time_unit, "gyro": gyro_unit, "accel": accel_unit}
    return _read(path, bad, wanted, given, gravity, delimiter, header_lines)


@public_reader(imu_csv)
def read_imu_csv(  # type: ignore[empty-body]
    path: str | os.PathLike[str],
    *,
    time_column: Column,
    gyro_columns: Sequence[Column],
    accel_columns: Sequence[Column],
    time_unit: TimeUnit | None = None,
    gyro_unit: Literal["rad/s", "deg/s"] | None = None,
    accel_unit: Literal["m/s^2", "g", "mg"] | None = None,
    standard_gravity: float = 9.80665,
    delimiter: str | None = None,
    header_lines: int | None = None,
    mag_columns: Sequence[Column] | None = None,
    on_bad_line: OnBadLine = "raise",
    report: ReadReport | None = None,
) -> ImuData:
    """Read IMU samples from a delimited text file, naming its columns and their units.

    Parameters
    ----------
    path
        The text file. Its header is its leading lines that are ``#`` lines or whose first field is
        not a number (or ``header_lines`` of them), judged against the next line (``docs/io.md``: a
        first line with text in the same fields as the next one's is data, a text column; pandas'
        ``0,1,2,…`` header is taken and reported; other integer lines above float data are refused).
        The last header line names the columns (a leading ``#`` is dropped, as in EuRoC's
        ``#timestamp [ns],…``), and a name not found there is looked up in the header lines above it
        (an exporter's group line). Every data line must have as many fields as the header (without
        one, as the first data line); a header or data lines ending in the delimiter (``a;b;c;``)
        lose that empty field where it makes them agree, and a header whose count still differs is
        one error naming both counts. Later ``#`` lines and blank lines are skipped. UTF-8, with or
        without a byte order mark.
    time_column, gyro_columns, accel_columns
        The time column and the x, y, z columns of the angular rate and the specific force, each a
        header name (exact, after stripping white space) or a 0-based index. Other columns
        (temperature, …) are not read.
    time_unit
        ``"s"``, ``"ms"``, ``"us"`` or ``"ns"``. With ``"ns"`` every stamp must be an integer and
        becomes exact int64 ``t_ns``; with ``"ms"`` or ``"us"``, integer stamps also become exact
        ``t_ns`` (× 10⁶ or × 10³) and otherwise, like ``"s"``, float seconds
        ``t = value / 1000`` (or / 10⁶), one correctly rounded division. None (default): the unit
        the time column's header name states (``time [ms]``, ``Time (s)``, ``time_ns``), else
        ``"ns"`` for an integer first stamp above 10¹⁴ (as seconds: three million years), else
        ``"s"``.
    gyro_unit
        ``"rad/s"`` or ``"deg/s"`` (converted as ``value * (π / 180)``). None (default): the unit the
        gyro columns' header names state (``Gyroscope X (deg/s)``; ``dps``, ``°/s``, ``rad/sec`` and
        other spellings in ``docs/io.md``), else ``"rad/s"``.
    accel_unit
        ``"m/s^2"``, ``"g"`` (converted as ``value * standard_gravity``) or ``"mg"`` (milli-g:
        ``value * (standard_gravity / 1000)``); None (default): the unit
        the accelerometer columns' names state, else ``"m/s^2"``. The reading must be the
        specific force (+1 g on the up axis at rest), as imukit's accelerometer convention.

        A unit given here wins over the one the columns' header names state, with a UserWarning
        naming both when they differ; without one, a name must state a unit imukit reads, else a
        ParameterError naming the argument (a column read in the wrong unit would be a wrong
        answer). Names of the x, y, z columns that state different units are refused too.
    standard_gravity
        [m/s²] per g, default the standard 9.80665 (used only for an accelerometer in ``"g"`` or
        ``"mg"``, given or stated by the header).
    delimiter
        ``","``, ``";"``, ``"\\t"`` or ``" "`` (runs of spaces and tabs), or by name ``"comma"``,
        ``"semicolon"``, ``"tab"``, ``"space"``; None (default): ``";"`` if
        the first non-blank line has one, else a tab if it has at least as many tabs as commas, else
        ``","`` if it has one, else white space. Decimal commas are not read.
    header_lines
        How many non-blank lines the header has (0: none); None (default): detected as above.
    mag_columns
        The x, y, z magnetometer columns (names or indices, as above), read into ``ImuData.mag`` as
        they are (no unit conversion: µT by convention, any unit for the filters); None (default):
        no magnetometer.
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
        A unit, delimiter or ``standard_gravity`` outside its domain; a unit the header states that
        imukit does not read, or different ones for x, y, z; a column name not in the header
        (the message lists the header's names), an index beyond the last column, names without a
        header line. Messages start with the argument's name.
    FileFormatError
        Naming the file and line: bad lines ("raise" mode), no data.
    """


def _read(
    path: str | os.PathLike[str],
    bad: BadLines,
    wanted: dict[str, Sequence[Column]],
    given: dict[str, str | None],
    standard_gravity: float,
    delimiter: str | None,
    header_lines: int | None,
) -> ImuData:
    """:func:`imu_csv` with checked arguments; ``given`` the units passed (None: the header's)."""
    table = read_table(path, bad, delimiter, header_lines)
    index = {name: [table.column(c, name) for c in columns] for name, columns in wanted.items()}
    columns = [c for name in wanted for c in index[name]]  # time, gyro, accel, then mag if wanted
    units = {
        kind: resolve(kind, given[kind], table.headers, index[f"{kind}_{group}"], f"{kind}_unit", table.where)
        for kind, group in (("time", "column"), ("gyro", "columns"), ("accel", "columns"))
    }
    time_unit = stamp_unit(table, index["time_column"][0], units["time"])
    degrees = units["gyro"] == "deg/s"
    gravity = {"g": standard_gravity, "mg": standard_gravity / 1000.0}.get(units["accel"] or "")

    def check(fields: list[str], row: list[float]) -> Problem | None:
        if gravity is not None and not all(math.isfinite(a * gravity) for a in row[4:7]):
            accel = ", ".join(map(repr, row[4:7]))
            return "non-finite", f"acceleration ({accel}) g overflows float64 in m/s^2"
        return None

    def overflowing(values: FloatArray) -> NDArray[np.bool_]:
        with np.errstate(over="ignore"):
            return np.asarray(~np.isfinite(values[:, 4:7] * (gravity or 1.0)).all(axis=1), dtype=np.bool_)

    data = read_stamped(table, bad, columns, time_unit, check, None if gravity is None else overflowing)
    stamps, values = data.stamps, data.values
    del data
    # In place, one column group at a time: peak memory stays under 3x the result.
    if degrees:
        values[:, 1:4] *= np.pi / 180.0
    if gravity is not None:
        values[:, 4:7] *= gravity
    gyro, accel = np.ascontiguousarray(values[:, 1:4]), np.ascontiguousarray(values[:, 4:7])
    mag = np.ascontiguousarray(values[:, 7:10]) if "mag_columns" in wanted else None
    del values
    return as_file_error(path, lambda: ImuData(stamps, gyro, accel, mag=mag))


def _gravity(value: object) -> float:
    # The one numeric-option rule (real_scalar): "9.8" and True are refused as every option refuses them.
    what = "a positive, finite number of m/s^2 per g"
    return real_scalar(value, "standard_gravity", what=what, accept=lambda g: math.isfinite(g) and g > 0.0)
