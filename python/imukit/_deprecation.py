"""The one way imukit says that a name is deprecated.

The warning points at the first line outside the imukit package, however many imukit frames lie in
between (``integrate(scheme="euler")`` and ``preintegrate(..., scheme="euler")`` reach the check at
different depths): the user sees their own line, and imukit's own use of a deprecated name, which
would point inside the package, is an error in the test suite (pyproject's ``filterwarnings``).
"""

from __future__ import annotations

import os
import sys
import warnings

__all__ = ["deprecated"]

_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep


def deprecated(message: str) -> None:
    """Warn ``message`` as a :class:`DeprecationWarning` at the caller's first frame outside imukit."""
    level, frame = 2, sys._getframe(1)
    while frame.f_back is not None and _inside(frame.f_code.co_filename):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, DeprecationWarning, stacklevel=level)


def _inside(filename: str) -> bool:
    # "<string>": code generated for imukit (a dataclass __init__) counts as imukit's own.
    return filename.startswith("<") or os.path.abspath(filename).startswith(_PACKAGE)
