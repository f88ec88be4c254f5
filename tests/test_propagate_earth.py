"""``propagate(..., frame=LocalLevel)``: the mean is ``integrate(frame=)``'s, and the covariance's
Coriolis term ``−2h[Ω]×`` on the velocity error is the one the Monte Carlo sees.

The error dynamics here are exactly linear (the velocity enters the model linearly, no IMU noise,
the attitude is known), so the Monte Carlo's NEES of ``[δp, δv]`` is χ²(6) per run when the
covariance is right. The initial velocity error is anisotropic (3 m/s east, 0.1 m/s otherwise, positions 1 km):
over an hour at 45° the Coriolis term turns it by ``2Ω sin φ T`` = 0.37 rad about the vertical, so
a covariance that does not turn it (no Earth term) or turns it twice as far is far off.

With a frame that follows the vehicle (``transport=True``) the covariance is the full local-level
error model (``crates/imukit/src/ellipsoid_errors.rs``): its Monte Carlo perturbs position,
velocity, attitude and both biases, and the Schuler period shows in the position covariance.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

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
    _, _, covs = _core.strapdown_propagate(
        *args, [0.0, 0.0, -9.81], "midpoint", len(imu) - 1, list(rate), [0.0] * 3, None
    )
    return np.asarray(covs[-1]).reshape(15, 15)


# Over the ellipsoid (transport=True): 250 m/s east at 45° N, 1000 m, for an hour (900 km), 5 Hz.
A, F = 6378137.0, 1 / 298.257223563
E2 = F * (2 - F)
LAT, HEIGHT = np.radians(45.0), 1000.0
RN = A * (1 - E2) / (1 - E2 * np.sin(LAT) ** 2) ** 1.5 + HEIGHT  # meridian radius plus height
RE = A / np.sqrt(1 - E2 * np.sin(LAT) ** 2) + HEIGHT  # transverse
# Initial errors: 3 mm north/east (as latitude/longitude), 1e-7 m up, 3e-5 m/s level, 1e-8 m/s up,
# 2e-8 rad tilt, 1e-7 rad heading, biases 1e-10 m/s² and 1e-10 rad/s. Small because the unaided
# vertical channel amplifies any error by e^{t/570 s} (550× in the hour) into every other state
# through Coriolis: the Monte Carlo must stay linear (10× these: NEES 9.38; 100×: 36.7).
SD = 1e-4 * np.array([30 / RN, 30 / (RE * np.cos(LAT)), 1e-3, 0.3, 0.3, 1e-4, 2e-4, 2e-4, 1e-3, *[1e-6] * 6])


def transported() -> tuple[ik.ImuData, ik.NavState, ik.LocalLevel]:
    frame = ik.LocalLevel(LAT, HEIGHT, transport=True)
    motion = ik.sim.ConstantTwist(body_velocity=(250.0, 0.0, 0.0), body_rate=(0.0, 0.0, 0.0))
    imu, truth = ik.sim.simulate(motion, rate=5.0, duration=3600.0, frame=frame)
    return imu, truth.state(0), frame


def test_transport_mean_is_integrate_and_its_covariance_is_consistent() -> None:
    imu, x0, frame = transported()
    p0 = np.diag(SD**2)
    out = ik.propagate(imu, initial=x0, covariance=p0, noise=NOISE, frame=frame, covariance_every=len(imu))
    base = ik.integrate(imu, initial=x0, frame=frame)
    assert np.array_equal(out.position, base.position) and np.array_equal(out.velocity, base.velocity)
    assert np.array_equal(out.rotation.as_quat(), base.rotation.as_quat())
    rng = np.random.default_rng(1)
    errors = np.empty((RUNS, 9))
    for r in range(RUNS):
        d = SD * rng.standard_normal(15)
        start = ik.NavState(x0.position + d[:3], x0.velocity + d[3:6], x0.rotation * Rotation.from_rotvec(d[6:9]))
        moved = ik.LocalLevel(start.position[0], start.position[2], transport=True)  # the truth's own start
        run = ik.integrate(imu, initial=start, frame=moved, bias=ik.ImuBias(gyro=d[12:15], accel=d[9:12]))
        d_theta = (base.rotation[-1].inv() * run.rotation[-1]).as_rotvec()
        errors[r] = np.concatenate(
            [run.position[-1] - base.position[-1], run.velocity[-1] - base.velocity[-1], d_theta]
        )
    metres = np.diag([RN, RE * np.cos(LAT), 1.0, *[1.0] * 6])  # NEES is unit-free; metres condition it

    def nees(cov: np.ndarray) -> float:
        e, c = errors @ metres, metres @ cov[:9, :9] @ metres
        return float(np.einsum("ri,ij,rj->r", e, np.linalg.inv(c), e).mean())

    half = 1.96 * np.sqrt(18 / RUNS)  # 95 % interval of the mean of 400 χ²(9): [8.58, 9.42]
    assert out.covariance is not None
    assert 9 - half < nees(out.covariance[-1]) < 9 + half  # seeds 1, 2, 3: 9.07, 8.97, 9.12
    # Without the curvature and transport terms: the fixed frame's error model at the start
    # (Coriolis only), its metres turned into latitude and longitude.
    fixed = ik.LocalLevel(LAT, HEIGHT)
    p0_metres = np.diag(np.concatenate([[SD[1] * RE * np.cos(LAT), SD[0] * RN], SD[2:]]) ** 2)
    at_start = ik.NavState(np.zeros(3), x0.velocity, x0.rotation)
    flat = ik.propagate(
        imu, initial=at_start, covariance=p0_metres, noise=NOISE, frame=fixed, covariance_every=len(imu)
    )
    to_geodetic = np.eye(15)
    to_geodetic[:3, :3] = [[0, 1 / RN, 0], [1 / (RE * np.cos(LAT)), 0, 0], [0, 0, 1]]
    assert flat.covariance is not None
    assert (
        nees(to_geodetic @ flat.covariance[-1] @ to_geodetic.T) > 1e3
    )  # 2.3e9: no Schuler loop, a vertical channel that does not diverge


def test_schuler_period_in_the_position_covariance() -> None:
    """At rest, a north velocity error of 1 m/s oscillates through the Schuler loop: the north
    position's standard deviation is ``|sin(ω_s t)| / ω_s``, ``ω_s = √(g/(R_N + h))`` (Titterton
    & Weston 2004, §12.3; Groves 2013, §14.2.4); its first zero is at half the Schuler period,
    42.19 min at 45° (84.4 min the period), its peak 1/ω_s = 805 m."""
    frame = ik.LocalLevel(LAT, 0.0, transport=True)
    still = ik.sim.ConstantTwist(body_velocity=(0.0, 0.0, 0.0), body_rate=(0.0, 0.0, 0.0))
    imu, truth = ik.sim.simulate(still, rate=1.0, duration=3600.0, frame=frame)
    p0 = np.zeros((15, 15))
    p0[4, 4] = 1.0  # north velocity (ENU y)
    out = ik.propagate(imu, initial=truth.state(0), covariance=p0, noise=NOISE, frame=frame)
    assert out.covariance is not None
    north = np.sqrt(out.covariance[:, 0, 0]) * (RN - HEIGHT)
    g = -frame.gravity[2]
    omega_s = np.sqrt(g / (RN - HEIGHT))
    first_zero = out.covariance_t[np.argmin(north[600:]) + 600]
    assert abs(first_zero - np.pi / omega_s) < 5.0  # 2529 s (1 s samples) against 2531.5 s
    assert abs(north.max() - 1 / omega_s) < 0.005 / omega_s  # 803.4 m against 805.8 m (Earth-rate coupling)
