"""What a file format is to detection: a :class:`Format` (``docs/io.md``, "Adding a format").

===============  ================================================================================
``name``         unique, e.g. ``"euroc-imu-csv"`` (:func:`imukit.io.unregister_format` takes it)
``kind``         what ``read`` returns: ``"imu"`` ``ImuData`` or ``(ImuData, Trajectory | None)``,
                 ``"trajectory"`` a ``Trajectory``, ``"both"`` ``(ImuData, Trajectory | None)``
                 (:func:`imukit.io.read_trajectory` takes its trajectory)
``sniff``        ``sniff(path, head) -> bool``: whether ``path`` is of this format, from its name or
                 layout, or its first lines (:class:`Head`); may raise :class:`FileFormatError` for
                 a file it recognises but cannot read safely (a pose CSV whose quaternion order is
                 not said)
``read``         ``read(path, bad, **options)``: the private reader, reporting bad lines to ``bad``
                 (:class:`imukit.io._report.BadLines`); ``options`` as named in ``options``
``description``  one line for the "tried …" error text and the CLI's help (formats that share it
                 are listed once)
``options``      the keyword options of :func:`imukit.io.read_imu` the reader takes (ROS bags' topics)
===============  ================================================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from itertools import islice
from pathlib import Path
from typing import Any, Callable, Literal

from imukit.io._lines import data_lines, plain_digits

__all__ = ["Format", "Head"]

Kind = Literal["imu", "trajectory", "both"]


class Head:
    """The first lines of ``path``, read on first use and shared by every format's sniff."""

    def __init__(self, path: Path) -> None:
        self.path = path

    @cached_property
    def lines(self) -> list[tuple[int, str]] | None:
        """``(line number, stripped text)`` of the first two non-blank lines, and of the first data line
        after them when it comes later (past a block of ``#`` lines); None for a folder, a missing path
        or a file that is not UTF-8 text."""
        if not self.path.is_file():
            return None
        try:
            with open(self.path, encoding="utf-8-sig") as f:  # -sig: a byte order mark is not part of the line
                first = list(islice(((n, line.strip()) for n, line in enumerate(f, 1) if line.strip()), 2))
            return first + list(islice(data_lines(self.path), 1))
        except UnicodeDecodeError:
            return None

    def fields(self, delimiter: str | None) -> list[str]:
        """The fields of the first line that is not a ``#`` comment; [] if there is none."""
        for _, text in self.lines or ():
            if not text.startswith("#"):
                return text.split(delimiter)
        return []


@dataclass(frozen=True)
class Format:
    """One format :func:`imukit.io.read_imu` / :func:`imukit.io.read_trajectory` detect (module doc)."""

    name: str
    kind: Kind
    sniff: Callable[[Path, Head], bool]
    read: Callable[..., Any]
    description: str
    options: tuple[str, ...] = ()

    def reads(self, kind: Literal["imu", "trajectory"]) -> bool:
        """Whether :func:`imukit.io.read_imu` (``"imu"``) or ``read_trajectory`` uses this format."""
        return self.kind in (kind, "both")


def is_number(text: str) -> bool:
    """Whether a field reads as a number by the readers' rule (:func:`imukit.io._lines.plain_digits`, `float()`)."""
    if not plain_digits(text):
        return False
    try:
        float(text)
    except ValueError:
        return False
    return True


def shorten(text: str, limit: int = 80) -> str:
    """``text`` quoted, cut to ``limit`` characters (a line shown in an error)."""
    return repr(text if len(text) <= limit else text[: limit - 3] + "...")
