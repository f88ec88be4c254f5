"""The ``filter`` and ``preintegrate`` jobs as plain functions, against the library called directly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from fleet_logs import rigidly_moved
from imukit import fleet, sim
from imukit.fleet import JOBS

NOISE = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)


@pytest.fixture(scope="module")
def moving(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, ik.ImuData, ik.Trajectory]:
    imu, truth = sim.simulate(sim.FigureEight(roll=0.2), rate=200.0, duration=20.0, noise=NOISE, seed=5)
    folder = tmp_path_factory.mktemp("jobs") / "log"
    ik.io.write_euroc(folder, imu, truth, noise=NOISE, rate_hz=200.0)
    return folder, imu, truth


@pytest.mark.parametrize("method", ["madgwick", "robust"])
def test_filter_job_scores_against_the_truth(method: str, moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    folder, imu, truth = moving
    output = JOBS["filter"](folder, method=method)
    # The same filter on the same samples, scored against the simulated truth at the same instants
    # (no interpolation): the job's association must reproduce it.
    result = {"madgwick": ik.filters.Madgwick, "robust": ik.filters.Robust}[method]().run(imu)
    rmse = ik.eval.attitude_error(result.rotation, truth.rotation, align_heading=True).rmse(degrees=True)
    assert output.scalars["scored_samples"] == len(imu)
    assert output.scalars["rmse_inclination_deg"] == pytest.approx(rmse.inclination, rel=1e-6)
    assert output.scalars["rmse_total_deg"] == pytest.approx(rmse.total, rel=1e-6)
    # The figure eight accelerates sideways, which tilts the accelerometer's gravity reference by degrees.
    assert 0.5 < rmse.inclination < 10.0
    assert output.rows is not None
    np.testing.assert_allclose(output.rows["q_xyzw"], result.rotation.as_quat(), rtol=0, atol=1e-12)


def test_filter_job_runs_robust_by_default(moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    """The default method is the filter docs/filters_accuracy.md ranks first, not Mahony."""
    folder, imu, _ = moving
    output = JOBS["filter"](folder)
    assert output.rows is not None
    np.testing.assert_array_equal(output.rows["q_xyzw"], ik.filters.Robust().run(imu).rotation.as_quat())
    assert np.abs(output.rows["q_xyzw"] - ik.filters.Mahony().run(imu).rotation.as_quat()).max() > 1e-4


def test_filter_job_scores_a_ned_estimate_in_ned(moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    """The log's truth is z up: a NED estimate was scored against it unturned, 175° (before 2026-12-07)."""
    folder = moving[0]
    enu, ned = (JOBS["filter"](folder, method="madgwick", world=w).scalars for w in ("ENU", "NED"))
    assert 0.5 < float(enu["rmse_inclination_deg"]) < 10.0
    for key in ("rmse_inclination_deg", "rmse_total_deg"):
        assert ned[key] == pytest.approx(enu[key], rel=1e-6), key


def test_filter_job_refuses_an_unknown_method(moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    with pytest.raises(ik.ParameterError, match="method: expected one of mahony, madgwick, robust"):
        JOBS["filter"](moving[0], method="kalman")


def test_preintegrate_job_rows_are_the_windows(moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    folder, imu, _ = moving
    output = fleet.preintegrate(folder, window_s=1.0)
    record = ik.preintegrate_windows(
        imu, ik.preint.regular_boundaries(imu, 1.0), ik.PreintParams(ik.io.find_noise_model(folder))
    )
    assert output.scalars["windows"] == 20 and output.rows is not None
    np.testing.assert_array_equal(output.rows["dp"], record.delta_position)
    np.testing.assert_array_equal(output.rows["covariance"], record.covariance.reshape(20, 81))


def test_integrate_job_is_dead_reckoning_from_the_truth(moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    folder, imu, truth = moving
    scalars = JOBS["integrate"](folder, bias_from_truth=True).scalars
    # The same integration started from the simulated truth's first state with its true bias.
    direct = ik.integrate(imu, initial=truth.state(0), bias=ik.ImuBias(truth.gyro_bias[0], truth.accel_bias[0]))
    final = float(np.linalg.norm(direct.position[-1] - truth.position[-1]))
    assert scalars["samples"] == len(imu) and scalars["scored_samples"] == len(imu)
    assert scalars["final_position_error_m"] == pytest.approx(final, rel=1e-6)
    angles = (truth.rotation.inv() * direct.rotation).magnitude()
    assert scalars["ate_rotation_rmse_deg"] == pytest.approx(np.degrees(np.sqrt(np.mean(angles**2))), rel=1e-6)
    assert 0.0 < final < 5.0  # white noise and a bias random walk over 20 s, true initial bias
    with pytest.raises(ik.ParameterError, match="no ground truth"):
        JOBS["integrate"](next(folder.rglob("imu0/data.csv")))


def test_evaluate_job_scores_an_estimate_against_its_reference(
    moving: tuple[Path, ik.ImuData, ik.Trajectory], tmp_path: Path
) -> None:
    folder, _, _ = moving
    reference = ik.io.read_trajectory(folder)  # the recording folder's ground truth
    offset = [0.3, -0.4, 0.1]
    estimate = rigidly_moved(reference, 10, 10.0, offset)
    ik.io.write_tum(estimate, tmp_path / "est.txt")
    raw = JOBS["evaluate"](tmp_path / "est.txt", reference=folder, align="none")
    s = raw.scalars
    # Unaligned: each pose is off by the frame change. Translation: ‖(R_z − I) p + d‖ per pose; rotation:
    # the angle of R⁻¹ R_z R, which is R_z's, 10°; relative motions T_i⁻¹ T_j are unchanged, RPE 0.
    p = np.array(reference.position[::10])
    expected = np.linalg.norm(Rotation.from_euler("z", 10.0, degrees=True).apply(p) + offset - p, axis=1)
    assert s["estimate_samples"] == s["scored_samples"] == len(p)
    assert s["ate_rmse_m"] == pytest.approx(np.sqrt(np.mean(expected**2)), rel=1e-6)
    assert s["ate_max_m"] == pytest.approx(expected.max(), rel=1e-6)
    assert s["final_position_error_m"] == pytest.approx(expected[-1], rel=1e-6)
    assert s["ate_rotation_rmse_deg"] == pytest.approx(10.0, rel=1e-6)
    assert s["rpe_rmse_m"] < 1e-6 and s["rpe_rotation_rmse_deg"] < 1e-4
    assert raw.rows is not None
    np.testing.assert_allclose(raw.rows["translation_error_m"], expected, rtol=1e-6)
    # se3 alignment (the default) finds the frame change: nothing left.
    aligned = JOBS["evaluate"](tmp_path / "est.txt", reference=folder).scalars
    assert aligned["ate_rmse_m"] < 1e-6 and aligned["ate_rotation_rmse_deg"] < 1e-4
    with pytest.raises(ik.ParameterError, match="reference: the evaluate job needs a reference"):
        JOBS["evaluate"](tmp_path / "est.txt")
