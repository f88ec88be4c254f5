"""The simulator from Python: noise-free simulation integrates back to the truth at the integrator's
own order, ideal readings against closed forms, waypoint splines, the noise model's statistics and
reproducibility, and bad input."""

from __future__ import annotations

import dataclasses
import inspect
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit import _core, sim

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)


def _errors(motion: sim.Motion, rate: float, duration: float) -> tuple[float, float]:
    imu, truth = sim.simulate(motion, rate=rate, duration=duration)
    traj = ik.integrate(imu, initial=truth.state(0), scheme="rk4")
    attitude = float((traj.rotation.inv() * truth.rotation).magnitude().max())
    return float(np.abs(traj.position - truth.position).max()), attitude


def test_noise_free_figure_eight_integrates_back_at_fourth_order() -> None:
    """60 s figure eight, rk4: halving the step shrinks both errors ~16×; at 200 Hz they are tiny."""
    (p200, a200), (p400, a400) = (_errors(sim.FigureEight(), rate, 60.0) for rate in (200.0, 400.0))
    assert p200 < 1e-5 and a200 < 1e-8
    assert 12 < p200 / p400 < 20 and 12 < a200 / a400 < 20
    # a wrong specific force (gravity sign) or body rate (world frame) would be far off
    imu, truth = sim.simulate(sim.FigureEight(), rate=200.0, duration=60.0)
    wrong = ik.integrate(imu, initial=truth.state(0), scheme="rk4", gravity=(0.0, 0.0, 9.81))
    assert np.abs(wrong.position - truth.position).max() > 1.0


def test_ideal_readings_of_simple_motions() -> None:
    tilt = Rotation.from_rotvec([0.3, -0.2, 0.5])
    imu, truth = sim.simulate(sim.Static(position=(1, 2, 3), rotation=tilt), rate=100.0, duration=1.0)
    assert len(imu) == 101 and imu.t[-1] == 1.0
    assert np.allclose(imu.gyro, 0.0, atol=0.0)
    assert np.allclose(imu.accel, tilt.inv().apply([0.0, 0.0, 9.81]), atol=1e-14, rtol=0)
    assert truth.gyro_bias is not None and not truth.gyro_bias.any()
    imu, truth = sim.simulate(sim.Circle(radius=4.0, angular_rate=0.5), rate=100.0, duration=10.0)
    assert np.allclose(imu.gyro, [0.0, 0.0, 0.5], atol=1e-15, rtol=0)
    # body frame: forward speed, centripetal r Ω² to the left (+y), gravity reaction up
    assert np.allclose(imu.accel, [0.0, 4.0 * 0.25, 9.81], atol=1e-12, rtol=0)
    assert np.allclose(np.linalg.norm(truth.velocity, axis=1), 2.0, atol=1e-14, rtol=0)


def test_the_teaching_ellipse() -> None:
    _, truth = sim.simulate(sim.VioEllipse(), rate=200.0, duration=20.0)
    k, t = math.pi / 10.0, truth.t
    assert np.allclose(truth.position[:, 0], 15.0 * np.cos(k * t) + 5.0, atol=1e-12, rtol=0)
    assert np.allclose(truth.position[:, 2], np.sin(10.0 * k * t) + 5.0, atol=1e-12, rtol=0)
    chi = np.stack([k * t, 0.2 * np.sin(t), 0.1 * np.cos(t)], axis=-1)
    assert (ik.euler.to_rotation(chi).inv() * truth.rotation).magnitude().max() < 1e-14


