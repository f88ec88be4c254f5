"""Preintegration in a rotating navigation frame (``omega_coriolis``): against GTSAM 4.3's
``predict`` (its exact rotating-Earth form), against GTSAM 4.2's first/second-order
``NavState::coriolis`` written out below on GTSAM's own ``NavState.retract``, against an RK4
integration of the rotating-frame mechanisation, and by Monte Carlo NEES over a 60 s powered
trajectory with Earth rotation.

GTSAM 4.3 facts relied on (gtsam 4.3.0 from PyPI): ``predict`` with ``setOmegaCoriolis`` uses
``NavState::predictPIM``'s rotating form for any non-zero ω; the second-order flag is deprecated and
ignored (``PreintegrationParams`` has no Python setter for it); ``NavState.retract`` is still the
component-wise chart ``(R Exp(δR), p + R δp, v + R δv)``.
"""

from __future__ import annotations

import gtsam
import numpy as np
import numpy.typing as npt
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

import imukit as ik
from imukit.preint import States

Array = npt.NDArray[np.float64]
EARTH_RATE = 7.292115e-5  # rad/s (WGS-84)
G = np.array([0.0, 0.0, -9.81])


def enu_earth_rate(latitude_deg: float) -> Array:
    """ω_ie in ENU axes at a latitude: (0, Ω cos φ, Ω sin φ) (Groves 2013, eq. 2.123 rotated to ENU)."""
    lat = np.radians(latitude_deg)
    return EARTH_RATE * np.array([0.0, np.cos(lat), np.sin(lat)])


def random_window(seed: int, n: int = 400) -> tuple[Array, Array, Array]:
    rng = np.random.default_rng(seed)
    acc = rng.normal(0.0, 3.0, (n, 3)) + np.array([0.0, 0.0, 9.81])
    gyro = rng.normal(0.0, 1.0, (n, 3))
    dt = 0.01 * rng.uniform(0.8, 1.2, n)
    return acc, gyro, dt


def random_state(seed: int) -> tuple[Array, Array, Array]:
    rng = np.random.default_rng(seed)
    return rng.normal(0.0, 1e3, 3), rng.normal(0.0, 30.0, 3), Rotation.random(random_state=seed).as_matrix()


def imukit_pim(acc: Array, gyro: Array, dt: Array) -> ik.PreintegratedImu:
    t = np.concatenate([[0.0], np.cumsum(dt)])
    imu = ik.ImuData(t, np.vstack([gyro, gyro[-1]]), np.vstack([acc, acc[-1]]))
    noise = ik.ImuNoise(gyro_density=1e-3, accel_density=1e-2, gyro_random_walk=0.0, accel_random_walk=0.0)
    return ik.preintegrate(imu, noise=noise, scheme="lie_euler")


def gtsam_pim(acc: Array, gyro: Array, dt: Array, omega: Array) -> gtsam.PreintegratedImuMeasurementsManifold:
    p = gtsam.PreintegrationParams.MakeSharedU(9.81)
    p.setGyroscopeCovariance(1e-6 * np.eye(3))
    p.setAccelerometerCovariance(1e-4 * np.eye(3))
    p.setIntegrationCovariance(np.zeros((3, 3)))
    p.setOmegaCoriolis(omega)
    pim = gtsam.PreintegratedImuMeasurementsManifold(p, gtsam.imuBias.ConstantBias())
    for a, w, h in zip(acc, gyro, dt):
        pim.integrateMeasurement(a, w, float(h))
    return pim


def nav_state(p: Array, v: Array, r: Array) -> ik.NavState:
    return ik.NavState(p, v, Rotation.from_matrix(r))


