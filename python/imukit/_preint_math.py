"""What a preintegration is used for, batched over its M windows: :func:`corrected`, :func:`predict`,
:func:`residual`, :func:`residual_jacobians`. The one implementation: ``PreintegratedImu``'s
methods call these with M = 1.

=====================  ===========================================================================
states                 arrays with the leading M: positions, velocities (M, 3), rotations ``R_wb``
                       (M, 3, 3); a bias (``ImuBias``) applies to every window
corrected              ``ΔR Exp(J_θ δb_g)``, ``Δv + J_v δb``, ``Δp + J_p δb``, ``δb`` the bias change
prediction             ``R_j = R_i ΔR``, ``v_j = v_i + g Δt + R_i Δv``,
                       ``p_j = p_i + v_i Δt + ½ g Δt² + R_i Δp``
rotating frame         ``omega_coriolis`` (3,) [rad/s] with ``second_order_coriolis`` or
                       ``exact_coriolis``: :mod:`imukit._preint_earth` (``predict``, ``residual``)
residual (M, 9)        ``[Log(ΔR̃ᵀ R_iᵀ R_j), R_iᵀ(v_j − v_i − g Δt) − Δṽ, R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp̃]``
Jacobians              rows ``[θ, v, p]``; state columns ``[δp, δv, δθ]`` (``R Exp(δθ)``), bias
                       columns ``[δb_g, δb_a]`` (Forster et al. 2017, eqs. 44–45)
=====================  ===========================================================================

Written with array operations only (matmul, broadcasting, ``swapaxes``) plus the SO(3) maps of
:mod:`imukit.so3` (``exp``, ``log``, ``hat``, right Jacobians), so that another engine (torch)
reuses the formulas by supplying those four maps for its arrays.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from imukit import _preint_earth, so3
from imukit._arrays import FloatArray
from imukit._errors import NonFiniteError, ParameterError
from imukit._preint_record import Preintegration
from imukit.imu import ImuBias

__all__ = ["Deltas", "ResidualJacobians", "States", "corrected", "predict", "residual", "residual_jacobians"]


class ResidualJacobians(NamedTuple):
    """Jacobians of :func:`residual`, rows ``[θ, v, p]`` (a leading M in the batched functions)."""

    state_i: FloatArray
    """9×9, columns ``[δp_i, δv_i, δθ_i]``."""
    state_j: FloatArray
    """9×9, columns ``[δp_j, δv_j, δθ_j]``."""
    bias: FloatArray
    """9×6, columns ``[δb_g, δb_a]``."""


class States(NamedTuple):
    """M navigation states as arrays: ``position``, ``velocity`` (M, 3), ``rotation`` R_wb (M, 3, 3)."""

    position: FloatArray
    velocity: FloatArray
    rotation: FloatArray


class Deltas(NamedTuple):
    """``ΔR`` (M, 3, 3), ``Δv``, ``Δp`` (M, 3), possibly corrected to another bias."""

    rotation: FloatArray
    velocity: FloatArray
    position: FloatArray


def _t(m: FloatArray) -> FloatArray:
    return np.swapaxes(m, -1, -2)


def _mv(m: FloatArray, v: FloatArray) -> FloatArray:
    out: FloatArray = (m @ v[..., None])[..., 0]
    return out


def bias_change(pre: Preintegration, bias: ImuBias) -> FloatArray:
    """``δb = bias − integration bias`` (6,), ``[δb_g, δb_a]``."""
    if not isinstance(bias, ImuBias):
        raise ParameterError(f"expected an imukit.ImuBias, got {type(bias).__name__}", argument="bias")
    b = pre.params.bias
    return np.concatenate([bias.gyro - b.gyro, bias.accel - b.accel])


def corrected(pre: Preintegration, bias: ImuBias | None = None) -> Deltas:
    """The deltas for ``bias`` to first order, without re-integration (module docs); the deltas as
    integrated without ``bias``."""
    if bias is None:
        return Deltas(pre.delta_rotation, pre.delta_velocity, pre.delta_position)
    d = pre.bias_jacobian @ bias_change(pre, bias)
    if not (np.isfinite(d).all() and np.isfinite(np.linalg.norm(d, axis=-1)).all()):
        raise NonFiniteError(f"too far from the integration bias to correct for: J δb = {d.tolist()}", argument="bias")
    return Deltas(
        pre.delta_rotation @ so3.exp(d[:, 0:3]), pre.delta_velocity + d[:, 3:6], pre.delta_position + d[:, 6:9]
    )


def _finite(arrays: tuple[FloatArray, ...], argument: str, what: str) -> None:
    """Finite states at extreme finite values (±1e308) overflow these sums: refused naming the
    argument (``NonFiniteError``), never returned as inf or passed on as NaN."""
    if not all(np.isfinite(a).all() for a in arrays):
        raise NonFiniteError(f"too large in magnitude: {what} overflows float64", argument=argument)


def predict(
    pre: Preintegration,
    state_i: States,
    bias: ImuBias | None = None,
    *,
    omega_coriolis: ArrayLike | None = None,
    second_order_coriolis: bool = False,
    exact_coriolis: bool = False,
) -> States:
    """The states at the windows' ends from those at their starts (module docs); in a frame rotating
    at ``omega_coriolis`` [rad/s] with the model the flags name (:mod:`imukit._preint_earth`)."""
    rotating = _preint_earth.coriolis(omega_coriolis, second_order_coriolis, exact_coriolis)
    deltas = corrected(pre, bias)
    dr, dv, dp = deltas
    g, dt = np.asarray(pre.params.gravity), pre.delta_t[:, None]
    p_i, v_i, r_i = state_i
    with np.errstate(over="ignore", invalid="ignore"):
        if rotating is not None:
            out = States(*_preint_earth.predict(rotating, deltas, g, dt, state_i))
        else:
            out = States(
                p_i + v_i * dt + 0.5 * g * dt * dt + _mv(r_i, dp),
                v_i + g * dt + _mv(r_i, dv),
                r_i @ dr,
            )
    _finite(out, "state_i", "the predicted state p_i + v_i Δt + ½ g Δt² + R_i Δp")
    return out


class _Parts(NamedTuple):
    r: FloatArray
    u_v: FloatArray
    u_p: FloatArray
    e: FloatArray


def _parts(
    pre: Preintegration,
    state_i: States,
    state_j: States,
    bias: ImuBias | None,
    gravity_terms: tuple[FloatArray, FloatArray] | None = None,
) -> _Parts:
    """The residual and the world-frame differences it rotates; ``gravity_terms`` are gravity
    integrated once and twice over the windows (default ``g Δt``, ``½ g Δt²``)."""
    dr, dv, dp = corrected(pre, bias)
    g, dt = np.asarray(pre.params.gravity), pre.delta_t[:, None]
    p_i, v_i, r_i = state_i
    p_j, v_j, r_j = state_j
    with np.errstate(over="ignore", invalid="ignore"):
        g_v, g_p = (g * dt, 0.5 * g * dt * dt) if gravity_terms is None else gravity_terms
        u_v = v_j - v_i - g_v
        u_p = p_j - p_i - v_i * dt - g_p
        ri_t = _t(r_i)
        e = _t(dr) @ ri_t @ r_j
        r_v, r_p = _mv(ri_t, u_v) - dv, _mv(ri_t, u_p) - dp
    # Before so3.log and the Jacobians, which would name their own internal argument ("phi").
    _finite((u_v, u_p, r_v, r_p), "state_j", "its difference from state_i (p_j − p_i − v_i Δt, v_j − v_i)")
    r = np.concatenate([so3.log(e), r_v, r_p], axis=-1)
    return _Parts(r, u_v, u_p, e)


def residual(
    pre: Preintegration,
    state_i: States,
    state_j: States,
    bias: ImuBias | None = None,
    *,
    omega_coriolis: ArrayLike | None = None,
    second_order_coriolis: bool = False,
    exact_coriolis: bool = False,
) -> FloatArray:
    """The residuals (M, 9) of the windows between ``state_i`` and ``state_j`` (module docs); in a
    rotating frame, the deltas the states imply under that model minus the measured ones
    (:mod:`imukit._preint_earth`), whose covariance is the preintegration's."""
    rotating = _preint_earth.coriolis(omega_coriolis, second_order_coriolis, exact_coriolis)
    if rotating is None:
        return _parts(pre, state_i, state_j, bias).r
    dr, dv, dp = corrected(pre, bias)
    g, dt = np.asarray(pre.params.gravity), pre.delta_t[:, None]
    with np.errstate(over="ignore", invalid="ignore"):
        er, ev, ep = _preint_earth.implied_deltas(rotating, g, dt, state_i, state_j)
        r_v, r_p = ev - dv, ep - dp
    _finite((er, r_v, r_p), "state_j", "its difference from state_i in the rotating frame")
    return np.concatenate([so3.log(_t(dr) @ er), r_v, r_p], axis=-1)