def test_waypoints_pass_through_their_points_and_integrate_back() -> None:
    times = np.array([0.0, 2.0, 4.0, 6.0, 8.0])
    positions = np.array([[0, 0, 1], [3, 1, 1.5], [5, 4, 2], [2, 6, 1.5], [0, 3, 1.0]])
    rotations = Rotation.from_euler(
        "ZYX", [[0, 0, 0], [0.5, 0.1, -0.1], [1.2, -0.1, 0.2], [2.0, 0.0, 0.1], [2.5, 0, 0]]
    )
    path = sim.Waypoints(times, positions, rotations)
    imu, truth = sim.simulate(path, rate=400.0, duration=8.0)
    for tk, p, r in zip(times, positions, rotations, strict=True):
        k = round(tk * 400)
        assert np.abs(truth.position[k] - p).max() < 1e-12
        assert (truth.rotation[k].inv() * r).magnitude() < 1e-12
    assert np.abs(truth.velocity[[0, -1]]).max() < 1e-12  # clamped: at rest at both ends
    # the body rate is R_wbᵀ Ṙ_wb: integrating it reproduces the spline's attitude (rk4, C² spline)
    rot = ik.integrate_attitude(imu.seconds, imu.gyro, initial=truth.rotation[0], scheme="rk4")
    assert (rot.inv() * truth.rotation).magnitude().max() < 1e-6
    world = truth.rotation.apply(imu.gyro.copy())  # the same rate in the world frame is wrong
    rot_world = ik.integrate_attitude(imu.seconds, world, initial=truth.rotation[0], scheme="rk4")
    assert (rot_world.inv() * truth.rotation).magnitude().max() > 1e-2
    with pytest.raises(ik.ParameterError, match="duration: the waypoints span"):
        sim.simulate(path, rate=100.0, duration=9.0)


def _final_position_errors(path: sim.Waypoints, scheme: str, rates: tuple[float, ...]) -> np.ndarray:
    errors = []
    for rate in rates:
        imu, truth = sim.simulate(path, rate=rate, duration=10.0)
        end = ik.integrate(imu, initial=truth.state(0), scheme=scheme).position[-1]
        errors.append(np.linalg.norm(end - truth.position[-1]))
    return np.array(errors)


def test_waypoints_orders() -> None:
    """A C² spline's readings have slopes that jump at the waypoints, so rk4 converges at order 2 on
    them (docs/simulation.md); on the poses of one global cubic (``not-a-knot``: the spline is that
    cubic) and a constant rate it converges at 4, which also checks the spline's derivatives."""
    rng = np.random.default_rng(1)
    times = np.arange(11.0)
    jagged = sim.Waypoints(
        times,
        np.cumsum(rng.normal(0, 1, (11, 3)), axis=0),
        Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.5, (11, 3)), axis=0)),
    )
    cubic = np.stack([0.01 * times**3 - 0.1 * times**2, 0.02 * times**3, -0.005 * times**3 + times], axis=1)
    smooth = sim.Waypoints(times, cubic, Rotation.from_rotvec(np.outer(times, [0, 0, 0.3])), bc_type="not-a-knot")
    ratios = _final_position_errors(jagged, "rk4", (100.0, 200.0, 400.0))
    np.testing.assert_allclose(ratios[:-1] / ratios[1:], 4.0, rtol=0.02)
    ratios = _final_position_errors(smooth, "rk4", (50.0, 100.0, 200.0))
    assert np.all(ratios[:-1] / ratios[1:] > 14.0)


def test_noise_is_seeded_and_biases_are_reported() -> None:
    bias = ik.ImuBias(gyro=[0.01, 0.0, -0.02], accel=[0.1, -0.1, 0.05])
    a = sim.simulate(sim.FigureEight(), rate=200.0, duration=20.0, noise=NOISE, bias=bias, seed=11)
    b = sim.simulate(sim.FigureEight(), rate=200.0, duration=20.0, noise=NOISE, bias=bias, seed=11)
    c = sim.simulate(sim.FigureEight(), rate=200.0, duration=20.0, noise=NOISE, bias=bias, seed=12)
    assert np.array_equal(a[0].gyro, b[0].gyro) and np.array_equal(a[0].accel, b[0].accel)
    assert not np.array_equal(a[0].gyro, c[0].gyro)
    ideal, _ = sim.simulate(sim.FigureEight(), rate=200.0, duration=20.0)
    truth = a[1]
    assert truth.gyro_bias is not None and truth.accel_bias is not None
    assert np.array_equal(truth.gyro_bias[0], bias.gyro)  # the walk starts at zero
    # the reading is ideal + true bias + white noise: the residual has σ_g / √dt
    white = a[0].gyro - ideal.gyro - truth.gyro_bias
    assert np.std(white) == pytest.approx(NOISE.gyro_density * math.sqrt(200.0), rel=0.03)
    walk = truth.accel_bias[-1] - bias.accel
    assert np.abs(walk).max() < 6 * NOISE.accel_random_walk * math.sqrt(20.0)


