"""``preintegrate(..., body_from_sensor=(R_bs, lever arm))``: a sensor off the body origin. The
readings become the body origin's before the step (centripetal and tangential terms, angular
acceleration from the gyro's central difference); checked against an analytic spinning body,
re-integration after a bias change (the bias Jacobian's centripetal term), merge = one pass, the
windows of one batch, and GTSAM 4.3's ``body_P_sensor`` at a constant rate."""

from __future__ import annotations

import pickle

import gtsam
import numpy as np
import numpy.typing as npt
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from test_preint_extrinsics import assert_one_pass

Array = npt.NDArray[np.float64]
R_BS = Rotation.from_euler("ZYX", [120, -30, 45], degrees=True)
ARM = np.array([0.3, -0.1, 0.2])
POSE = (R_BS, ARM)
NOISE = ik.ImuNoise(gyro_density=2e-3, accel_density=2e-2, gyro_random_walk=0.0, accel_random_walk=0.0)
BIAS = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.1, 0.05, -0.2])


def readings(seed: int, n: int = 401, jitter: float = 0.0) -> ik.ImuData:
    rng = np.random.default_rng(seed)
    t = np.concatenate([[0.0], np.cumsum(0.005 * rng.uniform(1 - jitter, 1 + jitter, n - 1))])
    # smooth rates (a lever arm needs a differentiable rate), random specific force
    k = np.arange(n)[:, None] * 0.005
    gyro = np.sin(k * rng.uniform(1, 4, 3) + rng.uniform(0, 6, 3)) * rng.uniform(0.5, 2.0, 3)
    return ik.ImuData(t, gyro, rng.normal(0.0, 3.0, (n, 3)) + np.array([0.0, 0.0, 9.81]))


def spinning(h: float, arm: Array) -> ik.ImuData:
    """A body whose origin stays still while it turns about a tilted axis u by θ(t) = 2t + t³
    (rate and angular acceleration both varying), read by a sensor at ``arm`` (body axes): its
    specific force is the body's, ``Rᵀ(0, 0, 9.81)``, plus ``α×r + ω×(ω×r)``, with ``ω = θ̇ u``,
    ``α = θ̈ u`` (u is fixed in both frames)."""
    t = np.arange(0.0, 1.0 + h / 2, h)
    u = np.array([0.3, 0.2, 0.9]) / np.linalg.norm([0.3, 0.2, 0.9])
    w = np.outer(2.0 + 3.0 * t * t, u)
    alpha = np.outer(6.0 * t, u)
    r = Rotation.from_rotvec(np.outer(2.0 * t + t**3, u))
    f = r.inv().apply([0.0, 0.0, 9.81]) + np.cross(alpha, arm) + np.cross(w, np.cross(w, arm))
    return ik.ImuData(t, w, f)


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_a_spinning_body_is_recovered_to_the_scheme_order(scheme: str) -> None:
    """The body stays at the origin: predicted from rest it stays there to the scheme's order
    (measured midpoint 200 Hz 1.44e-5 m, 400 Hz 3.6e-6 m; lie_euler 200 Hz 1.86e-3 m, 400 Hz 9.4e-4
    m: first order, as its rotation). Without the lever arm the prediction is 0.69 m off."""
    start = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    errors = []
    for h in (0.005, 0.0025):
        imu = spinning(h, ARM)
        pim = ik.preintegrate(imu, noise=NOISE, scheme=scheme, body_from_sensor=(Rotation.identity(), ARM))
        end = pim.predict(start)
        errors.append(float(np.abs(end.position).max()))
        truth = Rotation.from_rotvec(3.0 * np.array([0.3, 0.2, 0.9]) / np.linalg.norm([0.3, 0.2, 0.9]))
        assert (end.rotation.inv() * truth).magnitude() < 1e-2
    order = 2 if scheme == "midpoint" else 1
    assert errors[0] < (3e-5 if order == 2 else 4e-3)
    assert 0.7 * 2**order < errors[0] / errors[1] < 1.3 * 2**order
    plain = ik.preintegrate(spinning(0.005, ARM), noise=NOISE, scheme=scheme).predict(start)
    assert np.abs(plain.position).max() > 0.5


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_bias_jacobian_equals_reintegration_and_needs_its_centripetal_term(scheme: str) -> None:
    """Central differences of re-integrations after a bias change (step 1e-6): measured 8.3e-9
    (midpoint) and 1.1e-8 (lie_euler) absolute against entries up to 13.8. The centripetal term
    ``L`` (v, p rows, gyro columns) reaches 0.38 there: a Jacobian without it, or with it doubled,
    is 10⁵× outside the bound."""
    imu = readings(1)
    params = ik.PreintParams(NOISE, BIAS, scheme=scheme, body_from_sensor=POSE)
    jac = ik.preintegrate(imu, params).bias_jacobian
    ref = ik.preintegrate(imu, params).delta_rotation
    num = np.zeros((9, 6))
    eps = 1e-6
    for c in range(6):
        d = np.zeros(6)
        d[c] = eps
        out = []
        for sign in (1.0, -1.0):
            b = ik.ImuBias(gyro=BIAS.gyro + sign * d[:3], accel=BIAS.accel + sign * d[3:])
            q = ik.preintegrate(imu, params.replace(bias=b))
            out.append(np.concatenate([(ref.inv() * q.delta_rotation).as_rotvec(), q.delta_velocity, q.delta_position]))
        num[:, c] = (out[0] - out[1]) / (2 * eps)
    assert np.abs(num - jac).max() < 2e-7
    # Without the centripetal term: the body-origin readings' own Jacobian mapped by R_bs.
    gyro, accel = ik._core.body_readings(imu.seconds, imu.gyro, imu.accel, BIAS, R_BS.as_matrix().tolist(), list(ARM))
    body = ik.preintegrate(ik.ImuData(imu.t, gyro, accel), noise=NOISE, scheme=scheme).bias_jacobian
    no_l = np.concatenate([body[:, 0:3] @ R_BS.as_matrix(), body[:, 3:6] @ R_BS.as_matrix()], axis=1)
    assert np.abs(no_l[:, 3:6] - jac[:, 3:6]).max() < 1e-12  # L is in the gyro columns only
    assert np.abs(num - no_l).max() > 1e5 * 2e-7  # zero L
    assert np.abs(num - (2 * jac - no_l)).max() > 1e5 * 2e-7  # doubled L


