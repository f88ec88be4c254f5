"""Intrinsic ZYX Euler angles ``[yaw, pitch, roll]`` and the rate map E(χ), batched.

=====================  ===========================================================================
angles                 ``χ = [ψ, θ, φ] = [yaw, pitch, roll]``, shape ``(..., 3)``, radians unless
                       ``degrees=True``; same order as scipy's ``as_euler("ZYX")``
rotation               intrinsic z-y'-x'': ``R_wb = Rz(ψ) Ry(θ) Rx(φ)``
ranges                 :func:`from_rotation` gives ψ, φ ∈ (-π, π], θ ∈ [-π/2, π/2]
rate map               ``χ̇ = E(χ) ω_b`` for body rates ω_b (``Ṙ = R [ω_b]×``)
singularity            |θ| within ``tolerance_rad`` of π/2 raises :class:`imukit.GimbalLockError`
=====================  ===========================================================================

Every function takes the keyword-only
``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import FloatArray, as_float_array, batched, flag, real_scalar

__all__ = ["from_rotation", "rate_matrix", "rate_matrix_inv", "to_rotation"]


def _radians(angles: ArrayLike, degrees: bool) -> ArrayLike:
    return np.deg2rad(as_float_array(angles, "angles")) if flag(degrees, "degrees") else angles


def to_rotation(angles: ArrayLike, *, degrees: bool = False, threads: int | None = None) -> Rotation:
    """``Rotation`` of ``R = Rz(yaw) Ry(pitch) Rx(roll)``; ``(3,)`` gives a single rotation."""
    return Rotation.from_matrix(
        batched(_core.euler_to_matrix, [(_radians(angles, degrees), "angles", (3,))], (3, 3), threads=threads)
    )


def from_rotation(rotation: Rotation | ArrayLike, *, degrees: bool = False, threads: int | None = None) -> FloatArray:
    """``[yaw, pitch, roll]`` of a ``Rotation`` or of ``(..., 3, 3)`` matrices.

    ``to_rotation`` of the result reproduces the rotation to rounding, except where cos(pitch) < 1e-12:
    there roll is reported as 0 and the whole rotation about the vertical as yaw (only yaw ∓ roll is
    observable), which moves the rotation by at most 2e-12.
    """
    matrices = rotation.as_matrix() if isinstance(rotation, Rotation) else rotation
    angles = batched(_core.euler_from_matrix, [(matrices, "rotation", (3, 3))], (3,), threads=threads)
    return np.rad2deg(angles) if flag(degrees, "degrees") else angles


def rate_matrix(
    angles: ArrayLike, *, degrees: bool = False, tolerance_rad: float = 1e-6, threads: int | None = None
) -> FloatArray:
    """``E(χ)`` with ``χ̇ = E(χ) ω_b``: ``(..., 3)`` → ``(..., 3, 3)``.

    ``E = [[0, sφ/cθ, cφ/cθ], [0, cφ, -sφ], [1, sφ tθ, cφ tθ]]``. Raises
    :class:`imukit.GimbalLockError` (naming the element) when |pitch| is within ``tolerance_rad``
    radians of 90°. With ``degrees=True`` only the input angles are in degrees; E is unitless.
    """
    tolerance = real_scalar(
        tolerance_rad,
        "tolerance_rad",
        what="a finite, non-negative angle in radians below π/2",
        accept=lambda x: 0.0 <= x < np.pi / 2,
    )
    return batched(
        _core.euler_rate_matrix, [(_radians(angles, degrees), "angles", (3,))], (3, 3), tolerance, threads=threads
    )


def rate_matrix_inv(angles: ArrayLike, *, degrees: bool = False, threads: int | None = None) -> FloatArray:
    """``E⁻¹(χ)`` with ``ω_b = E⁻¹(χ) χ̇`` (defined everywhere): ``(..., 3)`` → ``(..., 3, 3)``."""
    return batched(_core.euler_rate_matrix_inv, [(_radians(angles, degrees), "angles", (3,))], (3, 3), threads=threads)