def residual_jacobians(
    pre: Preintegration,
    state_i: States,
    state_j: States,
    bias: ImuBias | None = None,
    *,
    omega_coriolis: ArrayLike | None = None,
    second_order_coriolis: bool = False,
    exact_coriolis: bool = False,
) -> ResidualJacobians:
    """Jacobians of :func:`residual` w.r.t. the states at i and j (M, 9, 9) and the bias (M, 9, 6),
    the bias through the first-order correction. With ``omega_coriolis``: ``exact_coriolis=True``,
    the exact residual is the plain one between the states lifted to the inertial frame at i
    (:func:`imukit._preint_earth.lift`), so these are the plain Jacobians times the lift's; first
    and second order, the residual is the plain one from state i to a state j' built from both
    (:func:`imukit._preint_earth.apparent_j`), so state i's Jacobian gains ``D_j ∂j'/∂i``."""
    rotating = _preint_earth.coriolis(omega_coriolis, second_order_coriolis, exact_coriolis)
    if rotating is None:
        return _jacobians(pre, state_i, state_j, bias)
    dt = pre.delta_t[:, None]
    if rotating.order != "exact":
        moved, a_i, a_j = _preint_earth.apparent_j(rotating, dt, state_i, state_j)
        d_i, d_j, d_b = _jacobians(pre, state_i, States(*moved), bias)
        return ResidualJacobians(d_i + d_j @ a_i, d_j @ a_j, d_b)
    g = np.asarray(pre.params.gravity)
    lifted_i, lifted_j, terms, l_i, l_j = _preint_earth.lift(rotating, g, dt, state_i, state_j)
    d_i, d_j, d_b = _jacobians(pre, States(*lifted_i), States(*lifted_j), bias, terms)
    return ResidualJacobians(d_i @ l_i, d_j @ l_j, d_b)