@pytest.mark.parametrize(("scheme", "jitter"), [("midpoint", 0.0), ("lie_euler", 0.2)])
def test_merge_with_a_lever_arm_equals_one_pass(scheme: str, jitter: float) -> None:
    """Spans cut from one batch (``span=``: the edge's angular acceleration sees both sides) merge
    into the one pass; GTSAM throws on a merge with ``body_P_sensor``. Measured: ΔR ≤ 9.8e-16 rad,
    Δv, Δp ≤ 7.9e-16, covariance ≤ 1.7e-15, bias Jacobian ≤ 1.3e-15 relative. Regular stamps for midpoint (its
    boundary sample has one interval length on each side only then, pose or not)."""
    imu = readings(4, jitter=jitter)
    params = ik.PreintParams(NOISE, BIAS, scheme=scheme, body_from_sensor=POSE)
    whole = ik.preintegrate(imu, params)
    cut = float(imu.t[200])
    merged = ik.preintegrate(imu, params, span=(0.0, cut)).merge(
        ik.preintegrate(imu, params, span=(cut, float(imu.t[-1])))
    )
    assert_one_pass(whole, merged)
    streamed = ik.PreintegratedImu(params)  # spans of one buffer, one call each: the one pass, bit for bit
    streamed.integrate(imu, span=(0.0, cut))
    streamed.integrate(imu, span=(cut, float(imu.t[-1])))
    # the complete covariance of a second span merges into the first's (lever.rs), to rounding
    assert np.abs(streamed.covariance - whole.covariance).max() < 1e-12 * np.abs(whole.covariance).max()
    assert np.array_equal(streamed.bias_jacobian, whole.bias_jacobian)
    # Pieces converted on their own (one-sided differences at the cut) are not the one pass:
    # the core's continuity check refuses them (the shared sample's converted readings differ).
    pieces = ik.preintegrate(imu[:201], params), ik.preintegrate(imu[200:], params)
    with pytest.raises(ik.ParameterError, match="continuation"):
        pieces[0].merge(pieces[1])
    # the windows of preintegrate_windows are the spans', exactly
    rec = ik.preintegrate_windows(imu, [0.0, cut, float(imu.t[-1])], params)
    first = ik.preintegrate(imu, params, span=(0.0, cut))
    for name in ("delta_velocity", "delta_position", "covariance", "bias_jacobian"):
        assert np.array_equal(getattr(rec, name)[0], getattr(first, name))
    copy = pickle.loads(pickle.dumps(first))  # the lever arm's pieces travel with it
    second = ik.preintegrate(imu, params, span=(cut, float(imu.t[-1])))
    assert np.array_equal(copy.merge(second).bias_jacobian, merged.bias_jacobian)


def test_what_a_lever_arm_refuses() -> None:
    pim = ik.PreintegratedImu(noise=NOISE, body_from_sensor=POSE)
    with pytest.raises(ik.ParameterError, match="body_from_sensor"):
        pim.integrate_measurement([0.0, 0.0, 9.81], [0.0, 0.0, 0.1], 0.0)
    imu = readings(5, 20)
    for bad in ((0.0, 0.001), (0.05, 0.0), (0.0,), "all"):
        with pytest.raises(ik.ImukitError, match="span"):
            ik.preintegrate(imu, noise=NOISE, span=bad)  # type: ignore[arg-type]


