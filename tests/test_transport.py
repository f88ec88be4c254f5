"""Navigation over the WGS-84 ellipsoid in a frame that follows the vehicle
(``LocalLevel(..., transport=True)``): the simulator's readings and track, and ``integrate`` back.

The references are written here, independently of imukit's ellipsoid code: the geodetic → ECEF
conversion (checked at the equator and the pole), the ECEF kinematics of a vehicle flying along a
parallel (closed form: ``r̈ = −λ̇² (x, y, 0)``) or a meridian (latitude by ``scipy.integrate``), the
readings as the inertial rate and specific force seen from ECEF, and the speed of the geodetic track
measured as the ECEF distance it covers (which checks the radii of curvature). The normal gravity
magnitude is ``ik.LocalLevel``'s, tested against the published values in ``test_navigation.py``.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest
from scipy.integrate import solve_ivp

import imukit as ik

Array = npt.NDArray[np.float64]
A = 6378137.0
F = 1 / 298.257223563
E2 = F * (2 - F)
OMEGA = 7.292115e-5
SPEED = 250.0
LAT, HEIGHT = math.radians(45.0), 1000.0


def ecef(lat: Array, lon: Array, h: Array) -> Array:
    """Geodetic → ECEF (Groves 2013, eq. 2.112), rows (N, 3)."""
    n = A / np.sqrt(1 - E2 * np.sin(lat) ** 2)
    return np.stack(
        [(n + h) * np.cos(lat) * np.cos(lon), (n + h) * np.cos(lat) * np.sin(lon), (n * (1 - E2) + h) * np.sin(lat)],
        axis=-1,
    )


def enu_axes(lat: float, lon: float) -> Array:
    """Rows: the east, north, up unit vectors in ECEF (C_e^n for ENU)."""
    sl, cl, sp, cp = math.sin(lon), math.cos(lon), math.sin(lat), math.cos(lat)
    return np.array([[-sl, cl, 0.0], [-sp * cl, -sp * sl, cp], [cp * cl, cp * sl, sp]])


def test_geodetic_to_ecef_at_known_points() -> None:
    b = A * (1 - F)
    assert np.allclose(ecef(np.array(0.0), np.array(0.0), np.array(0.0)), [A, 0, 0], rtol=0, atol=1e-9)
    assert np.allclose(ecef(np.array(math.pi / 2), np.array(0.3), np.array(10.0)), [0, 0, b + 10], rtol=0, atol=1e-6)
    # b = 6,356,752.3142 m (NIMA TR8350.2, table 3.1)
    assert b == pytest.approx(6356752.3142, abs=1e-4)


def fly(axes: str, velocity: tuple[float, float, float], duration: float, rate: float = 100.0) -> tuple:
    frame = ik.LocalLevel(LAT, HEIGHT, axes, transport=True)
    motion = ik.sim.ConstantTwist(body_velocity=velocity, body_rate=(0.0, 0.0, 0.0))
    imu, truth = ik.sim.simulate(motion, rate=rate, duration=duration, frame=frame)
    return frame, imu, truth


def metres(truth: ik.Trajectory, other: Array) -> float:
    """The largest ECEF distance between the truth's geodetic track and ``other`` (N, 3)."""
    p = truth.position
    return float(np.max(np.linalg.norm(ecef(p[:, 0], p[:, 1], p[:, 2]) - ecef(*other.T), axis=1)))


def track_speed(p: Array, t: Array) -> Array:
    """ECEF speed of a geodetic track by central differences."""
    r = ecef(p[:, 0], p[:, 1], p[:, 2])
    return np.linalg.norm(r[2:] - r[:-2], axis=1) / (t[2:] - t[:-2])


@pytest.mark.parametrize("axes", ["enu", "ned"])
def test_east_along_a_parallel_for_an_hour(axes: str) -> None:
    east = (SPEED, 0.0, 0.0) if axes == "enu" else (0.0, SPEED, 0.0)
    frame, imu, truth = fly(axes, east, 3600.0)
    p = truth.position
    # Along the parallel: latitude and height constant, the ECEF speed is 250 m/s.
    assert np.all(p[:, 0] == LAT) and np.all(p[:, 2] == HEIGHT)
    assert np.allclose(track_speed(p, imu.t), SPEED, rtol=1e-9, atol=0)
    # Readings seen from ECEF: body = local-level axes; inertial rate (Ω + λ̇) about the Earth's
    # axis; specific force r̈ + 2Ω×ṙ − g with r̈ = −λ̇²(x, y, 0).
    # λ̇ from the transverse radius, written here: v / ((R_E + h) cos φ).
    re = A / math.sqrt(1 - E2 * math.sin(LAT) ** 2)
    lon_rate = SPEED / ((re + HEIGHT) * math.cos(LAT))
    assert np.max(np.abs(p[:, 1] - lon_rate * imu.t)) < 1e-12
    c = enu_axes(LAT, 0.0)
    r = ecef(np.array(LAT), np.array(0.0), np.array(HEIGHT))
    spin = np.array([0.0, 0.0, OMEGA])
    rdot = lon_rate * np.array([-r[1], r[0], 0.0])
    rddot = -(lon_rate**2) * np.array([r[0], r[1], 0.0])
    gamma = -ik.LocalLevel(LAT, HEIGHT).gravity[2]
    gyro_enu = c @ np.array([0.0, 0.0, OMEGA + lon_rate])
    accel_enu = c @ (rddot + 2 * np.cross(spin, rdot)) + np.array([0.0, 0.0, gamma])
    to_axes = (lambda x: x) if axes == "enu" else (lambda x: np.array([x[1], x[0], -x[2]]))
    assert np.allclose(imu.gyro, to_axes(gyro_enu), rtol=0, atol=1e-18)
    assert np.allclose(imu.accel, to_axes(accel_enu), rtol=0, atol=1e-12)
    # Integrated back with the transport model: on the truth to the simulator's precision.
    for scheme in ("midpoint", "rk4"):
        est = ik.integrate(imu, initial=truth.state(0), frame=frame, scheme=scheme)
        assert metres(truth, est.position) < 1e-6
        assert np.max(np.abs(est.velocity - truth.velocity)) < 1e-9


