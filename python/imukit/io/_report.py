"""What the readers skipped: :class:`SkippedLine`, :class:`ReadReport`, :class:`SkippedLinesWarning`.

Every reader takes ``on_bad_line="raise" | "skip"`` and ``report=None``. One :class:`BadLines` per
public call carries both: in "raise" mode it raises the first bad line as a
:class:`imukit.FileFormatError`; in "skip" mode it records the line and, when the call ends, hands
the records to ``report`` or, without one, emits one :class:`SkippedLinesWarning`.
"""

from __future__ import annotations

import os
import warnings
from collections import Counter
from typing import Literal, NamedTuple, TypeVar

from imukit._errors import FileFormatError, ParameterError

__all__ = ["BadLines", "ReadReport", "SkippedLine", "SkippedLinesWarning", "check_on_bad_line"]

OnBadLine = Literal["raise", "skip"]
_T = TypeVar("_T")
# __str__ lists this many skipped lines, then says how many more there are.
_STR_LINES = 20
# The kinds of bad line (the part of SkippedLine.reason before ": "), singular -> plural for summaries.
KINDS = {
    "malformed": "malformed",
    "wrong column count": "wrong column counts",
    "non-finite": "non-finite",
    "duplicate stamp": "duplicate stamps",
    "stamp going back": "stamps going back",
    "stamp out of order": "stamps out of order",
    "zero quaternion": "zero quaternions",
    "not a rotation": "not rotations",
    "unpaired": "unpaired",
    "missing field": "missing fields",
    "zero stamp": "zero stamps",
    "truncated": "truncated",
    "header": "headers",
}


class SkippedLine(NamedTuple):
    """One line a reader skipped in ``on_bad_line="skip"`` mode."""

    path: str
    """The file, as the reader was given it."""
    line: int
    """1-based line number in that file (for a ROS bag: the message's 1-based index on its topic)."""
    reason: str
    """``"<kind>: <detail>"``; the detail is the message "raise" mode would have given
    (``"duplicate stamp: time must increase strictly, but 5 follows 5 (line 3)"``). The kinds:

    - ``malformed``: not a number (or not an integer stamp) where one is read; for a ROS bag also an
      undecodable message or ``nanosec`` ≥ 10⁹;
    - ``wrong column count``;
    - ``non-finite``: inf or NaN, or a value that overflows when converted to SI units;
    - ``duplicate stamp``: the stamp of the last kept line before it (the first is kept);
    - ``stamp going back``: below the stamp of the last kept line before it;
    - ``stamp out of order``: above the stamp of the first kept line after it (e.g. a stamp from the
      far future: it alone is skipped, the lines after it are kept);
    - ``zero quaternion``; ``not a rotation`` (KITTI: a rotation block that is not orthonormal);
    - ``unpaired``: a line whose partner in another file was skipped (KITTI poses and times);
    - ``missing field``: a ROS message flagging a field absent (covariance element 0 = -1);
    - ``zero stamp``: a ROS message with an unset (zero) header stamp;
    - ``header``: a first line of numbers taken as the header (``0,1,2,…`` as pandas writes), reported
      in both modes;
    - ``truncated``: a last line without newline whose last field has fewer decimals than the line
      before it (a writer cut off mid-number, ``9.81`` → ``9.``).

    Which stamps are kept: the longest strictly increasing subsequence of the stamps of the lines that
    are otherwise valid, the earliest lines among equally long ones."""
    text: str
    """The line, stripped of surrounding white space."""

    @property
    def kind(self) -> str:
        """The part of :attr:`reason` before the first ``": "``."""
        return self.reason.partition(": ")[0]


class SkippedLinesWarning(UserWarning):
    """Emitted once per read that skipped lines when no :class:`ReadReport` was passed to receive them."""


