"""Strapdown integration: convergence orders on an analytic trajectory, exactness of the closed
form for held inputs, gravity sign, bias handling, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from trajectories import GRAVITY, acceleration, attitude, body_rate, position, specific_force, velocity

EXPECTED = {"euler": 1, "midpoint": 2, "rk4": 4, "exp": 1}


def truth_state(t0: float) -> ik.NavState:
    t = np.array([t0])
    return ik.NavState(position(t)[0], velocity(t)[0], attitude(t)[0])


def final_errors(scheme: str, h: float, duration: float = 3.0) -> tuple[float, float]:
    t = np.linspace(0.0, duration, round(duration / h) + 1)
    imu = ik.ImuData(t, body_rate(t), specific_force(t))
    traj = ik.integrate(imu, initial=truth_state(0.0), scheme=scheme)
    end = t[-1:]
    return (
        float(np.linalg.norm(traj.position[-1] - position(end)[0])),
        float(np.linalg.norm(traj.velocity[-1] - velocity(end)[0])),
    )


@pytest.mark.parametrize("scheme", sorted(EXPECTED))
def test_convergence_order(scheme: str) -> None:
    steps = np.array([0.04, 0.02, 0.01, 0.005]) * (2 if EXPECTED[scheme] == 4 else 1)
    errors = np.array([final_errors(scheme, h) for h in steps])
    for name, column in (("position", errors[:, 0]), ("velocity", errors[:, 1])):
        order = np.polyfit(np.log(steps), np.log(column), 1)[0]
        assert abs(order - EXPECTED[scheme]) < 0.3, f"{scheme} {name}: measured order {order:.2f}"


def test_accelerometer_at_rest_reads_plus_g_up_and_integrates_to_rest() -> None:
    t = np.arange(1001) * 0.01
    accel = np.tile([0.0, 0.0, 9.81], (len(t), 1))  # z up, at rest: +9.81 on the up axis
    imu = ik.ImuData(t, np.zeros((len(t), 3)), accel)
    x0 = ik.NavState([1.0, 2.0, 3.0], [0.0, 0.0, 0.0], Rotation.identity())
    for scheme in EXPECTED:
        traj = ik.integrate(imu, initial=x0, scheme=scheme)
        assert np.abs(traj.position - [1.0, 2.0, 3.0]).max() < 1e-12
        assert np.abs(traj.velocity).max() < 1e-12
    # the sign matters: with gravity flipped the body falls up at 2g
    up = ik.integrate(imu, initial=x0, gravity=(0.0, 0.0, 9.81))
    assert up.position[-1, 2] == pytest.approx(3.0 + 0.5 * 2 * 9.81 * 10.0**2, rel=1e-12)
    # NED users: z down, gravity +9.81, the accelerometer reads -9.81 on z at rest
    ned = ik.ImuData(t, np.zeros((len(t), 3)), -accel)
    still = ik.integrate(ned, initial=x0, gravity=(0.0, 0.0, 9.81))
    assert np.abs(still.velocity).max() < 1e-12


def test_exp_is_exact_for_held_inputs() -> None:
    """Constant body rate and body specific force: exp at h = 0.1 s equals a dense RK4 reference."""
    w, f = np.array([0.4, -0.7, 1.1]), np.array([1.5, -0.3, 9.0])
    r0 = Rotation.from_rotvec([0.2, 0.1, -0.4])
    x0 = ik.NavState([0.0, 1.0, 2.0], [0.5, -0.2, 0.1], r0)
    coarse = np.arange(31) * 0.1
    fine = np.linspace(0.0, 3.0, 30001)

    def run(t: np.ndarray, scheme: str) -> ik.Trajectory:
        imu = ik.ImuData(t, np.tile(w, (len(t), 1)), np.tile(f, (len(t), 1)))
        return ik.integrate(imu, initial=x0, scheme=scheme)

    exact, reference = run(coarse, "exp"), run(fine, "rk4")
    assert np.abs(exact.position[-1] - reference.position[-1]).max() < 1e-9
    assert np.abs(exact.velocity[-1] - reference.velocity[-1]).max() < 1e-9
    assert (exact.rotation[-1].inv() * reference.rotation[-1]).magnitude() < 1e-12
    # midpoint at the same coarse step is visibly not exact
    assert np.abs(run(coarse, "midpoint").position[-1] - reference.position[-1]).max() > 1e-4


def test_bias_is_subtracted() -> None:
    t = np.linspace(0.0, 2.0, 401)
    imu_true = ik.ImuData(t, body_rate(t), specific_force(t))
    b = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.1, 0.05, -0.2])
    biased = ik.ImuData(t, body_rate(t) + b.gyro, specific_force(t) + b.accel)
    x0 = truth_state(0.0)
    a = ik.integrate(imu_true, initial=x0)
    c = ik.integrate(biased, initial=x0, bias=b)
    assert np.abs(a.position - c.position).max() < 1e-12
    assert np.abs(ik.integrate(biased, initial=x0).position[-1] - a.position[-1]).max() > 0.1


def test_trajectory_layout() -> None:
    t_ns = 1_403_715_523_912_140_000 + np.arange(201, dtype=np.int64) * 5_000_000
    seconds = (t_ns - t_ns[0]) * 1e-9
    imu = ik.ImuData(t_ns, body_rate(seconds), specific_force(seconds))
    traj = ik.integrate(imu, initial=truth_state(0.0), scheme="rk4")
    assert len(traj) == 201
    assert np.array_equal(traj.t_ns, t_ns)
    assert np.array_equal(traj.position[0], position(np.zeros(1))[0])
    assert np.abs(traj.position[-1] - position(seconds[-1:])[0]).max() < 1e-8


def test_bad_input() -> None:
    t = np.linspace(0.0, 1.0, 11)
    imu = ik.ImuData(t, np.zeros((11, 3)), np.zeros((11, 3)))
    x0 = truth_state(0.0)
    with pytest.raises(ik.ParameterError, match="scheme"):
        ik.integrate(imu, initial=x0, scheme="verlet")
    with pytest.raises(ik.ShapeError, match=r"gravity: expected shape \(3,\)"):
        ik.integrate(imu, initial=x0, gravity=(0.0, -9.81))
    with pytest.raises(ik.ParameterError, match="initial"):
        ik.integrate(imu, initial=(0, 0, 0))  # type: ignore[arg-type]
    with pytest.raises(ik.NonFiniteError, match="gravity"):
        ik.integrate(imu, initial=x0, gravity=(0.0, 0.0, np.nan))
    with pytest.raises(ik.ShapeError, match=r"covariance: expected shape \(15, 15\)"):
        ik.propagate(imu, initial=x0, covariance=np.eye(9), noise=ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4))
    with pytest.raises(ik.ParameterError, match="covariance_every"):
        ik.propagate(
            imu, initial=x0, covariance=np.eye(15), noise=ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4), covariance_every=0
        )
    with pytest.raises(ik.ParameterError, match="covariance"):
        asym = np.eye(15)
        asym[0, 1] = 1.0
        ik.propagate(imu, initial=x0, covariance=asym, noise=ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4))


def test_acceleration_helper_is_the_derivative_of_velocity() -> None:
    """The analytic truth itself: v = ṗ and a = v̇ by central differences (guards the test data)."""
    t = np.linspace(0.0, 3.0, 31)
    h = 1e-5
    assert np.abs((position(t + h) - position(t - h)) / (2 * h) - velocity(t)).max() < 1e-8
    assert np.abs((velocity(t + h) - velocity(t - h)) / (2 * h) - acceleration(t)).max() < 1e-8
    assert np.allclose(GRAVITY, [0.0, 0.0, -9.81])


def test_rk4_does_not_amplify_noise_across_a_gap() -> None:
    """Across a gap the cubic's weights grow to ±25; steps there fall back to the straight line."""
    rng = np.random.default_rng(7)
    t = np.concatenate([np.arange(100) * 0.005, 0.995 + 0.5 + np.arange(100) * 0.005])
    w, f = np.array([0.1, -0.2, 0.3]), np.array([0.2, 0.1, 9.81])
    x0 = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    truth = ik.integrate(ik.ImuData(t, np.tile(w, (200, 1)), np.tile(f, (200, 1))), initial=x0, scheme="exp")
    errors = {}
    for scheme in ("midpoint", "rk4"):
        e = []
        for _ in range(10):
            noisy = ik.ImuData(t, w + 0.0024 * rng.standard_normal((200, 3)), f + 0.028 * rng.standard_normal((200, 3)))
            traj = ik.integrate(noisy, initial=x0, scheme=scheme)
            e.append(np.linalg.norm(traj.velocity[-1] - truth.velocity[-1]))
        errors[scheme] = np.median(e)
    assert errors["rk4"] < 2 * errors["midpoint"], errors


