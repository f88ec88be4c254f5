"""Units that header names state (``Gyroscope X (deg/s)``, ``time [ns]``, ``time_ns``): one
vocabulary for every reader that takes columns by name or index (``docs/io.md``, "Units in the
header").

A unit is read from a bracket at the end of a name, or for a time column from a last word
(``time_ns``, ``timestamp ms``). Spellings are compared lower-cased with white space removed.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Sequence

from imukit._errors import ParameterError

__all__ = ["canonical", "resolve", "time_suffix", "unit_in_name", "words_and_unit"]

_SPELLINGS = {
    "time": {
        "s": ("s", "sec", "secs", "second", "seconds"),
        "ms": ("ms", "msec", "millisecond", "milliseconds"),
        "us": ("us", "µs", "μs", "usec", "microsecond", "microseconds"),
        "ns": ("ns", "nsec", "nanosecond", "nanoseconds"),
    },
    "gyro": {
        "rad/s": ("rad/s", "rad/sec", "rads^-1", "rads-1", "rad*s^-1", "radian/s", "radians/s"),
        "deg/s": ("deg/s", "deg/sec", "°/s", "º/s", "dps", "degs^-1", "degree/s", "degrees/s", "degrees/sec"),
    },
    "accel": {
        "m/s^2": ("m/s^2", "m/s²", "m/s2", "ms^-2", "ms-2", "m*s^-2", "m/s/s", "mps2"),
        "g": ("g", "g0"),
        "mg": ("mg", "millig", "milli-g"),
    },
}
_CANONICAL = {kind: {s: unit for unit, names in units.items() for s in names} for kind, units in _SPELLINGS.items()}
_BRACKET = re.compile(r"\s*[\[(]([^\])]*)[\])]\s*$")
_TIME_WORDS = ("time", "t", "timestamp", "stamp")


def canonical(kind: str, text: str) -> str | None:
    """``text`` (a stated unit) as imukit's name for it (``"dps"`` → ``"deg/s"``) for ``kind``
    (``"time"``, ``"gyro"``, ``"accel"``), None when it is not one of the spellings above."""
    return _CANONICAL[kind].get(re.sub(r"\s+", "", text.lower()))


def words_and_unit(name: str) -> tuple[str, str]:
    """``name`` as (its words, its bracketed unit): ``"Gyroscope X (deg/s)"`` → ``("gyroscope x", "deg/s")``:
    lower-cased, a leading ``#`` dropped, ``. _ - /`` and white space as single spaces."""
    unit = _BRACKET.search(name)
    bare = name[: unit.start()] if unit else name
    words = re.sub(r"[._\-/\s]+", " ", bare.strip().lstrip("#").lower()).strip()
    return words, (unit[1].strip().lower() if unit else "")


def unit_in_name(kind: str, name: str) -> str:
    """The unit ``name`` states for a column of ``kind``, as written (lower-cased): its bracket, or
    for a time column a last word (``time_ns``); ``""`` when it states none."""
    words, unit = words_and_unit(name)
    if not unit and kind == "time":
        suffix = time_suffix(words)
        unit = suffix[1] if suffix else ""
    return unit


def time_suffix(words: str) -> tuple[str, str] | None:
    """``"time ns"`` → ``("time", "ns")``: a time name whose last word is a time unit, else None
    (``words`` lower-cased, separators as single spaces)."""
    head, _, last = words.rpartition(" ")
    unit = canonical("time", last) if head in _TIME_WORDS else None
    return None if unit is None else (head, unit)


def resolve(
    kind: str,
    given: str | None,
    headers: list[tuple[int, list[str]]],
    columns: Sequence[int],
    argument: str,
    where: str,
) -> str | None:
    """The unit of the ``kind`` columns ``columns`` (0-based) of a file (``where``): ``given`` (the
    argument ``argument``; a warning when it contradicts the unit their header names state: a
    header can be wrong, but not silently overridden); else the unit the names state; else None
    (the reader's default). A column's unit is the one its name states in the last header line that
    states one there (an exporter's group line above the names). A ParameterError naming
    ``argument`` when the names state different units, or when, without ``given``, a name states a
    unit this module does not know: a column read in the wrong unit is a wrong answer, not a
    default."""
    stated: dict[str, str] = {}  # unit → the first name stating it
    unknown: list[str] = []
    for k in columns:
        for _, names in reversed(headers):
            text = unit_in_name(kind, names[k]) if k < len(names) else ""
            if text:
                unit = canonical(kind, text)
                if unit is None:
                    unknown.append(names[k])
                else:
                    stated.setdefault(unit, names[k])
                break
    quoted = ", ".join(f"{name!r} ({unit})" for unit, name in stated.items())
    if len(stated) > 1:
        raise ParameterError(
            f"the header of {where} states different units for the columns read: {quoted}", argument=argument
        )
    if given is not None:
        if stated and given not in stated:
            warnings.warn(
                f"{argument}={given!r} overrides the header of {where}, which names the column {quoted}; leave "
                f"{argument} out to read the header's unit",
                UserWarning,
                stacklevel=2,
            )
        return given
    if unknown:
        known = ", ".join(map(repr, _SPELLINGS[kind]))
        raise ParameterError(
            f"the header of {where} names the column {unknown[0]!r}, whose unit imukit does not read; pass "
            f"{argument}= ({known}) to say what the column holds",
            argument=argument,
        )
    return next(iter(stated), None)
