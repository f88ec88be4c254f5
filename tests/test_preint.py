"""Preintegration from Python: prediction equals strapdown integration, residual zero at the
prediction and first-order in a perturbation, streaming equals batch, bias correction."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from trajectories import attitude, body_rate, position, specific_force, velocity

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)


def window() -> tuple[ik.ImuData, ik.NavState]:
    t = np.linspace(0.0, 1.0, 201)
    z = np.zeros(1)
    return ik.ImuData(t, body_rate(t), specific_force(t)), ik.NavState(position(z)[0], velocity(z)[0], attitude(z)[0])


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
def test_predict_equals_strapdown_of_the_same_scheme(scheme: str) -> None:
    """The preintegrated prediction and the strapdown step of the same scheme are one discrete model."""
    imu, x0 = window()
    bias = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.1, 0.05, -0.2])
    pim = ik.preintegrate(imu, noise=NOISE, bias=bias, scheme=scheme)
    pred = pim.predict(x0)
    traj = ik.integrate(imu, initial=x0, bias=bias, scheme=scheme)
    assert np.abs(pred.position - traj.position[-1]).max() < 1e-11
    assert np.abs(pred.velocity - traj.velocity[-1]).max() < 1e-11
    assert (pred.rotation.inv() * traj.rotation[-1]).magnitude() < 1e-12
    assert pim.delta_t == pytest.approx(1.0, abs=1e-15)


def test_residual_is_zero_at_the_prediction_and_linear_nearby() -> None:
    imu, x0 = window()
    pim = ik.preintegrate(imu, noise=NOISE)
    xj = pim.predict(x0)
    assert np.abs(pim.residual(x0, xj)).max() < 1e-12
    moved = ik.NavState(
        xj.position + np.array([0.01, 0.0, 0.0]), xj.velocity, xj.rotation * Rotation.from_rotvec([0, 0, 1e-3])
    )
    r = pim.residual(x0, moved)
    assert r[2] == pytest.approx(1e-3, rel=1e-9)  # δθ_z
    assert np.abs(r[6:9] - x0.rotation.inv().apply([0.01, 0.0, 0.0])).max() < 1e-12


def test_streaming_equals_batch() -> None:
    imu, _ = window()
    batch = ik.preintegrate(imu, noise=NOISE, scheme="euler")
    stream = ik.PreintegratedImu(noise=NOISE, scheme="euler")
    for k in range(len(imu) - 1):
        stream.integrate_measurement(imu.accel[k], imu.gyro[k], imu.seconds[k + 1] - imu.seconds[k])
    assert np.array_equal(stream.delta_position, batch.delta_position)
    assert np.array_equal(stream.covariance, batch.covariance)
    assert np.array_equal(stream.bias_jacobian, batch.bias_jacobian)
    cov = batch.covariance
    assert np.array_equal(cov, cov.T) and np.all(np.linalg.eigvalsh(cov) > 0)


def test_corrected_is_first_order_in_the_bias_change() -> None:
    imu, _ = window()
    pim = ik.preintegrate(imu, noise=NOISE)
    gaps = []
    for s in (1e-2, 5e-3):
        b = ik.ImuBias(gyro=np.array([0.3, -0.5, 0.2]) * s, accel=np.array([-0.4, 0.1, 0.6]) * s)
        r, v, p = pim.corrected(b)
        exact = ik.preintegrate(imu, noise=NOISE, bias=b)
        gaps.append(
            max(
                (r.inv() * exact.delta_rotation).magnitude(),
                np.abs(v - exact.delta_velocity).max(),
                np.abs(p - exact.delta_position).max(),
            )
        )
    assert 3.5 < gaps[0] / gaps[1] < 4.5  # quadratic remainder


def test_bad_input() -> None:
    imu, _ = window()
    pim = ik.PreintegratedImu(noise=NOISE, scheme="euler")
    with pytest.raises(ik.ParameterError, match="dt"):
        pim.integrate_measurement([0, 0, 9.81], [0, 0, 0], 0.0)
    with pytest.raises(ik.NonFiniteError, match="gyro"):
        pim.integrate_measurement([0, 0, 9.81], [0, np.nan, 0], 0.005)
    with pytest.raises(ik.ShapeError, match="accel"):
        pim.integrate_measurement([0, 9.81], [0, 0, 0], 0.005)
    with pytest.raises(ik.ParameterError, match="scheme"):
        ik.preintegrate(imu, noise=NOISE, scheme="rk4")
    assert pim.delta_t == 0.0  # nothing was added by the refused calls


def test_combined_covariance() -> None:
    imu, _ = window()
    plain = ik.preintegrate(imu, noise=NOISE)
    assert plain.covariance_combined is None
    pim = ik.preintegrate(imu, noise=NOISE, combined=True)
    c = pim.covariance_combined
    assert c is not None and c.shape == (15, 15)
    assert np.array_equal(c, c.T)
    # the bias blocks are the accumulated random walk: σ² Δt on the diagonal
    assert np.allclose(np.diag(c)[9:12], NOISE.gyro_random_walk**2 * pim.delta_t, rtol=1e-12)
    assert np.allclose(np.diag(c)[12:15], NOISE.accel_random_walk**2 * pim.delta_t, rtol=1e-12)
    # the walk adds to the 9×9 part, and the cross terms are nonzero
    assert np.all(np.diag(c)[:9] > np.diag(plain.covariance))
    assert np.abs(c[:9, 9:]).max() > 0
    assert np.all(np.linalg.eigvalsh(c) > 0)


def test_merge_equals_one_preintegration() -> None:
    imu, x0 = window()
    whole = ik.preintegrate(imu, noise=NOISE)
    merged = ik.preintegrate(imu[:81], noise=NOISE).merge(ik.preintegrate(imu[80:], noise=NOISE))
    assert merged.delta_t == pytest.approx(whole.delta_t, abs=1e-15)
    assert np.abs(merged.delta_position - whole.delta_position).max() < 1e-13
    assert np.abs(merged.covariance - whole.covariance).max() < 1e-12 * np.abs(whole.covariance).max()
    assert np.abs(merged.bias_jacobian - whole.bias_jacobian).max() < 1e-12 * np.abs(whole.bias_jacobian).max()
    pred = merged.predict(x0)
    assert np.abs(pred.position - whole.predict(x0).position).max() < 1e-12
    with pytest.raises(ik.ParameterError, match="same bias"):
        whole.merge(ik.preintegrate(imu, noise=NOISE, bias=ik.ImuBias(gyro=[0.1, 0, 0])))


def test_reintegrate_replays_the_samples_with_the_new_bias() -> None:
    imu, _ = window()
    b = ik.ImuBias(gyro=[0.02, -0.01, 0.03], accel=[0.2, -0.1, 0.05])
    pim = ik.PreintegratedImu(noise=NOISE, scheme="euler")
    pim.integrate(imu[:101])
    for k in range(100, len(imu) - 1):  # and a streamed tail
        pim.integrate_measurement(imu.accel[k], imu.gyro[k], imu.seconds[k + 1] - imu.seconds[k])
    again = pim.reintegrate(b)
    fresh = ik.preintegrate(imu, noise=NOISE, bias=b, scheme="euler")
    assert again.bias == b
    assert np.abs(again.delta_position - fresh.delta_position).max() < 1e-13
    assert np.abs(again.covariance - fresh.covariance).max() < 1e-12 * np.abs(fresh.covariance).max()
    # and it is better than the first-order correction for this bias change
    _, _, p_first_order = pim.corrected(b)
    assert np.abs(p_first_order - fresh.delta_position).max() > 1e-6


def test_midpoint_streaming_and_batches_equal_one_batch() -> None:
    imu, _ = window()
    whole = ik.preintegrate(imu, noise=NOISE)
    assert whole.scheme == "midpoint"  # the default
    stream = ik.PreintegratedImu(noise=NOISE)
    with pytest.raises(ik.ParameterError, match="dt: the first sample of a midpoint window"):
        stream.integrate_measurement(imu.accel[0], imu.gyro[0], 0.005)
    stream.integrate_measurement(imu.accel[0], imu.gyro[0], 0.0)
    for k in range(1, len(imu)):
        stream.integrate_measurement(imu.accel[k], imu.gyro[k], imu.seconds[k] - imu.seconds[k - 1])
    assert np.array_equal(stream.delta_position, whole.delta_position)
    assert np.array_equal(stream.covariance, whole.covariance)
    # two batches sharing sample 80 are one batch, covariance included
    two = ik.PreintegratedImu(noise=NOISE)
    two.integrate(imu[:81])
    two.integrate(imu[80:])
    assert np.abs(two.delta_position - whole.delta_position).max() < 1e-13
    assert np.abs(two.covariance - whole.covariance).max() < 1e-12 * np.abs(whole.covariance).max()
    with pytest.raises(ik.ParameterError, match="imu: expected a continuation starting with the"):
        two.integrate(imu[100:])
    assert two.delta_t == pytest.approx(whole.delta_t, abs=1e-14)  # the refused batch added nothing


def _perturbed(x: ik.NavState, d: np.ndarray) -> ik.NavState:
    """``x ⊕ d`` in imukit's NavState chart ``[δp, δv, δθ]``."""
    return ik.NavState(x.position + d[0:3], x.velocity + d[3:6], x.rotation * Rotation.from_rotvec(d[6:9]))


