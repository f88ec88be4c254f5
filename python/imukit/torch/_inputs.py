"""Python-side checks and layout of ``imukit.torch`` inputs: tensor types, dtypes and shapes
(rule 2 of the house: values are not inspected), broadcasting of the batch dimensions, and the
move of the sequence dimension to the front for the scans.
"""

from __future__ import annotations

from typing import Any

import torch

from imukit._errors import DTypeError, ParameterError, ShapeError
from imukit._names import canonical
from imukit.imu import ImuNoise
from imukit.torch._steps import Samples, rates

_FLOATS = (torch.float32, torch.float64)


def choice(value: object, argument: str, names: tuple[str, ...]) -> str:
    """One of ``names`` (deprecated aliases of the core accepted, with their warning): there is no
    core call here to refuse an unknown name."""
    name = canonical(value, argument, names, {"euler": "lie_euler"} if "lie_euler" in names else None)
    if name not in names:
        raise ParameterError(f"expected one of {names}, got {value!r}", argument=argument)
    return name


def vectors(x: Any, name: str) -> torch.Tensor:
    """A float32/float64 tensor of shape (..., N, 3)."""
    if not isinstance(x, torch.Tensor):
        raise ParameterError(f"expected a torch.Tensor, got {type(x).__name__}", argument=name)
    if x.dtype not in _FLOATS:
        raise DTypeError(f"expected float32 or float64, got {x.dtype}", argument=name)
    if x.ndim < 2 or x.shape[-1] != 3:
        raise ShapeError(f"expected shape (..., N, 3), got {tuple(x.shape)}", argument=name)
    return x


def like(x: Any, ref: torch.Tensor, name: str, tail: tuple[int, ...]) -> torch.Tensor:
    """``x`` (a number, sequence or tensor) as a tensor of ``ref``'s dtype and device, whose
    last dimensions are ``tail`` (no trailing dimensions required for a scalar when ``tail`` is ())."""
    if isinstance(x, torch.Tensor):
        if not x.is_floating_point():
            raise DTypeError(f"expected a floating-point tensor, got {x.dtype}", argument=name)
        if x.device != ref.device:
            raise ParameterError(f"expected a tensor on {ref.device}, got {x.device}", argument=name)
        t = x.to(ref.dtype)
    else:
        try:
            t = torch.as_tensor(x, dtype=ref.dtype, device=ref.device)
        except (TypeError, ValueError, RuntimeError):
            raise ParameterError(f"expected a tensor or numbers, got {x!r}", argument=name) from None
    if tuple(t.shape[t.ndim - len(tail) :]) != tail or t.ndim < len(tail):
        shape = ", ".join(["..."] + [str(d) for d in tail])
        raise ShapeError(f"expected shape ({shape}), got {tuple(t.shape)}", argument=name)
    return t


def _mask(mask: Any, n: int, device: torch.device) -> torch.Tensor:
    """A boolean tensor (..., N): True where a sample belongs to its window."""
    if not isinstance(mask, torch.Tensor) or mask.dtype != torch.bool:
        raise ParameterError("expected a boolean torch.Tensor (..., N)", argument="mask")
    if mask.ndim < 1 or mask.shape[-1] != n:
        raise ShapeError(f"expected shape (..., {n}), got {tuple(mask.shape)}", argument="mask")
    return mask.to(device)


def _per_sample(cov: Any, ref: torch.Tensor, name: str) -> torch.Tensor:
    """A per-sample covariance, (..., N, 3, 3) or its diagonal (..., N, 3), as (..., N, 3, 3)."""
    c = like(cov, ref, name, ())
    if c.ndim >= 2 and c.shape[-1] == 3 and (c.ndim < 3 or c.shape[-2] != 3):
        return torch.diag_embed(c)
    if c.ndim >= 3 and c.shape[-2:] == (3, 3):
        return c
    raise ShapeError(f"expected shape (..., N, 3, 3) or (..., N, 3), got {tuple(c.shape)}", argument=name)


def _densities(noise: Any, ref: torch.Tensor) -> torch.Tensor:
    """White-noise densities ``[σ_g, σ_a]`` (..., 2) from an ``ImuNoise`` or a tensor."""
    if isinstance(noise, ImuNoise):
        return torch.tensor([noise.gyro_density, noise.accel_density], dtype=ref.dtype, device=ref.device)
    return like(noise, ref, "noise", (2,))


