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
from imukit.io._table import TIME_UNITS, Column, TimeUnit, check_columns, check_header_lines, read_stamped, read_table

__all__ = ["read_imu_csv"]


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
    header_lines: int | None,
    mag_columns: Sequence[Column] | None = None,
) -> ImuData:
    """:func:`read_imu_csv` reporting to ``bad``."""
    choice(time_unit, "time_unit", TIME_UNITS)
    choice(gyro_unit, "gyro_unit", ("rad/s", "deg/s"))
    choice(accel_unit, "accel_unit", ("m/s^2", "g"))
    gravity = _gravity(standard_gravity)
    header_lines = check_header_lines(header_lines)
    wanted = {"time_column": [time_column], "gyro_columns": gyro_columns, "accel_columns": accel_columns}
    if mag_columns is not None:
        wanted["mag_columns"] = mag_columns
    for name, columns in wanted.items():
        check_columns(columns, name, 1 if name == "time_column" else 3)
    scale = gravity if accel_unit == "g" else None
    return _read(path, bad, wanted, time_unit, gyro_unit == "deg/s", scale, delimiter, header_lines)


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
    header_lines: int | None,
) -> ImuData:
    """:func:`imu_csv` with checked arguments."""
    table = read_table(path, bad, delimiter, header_lines)
    index = {name: [table.column(c, name) for c in columns] for name, columns in wanted.items()}
    columns = [c for name in wanted for c in index[name]]  # time, gyro, accel, then mag if wanted

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