def _central(f: Callable[[np.ndarray], np.ndarray], n: int, eps: float = 1e-6) -> np.ndarray:
    cols = [(f(eps * e) - f(-eps * e)) / (2 * eps) for e in np.eye(n)]
    return np.stack(cols, axis=1)


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
@pytest.mark.parametrize("offset", [0.0, 0.3])
def test_residual_jacobians_match_central_differences(scheme: str, offset: float) -> None:
    """State columns by differences of ``residual`` itself; bias columns by differences of full
    re-integrations with the perturbed bias (at the integration bias, where the first-order correction
    is exact to first order) and of the corrected residual (away from it)."""
    imu, x0 = window()
    bias = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.1, 0.05, -0.2])
    pim = ik.preintegrate(imu, noise=NOISE, bias=bias, scheme=scheme)
    rng = np.random.default_rng(7)
    xi = _perturbed(x0, offset * rng.normal(size=9))
    xj = _perturbed(pim.predict(x0), offset * rng.normal(size=9))
    jac = pim.residual_jacobians(xi, xj)
    num_i = _central(lambda d: pim.residual(_perturbed(xi, d), xj), 9)
    num_j = _central(lambda d: pim.residual(xi, _perturbed(xj, d)), 9)

    def reintegrated(d: np.ndarray) -> np.ndarray:
        b = ik.ImuBias(gyro=bias.gyro + d[0:3], accel=bias.accel + d[3:6])
        return ik.preintegrate(imu, noise=NOISE, bias=b, scheme=scheme).residual(xi, xj)

    num_b = _central(reintegrated, 6)
    for analytic, numeric in [(jac.state_i, num_i), (jac.state_j, num_j), (jac.bias, num_b)]:
        assert np.abs(analytic - numeric).max() < 1e-6 * max(1.0, np.abs(numeric).max())
    # away from the integration bias the Jacobian is that of the corrected residual
    moved = ik.ImuBias(gyro=bias.gyro + np.array([0.02, -0.01, 0.015]), accel=bias.accel + np.array([0.1, 0.2, -0.1]))
    jac_moved = pim.residual_jacobians(xi, xj, moved).bias

    def corrected(d: np.ndarray) -> np.ndarray:
        b = ik.ImuBias(gyro=moved.gyro + d[0:3], accel=moved.accel + d[3:6])
        return pim.residual(xi, xj, b)

    assert np.abs(jac_moved - _central(corrected, 6)).max() < 1e-6 * np.abs(jac_moved).max()
    # and away from the prediction its rotation block depends on the bias change (the J_r(J δb) term;
    # at the prediction J_r⁻¹(r) Exp(r)ᵀ cancels it)
    if offset > 0:
        assert np.abs(jac_moved[0:3, 0:3] - jac.bias[0:3, 0:3]).max() > 1e-4


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
def test_windows_on_samples_equal_preintegrations_of_the_slices(scheme: str) -> None:
    imu, _ = window()
    cuts = [0, 37, 100, 200]
    windows = ik.preintegrate_windows(imu, imu.t[cuts], noise=NOISE, scheme=scheme, combined=True)
    assert [w.scheme for w in windows] == [scheme] * 3
    for w, lo, hi in zip(windows, cuts[:-1], cuts[1:], strict=True):
        alone = ik.preintegrate(imu[lo : hi + 1], noise=NOISE, scheme=scheme, combined=True)
        assert np.abs(w.delta_position - alone.delta_position).max() < 1e-14
        assert np.abs(w.covariance - alone.covariance).max() <= 1e-14 * np.abs(alone.covariance).max()
        combined, alone_combined = w.covariance_combined, alone.covariance_combined
        assert combined is not None and alone_combined is not None
        assert np.abs(combined - alone_combined).max() <= 1e-14 * np.abs(alone_combined).max()
    one, two = (
        ik.preintegrate_windows(imu, imu.t[cuts], noise=NOISE, scheme=scheme, threads=n)[1].covariance for n in (1, 2)
    )
    assert np.array_equal(one, two)


