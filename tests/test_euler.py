"""ZYX Euler angles and the rate map E(χ)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik


def test_rate_matrix_against_finite_differences(rng: np.random.Generator) -> None:
    """χ(t) = euler(R0 Exp(ω t)); its central difference at t = 0 equals E(χ(0)) ω."""
    r0 = Rotation.random(500, rng=rng)
    chi0 = ik.euler.from_rotation(r0)
    keep = np.abs(chi0[:, 1]) < np.radians(80)  # stay clear of the singularity and of wrap-around
    r0, chi0 = r0[keep], chi0[keep]
    w = rng.normal(size=(len(chi0), 3))
    h = 1e-6

    def chi(t: float) -> np.ndarray:
        return ik.euler.from_rotation(r0 * Rotation.from_rotvec(w * t))

    dchi = (chi(h) - chi(-h)) / (2 * h)
    dchi = (dchi + np.pi / h) % (2 * np.pi / h) - np.pi / h  # yaw/roll wrap at ±π
    predicted = np.einsum("nij,nj->ni", ik.euler.rate_matrix(chi0), w)
    assert np.abs(predicted - dchi).max() < 1e-6 * np.abs(predicted).max()
    # E⁻¹ maps back to the body rate
    back = np.einsum("nij,nj->ni", ik.euler.rate_matrix_inv(chi0), predicted)
    assert np.abs(back - w).max() < 1e-12 * np.abs(w).max() * 1e3


def test_rate_matrix_numbers_at_pitch_30_degrees() -> None:
    e = ik.euler.rate_matrix([0.0, 30.0, 0.0], degrees=True)
    c = np.cos(np.radians(30.0))
    t = np.tan(np.radians(30.0))
    assert np.allclose(e, [[0.0, 0.0, 1 / c], [0.0, 1.0, 0.0], [1.0, 0.0, t]], atol=1e-15)


@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2, np.pi / 2 - 5e-7, 3 * np.pi / 2])
def test_gimbal_lock_raises_with_index(pitch: float) -> None:
    angles = np.array([[0.1, 0.2, 0.3], [0.1, pitch, 0.3]])
    with pytest.raises(ik.GimbalLockError, match=r"^angles: gimbal lock at element 1: pitch") as info:
        ik.euler.rate_matrix(angles)
    assert isinstance(info.value, ValueError)


def test_gimbal_tolerance_is_respected() -> None:
    just_outside = [0.0, np.pi / 2 - 2e-6, 0.0]
    assert np.isfinite(ik.euler.rate_matrix(just_outside)).all()
    with pytest.raises(ik.GimbalLockError):
        ik.euler.rate_matrix(just_outside, tolerance_rad=1e-3)
    for bad in (-1.0, np.nan, np.inf):
        with pytest.raises(ik.ParameterError, match=r"^tolerance_rad: expected a finite, non-negative"):
            ik.euler.rate_matrix(just_outside, tolerance_rad=bad)


def test_angles_lie_in_half_open_interval() -> None:
    """atan2 returns -π for a -0.0 numerator; the documented range is (-π, π]."""
    m = np.diag([-1.0, -1.0, 1.0])
    m[1, 0] = -0.0
    m[2, 1] = -0.0
    chi = ik.euler.from_rotation(np.stack([m, m.T]))
    assert np.array_equal(chi[:, 0], [np.pi, np.pi])
    roll_pi = np.diag([1.0, -1.0, -1.0])
    roll_pi[2, 1] = -0.0
    assert ik.euler.from_rotation(roll_pi)[2] == np.pi


def test_from_rotation_at_exact_gimbal_lock_reproduces_the_rotation() -> None:
    for pitch in (np.pi / 2, -np.pi / 2):
        r = ik.euler.to_rotation([0.4, pitch, -0.3])
        chi = ik.euler.from_rotation(r)
        assert chi[2] == 0.0 or abs(abs(chi[1]) - np.pi / 2) > 0
        assert np.abs(ik.euler.to_rotation(chi).as_matrix() - r.as_matrix()).max() < 1e-12


def test_to_rotation_is_rz_ry_rx() -> None:
    yaw, pitch, roll = 0.3, -0.4, 0.5
    rz = Rotation.from_rotvec([0, 0, yaw])
    ry = Rotation.from_rotvec([0, pitch, 0])
    rx = Rotation.from_rotvec([roll, 0, 0])
    r = ik.euler.to_rotation([yaw, pitch, roll])
    assert isinstance(r, Rotation)
    assert np.abs(r.as_matrix() - (rz * ry * rx).as_matrix()).max() < 1e-15
