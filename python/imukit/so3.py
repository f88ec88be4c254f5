"""SO(3): hat/vee, exp/log and the Jacobians of the exponential map, batched.

=====================  ===========================================================================
group element          3x3 rotation matrix ``R_wb`` (active: ``v_w = R_wb @ v_b``), shape ``(..., 3, 3)``
tangent                rotation vector ``φ = θ u`` in radians, shape ``(..., 3)``; :func:`log` gives θ ∈ [0, π]
perturbation           right (local): ``R Exp(δ)``; the ``left_`` functions are for ``Exp(δ) R``
body rate              ``Ṙ = R [ω]×``; ``R(t) = R(t0) Exp(ω (t - t0))`` for constant ω
=====================  ===========================================================================

Jacobians, named by the first-order identity they satisfy::

    right_jacobian(φ)      Exp(φ + δ) ≈ Exp(φ) Exp(J_r(φ) δ)
    right_jacobian_inv(φ)  Log(Exp(φ) Exp(δ)) ≈ φ + J_r⁻¹(φ) δ
    left_jacobian(φ)       Exp(φ + δ) ≈ Exp(J_l(φ) δ) Exp(φ)        J_l(φ) = J_r(-φ)
    left_jacobian_inv(φ)   Log(Exp(δ) Exp(φ)) ≈ φ + J_l⁻¹(φ) δ

The inverses are singular at θ = 2πk (k ≠ 0). All functions take any array-like whose last
dimension(s) match, broadcast over leading dimensions and return float64 arrays. See
``docs/conventions.md``. Every function takes the keyword-only
``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.
"""

from __future__ import annotations

from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import FloatArray, batched

__all__ = [
    "exp",
    "exp_double_integral",
    "hat",
    "left_jacobian",
    "left_jacobian_inv",
    "log",
    "right_jacobian",
    "right_jacobian_inv",
    "vee",
]


def hat(phi: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``[φ]×``, the skew matrix with ``[φ]× v = φ × v``: ``(..., 3)`` → ``(..., 3, 3)``."""
    return batched(_core.so3_hat, [(phi, "phi", (3,))], (3, 3), threads=threads)


def vee(matrix: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """Inverse of :func:`hat`: ``(..., 3, 3)`` → ``(..., 3)``.

    For a matrix that is not exactly skew, returns the vector of its skew part ``(M - Mᵀ)/2``
    (the nearest element of so(3)).
    """
    return batched(_core.so3_vee, [(matrix, "matrix", (3, 3))], (3,), threads=threads)


def exp(phi: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``Exp(φ)``, Rodrigues' formula, exact to rounding near θ = 0: ``(..., 3)`` → ``(..., 3, 3)``.

    For a scipy ``Rotation`` instead of matrices use ``Rotation.from_rotvec``; this returns the
    matrices that the Jacobian formulas consume.
    """
    return batched(_core.so3_exp, [(phi, "phi", (3,))], (3, 3), threads=threads)


def log(rotation: Rotation | ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``Log(R)``: rotation vectors with angle in [0, π], ``(..., 3, 3)`` or ``Rotation`` → ``(..., 3)``.

    Accurate at the identity and at π. Matrices must be orthonormal with det +1 to 1e-6
    (:class:`imukit.InvalidRotationError` otherwise). At exactly π both ``φ`` and ``-φ`` are the
    logarithm; either may be returned.
    """
    matrices = rotation.as_matrix() if isinstance(rotation, Rotation) else rotation
    return batched(_core.so3_log, [(matrices, "rotation", (3, 3))], (3,), threads=threads)


def exp_double_integral(phi: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``Γ₂(φ) = ∫₀¹ (1 − s) Exp(s φ) ds = Σ_n [φ]×ⁿ / (n + 2)!``; ``(..., 3)`` → ``(..., 3, 3)``.
    With ``left_jacobian`` (``Γ₁``) it integrates a constant rotation rate twice (``docs/so3.md``)."""
    return batched(_core.so3_exp_double_integral, [(phi, "phi", (3,))], (3, 3), threads=threads)


def right_jacobian(phi: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``J_r(φ)``: ``Exp(φ + δ) ≈ Exp(φ) Exp(J_r(φ) δ)``; ``(..., 3)`` → ``(..., 3, 3)``."""
    return batched(_core.so3_jacobian, [(phi, "phi", (3,))], (3, 3), "right", threads=threads)


def right_jacobian_inv(phi: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``J_r⁻¹(φ)``: ``Log(Exp(φ) Exp(δ)) ≈ φ + J_r⁻¹(φ) δ``; ``(..., 3)`` → ``(..., 3, 3)``."""
    return batched(_core.so3_jacobian, [(phi, "phi", (3,))], (3, 3), "right_inv", threads=threads)


def left_jacobian(phi: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``J_l(φ) = J_r(-φ)``: ``Exp(φ + δ) ≈ Exp(J_l(φ) δ) Exp(φ)``; ``(..., 3)`` → ``(..., 3, 3)``."""
    return batched(_core.so3_jacobian, [(phi, "phi", (3,))], (3, 3), "left", threads=threads)


def left_jacobian_inv(phi: ArrayLike, *, threads: int | None = None) -> FloatArray:
    """``J_l⁻¹(φ)``: ``Log(Exp(δ) Exp(φ)) ≈ φ + J_l⁻¹(φ) δ``; ``(..., 3)`` → ``(..., 3, 3)``."""
    return batched(_core.so3_jacobian, [(phi, "phi", (3,))], (3, 3), "left_inv", threads=threads)