def test_sensor_errors_scale_misalignment_and_saturation() -> None:
    errors = sim.SensorErrors.from_scale_misalignment(
        [0.01, -0.02, 0.0], [[0, 1e-3, 0], [0, 0, -2e-3], [5e-4, 0, 0]], range=3.0, resolution=1e-3
    )
    ideal, _ = sim.simulate(sim.FigureEight(), rate=100.0, duration=5.0)
    imu, _ = sim.simulate(sim.FigureEight(), rate=100.0, duration=5.0, gyro_errors=errors, accel_errors=errors)
    misalignment = np.array([[0, 1e-3, 0], [0, 0, -2e-3], [5e-4, 0, 0]])
    t_matrix = (np.eye(3) + np.diag([0.01, -0.02, 0.0])) @ (np.eye(3) + misalignment)
    expected = np.round(np.clip(ideal.accel @ t_matrix.T, -3.0, 3.0) / 1e-3) * 1e-3
    assert np.array_equal(imu.accel, expected)
    assert imu.accel[:, 2].max() == 3.0  # gravity's 9.81 saturates
    with pytest.raises(ik.ShapeError, match="misalignment: expected a \\(3, 3\\) matrix with a zero diagonal"):
        sim.SensorErrors.from_scale_misalignment([0, 0, 0], np.eye(3))


def test_bad_input() -> None:
    with pytest.raises(ik.ParameterError, match="rate"):
        sim.simulate(sim.Static(), rate=0.0, duration=1.0)
    with pytest.raises(ik.ParameterError, match="duration"):
        sim.simulate(sim.Static(), rate=100.0, duration=0.001)
    with pytest.raises(ik.ParameterError, match="seed"):
        sim.simulate(sim.Static(), rate=100.0, duration=1.0, seed=-1)
    with pytest.raises(ik.ParameterError, match="turn_on_sigma: expected a finite, non-negative number"):
        sim.SensorErrors(turn_on_sigma=math.nan)
    with pytest.raises(ik.ParameterError, match="gauss_markov_tau: expected a positive number"):
        sim.SensorErrors(gauss_markov_tau=0.0)
    with pytest.raises(ik.ParameterError, match=r"gyro_errors: expected an imukit\.sim\.SensorErrors"):
        sim.simulate(sim.Static(), rate=100.0, duration=1.0, gyro_errors=NOISE)  # type: ignore[arg-type]
    with pytest.raises(ik.ShapeError, match="center"):
        sim.simulate(sim.Helix(center=(0, 0)), rate=100.0, duration=1.0)
    # 10 ms steps vanish in the rounding of 1e17 s.
    with pytest.raises(ik.ParameterError, match="too large for steps") as caught:
        sim.simulate(sim.Static(), rate=100.0, duration=1.0, start=1e17)
    assert caught.value.argument == "start"


def test_the_stamps_are_k_over_rate_from_start() -> None:
    """``start + k / rate`` rounded once each (the in-place construction), and from 0 the seconds
    since the first sample are the stamps themselves."""
    for start in (0.0, -3.25, 1.7e9):
        imu, truth = sim.simulate(sim.Static(), rate=300.0, duration=50.0, start=start)
        expected = np.array([start + k / 300.0 for k in range(15_001)])
        assert np.array_equal(imu.t, expected) and np.array_equal(truth.t, expected)
        assert np.array_equal(imu.seconds, expected - expected[0])