def test_finite_input_that_overflows_is_an_error_not_nan() -> None:
    t = np.arange(5) * 0.01
    x0 = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    gyro = np.zeros((5, 3))
    gyro[2] = 1e200
    with pytest.raises(ik.NonFiniteError, match="too large"):
        ik.integrate(ik.ImuData(t, gyro, np.zeros((5, 3))), initial=x0, scheme="euler")
    accel = np.zeros((5, 3))
    accel[-1] = [0.0, 0.0, 1e308]
    imu = ik.ImuData(t, np.zeros((5, 3)), accel)
    for scheme in EXPECTED:  # euler and exp never use the last sample; rk4 overflows on it
        try:
            traj = ik.integrate(imu, initial=x0, scheme=scheme)
        except ik.NonFiniteError as e:
            assert "element 4 is too large" in str(e)
        else:
            assert np.isfinite(traj.velocity).all() and np.isfinite(traj.rotation.as_quat()).all()
    with pytest.raises(ik.NonFiniteError):
        ik.propagate(imu, initial=x0, covariance=np.eye(15), noise=ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4), scheme="rk4")
    # huge but finite samples whose sum overflows are not mistaken for bad input
    big = ik.ImuData(t, np.full((5, 3), 1e308), np.full((5, 3), 1e308))
    with pytest.raises(ik.NonFiniteError, match="too large"):
        ik.integrate(big, initial=x0)


