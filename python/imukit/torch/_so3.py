"""SO(3) in torch, batched over leading dimensions: ``hat``, ``exp_and_right_jacobian``.

``Exp(φ) = I + A [φ]× + B [φ]×²`` and ``J_r(φ) = I − B [φ]× + C [φ]×²`` with ``θ = |φ|``,
``A = sin θ/θ``, ``B = (1 − cos θ)/θ²``, ``C = (θ − sin θ)/θ³`` (Solà, Deray & Atchuthan 2018,
eqs. 143 and 183; imukit's right Jacobian, ``docs/so3.md``). Below ``θ² = 10⁻³`` the coefficients
come from their Taylor series to θ⁶, whose truncation error (θ⁸/9!, < 10⁻¹⁷) is below float64
rounding; the closed forms are evaluated on a substituted θ there, so that no branch produces a
NaN gradient at φ = 0 (a masked sample is a zero rotation).
"""

from __future__ import annotations

import torch

_SERIES_BELOW = 1e-3


def hat(v: torch.Tensor) -> torch.Tensor:
    """``[v]×`` of ``v`` (..., 3) as (..., 3, 3)."""
    x, y, z = v.unbind(-1)
    zero = torch.zeros_like(x)
    rows = (zero, -z, y, z, zero, -x, -y, x, zero)
    return torch.stack(rows, dim=-1).reshape(*v.shape[:-1], 3, 3)


def _coefficients(t2: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    small = t2 < _SERIES_BELOW
    safe = torch.where(small, torch.ones_like(t2), t2)
    t = safe.sqrt()
    s, c = torch.sin(t), torch.cos(t)
    a_closed, b_closed, c_closed = s / t, (1 - c) / safe, (t - s) / (safe * t)
    a_series = 1 - t2 / 6 * (1 - t2 / 20 * (1 - t2 / 42))
    b_series = 0.5 - t2 / 24 * (1 - t2 / 30 * (1 - t2 / 56))
    c_series = 1 / 6 - t2 / 120 * (1 - t2 / 42 * (1 - t2 / 72))
    return (
        torch.where(small, a_series, a_closed),
        torch.where(small, b_series, b_closed),
        torch.where(small, c_series, c_closed),
    )


def exp_and_right_jacobian(phi: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """``Exp(φ)`` and ``J_r(φ)`` for ``φ`` (..., 3), each (..., 3, 3)."""
    k = hat(phi)
    k2 = k @ k
    a, b, c = (x[..., None, None] for x in _coefficients((phi * phi).sum(-1)))
    eye = torch.eye(3, dtype=phi.dtype, device=phi.device)
    return eye + a * k + b * k2, eye - b * k + c * k2


def quat_multiply(p: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
    """Hamilton product ``p ⊗ q`` of (..., 4) quaternions stored ``[x, y, z, w]``."""
    pv, pw, qv, qw = p[..., :3], p[..., 3:], q[..., :3], q[..., 3:]
    return torch.cat((pw * qv + qw * pv + torch.linalg.cross(pv, qv), pw * qw - (pv * qv).sum(-1, keepdim=True)), -1)


def quat_to_matrix(q: torch.Tensor) -> torch.Tensor:
    """The rotation matrix (..., 3, 3) of unit quaternions (..., 4) ``[x, y, z, w]``."""
    v, w = q[..., :3], q[..., 3:]
    eye = torch.eye(3, dtype=q.dtype, device=q.device)
    k = hat(v)
    return eye + 2 * w[..., None] * k + 2 * k @ k
