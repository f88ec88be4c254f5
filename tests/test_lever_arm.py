"""``integrate(..., body_from_sensor=(R_bs, r))``: an IMU mounted 0.3 m off the body origin and
rotated, on a spinning body (``sim.ConstantTwist``, 2 rad/s about a tilted axis). The sensor's
readings are written here from rigid-body kinematics (Titterton & Weston 2004, eq. 3.48):
``ω_s = R_bsᵀ ω_b``, ``f_s = R_bsᵀ (f_b + α × r + ω × (ω × r))`` with ``α = 0`` for a constant twist.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

Array = npt.NDArray[np.float64]
R_BS = Rotation.from_euler("ZYX", [90, 10, -20], degrees=True)
ARM = np.array([0.3, 0.0, 0.0])
RATE = np.array([0.1, -0.05, 2.0])


def spinning(rate_hz: float, duration: float = 10.0) -> tuple[ik.ImuData, ik.Trajectory]:
    """The sensor's readings and the body's truth."""
    body, truth = ik.sim.simulate(
        ik.sim.ConstantTwist(body_velocity=(1.0, 0.0, 0.2), body_rate=RATE), rate=rate_hz, duration=duration
    )
    centripetal = np.cross(body.gyro, np.cross(body.gyro, ARM))
    sensor = ik.ImuData(body.t, R_BS.inv().apply(np.array(body.gyro)), R_BS.inv().apply(body.accel + centripetal))
    return sensor, truth


def start(truth: ik.Trajectory) -> ik.NavState:
    return ik.NavState(truth.position[0], truth.velocity[0], truth.rotation[0])


def test_body_trajectory_recovered_to_the_integrators_order() -> None:
    """Measured at 200 / 400 Hz over 10 s: 8.1e-5 / 2.0e-5 m (midpoint: second order) and
    attitude 1.5e-14 rad; without the lever-arm terms the error is 5.7 m (next test)."""
    errors = []
    for rate_hz in (200.0, 400.0):
        sensor, truth = spinning(rate_hz)
        out = ik.integrate(sensor, initial=start(truth), body_from_sensor=(R_BS, ARM))
        errors.append(float(np.abs(out.position - truth.position).max()))
        assert (out.rotation * truth.rotation.inv()).magnitude().max() < 1e-10
    assert errors[0] < 1e-4
    assert 3.5 < errors[0] / errors[1] < 4.5


def test_without_the_lever_arm_the_error_is_the_predicted_centripetal_term() -> None:
    """Rotation only (zero lever arm): the integrated point moves as ``p_b + R r − R₀ r −
    t R₀ (ω × r)`` (the sensor's path, started with the body's velocity): the error matches that
    prediction to the integrator's error (measured 8.5e-5 m of 5.7 m)."""
    sensor, truth = spinning(200.0)
    out = ik.integrate(sensor, initial=start(truth), body_from_sensor=(R_BS, np.zeros(3)))
    t = truth.t[:, None]
    r0 = truth.rotation[0]
    predicted = truth.rotation.apply(ARM) - r0.apply(ARM) - t * r0.apply(np.cross(RATE, ARM))
    error = out.position - truth.position
    assert np.abs(error).max() > 5.0
    assert np.abs(error - predicted).max() < 2e-4


def test_body_from_sensor_is_checked() -> None:
    sensor, truth = spinning(50.0, 1.0)
    with pytest.raises(ik.ParameterError, match="body_from_sensor"):
        ik.integrate(sensor, initial=start(truth), body_from_sensor=R_BS)  # type: ignore[arg-type]
    with pytest.raises(ik.ShapeError, match="body_from_sensor"):
        ik.integrate(sensor, initial=start(truth), body_from_sensor=(R_BS, [0.3, 0.0]))


def test_propagate_takes_the_rotation() -> None:
    """``propagate`` with a rotated sensor: the mean is ``integrate``'s (bit for bit) and the
    covariance is that of the readings rotated by hand (isotropic noise); the lever arm's own
    terms are tested in test_propagate_lever_arm.py."""
    sensor, truth = spinning(100.0, 2.0)
    rotated_only = ik.ImuData(sensor.t, R_BS.apply(np.array(sensor.gyro)), R_BS.apply(np.array(sensor.accel)))
    noise = ik.ImuNoise(gyro_density=1e-3, accel_density=1e-2, gyro_random_walk=1e-5, accel_random_walk=1e-4)
    p0 = np.eye(15) * 1e-4
    out = ik.propagate(sensor, initial=start(truth), covariance=p0, noise=noise, body_from_sensor=(R_BS, np.zeros(3)))
    by_hand = ik.propagate(rotated_only, initial=start(truth), covariance=p0, noise=noise)
    mean = ik.integrate(sensor, initial=start(truth), body_from_sensor=(R_BS, np.zeros(3)))
    assert np.array_equal(out.position, mean.position)
    assert out.covariance is not None and by_hand.covariance is not None
    assert np.abs(out.covariance - by_hand.covariance).max() < 1e-12 * np.abs(by_hand.covariance).max()


@pytest.mark.parametrize("make", [ik.filters.Mahony, ik.filters.Madgwick])
def test_filters_take_the_rotation(make: type) -> None:
    """A filter run on a rotated IMU with ``body_from_sensor`` equals the run on the readings (and
    magnetometer) rotated by hand (measured 3.9e-12 rad: rounding of the two rotations) and
    differs from the plain run by the mounting (the sensor's attitude is ``R_wb R_bs``); a lever
    arm is refused."""
    sensor, _ = spinning(100.0, 2.0)
    mag = R_BS.inv().apply(np.tile([20.0, 5.0, -40.0], (len(sensor), 1)))
    rotated = ik.ImuData(sensor.t, R_BS.apply(np.array(sensor.gyro)), R_BS.apply(np.array(sensor.accel)))
    out = make().run(sensor, mag=mag, body_from_sensor=(R_BS, np.zeros(3)))
    by_hand = make().run(rotated, mag=R_BS.apply(mag))
    assert (out.rotation * by_hand.rotation.inv()).magnitude().max() < 1e-10
    plain = make().run(sensor, mag=mag)
    assert (plain.rotation[-1] * out.rotation[-1].inv()).magnitude() > 0.1
    with pytest.raises(ik.ParameterError, match="lever arm"):
        make().run(sensor, body_from_sensor=(R_BS, ARM))
