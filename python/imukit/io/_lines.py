"""Plumbing shared by the line-based readers and writers (TUM, EuRoC CSV).

Every reader reports problems as :class:`imukit.FileFormatError` messages starting
``path: <file>, line <n>:``; every writer prints floats with ``repr``, the shortest text that reads
back to the same float, so a write → read round trip is bit-exact.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Iterator

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imukit._arrays import FloatArray, rotation_from_unit_quat
from imukit._errors import FileFormatError

INT64_MIN = -(2**63)
INT64_MAX = 2**63 - 1
# Quaternions within this of unit norm are kept bit for bit; others are normalised.
_UNIT_TOLERANCE = 1e-15


def data_lines(path: str | os.PathLike[str]) -> Iterator[tuple[int, str]]:
    """``(line number, stripped text)`` of each line that is neither blank nor a ``#`` comment.

    Stripping also removes the ``\\r`` of files written with Windows line ends.
    """
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, start=1):
            text = line.strip()
            if text and not text.startswith("#"):
                yield number, text


def parse_floats(fields: list[str], where: str, number: int, text: str) -> list[float]:
    """``fields`` as finite floats, else :class:`FileFormatError` naming the file and line."""
    try:
        row = [float(x) for x in fields]
    except ValueError:
        raise FileFormatError(f"path: {where}, line {number}: not a number in {text!r}") from None
    if not all(map(math.isfinite, row)):
        raise FileFormatError(f"path: {where}, line {number}: non-finite value in {text!r}")
    return row


def check_stamps_increase(
    stamps: NDArray[np.int64] | FloatArray, texts: list[str], lines: list[int], where: str
) -> None:
    """Raise :class:`FileFormatError` at the first line whose stamp does not exceed the previous one."""
    bad = np.flatnonzero(np.diff(stamps) <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise FileFormatError(
            f"path: {where}, line {lines[k]}: time must increase strictly, "
            f"but {texts[k]} follows {texts[k - 1]} (line {lines[k - 1]})"
        )


def rotations_from_rows(quat: FloatArray, lines: list[int], where: str) -> Rotation:
    """A ``Rotation`` from ``(N, 4)`` xyzw rows read from a file (modified in place).

    Rows that are unit to 1e-15 are kept bit for bit (so written rotations come back exactly);
    others, e.g. printed with 6 decimals, are normalised. A zero row is an error naming its line.
    """
    norm = np.linalg.norm(quat, axis=1)
    zero = np.flatnonzero(norm == 0.0)
    if zero.size:
        raise FileFormatError(f"path: {where}, line {lines[int(zero[0])]}: zero quaternion")
    off = np.abs(norm - 1.0) > _UNIT_TOLERANCE
    quat[off] /= norm[off, None]
    return rotation_from_unit_quat(quat)


def write_rows(
    path: str | os.PathLike[str], header: str | None, stamps: Iterable[str], values: FloatArray, sep: str
) -> None:
    """Write ``stamp<sep>v0<sep>v1…`` per row (floats as ``repr``), after ``header`` when given."""
    with open(path, "w", encoding="ascii", newline="\n") as f:
        if header is not None:
            f.write(header + "\n")
        for stamp, row in zip(stamps, values.tolist()):
            f.write(stamp + sep + sep.join(map(repr, row)) + "\n")
