"""imukit against scipy on 10,000 random rotations, to 1e-12."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik

from conftest import assert_quat_close

TOL = 1e-12


def test_exp_matches_from_rotvec(rotvecs: np.ndarray) -> None:
    ours = ik.so3.exp(rotvecs)
    assert ours.shape == (len(rotvecs), 3, 3)
    assert np.abs(ours - Rotation.from_rotvec(rotvecs).as_matrix()).max() < TOL


def test_log_matches_as_rotvec(rotvecs: np.ndarray) -> None:
    rotations = Rotation.from_rotvec(rotvecs)
    ours = ik.so3.log(rotations.as_matrix())
    assert np.abs(ours - rotations.as_rotvec()).max() < TOL
    # A Rotation is accepted directly.
    assert np.abs(ik.so3.log(rotations) - ours).max() == 0.0


def test_log_at_pi_and_identity_matches_scipy() -> None:
    axes = np.eye(3)
    phi = np.concatenate([axes * np.pi, axes * (np.pi - 1e-6), axes * 1e-8, np.zeros((1, 3))])
    ours = ik.so3.log(ik.so3.exp(phi))
    # At exactly π, φ and -φ are both logarithms: compare the rotations they make.
    assert np.abs(ik.so3.exp(ours) - Rotation.from_rotvec(phi).as_matrix()).max() < TOL
    assert np.abs(np.linalg.norm(ours, axis=1) - np.linalg.norm(phi, axis=1)).max() < TOL
    assert np.abs(ours[3:] - phi[3:]).max() < TOL


def test_quaternion_exp_log_match_scipy(rotvecs: np.ndarray) -> None:
    q = ik.quat.exp(rotvecs)
    assert_quat_close(q, Rotation.from_rotvec(rotvecs).as_quat(), atol=TOL)
    assert np.abs(ik.quat.log(q) - rotvecs).max() < 1e-11 * np.pi
    assert np.abs(ik.quat.log(-q) - rotvecs).max() < 1e-11 * np.pi


def test_product_matches_rotation_composition(rng: np.random.Generator) -> None:
    a, b = Rotation.random(10_000, rng=rng), Rotation.random(10_000, rng=rng)
    ours = ik.quat.multiply(a.as_quat(), b.as_quat())
    assert_quat_close(ours, (a * b).as_quat(), atol=TOL)
    # scalar_first round-trips through wxyz storage
    wxyz = ik.quat.multiply(a.as_quat(scalar_first=True), b.as_quat(scalar_first=True), scalar_first=True)
    assert_quat_close(wxyz, (a * b).as_quat(scalar_first=True), atol=TOL)


def test_rotate_matches_apply(rng: np.random.Generator) -> None:
    r = Rotation.random(10_000, rng=rng)
    v = rng.normal(size=(10_000, 3))
    assert np.abs(ik.quat.rotate(r.as_quat(), v) - r.apply(v)).max() < TOL * 10


def test_euler_zyx_matches_scipy_intrinsic(rotvecs: np.ndarray) -> None:
    rotations = Rotation.from_rotvec(rotvecs)
    ours = ik.euler.from_rotation(rotations)
    assert np.abs(ours - rotations.as_euler("ZYX")).max() < TOL
    back = ik.euler.to_rotation(ours)
    assert np.abs(back.as_matrix() - rotations.as_matrix()).max() < TOL
    degrees = ik.euler.from_rotation(rotations, degrees=True)
    assert np.abs(degrees - rotations.as_euler("ZYX", degrees=True)).max() < TOL * 180
    assert np.abs(ik.euler.to_rotation(degrees, degrees=True).as_matrix() - rotations.as_matrix()).max() < TOL


def test_euler_is_not_extrinsic() -> None:
    """scipy's lower-case "zyx" is extrinsic; ours equals upper-case "ZYX" only."""
    angles = np.array([0.3, -0.4, 0.5])
    ours = ik.euler.to_rotation(angles).as_matrix()
    assert np.abs(ours - Rotation.from_euler("ZYX", angles).as_matrix()).max() < TOL
    assert np.abs(ours - Rotation.from_euler("zyx", angles).as_matrix()).max() > 0.1
