"""Quaternion algebra: product matrices, Ω(ω) in VINS-Mono's form, JPL, scalar_first."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

from conftest import assert_quat_close

WX, WY, WZ = 0.1, -0.2, 0.3


def test_omega_equals_vins_mono_form_element_by_element() -> None:
    """VINS-Mono (Qin et al. 2018, eq. 3): Ω(ω) = [[-[ω]×, ω], [-ωᵀ, 0]] on [x, y, z, w]."""
    vins = np.array(
        [
            [0.0, WZ, -WY, WX],
            [-WZ, 0.0, WX, WY],
            [WY, -WX, 0.0, WZ],
            [-WX, -WY, -WZ, 0.0],
        ]
    )
    expected_numbers = np.array(
        [
            [0.0, 0.3, 0.2, 0.1],
            [-0.3, 0.0, 0.1, -0.2],
            [-0.2, -0.1, 0.0, 0.3],
            [-0.1, 0.2, -0.3, 0.0],
        ]
    )
    assert np.array_equal(vins, expected_numbers)
    omega = ik.quat.omega_matrix([WX, WY, WZ])
    assert np.array_equal(omega, vins)
    # ... and it is the right-product matrix of the pure quaternion [ω, 0].
    assert np.array_equal(omega, ik.quat.right_matrix([WX, WY, WZ, 0.0]))


def test_omega_gives_the_quaternion_derivative(rng: np.random.Generator) -> None:
    """q̇ = ½ Ω(ω) q matches the central difference of q ⊗ Exp(ω t) at t = 0."""
    q = Rotation.random(rng=rng).as_quat()
    w = np.array([WX, WY, WZ])
    h = 1e-6
    dq = (ik.quat.multiply(q, ik.quat.exp(w * h)) - ik.quat.multiply(q, ik.quat.exp(-w * h))) / (2 * h)
    assert np.abs(dq - 0.5 * ik.quat.omega_matrix(w) @ q).max() < 1e-9
    # the left-multiplied (world-rate) form is a different matrix: the test can tell them apart
    assert np.abs(dq - 0.5 * ik.quat.left_matrix(np.append(w, 0.0)) @ q).max() > 1e-2


def test_scalar_first_omega_is_the_same_operator_on_wxyz(rng: np.random.Generator) -> None:
    q = Rotation.random(rng=rng).as_quat()
    w = np.array([WX, WY, WZ])
    xyzw = ik.quat.omega_matrix(w) @ q
    wxyz = ik.quat.omega_matrix(w, scalar_first=True) @ q[[3, 0, 1, 2]]
    assert np.allclose(wxyz, xyzw[[3, 0, 1, 2]], atol=1e-15)
    # Solà (2017, eq. 199) writes it for wxyz as [[0, -ωᵀ], [ω, -[ω]×]]
    assert np.array_equal(ik.quat.omega_matrix(w, scalar_first=True)[0], [0.0, -WX, -WY, -WZ])


def test_jpl_omega_is_the_same_matrix_and_integrates_world_to_body() -> None:
    """JPL (Trawny & Roumeliotis eq. 108): q̄̇ = ½ Ω(ω) q̄ for q̄ of ᴮC_W, same numbers as Hamilton q_wb."""
    w = np.array([WX, WY, WZ])
    assert np.array_equal(ik.quat.omega_matrix(w, convention="jpl"), ik.quat.omega_matrix(w))
    # JPL Ω is the JPL *left* product with [ω, 0].
    pure = np.append(w, 0.0)
    assert np.array_equal(ik.quat.omega_matrix(w, convention="jpl"), ik.quat.left_matrix(pure, convention="jpl"))
    # Integrate the JPL ODE; the JPL quaternion's matrix C(q̄) (= R(q)ᵀ for the same numbers,
    # since JPL is passive) must equal the world-to-body rotation R_wbᵀ of the Hamilton solution.
    t = 0.7
    hamilton_r_wb = Rotation.from_rotvec(w * t).as_matrix()
    q_bar = np.array([0.0, 0.0, 0.0, 1.0])
    steps = 2000
    a = 0.5 * ik.quat.omega_matrix(w, convention="jpl") * (t / steps)
    for _ in range(steps):  # RK4 on the linear ODE
        k1 = a @ q_bar
        k2 = a @ (q_bar + k1 / 2)
        k3 = a @ (q_bar + k2 / 2)
        k4 = a @ (q_bar + k3)
        q_bar = q_bar + (k1 + 2 * k2 + 2 * k3 + k4) / 6
    x, y, z, s = q_bar
    # Trawny & Roumeliotis eq. 62: C(q̄) = (2s² - 1) I - 2 s [v]× + 2 v vᵀ
    v = np.array([x, y, z])
    skew = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    c_jpl = (2 * s * s - 1) * np.eye(3) - 2 * s * skew + 2 * np.outer(v, v)
    assert np.abs(c_jpl - hamilton_r_wb.T).max() < 1e-12


def test_product_matrices(rng: np.random.Generator) -> None:
    q, p = rng.normal(size=(2, 50, 4))
    qp = ik.quat.multiply(q, p)
    assert np.allclose(np.einsum("nij,nj->ni", ik.quat.left_matrix(q), p), qp, atol=1e-14)
    assert np.allclose(np.einsum("nij,nj->ni", ik.quat.right_matrix(p), q), qp, atol=1e-14)
    # JPL: q ⊗_J p = p ⊗_H q, L_J = R_H, R_J = L_H
    assert np.array_equal(ik.quat.multiply(q, p, convention="jpl"), ik.quat.multiply(p, q))
    assert np.array_equal(ik.quat.left_matrix(q, convention="jpl"), ik.quat.right_matrix(q))
    assert np.array_equal(ik.quat.right_matrix(q, convention="jpl"), ik.quat.left_matrix(q))
    # scalar_first matrices act on wxyz vectors
    perm = [3, 0, 1, 2]
    lq = ik.quat.left_matrix(q[:, perm], scalar_first=True)
    assert np.allclose(np.einsum("nij,nj->ni", lq, p[:, perm]), qp[:, perm], atol=1e-14)


def test_hamilton_vs_jpl_basis_products() -> None:
    i, j, k = np.eye(4)[:3]
    assert np.array_equal(ik.quat.multiply(i, j), k)  # Hamilton: i j = k
    assert np.array_equal(ik.quat.multiply(i, j, convention="jpl"), -k)  # JPL: i j = -k


def test_conjugate_inverse_normalize(rng: np.random.Generator) -> None:
    q = rng.normal(size=(100, 4)) * 3
    identity = np.array([0.0, 0.0, 0.0, 1.0])
    assert np.allclose(ik.quat.multiply(q, ik.quat.inverse(q)), identity, atol=1e-14)
    assert np.array_equal(ik.quat.conjugate(q), q * [-1, -1, -1, 1])
    n = ik.quat.normalize(q)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-15)
    assert np.allclose(n * np.linalg.norm(q, axis=1, keepdims=True), q, atol=1e-14)
    assert_quat_close(ik.quat.normalize(q[:, [3, 0, 1, 2]], scalar_first=True)[:, [1, 2, 3, 0]], n, atol=1e-15)


def test_rotate_is_active_body_to_world() -> None:
    """q_wb = 90° about z maps the body x axis onto the world y axis."""
    q = ik.quat.exp([0.0, 0.0, np.pi / 2])
    assert np.allclose(ik.quat.rotate(q, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)
    assert np.allclose(ik.quat.rotate(q * 5.0, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)


@pytest.mark.parametrize("func", [ik.quat.inverse, ik.quat.normalize, ik.quat.log])
def test_zero_quaternion_is_refused(func: object) -> None:
    with pytest.raises(ik.InvalidQuaternionError, match=r"^q: element 1 is a zero-norm quaternion"):
        func([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])  # type: ignore[operator]
    with pytest.raises(ik.InvalidQuaternionError, match=r"^q / v: element 0 is a zero-norm"):
        ik.quat.rotate([0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
