"""The fast path of the line readers: a file parsed in blocks straight into arrays (issue 17, item 14).

:func:`read_table` reads ``path`` in blocks of :data:`BLOCK_BYTES` whole lines; the compiled core
(``imukit::text``) turns each block's plain lines into rows of float64 (and exact int64 stamps) and
hands every other line back by number. Those lines, and the rows a format's ``suspect`` mask flags
(a zero quaternion), go through :func:`imukit.io._lines.parse_rows`, the reference, so the rows kept
and the skip report (which line, why) are those of the pure-Python reader, bit for bit; only lines
the core reads exactly as Python's ``float()`` would are taken from it. Memory: the result arrays,
one block of text and its rows (3 M EuRoC lines: 40 s and 4.3 GB before, see ``bench/bench_readers.py``).

A first line whose stamp field holds a word (``timestamp,x,y,z,…``) is a header even without EuRoC's
``#``. A file with a lone carriage return (a line break to Python's text files, not to the core) is read by
the pure-Python path whole. A last line without a newline whose last field has fewer decimals than
the line before it is reported as ``truncated`` (a writer cut off mid-number: ``9.81`` → ``9.``).
"""

from __future__ import annotations

import codecs
import os
from collections.abc import Callable, Sequence
from typing import BinaryIO, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit import _core
from imukit._arrays import FloatArray
from imukit.io._format import is_number
from imukit.io._lines import RowCheck, Rows, Split, in_order, open_text, parse_rows, regular_file
from imukit.io._report import BadLines

BLOCK_BYTES = 1 << 24
# How much of the end of a file the truncation check compares the last line with.
_TAIL_BYTES = 1 << 16
_TAIL_LINES = 500
_MIN_LINES = 8
# The core's stamp of a row whose stamp has not the exact form (imukit::text::INEXACT).
INEXACT = -(2**63)
StampForm = Literal["float", "integer", "nine-decimals"]
Mask = Callable[[FloatArray], NDArray[np.bool_]]


class Table(NamedTuple):
    """The rows of a file, in file order."""

    lines: NDArray[np.int64]
    """1-based line numbers."""
    values: FloatArray
    """``(N, C)``: the requested columns."""
    stamps: NDArray[np.int64] | None
    """Exact nanoseconds of the stamp column, or None when a row's stamp has not the exact form."""

    def take(self, keep: NDArray[np.intp] | slice) -> Table:
        return Table(self.lines[keep], self.values[keep], None if self.stamps is None else self.stamps[keep])


class Layout(NamedTuple):
    """What a line holds (as for :func:`imukit.io._lines.parse_rows`), and its stamp."""

    separator: str | None
    """One character, or None for runs of white space."""
    width: int
    expected: str
    columns: Sequence[int]
    stamp_column: int
    stamp: StampForm
    """The exact form of the stamp: ``float`` (none), ``integer`` or ``nine-decimals``."""
    exact: Callable[[str], int | None] | None
    """The Python reading of that form (for the lines the core defers)."""
    stamp_required: bool
    """Whether a stamp without the exact form is a bad line (``check`` must say so) or makes ``stamps`` None."""
    check: RowCheck | None = None
    suspect: Mask | None = None
    """The rows ``check`` may refuse, vectorised: they are re-read through ``check``."""
    data_from: int | None = None
    """The line the data starts on, the lines before it a header (:mod:`imukit.io._table`); None: a first
    line with a word in its stamp field is a header (module doc)."""
    trailing: bool = False
    """Whether a line ending in the separator has that empty last field dropped (``a;b;c;``)."""

    def split(self) -> Split:
        sep = self.separator
        if sep is None:
            return str.split
        if self.trailing:
            return lambda text: text.split(sep)[:-1] if text.endswith(sep) else text.split(sep)
        return lambda text: text.split(sep)

    def parse(self, numbered: list[tuple[int, str]], path: str | os.PathLike[str], bad: BadLines) -> Rows:
        """The lines ``numbered`` through the reference parser."""
        return parse_rows(
            numbered,
            path,
            bad,
            split=self.split(),
            width=self.width,
            expected=self.expected,
            columns=self.columns,
            check=self.check,
        )


