"""The rotating Earth: :class:`LocalLevel`, a navigation frame fixed on the WGS-84 ellipsoid.

=====================  ===========================================================================
frame                  origin at geodetic ``latitude`` [rad] (``degrees=True`` for degrees) and
                       ``height`` [m] above the ellipsoid (−a/2 … 1000 km); ``axes`` ``"enu"`` (default, imukit's
                       z-up world) or ``"ned"``; it turns with the Earth
``earth_rate``         ``ω_ie`` (3,) in the frame's axes [rad/s]: ENU ``Ω (0, cos φ, sin φ)``, NED
                       ``Ω (cos φ, 0, −sin φ)``, ``Ω = 7.292115e-5``; pass it as ``omega_coriolis``
``gravity``            plumb-bob gravity (3,) at the origin [m/s²], pointing down: WGS-84 normal
                       gravity (Somigliana) with the free-air height correction
``transport``          ``False`` (default): the frame stays fixed at its origin, positions are
                       metres in it. ``True``: the frame **follows the vehicle** over the
                       ellipsoid, starting at the origin: positions are geodetic
                       ``(latitude [rad], longitude [rad], height [m])``, the frame turns at
                       ``ω_ie + ω_en`` (transport rate), gravity follows latitude and height
                       (``crates/imukit/src/ellipsoid.rs``); ``integrate`` takes schemes
                       ``"midpoint"`` and ``"rk4"`` there
used by                :func:`imukit.integrate` and :func:`imukit.sim.simulate` (``frame=``); the
                       preintegration's ``predict`` / ``residual`` take ``frame.earth_rate`` as
                       ``omega_coriolis`` and the params ``frame.gravity``
=====================  ===========================================================================

The numbers come from the core (``crates/imukit/src/earth.rs``), which also checks the values;
equations, references and their size per IMU grade: ``docs/navigation.md``.
"""

from __future__ import annotations

import math
import types

import numpy as np

from imukit import _core
from imukit._arrays import FloatArray, flag, readonly_copy, real_scalar
from imukit._errors import ParameterError
from imukit._frozen import Frozen
from imukit._names import canonical

__all__ = ["AXES", "LocalLevel"]

AXES: tuple[str, ...] = _core.LOCAL_LEVEL_AXES


class LocalLevel(Frozen):
    """A local-level frame fixed on the Earth at ``latitude``, ``height`` with ``axes`` (module docs).
    Immutable; ``earth_rate`` and ``gravity`` are read-only arrays computed once."""

    __slots__ = ("axes", "earth_rate", "gravity", "height", "latitude", "transport")
    _fields = ("latitude", "height", "axes", "earth_rate", "gravity", "transport")

    latitude: float
    height: float
    axes: str
    earth_rate: FloatArray
    gravity: FloatArray
    transport: bool

    def __init__(
        self,
        latitude: float,
        height: float = 0.0,
        axes: str = "enu",
        *,
        degrees: bool = False,
        transport: bool = False,
    ) -> None:
        for name, value in (("degrees", degrees), ("transport", transport)):
            flag(value, name)
        lat = real_scalar(latitude, "latitude", what="a latitude", accept=lambda x: True)
        h = real_scalar(height, "height", what="a height in metres", accept=lambda x: True)
        name = canonical(axes, "axes", AXES)
        lat = math.radians(lat) if degrees else lat
        # The core checks the values (latitude within ±π/2, and off the poles for a frame that
        # follows the vehicle; finite height), read by field name.
        fields = types.SimpleNamespace(latitude=lat, height=h, axes=name, transport=bool(transport))
        earth_rate, gravity = _core.local_level(fields)
        self._set(lat, h, name, readonly_copy(np.array(earth_rate)), readonly_copy(np.array(gravity)), transport)

    def __repr__(self) -> str:
        moving = ", transport=True" if self.transport else ""
        return f"LocalLevel(latitude={self.latitude!r}, height={self.height!r}, axes={self.axes!r}{moving})"


def world_of(frame: LocalLevel | None, gravity: list[float]) -> tuple[list[float], list[float]]:
    """``(gravity, rotation rate)`` of the world the core integrates in: ``gravity`` and zero
    without a frame, else the frame's; a frame with a non-default ``gravity`` is refused (two
    gravities for one world)."""
    if frame is None:
        return gravity, [0.0, 0.0, 0.0]
    if not isinstance(frame, LocalLevel):
        raise ParameterError(f"expected an imukit.LocalLevel or None, got {type(frame).__name__}", argument="frame")
    if tuple(gravity) != tuple(_core.GRAVITY):
        raise ParameterError("leave gravity at its default with a frame, which has its own", argument="gravity")
    return [float(v) for v in frame.gravity], [float(v) for v in frame.earth_rate]