def gap(a: ik.NavState, b: ik.NavState) -> tuple[float, float, float]:
    """Rotation angle [rad], position and velocity differences (max abs)."""
    return (
        float((a.rotation.inv() * b.rotation).magnitude()),
        float(np.abs(a.position - b.position).max()),
        float(np.abs(a.velocity - b.velocity).max()),
    )


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("latitude", [0.0, 45.0, 89.0])
def test_exact_prediction_equals_gtsam_4_3(seed: int, latitude: float) -> None:
    """GTSAM 4.3's ``predict`` with ``omegaCoriolis`` (4 s windows, |p| ~ 1 km, |v| ~ 30 m/s, and a
    1000× Earth rate so that every term is far above rounding). Measured: ≤ 3.2e-15 rad,
    ≤ 4.6e-13 m, ≤ 7.5e-14 m/s; the first-order form is 9.5 to 163 m away."""
    acc, gyro, dt = random_window(seed)
    omega = 1e3 * enu_earth_rate(latitude)
    pim = imukit_pim(acc, gyro, dt)
    ref = gtsam_pim(acc, gyro, dt, omega)
    p, v, r = random_state(seed + 10)
    out = ref.predict(gtsam.NavState(gtsam.Rot3(r), p, v), gtsam.imuBias.ConstantBias())
    expected = ik.NavState(out.position(), out.velocity(), Rotation.from_matrix(out.attitude().matrix()))
    exact = pim.predict(nav_state(p, v, r), omega_coriolis=omega, exact_coriolis=True)
    d_r, d_p, d_v = gap(exact, expected)
    assert d_r < 1e-12 and d_p < 1e-9 and d_v < 1e-9
    first = pim.predict(nav_state(p, v, r), omega_coriolis=omega)
    assert max(gap(first, expected)) > 1e-4  # the orders differ: the comparison can fail


def gtsam_42_coriolis(state: gtsam.NavState, pim: ik.PreintegratedImu, omega: Array, second: bool) -> gtsam.NavState:
    """GTSAM 4.2's prediction, written from ``NavState::correctPIM`` and ``NavState::coriolis``
    (gtsam/navigation/NavState.cpp): ``ξ = [Log ΔR, Δp + Rᵀ(v Δt + ½ g Δt²), Δv + Rᵀ g Δt]`` plus
    ``Rᵀ[−ω Δt, −Δt² ω×v, −2Δt ω×v]`` (second order: ``−Rᵀ[0, ½Δt² ω×ω×p, Δt ω×ω×p]``), then
    ``state.retract(ξ)``."""
    r, p, v = state.attitude().matrix(), state.position(), state.velocity()
    dt = pim.delta_t
    wv, wwp = np.cross(omega, v), np.cross(omega, np.cross(omega, p))
    d_r = pim.delta_rotation.as_rotvec() - r.T @ omega * dt
    d_p = pim.delta_position + r.T @ (
        v * dt + 0.5 * G * dt * dt - dt * dt * wv - (0.5 * dt * dt * wwp if second else 0)
    )
    d_v = pim.delta_velocity + r.T @ (G * dt - 2 * dt * wv - (dt * wwp if second else 0))
    result: gtsam.NavState = state.retract(np.concatenate([d_r, d_p, d_v]))
    return result


@pytest.mark.parametrize("second", [False, True])
@pytest.mark.parametrize("seed", [4, 5])
def test_first_and_second_order_equal_gtsam_4_2(seed: int, second: bool) -> None:
    """Measured ≤ 5.7e-16 rad, ≤ 1.2e-13 m, ≤ 3.6e-14 m/s; the other order is 17 to 58 m away
    at this |p| (1 km) and ω (1000× the Earth's)."""
    acc, gyro, dt = random_window(seed)
    omega = 1e3 * enu_earth_rate(30.0)
    pim = imukit_pim(acc, gyro, dt)
    p, v, r = random_state(seed + 20)
    ref = gtsam_42_coriolis(gtsam.NavState(gtsam.Rot3(r), p, v), pim, omega, second)
    expected = ik.NavState(ref.position(), ref.velocity(), Rotation.from_matrix(ref.attitude().matrix()))
    out = pim.predict(nav_state(p, v, r), omega_coriolis=omega, second_order_coriolis=second)
    d_r, d_p, d_v = gap(out, expected)
    assert d_r < 1e-12 and d_p < 1e-9 and d_v < 1e-9
    other = pim.predict(nav_state(p, v, r), omega_coriolis=omega, second_order_coriolis=not second)
    assert gap(other, expected)[1] > 1e-4