def constant_rate(n: int = 301) -> ik.ImuData:
    """A sensor turning at a constant rate (α = 0: GTSAM's centripetal-only correction is then the
    whole lever-arm term, and the central difference is exactly zero), random specific force."""
    rng = np.random.default_rng(7)
    t = np.arange(n) * 0.005
    gyro = np.tile([0.7, -1.1, 1.9], (n, 1))
    return ik.ImuData(t, gyro, rng.normal(0.0, 3.0, (n, 3)) + np.array([0.0, 0.0, 9.81]))


def test_prediction_equals_gtsam_body_p_sensor_with_a_lever_arm() -> None:
    """GTSAM 4.3's manifold preintegration with ``body_P_sensor = (R_bs, r)``: it converts each
    sample by ``ω_b = R ω̂``, ``a_b = R â − ω_b×(ω_b×r)`` (centripetal only, no angular
    acceleration), so at a constant rate both are the same discrete model: measured 4.7e-15 rad,
    6.4e-14 m, 4.3e-14 m/s (without the lever arm 0.80 m off). Its bias Jacobians omit both
    ``R_bs`` and the centripetal term ``L``: after a gyro bias change of 0.01 rad/s ours is 3.8e-4 m
    from the re-integration (second order), GTSAM's 4.6e-2 m."""
    imu = constant_rate()
    bias = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.1, 0.05, -0.2])
    p = gtsam.PreintegrationParams.MakeSharedU(9.81)
    p.setGyroscopeCovariance(4e-6 * np.eye(3))
    p.setAccelerometerCovariance(4e-4 * np.eye(3))
    p.setIntegrationCovariance(np.zeros((3, 3)))
    p.setBodyPSensor(gtsam.Pose3(gtsam.Rot3(R_BS.as_matrix()), ARM))
    ref = gtsam.PreintegratedImuMeasurementsManifold(p, gtsam.imuBias.ConstantBias(bias.accel, bias.gyro))
    for k in range(len(imu) - 1):
        ref.integrateMeasurement(imu.accel[k], imu.gyro[k], float(imu.t[k + 1] - imu.t[k]))
    params = ik.PreintParams(NOISE, bias, scheme="lie_euler", body_from_sensor=POSE)
    pim = ik.preintegrate(imu, params)
    rot = Rotation.random(random_state=3)
    pos, vel = np.array([10.0, -3.0, 2.0]), np.array([1.0, 2.0, -0.5])
    state, g_state = ik.NavState(pos, vel, rot), gtsam.NavState(gtsam.Rot3(rot.as_matrix()), pos, vel)

    def theirs(b: ik.ImuBias) -> ik.NavState:
        out = ref.predict(g_state, gtsam.imuBias.ConstantBias(b.accel, b.gyro))
        return ik.NavState(out.position(), out.velocity(), Rotation.from_matrix(out.attitude().matrix()))

    ours, same = pim.predict(state), theirs(bias)
    assert (ours.rotation.inv() * same.rotation).magnitude() < 1e-9
    assert np.abs(ours.position - same.position).max() < 1e-9
    assert np.abs(ours.velocity - same.velocity).max() < 1e-9
    # without the lever arm GTSAM's prediction is decimetres away: the comparison can fail
    rotated = ik.preintegrate(imu, params.replace(body_from_sensor=(R_BS, np.zeros(3)))).predict(state)
    assert np.abs(rotated.position - same.position).max() > 0.1

    moved = ik.ImuBias(gyro=bias.gyro + 0.01, accel=bias.accel)
    exact = ik.preintegrate(imu, params.replace(bias=moved)).predict(state)
    assert np.abs(pim.predict(state, moved).position - exact.position).max() < 1e-3
    assert np.abs(theirs(moved).position - exact.position).max() > 1e-2


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_engines_agree_with_a_lever_arm(scheme: str) -> None:
    """The lever arm wraps every engine the same way: the numpy reference engine gives the Rust
    one's record to the engines' usual 1e-12 / 1e-10."""
    imu = readings(6, 120, jitter=0.2)
    params = ik.PreintParams(NOISE, BIAS, scheme=scheme, body_from_sensor=POSE)
    edges = [0.0, float(imu.t[25]), float(imu.t[60]), float(imu.t[-1])]
    rust, ref = (ik.preintegrate_windows(imu, edges, params, engine=e) for e in ("rust", "numpy_ref"))
    for name, bound in (
        ("delta_velocity", 1e-12),
        ("delta_position", 1e-12),
        ("bias_jacobian", 1e-12),
        ("covariance", 1e-10),
    ):
        x, y = getattr(rust, name), getattr(ref, name)
        assert np.abs(x - y).max() < bound * np.abs(x).max()
    assert rust.params == params
