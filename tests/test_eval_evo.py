"""imukit.eval against the peer evo (APE, RPE, Umeyama, association), on synthetic and real trajectories.

Where the definitions coincide (synchronised stamps: no interpolation) the numbers must be equal to
1e-9. Where they differ on purpose (interpolating association, gaps, evo's all-pairs distance rule)
the tests show the difference.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

import imukit as ik
from euroc import DATA, GT_CSV

evo = pytest.importorskip("evo", reason="evo (a test dependency, Python ≥ 3.11) is not installed")
from evo.core import filters, metrics, sync  # noqa: E402
from evo.core.sync_method import SyncMethod  # noqa: E402
from evo.core.trajectory import PoseTrajectory3D  # noqa: E402

KITTI_POSES = DATA.parent / "kitti_gtsam" / "KITTI_00_gt_poses_evo.txt"
KITTI_TIMES = DATA.parent / "kitti_gtsam" / "KITTI_00_gt_times_evo.txt"
STATS = ("rmse", "mean", "median", "std", "min", "max")
TRANSFORM = Rotation.from_rotvec([0.05, -0.1, 2.0])
SHIFT = np.array([3.0, -1.0, 0.4])


def to_evo(traj: ik.Trajectory) -> PoseTrajectory3D:
    return PoseTrajectory3D(
        positions_xyz=np.array(traj.position),
        orientations_quat_wxyz=traj.rotation.as_quat(scalar_first=True),
        timestamps=np.array(traj.t),
    )


def perturbed(
    ref: ik.Trajectory, rng: np.random.Generator, *, scale: float = 1.0, sigma: float = 0.01
) -> ik.Trajectory:
    """``ref`` in another world (TRANSFORM, SHIFT, ``scale``) with σ [m] position and σ [rad] attitude noise."""
    n = len(ref)
    noisy = np.array(ref.position) + rng.normal(0.0, sigma, (n, 3))
    rotation = TRANSFORM * ref.rotation * Rotation.from_rotvec(rng.normal(0.0, sigma, (n, 3)))
    t_s = None if ref.t_ns is not None else ref.t
    return ik.Trajectory(t_s, scale * TRANSFORM.apply(noisy) + SHIFT, None, rotation, t_ns=ref.t_ns)


def evo_ape(ref: PoseTrajectory3D, est: PoseTrajectory3D, relation: metrics.PoseRelation) -> dict[str, float]:
    metric = metrics.APE(relation)
    metric.process_data((ref, est))
    return metric.get_all_statistics()


def assert_stats_equal(ours: ik.eval.ErrorStats, theirs: dict[str, float], what: str) -> None:
    for name in STATS:
        assert getattr(ours, name) == pytest.approx(theirs[name], abs=1e-9), f"{what} {name}"


def assert_ape_equals_evo(est: ik.Trajectory, ref: ik.Trajectory, method: str) -> ik.eval.AbsoluteError:
    ours = ik.eval.ape(est, ref, align=method)
    ref_evo, est_evo = to_evo(ref), to_evo(est)
    if method != "none":
        r, t, s = est_evo.align(ref_evo, correct_scale=method == "sim3")
        np.testing.assert_allclose(ours.alignment.rotation.as_matrix(), r, atol=1e-9)
        np.testing.assert_allclose(ours.alignment.translation, t, atol=1e-9)
        assert ours.alignment.scale == pytest.approx(s, abs=1e-12)
    assert_stats_equal(ours.translation_stats, evo_ape(ref_evo, est_evo, metrics.PoseRelation.translation_part), "t")
    assert_stats_equal(ours.rotation_stats, evo_ape(ref_evo, est_evo, metrics.PoseRelation.rotation_angle_rad), "R")
    return ours


def evo_rpe(
    ref: ik.Trajectory, est: ik.Trajectory, relation: metrics.PoseRelation, delta: float, unit: str, all_pairs: bool
) -> metrics.RPE:
    evo_unit = {"m": metrics.Unit.meters, "frames": metrics.Unit.frames}[unit]
    metric = metrics.RPE(relation, delta, evo_unit, all_pairs=all_pairs, pairs_from_reference=True)
    metric.process_data((to_evo(ref), to_evo(est)))
    return metric


def assert_rpe_equals_evo(est: ik.Trajectory, ref: ik.Trajectory, delta: float, unit: str, all_pairs: bool) -> None:
    ours = ik.eval.rpe(est, ref, delta=delta, unit=unit, all_pairs=all_pairs)
    t = evo_rpe(ref, est, metrics.PoseRelation.translation_part, delta, unit, all_pairs)
    r = evo_rpe(ref, est, metrics.PoseRelation.rotation_angle_rad, delta, unit, all_pairs)
    np.testing.assert_array_equal(ours.pairs[:, 1], t.delta_ids)
    np.testing.assert_allclose(ours.translation, t.error, atol=1e-9, rtol=0)
    np.testing.assert_allclose(ours.rotation, r.error, atol=1e-9, rtol=0)
    assert_stats_equal(ours.translation_stats, t.get_all_statistics(), "t")


@pytest.fixture
def walk(rng: np.random.Generator) -> ik.Trajectory:
    n = 500
    return ik.Trajectory(
        np.arange(n) * 0.1,
        np.cumsum(rng.normal(0.0, 0.2, (n, 3)), axis=0),
        None,
        Rotation.from_rotvec(np.cumsum(rng.normal(0.0, 0.05, (n, 3)), axis=0)),
    )


@pytest.mark.parametrize("method", ["none", "se3", "sim3"])
def test_ape_and_alignment_equal_evo(rng: np.random.Generator, walk: ik.Trajectory, method: str) -> None:
    ours = assert_ape_equals_evo(perturbed(walk, rng, scale=0.7), walk, method)
    if method == "sim3":
        assert ours.alignment.scale == pytest.approx(1 / 0.7, rel=1e-2)


@pytest.mark.parametrize(("delta", "unit"), [(1, "frames"), (7, "frames"), (2.0, "m"), (10.0, "m")])
def test_rpe_equals_evo(rng: np.random.Generator, walk: ik.Trajectory, delta: float, unit: str) -> None:
    est = perturbed(walk, rng)
    assert_rpe_equals_evo(est, walk, delta, unit, all_pairs=False)
    if unit == "frames":
        assert_rpe_equals_evo(est, walk, delta, unit, all_pairs=True)


def test_all_pairs_over_distance_differs_from_evo_on_purpose(rng: np.random.Generator, walk: ik.Trajectory) -> None:
    # evo takes, from every i, the j whose distance is *closest* to delta (kept when within 10 %);
    # imukit the first j that *reaches* delta, as in the consecutive case: its separations are never short.
    ours = ik.eval.rpe(perturbed(walk, rng), walk, delta=2.0, unit="m", all_pairs=True)
    theirs = np.array(filters.filter_pairs_by_path(to_evo(walk).poses_se3, 2.0, 0.2, all_pairs=True))
    distance = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(walk.position, axis=0), axis=1))])
    np.testing.assert_allclose(ours.separation, distance[ours.pairs[:, 1]] - distance[ours.pairs[:, 0]], rtol=1e-12)
    assert ours.separation.min() >= 2.0
    evo_separation = distance[theirs[:, 1]] - distance[theirs[:, 0]]
    assert evo_separation.min() < 2.0 and evo_separation.max() <= 2.2


def smooth(t: np.ndarray) -> ik.Trajectory:
    """A circle of radius 2 m at 1 rad/s (2 m/s), heading along the motion, 0.3 m vertical wobble."""
    position = np.stack([2 * np.cos(t), 2 * np.sin(t), 0.3 * np.sin(3 * t)], axis=1)
    return ik.Trajectory(t, position, None, Rotation.from_rotvec(np.outer(t + np.pi / 2, [0.0, 0.0, 1.0])))


def test_interpolating_association_beats_evos_nearest_stamp_on_offset_stamps() -> None:
    ref = smooth(np.arange(0, 2001) * 0.005)  # 200 Hz reference
    est = smooth(np.arange(0, 400) * 0.025 + 0.0025)  # 40 Hz truth, stamps halfway between reference ones
    ours = ik.eval.ape(est, ref, align="none")
    # a chord's sag over a step dt is at most |p̈| dt² / 8; |p̈| ≤ √(2² + 2.7²) m/s² (circle, wobble): 1.05e-5 m
    assert ours.n_dropped == 0 and ours.translation_stats.max < 1.06e-5 and ours.rotation_stats.max < 1e-12
    ref_e, est_e = sync.associate_trajectories(to_evo(ref), to_evo(est), max_diff=0.01)
    nearest = evo_ape(ref_e, est_e, metrics.PoseRelation.translation_part)
    # nearest reference sample is 2.5 ms away: ≈ 2 m/s × 2.5 ms = 5 mm (plus the vertical wobble's share)
    assert nearest["min"] > 4.9e-3 and nearest["max"] < 5.5e-3
    # evo's interpolating sync (1.38+) resamples the reference exactly like imukit where there is no gap
    ref_i, est_i = sync.associate_trajectories(
        to_evo(ref), to_evo(est), max_diff=0.01, sync_method=SyncMethod.interpolation
    )
    interp = evo_ape(ref_i, est_i, metrics.PoseRelation.translation_part)
    assert_stats_equal(ours.translation_stats, interp, "t")


def test_gaps_are_dropped_where_evo_interpolates_across_them() -> None:
    t = np.arange(0, 2001) * 0.005
    keep = (t < 4.0) | (t > 4.5)  # a 0.5 s reference dropout
    ref = smooth(t[keep])
    est = smooth(np.arange(0, 400) * 0.025 + 0.0025)
    ours = ik.eval.ape(est, ref, align="none")
    before, after = ref.t[ref.t < 4.0][-1], ref.t[ref.t > 4.5][0]  # 3.995 s, 4.505 s
    assert ours.n_dropped == int(((est.t > before) & (est.t < after)).sum()) == 21
    assert (ours.n_in_gaps, ours.n_outside_span) == (21, 0)
    np.testing.assert_array_equal(ours.mask, (est.t < before) | (est.t > after))
    assert ours.translation_stats.max < 1.06e-5
    ref_i, est_i = sync.associate_trajectories(
        to_evo(ref), to_evo(est), max_diff=0.01, sync_method=SyncMethod.interpolation
    )
    # evo keeps the two estimate stamps within 10 ms of the gap's edges (4.0025 s, 4.5025 s) and
    # interpolates them on the chord across the dropout
    assert est_i.num_poses == len(est) - 21 + 2
    # 7.5 ms into the 510 ms chord the sag is a few mm (3.8 mm measured), 300 times our interpolation error
    assert evo_ape(ref_i, est_i, metrics.PoseRelation.translation_part)["max"] > 2e-3


requires_euroc_gt = pytest.mark.skipif(not GT_CSV.exists(), reason=f"EuRoC ground truth not found at {GT_CSV}")
requires_kitti = pytest.mark.skipif(not KITTI_POSES.exists(), reason=f"KITTI poses not found at {KITTI_POSES}")


@requires_euroc_gt
def test_euroc_groundtruth_perturbed_equals_evo(rng: np.random.Generator) -> None:
    gt = ik.io.read_euroc_groundtruth(GT_CSV)
    est = perturbed(gt, rng)
    ours = assert_ape_equals_evo(est, gt, "se3")
    # the known transform is recovered through 1 cm / 0.01 rad noise on 16 700 samples
    expected_rotation = TRANSFORM.inv()
    assert (ours.alignment.rotation * expected_rotation.inv()).magnitude() < 1e-3
    assert ours.translation_stats.rmse == pytest.approx(0.01 * np.sqrt(3), rel=0.05)
    assert_rpe_equals_evo(est, gt, 1.0, "m", all_pairs=False)


@requires_euroc_gt
def test_euroc_offset_stamps_interpolated_exactly() -> None:
    gt = ik.io.read_euroc_groundtruth(GT_CSV)
    assert gt.t_ns is not None
    # an estimate at 50 Hz on stamps 2.5 ms after ground-truth ones (halfway between 200 Hz samples):
    # the truth there, interpolated independently with numpy and scipy's Slerp
    t_ns = gt.t_ns[10:-10:4] + 2_500_000
    rel = (gt.t_ns - gt.t_ns[0]).astype(float)
    at = (t_ns - gt.t_ns[0]).astype(float)
    position = np.stack([np.interp(at, rel, c) for c in gt.position.T], axis=1)
    est = ik.Trajectory(None, position, None, Slerp(rel, gt.rotation)(at), t_ns=t_ns)
    ours = ik.eval.ape(est, gt, align="none")
    assert ours.n_dropped == 0
    assert ours.translation_stats.max < 1e-12 and ours.rotation_stats.max < 1e-12
    ref_e, est_e = sync.associate_trajectories(to_evo(gt), to_evo(est), max_diff=0.01)
    nearest = evo_ape(ref_e, est_e, metrics.PoseRelation.translation_part)
    assert nearest["rmse"] > 1e-4  # half a 200 Hz step of motion: ~1 mm at this dataset's speeds


@requires_kitti
def test_kitti_sim3_and_rpe_over_100_m_equal_evo(rng: np.random.Generator) -> None:
    rows = np.loadtxt(KITTI_POSES).reshape(-1, 3, 4)
    t = np.loadtxt(KITTI_TIMES)
    gt = ik.Trajectory(t, rows[:, :, 3], None, Rotation.from_matrix(rows[:, :, :3]))
    est = perturbed(gt, rng, scale=0.5, sigma=0.1)
    ours = assert_ape_equals_evo(est, gt, "sim3")
    assert ours.alignment.scale == pytest.approx(2.0, rel=1e-3)
    assert_rpe_equals_evo(est, gt, 100.0, "m", all_pairs=False)
    assert_rpe_equals_evo(est, gt, 10, "frames", all_pairs=True)