def test_residual_vanishes_at_the_prediction_and_defaults_unchanged() -> None:
    acc, gyro, dt = random_window(6)
    pim = imukit_pim(acc, gyro, dt)
    omega = 1e3 * enu_earth_rate(45.0)
    state_i = nav_state(*random_state(7))
    for flags in ({}, {"second_order_coriolis": True}, {"exact_coriolis": True}):
        state_j = pim.predict(state_i, omega_coriolis=omega, **flags)
        assert np.abs(pim.residual(state_i, state_j, omega_coriolis=omega, **flags)).max() < 1e-9
        # with no Earth rate the model is not satisfied: the residual sees the rotation
        assert np.abs(pim.residual(state_i, state_j)).max() > 1e-3
    # without omega_coriolis, the exact same numbers as before
    plain = pim.predict(state_i)
    assert pim.residual(state_i, plain).tolist() == pim.residual(state_i, plain, omega_coriolis=None).tolist()


def test_keywords_are_checked() -> None:
    acc, gyro, dt = random_window(8, n=10)
    pim = imukit_pim(acc, gyro, dt)
    s = nav_state(*random_state(9))
    with pytest.raises(ik.ShapeError, match="omega_coriolis"):
        pim.predict(s, omega_coriolis=[0.0, 1.0])
    with pytest.raises(ik.NonFiniteError, match="omega_coriolis"):
        pim.predict(s, omega_coriolis=[0.0, np.nan, 0.0])
    with pytest.raises(ik.ParameterError, match="exact_coriolis"):
        pim.predict(s, omega_coriolis=[0.0, 0.0, 1e-4], second_order_coriolis=True, exact_coriolis=True)
    with pytest.raises(ik.ParameterError, match="second_order_coriolis: needs omega_coriolis"):
        pim.residual(s, s, second_order_coriolis=True)
    with pytest.raises(ik.ParameterError, match="exact_coriolis"):
        pim.residual_jacobians(s, s, omega_coriolis=[0.0, 0.0, 1e-4], second_order_coriolis=True, exact_coriolis=True)


# ---- a 60 s powered trajectory in a rotating frame: the mechanisation integrated by RK4 ----------

OMEGA_B = np.array([0.01, -0.02, 0.05])  # constant gyro reading [rad/s] (inertial body rate)
FORCE = np.array([2.0, 0.5, 9.81])  # constant specific force [m/s²]: thrust plus lift
DURATION, RATE = 60.0, 100.0
TACTICAL = ik.ImuNoise(gyro_density=1e-4, accel_density=1e-3, gyro_random_walk=0.0, accel_random_walk=0.0)


