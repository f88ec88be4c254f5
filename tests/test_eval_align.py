"""imukit.eval.align / ape: known transforms recovered, Umeyama's reflection case by hand, degenerate input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

N = 200
TRANSFORM = Rotation.from_rotvec([0.3, -0.2, 1.1])
SHIFT = np.array([4.0, -2.0, 0.5])


def poses(position: np.ndarray, rotation: Rotation, velocity: np.ndarray | None = None) -> ik.Trajectory:
    return ik.Trajectory(np.arange(len(position)) * 0.01, position, velocity, rotation)


@pytest.fixture
def ref(rng: np.random.Generator) -> ik.Trajectory:
    """A 3-D random walk (non-collinear, non-planar) with random attitudes and velocities."""
    return poses(np.cumsum(rng.normal(0.0, 0.3, (N, 3)), axis=0), Rotation.random(N, rng=rng), rng.normal(size=(N, 3)))


def moved(traj: ik.Trajectory, rotation: Rotation, shift: np.ndarray, scale: float = 1.0) -> ik.Trajectory:
    """``traj`` expressed in another world: p' = s R p + t, R_wb' = R R_wb."""
    return poses(scale * rotation.apply(np.array(traj.position)) + shift, rotation * traj.rotation)


def test_constant_offset_ape_is_the_offset_without_alignment_and_zero_with_se3(ref: ik.Trajectory) -> None:
    est = moved(ref, Rotation.identity(), SHIFT)
    raw = ik.eval.ape(est, ref, align="none")
    np.testing.assert_allclose(raw.translation, np.linalg.norm(SHIFT), rtol=1e-13)
    assert raw.translation_stats.rmse == pytest.approx(np.linalg.norm(SHIFT), rel=1e-13)
    assert raw.translation_stats.std == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(raw.rotation, 0.0, atol=1e-14)
    for method in ("se3", "position"):
        fixed = ik.eval.ape(est, ref, align=method)
        assert fixed.translation_stats.max < 1e-12, method
        np.testing.assert_allclose(fixed.alignment.translation, -SHIFT, atol=1e-12)
        assert fixed.alignment.rotation.magnitude() < 1e-12


def test_rotation_error_is_the_angle_of_the_body_frame_difference(ref: ik.Trajectory) -> None:
    # R_est = R_ref Rx(0.3): R_ref⁻¹ R_est = Rx(0.3) at every sample, whatever R_ref; positions equal,
    # so no alignment moves anything (orientations do not enter the fit)
    est = poses(np.array(ref.position), ref.rotation * Rotation.from_rotvec([0.3, 0.0, 0.0]))
    for method in ("none", "se3", "yaw"):
        err = ik.eval.ape(est, ref, align=method)
        np.testing.assert_allclose(err.rotation, 0.3, atol=1e-14, err_msg=method)
        assert err.translation_stats.max < 1e-12 and err.alignment.rotation.magnitude() < 1e-14


def test_se3_recovers_a_rigid_transform_and_undoes_it(ref: ik.Trajectory) -> None:
    est = moved(ref, TRANSFORM, SHIFT)
    raw = ik.eval.ape(est, ref, align="none")
    assert raw.translation_stats.min > 0.1 and raw.rotation_stats.min == pytest.approx(TRANSFORM.magnitude(), abs=1e-9)
    fit = ik.eval.ape(est, ref, align="se3")
    inv = TRANSFORM.inv()
    assert (fit.alignment.rotation * TRANSFORM).magnitude() < 1e-12
    np.testing.assert_allclose(fit.alignment.translation, -inv.apply(SHIFT), atol=1e-12)
    assert fit.alignment.scale == 1.0
    assert fit.translation_stats.max < 1e-12 and fit.rotation_stats.max < 1e-12
    assert fit.n_dropped == 0


def test_sim3_returns_the_scale_that_se3_cannot_fix(ref: ik.Trajectory) -> None:
    est = moved(ref, TRANSFORM, SHIFT, scale=0.5)  # a monocular estimate at half scale
    sim3 = ik.eval.ape(est, ref, align="sim3")
    assert sim3.alignment.scale == pytest.approx(2.0, rel=1e-13)
    assert sim3.translation_stats.max < 1e-12
    se3 = ik.eval.ape(est, ref, align="se3")
    assert se3.alignment.scale == 1.0 and se3.translation_stats.rmse > 0.5


def test_yaw_fixes_a_heading_rotation_but_not_a_tilt(ref: ik.Trajectory) -> None:
    heading = Rotation.from_rotvec([0.0, 0.0, 2.5])
    yaw = ik.eval.ape(moved(ref, heading, SHIFT), ref, align="yaw")
    assert (yaw.alignment.rotation * heading).magnitude() < 1e-12
    assert yaw.translation_stats.max < 1e-12 and yaw.rotation_stats.max < 1e-12
    tilt = Rotation.from_rotvec([0.2, 0.0, 0.0])
    tilted = moved(ref, tilt, SHIFT)
    yaw_only = ik.eval.ape(tilted, ref, align="yaw")
    rotvec = yaw_only.alignment.rotation.as_rotvec()
    assert rotvec[0] == rotvec[1] == 0.0  # a turn about world z, whatever the data
    # the tilt stays in the attitude error: R_ref⁻¹ R_z R_tilt R_ref has angle ≥ the 0.2 rad tilt
    assert yaw_only.rotation_stats.min >= 0.2 - 1e-12 and yaw_only.translation_stats.rmse > 0.1
    assert ik.eval.ape(tilted, ref, align="se3").translation_stats.max < 1e-12


def test_yaw_is_the_least_squares_heading(rng: np.random.Generator, ref: ik.Trajectory) -> None:
    # with noise, the closed form must beat every nearby heading (brute force over a fine grid)
    noisy = poses(ref.position + rng.normal(0.0, 0.2, (N, 3)), ref.rotation)
    fit = ik.eval.align(noisy, ref, method="yaw")

    def cost(theta: float) -> float:
        r = Rotation.from_rotvec([0.0, 0.0, theta])
        x = r.apply(np.array(noisy.position))
        return float(np.sum((ref.position - x - (ref.position - x).mean(axis=0)) ** 2))

    best = fit.rotation.as_rotvec()[2]
    grid = best + np.linspace(-0.01, 0.01, 41)
    costs = [cost(g) for g in grid]
    assert int(np.argmin(costs)) == 20 and cost(best) <= min(costs)
    rotated = fit.rotation.apply(np.array(noisy.position))
    np.testing.assert_allclose(fit.translation, (ref.position - rotated).mean(axis=0))


def test_reflection_case_by_hand() -> None:
    # Six points ±a e_x, ±b e_y, ±c e_z (a > b > c) and their mirror image z → −z. Then
    # Σ_xy = diag(a², b², −c²)/3 = U D Vᵀ with U = diag(1, 1, −1), V = I: U Vᵀ is the reflection.
    # Umeyama's S = diag(1, 1, det U det V) = diag(1, 1, −1) gives R = U S Vᵀ = I, t = 0 and
    # s = tr(D S) / σx² = (a² + b² − c²) / (a² + b² + c²) = (9 + 4 − 1) / 14 = 6/7.
    a, b, c = 3.0, 2.0, 1.0
    x = np.array([[a, 0, 0], [-a, 0, 0], [0, b, 0], [0, -b, 0], [0, 0, c], [0, 0, -c]])
    mirror = x * [1.0, 1.0, -1.0]
    est, ref = poses(x, Rotation.identity(6)), poses(mirror, Rotation.identity(6))
    sim3 = ik.eval.align(est, ref, method="sim3")
    np.testing.assert_allclose(sim3.rotation.as_matrix(), np.eye(3), atol=1e-15)
    np.testing.assert_allclose(sim3.translation, 0.0, atol=1e-15)
    assert sim3.scale == pytest.approx(6.0 / 7.0, rel=1e-15)
    # the naive U Vᵀ would be the reflection itself (det −1): not a rotation
    u, _, vt = np.linalg.svd(mirror.T @ x / 6)
    assert np.linalg.det(u @ vt) == pytest.approx(-1.0)


def test_reflection_case_agrees_with_scipy_kabsch(rng: np.random.Generator) -> None:
    x = rng.normal(size=(50, 3)) * [5.0, 2.0, 1.0]
    y = TRANSFORM.apply(x * [1.0, 1.0, -1.0]) + SHIFT  # a mirrored copy: no rotation fits it exactly
    fit = ik.eval.align(poses(x, Rotation.identity(50)), poses(y, Rotation.identity(50)), method="se3")
    kabsch, _ = Rotation.align_vectors(y - y.mean(axis=0), x - x.mean(axis=0))
    assert (fit.rotation.inv() * kabsch).magnitude() < 1e-10
    assert np.linalg.det(fit.rotation.as_matrix()) == pytest.approx(1.0, abs=1e-12)


def test_apply_transforms_positions_rotations_and_scales_velocities(ref: ik.Trajectory) -> None:
    alignment = ik.eval.Alignment(TRANSFORM, SHIFT, 2.0, "sim3")
    out = alignment.apply(ref)
    np.testing.assert_allclose(out.position, 2.0 * TRANSFORM.apply(np.array(ref.position)) + SHIFT, atol=1e-12)
    assert out.velocity is not None and ref.velocity is not None
    np.testing.assert_allclose(out.velocity, 2.0 * TRANSFORM.apply(np.array(ref.velocity)), atol=1e-12)
    assert ((TRANSFORM * ref.rotation).inv() * out.rotation).magnitude().max() < 1e-14
    np.testing.assert_array_equal(out.t, ref.t)


@pytest.mark.parametrize("method", ["se3", "sim3"])
@pytest.mark.parametrize(
    ("points", "message"),
    [
        ([[0.0, 0, 0], [1, 0, 0]], "needs at least 3 non-collinear positions, got 2"),
        ([[0.0, 0, 0], [1, 1, 1], [2, 2, 2], [5, 5, 5]], "singular values"),
        ([[1.0, 2, 3]] * 4, "singular values"),
    ],
)
def test_degenerate_umeyama_input_is_refused(method: str, points: list[list[float]], message: str) -> None:
    traj = poses(np.array(points), Rotation.identity(len(points)))
    with pytest.raises(ik.ParameterError, match=f"^estimate.*{message}"):
        ik.eval.align(traj, traj, method=method)


def test_too_few_paired_samples_for_umeyama_name_the_association(ref: ik.Trajectory) -> None:
    # shifted back by 1.03 s, only the estimate's last 2 samples fall inside the reference
    late = ik.Trajectory(ref.t[:5] + 1.0, ref.position[:5], None, ref.rotation[:5])
    message = r"^offset: se3 alignment needs at least 3 paired samples, but only 2 of 5 estimate samples"
    with pytest.raises(ik.ParameterError, match=message):
        ik.eval.ape(late, ref, offset=-1.03)
    assert ik.eval.ape(late, ref, offset=-1.03, align="position").translation.shape == (2,)


def test_degenerate_yaw_input_is_refused() -> None:
    vertical = poses(np.outer(np.arange(5.0), [0.0, 0.0, 1.0]), Rotation.identity(5))
    with pytest.raises(ik.ParameterError, match=r"^estimate / reference: yaw alignment needs") as info:
        ik.eval.align(vertical, vertical, method="yaw")
    assert info.value.argument == "estimate / reference"  # None before 2026-12-07


def test_bad_arguments(ref: ik.Trajectory) -> None:
    with pytest.raises(ik.ParameterError, match=r"^method: expected one of"):
        ik.eval.align(ref, ref, method="sim2")
    for metric in (ik.eval.ape, ik.eval.rpe):
        with pytest.raises(ik.ParameterError, match=r"^align: expected one of"):
            metric(ref, ref, align="umeyama")
    with pytest.raises(ik.ShapeError, match=r"^estimate / reference: expected equally long") as info:
        ik.eval.align(poses(ref.position[:10], ref.rotation[:10]), ref)
    assert info.value.argument == "estimate / reference"
    with pytest.raises(ik.ParameterError, match=r"^trajectory: expected an imukit Trajectory"):
        ik.eval.Alignment(TRANSFORM, SHIFT, 1.0, "se3").apply(ref.position)  # type: ignore[arg-type]
