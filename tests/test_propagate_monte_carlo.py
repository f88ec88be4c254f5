"""Monte Carlo consistency of ``propagate``: 2,000 seeded noisy runs of a 2 s trajectory, noise and
bias random walk drawn from the same ImuNoise; the error at the end against the propagated
covariance (NEES in its χ² 99% interval; relative Frobenius error that a zero or doubled covariance
fails)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

import imukit as ik
from trajectories import attitude, body_rate, position, specific_force, velocity

RUNS = 2000
RATE = 200.0
NOISE = ik.ImuNoise(gyro_density=2e-3, accel_density=2e-2, gyro_random_walk=1e-3, accel_random_walk=1e-2)
P0 = np.diag(np.repeat([1e-4, 1e-4, 1e-6, 1e-4, 1e-6], 3) ** 1)


def _error(truth: ik.Trajectory, est: ik.Trajectory, b_a: np.ndarray, b_g: np.ndarray) -> np.ndarray:
    """δx = x_true ⊖ x̂ at the last sample, order [δp, δv, δθ, δb_a, δb_g] (estimated biases are 0)."""
    d_theta = (est.rotation[-1].inv() * truth.rotation[-1]).as_rotvec()
    return np.concatenate(
        [truth.position[-1] - est.position[-1], truth.velocity[-1] - est.velocity[-1], d_theta, b_a, b_g]
    )


def monte_carlo() -> tuple[np.ndarray, np.ndarray]:
    """Errors of all runs (RUNS, 15) and the propagated covariance at the end (15, 15)."""
    rng = np.random.default_rng(20261122)
    t = np.arange(round(2.0 * RATE) + 1) / RATE
    dt = np.diff(t)
    n = len(t)
    w_true, f_true = body_rate(t), specific_force(t)
    z = np.zeros(1)
    x_true = ik.NavState(position(z)[0], velocity(z)[0], attitude(z)[0])
    truth = ik.integrate(ik.ImuData(t, w_true, f_true), initial=x_true, scheme="euler")
    chol = np.linalg.cholesky(P0)
    errors = np.empty((RUNS, 15))
    for r in range(RUNS):
        d0 = chol @ rng.standard_normal(15)  # initial error: truth = estimate ⊕ d0
        x_hat = ik.NavState(
            x_true.position - d0[0:3],
            x_true.velocity - d0[3:6],
            x_true.rotation * Rotation.from_rotvec(-d0[6:9]),
        )
        steps_a = rng.standard_normal((n - 1, 3)) * NOISE.accel_random_walk * np.sqrt(dt)[:, None]
        steps_g = rng.standard_normal((n - 1, 3)) * NOISE.gyro_random_walk * np.sqrt(dt)[:, None]
        b_a = d0[9:12] + np.vstack([np.zeros(3), np.cumsum(steps_a, axis=0)])
        b_g = d0[12:15] + np.vstack([np.zeros(3), np.cumsum(steps_g, axis=0)])
        white = rng.standard_normal((2, n, 3)) / np.sqrt(np.append(dt, dt[-1]))[:, None]
        imu = ik.ImuData(t, w_true + b_g + white[0] * NOISE.gyro_density, f_true + b_a + white[1] * NOISE.accel_density)
        est = ik.integrate(imu, initial=x_hat, scheme="euler")
        errors[r] = _error(truth, est, b_a[-1], b_g[-1])
    nominal = ik.propagate(
        ik.ImuData(t, w_true, f_true), initial=x_true, covariance=P0, noise=NOISE, scheme="euler", covariance_every=n
    )
    assert nominal.covariance is not None
    return errors, nominal.covariance[-1]


def test_propagated_covariance_matches_monte_carlo() -> None:
    errors, p = monte_carlo()
    nees = np.einsum("ri,ij,rj->r", errors, np.linalg.inv(p), errors)
    low, high = chi2.ppf([0.005, 0.995], 15 * RUNS) / RUNS
    assert low < nees.mean() < high, f"average NEES {nees.mean():.3f} outside [{low:.3f}, {high:.3f}]"
    sample = errors.T @ errors / RUNS  # the errors have zero mean by construction
    rel = np.linalg.norm(sample - p) / np.linalg.norm(p)
    assert rel < 0.1, f"relative Frobenius error {rel:.3f}"
    # the statistics can fail: a doubled or zero covariance is rejected
    assert not (low < np.einsum("ri,ij,rj->r", errors, np.linalg.inv(2 * p), errors).mean() < high)
    assert np.linalg.norm(sample - 2 * p) / np.linalg.norm(2 * p) > 0.1
    assert np.linalg.norm(sample - 0 * p) / np.linalg.norm(p) > 0.1