def zero_quaternions(first: int) -> Mask:
    """The ``suspect`` mask of rows whose four values from ``first`` on, a quaternion, are all zero."""

    def zero(values: FloatArray) -> NDArray[np.bool_]:
        return np.asarray(~np.any(values[:, first : first + 4], axis=1), dtype=np.bool_)

    return zero


def read_table(path: str | os.PathLike[str], bad: BadLines, layout: Layout) -> Table:
    """The rows of ``path`` (module doc); bad lines go to ``bad`` in file order."""
    with open(regular_file(path), "rb", buffering=0) as f:
        # One pass counting lines first: the arrays are allocated once, at most one row a line, and filled
        # block by block (concatenating blocks would hold the rows twice).
        size = 1 + sum(chunk.count(b"\n") for chunk in iter(lambda: f.read(BLOCK_BYTES), b""))
        f.seek(0)
        out = _Rows(size, layout)
        carry, number, previous = _skip_header(f, layout.data_from or 1), layout.data_from or 1, b""
        if carry is None:
            return _pure_python(path, bad, layout)
        while True:
            chunk = f.read(BLOCK_BYTES)
            data = carry + chunk
            if number == 1:
                data = data.removeprefix(codecs.BOM_UTF8)
                data = _header_as_comment(data, layout) if layout.data_from is None else data
            end = data.rfind(b"\n") + 1 if chunk else len(data)
            block, carry = data[:end], data[end:]
            # A lone \r: Python's text files break lines there, the core does not.
            if b"\r" in block and block.count(b"\r") != block.count(b"\r\n"):
                return _pure_python(path, bad, layout)
            cut = None
            if not chunk and block and not block.endswith(b"\n"):
                tail = (previous + block).decode("utf-8", "surrogateescape").split("\n")
                cut = _truncation(tail)
                if cut is not None:
                    block = block[: block.rfind(b"\n") + 1]
            if block:
                part, count = _block(path, bad, layout, block, number)
                out.add(part)
                number += count
                previous = (previous + block)[-_TAIL_BYTES:]
            if cut is not None:
                bad.bad(path, number, "truncated", cut, tail[-1].strip())
            if not chunk:
                break
    return out.table()


def _skip_header(f: BinaryIO, first: int) -> bytes | None:
    """The bytes read past the ``first - 1`` lines of a header from ``f`` (at its start), or None when a
    lone carriage return in them (a line break to Python's text files) makes the line count differ."""
    data, skip = b"", first - 1
    while skip:
        chunk = f.read(BLOCK_BYTES)
        if not chunk:
            return data
        data += chunk
        if data.count(b"\n") >= skip:
            end = -1
            for _ in range(skip):
                end = data.index(b"\n", end + 1)
            head, data = data[: end + 1], data[end + 1 :]
            return None if head.count(b"\r") != head.count(b"\r\n") else data
    return data


def _header_as_comment(data: bytes, layout: Layout) -> bytes:
    """``data`` (the start of a file) with a ``#`` put before its first non-blank line when that line is a
    header written without one (``timestamp,x,y,z,…``: a stamp field with letters), so that it is passed
    over as EuRoC's ``#timestamp [ns],…`` is; line numbers stay the same."""
    start = len(data) - len(data.lstrip())
    stop = data.find(b"\n", start)
    first = data[start : stop if stop >= 0 else len(data)].decode("utf-8", "surrogateescape").strip()
    return data[:start] + b"#" + data[start:] if _unmarked_header(first, layout) else data


def _unmarked_header(first: str, layout: Layout) -> bool:
    """Whether the first non-blank line ``first`` (stripped) is a header without ``#``."""
    fields = layout.split()(first)
    if first.startswith("#") or len(fields) <= layout.stamp_column:
        return False
    stamp = fields[layout.stamp_column].strip()
    return any(c.isalpha() for c in stamp) and not is_number(stamp)


