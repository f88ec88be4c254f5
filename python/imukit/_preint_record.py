"""The preintegration vocabulary as data: :class:`PreintParams` (how to preintegrate) and
:class:`Preintegration` (what came out: M windows as arrays with a leading window dimension).

=====================  ===========================================================================
``PreintParams``       noise, bias, gravity, scheme, combined, saturation_noise_factor,
                       body_from_sensor; frozen;
                       defaults from the core (``GRAVITY``, ``DEFAULT_SATURATION_NOISE_FACTOR``);
                       ``scheme="euler"`` is the deprecated alias of ``"lie_euler"``
``Preintegration``     ``delta_rotation (M,3,3)``, ``delta_velocity (M,3)``, ``delta_position (M,3)``,
                       ``delta_t (M,)``, ``covariance (M,9,9)``, ``bias_jacobian (M,9,6)``,
                       ``covariance_combined (M,15,15)`` or None, ``t_start``/``t_end (M,)`` float s
                       (NaN where unknown: a streamed accumulator), ``t_start_ns``/``t_end_ns (M,)``
                       int64 or None (exact edges of nanosecond stamps), ``params``
records                arrays read-only; ``rec[m]`` and ``rec[a:b]`` are records (M = 1, b − a);
                       ``len(rec)`` is M; pickle and ``copy.deepcopy`` rebuild them exactly
=====================  ===========================================================================
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imukit import _core
from imukit._arrays import FloatArray, choice, flag, real_scalar, vector3
from imukit._errors import ParameterError, ShapeError
from imukit._extrinsics import Pose, has_lever_arm, sensor_pose
from imukit._names import canonical
from imukit.imu import ImuBias, ImuNoise

__all__ = ["SCHEMES", "SCHEME_ALIASES", "PreintParams", "Preintegration", "scheme_name"]

SCHEMES: tuple[str, ...] = tuple(_core.PREINT_SCHEMES)
"""Canonical scheme names, in the core's order."""
SCHEME_ALIASES: dict[str, str] = dict(_core.PREINT_SCHEME_ALIASES)
"""Deprecated scheme names → canonical (they still work, with a :class:`DeprecationWarning`)."""


def scheme_name(scheme: str) -> str:
    """The canonical name of ``scheme``; a deprecated alias warns (:class:`DeprecationWarning`)."""
    if isinstance(scheme, str) and scheme in SCHEME_ALIASES:
        return canonical(scheme, "scheme", SCHEMES, SCHEME_ALIASES)
    return choice(scheme, "scheme", SCHEMES)


@dataclasses.dataclass(frozen=True, eq=False)
class PreintParams:
    """How to preintegrate: the options that :func:`imukit.preintegrate`,
    :func:`imukit.preintegrate_windows` and :class:`imukit.PreintegratedImu` take, as one value.

    ``gravity`` defaults to the core's ``GRAVITY``, ``saturation_noise_factor`` to the
    core's ``DEFAULT_SATURATION_NOISE_FACTOR``; ``scheme`` is ``"midpoint"`` or ``"lie_euler"``
    (``"euler"``: deprecated alias).
    """

    noise: ImuNoise
    bias: ImuBias = dataclasses.field(default_factory=ImuBias)
    gravity: tuple[float, float, float] = _core.GRAVITY
    scheme: str = _core.PREINT_DEFAULT_SCHEME
    combined: bool = False
    saturation_noise_factor: float = _core.DEFAULT_SATURATION_NOISE_FACTOR
    body_from_sensor: Any = None
    """``(R_bs, lever arm)``, the IMU's pose in the body frame (``(Rotation, (3,))``), kept as
    ``(R_bs rows, lever arm)`` tuples; the deltas are then the body's (:mod:`imukit._extrinsics`;
    with a lever arm, ``combined=True`` is refused)."""

    def __post_init__(self) -> None:
        if not isinstance(self.noise, ImuNoise):
            raise ParameterError(f"expected an imukit.ImuNoise, got {type(self.noise).__name__}", argument="noise")
        bias = ImuBias() if self.bias is None else self.bias
        if not isinstance(bias, ImuBias):
            raise ParameterError(f"expected an imukit.ImuBias or None, got {type(bias).__name__}", argument="bias")
        factor = real_scalar(
            self.saturation_noise_factor,
            "saturation_noise_factor",
            what="a finite factor ≥ 1",
            accept=lambda x: math.isfinite(x) and x >= 1.0,
        )
        g = vector3(self.gravity, "gravity")
        pose = _pose(self.body_from_sensor)
        fields = {
            "bias": bias,
            "gravity": (float(g[0]), float(g[1]), float(g[2])),
            "scheme": scheme_name(self.scheme),
            "combined": flag(self.combined, "combined"),
            "saturation_noise_factor": factor,
            "body_from_sensor": pose,
        }
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PreintParams):
            return NotImplemented
        return all(getattr(self, f.name) == getattr(other, f.name) for f in dataclasses.fields(self))

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[Any, ...]:
        # ImuBias is rebuilt from its arrays: it is a slotted immutable type.
        b = self.bias
        return (
            _params,
            (
                self.noise,
                b.gyro,
                b.accel,
                self.gravity,
                self.scheme,
                self.combined,
                self.saturation_noise_factor,
                self.body_from_sensor,
            ),
        )

    def replace(self, **changes: Any) -> PreintParams:
        """A copy with ``changes`` (``dataclasses.replace``)."""
        return dataclasses.replace(self, **changes)

    def _template(self) -> _core.Preintegrator:
        """An empty core preintegrator with these options (the glue reads them by name)."""
        return _core.Preintegrator(self._integrated())

    def _integrated(self) -> PreintParams:
        """The options the core integrates with: with a lever arm the readings are the body
        origin's, bias removed (:mod:`imukit._extrinsics`), so no bias and no pose."""
        if not has_lever_arm(self.body_from_sensor):
            return self
        return dataclasses.replace(self, bias=ImuBias(), body_from_sensor=None)


