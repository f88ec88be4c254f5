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
from scipy.spatial.transform import Rotation, RotationSpline

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


def test_waypoints_over_their_whole_span() -> None:
    """A sensor pose on ``sim.Waypoints`` from the first waypoint's time to the last: the stencil
    for α reached 2 ms outside the splines, and the whole span was refused (naming ``duration``)
    before 2026-12-07. Near the ends it is one-sided now; α against scipy's own second derivative
    of the rotation spline (``RotationSpline(t, 2)``, body axes as its rate)."""
    times = np.array([0.0, 1.0, 2.5, 4.0])
    rotations = Rotation.from_euler("ZYX", [[0, 0, 0], [40, 10, -5], [100, -20, 15], [150, 5, 0]], degrees=True)
    positions = np.array([[0, 0, 0], [1, 0.5, 0.1], [2, -0.5, 0.3], [3, 0, 0]], dtype=float)
    motion = ik.sim.Waypoints(times, positions, rotations)
    body, _ = ik.sim.simulate(motion, rate=200.0, duration=4.0)
    sensor, _ = ik.sim.simulate(motion, rate=200.0, duration=4.0, body_from_sensor=(R_BS, ARM))
    assert len(sensor) == 801 and sensor.t[-1] == 4.0
    alpha = RotationSpline(times, rotations)(body.t, 2)
    gyro, accel = expected(body, alpha)
    assert np.abs(sensor.gyro - gyro).max() < 1e-13
    assert np.abs(np.cross(alpha, ARM)).max() > 0.1  # the α term matters here
    # The splines are C²: α is continuous with kinks at the waypoints, where a stencil over ±2 ms
    # is off by O(δ · jump of α̇); elsewhere, and at both ends, to the stencil's truncation.
    near_knot = np.min(np.abs(body.t[:, None] - times[None, 1:-1]), axis=1) < 3e-3
    error = np.abs(sensor.accel - accel).max(axis=1)
    assert error[~near_knot].max() < 1e-10, error[~near_knot].max()  # measured 1.9e-13
    assert error[[0, 1, -2, -1]].max() < 1e-10  # measured 1.9e-13 (the last sample)
    assert error.max() < 1e-3  # measured 9e-5 at a waypoint


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