class _Rows:
    """Arrays of ``size`` rows (an upper bound), filled in order; :meth:`table` views the filled ones."""

    def __init__(self, size: int, layout: Layout) -> None:
        self.lines = np.empty(size, np.int64)
        self.values = np.empty((size, len(layout.columns)))
        self.stamps = None if layout.stamp == "float" else np.empty(size, np.int64)
        self.n = 0

    def add(self, part: Table) -> None:
        k, m = self.n, len(part.lines)
        self.lines[k : k + m] = part.lines
        self.values[k : k + m] = part.values
        if self.stamps is not None and part.stamps is not None:
            self.stamps[k : k + m] = part.stamps
        self.n += m

    def table(self) -> Table:
        stamps = None if self.stamps is None else self.stamps[: self.n]
        exact = stamps is not None and not bool(np.any(stamps == INEXACT))
        return Table(self.lines[: self.n], self.values[: self.n], stamps if exact else None)


def _block(path: str | os.PathLike[str], bad: BadLines, layout: Layout, block: bytes, first: int) -> tuple[Table, int]:
    sep = None if layout.separator is None else ord(layout.separator)
    numbers, offsets, values, stamps, _, later, later_offsets, count = _core.text_parse_block(
        block,
        first,
        sep,
        layout.width,
        list(layout.columns),
        layout.stamp_column,
        layout.stamp,
        layout.stamp_required,
        layout.trailing,
    )
    lines = numbers.astype(np.int64)
    if layout.suspect is not None and len(values):
        flagged = layout.suspect(values)
        if flagged.any():
            later = np.concatenate([later, lines[flagged].astype(np.uint64)])
            later_offsets = np.concatenate([later_offsets, offsets[flagged]])
            lines, values = lines[~flagged], values[~flagged]
            stamps = stamps[~flagged] if len(stamps) else stamps
    if not len(later):
        return Table(lines, values, stamps), count
    # The deferred lines through the reference parser, in file order (so "raise" raises the first).
    order = np.argsort(later, kind="stable")
    numbered = []
    for k in order:
        start = int(later_offsets[k])
        stop = block.find(b"\n", start)
        text = block[start : stop if stop >= 0 else len(block)].decode("utf-8", "surrogateescape").strip()
        if text and not text.startswith("#"):
            numbered.append((int(later[k]), text))
    rows = layout.parse(numbered, path, bad)
    more = _stamps(rows, layout)
    merged_lines = np.concatenate([lines, np.asarray(rows.lines, dtype=np.int64)])
    merged = np.argsort(merged_lines, kind="stable")
    table = Table(
        merged_lines[merged],
        np.concatenate([values, np.asarray(rows.values, dtype=np.float64).reshape(-1, len(layout.columns))])[merged],
        np.concatenate([stamps, more])[merged] if layout.stamp != "float" else stamps,
    )
    return table, count


def _stamps(rows: Rows, layout: Layout) -> NDArray[np.int64]:
    """The exact stamps of rows read by Python, :data:`INEXACT` for those without the exact form."""
    if layout.exact is None:
        return np.zeros(0, np.int64)
    ns = [layout.exact(fields[layout.stamp_column].strip()) for fields in rows.fields]
    return np.array([INEXACT if n is None or n == INEXACT else n for n in ns], dtype=np.int64)


def _truncation(tail: list[str]) -> str | None:
    """Why the last of the lines ``tail`` (the end of a file without a final newline) reads as cut off
    mid-number, or None: its last field has fewer decimals than every one of the data lines before it
    in ``tail`` (a few hundred, at least :data:`_MIN_LINES`; ``repr`` prints 1 to 17 decimals, fixed
    formats always as many)."""
    texts = [t.strip() for t in tail]
    data = [t for t in texts if t and not t.startswith("#")]
    if not texts[-1] or texts[-1].startswith("#") or len(data) <= _MIN_LINES:
        return None
    ours = _decimals(data[-1])
    theirs = [d for d in map(_decimals, data[:-1]) if d is not None]
    if ours is None or not theirs or ours >= min(theirs):
        return None
    return (
        f"the last line has no newline and its last field {_last_field(data[-1])!r} has {ours} decimals, "
        f"fewer than any of the {len(theirs)} lines before it ({min(theirs)} or more): cut off mid-number"
    )


