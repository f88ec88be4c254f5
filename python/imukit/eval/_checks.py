"""Argument checks shared by the evaluation functions (messages start with the argument's name)."""

from __future__ import annotations

import numpy as np

from imukit._errors import ParameterError
from imukit.state import Trajectory


def check_trajectory(x: object, name: str) -> Trajectory:
    """``x`` if it is a :class:`~imukit.Trajectory`, else :class:`ParameterError` naming ``name``."""
    if not isinstance(x, Trajectory):
        raise ParameterError(f"expected an imukit Trajectory, got {type(x).__name__}", argument=name)
    return x


def finite_float(x: object, name: str, *, positive: bool = False) -> float:
    """``x`` as a finite float (> 0 when ``positive``), else :class:`ParameterError` naming ``name``."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise ParameterError(f"expected a number, got {x!r}", argument=name)
    value = float(x)
    if not np.isfinite(value) or (positive and value <= 0.0):
        raise ParameterError(f"expected a finite{' positive' if positive else ''} number, got {value!r}", argument=name)
    return value
