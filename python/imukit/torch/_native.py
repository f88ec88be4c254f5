"""The CPU path of ``imukit.torch``: the Rust kernels (``crates/imukit/src/adjoint``) forward and
their analytic reverse sweep as the backward of one ``torch.autograd.Function``.

The kernels read float64 C-contiguous buffers in place (``Tensor.numpy()`` views, no copy): a
contiguous float64 CPU input reaches Rust as is; broadcast, strided or float32 inputs are first
made contiguous float64 by torch (float32 is widened, and the outputs narrowed back: the kernels
compute in float64). What differs per scheme is prepared here in torch, where autograd carries it:
bias subtraction, masking (a step of 0), the midpoint rate ``½(ω₀ + ω₁)``; the kernels see each
interval's ``h``, ``ω̂``, specific forces and the noise: the variance densities ``σ²`` per window
when the noise is densities only (the kernels discretise them, ``σ²/h``, and return their
cotangents: nothing per sample is built in torch), else each sample's covariance blocks
(``_inputs.noise_blocks``: per-sample ``gyro_cov`` / ``accel_cov``) (module docs of ``adjoint``).

Covered: every output of both schemes (deltas, covariance, bias Jacobian, per step or final);
``integrate_attitude``'s ``exp`` scheme is the euler rotation (``rk2`` has no kernel).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from imukit import _core
from imukit.torch._inputs import noise_blocks
from imukit.torch._steps import Samples, rates


def supported(x: torch.Tensor) -> bool:
    """Whether the kernels cover this call: CPU tensors."""
    return x.device.type == "cpu"


_Array = np.ndarray[Any, np.dtype[np.float64]]


def _buffer(x: torch.Tensor) -> _Array:
    return x.detach().contiguous().numpy()


def _buffers(inputs: tuple[Any, ...]) -> tuple[_Array, _Array, _Array, dict[str, Any]]:
    """``h, w, a`` and the optional buffers by keyword, as the kernels take them."""
    h, w, a, a_end, cov_g, cov_a, q = inputs
    optional = {"a_end": a_end, "gyro_cov": cov_g, "accel_cov": cov_a, "noise_density": q}
    return _buffer(h), _buffer(w), _buffer(a), {k: None if x is None else _buffer(x) for k, x in optional.items()}


class _Kernel(torch.autograd.Function):
    """``records = forward(h, w, a, a_end, Σ_g, Σ_a, σ²)`` (B, S, width); the backward is the Rust
    reverse sweep. Not twice differentiable."""

    @staticmethod
    def forward(ctx: Any, options: dict[str, Any], *inputs: torch.Tensor | None) -> torch.Tensor:
        h, w, a, optional = _buffers(inputs)
        out = _core.preint_adjoint(h, w, a, bar=None, **optional, **options)
        ctx.save_for_backward(*inputs)
        ctx.options = options
        return torch.from_numpy(out)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx: Any, bar: torch.Tensor) -> tuple[torch.Tensor | None, ...]:
        inputs = ctx.saved_tensors
        h, w, a, optional = _buffers(inputs)
        bar_buffer = bar.contiguous().numpy()
        g = torch.from_numpy(_core.preint_adjoint(h, w, a, bar=bar_buffer, **optional, **ctx.options))
        widths = [1, 3, 3, 3, 9, 9, 2]
        parts = iter(torch.split(g, [k for k, x in zip(widths, inputs) if x is not None], dim=-1))
        grads = [None if x is None else next(parts) for x in inputs]
        q = grads[-1]
        if q is not None:
            grads[-1] = q.sum(1)  # each interval's share of its window's densities
        return (None, *(None if gx is None else gx.reshape(x.shape) for x, gx in zip(inputs, grads)))


def preintegrate(
    s: Samples, batch: torch.Size, scheme: str, *, per_step: bool, covariance: bool, jacobian: bool
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor | None, torch.Tensor | None]:
    """``(ΔR, Δv, Δp, Δt, P or None, J or None)`` of every window, laid out (*B, [N,] ...)."""
    n, first = s.dt.shape[0], len(batch)
    h, w, a0, a1 = rates(s, scheme)

    def windows(x: torch.Tensor) -> torch.Tensor:
        """Sequence-first (N, *B, ...) to (B, N, ...) float64."""
        return x.movedim(0, first).reshape(-1, n, *x.shape[first + 1 :]).to(torch.float64)

    cov_g = cov_a = q = None
    if covariance and s.densities is not None and s.gyro_cov is None and s.accel_cov is None:
        q = (s.densities**2).reshape(-1, 2).to(torch.float64)
    elif covariance:
        cov = noise_blocks(s, scheme)
        if cov is not None:
            cov_g, cov_a = windows(cov[..., :3, :3]), windows(cov[..., 3:, 3:])
    a_end = windows(a1) if scheme == "midpoint" else None
    options = {"per_step": per_step, "covariance": covariance, "jacobian": jacobian}
    records = _Kernel.apply(options, windows(h), windows(w), windows(a0), a_end, cov_g, cov_a, q)
    records = records.to(s.dt.dtype).reshape(*batch, *((n,) if per_step else ()), -1)
    lead = records.shape[:-1]
    rot, vel, pos = records[..., :9].reshape(*lead, 3, 3), records[..., 9:12], records[..., 12:15]
    at = 15
    cov = jac = None
    if covariance:
        cov, at = records[..., at : at + 81].reshape(*lead, 9, 9), at + 81
    if jacobian:
        jac = records[..., at : at + 54].reshape(*lead, 9, 6)
    t = h.movedim(0, first)
    t = t.cumsum(-1) if per_step else t.sum(-1)
    return rot, vel, pos, t, cov, jac
