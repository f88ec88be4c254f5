"""``propagate(..., frame=LocalLevel)``: the mean is ``integrate(frame=)``'s, and the covariance's
Coriolis term ``−2h[Ω]×`` on the velocity error is the one the Monte Carlo sees.

The error dynamics here are exactly linear (the velocity enters the model linearly, no IMU noise,
the attitude is known), so the Monte Carlo's NEES of ``[δp, δv]`` is χ²(6) per run when the
covariance is right. The initial velocity error is anisotropic (3 m/s east, 0.1 m/s otherwise, positions 1 km):
over an hour at 45° the Coriolis term turns it by ``2Ω sin φ T`` = 0.37 rad about the vertical, so
a covariance that does not turn it (no Earth term) or turns it twice as far is far off.
"""

from __future__ import annotations

import numpy as np
import pytest

import imukit as ik

RUNS = 400


def scenario() -> tuple[ik.ImuData, ik.NavState, ik.LocalLevel, np.ndarray]:
    frame = ik.LocalLevel(45.0, 200.0, degrees=True)
    motion = ik.sim.ConstantTwist(body_velocity=(10.0, 0.0, 0.0), body_rate=(0.0, 0.0, 0.0))
    imu, truth = ik.sim.simulate(motion, rate=10.0, duration=3600.0, frame=frame)
    p0 = np.diag([1e6] * 3 + [9.0, 1e-2, 1e-2] + [0.0] * 9)
    return imu, truth.state(0), frame, p0


NOISE = ik.ImuNoise(0.0, 0.0, 0.0, 0.0)


def mean_nees(imu: ik.ImuData, x0: ik.NavState, frame: ik.LocalLevel, cov: np.ndarray, p0: np.ndarray) -> float:
    rng = np.random.default_rng(1)
    base = ik.integrate(imu, initial=x0, frame=frame)
    info = np.linalg.inv(cov[:6, :6])
    scores = []
    for _ in range(RUNS):
        d = rng.multivariate_normal(np.zeros(6), p0[:6, :6])
        start = ik.NavState(x0.position + d[:3], x0.velocity + d[3:], x0.rotation)
        run = ik.integrate(imu, initial=start, frame=frame)
        e = np.concatenate([run.position[-1] - base.position[-1], run.velocity[-1] - base.velocity[-1]])
        scores.append(e @ info @ e)
    return float(np.mean(scores))


def test_mean_is_integrate_and_the_coriolis_covariance_is_consistent() -> None:
    imu, x0, frame, p0 = scenario()
    out = ik.propagate(imu, initial=x0, covariance=p0, noise=NOISE, frame=frame, covariance_every=len(imu))
    mean = ik.integrate(imu, initial=x0, frame=frame)
    assert np.array_equal(out.position, mean.position) and np.array_equal(out.velocity, mean.velocity)
    # 95 % interval of the mean of 400 χ²(6): 6 ± 1.96·√(12/400) (seeds 1, 2, 3: 6.06, 6.00, 5.94)
    half = 1.96 * np.sqrt(12 / RUNS)
    nees = mean_nees(imu, x0, frame, out.covariance[-1], p0)
    assert 6 - half < nees < 6 + half, nees
    # The same run without the Earth term in the covariance (inertial propagate), or with it doubled
    # (a frame turning twice as fast gives the covariance 2Ω; its mean is not used): far outside.
    inertial = ik.propagate(imu, initial=x0, covariance=p0, noise=NOISE, covariance_every=len(imu))
    assert mean_nees(imu, x0, frame, inertial.covariance[-1], p0) > 100  # 254
    doubled = _covariance_with_rate(imu, x0, p0, 2.0 * frame.earth_rate)
    assert mean_nees(imu, x0, frame, doubled, p0) > 100


def _covariance_with_rate(imu: ik.ImuData, x0: ik.NavState, p0: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """The final covariance of a world turning at ``rate`` (the core's entry, below the public
    frame, which only has the Earth's own rate)."""
    from imukit import _core

    args = (imu.seconds, imu.gyro, imu.accel, x0, p0, ik.ImuBias(), NOISE)
    _, _, covs = _core.strapdown_propagate(*args, [0.0, 0.0, -9.81], "midpoint", len(imu) - 1, list(rate))
    return np.asarray(covs[-1]).reshape(15, 15)


def test_a_transported_frame_is_refused() -> None:
    imu, x0, _, p0 = scenario()
    with pytest.raises(ik.ParameterError) as info:
        ik.propagate(imu, initial=x0, covariance=p0, noise=NOISE, frame=ik.LocalLevel(0.7, transport=True))
    assert info.value.argument == "frame"
