"""Prediction and residual of a preintegrated window in a rotating navigation frame (the Earth's),
batched over M windows; :mod:`imukit._preint_math` calls these when ``omega_coriolis`` is given.

=====================  ===========================================================================
ω                      ``omega_coriolis`` (3,): the navigation frame's rotation rate relative to
                       inertial space, in navigation axes [rad/s] (GTSAM's ``omegaCoriolis``); a
                       local-level frame gives the Earth rate ``ω_ie`` (``docs/navigation.md``)
``"first"``            GTSAM 4.2's ``NavState::coriolis``: ``R_j = R_i Exp(Log ΔR − Δt R_iᵀω)``,
                       ``v_j = … − 2Δt ω×v_i``, ``p_j = … − Δt² ω×v_i``
``"second"``           also the centrifugal terms ``− Δt ω×(ω×p_i)`` (v) and ``− ½Δt² ω×(ω×p_i)`` (p)
``"exact"``            the closed form for constant ω and gravity fixed in the rotating frame:
                       ``A = Exp(−ωΔt)``, ``v̄ = v_i + ω×p_i``, ``R_j = A R_i ΔR``,
                       ``p_j = A (p_i + v̄Δt + R_i Δp + Δt² Γ₂(ωΔt) g)``,
                       ``v_j = A (v̄ + R_i Δv + Δt Γ₁(ωΔt) g) − ω×p_j``; equal to GTSAM 4.3's
                       ``NavState::predictPIM`` (Brossard et al.'s rotating-frame form)
residual               the deltas the two states imply under the same model, minus the measured
                       ones: ``[Log(ΔR̃ᵀ ΔR(x_i, x_j)), Δv(x_i, x_j) − Δṽ, Δp(x_i, x_j) − Δp̃]``, so the
                       noise enters exactly as without ω and the preintegration covariance is the
                       residual's (tested by Monte Carlo with Earth rotation)
=====================  ===========================================================================

Derivation of ``"exact"`` (ours): put an inertial frame on the navigation frame at time i, so the
navigation frame has turned by ``Exp(ω t)`` at ``t`` after i. The gyro measures the body's inertial
rate, so the preintegrated ``ΔR, Δv, Δp`` are the inertial increments written in the body frame at
i (Forster et al., T-RO 2017, eq. 33, with the inertial frame as world); inertial velocity is
``v̄ = v + ω×p`` rotated into the inertial frame; gravity ``g`` fixed in the rotating frame is
``Exp(ω t) g`` in the inertial one and integrates once to ``Δt Γ₁(ωΔt) g`` and twice to
``Δt² Γ₂(ωΔt) g`` with ``Γ_k(φ) = Σ_n [φ]×ⁿ / (n + k)!`` (``Γ₁ = J_l``; Barfoot, "State Estimation
for Robotics", 2017, §7.1.4; Brossard, Barrau, Chauchat & Bonnabel, "Associating uncertainty to
extended poses for on-Lie-group IMU preintegration with rotating Earth", T-RO 2022). Mapping back
by ``Exp(−ωΔt)`` gives the table. The first- and second-order forms are its expansion to first
order in ω (plus the centrifugal term), as in Titterton & Weston, "Strapdown Inertial Navigation
Technology", 2004, eq. 3.33 and Lupton & Sukkarieh, T-RO 2012.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from imukit import so3
from imukit._arrays import FloatArray, as_float_array, flag
from imukit._errors import NonFiniteError, ParameterError, ShapeError

__all__ = ["Coriolis", "apparent_j", "coriolis", "implied_deltas", "lift", "predict"]


class Coriolis(NamedTuple):
    """The rotating frame: ``omega`` (3,) [rad/s] and the model's ``order`` (module docs)."""

    omega: FloatArray
    order: str


def coriolis(omega_coriolis: ArrayLike | None, second_order: bool, exact: bool) -> Coriolis | None:
    """The model the keywords name, None without ``omega_coriolis``."""
    second_order, exact = flag(second_order, "second_order_coriolis"), flag(exact, "exact_coriolis")
    if omega_coriolis is None:
        if second_order or exact:
            raise ParameterError(
                "needs omega_coriolis", argument="second_order_coriolis" if second_order else "exact_coriolis"
            )
        return None
    if second_order and exact:
        raise ParameterError("expected one of second_order_coriolis and exact_coriolis", argument="exact_coriolis")
    w = as_float_array(omega_coriolis, "omega_coriolis")
    if w.shape != (3,):
        raise ShapeError(f"expected shape (3,), got {w.shape}", argument="omega_coriolis")
    if not np.isfinite(w).all():
        raise NonFiniteError("contains a NaN or infinite value", argument="omega_coriolis")
    return Coriolis(w, "exact" if exact else "second" if second_order else "first")


