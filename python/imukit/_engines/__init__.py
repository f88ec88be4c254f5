"""Preintegration engines: the seam behind :func:`imukit.preintegrate_windows` (``engine=``).

An engine is a function ``(imu, windows, params, threads) -> Preintegration``: it preintegrates
every window of :class:`Windows` (edges on ``imu.seconds``' axis, plus the absolute edges the
record carries) with :class:`imukit.PreintParams` and returns one record. :data:`ENGINES` is the
registry: an engine joins by one line there, and ``tests/test_preint_engines.py`` holds every
registered engine to the Rust one.

=============  ===================================================================================
``rust``       the core: one native call fills the record's arrays, windows in parallel, GIL
               released (the default)
``numpy_ref``  a pure-numpy reference written from the equations (slow: a Python loop per sample)
=============  ===================================================================================
"""

from __future__ import annotations

from typing import Protocol

from imukit._engines import numpy_ref, rust
from imukit._engines._windows import Windows
from imukit._preint_record import Preintegration, PreintParams
from imukit.imu import ImuData

__all__ = ["ENGINES", "Engine", "Windows"]


class Engine(Protocol):
    """A preintegration engine (module docs)."""

    def __call__(self, imu: ImuData, windows: Windows, params: PreintParams, threads: int | None) -> Preintegration: ...


ENGINES: dict[str, Engine] = {
    "rust": rust.preintegrate_windows,
    "numpy_ref": numpy_ref.preintegrate_windows,
}
