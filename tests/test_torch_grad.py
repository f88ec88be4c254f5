"""``imukit.torch`` gradients: ``torch.autograd.gradcheck`` (float64, central differences against
autograd) for every function and differentiable input, covariance and bias Jacobian outputs
included; and the bias Jacobian the preintegration returns equals the derivative of its deltas
with respect to the bias, taken by autograd.
"""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch", reason="imukit.torch needs torch (pip install imukit[torch])")

import imukit.torch as it  # noqa: E402
from torch_cases import case  # noqa: E402

SCHEMES = ["midpoint", "lie_euler"]


def _leaves(*xs):
    return tuple(x.detach().clone().requires_grad_(True) for x in xs)


@pytest.mark.parametrize("method", ["scan", "sequential"])
@pytest.mark.parametrize("scheme", SCHEMES)
def test_gradcheck_preintegrate_with_noise_densities(scheme: str, method: str) -> None:
    c = case((2,), 5, seed=10)
    densities = torch.tensor([[1.7e-2, 2.0e-1], [3e-2, 1e-1]], dtype=torch.float64)
    inputs = _leaves(c.dt, c.gyro, c.accel, c.bias, densities)

    def f(dt, gyro, accel, bias, noise):
        out = it.preintegrate(
            dt, gyro, accel, bias=bias, noise=noise, scheme=scheme, method=method,
            return_covariance=True, return_jacobian=True, per_step=True,
        )  # fmt: skip
        return tuple(out)

    assert torch.autograd.gradcheck(f, inputs, fast_mode=True)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_gradcheck_preintegrate_with_per_sample_covariances(scheme: str) -> None:
    c = case((2,), 4, seed=11)
    g = torch.Generator().manual_seed(3)
    gyro_cov = 1e-4 * torch.rand(2, 4, 3, 3, generator=g, dtype=torch.float64)  # full 3×3 blocks
    accel_cov = 1e-2 * torch.rand(2, 4, 3, generator=g, dtype=torch.float64)  # diagonals
    inputs = _leaves(c.dt, c.gyro, c.accel, gyro_cov, accel_cov)

    def f(dt, gyro, accel, gcov, acov):
        out = it.preintegrate(dt, gyro, accel, gyro_cov=gcov, accel_cov=acov, scheme=scheme, return_covariance=True)
        return out.covariance, out.delta_rotation

    assert torch.autograd.gradcheck(f, inputs, fast_mode=True)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_gradcheck_integrate(scheme: str) -> None:
    c = case((2,), 5, seed=12)
    r0 = torch.linalg.matrix_exp(torch.tensor([[0.0, -0.5, -0.2], [0.5, 0.0, -0.3], [0.2, 0.3, 0.0]]).double())
    v0, p0 = torch.tensor([1.0, 2.0, -0.5]).double(), torch.tensor([-1.0, 0.5, 2.0]).double()
    gravity = torch.tensor([0.0, 0.0, -9.81]).double()
    inputs = _leaves(c.dt, c.gyro, c.accel, c.bias, r0, v0, p0, gravity)

    def f(dt, gyro, accel, bias, r, v, p, grav):
        out = it.integrate(dt, gyro, accel, initial_state=it.State(r, v, p), bias=bias, gravity=grav, scheme=scheme)
        return tuple(out)

    assert torch.autograd.gradcheck(f, inputs, fast_mode=True)


@pytest.mark.parametrize("scheme", ["rk2", "exp"])
def test_gradcheck_integrate_attitude(scheme: str) -> None:
    c = case((2,), 6, seed=13)
    r0 = torch.linalg.matrix_exp(torch.tensor([[0.0, -0.5, -0.2], [0.5, 0.0, -0.3], [0.2, 0.3, 0.0]]).double())
    inputs = _leaves(c.dt, c.gyro, r0)
    assert torch.autograd.gradcheck(
        lambda dt, w, r: it.integrate_attitude(dt, w, initial=r, scheme=scheme), inputs, fast_mode=True
    )


def test_gradcheck_at_zero_rates_and_masked_samples() -> None:
    """Zero rotation steps (a masked sample, a still gyro) take the series branch of Exp and J_r:
    finite gradients that match central differences."""
    c = case((2,), 5, seed=14)
    gyro = c.gyro.clone()
    gyro[0, 1] = 0.0
    inputs = _leaves(c.dt, gyro, c.accel, c.bias)
    lengths = torch.tensor([5, 3])

    def f(dt, w, a, b):
        out = it.preintegrate(
            dt, w, a, bias=b, noise=torch.tensor([1e-2, 1e-1]).double(), lengths=lengths,
            return_covariance=True, return_jacobian=True,
        )  # fmt: skip
        return tuple(out)

    assert torch.autograd.gradcheck(f, inputs, fast_mode=True)


def _vee_skew(r: torch.Tensor) -> torch.Tensor:
    """``vee((R − Rᵀ)/2)``: equal to ``Log(R)`` to first order at R = I, which is all a derivative
    at the identity needs."""
    s = 0.5 * (r - r.transpose(-1, -2))
    return torch.stack((s[..., 2, 1], s[..., 0, 2], s[..., 1, 0]), -1)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_bias_jacobian_equals_autograd(scheme: str) -> None:
    """Rows ``[θ, v, p]``: θ is the right perturbation, ``ΔR(b + δ) = ΔR(b) Exp(J_θ δ)``, so its
    derivative is that of ``Log(ΔR(b)ᵀ ΔR(b + δ))`` at δ = 0."""
    c = case((), 200, seed=15)
    out = it.preintegrate(c.dt, c.gyro, c.accel, bias=c.bias, scheme=scheme, return_jacobian=True)
    r_hat = out.delta_rotation.detach()

    def deltas(delta):
        d = it.preintegrate(c.dt, c.gyro, c.accel, bias=c.bias + delta, scheme=scheme)
        return torch.cat((_vee_skew(r_hat.T @ d.delta_rotation), d.delta_velocity, d.delta_position))

    jac = torch.autograd.functional.jacobian(deltas, torch.zeros(6, dtype=torch.float64))
    scale = float(jac.abs().max())
    assert float((jac - out.bias_jacobian).abs().max()) < 1e-12 * scale
    # The accelerometer bias does not reach the rotation.
    assert float(jac[:3, 3:].abs().max()) == 0.0
