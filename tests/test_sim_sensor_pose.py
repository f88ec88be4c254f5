"""``sim.simulate(..., body_from_sensor=(R_bs, r))``: the readings of a sensor mounted off the body
origin and rotated. Expected readings are written here from rigid-body kinematics (Titterton &
Weston 2004, eq. 3.48), ``ω_s = R_bsᵀ ω_b``, ``f_s = R_bsᵀ (f_b + α × r + ω × (ω × r))``: for a
constant twist ``α = 0``; for a figure eight ``α`` is the derivative of the body rate, taken here by
scipy's spline of the simulated body rate at 1 kHz.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

import imukit as ik

R_BS = Rotation.from_euler("ZYX", [90, 10, -20], degrees=True)
ARM = np.array([0.3, -0.1, 0.05])
TWIST = ik.sim.ConstantTwist(body_velocity=(1.0, 0.0, 0.2), body_rate=(0.1, -0.05, 2.0))


def expected(body: ik.ImuData, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    w = np.array(body.gyro)
    f = body.accel + np.cross(alpha, ARM) + np.cross(w, np.cross(w, ARM))
    return R_BS.inv().apply(w), R_BS.inv().apply(f)


def test_constant_twist_readings_are_the_rigid_body_ones() -> None:
    body, _ = ik.sim.simulate(TWIST, rate=200.0, duration=2.0)
    sensor, truth = ik.sim.simulate(TWIST, rate=200.0, duration=2.0, body_from_sensor=(R_BS, ARM))
    gyro, accel = expected(body, np.zeros_like(body.gyro))
    assert np.abs(sensor.gyro - gyro).max() < 1e-14
    assert np.abs(sensor.accel - accel).max() < 1e-13  # measured 1.8e-15: the stencil's α of a constant rate
    assert np.array_equal(truth.position, ik.sim.simulate(TWIST, rate=200.0, duration=2.0)[1].position)


def test_figure_eight_angular_acceleration_enters() -> None:
    motion = ik.sim.FigureEight()
    body, _ = ik.sim.simulate(motion, rate=1000.0, duration=6.0)
    sensor, _ = ik.sim.simulate(motion, rate=1000.0, duration=6.0, body_from_sensor=(R_BS, ARM))
    alpha = CubicSpline(body.t, body.gyro).derivative()(body.t)
    gyro, accel = expected(body, alpha)
    inner = slice(50, -50)  # away from the spline's ends
    assert np.abs(sensor.gyro - gyro).max() < 1e-14
    tangential = np.abs(np.cross(alpha, ARM)).max()
    assert tangential > 0.05  # the α term matters here
    assert np.abs(sensor.accel - accel)[inner].max() < 1e-10  # measured 1.6e-13


def test_integrate_recovers_the_body_and_without_the_arm_errs_as_predicted() -> None:
    sensor, truth = ik.sim.simulate(TWIST, rate=400.0, duration=10.0, body_from_sensor=(R_BS, ARM))
    x0 = ik.NavState(truth.position[0], truth.velocity[0], truth.rotation[0])
    out = ik.integrate(sensor, initial=x0, body_from_sensor=(R_BS, ARM))
    assert np.abs(out.position - truth.position).max() < 5e-5  # measured 2.0e-5 (midpoint, central-difference α)
    assert (out.rotation * truth.rotation.inv()).magnitude().max() < 1e-10
    # Rotation only: the integrated point is the sensor's path started with the body's velocity.
    off = ik.integrate(sensor, initial=x0, body_from_sensor=(R_BS, np.zeros(3)))
    t = truth.t[:, None]
    r0 = truth.rotation[0]
    rate = np.array(TWIST.body_rate)
    predicted = truth.rotation.apply(ARM) - r0.apply(ARM) - t * r0.apply(np.cross(rate, ARM))
    error = off.position - truth.position
    assert np.abs(error).max() > 3.0
    assert np.abs(error - predicted).max() < 1e-4  # measured 2.5e-5 of 5.6 m


def test_sensor_pose_is_checked() -> None:
    with pytest.raises(ik.ParameterError) as info:
        ik.sim.simulate(TWIST, rate=100.0, duration=1.0, body_from_sensor=(R_BS, ARM, 1))  # type: ignore[arg-type]
    assert info.value.argument == "body_from_sensor"
    moving = ik.LocalLevel(0.7, transport=True)
    with pytest.raises(ik.ParameterError) as info:
        ik.sim.simulate(TWIST, rate=100.0, duration=1.0, frame=moving, body_from_sensor=(R_BS, ARM))
    assert info.value.argument == "body_from_sensor"
