"""Differentiable, batched IMU integration and preintegration in torch (``imukit[torch]``).

The same numbers as the numpy API (``imukit.integrate_attitude``, ``imukit.integrate``,
``imukit.preintegrate``; conventions in ``docs/conventions.md``, math in
``docs/preintegration.md``), on CPU or CUDA tensors, float32 or float64, with any leading batch
dimensions, and gradients by autograd with respect to every tensor input. ``docs/torch.md`` is the
guide.

- Shapes: ``gyro``, ``accel`` (..., N, 3); ``dt`` (..., N) or a scalar; ``bias`` (..., 6)
  ``[b_g, b_a]``; ragged windows through ``lengths`` (...,) integers ≤ N (samples from
  ``lengths`` on are ignored; per-step outputs there repeat the window's end) and/or ``mask``
  (..., N) booleans (False: the sample is not in the window; lie_euler skips it, midpoint counts an
  interval only when both its samples are in, so a window padded at either end is that window
  alone).
- ``dt`` as ``PreintegratedImu.integrate_measurement``: ``lie_euler`` / ``exp``: sample k is held
  over the next ``dt[k]`` s; ``midpoint`` / ``rk2``: sample k was taken ``dt[k]`` s after sample
  k − 1 (``dt[0]`` is not used).
- Per step, index k is the result after sample k was consumed: at ``t_{k+1}`` (lie_euler, exp),
  at ``t_k`` (midpoint, rk2; index 0 is the start).
- Rotations are matrices (..., 3, 3), ``R_wb`` or ``ΔR_ij``.
- Covariance 9 × 9 ``[δθ, δv, δp]``, right perturbation; white noise from ``noise`` (an
  ``ImuNoise`` or a tensor (..., 2) of densities ``[σ_g, σ_a]``, discretised as ``σ²/h``) or per
  sample from ``gyro_cov`` / ``accel_cov`` (..., N, 3, 3) or their diagonals (..., N, 3), the
  covariance of each reading's white noise (each replaces ``noise`` for its sensor).
- Bias Jacobian 9 × 6, rows ``[θ, v, p]``, columns ``[b_g, b_a]``.
- ``method``: ``"auto"`` (default): ``"native"`` where it applies, else ``"scan"``;
  ``"native"``, the Rust kernels with their analytic backward (CPU tensors; every output of both
  schemes, ``integrate_attitude``'s ``exp``; ``_native.py``); ``"scan"``, associative scans over the sequence in
  torch, depth O(log N) (``_scan.py``), the device (CUDA) path; ``"sequential"``, the step-by-step
  recursion in torch, the reference.

``import imukit`` does not import torch; ``import imukit.torch`` needs it (``pip install imukit[torch]``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

try:
    import torch
except ImportError as exc:  # pragma: no cover - torch is installed wherever the tests run
    from imukit._errors import MissingDependencyError

    raise MissingDependencyError("imukit.torch needs torch: pip install imukit[torch]") from exc

from imukit import _core
from imukit._arrays import flag
from imukit._errors import ParameterError
from imukit.preint import PreintParams
from imukit.torch import _native, _scan, _steps
from imukit.torch._inputs import choice, like, noise_blocks, samples
from imukit.torch._so3 import quat_multiply, quat_to_matrix

__all__ = ["Preintegrated", "State", "integrate", "integrate_attitude", "preintegrate"]

_PREINT_SCHEMES = ("midpoint", "lie_euler")
_METHODS = ("auto", "native", "scan", "sequential")


class Preintegrated(NamedTuple):
    """The result of :func:`preintegrate`: ``delta_rotation`` (..., 3, 3), ``delta_velocity``,
    ``delta_position`` (..., 3), ``delta_t`` (...), ``covariance`` (..., 9, 9) and ``bias_jacobian``
    (..., 9, 6) when asked for (else None); with ``per_step``, an N dimension before the last ones."""

    delta_rotation: torch.Tensor
    delta_velocity: torch.Tensor
    delta_position: torch.Tensor
    delta_t: torch.Tensor
    covariance: torch.Tensor | None
    bias_jacobian: torch.Tensor | None


class State(NamedTuple):
    """A navigation state: ``rotation`` ``R_wb`` (..., 3, 3), ``velocity``, ``position`` (..., 3)
    in the world frame."""

    rotation: torch.Tensor
    velocity: torch.Tensor
    position: torch.Tensor


def _method(method: str, x: torch.Tensor, kernel: bool = True) -> str:
    """The path that runs: ``auto`` resolved, ``native`` refused where the kernels do not apply
    (CUDA tensors; no ``kernel`` for the call)."""
    method = choice(method, "method", _METHODS)
    native = kernel and _native.supported(x)
    if method == "native" and not native:
        raise ParameterError("the native kernels need CPU tensors (and integrate_attitude: exp)", argument="method")
    if method == "auto":
        return "native" if native else "scan"
    return method


def _compose(combine: _scan.Combine, xs: _scan.Elements, *, keep: bool, method: str) -> _scan.Elements:
    if method == "sequential":
        return _scan.sequential(combine, xs, keep=keep)
    return _scan.scan(combine, xs) if keep else _scan.reduce(combine, xs)


def _out(x: torch.Tensor, first: int, keep: bool) -> torch.Tensor:
    """Sequence-first ``x`` back to (*B, N, ...) (``keep``) or (*B, ...)."""
    return x.movedim(0, first) if keep else x[0]


def preintegrate(
    dt: Any,
    gyro: torch.Tensor,
    accel: torch.Tensor,
    *,
    bias: Any = None,
    noise: Any = None,
    gyro_cov: Any = None,
    accel_cov: Any = None,
    lengths: torch.Tensor | None = None,
    mask: torch.Tensor | None = None,
    scheme: str = PreintParams.scheme,
    return_covariance: bool = False,
    return_jacobian: bool = False,
    per_step: bool = False,
    method: str = "auto",
) -> Preintegrated:
    """Preintegrated ``ΔR``, ``Δv``, ``Δp``, ``Δt`` of each window (module docs for the shapes);
    ``return_covariance`` needs ``noise``, ``gyro_cov`` or ``accel_cov``."""
    scheme = choice(scheme, "scheme", _PREINT_SCHEMES)
    return_covariance, return_jacobian, per_step = (
        flag(value, name)
        for value, name in (
            (return_covariance, "return_covariance"),
            (return_jacobian, "return_jacobian"),
            (per_step, "per_step"),
        )
    )
    noisy = noise is not None or gyro_cov is not None or accel_cov is not None
    if return_covariance and not noisy:
        raise ParameterError("needs noise, gyro_cov or accel_cov", argument="return_covariance")
    s, batch = samples(
        dt,
        gyro,
        accel,
        bias=bias,
        lengths=lengths,
        mask=mask,
        noise=noise,
        gyro_cov=gyro_cov,
        accel_cov=accel_cov,
    )
    linear = return_covariance or return_jacobian
    method = _method(method, s.gyro)
    if method == "native":
        out = _native.preintegrate(
            s, batch, scheme, per_step=per_step, covariance=return_covariance, jacobian=return_jacobian
        )
        return Preintegrated(*out)
    iv = _steps.intervals(s, scheme)
    elements = _steps.deltas(iv, scheme)
    rot, vel, pos, t = _compose(_steps.compose_deltas, elements, keep=per_step or linear, method=method)
    cov = jac = None
    if linear:
        eye = torch.eye(3, dtype=rot.dtype, device=rot.device).expand_as(rot[:1])
        before = torch.cat((eye, rot[:-1]))
        maps = _steps.linear(iv, before, noise_blocks(s, scheme) if return_covariance else None, scheme)
        lin = _compose(_steps.compose_linear, maps, keep=per_step, method=method)
        cov = lin[1][..., :9, :9] if return_covariance else None
        jac = lin[-1][..., :9, :] if return_jacobian else None
        if not per_step:
            rot, vel, pos, t = (x[-1:] for x in (rot, vel, pos, t))
    first = len(batch)
    rot, vel, pos, t = (_out(x, first, per_step) for x in (rot, vel, pos, t))
    return Preintegrated(
        rot,
        vel,
        pos,
        t,
        None if cov is None else _out(cov, first, per_step),
        None if jac is None else _out(jac, first, per_step),
    )


def integrate(
    dt: Any,
    gyro: torch.Tensor,
    accel: torch.Tensor,
    *,
    initial_state: State,
    bias: Any = None,
    gravity: Any = _core.GRAVITY,
    lengths: torch.Tensor | None = None,
    mask: torch.Tensor | None = None,
    scheme: str = _core.STRAPDOWN_DEFAULT_SCHEME,
    method: str = "auto",
) -> State:
    """Strapdown states (..., N, ...) in the world frame from ``initial_state`` (module docs for
    the per-step index), as ``imukit.integrate``: the per-step preintegration predicted from the
    initial state, ``R = R₀ΔR``, ``v = v₀ + g t + R₀Δv``, ``p = p₀ + v₀ t + ½ g t² + R₀Δp``."""
    if not isinstance(initial_state, State):
        got = type(initial_state).__name__
        raise ParameterError(f"expected an imukit.torch.State, got {got}", argument="initial_state")
    d = preintegrate(
        dt, gyro, accel, bias=bias, lengths=lengths, mask=mask, scheme=scheme, per_step=True, method=method
    )
    r0 = like(initial_state.rotation, d.delta_rotation, "initial_state.rotation", (3, 3))[..., None, :, :]
    v0 = like(initial_state.velocity, d.delta_rotation, "initial_state.velocity", (3,))[..., None, :]
    p0 = like(initial_state.position, d.delta_rotation, "initial_state.position", (3,))[..., None, :]
    g = like(gravity, d.delta_rotation, "gravity", (3,))
    t = d.delta_t[..., None]
    velocity = v0 + g * t + (r0 @ d.delta_velocity[..., None])[..., 0]
    position = p0 + v0 * t + 0.5 * g * t * t + (r0 @ d.delta_position[..., None])[..., 0]
    return State(r0 @ d.delta_rotation, velocity, position)


def integrate_attitude(
    dt: Any,
    gyro: torch.Tensor,
    *,
    initial: torch.Tensor | None = None,
    scheme: str = _core.ATTITUDE_DEFAULT_SCHEME,
    lengths: torch.Tensor | None = None,
    mask: torch.Tensor | None = None,
    method: str = "auto",
) -> torch.Tensor:
    """Attitudes ``R_wb`` (..., N, 3, 3) from body rates, as ``imukit.integrate_attitude``:
    ``"exp"`` (``R ← R Exp(ω_k h)``) or ``"rk2"`` (explicit midpoint on the quaternion ODE with
    ``½(ω_{k−1} + ω_k)``, a right product by ``[ωh/2, 1 − |ω|²h²/8]``, normalised)."""
    scheme = choice(scheme, "scheme", ("exp", "rk2"))
    s, batch = samples(dt, gyro, None, bias=None, lengths=lengths, mask=mask)
    # exp is the preintegration's rotation (lie_euler); rk2 has no native kernel.
    method = _method(method, s.gyro, kernel=scheme == "exp")
    if method == "native":
        rot = _native.preintegrate(s, batch, "lie_euler", per_step=True, covariance=False, jacobian=False)[0]
    elif scheme == "exp":
        steps = (_steps.intervals(s, "lie_euler").step,)
        (rot,) = _compose(lambda a, b: (a[0] @ b[0],), steps, keep=True, method=method)
    else:
        (q,) = _compose(lambda a, b: (quat_multiply(a[0], b[0]),), (_steps.rk2_steps(s),), keep=True, method=method)
        rot = quat_to_matrix(q / q.norm(dim=-1, keepdim=True))
    if method != "native":
        rot = rot.movedim(0, len(batch))
    if initial is None:
        return rot
    return like(initial, rot, "initial", (3, 3))[..., None, :, :] @ rot
