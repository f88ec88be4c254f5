"""Trajectory files: TUM format (:func:`write_tum`, :func:`read_tum`).

=====================  ===========================================================================
line                   ``timestamp tx ty tz qx qy qz qw``, space separated, one pose per line
timestamp              seconds; from ``t_ns`` it is printed exactly as ``SSSSSSSSSS.NNNNNNNNN``
position               ``p_w`` of the body origin [m]
quaternion             ``q_wb`` (body to world), Hamilton, scalar-last ``xyzw`` like scipy
comments               lines starting with ``#`` (and blank lines) are skipped on reading
=====================  ===========================================================================

Floats are written with ``repr``, the shortest text that reads back to the same float, so a
write → read round trip is bit-exact.
"""

from __future__ import annotations

import os
import re

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import rotation_from_unit_quat
from imukit._errors import FileFormatError
from imukit.state import Trajectory

__all__ = ["FileFormatError", "read_tum", "write_tum"]

_NS_STAMP = re.compile(r"(-?)(\d+)\.(\d{9})")
_INT64_MAX = 2**63 - 1
# Quaternions within this of unit norm are kept bit for bit; others are normalised.
_UNIT_TOLERANCE = 1e-15


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
    values = np.concatenate([trajectory.position, trajectory.rotation.as_quat()], axis=1).tolist()
    with open(path, "w", encoding="ascii", newline="\n") as f:
        for stamp, row in zip(stamps, values):
            f.write(stamp + " " + " ".join(map(repr, row)) + "\n")


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
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, start=1):
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            fields = text.split()
            if len(fields) != 8:
                raise FileFormatError(
                    f"path: {where}, line {number}: expected 8 fields 'timestamp tx ty tz qx qy qz qw', "
                    f"got {len(fields)}"
                )
            try:
                row = [float(x) for x in fields]
            except ValueError:
                raise FileFormatError(f"path: {where}, line {number}: not a number in {text!r}") from None
            if not np.isfinite(row).all():
                raise FileFormatError(f"path: {where}, line {number}: non-finite value in {text!r}")
            lines.append(number)
            stamps.append(fields[0])
            rows.append(row)
    if not rows:
        raise FileFormatError(f"path: {where}: no data lines")
    data = np.array(rows, dtype=np.float64)
    t_ns = _exact_ns(stamps)
    bad = np.flatnonzero(np.diff(data[:, 0] if t_ns is None else t_ns) <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise FileFormatError(
            f"path: {where}, line {lines[k]}: time must increase strictly, "
            f"but {stamps[k]} follows {stamps[k - 1]} (line {lines[k - 1]})"
        )
    quat = np.ascontiguousarray(data[:, 4:8])
    norm = np.linalg.norm(quat, axis=1)
    zero = np.flatnonzero(norm == 0.0)
    if zero.size:
        raise FileFormatError(f"path: {where}, line {lines[int(zero[0])]}: zero quaternion")
    off = np.abs(norm - 1.0) > _UNIT_TOLERANCE
    quat[off] /= norm[off, None]
    t = data[:, 0] if t_ns is None else None  # with t_ns, Trajectory sets t = t_ns / 1e9
    return Trajectory(t, data[:, 1:4], None, rotation_from_unit_quat(quat), t_ns=t_ns)


def _exact_ns(stamps: list[str]) -> NDArray[np.int64] | None:
    ns = []
    for stamp in stamps:
        match = _NS_STAMP.fullmatch(stamp)
        if match is None:
            return None
        sign, whole, frac = match.groups()
        ns.append((-1 if sign else 1) * (int(whole) * 10**9 + int(frac)))
        if abs(ns[-1]) > _INT64_MAX:
            return None
    return np.array(ns, dtype=np.int64)