def test_a_simulation_exports_to_euroc_and_tum_exactly(tmp_path: Path) -> None:
    imu, truth = sim.simulate(sim.VioEllipse(), rate=200.0, duration=2.0, noise=NOISE, seed=3)
    ik.io.write_euroc(tmp_path / "mav0", imu, truth, epoch_ns=1_403_636_579_758_555_392, noise=NOISE, rate_hz=200.0)
    imu_back, truth_back = ik.io.read_euroc(tmp_path)
    assert truth_back is not None and truth_back.gyro_bias is not None and truth.gyro_bias is not None
    assert np.array_equal(imu_back.gyro, imu.gyro) and np.array_equal(imu_back.accel, imu.accel)
    assert np.array_equal(truth_back.position, truth.position)
    assert np.array_equal(truth_back.gyro_bias, truth.gyro_bias)
    assert np.array_equal(np.diff(imu_back.t_ns), np.full(len(imu) - 1, 5_000_000))
    assert ik.io.read_kalibr_imu(tmp_path / "mav0" / "imu0" / "sensor.yaml").noise == NOISE
    truth.write_tum(tmp_path / "truth.tum")
    tum = ik.io.read_tum(tmp_path / "truth.tum")
    assert np.array_equal(tum.position, truth.position)


def test_sensor_error_defaults_are_the_cores_perfect_triad() -> None:
    """SensorErrors' defaults are read from the core's SensorModel::default(), not re-typed."""
    perfect = _core.sim_sensor_default()
    errors = ik.sim.SensorErrors()
    assert {f.name for f in dataclasses.fields(errors)} == set(perfect)
    for name, value in perfect.items():
        assert np.array_equal(np.asarray(getattr(errors, name)), np.asarray(value)), name
    assert np.array_equal(np.asarray(perfect["matrix"]), np.eye(3))
    assert perfect["range"] == math.inf and perfect["gauss_markov_tau"] == math.inf


def test_sensor_errors_reach_the_core_by_field_name_whatever_their_number_types() -> None:
    """The core reads SensorErrors by attribute: ints, float32 and a nested-tuple matrix give the
    same readings as float64 (a field read under the wrong name or position would not)."""
    common = {"rate": 200.0, "duration": 2.0, "seed": 5, "noise": ik.ImuNoise(1e-3, 1e-2, 1e-4, 1e-3)}
    as_floats = ik.sim.SensorErrors(
        matrix=np.diag([1.01, 0.99, 1.0]), turn_on_sigma=0.5, gauss_markov_sigma=0.25, gauss_markov_tau=2.0, range=4.0
    )
    as_others = ik.sim.SensorErrors(
        matrix=((1.01, 0, 0), (0, 0.99, 0), (0, 0, 1)),
        turn_on_sigma=np.float32(0.5),
        gauss_markov_sigma=0.25,
        gauss_markov_tau=2,
        range=4,
    )
    a, _ = ik.sim.simulate(ik.sim.FigureEight(), gyro_errors=as_floats, **common)
    b, _ = ik.sim.simulate(ik.sim.FigureEight(), gyro_errors=as_others, **common)
    assert np.array_equal(a.gyro, b.gyro) and a.gyro_range == b.gyro_range == 4.0
    swapped = dataclasses.replace(as_floats, gauss_markov_sigma=0.5, turn_on_sigma=0.25)
    c, _ = ik.sim.simulate(ik.sim.FigureEight(), gyro_errors=swapped, **common)
    assert not np.array_equal(a.gyro, c.gyro)


def test_gravity_default_is_the_cores() -> None:
    default = inspect.signature(ik.sim.simulate).parameters["gravity"].default
    assert default is ik.imu.GRAVITY and ik.GRAVITY == ik.imu.GRAVITY == _core.GRAVITY == (0.0, 0.0, -9.81)


def test_a_motion_beyond_float64_is_refused_naming_the_motion_parameters() -> None:
    """The core checks the truth as it writes it (no numpy pass): z = c t overflows after 1.8 s."""
    with pytest.raises(ik.NonFiniteError) as info:
        ik.sim.simulate(ik.sim.Helix(climb_rate=1e308), rate=10, duration=3)
    assert "climb_rate" in str(info.value.argument)
    assert "beyond float64 over [0.0, 3.0] s" in str(info.value)
    imu, _ = ik.sim.simulate(ik.sim.Helix(climb_rate=1e308), rate=10, duration=1.7)  # finite up to here
    assert np.isfinite(imu.accel).all()
