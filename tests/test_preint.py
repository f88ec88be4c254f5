"""Preintegration from Python: prediction equals strapdown integration, residual zero at the
prediction and first-order in a perturbation, streaming equals batch, bias correction."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from trajectories import attitude, body_rate, position, specific_force, velocity

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)


def window() -> tuple[ik.ImuData, ik.NavState]:
    t = np.linspace(0.0, 1.0, 201)
    z = np.zeros(1)
    return ik.ImuData(t, body_rate(t), specific_force(t)), ik.NavState(position(z)[0], velocity(z)[0], attitude(z)[0])


def test_predict_equals_strapdown_euler() -> None:
    """The preintegrated prediction and the euler strapdown step are the same discrete model."""
    imu, x0 = window()
    bias = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.1, 0.05, -0.2])
    pim = ik.preintegrate(imu, noise=NOISE, bias=bias)
    pred = pim.predict(x0)
    traj = ik.integrate(imu, initial=x0, bias=bias, scheme="euler")
    assert np.abs(pred.position - traj.position[-1]).max() < 1e-11
    assert np.abs(pred.velocity - traj.velocity[-1]).max() < 1e-11
    assert (pred.rotation.inv() * traj.rotation[-1]).magnitude() < 1e-12
    assert pim.delta_t == pytest.approx(1.0, abs=1e-15)


def test_residual_is_zero_at_the_prediction_and_linear_nearby() -> None:
    imu, x0 = window()
    pim = ik.preintegrate(imu, noise=NOISE)
    xj = pim.predict(x0)
    assert np.abs(pim.residual(x0, xj)).max() < 1e-12
    moved = ik.NavState(
        xj.position + np.array([0.01, 0.0, 0.0]), xj.velocity, xj.rotation * Rotation.from_rotvec([0, 0, 1e-3])
    )
    r = pim.residual(x0, moved)
    assert r[2] == pytest.approx(1e-3, rel=1e-9)  # δθ_z
    assert np.abs(r[6:9] - x0.rotation.inv().apply([0.01, 0.0, 0.0])).max() < 1e-12


def test_streaming_equals_batch() -> None:
    imu, _ = window()
    batch = ik.preintegrate(imu, noise=NOISE)
    stream = ik.PreintegratedImu(noise=NOISE)
    for k in range(len(imu) - 1):
        stream.integrate_measurement(imu.accel[k], imu.gyro[k], imu.seconds[k + 1] - imu.seconds[k])
    assert np.array_equal(stream.delta_position, batch.delta_position)
    assert np.array_equal(stream.covariance, batch.covariance)
    assert np.array_equal(stream.bias_jacobian, batch.bias_jacobian)
    cov = batch.covariance
    assert np.array_equal(cov, cov.T) and np.all(np.linalg.eigvalsh(cov) > 0)


def test_corrected_is_first_order_in_the_bias_change() -> None:
    imu, _ = window()
    pim = ik.preintegrate(imu, noise=NOISE)
    gaps = []
    for s in (1e-2, 5e-3):
        b = ik.ImuBias(gyro=np.array([0.3, -0.5, 0.2]) * s, accel=np.array([-0.4, 0.1, 0.6]) * s)
        r, v, p = pim.corrected(b)
        exact = ik.preintegrate(imu, noise=NOISE, bias=b)
        gaps.append(
            max(
                (r.inv() * exact.delta_rotation).magnitude(),
                np.abs(v - exact.delta_velocity).max(),
                np.abs(p - exact.delta_position).max(),
            )
        )
    assert 3.5 < gaps[0] / gaps[1] < 4.5  # quadratic remainder


def test_bad_input() -> None:
    imu, _ = window()
    pim = ik.PreintegratedImu(noise=NOISE)
    with pytest.raises(ik.ParameterError, match="dt"):
        pim.integrate_measurement([0, 0, 9.81], [0, 0, 0], 0.0)
    with pytest.raises(ik.NonFiniteError, match="gyro"):
        pim.integrate_measurement([0, 0, 9.81], [0, np.nan, 0], 0.005)
    with pytest.raises(ik.ShapeError, match="accel"):
        pim.integrate_measurement([0, 9.81], [0, 0, 0], 0.005)
    with pytest.raises(ik.ParameterError, match="scheme"):
        ik.preintegrate(imu, noise=NOISE, scheme="rk4")
    assert pim.delta_t == 0.0  # nothing was added by the refused calls


def test_combined_covariance() -> None:
    imu, _ = window()
    plain = ik.preintegrate(imu, noise=NOISE)
    assert plain.covariance_combined is None
    pim = ik.preintegrate(imu, noise=NOISE, combined=True)
    c = pim.covariance_combined
    assert c is not None and c.shape == (15, 15)
    assert np.array_equal(c, c.T)
    # the bias blocks are the accumulated random walk: σ² Δt on the diagonal
    assert np.allclose(np.diag(c)[9:12], NOISE.gyro_random_walk**2 * pim.delta_t, rtol=1e-12)
    assert np.allclose(np.diag(c)[12:15], NOISE.accel_random_walk**2 * pim.delta_t, rtol=1e-12)
    # the walk adds to the 9×9 part, and the cross terms are nonzero
    assert np.all(np.diag(c)[:9] > np.diag(plain.covariance))
    assert np.abs(c[:9, 9:]).max() > 0
    assert np.all(np.linalg.eigvalsh(c) > 0)


def test_merge_equals_one_preintegration() -> None:
    imu, x0 = window()
    whole = ik.preintegrate(imu, noise=NOISE)
    merged = ik.preintegrate(imu[:81], noise=NOISE).merge(ik.preintegrate(imu[80:], noise=NOISE))
    assert merged.delta_t == pytest.approx(whole.delta_t, abs=1e-15)
    assert np.abs(merged.delta_position - whole.delta_position).max() < 1e-13
    assert np.abs(merged.covariance - whole.covariance).max() < 1e-12 * np.abs(whole.covariance).max()
    assert np.abs(merged.bias_jacobian - whole.bias_jacobian).max() < 1e-12 * np.abs(whole.bias_jacobian).max()
    pred = merged.predict(x0)
    assert np.abs(pred.position - whole.predict(x0).position).max() < 1e-12
    with pytest.raises(ik.ParameterError, match="same bias"):
        whole.merge(ik.preintegrate(imu, noise=NOISE, bias=ik.ImuBias(gyro=[0.1, 0, 0])))


def test_reintegrate_replays_the_samples_with_the_new_bias() -> None:
    imu, _ = window()
    b = ik.ImuBias(gyro=[0.02, -0.01, 0.03], accel=[0.2, -0.1, 0.05])
    pim = ik.PreintegratedImu(noise=NOISE)
    pim.integrate(imu[:101])
    for k in range(100, len(imu) - 1):  # and a streamed tail
        pim.integrate_measurement(imu.accel[k], imu.gyro[k], imu.seconds[k + 1] - imu.seconds[k])
    again = pim.reintegrate(b)
    fresh = ik.preintegrate(imu, noise=NOISE, bias=b)
    assert again.bias == b
    assert np.abs(again.delta_position - fresh.delta_position).max() < 1e-13
    assert np.abs(again.covariance - fresh.covariance).max() < 1e-12 * np.abs(fresh.covariance).max()
    # and it is better than the first-order correction for this bias change
    _, _, p_first_order = pim.corrected(b)
    assert np.abs(p_first_order - fresh.delta_position).max() > 1e-6