def _params(
    noise: ImuNoise,
    gyro: FloatArray,
    accel: FloatArray,
    gravity: tuple[float, float, float],
    scheme: str,
    combined: bool,
    factor: float,
    pose: Pose | None = None,
) -> PreintParams:
    return PreintParams(noise, ImuBias(gyro, accel), gravity, scheme, combined, factor, pose)


def _pose(value: object) -> Pose | None:
    """A ``(Rotation, lever arm)`` pair as tuples, or already such tuples (a copy, a pickle)."""
    if value is None:
        return None
    if isinstance(value, tuple) and len(value) == 2 and isinstance(value[0], tuple):
        pose: Pose = value
    else:
        pose = sensor_pose(value)
    return pose


_SHAPES = {
    "delta_rotation": (3, 3),
    "delta_velocity": (3,),
    "delta_position": (3,),
    "delta_t": (),
    "covariance": (9, 9),
    "bias_jacobian": (9, 6),
    "covariance_combined": (15, 15),
    "t_start": (),
    "t_end": (),
    "t_start_ns": (),
    "t_end_ns": (),
}
_OPTIONAL = ("covariance_combined", "t_start_ns", "t_end_ns")


@dataclasses.dataclass(frozen=True, eq=False)
class Preintegration:
    """M preintegrated windows as arrays with a leading window dimension (module docs)."""

    delta_rotation: FloatArray
    """``ΔR_ij`` (M, 3, 3)."""
    delta_velocity: FloatArray
    """``Δv_ij`` (M, 3) [m/s], gravity-free, frame i."""
    delta_position: FloatArray
    """``Δp_ij`` (M, 3) [m], gravity-free, frame i."""
    delta_t: FloatArray
    """``Δt_ij`` (M,) [s]."""
    covariance: FloatArray
    """(M, 9, 9) covariance of ``[δθ, δv, δp]``."""
    bias_jacobian: FloatArray
    """(M, 9, 6) ``∂(θ, v, p)/∂(b_g, b_a)``."""
    covariance_combined: FloatArray | None
    """(M, 15, 15) covariance of ``[δθ, δv, δp, δb_g, δb_a]`` with the bias walk, or None."""
    t_start: FloatArray
    """(M,) window starts [s] on the samples' clock (NaN where unknown)."""
    t_end: FloatArray
    """(M,) window ends [s]."""
    params: PreintParams
    """The options the windows were preintegrated with."""
    t_start_ns: NDArray[np.int64] | None = None
    """(M,) exact window starts [ns] for nanosecond stamps, else None."""
    t_end_ns: NDArray[np.int64] | None = None
    """(M,) exact window ends [ns]."""

    def __post_init__(self) -> None:
        if not isinstance(self.params, PreintParams):
            raise ParameterError(
                f"expected an imukit.PreintParams, got {type(self.params).__name__}", argument="params"
            )
        m = np.shape(self.delta_t)[0] if np.ndim(self.delta_t) == 1 else -1
        for name, tail in _SHAPES.items():
            value = getattr(self, name)
            if value is None and name in _OPTIONAL:
                continue
            dtype = np.int64 if name.endswith("_ns") else np.float64
            array = np.array(value, dtype=dtype)  # a private copy: the record owns its arrays
            if m < 0 or array.shape != (m, *tail):
                raise ShapeError(f"expected shape {('M', *tail)} with M = {m}, got {array.shape}", argument=name)
            array.flags.writeable = False
            object.__setattr__(self, name, array)

    @classmethod
    def _owning(cls, **fields: Any) -> Preintegration:
        """A record that takes fresh arrays the caller built for it (an engine's output, a core
        snapshot) as they are: made read-only, neither copied nor checked."""
        out = object.__new__(cls)
        for f in dataclasses.fields(cls):
            value = fields.get(f.name)
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            object.__setattr__(out, f.name, value)
        return out

    def __len__(self) -> int:
        return int(self.delta_t.shape[0])

    def __getitem__(self, key: int | slice) -> Preintegration:
        if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
            m = len(self)
            k = int(key) + m if key < 0 else int(key)
            if not 0 <= k < m:
                raise IndexError(f"window {key} out of range for {m} windows")
            key = slice(k, k + 1)
        if not isinstance(key, slice):
            raise TypeError(f"Preintegration indices are ints or slices, not {type(key).__name__}")
        parts: dict[str, Any] = {name: _take(getattr(self, name), key) for name in _SHAPES}
        return dataclasses.replace(self, **parts)

    def __reduce__(self) -> tuple[Any, ...]:
        return (Preintegration, tuple(getattr(self, f.name) for f in dataclasses.fields(self)))

    def __repr__(self) -> str:
        return f"Preintegration(M={len(self)}, scheme={self.params.scheme!r}, combined={self.params.combined})"


def _take(value: NDArray[Any] | None, key: slice) -> NDArray[Any] | None:
    return None if value is None else value[key]