def samples(
    dt: Any,
    gyro: Any,
    accel: Any | None,
    *,
    bias: Any,
    lengths: Any,
    mask: Any = None,
    noise: Any = None,
    gyro_cov: Any = None,
    accel_cov: Any = None,
) -> tuple[Samples, torch.Size]:
    """The inputs broadcast to one batch shape B and laid out sequence first, and B."""
    w = vectors(gyro, "gyro")
    a = torch.zeros_like(w) if accel is None else vectors(accel, "accel").to(w.dtype)
    n = w.shape[-2]
    if a.shape[-2] != n:
        raise ShapeError(f"expected N = {n} samples as gyro, got {tuple(a.shape)}", argument="accel")
    d = like(dt, w, "dt", ())
    if d.ndim and d.shape[-1] != n:
        raise ShapeError(f"expected a scalar or shape (..., {n}), got {tuple(d.shape)}", argument="dt")
    b = torch.zeros(6, dtype=w.dtype, device=w.device) if bias is None else like(bias, w, "bias", (6,))
    covs = {}
    for name, c in (("gyro_cov", gyro_cov), ("accel_cov", accel_cov)):
        if c is not None:
            covs[name] = _per_sample(c, w, name)
            if covs[name].shape[-3] != n:
                raise ShapeError(f"expected N = {n} samples, got {tuple(covs[name].shape)}", argument=name)
    dens = None if noise is None else _densities(noise, w)
    if lengths is None:
        count = torch.full((), n, device=w.device)
    elif not isinstance(lengths, torch.Tensor) or lengths.is_floating_point() or lengths.is_complex():
        raise ParameterError("expected an integer torch.Tensor (...,) of window lengths", argument="lengths")
    else:
        count = lengths.to(w.device)
    keep = torch.ones((n,), dtype=torch.bool, device=w.device) if mask is None else _mask(mask, n, w.device)
    shapes = [w.shape[:-2], a.shape[:-2], d.shape[:-1], b.shape[:-1], count.shape, keep.shape[:-1]]
    shapes += [c.shape[:-3] for c in covs.values()] + ([] if dens is None else [dens.shape[:-1]])
    try:
        batch = torch.broadcast_shapes(*shapes)  # type: ignore[no-untyped-call]
    except RuntimeError as exc:
        raise ShapeError(f"batch dimensions do not broadcast: {exc}", argument="gyro") from None
    first = len(batch)

    def seq(x: torch.Tensor, tail: int) -> torch.Tensor:
        return x.expand(*batch, n, *x.shape[x.ndim - tail :]).movedim(first, 0)

    dts = seq(d[..., None], 1)[..., 0]
    valid = torch.arange(n, device=w.device).view(n, *([1] * first)) < count
    valid = (valid & seq(keep[..., None], 1)[..., 0]).expand(n, *batch)
    per_sample = {name: seq(c, 2) for name, c in covs.items()}
    dens = None if dens is None else dens.expand(*batch, 2)
    return Samples(dts, seq(w, 1), seq(a, 1), valid, b.expand(*batch, 6), dens, **per_sample), batch


def noise_blocks(s: Samples, scheme: str) -> torch.Tensor | None:
    """Each sample's 6×6 white-noise covariance ``[gyro, accel]`` (N, *B, 6, 6), zero where masked;
    None without noise. From the densities: ``σ²/h I`` with h the step the sample owns, the Rust
    kernels' rule (``adjoint`` module docs, docs/conventions.md row 11): its interval's (lie_euler:
    the one it starts; midpoint: the one it ends) or, for midpoint when that one is empty (a
    window's first sample, a repeated time stamp), the next interval's; a sample that owns no step
    of positive length (masked, or dt = 0) has no noise (docs/torch.md, "dt = 0")."""
    if s.densities is None and s.gyro_cov is None and s.accel_cov is None:
        return None
    valid = s.valid
    own = rates(s, scheme)[0]  # each interval's step, 0 where masked
    if scheme == "midpoint":
        own = torch.where(own > 0, own, torch.cat((own[1:], torch.zeros_like(own[:1]))))
    owns = own > 0
    own = torch.where(owns, own, torch.ones_like(own))  # no 0 division, even where not taken
    eye = torch.eye(3, dtype=own.dtype, device=own.device)
    blocks = []
    for i, given in enumerate((s.gyro_cov, s.accel_cov)):
        if given is not None:
            block = torch.where(valid[..., None, None], given, torch.zeros_like(given))
        elif s.densities is not None:
            var = torch.where(owns, s.densities[..., i] ** 2 / own, torch.zeros_like(own))
            block = var[..., None, None] * eye
        else:
            block = torch.zeros(*own.shape, 3, 3, dtype=own.dtype, device=own.device)
        blocks.append(block)
    zero = torch.zeros_like(blocks[0])
    return torch.cat((torch.cat((blocks[0], zero), -1), torch.cat((zero, blocks[1]), -1)), -2)
