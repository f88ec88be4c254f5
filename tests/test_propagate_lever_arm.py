"""``propagate(..., body_from_sensor=(R_bs, r))`` with a lever arm: the mean is
``integrate(body_from_sensor=)``'s, and the covariance carries the gyro noise that the conversion
to the body origin puts into the specific force (the centripetal ``D(ω) w_k`` and the tangential
``[r]× (w_{k+1} − w_{k−1}) / 2h``, correlated across three samples; ``propagate.rs``, module
``augmented``).

Monte Carlo: a sensor 0.3 m off the body on a body spinning at 3 rad/s, gyro noise dominating
(σ_g 1e-2 rad/s/√Hz, σ_a 1e-3 m/s²/√Hz), 400 noisy runs of 1 s at 200 Hz against the noise-free
run; NEES of ``[δp, δv, δθ]`` is χ²(9) per run when the covariance is right. The covariance is the
one of the first-order step (as ``propagate``'s always is) with the readings weighted as the
scheme weights them (``lie_euler``, ``exp``: sample k; ``midpoint``, ``rk4``: half of k and k + 1,
which matters for the tangential term's edges at the record's ends: rk4 with sample k's weights
alone gave 10.0); with zero or doubled lever-arm terms (the
core's lever arm 0 or 2r on the same body readings: every term is linear in r) the NEES leaves
the interval.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit import _core

R_BS = Rotation.from_euler("ZYX", [90, 10, -20], degrees=True)
ARM = np.array([0.3, 0.0, 0.0])
SPIN = ik.sim.ConstantTwist(body_velocity=(1.0, 0.0, 0.2), body_rate=(0.3, -0.2, 3.0))
NOISE = ik.ImuNoise(gyro_density=1e-2, accel_density=1e-3, gyro_random_walk=0.0, accel_random_walk=0.0)
RATE, RUNS = 200.0, 400
P0 = np.zeros((15, 15))


def _covariance_with_arm(sensor: ik.ImuData, x0: ik.NavState, arm: np.ndarray, scheme: str) -> np.ndarray:
    """The final covariance with the lever-arm terms of ``arm`` on the body readings of ``ARM``."""
    rows = [list(r) for r in R_BS.as_matrix()]
    gyro, accel = _core.body_readings(sensor.seconds, sensor.gyro, sensor.accel, ik.ImuBias(), rows, list(ARM))
    args = (sensor.seconds, gyro, accel, x0, P0, ik.ImuBias(), NOISE, list(_core.GRAVITY), scheme)
    _, _, covs = _core.strapdown_propagate(*args, len(sensor) - 1, [0.0, 0.0, 0.0], list(arm), None)
    return np.asarray(covs[-1]).reshape(15, 15)


def test_mean_is_integrate_bit_for_bit() -> None:
    sensor, truth = ik.sim.simulate(SPIN, rate=RATE, duration=2.0, body_from_sensor=(R_BS, ARM))
    for scheme in ik.strapdown.SCHEMES:
        out = ik.propagate(
            sensor, initial=truth.state(0), covariance=P0, noise=NOISE, scheme=scheme, body_from_sensor=(R_BS, ARM)
        )
        mean = ik.integrate(sensor, initial=truth.state(0), scheme=scheme, body_from_sensor=(R_BS, ARM))
        assert np.array_equal(out.position, mean.position) and np.array_equal(out.velocity, mean.velocity)
        assert np.array_equal(out.rotation.as_quat(), mean.rotation.as_quat())


@pytest.mark.parametrize("scheme", ["lie_euler", "midpoint", "rk4", "exp"])
def test_monte_carlo_nees_with_a_lever_arm(scheme: str) -> None:
    sensor, truth = ik.sim.simulate(SPIN, rate=RATE, duration=1.0, body_from_sensor=(R_BS, ARM))
    x0, pose = truth.state(0), (R_BS, ARM)
    out = ik.propagate(
        sensor, initial=x0, covariance=P0, noise=NOISE, scheme=scheme, body_from_sensor=pose, covariance_every=400
    )
    clean = ik.integrate(sensor, initial=x0, scheme=scheme, body_from_sensor=pose)
    rng = np.random.default_rng(1)
    scale = np.array([NOISE.gyro_density, NOISE.accel_density])[:, None, None] * np.sqrt(RATE)
    errors = np.empty((RUNS, 9))
    for r in range(RUNS):
        white = rng.standard_normal((2, len(sensor), 3)) * scale
        noisy = ik.ImuData(sensor.t, sensor.gyro + white[0], sensor.accel + white[1])
        est = ik.integrate(noisy, initial=x0, scheme=scheme, body_from_sensor=pose)
        d_theta = (est.rotation[-1].inv() * clean.rotation[-1]).as_rotvec()
        errors[r] = np.concatenate(
            [clean.position[-1] - est.position[-1], clean.velocity[-1] - est.velocity[-1], d_theta]
        )

    def nees(cov: np.ndarray) -> float:
        return float(np.einsum("ri,ij,rj->r", errors, np.linalg.inv(cov[:9, :9]), errors).mean())

    half = 1.96 * np.sqrt(18 / RUNS)  # 95 % interval of the mean of 400 χ²(9): [8.58, 9.42]
    assert out.covariance is not None
    assert (
        9 - half < nees(out.covariance[-1]) < 9 + half
    )  # seeds 1, 2, 3: 9.26, 8.79, 8.89 (rk4 9.29, 8.66, 8.92; exp 9.26, 8.80, 8.85)
    assert (
        nees(_covariance_with_arm(sensor, x0, 0 * ARM, scheme)) > 100
    )  # zeroed: 8.1e3, 7.2e3, 7.4e3 (midpoint 5.3e3, 4.8e3, 4.8e3)
    assert (
        nees(_covariance_with_arm(sensor, x0, 2 * ARM, scheme)) < 9 - half
    )  # doubled: 6.99, 6.61, 6.55 (midpoint 7.02, 6.58, 6.60)


def test_body_is_recovered_and_without_the_arm_errs_by_the_centripetal_term() -> None:
    """The mean with the lever arm recovers the body to the midpoint scheme's order; with the
    rotation only, the error is the sensor's own path, ``R r − R₀ r − t R₀ (ω × r)``."""
    twist = ik.sim.ConstantTwist(body_velocity=(1.0, 0.0, 0.2), body_rate=(0.1, -0.05, 2.0))
    sensor, truth = ik.sim.simulate(twist, rate=400.0, duration=10.0, body_from_sensor=(R_BS, ARM))
    x0 = truth.state(0)
    p0 = np.eye(15) * 1e-6
    out = ik.propagate(sensor, initial=x0, covariance=p0, noise=NOISE, body_from_sensor=(R_BS, ARM))
    assert np.abs(out.position - truth.position).max() < 5e-5  # midpoint, central-difference α
    off = ik.propagate(sensor, initial=x0, covariance=p0, noise=NOISE, body_from_sensor=(R_BS, np.zeros(3)))
    t, r0 = truth.t[:, None], truth.rotation[0]
    predicted = truth.rotation.apply(ARM) - r0.apply(ARM) - t * r0.apply(np.cross(twist.body_rate, ARM))
    error = off.position - truth.position
    assert np.abs(error).max() > 3.0
    assert np.abs(error - predicted).max() < 1e-4
