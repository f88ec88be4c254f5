"""Plumbing shared by the line-based readers and writers (TUM, EuRoC, TUM-VI, GTSAM, KITTI, CSV).

Every reader reports problems as :class:`imukit.FileFormatError` messages starting
``path: <file>, line <n>:``, or skips the line (``on_bad_line="skip"``, :mod:`imukit.io._report`);
every writer prints floats with ``repr``, the shortest text that reads back to the same float, so a
write → read round trip is bit-exact.

A reader is a private ``x(path, bad)`` made public by :func:`public_reader`, which makes the
``on_bad_line`` / ``report`` pair into one :class:`BadLines`; it builds its result through
:func:`as_file_error`, so a value the data types refuse (stamps that are not nanoseconds) is a
:class:`imukit.FileFormatError` naming the file. It runs two passes through :class:`BadLines`:
:func:`parse_rows` checks each line on its own (field count, numbers, finiteness, a format's own row
check), then :func:`increasing` keeps the longest strictly increasing run of the stamps of the rows
that passed (:func:`in_order`, shared with the ROS bag reader), so one wild stamp costs its own line
only.
"""

from __future__ import annotations

import functools
import inspect
import math
import os
import re
import stat
from bisect import bisect_left
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, NamedTuple, TextIO, TypeVar, Union

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imukit._arrays import FloatArray, rotation_from_unit_quat
from imukit._errors import FileFormatError, ImukitError
from imukit.io._report import BadLines, ReadReport