def _jacobians(
    pre: Preintegration,
    state_i: States,
    state_j: States,
    bias: ImuBias | None,
    gravity_terms: tuple[FloatArray, FloatArray] | None = None,
) -> ResidualJacobians:
    r, u_v, u_p, e = _parts(pre, state_i, state_j, bias, gravity_terms)
    jac = pre.bias_jacobian
    m = len(pre)
    r_i, r_j = state_i.rotation, state_j.rotation
    ri_t = _t(r_i)
    jr_inv = so3.right_jacobian_inv(r[:, 0:3])
    dbg = np.zeros(3) if bias is None else bias_change(pre, bias)[0:3]
    d_i, d_j, d_b = np.zeros((m, 9, 9)), np.zeros((m, 9, 9)), np.zeros((m, 9, 6))
    # θ: E Exp(δθ_j) on the right; R_i Exp(δθ_i) enters as E Exp(−R_jᵀ R_i δθ_i).
    d_i[:, 0:3, 6:9] = -jr_inv @ _t(r_j) @ r_i
    d_j[:, 0:3, 6:9] = jr_inv
    j_theta = jac[:, 0:3, 0:3]
    d_b[:, 0:3, 0:3] = -jr_inv @ _t(e) @ so3.right_jacobian(_mv(j_theta, np.broadcast_to(dbg, (m, 3)))) @ j_theta
    # v, p: R_iᵀ u with R_i Exp(δθ_i) gives +[R_iᵀ u]× δθ_i.
    d_i[:, 3:6, 3:6], d_i[:, 3:6, 6:9] = -ri_t, so3.hat(_mv(ri_t, u_v))
    d_j[:, 3:6, 3:6] = ri_t
    d_i[:, 6:9, 0:3] = -ri_t
    d_i[:, 6:9, 3:6] = -ri_t * pre.delta_t[:, None, None]
    d_i[:, 6:9, 6:9] = so3.hat(_mv(ri_t, u_p))
    d_j[:, 6:9, 0:3] = ri_t
    d_b[:, 3:9] = -jac[:, 3:9]
    return ResidualJacobians(d_i, d_j, d_b)