def test_trajectory_outputs_are_guarded() -> None:
    t = np.arange(11) * 0.01
    imu = ik.ImuData(t, np.zeros((11, 3)), np.tile([0.0, 0.0, 9.81], (11, 1)))
    x0 = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    traj = ik.propagate(
        imu, initial=x0, covariance=np.eye(15), noise=ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4), covariance_every=4
    )
    assert traj.covariance_t is not None and traj.covariance is not None
    assert np.array_equal(traj.covariance_t, t[[0, 4, 8, 10]])
    for arr in (traj.position, traj.velocity, traj.covariance, traj.covariance_t):
        assert not arr.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 1.0
    # a stride that lands on the last sample keeps it once, and each covariance is its sample's
    noise = ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4)
    full = ik.propagate(imu, initial=x0, covariance=np.eye(15), noise=noise, covariance_every=1)
    assert full.covariance is not None and full.covariance_t is not None
    assert np.array_equal(full.covariance_t, t)
    on = ik.propagate(imu, initial=x0, covariance=np.eye(15), noise=noise, covariance_every=5)
    assert on.covariance is not None and on.covariance_t is not None
    assert np.array_equal(on.covariance_t, t[[0, 5, 10]])
    assert np.array_equal(on.covariance, full.covariance[[0, 5, 10]])
    # a stride past the end keeps the first and the last sample
    long = ik.propagate(imu, initial=x0, covariance=np.eye(15), noise=ik.ImuNoise(0, 0, 0, 0), covariance_every=10**30)
    assert np.array_equal(long.covariance_t, t[[0, 10]])
    for bad in (2.7, "3", True, 0):
        with pytest.raises(ik.ParameterError, match="covariance_every"):
            ik.propagate(imu, initial=x0, covariance=np.eye(15), noise=ik.ImuNoise(0, 0, 0, 0), covariance_every=bad)  # type: ignore[arg-type]
    negative = np.eye(15)
    negative[3, 3] = -1.0
    with pytest.raises(ik.ParameterError, match="non-negative diagonal"):
        ik.propagate(imu, initial=x0, covariance=negative, noise=ik.ImuNoise(0, 0, 0, 0))
    # a Trajectory keeps its own copy of the rotations it was given
    r = Rotation.from_rotvec(np.zeros((2, 3)))
    user = ik.Trajectory([0.0, 1.0], np.zeros((2, 3)), None, r)
    r[0] = Rotation.from_rotvec([1.0, 0.0, 0.0])
    assert user.rotation[0].magnitude() == 0.0