class ReadReport:
    """Receives the lines a reader skipped; pass one as ``report=`` (it may be reused across reads).

    Attributes
    ----------
    skipped
        :class:`SkippedLine` records, file by file in reading order, by line number within a file.
    """

    def __init__(self) -> None:
        self.skipped: list[SkippedLine] = []

    def __len__(self) -> int:
        return len(self.skipped)

    def __bool__(self) -> bool:
        return bool(self.skipped)

    def summary(self) -> str:
        """One line: ``"3 lines skipped in a.csv: 2 duplicate stamps, 1 malformed"`` (most frequent kind
        first), or ``"no lines skipped"``."""
        return summarise(self.skipped)

    def __str__(self) -> str:
        lines = [self.summary()]
        lines += [f"  {s.path}, line {s.line}: {s.reason}" for s in self.skipped[:_STR_LINES]]
        if len(self.skipped) > _STR_LINES:
            lines.append(f"  … and {len(self.skipped) - _STR_LINES} more")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"<ReadReport: {self.summary()}>"


def summarise(skipped: list[SkippedLine], *, files: bool = True) -> str:
    """``"3 lines skipped in a.csv: 2 duplicate stamps, 1 malformed"`` (without ``in …`` unless ``files``)."""
    if not skipped:
        return "no lines skipped"
    counts = Counter(s.kind for s in skipped).most_common()
    kinds = ", ".join(f"{n} {KINDS.get(kind, kind) if n > 1 else kind}" for kind, n in counts)
    noun = "line" if len(skipped) == 1 else "lines"
    where = f" in {', '.join(dict.fromkeys(s.path for s in skipped))}" if files else ""
    return f"{len(skipped)} {noun} skipped{where}: {kinds}"


def check_on_bad_line(on_bad_line: object) -> OnBadLine:
    """``on_bad_line`` if it is ``"raise"`` or ``"skip"``, else :class:`imukit.ParameterError`."""
    if on_bad_line == "raise" or on_bad_line == "skip":
        return on_bad_line
    raise ParameterError(f"expected 'raise' or 'skip', got {on_bad_line!r}", argument="on_bad_line")


class BadLines:
    """The ``on_bad_line`` / ``report`` pair of one public reader call (internal).

    Readers call :meth:`bad` for each bad line and end with :meth:`done`, which hands the records
    to the report, or warns when there is none.
    """

    def __init__(self, on_bad_line: object, report: object) -> None:
        self.skip = check_on_bad_line(on_bad_line) == "skip"
        if report is not None and not isinstance(report, ReadReport):
            raise ParameterError(
                f"expected an imukit.io.ReadReport or None, got {type(report).__name__}", argument="report"
            )
        self.report = report
        self.records: list[SkippedLine] = []

    def bad(self, path: str | os.PathLike[str], line: int, kind: str, detail: str, text: str) -> None:
        """Line ``line`` of ``path`` is bad: raise ``path: <path>, line <n>: <detail>``, or record it."""
        where = os.fspath(path)
        if not self.skip:
            raise FileFormatError(f"{where}, line {line}: {detail}", argument="path")
        self.records.append(SkippedLine(where, line, f"{kind}: {detail}", text))

    def note(self, path: str | os.PathLike[str], line: int, kind: str, detail: str, text: str) -> None:
        """Record line ``line`` of ``path``, read as something other than data, in either mode."""
        self.records.append(SkippedLine(os.fspath(path), line, f"{kind}: {detail}", text))

    def skipped_in(self, path: str | os.PathLike[str]) -> str:
        """``" (N lines skipped: …)"`` for the records of ``path`` so far, or ``""``: for an error saying
        that nothing valid is left."""
        where = os.fspath(path)
        mine = [s for s in self.records if s.path == where]
        return f" ({summarise(mine, files=False)})" if mine else ""

    def done(self, value: _T) -> _T:
        """Hand the records over (to the report, else as one warning) and return ``value``.

        Records are ordered by file (in first-seen order) and by line within a file, whatever order the
        checks found them in.
        """
        if self.records:
            order = {path: k for k, path in enumerate(dict.fromkeys(s.path for s in self.records))}
            records = sorted(self.records, key=lambda s: (order[s.path], s.line))
            self.records = []
            if self.report is not None:
                self.report.skipped.extend(records)
            else:
                # stacklevel 3: this method, the public reader, its caller.
                warnings.warn(summarise(records), SkippedLinesWarning, stacklevel=3)
        return value
