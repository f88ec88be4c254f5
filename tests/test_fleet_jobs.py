"""The ``filter`` and ``preintegrate`` jobs as plain functions, against the library called directly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit import fleet, sim
from imukit.fleet import JOBS

NOISE = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)


@pytest.fixture(scope="module")
def moving(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, ik.ImuData, ik.Trajectory]:
    imu, truth = sim.simulate(sim.FigureEight(roll=0.2), rate=200.0, duration=20.0, noise=NOISE, seed=5)
    folder = tmp_path_factory.mktemp("jobs") / "log"
    ik.io.write_euroc(folder, imu, truth, noise=NOISE, rate_hz=200.0)
    return folder, imu, truth


def test_filter_job_scores_against_the_truth(moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    folder, imu, truth = moving
    output = JOBS["filter"](folder, method="madgwick")
    # The same filter on the same samples, scored against the simulated truth at the same instants
    # (no interpolation): the job's association must reproduce it.
    result = ik.filters.Madgwick().run(imu)
    rmse = ik.eval.attitude_error(result.rotation, truth.rotation, align_heading=True).rmse(degrees=True)
    assert output.scalars["scored_samples"] == len(imu)
    assert output.scalars["rmse_inclination_deg"] == pytest.approx(rmse.inclination, rel=1e-6)
    assert output.scalars["rmse_total_deg"] == pytest.approx(rmse.total, rel=1e-6)
    # The figure eight accelerates sideways, which tilts the accelerometer's gravity reference by degrees.
    assert 0.5 < rmse.inclination < 10.0
    assert output.rows is not None
    np.testing.assert_allclose(output.rows["q_xyzw"], result.rotation.as_quat(), rtol=0, atol=1e-12)


def test_filter_job_refuses_an_unknown_method(moving: tuple[Path, ik.ImuData, ik.Trajectory]) -> None:
    with pytest.raises(ik.ParameterError, match="method: expected one of mahony, madgwick"):
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
    assert 0.0 < final < 5.0  # white noise and a bias random walk over 20 s, true initial bias
    with pytest.raises(ik.ParameterError, match="no ground truth"):
        JOBS["integrate"](next(folder.rglob("imu0/data.csv")))