def test_north_along_a_meridian_for_an_hour() -> None:
    frame, imu, truth = fly("enu", (0.0, SPEED, 0.0), 3600.0)
    # The body is level with its x axis east while it flies north.
    p = truth.position
    assert np.allclose(track_speed(p, imu.t), SPEED, rtol=1e-9, atol=0)

    def rates(_: float, y: Array) -> Array:  # φ̇ = v_N / (R_N + h), R_N written here
        rn = A * (1 - E2) / (1 - E2 * math.sin(y[0]) ** 2) ** 1.5
        return np.array([SPEED / (rn + HEIGHT)])

    ref = solve_ivp(rates, (0.0, 3600.0), [LAT], t_eval=imu.t, rtol=1e-13, atol=1e-15, method="DOP853")
    assert np.max(np.abs(p[:, 0] - ref.y[0])) < 1e-11
    assert np.all(p[:, 1] == 0.0)
    est = ik.integrate(imu, initial=truth.state(0), frame=frame, scheme="rk4")
    assert metres(truth, est.position) < 1e-6
    # 900 km north: the latitude moved by 8.1°
    assert math.degrees(p[-1, 0] - LAT) == pytest.approx(8.1, abs=0.05)


def test_fixed_frame_drifts_by_the_gravity_it_does_not_turn() -> None:
    """The same readings integrated in the fixed frame at the start (no transport): the physics is
    exact except gravity, constant there while the true gravity turns with the vehicle, so the
    error is −∬ (C_n0e (−γ u(t)) − g₀) dt², written here from the ECEF track (the Coriolis on the
    error, 2Ω × δv, is ~1 % over 60 s)."""
    frame, imu, truth = fly("enu", (SPEED, 0.0, 0.0), 60.0)
    fixed = ik.LocalLevel(LAT, HEIGHT)
    est = ik.integrate(
        imu,
        initial=ik.NavState(np.zeros(3), truth.velocity[0], truth.rotation[0]),
        frame=fixed,
        scheme="rk4",
    )
    p = truth.position
    c0 = enu_axes(LAT, 0.0)
    r = ecef(p[:, 0], p[:, 1], p[:, 2])
    in_fixed = (r - r[0]) @ c0.T
    gamma = -fixed.gravity[2]
    up = np.stack([enu_axes(LAT, lon)[2] for lon in p[:, 1]])
    dg = -gamma * up @ c0.T - fixed.gravity
    h = imu.t[1] - imu.t[0]
    dv = np.concatenate([[np.zeros(3)], np.cumsum((dg[1:] + dg[:-1]) * h / 2, axis=0)])
    dp = np.concatenate([[np.zeros(3)], np.cumsum((dv[1:] + dv[:-1]) * h / 2, axis=0)])
    error = est.position[-1] - in_fixed[-1]  # the model's gravity minus the true one, twice integrated
    assert np.linalg.norm(error) > 10.0  # 13.8 m after 60 s
    assert np.linalg.norm(error + dp[-1]) < 0.01 * np.linalg.norm(dp[-1])
    # With the transport model the same readings stay on the track.
    assert metres(truth, ik.integrate(imu, initial=truth.state(0), frame=frame).position) < 1e-7


def test_transport_frame_values_are_checked() -> None:
    frame, imu, truth = fly("enu", (SPEED, 0.0, 0.0), 1.0)
    elsewhere = ik.NavState(np.array([0.1, 0.0, HEIGHT]), truth.velocity[0], truth.rotation[0])
    with pytest.raises(ik.ParameterError) as info:
        ik.integrate(imu, initial=elsewhere, frame=frame)
    assert info.value.argument == "initial.position"
    with pytest.raises(ik.ParameterError) as info:
        ik.integrate(imu, initial=truth.state(0), frame=frame, scheme="exp")
    assert info.value.argument == "scheme"
    with pytest.raises(ik.ParameterError) as info:
        ik.LocalLevel(LAT, transport=1)  # type: ignore[arg-type]
    assert info.value.argument == "transport"
    assert "transport=True" in repr(frame)
