"""TUM trajectory files: :func:`write_tum`, :func:`read_tum` (format in ``docs/io.md``)."""

from __future__ import annotations

import os
import re

import numpy as np
from numpy.typing import NDArray

from imukit._errors import FileFormatError
from imukit.io._lines import (
    INT64_MAX,
    check_stamps_increase,
    data_lines,
    parse_floats,
    rotations_from_rows,
    write_rows,
)
from imukit.state import Trajectory

__all__ = ["read_tum", "write_tum"]

_NS_STAMP = re.compile(r"(-?)(\d+)\.(\d{9})")


def _ns_text(ns: int) -> str:
    sign, ns = ("-", -ns) if ns < 0 else ("", ns)
    return f"{sign}{ns // 10**9}.{ns % 10**9:09d}"


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
        else [_ns_text(int(ns)) for ns in trajectory.t_ns]
    )
    write_rows(path, None, stamps, np.concatenate([trajectory.position, trajectory.rotation.as_quat()], axis=1), " ")


def read_tum(path: str | os.PathLike[str]) -> Trajectory:
    """Read a TUM file into a :class:`imukit.Trajectory` (``velocity`` None).

    If every timestamp has exactly nine decimals (``1403636579.758555392``, as :func:`write_tum`
    writes ``t_ns``), ``t_ns`` is parsed exactly and ``t`` is ``t_ns / 1e9``; otherwise ``t_ns`` is
    None and ``t`` is the parsed float. Quaternions that are unit to rounding are kept bit for bit,
    others (e.g. printed with 6 digits) are normalised.

    Raises
    ------
    FileFormatError
        (a ``ValueError``) naming the file and line: wrong number of fields, text that is not a
        number, non-finite values, a zero quaternion, time not strictly increasing, or no data.
    """
    where = os.fspath(path)
    lines: list[int] = []
    stamps: list[str] = []
    rows: list[list[float]] = []
    for number, text in data_lines(path):
        fields = text.split()
        if len(fields) != 8:
            raise FileFormatError(
                f"path: {where}, line {number}: expected 8 fields 'timestamp tx ty tz qx qy qz qw', got {len(fields)}"
            )
        rows.append(parse_floats(fields, where, number, text))
        lines.append(number)
        stamps.append(fields[0])
    if not rows:
        raise FileFormatError(f"path: {where}: no data lines")
    data = np.array(rows, dtype=np.float64)
    t_ns = _exact_ns(stamps)
    check_stamps_increase(data[:, 0] if t_ns is None else t_ns, stamps, lines, where)
    rotation = rotations_from_rows(np.ascontiguousarray(data[:, 4:8]), lines, where)
    t = data[:, 0] if t_ns is None else None  # with t_ns, Trajectory sets t = t_ns / 1e9
    return Trajectory(t, data[:, 1:4], None, rotation, t_ns=t_ns)


def _exact_ns(stamps: list[str]) -> NDArray[np.int64] | None:
    ns = []
    for stamp in stamps:
        match = _NS_STAMP.fullmatch(stamp)
        if match is None:
            return None
        sign, whole, frac = match.groups()
        ns.append((-1 if sign else 1) * (int(whole) * 10**9 + int(frac)))
        if abs(ns[-1]) > INT64_MAX:
            return None
    return np.array(ns, dtype=np.int64)