NS_PER_S = 1_000_000_000
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
_T = TypeVar("_T")
_F = TypeVar("_F", bound=Callable[..., Any])


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
    (not a number), not a ``UnicodeDecodeError`` for the whole file. A UTF-8 byte order mark (as Excel
    writes) is dropped, so a first ``#`` line stays a comment.
    """
    with open_text(path) as f:
        for number, line in enumerate(f, start=1):
            text = line.strip()
            if text and not text.startswith("#"):
                yield number, text


def open_text(path: str | os.PathLike[str]) -> TextIO:
    """``path`` opened as UTF-8 text (byte order mark dropped, other bytes as lone surrogates), if it is a
    regular file (:func:`regular_file`)."""
    return open(regular_file(path), encoding="utf-8-sig", errors="surrogateescape")


def regular_file(path: str | os.PathLike[str]) -> int:
    """A read-only descriptor of ``path``, if it is a regular file.

    A FIFO, socket or device would block or never end, a folder or a symlink loop fails with an
    ``OSError`` deep in the reader: each is a :class:`FileFormatError` naming the path, found before a
    byte is read (the FIFO opened non-blocking so the check itself cannot hang). A missing file stays
    ``FileNotFoundError``, as the readers document.
    """
    where = os.fspath(path)
    try:
        fd = os.open(where, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError as exc:
        if os.path.islink(where):  # there, but pointing nowhere: not the same as absent
            target = os.readlink(where)
            raise FileFormatError(
                f"{where}: a symbolic link to {target!r}, which does not exist", argument="path"
            ) from exc
        raise
    except OSError as exc:
        raise FileFormatError(f"{where}: cannot be opened as a file ({exc.strerror})", argument="path") from exc
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        kind = "a folder" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode) else "not a regular file"
        raise FileFormatError(f"{where}: expected a regular file, got {kind}", argument="path")
    if hasattr(os, "set_blocking"):
        os.set_blocking(fd, True)
    return fd


_DELIMITERS_AND_SPACE = ",;\t "


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

    A line of delimiters alone (``,,,,,,``: a spreadsheet's empty row) holds no value and is passed
    over as a blank line is. Other lines go to ``bad``: ``expected {width} {expected}, got n`` (wrong column count),
    ``not a number in '…'`` (malformed: ``float()`` refuses a field, or it has more than ASCII or an
    ``_``, :func:`plain_digits`), ``non-finite value in '…'`` (non-finite), or ``check``'s
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
            chosen = fields[start:stop] if consecutive else [fields[c] for c in columns]
            try:
                if not plain_digits("".join(chosen)):
                    raise ValueError(chosen)
                row = list(map(float, chosen))
            except ValueError:
                problem = "malformed", f"not a number in {text!r}"
            else:
                if not all(map(isfinite, row)):
                    problem = "non-finite", f"non-finite value in {text!r}"
                elif check is not None:
                    problem = check(fields, row)
        if problem is not None and not text.strip(_DELIMITERS_AND_SPACE):
            continue
        if problem is None:
            rows.lines.append(number)
            rows.texts.append(text)
            rows.fields.append(fields)
            rows.values.append(row)
        else:
            bad.bad(path, number, *problem, text)
    return rows


def plain_digits(text: str) -> bool:
    """Whether ``text`` has only the characters a number in a data file is written with: ASCII, no
    ``_``. Python's ``float()`` also reads ``1_000``, Unicode digits (``١``) and Unicode spaces
    around a number (a no-break space); no writer of sensor logs produces them, so a field holding
    them is damaged or not a number, and its line is ``malformed`` (issue 17, item 16)."""
    return text.isascii() and "_" not in text


def integer_stamp(text: str, scale: int = 1) -> int | None:
    """``text`` (an integer, e.g. ``1403715523912140000``) × ``scale``, or None if it is not an integer
    or the product falls outside int64."""
    if not _INTEGER.fullmatch(text):
        return None
    value = int(text) * scale
    return value if INT64_MIN <= value <= INT64_MAX else None


class Disorder(NamedTuple):
    """A stamp :func:`in_order` leaves out, and the kept stamp it clashes with."""

    at: int
    """The stamp left out."""
    kind: str
    """``duplicate stamp`` (equal to the kept stamp before it), ``stamp going back`` (below it) or
    ``stamp out of order`` (above the kept stamp after it: a stamp from the future)."""
    other: int
    """The kept stamp it is compared with: the last kept one before it, or for ``stamp out of order`` the
    first kept one after it."""

    def detail(self, shown: Sequence[str], where: Callable[[int], str]) -> str:
        """``time must increase strictly, but 5 follows 5 (line 3)``: ``shown[k]`` prints stamp k and
        ``where(k)`` names its place (``line 3``)."""
        relation = "comes before" if self.kind == "stamp out of order" else "follows"
        return f"time must increase strictly, but {shown[self.at]} {relation} {shown[self.other]} ({where(self.other)})"


def in_order(stamps: Sequence[int] | Sequence[float], *, first: bool = False) -> tuple[list[int], list[Disorder]]:
    """The indices of the longest strictly increasing subsequence of ``stamps``, and the others.

    A stamp shifted far into the future or the past is one element off that subsequence, so it alone is
    left out, and of a block of stamps shifted back, the shorter side is. Among subsequences of the
    same length the one of the earliest indices is kept: of equal stamps the first, and a stamp below
    its predecessor is left out (rather than the predecessor) when that costs no more. In O(n log n).

    ``first``: only the first stamp not above its predecessor, as ``stamp going back`` or ``duplicate
    stamp`` (what ``on_bad_line="raise"`` reports), and no kept indices.
    """
    n = len(stamps)
    stop = next((k for k in range(1, n) if not stamps[k - 1] < stamps[k]), None)
    if stop is None:
        return list(range(n)), []
    if first:
        return [], [Disorder(stop, _behind(stamps[stop], stamps[stop - 1]), stop - 1)]
    # ahead[k]: the length of the longest strictly increasing subsequence starting at k, from patience
    # sorting of the reversed, negated stamps (tails[m]: the least last value of such a run of m + 1).
    ahead = [0] * n
    tails: list[int | float] = []
    for k in range(n - 1, -1, -1):
        m = bisect_left(tails, -stamps[k])
        if m == len(tails):
            tails.append(-stamps[k])
        else:
            tails[m] = -stamps[k]
        ahead[k] = m + 1
    # Greedy from the front: the first stamp that can still start a run of the remaining length.
    keep: list[int] = []
    need = len(tails)
    for k in range(n):
        if ahead[k] == need and (not keep or stamps[keep[-1]] < stamps[k]):
            keep.append(k)
            need -= 1
    out: list[Disorder] = []
    p = 0  # keep[p]: the first kept index after k
    for k in range(n):
        if p < len(keep) and keep[p] == k:
            p += 1
        elif p > 0 and stamps[k] <= stamps[keep[p - 1]]:
            out.append(Disorder(k, _behind(stamps[k], stamps[keep[p - 1]]), keep[p - 1]))
        else:  # above the last kept stamp: then above the next one, or the subsequence would be longer
            out.append(Disorder(k, "stamp out of order", keep[p]))
    return keep, out


def _behind(stamp: int | float, kept: int | float) -> str:
    return "duplicate stamp" if stamp == kept else "stamp going back"


def increasing(
    rows: Rows,
    stamps: Sequence[int] | Sequence[float],
    shown: Sequence[str],
    path: str | os.PathLike[str],
    bad: BadLines,
) -> list[int]:
    """Indices of the rows :func:`in_order` keeps; the others go to ``bad`` (in "raise" mode: the first
    row whose stamp does not exceed its predecessor's). ``shown[k]`` is the stamp as the messages print it."""
    keep, out = in_order(stamps, first=not bad.skip)
    for d in out:
        bad.bad(path, rows.lines[d.at], d.kind, d.detail(shown, lambda k: f"line {rows.lines[k]}"), rows.texts[d.at])
    return keep


def ns_text(ns: int) -> str:
    """Integer nanoseconds as exact decimal seconds, ``1403636579.758555392``."""
    sign, ns = ("-", -ns) if ns < 0 else ("", ns)
    return f"{sign}{ns // NS_PER_S}.{ns % NS_PER_S:09d}"


def require_rows(rows: Rows, path: str | os.PathLike[str], bad: BadLines) -> None:
    """:class:`FileFormatError` when no line is left (saying how many were skipped)."""
    if not rows.lines:
        raise FileFormatError(f"{os.fspath(path)}: no data lines{bad.skipped_in(path)}", argument="path")


def zero_quaternion(quat: Sequence[float]) -> Problem | None:
    """The row check for a quaternion that is all zeros (no rotation)."""
    return ("zero quaternion", "zero quaternion") if not any(quat) else None


def rotations_from_rows(quat: FloatArray, lines: Sequence[int] | NDArray[np.int64], where: str) -> Rotation:
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
        raise FileFormatError(
            f"{where}, line {lines[int(extreme[largest == 0.0][0])]}: zero quaternion", argument="path"
        )
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
    """Write ``stamp<sep>v0<sep>v1…`` per row (floats as ``repr``), after ``header`` when given; all or
    nothing (:func:`atomic`)."""
    with atomic(path) as temporary, open(temporary, "w", encoding="ascii", newline="\n") as f:
        if header is not None:
            f.write(header + "\n")
        for stamp, row in zip(stamps, values.tolist()):
            f.write(stamp + sep + sep.join(map(repr, row)) + "\n")


@contextmanager
def atomic(path: str | os.PathLike[str]) -> Iterator[str]:
    """A temporary name beside ``path`` to write to, renamed to ``path`` when the block ends normally and
    removed when it raises (Ctrl-C included): a reader never sees a half-written file under ``path``."""
    final = os.fspath(path)
    folder, name = os.path.split(final)
    temporary = os.path.join(folder, f".{name}.{os.getpid()}.imukit-partial")
    try:
        yield temporary
        os.replace(temporary, final)
    finally:
        if os.path.lexists(temporary):
            os.unlink(temporary)


def as_file_error(path: str | os.PathLike[str], make: Callable[[], _T]) -> _T:
    """``make()``, its validation errors (e.g. stamps that are not nanoseconds) as FileFormatError."""
    try:
        return make()
    except ImukitError as exc:
        raise FileFormatError(f"{os.fspath(path)}: {exc}", argument="path") from exc


def public_reader(private: Callable[..., Any]) -> Callable[[_F], _F]:
    """The public ``read_x(..., on_bad_line="raise", report=None)`` from the private ``x(..., bad)``.

    The decorated function gives the signature, its defaults and the docstring; its body is never run.
    A call binds its arguments to that signature, makes ``on_bad_line`` and ``report`` into one
    :class:`BadLines`, calls ``private(**the other arguments, bad=bad)`` and hands the skipped lines
    over with :meth:`BadLines.done` (whose warning then points at the caller of ``read_x``).
    """

    def decorate(public: _F) -> _F:
        signature = inspect.signature(public)

        @functools.wraps(public)
        def read(*args: Any, **kwargs: Any) -> Any:
            arguments = signature.bind(*args, **kwargs)
            arguments.apply_defaults()
            given = arguments.arguments
            bad = BadLines(given.pop("on_bad_line"), given.pop("report"))
            return bad.done(private(**given, bad=bad))

        return read  # type: ignore[return-value]

    return decorate


def read_into(bad: BadLines, read: Callable[..., _T], *args: Any, **options: Any) -> _T:
    """``read(*args, **options)``, a public reader, in ``bad``'s mode, its skipped lines handed to ``bad``
    (so that a reader calling another one warns once, at its own caller)."""
    report = bad.report if bad.report is not None else ReadReport()
    result = read(*args, **options, on_bad_line="skip" if bad.skip else "raise", report=report)
    if bad.report is None:
        bad.records += report.skipped
    return result
