"""The imukit exception hierarchy.

Every error imukit raises on bad input is an :class:`ImukitError`; the ones about a value also
derive from :class:`ValueError` (and dtype errors from :class:`TypeError`), so callers can catch
either. Messages start with the name of the offending argument.
"""

from __future__ import annotations

__all__ = [
    "DTypeError",
    "FileFormatError",
    "GimbalLockError",
    "ImukitError",
    "InvalidQuaternionError",
    "InvalidRotationError",
    "MissingDependencyError",
    "NonFiniteError",
    "ParameterError",
    "ResourceError",
    "ShapeError",
    "TimestampError",
]


class ImukitError(Exception):
    """Base class of every exception imukit raises on purpose.

    ``argument`` names the input at fault (a keyword of the function called, or a dotted field such
    as ``"gain_ramp.duration_s"``), ``index`` the sample or row of it when one is at fault; both
    are None where nothing narrower than the call is to blame. ``message`` says what was expected;
    ``str(exc)`` is ``"<argument>: <message>"``. Callers (the CLI among them) read the fields, never
    the text.
    """

    def __init__(self, message: str, *, argument: str | None = None, index: int | None = None) -> None:
        self.message = message
        self.argument = argument
        self.index = index
        super().__init__(message if argument is None else f"{argument}: {message}")

    def __reduce__(self) -> tuple[object, ...]:
        # Exceptions pickle as cls(*args): the keyword fields need their own constructor call.
        return (_rebuild, (type(self), self.message, self.argument, self.index))


def _rebuild(cls: type[ImukitError], message: str, argument: str | None, index: int | None) -> ImukitError:
    return cls(message, argument=argument, index=index)


class ShapeError(ImukitError, ValueError):
    """An array has the wrong shape (the message names the expected one)."""


class DTypeError(ImukitError, TypeError):
    """An array has a dtype that cannot be read as real numbers (object, complex, str, ...)."""


class NonFiniteError(ImukitError, ValueError):
    """An input holds NaN or ±inf, or finite input is too large to compute with."""


class InvalidQuaternionError(ImukitError, ValueError):
    """A quaternion has zero norm and so represents no rotation."""


class InvalidRotationError(ImukitError, ValueError):
    """A 3x3 matrix is not a rotation (not orthonormal, or det ≠ +1)."""


class GimbalLockError(ImukitError, ValueError):
    """Pitch is within the tolerance of ±90°, where the ZYX Euler-angle rate map is singular."""


class ParameterError(ImukitError, ValueError):
    """A keyword option has a value outside its domain."""


class ResourceError(ImukitError, MemoryError):
    """The memory a result sized by the input needs cannot be had (the message names the argument
    that sized it and the size: ``"boundaries: 20,000,000 windows need 51.7 GB"``)."""


class TimestampError(ImukitError, ValueError):
    """Timestamps that are not strictly increasing (the message names the first bad sample)."""


class FileFormatError(ImukitError, ValueError):
    """A file that cannot be read (the message names the file, and the line number or the key)."""


class MissingDependencyError(ImukitError, ImportError):
    """An optional package that a function needs (matplotlib for plots) is not installed."""


# Tracebacks and reprs name the public path (imukit.GimbalLockError), not this private module.
for _cls in (
    ImukitError,
    ShapeError,
    DTypeError,
    NonFiniteError,
    InvalidQuaternionError,
    InvalidRotationError,
    GimbalLockError,
    ParameterError,
    ResourceError,
    TimestampError,
    FileFormatError,
    MissingDependencyError,
):
    _cls.__module__ = "imukit"
