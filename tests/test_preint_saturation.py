"""Preintegration of clipped samples: the white-noise density of a clipped sensor is multiplied by
``saturation_noise_factor`` (euler: on the interval the sample starts; midpoint: on both intervals
it bounds), the deltas do not change. Checked against merges of separately preintegrated pieces
with the inflated noise set by hand, and, through a simulated clipped motion, window by window."""

from __future__ import annotations

import numpy as np
import pytest

import imukit as ik
from imukit.sim import FigureEight, SensorErrors, simulate

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 0.0, 0.0)
BIAS = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.1, 0.05, -0.2])
MOTION = FigureEight(amplitude=(3.0, 2.0, 0.5), angular_rate=1.2, roll=0.4, pitch=0.3)


def clipped_motion(*, percentile: float = 85.0) -> tuple[ik.ImuData, ik.ImuData]:
    """The same readings twice: without ranges, and with ranges at the ``percentile`` of each sensor's
    largest axis magnitude, so that some samples (and not all) are clipped."""
    free, _ = simulate(MOTION, rate=200.0, duration=8.0)
    limits = [float(np.percentile(np.abs(x).max(axis=1), percentile)) for x in (free.gyro, free.accel)]
    errors = [SensorErrors(range=limit) for limit in limits]
    clipped, _ = simulate(MOTION, rate=200.0, duration=8.0, gyro_errors=errors[0], accel_errors=errors[1])
    same = ik.ImuData(clipped.t, clipped.gyro, clipped.accel)
    return clipped, same


def test_the_simulated_motion_clips_some_samples_of_each_sensor() -> None:
    clipped, _ = clipped_motion()
    for flags in (clipped.gyro_saturated, clipped.accel_saturated):
        assert 0.05 < flags.mean() < 0.3


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
def test_windows_with_a_used_clipped_sample_grow_and_the_others_are_bit_identical(scheme: str) -> None:
    clipped, unflagged = clipped_motion()
    edges = np.arange(0, len(clipped), 40)
    b = clipped.t[edges]
    flagged = ik.preintegrate_windows(clipped, b, noise=NOISE, bias=BIAS, scheme=scheme)
    plain = ik.preintegrate_windows(unflagged, b, noise=NOISE, bias=BIAS, scheme=scheme)
    used_gyro = used_accel = 0
    for m, (f, p) in enumerate(zip(flagged, plain)):
        # euler uses samples lo … hi − 1 (each held over its interval); midpoint lo … hi.
        lo, hi = edges[m], edges[m + 1] + (1 if scheme == "midpoint" else 0)
        g, a = clipped.gyro_saturated[lo:hi].any(), clipped.accel_saturated[lo:hi].any()
        np.testing.assert_array_equal(f.delta_velocity, p.delta_velocity)
        np.testing.assert_array_equal(f.delta_position, p.delta_position)
        np.testing.assert_array_equal(f.delta_rotation.as_matrix(), p.delta_rotation.as_matrix())
        if not (g or a):
            np.testing.assert_array_equal(f.covariance, p.covariance)
            continue
        # A clipped sensor's white noise ×100 in density: its variance term grows by orders of
        # magnitude even from one sample of the window's 40.
        if g:
            used_gyro += 1
            assert np.trace(f.covariance[0:3, 0:3]) > 50.0 * np.trace(p.covariance[0:3, 0:3])
        if a and not g:
            used_accel += 1
            assert np.trace(f.covariance[3:6, 3:6]) > 50.0 * np.trace(p.covariance[3:6, 3:6])
            np.testing.assert_array_equal(f.covariance[0:3, 0:3], p.covariance[0:3, 0:3])
    assert used_gyro > 0 and used_accel > 0  # both kinds of window occur


def _pieces(imu: ik.ImuData) -> list[ik.PreintegratedImu]:
    """Euler preintegrations of each run of unclipped intervals with the configured noise and of each
    clipped interval with its clipped sensor's density × 100, set by hand."""
    out = []
    k, n = 0, len(imu)
    g, a = imu.gyro_saturated, imu.accel_saturated
    while k < n - 1:
        end = k + 1
        if not (g[k] or a[k]):
            while end < n - 1 and not (g[end] or a[end]):
                end += 1
        noise = ik.ImuNoise(
            NOISE.gyro_density * (100.0 if g[k] else 1.0),
            NOISE.accel_density * (100.0 if a[k] else 1.0),
            0.0,
            0.0,
        )
        piece = ik.PreintegratedImu(noise=noise, bias=BIAS, scheme="euler")
        piece.integrate(ik.ImuData(imu.t[k : end + 1], imu.gyro[k : end + 1], imu.accel[k : end + 1]))
        out.append(piece)
        k = end
    return out