def test_windows_between_samples_integer_stamps_and_reintegration() -> None:
    t_ns = np.arange(201, dtype=np.int64) * 5_000_000 + 1_403_636_579_758_555_392
    imu_f, _ = window()
    imu = ik.ImuData(t_ns, imu_f.gyro, imu_f.accel)
    b = [t_ns[0] + 12_345_678, t_ns[0] + 500_000_000, t_ns[-1] - 1]
    windows = ik.preintegrate_windows(imu, b, noise=NOISE, scheme="euler")
    assert [w.delta_t for w in windows] == pytest.approx([0.487654322, 0.499999999], abs=1e-12)
    # euler holds sample 2 over [b0, t_3): the same as integrateMeasurement with the shortened step
    manual = ik.PreintegratedImu(noise=NOISE, scheme="euler")
    manual.integrate_measurement(imu.accel[2], imu.gyro[2], 0.002_654_322)
    for k in range(3, 100):
        manual.integrate_measurement(imu.accel[k], imu.gyro[k], 0.005)
    assert np.abs(windows[0].delta_position - manual.delta_position).max() < 1e-12
    new_bias = ik.ImuBias(gyro=[0.01, 0.0, -0.01])
    again = windows[1].reintegrate(new_bias)
    fresh = ik.preintegrate_windows(imu, b, noise=NOISE, bias=new_bias, scheme="euler")[1]
    assert np.array_equal(again.delta_position, fresh.delta_position)


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
def test_reintegrate_replays_merged_windows(scheme: str) -> None:
    # A merged preintegration holds a window after another input: reintegrate must preintegrate
    # that window on its own and merge it on, as merge() did (it once reused the non-empty result
    # as the window's start: midpoint then took a dt = 0 step and overflowed).
    imu, _ = window()
    b, new_bias = [0.0, 0.4, 0.9], ik.ImuBias(gyro=[0.01, 0.0, -0.01], accel=[0.05, -0.02, 0.0])
    w = ik.preintegrate_windows(imu, b, noise=NOISE, scheme=scheme)
    fresh = ik.preintegrate_windows(imu, b, noise=NOISE, bias=new_bias, scheme=scheme)
    again, expected = w[0].merge(w[1]).reintegrate(new_bias), fresh[0].merge(fresh[1])
    for name in ("delta_position", "delta_velocity", "covariance", "bias_jacobian"):
        assert np.array_equal(getattr(again, name), getattr(expected, name)), name
    assert again.delta_t == expected.delta_t
    # A batch followed by a window: the same merge, with the new bias.
    head = ik.preintegrate(imu[:81], noise=NOISE, scheme=scheme)
    tail = ik.preintegrate_windows(imu, [0.4, 0.9], noise=NOISE, scheme=scheme)[0]
    mixed = head.merge(tail).reintegrate(new_bias)
    head_new = ik.preintegrate(imu[:81], noise=NOISE, bias=new_bias, scheme=scheme)
    tail_new = ik.preintegrate_windows(imu, [0.4, 0.9], noise=NOISE, bias=new_bias, scheme=scheme)[0]
    assert np.array_equal(mixed.delta_position, head_new.merge(tail_new).delta_position)