def rk4_truth(omega: Array, p0: Array, v0: Array, r0: Array, steps: int) -> tuple[Array, Array, Array]:
    """The rotating-frame mechanisation (Titterton & Weston 2004, eq. 3.33, with centrifugal):
    ``Ṙ = R[ω_b]× − [ω]×R`` (solved in closed form: ``R(t) = Exp(−ωt) R₀ Exp(ω_b t)``),
    ``v̇ = R f + g − 2ω×v − ω×(ω×p)``, ``ṗ = v`` by classical RK4."""

    def rot(t: float) -> Array:
        out: Array = Rotation.from_rotvec(-omega * t).as_matrix() @ r0 @ Rotation.from_rotvec(OMEGA_B * t).as_matrix()
        return out

    def deriv(t: float, x: Array) -> Array:
        p, v = x[:3], x[3:]
        acc = rot(t) @ FORCE + G - 2 * np.cross(omega, v) - np.cross(omega, np.cross(omega, p))
        return np.concatenate([v, acc])

    x, h = np.concatenate([p0, v0]), DURATION / steps
    for k in range(steps):
        t = k * h
        k1 = deriv(t, x)
        k2 = deriv(t + h / 2, x + h / 2 * k1)
        k3 = deriv(t + h / 2, x + h / 2 * k2)
        k4 = deriv(t + h, x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x[:3], x[3:], rot(DURATION)


@pytest.fixture(scope="module")
def powered() -> tuple[ik.NavState, ik.NavState, Array]:
    omega = enu_earth_rate(45.0)
    p0, v0 = np.array([0.0, 0.0, 1000.0]), np.array([50.0, 20.0, 0.0])
    r0 = Rotation.from_euler("ZYX", [30, 5, -3], degrees=True).as_matrix()
    p1, v1, r1 = rk4_truth(omega, p0, v0, r0, 3000)
    return nav_state(p0, v0, r0), nav_state(p1, v1, r1), omega


def noisy_imu(rng: np.random.Generator, sigma_g: float, sigma_a: float, rate: float = RATE) -> ik.ImuData:
    n = int(DURATION * rate) + 1
    t = np.arange(n) / rate
    gyro = OMEGA_B + rng.normal(0.0, sigma_g * np.sqrt(rate), (n, 3))
    accel = FORCE + rng.normal(0.0, sigma_a * np.sqrt(rate), (n, 3))
    return ik.ImuData(t, gyro, accel)


def test_exact_prediction_equals_rk4_mechanisation(powered: tuple[ik.NavState, ik.NavState, Array]) -> None:
    """Noise-free constant readings: the exact form reproduces the RK4 solution of the rotating-frame
    equations up to the midpoint deltas' own O(h²) error (measured at 100 / 200 Hz: 1.6e-4 /
    3.9e-5 m, 3.0e-6 / 7.6e-7 m/s, 4e-15 rad); the first-order form is 4.3e-3 rad and 23 m off (its
    ``Exp(Log ΔR − Δt Rᵀω)`` mixes the 3.3 rad turn with the Earth's), ignoring ω costs 1.2 m/s and
    20 m."""
    state_i, state_j, omega = powered
    gaps = []
    for rate in (RATE, 2 * RATE):
        pim = ik.preintegrate(noisy_imu(np.random.default_rng(0), 0.0, 0.0, rate), noise=TACTICAL)
        gaps.append(gap(pim.predict(state_i, omega_coriolis=omega, exact_coriolis=True), state_j))
    assert gaps[0][0] < 1e-12 and gaps[0][1] < 3e-4 and gaps[0][2] < 1e-5
    assert 3.5 < gaps[0][1] / gaps[1][1] < 4.5 and 3.5 < gaps[0][2] / gaps[1][2] < 4.5  # the scheme's O(h²)
    d_r, d_p, _ = gap(pim.predict(state_i, omega_coriolis=omega), state_j)
    assert d_r > 1e-3 and d_p > 10.0
    _, d_p, d_v = gap(pim.predict(state_i), state_j)
    assert d_p > 10.0 and d_v > 1.0


def test_nees_with_earth_rotation(powered: tuple[ik.NavState, ik.NavState, Array]) -> None:
    """400 noisy 60 s runs (σ_g = 1e-4 rad/s/√Hz, σ_a = 1e-3 m/s²/√Hz: tactical grade): the mean
    NEES ``rᵀ Σ⁻¹ r`` of the exact residual at the true states lies in the 95% χ² interval of the
    mean of 400 χ²₉ (measured 9.33 in [8.59, 9.42]; 3 × 1000 runs
    gave 8.79, 9.12, 9.01, each ± 0.13); the first-order model (521) and no Earth model (2954)
    are inconsistent by orders of magnitude."""
    state_i, state_j, omega = powered
    rng = np.random.default_rng(22)
    trials = 400
    nees: dict[str, list[float]] = {"exact": [], "first": [], "none": []}
    for _ in range(trials):
        pim = ik.preintegrate(noisy_imu(rng, 1e-4, 1e-3), noise=TACTICAL)
        info = np.linalg.inv(pim.covariance)
        for name, kw in (("exact", {"exact_coriolis": True}), ("first", {}), ("none", None)):
            r = (
                pim.residual(state_i, state_j)
                if kw is None
                else pim.residual(state_i, state_j, omega_coriolis=omega, **kw)
            )
            nees[name].append(float(r @ info @ r))
    lo, hi = chi2.ppf([0.025, 0.975], 9 * trials) / trials
    assert lo < np.mean(nees["exact"]) < hi
    assert np.mean(nees["first"]) > 10 * hi and np.mean(nees["none"]) > 100 * hi


def test_batched_predict_matches_single(powered: tuple[ik.NavState, ik.NavState, Array]) -> None:
    """The batched ``imukit.preint.predict`` on a record is the method's."""
    state_i, _, omega = powered
    imu = noisy_imu(np.random.default_rng(3), 1e-4, 1e-3)
    pim = ik.preintegrate(imu, noise=TACTICAL)
    states = States(state_i.position[None], state_i.velocity[None], state_i.rotation.as_matrix()[None])
    p, v, r = ik.preint.predict(pim.snapshot(), states, omega_coriolis=omega, exact_coriolis=True)
    one = pim.predict(state_i, omega_coriolis=omega, exact_coriolis=True)
    assert np.array_equal(r[0], one.rotation.as_matrix()) or np.abs(r[0] - one.rotation.as_matrix()).max() < 1e-15
    assert np.array_equal(p[0], one.position) and np.array_equal(v[0], one.velocity)


@pytest.mark.parametrize("model", ["exact", "first", "second"])
def test_residual_jacobians_equal_central_differences(
    powered: tuple[ik.NavState, ik.NavState, Array], model: str
) -> None:
    """Jacobians of the rotating-frame residual (each model) against central differences of
    ``residual`` in imukit's charts (``p + δp``, ``v + δv``, ``R Exp(δθ)``; bias through the
    correction), with a 1000× Earth rate so that the Coriolis terms show (the plain Jacobians
    differ by > 1e-3). Measured (i, j): exact 1.7e-9, 9.0e-9; first order 1.7e-9, 6.5e-9; second the same."""
    state_i, state_j, _ = powered
    omega = 1e3 * enu_earth_rate(45.0)
    imu = noisy_imu(np.random.default_rng(4), 1e-4, 1e-3)
    pim = ik.preintegrate(imu, noise=TACTICAL, bias=ik.ImuBias(gyro=[1e-3, 0, -1e-3], accel=[0.01, 0.02, 0]))
    bias = ik.ImuBias(gyro=[2e-3, 1e-3, -1e-3], accel=[0.0, 0.03, 0.01])
    flags = {"exact": {"exact_coriolis": True}, "first": {}, "second": {"second_order_coriolis": True}}[model]
    kw = {"omega_coriolis": omega, **flags}
    jac = pim.residual_jacobians(state_i, state_j, bias, **kw)

    def moved(s: ik.NavState, d: Array) -> ik.NavState:
        return ik.NavState(s.position + d[0:3], s.velocity + d[3:6], s.rotation * Rotation.from_rotvec(d[6:9]))

    h = 1e-4  # measured: 1.7e-9 (i), 9e-9 (j) relative; truncation and rounding balance here
    for which, expected in (("i", jac.state_i), ("j", jac.state_j)):
        numeric = np.zeros((9, 9))
        for k in range(9):
            d = np.zeros(9)
            d[k] = h
            plus = (moved(state_i, d), state_j) if which == "i" else (state_i, moved(state_j, d))
            minus = (moved(state_i, -d), state_j) if which == "i" else (state_i, moved(state_j, -d))
            numeric[:, k] = (pim.residual(*plus, bias, **kw) - pim.residual(*minus, bias, **kw)) / (2 * h)
        assert np.abs(numeric - expected).max() < 1e-7 * np.abs(expected).max()
    numeric = np.zeros((9, 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = h
        up = ik.ImuBias(gyro=bias.gyro + d[0:3], accel=bias.accel + d[3:6])
        down = ik.ImuBias(gyro=bias.gyro - d[0:3], accel=bias.accel - d[3:6])
        numeric[:, k] = (pim.residual(state_i, state_j, up, **kw) - pim.residual(state_i, state_j, down, **kw)) / (
            2 * h
        )
    assert np.abs(numeric - jac.bias).max() < 1e-6 * np.abs(jac.bias).max()
    plain = pim.residual_jacobians(state_i, state_j, bias)
    for name in ("state_i", "state_j"):
        assert np.abs(getattr(plain, name) - getattr(jac, name)).max() > 1e-3 * np.abs(getattr(jac, name)).max()