def test_euler_covariance_equals_merged_pieces_with_hand_inflated_noise() -> None:
    clipped, _ = clipped_motion()
    imu = clipped[:400]
    pim = ik.preintegrate(imu, noise=NOISE, bias=BIAS, scheme="euler")
    pieces = _pieces(imu)
    assert len(pieces) > 10
    # PreintegratedImu.merge refuses pieces of different noise, so they are composed here with the
    # euler merge formula (docs/preintegration.md; no noise is shared across a boundary in euler).
    cov = np.zeros((9, 9))
    r = np.eye(3)
    for piece in pieces:
        j1 = np.eye(9)
        j1[0:3, 0:3] = piece.delta_rotation.as_matrix().T
        j1[3:6, 0:3] = -r @ ik.so3.hat(piece.delta_velocity)
        j1[6:9, 0:3] = -r @ ik.so3.hat(piece.delta_position)
        j1[6:9, 3:6] = np.eye(3) * piece.delta_t
        j2 = np.zeros((9, 9))
        j2[0:3, 0:3], j2[3:6, 3:6], j2[6:9, 6:9] = np.eye(3), r, r
        cov = j1 @ cov @ j1.T + j2 @ piece.covariance @ j2.T
        r = r @ piece.delta_rotation.as_matrix()
    np.testing.assert_allclose(pim.covariance, cov, rtol=1e-9, atol=1e-9 * np.abs(cov).max())
    # Sensitive: without the flags the covariance is far from it.
    plain = ik.preintegrate(imu, noise=NOISE, bias=BIAS, scheme="euler", saturation_noise_factor=1.0)
    assert np.abs(plain.covariance - cov).max() > 0.5 * np.abs(cov).max()


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
def test_streaming_with_flags_equals_the_batch(scheme: str) -> None:
    clipped, _ = clipped_motion()
    imu = clipped[:300]
    batch = ik.preintegrate(imu, noise=NOISE, bias=BIAS, scheme=scheme)
    stream = ik.PreintegratedImu(noise=NOISE, bias=BIAS, scheme=scheme)
    t, g, a = imu.seconds, imu.gyro_saturated, imu.accel_saturated
    if scheme == "midpoint":
        stream.integrate_measurement(imu.accel[0], imu.gyro[0], 0.0, gyro_saturated=g[0], accel_saturated=a[0])
    for k in range(1, len(imu)):
        held = k - 1 if scheme == "euler" else k
        stream.integrate_measurement(
            imu.accel[held], imu.gyro[held], t[k] - t[k - 1], gyro_saturated=g[held], accel_saturated=a[held]
        )
    np.testing.assert_array_equal(stream.covariance, batch.covariance)
    np.testing.assert_array_equal(stream.delta_velocity, batch.delta_velocity)
    # reintegrate replays the flags and the factor, for both ways of building it.
    for pim in (stream, batch):
        np.testing.assert_array_equal(pim.reintegrate(BIAS).covariance, batch.covariance)


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
def test_factor_one_and_no_ranges_give_the_unflagged_result_bit_for_bit(scheme: str) -> None:
    clipped, unflagged = clipped_motion()
    plain = ik.preintegrate(unflagged, noise=NOISE, bias=BIAS, scheme=scheme)
    one = ik.preintegrate(clipped, noise=NOISE, bias=BIAS, scheme=scheme, saturation_noise_factor=1.0)
    np.testing.assert_array_equal(one.covariance, plain.covariance)
    flagged = ik.preintegrate(clipped, noise=NOISE, bias=BIAS, scheme=scheme)
    assert not np.array_equal(flagged.covariance, plain.covariance)
    np.testing.assert_array_equal(flagged.bias_jacobian, plain.bias_jacobian)
    # Default factor 100: OKVIS' sigma_g_c *= 100. A larger factor inflates more.
    more = ik.preintegrate(clipped, noise=NOISE, bias=BIAS, scheme=scheme, saturation_noise_factor=1000.0)
    assert np.trace(more.covariance) > 10.0 * np.trace(flagged.covariance)


@pytest.mark.parametrize("bad", [0.5, float("nan"), float("inf"), "100", None])
def test_a_bad_factor_is_refused_with_its_name(bad: object) -> None:
    clipped, _ = clipped_motion()
    with pytest.raises(ik.ParameterError, match=r"^saturation_noise_factor: expected a finite factor ≥ 1"):
        ik.preintegrate(clipped, noise=NOISE, saturation_noise_factor=bad)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^saturation_noise_factor: "):
        ik.preintegrate_windows(clipped, clipped.t[[0, -1]], noise=NOISE, saturation_noise_factor=bad)  # type: ignore[arg-type]


def test_bad_flags_and_mismatched_factors_are_refused() -> None:
    pim = ik.PreintegratedImu(noise=NOISE, scheme="euler")
    for name in ("gyro_saturated", "accel_saturated"):
        with pytest.raises(ik.ParameterError, match=rf"^{name}: expected a bool, got 1"):
            pim.integrate_measurement([0, 0, 9.8], [0, 0, 0], 0.01, **{name: 1})  # type: ignore[arg-type]
    clipped, _ = clipped_motion()
    x = ik.preintegrate(clipped[:10], noise=NOISE, scheme="euler")
    y = ik.preintegrate(clipped[9:20], noise=NOISE, scheme="euler", saturation_noise_factor=10.0)
    with pytest.raises(ik.ParameterError, match=r"^other: .*saturation noise factor"):
        x.merge(y)