def test_windows_refuse_bad_boundaries_and_threads() -> None:
    imu, _ = window()
    span = r"^boundaries: expected times on imu.t's clock \(seconds\) within the samples' span \[0.0, 1.0\], "
    span += "got 0.5 to 1.5$"
    with pytest.raises(ik.ParameterError, match=span):
        ik.preintegrate_windows(imu, [0.5, 1.5], noise=NOISE)
    with pytest.raises(ik.ParameterError, match="boundaries must be strictly increasing"):
        ik.preintegrate_windows(imu, [0.5, 0.2], noise=NOISE)
    with pytest.raises(ik.ShapeError, match="boundaries"):
        ik.preintegrate_windows(imu, [[0.1, 0.2]], noise=NOISE)
    with pytest.raises(ik.ParameterError, match="threads"):
        ik.preintegrate_windows(imu, [0.1, 0.2], noise=NOISE, threads=0)
    with pytest.raises(ik.ParameterError, match="scheme"):
        ik.preintegrate_windows(imu, [0.1, 0.2], noise=NOISE, scheme="rk4")


@pytest.mark.parametrize(
    "keyword",
    [
        {"body_from_sensor": (Rotation.from_euler("ZYX", [120, -30, 45], degrees=True), [0.3, -0.1, 0.15])},
        {"gravity": (0.0, 0.0, -1.0)},
        {"scheme": "lie_euler"},
        {"combined": True},
        {"saturation_noise_factor": 4.0},
        {"bias": ik.ImuBias([0.01, 0, 0], [0, 0, 0])},
        {"noise": ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4)},
    ],
    ids=lambda k: next(iter(k)),
)
def test_a_keyword_next_to_params_is_refused(keyword: dict) -> None:
    """``preintegrate(imu, params, body_from_sensor=...)`` dropped the keyword before 2026-12-07: the
    prediction was 543 m off for a sensor 120° turned on a 0.3 m arm, without a word."""
    imu, _ = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=2.0)
    params = ik.PreintParams(ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4))
    name = next(iter(keyword))
    calls = [lambda: ik.preintegrate(imu, params, **keyword), lambda: ik.PreintegratedImu(params, **keyword)]
    if name != "body_from_sensor":  # not a keyword of preintegrate_windows
        calls.append(lambda: ik.preintegrate_windows(imu, [0.0, 1.0, 2.0], params, **keyword))
    for call in calls:
        with pytest.raises(ik.ParameterError, match="given with params") as info:
            call()
        assert info.value.argument == name