def _last_field(line: str) -> str:
    for sep in (",", ";", "\t", " "):
        line = line.rsplit(sep, 1)[-1]
    return line.strip()


def _decimals(line: str) -> int | None:
    """The number of digits after the point of the last field of ``line`` (its mantissa), None for no number."""
    mantissa = _last_field(line).lower().split("e", 1)[0]
    whole, point, fraction = mantissa.partition(".")
    if not (whole.lstrip("+-") + fraction).isascii() or not (whole.lstrip("+-") + fraction).isdigit():
        return None
    return len(fraction) if point else 0


def _pure_python(path: str | os.PathLike[str], bad: BadLines, layout: Layout) -> Table:
    """:func:`read_table` by the reference parser alone (a file with lone carriage returns)."""
    with open_text(path) as f:
        raw = list(f)
    start = layout.data_from or 1
    numbered = [
        (n, text) for n, line in enumerate(raw, 1) if n >= start and (text := line.strip()) and not text.startswith("#")
    ]
    first = next((line.strip() for line in raw if line.strip()), "")
    if layout.data_from is None and numbered and numbered[0][1] == first and _unmarked_header(first, layout):
        numbered.pop(0)
    cut = _truncation(raw[-_TAIL_LINES:]) if raw and not raw[-1].endswith(("\n", "\r")) else None
    if cut is not None:
        numbered.pop()
    rows = layout.parse(numbered, path, bad)
    if cut is not None:
        bad.bad(path, len(raw), "truncated", cut, raw[-1].strip())
    stamps = _stamps(rows, layout)
    values = np.asarray(rows.values, dtype=np.float64).reshape(-1, len(layout.columns))
    exact = layout.exact is not None and not bool(np.any(stamps == INEXACT))
    return Table(np.asarray(rows.lines, dtype=np.int64), values, stamps if exact else None)


def increasing_table(
    table: Table, order: NDArray[np.int64] | FloatArray, path: str | os.PathLike[str], bad: BadLines, layout: Layout
) -> Table:
    """The rows :func:`imukit.io._lines.in_order` keeps of the stamps ``order``; the others go to ``bad``
    with the messages of :func:`imukit.io._lines.increasing` (their texts read again from the file)."""
    if len(order) < 2 or bool(np.all(order[1:] > order[:-1])):
        return table
    keep, out = in_order(order.tolist(), first=not bad.skip)
    wanted = {int(table.lines[k]) for d in out for k in (d.at, d.other)}
    texts = _line_texts(path, wanted)
    split = layout.split()
    lines = table.lines.tolist()

    def shown_stamps() -> list[str]:
        shown = [""] * len(lines)
        for d in out:
            for k in (d.at, d.other):
                shown[k] = split(texts[lines[k]])[layout.stamp_column].strip()
        return shown

    shown = shown_stamps()
    for d in out:
        bad.bad(path, lines[d.at], d.kind, d.detail(shown, lambda k: f"line {lines[k]}"), texts[lines[d.at]])
    return table.take(np.asarray(keep, dtype=np.intp))


def _line_texts(path: str | os.PathLike[str], numbers: set[int]) -> dict[int, str]:
    """The stripped texts of lines ``numbers`` of ``path`` (read again: only for lines out of order)."""
    found: dict[int, str] = {}
    last = max(numbers, default=0)
    with open_text(path) as f:
        for n, line in enumerate(f, 1):
            if n in numbers:
                found[n] = line.strip()
            if n >= last:
                break
    return found
