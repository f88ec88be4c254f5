"""Quaternion algebra, batched: Hamilton (default) and JPL products, product matrices, Ω(ω).

=====================  ===========================================================================
layout                 scalar-last ``[x, y, z, w]`` like scipy's ``Rotation.as_quat()``;
                       ``scalar_first=True`` for ``[w, x, y, z]`` (inputs and outputs alike)
product                Hamilton (``i j = k``) unless ``convention="jpl"`` (``i j = -k``)
meaning                active ``q_wb``: ``v_w = q_wb ⊗ [v_b, 0] ⊗ q_wb*``
4x4 matrices           ``q ⊗ p = L(q) p = R(p) q`` acting on the chosen layout
body rate              ``q̇ = ½ q ⊗ [ω, 0] = ½ Ω(ω) q``, ``Ω(ω) = R([ω, 0])``
=====================  ===========================================================================

``convention="jpl"`` exists for porting formulas written for JPL quaternions (Trawny &
Roumeliotis 2005; MSCKF, OpenVINS): ``q ⊗_J p = p ⊗_H q``, so ``L_J = R_H`` and ``R_J = L_H``.
For Ω the two conventions give the same matrix: the JPL quaternion of the world-to-body
rotation stores the same numbers as the Hamilton quaternion of ``R_wb``, and both obey
``q̇ = ½ Ω(ω) q`` with ``Ω(ω) = [[-[ω]×, ω], [-ωᵀ, 0]]`` (xyzw). See ``docs/conventions.md``.
Every function takes the keyword-only
``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from imukit import _core
from imukit._arrays import FloatArray, batched, matrix4_out, quat_out, to_xyzw
from imukit._names import canonical

__all__ = [
    "conjugate",
    "exp",
    "inverse",
    "left_matrix",
    "log",
    "multiply",
    "normalize",
    "omega_matrix",
    "right_matrix",
    "rotate",
]

_CONVENTIONS: tuple[str, ...] = _core.QUAT_CONVENTIONS


def multiply(
    q: ArrayLike, p: ArrayLike, *, scalar_first: bool = False, convention: str = "hamilton", threads: int | None = None
) -> FloatArray:
    """``q ⊗ p``; ``(..., 4)`` × ``(..., 4)`` → ``(..., 4)``. Not normalised."""
    convention = canonical(convention, "convention", _CONVENTIONS)
    q, p = to_xyzw(q, "q", scalar_first), to_xyzw(p, "p", scalar_first)
    out = batched(_core.quat_multiply, [(q, "q", (4,)), (p, "p", (4,))], (4,), convention, threads=threads)
    return quat_out(out, scalar_first)


def conjugate(q: ArrayLike, *, scalar_first: bool = False, threads: int | None = None) -> FloatArray:
    """``q* = [-x, -y, -z, w]``; ``(..., 4)`` → ``(..., 4)``."""
    out = batched(_core.quat_conjugate, [(to_xyzw(q, "q", scalar_first), "q", (4,))], (4,), threads=threads)
    return quat_out(out, scalar_first)


def inverse(q: ArrayLike, *, scalar_first: bool = False, threads: int | None = None) -> FloatArray:
    """``q⁻¹ = q* / |q|²``; raises :class:`imukit.InvalidQuaternionError` for a zero quaternion."""
    out = batched(_core.quat_inverse, [(to_xyzw(q, "q", scalar_first), "q", (4,))], (4,), threads=threads)
    return quat_out(out, scalar_first)


def normalize(q: ArrayLike, *, scalar_first: bool = False, threads: int | None = None) -> FloatArray:
    """``q / |q|``; raises :class:`imukit.InvalidQuaternionError` for a zero quaternion."""
    out = batched(_core.quat_normalize, [(to_xyzw(q, "q", scalar_first), "q", (4,))], (4,), threads=threads)
    return quat_out(out, scalar_first)


def rotate(q: ArrayLike, v: ArrayLike, *, scalar_first: bool = False, threads: int | None = None) -> FloatArray:
    """``q ⊗ [v, 0] ⊗ q*`` with q normalised first: ``(..., 4)``, ``(..., 3)`` → ``(..., 3)``."""
    q = to_xyzw(q, "q", scalar_first)
    return batched(_core.quat_rotate, [(q, "q", (4,)), (v, "v", (3,))], (3,), threads=threads)


def left_matrix(
    q: ArrayLike, *, scalar_first: bool = False, convention: str = "hamilton", threads: int | None = None
) -> FloatArray:
    """``L(q)`` with ``q ⊗ p = L(q) p``; ``(..., 4)`` → ``(..., 4, 4)`` in the chosen layout."""
    return _product_matrix(q, "left", scalar_first, convention, threads)


def right_matrix(
    p: ArrayLike, *, scalar_first: bool = False, convention: str = "hamilton", threads: int | None = None
) -> FloatArray:
    """``R(p)`` with ``q ⊗ p = R(p) q``; ``(..., 4)`` → ``(..., 4, 4)`` in the chosen layout."""
    return _product_matrix(p, "right", scalar_first, convention, threads)


def _product_matrix(q: ArrayLike, side: str, scalar_first: bool, convention: str, threads: int | None) -> FloatArray:
    convention = canonical(convention, "convention", _CONVENTIONS)
    name = "q" if side == "left" else "p"
    out = batched(
        _core.quat_product_matrix,
        [(to_xyzw(q, name, scalar_first), name, (4,))],
        (4, 4),
        side,
        convention,
        threads=threads,
    )
    return matrix4_out(out, scalar_first)


def omega_matrix(
    w: ArrayLike, *, convention: str = "hamilton", scalar_first: bool = False, threads: int | None = None
) -> FloatArray:
    """``Ω(ω)`` with ``q̇ = ½ Ω(ω) q`` for body rates ``w`` = ω [rad/s]: ``(..., 3)`` → ``(..., 4, 4)``.

    Hamilton: ``Ω(ω) = R([ω, 0])``, i.e. ``q̇ = ½ q ⊗ [ω, 0]`` for ``q = q_wb``. JPL: ``Ω(ω) =
    L_J([ω, 0])``, i.e. ``q̇ = ½ [ω, 0] ⊗_J q`` for the JPL quaternion of the world-to-body
    rotation. Both equal ``[[-[ω]×, ω], [-ωᵀ, 0]]`` in xyzw layout (VINS-Mono eq. 3, Trawny &
    Roumeliotis eq. 108); ``scalar_first=True`` re-expresses it for wxyz vectors.
    """
    convention = canonical(convention, "convention", _CONVENTIONS)
    out = batched(_core.quat_omega_matrix, [(w, "w", (3,))], (4, 4), convention, threads=threads)
    return matrix4_out(out, scalar_first)


def exp(phi: ArrayLike, *, scalar_first: bool = False, threads: int | None = None) -> FloatArray:
    """Unit quaternion ``[sin(θ/2) u, cos(θ/2)]`` of the rotation vector φ: ``(..., 3)`` → ``(..., 4)``."""
    return quat_out(batched(_core.quat_exp, [(phi, "phi", (3,))], (4,), threads=threads), scalar_first)


def log(q: ArrayLike, *, scalar_first: bool = False, threads: int | None = None) -> FloatArray:
    """Rotation vector (angle in [0, π]) of the normalised quaternion; ``q`` and ``-q`` agree."""
    return batched(_core.quat_log, [(to_xyzw(q, "q", scalar_first), "q", (4,))], (3,), threads=threads)
