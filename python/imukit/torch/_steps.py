"""Per-interval elements of preintegration and their compositions (torch, batched).

Every interval is an element of an SE₂(3)-like group, ``(ΔR, Δv, Δp, Δt)`` in the frame at its
start, and a window is their product (docs/preintegration.md, "merge"):
``(R₁, v₁, p₁, t₁) ∘ (R₂, v₂, p₂, t₂) = (R₁R₂, v₁ + R₁v₂, p₁ + v₁t₂ + R₁p₂, t₁ + t₂)``.

The error state follows ``x_{k+1} = F_k x_k + noise_k`` and the bias Jacobian ``J ← F J + G``, so the
pairs compose associatively as well:
``(F₁, Q₁, G₁) ∘ (F₂, Q₂, G₂) = (F₂F₁, F₂Q₁F₂ᵀ + Q₂, F₂G₁ + G₂)``. ``F``, ``G``, ``Q`` of interval k
depend on the rotation ``ΔR`` accumulated before it, so a first pass composes the deltas and a
second pass the linear maps; both are associative scans.

Schemes, as the Rust kernels (``crates/imukit/src/preint/``: ``mod.rs`` lie_euler, Forster et al.
T-RO 2017; ``midpoint.rs``, VINS-Mono with an exact rotation step):

- ``lie_euler``: sample k held over ``dt[k]``; ``A = [[Φ, 0, 0], [M h, I, 0], [½M h², h I, I]]``,
  ``Φ = Exp(ω̂h)ᵀ``, ``M = −ΔR[â]×``; noise input ``[[J_r h, 0], [0, ΔR h], [0, ½ΔR h²]]``, bias input
  its negative.
- ``midpoint``: interval k joins samples k − 1 and k (``dt[k]``, element 0 is the identity);
  ``M = −½(R₀[â₀]× + R₁[â₁]× Φ)``, ``K = ¼h R₁[â₁]× J_r``,
  ``B_s = [[−½hJ_r, 0], [hK, −½hR_s], [½h²K, −¼h²R_s]]``, bias input ``B₀ + B₁``. A sample's noise
  enters both intervals it bounds, so the state is augmented with the last sample's noise n:
  ``[δx; n] ← [[A, B₀], [0, 0]] [δx; n] + [B₁; I] n_new`` (15 × 15), the same exact correlation as
  the Rust kernel's ``Cov(δx, n_last)``.
"""

from __future__ import annotations

from typing import NamedTuple

import torch

from imukit.torch._so3 import exp_and_right_jacobian, hat

Elements = tuple[torch.Tensor, ...]


class Samples(NamedTuple):
    """Inputs with the sequence first: ``dt`` (N, *B), ``gyro``, ``accel`` (N, *B, 3), ``valid`` (N, *B)
    bool, ``bias`` (*B, 6) ``[b_g, b_a]``; the white noise as given: ``densities`` (*B, 2)
    ``[σ_g, σ_a]``, ``gyro_cov``, ``accel_cov`` (N, *B, 3, 3) per sample (each replaces its
    density), or None (``_inputs.noise_blocks`` makes each sample's 6×6 covariance of them)."""

    dt: torch.Tensor
    gyro: torch.Tensor
    accel: torch.Tensor
    valid: torch.Tensor
    bias: torch.Tensor
    densities: torch.Tensor | None = None
    gyro_cov: torch.Tensor | None = None
    accel_cov: torch.Tensor | None = None


class Interval(NamedTuple):
    """One interval's quantities, shared by its delta and its linearisation."""

    h: torch.Tensor
    step: torch.Tensor
    jr: torch.Tensor
    a0: torch.Tensor
    a1: torch.Tensor


