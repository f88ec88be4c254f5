"""TUM trajectory files: :func:`write_tum`, :func:`read_tum` (format in ``docs/io.md``)."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from imukit._errors import FileFormatError
from imukit.io._blocks import Layout, increasing_table, read_table, zero_quaternions
from imukit.io._format import Format, Head
from imukit.io._lines import (
    INT64_MAX,
    as_file_error,
    ns_text,
    public_reader,
    rotations_from_rows,
    write_rows,
    zero_quaternion,
)
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.state import Trajectory

__all__ = ["read_tum", "write_tum"]

_NS_STAMP = re.compile(r"(-?)(\d+)\.(\d{9})")


def write_tum(trajectory: Trajectory, path: str | os.PathLike[str]) -> None:
    """Write ``trajectory`` as a TUM file: ``timestamp tx ty tz qx qy qz qw`` per sample, no header.

    The timestamp is ``t_ns`` printed exactly (``1403636579.758555392``) when the trajectory has
    it, else ``repr(t)``. Quaternions are written as stored by the ``Rotation`` (not canonicalised).
    """
    if not isinstance(trajectory, Trajectory):
        raise TypeError(f"trajectory: expected an imukit Trajectory, got {type(trajectory).__name__}")
    stamps = (
        [repr(float(t)) for t in trajectory.t]
        if trajectory.t_ns is None
        else [ns_text(int(ns)) for ns in trajectory.t_ns]
    )
    write_rows(path, None, stamps, np.concatenate([trajectory.position, trajectory.rotation.as_quat()], axis=1), " ")


def tum(path: str | os.PathLike[str], bad: BadLines) -> Trajectory:
    """:func:`read_tum` reporting to ``bad``."""
    layout = Layout(
        None,
        8,
        "fields 'timestamp tx ty tz qx qy qz qw'",
        range(8),
        0,
        "nine-decimals",
        exact_ns,
        False,
        lambda fields, row: zero_quaternion(row[4:8]),
        zero_quaternions(4),
    )
    table = read_table(path, bad, layout)
    table = increasing_table(table, table.values[:, 0] if table.stamps is None else table.stamps, path, bad, layout)
    if not len(table.lines):
        raise FileFormatError(f"{os.fspath(path)}: no data lines{bad.skipped_in(path)}", argument="path")
    rotation = rotations_from_rows(np.ascontiguousarray(table.values[:, 4:8]), table.lines, os.fspath(path))
    # The columns the Trajectory copies, and the rows dropped first: peak memory stays under 3x the result.
    t = None if table.stamps is not None else np.ascontiguousarray(table.values[:, 0])
    position, t_ns = np.ascontiguousarray(table.values[:, 1:4]), table.stamps
    del table
    # With t_ns, Trajectory sets t = t_ns / 1e9.
    return as_file_error(path, lambda: Trajectory(t, position, None, rotation, t_ns=t_ns))


@public_reader(tum)
def read_tum(  # type: ignore[empty-body]
    path: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> Trajectory:
    """Read a TUM file into a :class:`imukit.Trajectory` (``velocity`` None).

    If every timestamp has exactly nine decimals (``1403636579.758555392``, as :func:`write_tum`
    writes ``t_ns``), ``t_ns`` is parsed exactly and ``t`` is ``t_ns / 1e9``; otherwise ``t_ns`` is
    None and ``t`` is the parsed float. Quaternions that are unit to rounding are kept bit for bit,
    others (e.g. printed with 6 digits) are normalised.

    Parameters
    ----------
    path
        The text file.
    on_bad_line
        ``"raise"`` (default) or ``"skip"``: bad lines (below) are left out and reported
        (``docs/io.md``); of the stamps, the longest strictly increasing subsequence is kept (a
        repeated stamp keeps its first line; one wild stamp costs its own line only).
    report
        An :class:`imukit.io.ReadReport` that receives the skipped lines; without one, skipping
        emits one :class:`imukit.io.SkippedLinesWarning`.

    Raises
    ------
    FileFormatError
        (a ``ValueError``) naming the file and line: wrong number of fields, text that is not a
        number, non-finite values, a zero quaternion, time not strictly increasing, or no data.
    """


def exact_ns(stamp: str) -> int | None:
    """Nanoseconds of a stamp with exactly nine decimals (``1403636579.758555392``), else None."""
    match = _NS_STAMP.fullmatch(stamp)
    if match is None:
        return None
    sign, whole, frac = match.groups()
    ns = (-1 if sign else 1) * (int(whole) * 10**9 + int(frac))
    return ns if abs(ns) <= INT64_MAX else None


def _tum_like(path: Path, head: Head) -> bool:
    return len(head.fields(",")) == 1 and len(head.fields(None)) == 8


TUM = Format("tum", "trajectory", _tum_like, tum, "TUM")
