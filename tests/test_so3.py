"""SO(3) in Python: Jacobians against central differences computed with scipy, hat/vee, shapes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad_vec
from scipy.spatial.transform import Rotation

import imukit as ik

H = 1e-6


def _regimes(rng: np.random.Generator, n: int = 200) -> np.ndarray:
    axes = Rotation.random(4 * n, rng=rng).apply([1.0, 0.0, 0.0])
    angles = np.concatenate(
        [np.zeros(n), np.full(n, 1e-8), np.full(n, np.pi - 1e-6), rng.uniform(1e-3, np.pi - 1e-3, n)]
    )
    return axes * angles[:, None]


def _numeric(f: object, phi: np.ndarray) -> np.ndarray:
    """Central-difference Jacobian of the tangent-valued f(φ, δ) in δ, column by column."""
    cols = []
    for k in range(3):
        d = np.zeros(3)
        d[k] = H
        cols.append((f(phi, d) - f(phi, -d)) / (2 * H))  # type: ignore[operator]
    return np.stack(cols, axis=-1)


def _r(v: np.ndarray) -> Rotation:
    return Rotation.from_rotvec(v)


DEFINITIONS = {
    # J_r: Exp(φ + δ) = Exp(φ) Exp(J_r δ)  ⇒  J_r δ ≈ Log(Exp(φ)ᵀ Exp(φ + δ))
    "right_jacobian": lambda p, d: (_r(p).inv() * _r(p + d)).as_rotvec(),
    # J_l: Exp(φ + δ) = Exp(J_l δ) Exp(φ)
    "left_jacobian": lambda p, d: (_r(p + d) * _r(p).inv()).as_rotvec(),
    # J_r⁻¹: Log(Exp(φ) Exp(δ)) ≈ φ + J_r⁻¹ δ  (the branch of Log stays put away from π)
    "right_jacobian_inv": lambda p, d: (_r(p) * _r(np.tile(d, (len(p), 1)))).as_rotvec(),
    "left_jacobian_inv": lambda p, d: (_r(np.tile(d, (len(p), 1))) * _r(p)).as_rotvec(),
}


@pytest.mark.parametrize("name", sorted(DEFINITIONS))
def test_jacobians_against_scipy_central_differences(name: str, rng: np.random.Generator) -> None:
    phi = _regimes(rng)
    if name.endswith("_inv"):
        # Log jumps across θ = π, so the derivative of Log(...) exists only away from it.
        phi = phi[np.linalg.norm(phi, axis=1) < np.pi - 1e-3]
    analytic = getattr(ik.so3, name)(phi)
    numeric = _numeric(DEFINITIONS[name], phi)
    err = np.abs(analytic - numeric).max()
    assert err < 2e-8, f"{name}: max deviation {err:.2e}"


def test_jacobian_relations(rng: np.random.Generator) -> None:
    phi = _regimes(rng)
    jr, jl = ik.so3.right_jacobian(phi), ik.so3.left_jacobian(phi)
    assert np.abs(jr - ik.so3.left_jacobian(-phi)).max() < 1e-15
    assert np.abs(jl - ik.so3.exp(phi) @ jr).max() < 1e-14
    eye = np.broadcast_to(np.eye(3), jr.shape)
    assert np.abs(jr @ ik.so3.right_jacobian_inv(phi) - eye).max() < 1e-9
    assert np.abs(jl @ ik.so3.left_jacobian_inv(phi) - eye).max() < 1e-9


def test_adjoint_and_left_right_rates(rng: np.random.Generator) -> None:
    """R [a]× Rᵀ = [R a]×, and a body rate ω_r is the world rate ω_l = R ω_r."""
    r = Rotation.random(100, rng=rng).as_matrix()
    a = rng.normal(size=(100, 3))
    ra = np.einsum("nij,nj->ni", r, a)
    assert np.abs(r @ ik.so3.hat(a) @ np.swapaxes(r, 1, 2) - ik.so3.hat(ra)).max() < 1e-14
    dt = 1e-3
    body = r @ ik.so3.exp(a * dt)  # R Exp(ω_r dt)
    world = ik.so3.exp(ra * dt) @ r  # Exp(R ω_r dt) R
    assert np.abs(body - world).max() < 1e-14


def test_hat_vee() -> None:
    k = ik.so3.hat([1.0, 2.0, 3.0])
    assert np.array_equal(k, [[0.0, -3.0, 2.0], [3.0, 0.0, -1.0], [-2.0, 1.0, 0.0]])
    assert np.array_equal(k @ [4.0, 5.0, 6.0], np.cross([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]))
    assert np.array_equal(ik.so3.vee(k), [1.0, 2.0, 3.0])
    # the skew part of a general matrix
    m = k + np.diag([7.0, 8.0, 9.0]) + np.ones((3, 3))
    assert np.array_equal(ik.so3.vee(m), [1.0, 2.0, 3.0])


def test_shapes_broadcast_and_empty() -> None:
    phi = np.zeros((2, 5, 3))
    assert ik.so3.exp(phi).shape == (2, 5, 3, 3)
    assert ik.so3.log(ik.so3.exp(phi)).shape == (2, 5, 3)
    assert ik.so3.exp([0.0, 0.0, 0.0]).shape == (3, 3)
    assert ik.so3.exp(np.zeros((0, 3))).shape == (0, 3, 3)
    assert ik.so3.right_jacobian(np.zeros((4, 1, 3))).shape == (4, 1, 3, 3)
    # array-likes, ints and non-contiguous views are read as float64
    assert ik.so3.exp([[0, 0, 1]]).dtype == np.float64
    view = np.arange(30.0).reshape(5, 6)[:, ::2] * 0.01
    assert np.array_equal(ik.so3.exp(view), ik.so3.exp(np.ascontiguousarray(view)))
    assert np.array_equal(ik.so3.exp(np.asfortranarray(view)), ik.so3.exp(view))
    # broadcasting of two inputs
    q = ik.quat.exp(np.zeros((4, 1, 3)))
    v = np.ones((1, 7, 3))
    assert ik.quat.rotate(q, v).shape == (4, 7, 3)


def test_exp_double_integral_equals_its_series_and_quadrature() -> None:
    """``Γ₂(φ) = Σ_n [φ]×ⁿ/(n + 2)!`` (40 terms in numpy) and ``∫₀¹ (1 − s) Exp(sφ) ds`` (scipy
    quadrature) at angles from 1e-9 to 3 rad, the small-angle branch included."""
    for angle in (1e-9, 1e-4, 1e-2, 0.3, 1.0, 3.0):
        phi = angle * np.array([0.6, -0.48, 0.64])
        k = np.array([[0.0, -phi[2], phi[1]], [phi[2], 0.0, -phi[0]], [-phi[1], phi[0], 0.0]])
        series = sum(np.linalg.matrix_power(k, n) / math.factorial(n + 2) for n in range(40))
        quad, _ = quad_vec(
            lambda s, phi=phi: (1 - s) * Rotation.from_rotvec(s * phi).as_matrix(), 0.0, 1.0, epsabs=1e-14
        )
        out = ik.so3.exp_double_integral(phi)
        assert np.abs(out - series).max() < 1e-15
        assert np.abs(out - quad).max() < 1e-12
    assert ik.so3.exp_double_integral(np.zeros((2, 4, 3))).shape == (2, 4, 3, 3)