def _mv(m: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    return (m @ v[..., None])[..., 0]


def _previous(x: torch.Tensor) -> torch.Tensor:
    return torch.cat((x[:1], x[:-1]))


def pairs_valid(valid: torch.Tensor) -> torch.Tensor:
    """Whether each midpoint interval counts: both its samples are in the window (interval 0,
    before the first sample, never)."""
    return torch.cat((torch.zeros_like(valid[:1]), valid[1:] & valid[:-1]))


def rates(s: Samples, scheme: str) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Each interval's step ``h`` (0 where masked), bias-corrected rate ``ω̂`` and specific forces
    at its two ends (the same one for lie_euler)."""
    bg, ba = s.bias[..., :3], s.bias[..., 3:]
    a1 = s.accel - ba
    if scheme == "midpoint":
        h = torch.where(pairs_valid(s.valid), s.dt, torch.zeros_like(s.dt))
        return h, 0.5 * (_previous(s.gyro) + s.gyro) - bg, _previous(a1), a1
    return torch.where(s.valid, s.dt, torch.zeros_like(s.dt)), s.gyro - bg, a1, a1


def intervals(s: Samples, scheme: str) -> Interval:
    """Each interval's step ``h`` (0 where masked), ``Exp(ω̂h)``, ``J_r(ω̂h)`` and the
    bias-corrected specific forces at its two ends (the same one for lie_euler)."""
    h, w, a0, a1 = rates(s, scheme)
    step, jr = exp_and_right_jacobian(w * h[..., None])
    return Interval(h, step, jr, a0, a1)


def deltas(iv: Interval, scheme: str) -> Elements:
    """The elements ``(ΔR, Δv, Δp, Δt)`` of every interval."""
    acc = 0.5 * (iv.a0 + _mv(iv.step, iv.a1)) if scheme == "midpoint" else iv.a0
    h = iv.h[..., None]
    return iv.step, acc * h, 0.5 * acc * h * h, iv.h


def compose_deltas(a: Elements, b: Elements) -> Elements:
    ra, va, pa, ta = a
    rb, vb, pb, tb = b
    return ra @ rb, va + _mv(ra, vb), pa + va * tb[..., None] + _mv(ra, pb), ta + tb


def compose_linear(a: Elements, b: Elements) -> Elements:
    """``(F, G)`` or ``(F, Q, G)`` pairs (module docs)."""
    fa, ga, fb, gb = a[0], a[-1], b[0], b[-1]
    if len(a) == 2:
        return fb @ fa, fb @ ga + gb
    return fb @ fa, fb @ a[1] @ fb.transpose(-1, -2) + b[1], fb @ ga + gb


def _blocks(rows: list[list[torch.Tensor | None]], like: torch.Tensor) -> torch.Tensor:
    zero = torch.zeros_like(like)
    return torch.cat([torch.cat([zero if b is None else b for b in row], dim=-1) for row in rows], dim=-2)


def _eye(like: torch.Tensor) -> torch.Tensor:
    return torch.eye(3, dtype=like.dtype, device=like.device).expand_as(like)


def linear(iv: Interval, before: torch.Tensor, cov: torch.Tensor | None, scheme: str) -> Elements:
    """``(F, Q, G)`` of every interval, given ``before``, the rotation accumulated before it, and
    ``cov`` (N, *B, 6, 6), each sample's noise covariance; without ``cov``, ``(A, G)`` (9 × 9: the
    bias Jacobian needs no augmentation)."""
    h = iv.h[..., None, None]
    phi, eye = iv.step.transpose(-1, -2), _eye(iv.step)
    if scheme == "midpoint":
        r1 = before @ iv.step
        r1a = r1 @ hat(iv.a1)
        m = -0.5 * (before @ hat(iv.a0) + r1a @ phi)
        k = 0.25 * h * r1a @ iv.jr

        def noise_input(r: torch.Tensor) -> torch.Tensor:
            return _blocks([[-0.5 * h * iv.jr, None], [h * k, -0.5 * h * r], [0.5 * h * h * k, -0.25 * h * h * r]], k)

        b0, b1 = noise_input(before), noise_input(r1)
        g = b0 + b1
    else:
        m = -before @ hat(iv.a0)
        b1 = _blocks([[h * iv.jr, None], [None, h * before], [None, 0.5 * h * h * before]], m)
        g = -b1
    a = _blocks([[phi, None, None], [h * m, eye, None], [0.5 * h * h * m, h * eye, eye]], m)
    if cov is None:
        return a, g
    b1s = b1 @ cov
    q = b1s @ b1.transpose(-1, -2)
    if scheme != "midpoint":
        return a, q, g
    # Augmented with the last sample's noise (module docs).
    lead = a.shape[:-2]
    f = torch.cat((torch.cat((a, b0), -1), a.new_zeros(*lead, 6, 15)), -2)
    q = torch.cat((torch.cat((q, b1s), -1), torch.cat((b1s.transpose(-1, -2), cov), -1)), -2)
    return f, q, torch.cat((g, g.new_zeros(*lead, 6, 6)), -2)


def rk2_steps(s: Samples) -> torch.Tensor:
    """Quaternions (N, *B, 4) of the explicit-midpoint steps on ``q̇ = ½ q ⊗ [ω, 0]`` as
    ``attitude.rs`` takes them: ``q_mid = q + ½h f(q, ω₀)``, ``q⁺ = q + h f(q_mid, ω̄)``,
    ``ω̄ = ½(ω₀ + ω₁)``, i.e. ``q⁺ = q ⊗ (1 + ½h[ω̄, 0] + ⅛h²[ω₀, 0] ⊗ [ω̄, 0])``, a right product
    by ``[½hω̄ + ⅛h² ω₀ × ω̄, 1 − ⅛h² ω₀·ω̄]``. Element 0 is the identity."""
    h = torch.where(pairs_valid(s.valid), s.dt, torch.zeros_like(s.dt))[..., None]
    w0 = _previous(s.gyro)
    w = 0.5 * (w0 + s.gyro)
    vector = 0.5 * h * w + h * h / 8 * torch.linalg.cross(w0, w)
    return torch.cat((vector, 1 - (w0 * w).sum(-1, keepdim=True) * h * h / 8), -1)
