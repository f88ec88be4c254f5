"""Plumbing shared by the line-based readers and writers (TUM, EuRoC, TUM-VI, GTSAM, KITTI, CSV).

Every reader reports problems as :class:`imukit.FileFormatError` messages starting
``path: <file>, line <n>:``, or skips the line (``on_bad_line="skip"``, :mod:`imukit.io._report`);
every writer prints floats with ``repr``, the shortest text that reads back to the same float, so a
write → read round trip is bit-exact.

A reader runs two passes through :class:`BadLines`: :func:`parse_rows` checks each line on its own
(field count, numbers, finiteness, a format's own row check), then :func:`increasing` checks the
stamps of the rows that passed, in file order, against the last one kept.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import NamedTuple, Union

import numpy as np
from scipy.spatial.transform import Rotation

from imukit._arrays import FloatArray, rotation_from_unit_quat
from imukit._errors import FileFormatError
from imukit.io._report import BadLines

INT64_MIN = -(2**63)
INT64_MAX = 2**63 - 1
# Quaternions within this of unit norm are kept bit for bit; others are normalised.
_UNIT_TOLERANCE = 1e-15
# Norms between these come from squares that neither overflow nor lose digits to underflow.
_SAFE_NORM = (1e-150, 1e150)
# 20 digits and a sign cover int64; longer texts are refused before int() (which limits to 4300 digits).
_INTEGER = re.compile(r"[+-]?[0-9]{1,20}")

Problem = tuple[str, str]  # (kind, detail) of a bad line
RowCheck = Callable[[list[str], list[float]], Union[Problem, None]]
Split = Callable[[str], list[str]]


class Rows(NamedTuple):
    """The lines of a file that passed :func:`parse_rows`, in file order."""

    lines: list[int]
    """1-based line numbers."""
    texts: list[str]
    """The stripped lines."""
    fields: list[list[str]]
    """Each line split into its fields."""
    values: list[list[float]]
    """The finite floats of the requested columns."""

    def take(self, keep: Sequence[int]) -> Rows:
        return Rows(
            [self.lines[k] for k in keep],
            [self.texts[k] for k in keep],
            [self.fields[k] for k in keep],
            [self.values[k] for k in keep],
        )


def data_lines(path: str | os.PathLike[str]) -> Iterator[tuple[int, str]]:
    """``(line number, stripped text)`` of each line that is neither blank nor a ``#`` comment.

    Stripping also removes the ``\\r`` of files written with Windows line ends. Bytes that are not
    UTF-8 come through as lone surrogates (``surrogateescape``), so a damaged line is one bad line
    (not a number), not a ``UnicodeDecodeError`` for the whole file.
    """
    with open(path, encoding="utf-8", errors="surrogateescape") as f:
        for number, line in enumerate(f, start=1):
            text = line.strip()
            if text and not text.startswith("#"):
                yield number, text


def parse_rows(
    numbered: Iterable[tuple[int, str]],
    path: str | os.PathLike[str],
    bad: BadLines,
    *,
    split: Split,
    width: int,
    expected: str,
    columns: Sequence[int],
    check: RowCheck | None = None,
) -> Rows:
    """The lines with ``width`` fields whose ``columns`` (at least one) are finite numbers and that pass
    ``check``.

    Other lines go to ``bad``: ``expected {width} {expected}, got n`` (wrong column count),
    ``not a number in '…'`` (malformed), ``non-finite value in '…'`` (non-finite), or ``check``'s
    ``(kind, detail)``.
    """
    rows = Rows([], [], [], [])
    start, stop = columns[0], columns[0] + len(columns)
    consecutive = list(columns) == list(range(start, stop))  # then a slice, twice as fast as indexing
    isfinite = math.isfinite
    for number, text in numbered:
        # One loop, no helper calls: this runs for every line of files with 10⁵-10⁶ lines.
        fields = split(text)
        problem: Problem | None = None
        row: list[float] = []
        if len(fields) != width:
            problem = "wrong column count", f"expected {width} {expected}, got {len(fields)}"
        else:
            try:
                row = list(map(float, fields[start:stop] if consecutive else [fields[c] for c in columns]))
            except ValueError:
                problem = "malformed", f"not a number in {text!r}"
            else:
                if not all(map(isfinite, row)):
                    problem = "non-finite", f"non-finite value in {text!r}"
                elif check is not None:
                    problem = check(fields, row)
        if problem is None:
            rows.lines.append(number)
            rows.texts.append(text)
            rows.fields.append(fields)
            rows.values.append(row)
        else:
            bad.bad(path, number, *problem, text)
    return rows


def integer_stamp(text: str, scale: int = 1) -> int | None:
    """``text`` (an integer, e.g. ``1403715523912140000``) × ``scale``, or None if it is not an integer
    or the product falls outside int64."""
    if not _INTEGER.fullmatch(text):
        return None
    value = int(text) * scale
    return value if INT64_MIN <= value <= INT64_MAX else None


def increasing(
    rows: Rows,
    stamps: Sequence[int] | Sequence[float],
    shown: Sequence[str],
    path: str | os.PathLike[str],
    bad: BadLines,
) -> list[int]:
    """Indices of the rows whose stamp exceeds the last kept one; the others go to ``bad`` as a
    duplicate stamp (equal: the first is kept) or a stamp going back (smaller: later, larger stamps
    are kept). ``shown[k]`` is the stamp as the messages print it."""
    keep: list[int] = []
    for k, stamp in enumerate(stamps):
        if keep and stamp <= stamps[keep[-1]]:
            last = keep[-1]
            kind = "duplicate stamp" if stamp == stamps[last] else "stamp going back"
            detail = f"time must increase strictly, but {shown[k]} follows {shown[last]} (line {rows.lines[last]})"
            bad.bad(path, rows.lines[k], kind, detail, rows.texts[k])
        else:
            keep.append(k)
    return keep


def require_rows(rows: Rows, path: str | os.PathLike[str], bad: BadLines) -> None:
    """:class:`FileFormatError` when no line is left (saying how many were skipped)."""
    if not rows.lines:
        raise FileFormatError(f"path: {os.fspath(path)}: no data lines{bad.skipped_in(path)}")


def zero_quaternion(quat: Sequence[float]) -> Problem | None:
    """The row check for a quaternion that is all zeros (no rotation)."""
    return ("zero quaternion", "zero quaternion") if not any(quat) else None


def rotations_from_rows(quat: FloatArray, lines: Sequence[int], where: str) -> Rotation:
    """A ``Rotation`` from ``(N, 4)`` xyzw rows read from a file (modified in place).

    Rows that are unit to 1e-15 are kept bit for bit (so written rotations come back exactly);
    others, e.g. printed with 6 decimals, are divided by their norm. Rows so large or small that
    their squares overflow or underflow (1e308, 5e-324) are first divided by their largest component.
    A zero row is an error naming its line (``lines[k]`` is row k's line; the line readers have left
    such rows out already).
    """
    with np.errstate(over="ignore", under="ignore"):  # such rows are rescaled below
        norm = np.linalg.norm(quat, axis=1)
    off = ~(np.abs(norm - 1.0) <= _UNIT_TOLERANCE)
    plain = off & (norm > _SAFE_NORM[0]) & (norm < _SAFE_NORM[1])
    quat[plain] /= norm[plain, None]
    extreme = np.flatnonzero(off & ~plain)
    largest = np.abs(quat[extreme]).max(axis=1, initial=0.0)
    if np.any(largest == 0.0):
        raise FileFormatError(f"path: {where}, line {lines[int(extreme[largest == 0.0][0])]}: zero quaternion")
    scaled = quat[extreme] / largest[:, None]
    quat[extreme] = scaled / np.linalg.norm(scaled, axis=1)[:, None]
    return rotation_from_unit_quat(quat)


def all_exact(stamps: Sequence[str], exact: Callable[[str], int | None]) -> list[int] | None:
    """``exact(s)`` (integer nanoseconds) for every stamp, or None if any of them has none."""
    ns = [exact(s) for s in stamps]
    return None if any(n is None for n in ns) else ns  # type: ignore[return-value]


def write_rows(
    path: str | os.PathLike[str], header: str | None, stamps: Iterable[str], values: FloatArray, sep: str
) -> None:
    """Write ``stamp<sep>v0<sep>v1…`` per row (floats as ``repr``), after ``header`` when given."""
    with open(path, "w", encoding="ascii", newline="\n") as f:
        if header is not None:
            f.write(header + "\n")
        for stamp, row in zip(stamps, values.tolist()):
            f.write(stamp + sep + sep.join(map(repr, row)) + "\n")