def _mv(m: FloatArray, v: FloatArray) -> FloatArray:
    out: FloatArray = (m @ v[..., None])[..., 0]
    return out


class _Exact(NamedTuple):
    """What ``"exact"`` needs from state i: ``A = Exp(−ωΔt)``, ``v̄``, and gravity integrated once
    and twice in the rotating frame."""

    a: FloatArray
    v_bar: FloatArray
    g_v: FloatArray
    g_p: FloatArray


def _exact(w: FloatArray, g: FloatArray, dt: FloatArray, p_i: FloatArray, v_i: FloatArray) -> _Exact:
    phi = w * dt
    g_v = _mv(so3.left_jacobian(phi), np.broadcast_to(g, phi.shape)) * dt
    g_p = _mv(so3.exp_double_integral(phi), np.broadcast_to(g, phi.shape)) * dt * dt
    return _Exact(so3.exp(-phi), v_i + np.cross(w, p_i), g_v, g_p)


def _apparent(c: Coriolis, dt: FloatArray, p_i: FloatArray, v_i: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The first/second-order Coriolis and centrifugal changes of ``(v, p)`` over the windows."""
    wv = np.cross(c.omega, v_i)
    dv, dp = -2.0 * dt * wv, -dt * dt * wv
    if c.order == "second":
        c2 = np.cross(c.omega, np.cross(c.omega, p_i))
        dv, dp = dv - dt * c2, dp - 0.5 * dt * dt * c2
    return dv, dp


def predict(
    c: Coriolis,
    deltas: tuple[FloatArray, FloatArray, FloatArray],
    g: FloatArray,
    dt: FloatArray,
    state_i: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(p_j, v_j, R_j)`` from state i and the (corrected) deltas; ``dt`` (M, 1)."""
    dr, dv, dp = deltas
    p_i, v_i, r_i = state_i
    if c.order == "exact":
        e = _exact(c.omega, g, dt, p_i, v_i)
        p_j = _mv(e.a, p_i + e.v_bar * dt + _mv(r_i, dp) + e.g_p)
        v_j = _mv(e.a, e.v_bar + _mv(r_i, dv) + e.g_v) - np.cross(c.omega, p_j)
        return p_j, v_j, e.a @ r_i @ dr
    cv, cp = _apparent(c, dt, p_i, v_i)
    tilt = _mv(np.swapaxes(r_i, -1, -2), c.omega * dt)
    return (
        p_i + v_i * dt + 0.5 * g * dt * dt + _mv(r_i, dp) + cp,
        v_i + g * dt + _mv(r_i, dv) + cv,
        r_i @ so3.exp(so3.log(dr) - tilt),
    )


def implied_deltas(
    c: Coriolis,
    g: FloatArray,
    dt: FloatArray,
    state_i: tuple[FloatArray, FloatArray, FloatArray],
    state_j: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(ΔR, Δv, Δp)`` that would carry state i to state j under the model (the inverse of
    :func:`predict` in the deltas)."""
    p_i, v_i, r_i = state_i
    p_j, v_j, r_j = state_j
    ri_t = np.swapaxes(r_i, -1, -2)
    if c.order == "exact":
        e = _exact(c.omega, g, dt, p_i, v_i)
        a_t = np.swapaxes(e.a, -1, -2)
        dv = _mv(ri_t, _mv(a_t, v_j + np.cross(c.omega, p_j)) - e.v_bar - e.g_v)
        dp = _mv(ri_t, _mv(a_t, p_j) - p_i - e.v_bar * dt - e.g_p)
        return ri_t @ a_t @ r_j, dv, dp
    cv, cp = _apparent(c, dt, p_i, v_i)
    dv = _mv(ri_t, v_j - v_i - g * dt - cv)
    dp = _mv(ri_t, p_j - p_i - v_i * dt - 0.5 * g * dt * dt - cp)
    dr = so3.exp(so3.log(ri_t @ r_j) + _mv(ri_t, c.omega * dt))
    return dr, dv, dp


Lifted = tuple[FloatArray, FloatArray, FloatArray]


def lift(
    c: Coriolis,
    g: FloatArray,
    dt: FloatArray,
    state_i: tuple[FloatArray, FloatArray, FloatArray],
    state_j: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[Lifted, Lifted, tuple[FloatArray, FloatArray], FloatArray, FloatArray]:
    """The states in the inertial frame that coincides with the navigation frame at i: i as
    ``(p_i, v_i + ω×p_i, R_i)``, j as ``(Aᵀp_j, Aᵀ(v_j + ω×p_j), AᵀR_j)``; the gravity terms
    ``(Δt Γ₁ g, Δt² Γ₂ g)``; and the Jacobians (M, 9, 9) of each lift, columns and rows
    ``[δp, δv, δθ]`` (``R Exp(δθ)`` lifts to ``AᵀR Exp(δθ)``): ``[[I, 0, 0], [[ω]×, I, 0], [0, 0, I]]``
    at i, ``[[Aᵀ, 0, 0], [Aᵀ[ω]×, Aᵀ, 0], [0, 0, I]]`` at j. In those states the exact residual is
    the inertial one with these gravity terms."""
    p_i, v_i, r_i = state_i
    p_j, v_j, r_j = state_j
    e = _exact(c.omega, g, dt, p_i, v_i)
    a_t = np.swapaxes(e.a, -1, -2)
    wx = so3.hat(c.omega)
    m = len(dt)
    l_i = np.broadcast_to(np.eye(9), (m, 9, 9)).copy()
    l_i[:, 3:6, 0:3] = wx
    l_j = np.broadcast_to(np.eye(9), (m, 9, 9)).copy()
    l_j[:, 0:3, 0:3] = a_t
    l_j[:, 3:6, 0:3] = a_t @ wx
    l_j[:, 3:6, 3:6] = a_t
    lifted_j = (_mv(a_t, p_j), _mv(a_t, v_j + np.cross(c.omega, p_j)), a_t @ r_j)
    return (p_i, e.v_bar, r_i), lifted_j, (e.g_v, e.g_p), l_i, l_j


def apparent_j(
    c: Coriolis,
    dt: FloatArray,
    state_i: tuple[FloatArray, FloatArray, FloatArray],
    state_j: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[Lifted, FloatArray, FloatArray]:
    """For ``"first"`` / ``"second"``: the state j' whose plain residual from i is this model's,
    ``p_j − c_p``, ``v_j − c_v`` (the Coriolis and centrifugal changes of :func:`predict`) and
    ``R_i Exp(φ)``, ``φ = Log(R_iᵀR_j) + R_iᵀωΔt``; and its Jacobians (M, 9, 9) w.r.t. state i and
    state j (columns and rows ``[δp, δv, δθ]``, ``R Exp(δθ)``). With ``X = R_iᵀR_j``:
    ``∂θ'/∂θ_j = J_r(φ) J_r⁻¹(Log X)``, ``∂θ'/∂θ_i = Exp(φ)ᵀ + J_r(φ)(−J_l⁻¹(Log X) + [R_iᵀωΔt]×)``
    (``R_i Exp(δθ)`` turns ``Log X`` by ``−J_l⁻¹ δθ`` and ``R_iᵀωΔt`` by ``[R_iᵀωΔt]× δθ``);
    ``∂v'/∂v_i = 2Δt[ω]×``, ``∂p'/∂v_i = Δt²[ω]×`` and, second order, ``∂v'/∂p_i = Δt[ω]×²``,
    ``∂p'/∂p_i = ½Δt²[ω]×²``."""
    p_i, v_i, r_i = state_i
    p_j, v_j, r_j = state_j
    cv, cp = _apparent(c, dt, p_i, v_i)
    ri_t = np.swapaxes(r_i, -1, -2)
    log_x = so3.log(ri_t @ r_j)
    tilt = _mv(ri_t, c.omega * dt)
    phi = log_x + tilt
    jr_phi = so3.right_jacobian(phi)
    m = len(dt)
    wx = np.broadcast_to(so3.hat(c.omega), (m, 3, 3))
    t1 = dt[:, :, None]
    l_i = np.zeros((m, 9, 9))
    l_i[:, 0:3, 3:6] = t1 * t1 * wx
    l_i[:, 3:6, 3:6] = 2.0 * t1 * wx
    if c.order == "second":
        l_i[:, 0:3, 0:3] = 0.5 * t1 * t1 * (wx @ wx)
        l_i[:, 3:6, 0:3] = t1 * (wx @ wx)
    l_i[:, 6:9, 6:9] = np.swapaxes(so3.exp(phi), -1, -2) + jr_phi @ (-so3.right_jacobian_inv(-log_x) + so3.hat(tilt))
    l_j = np.broadcast_to(np.eye(9), (m, 9, 9)).copy()
    l_j[:, 6:9, 6:9] = jr_phi @ so3.right_jacobian_inv(log_x)
    return (p_j - cp, v_j - cv, r_i @ so3.exp(phi)), l_i, l_j
