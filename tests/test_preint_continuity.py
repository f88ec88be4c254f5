"""The continuity rule of ``PreintegratedImu.integrate`` and ``merge`` in both schemes (issue 17,
item 4): a batch continuing a preintegration starts with its last sample (same stamp, same
readings). Feeding ``imu[0:50]``, ``imu[50:100]``, … to the lie_euler scheme used to drop the
interval at each chunk boundary silently (Δp off by 0.145 m after 1 s in 4 chunks); repeated,
out-of-order and gapped batches and merges were accepted.
"""

from __future__ import annotations

import numpy as np
import pytest

import imukit as ik

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)


def _imu(n: int = 200, moving: bool = True, ns: bool = False) -> ik.ImuData:
    t = np.arange(n) * 0.005
    if moving:
        gyro = np.column_stack([np.sin(3 * t), np.cos(2 * t), 0.5 * t])
        accel = np.column_stack([np.cos(t), 2 * np.sin(4 * t), 9.81 + t])
    else:  # a quantised sensor at rest: every sample reads the same
        gyro, accel = np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1))
    stamps = (1_400_000_000_000_000_000 + np.arange(n) * 5_000_000) if ns else t
    return ik.ImuData(stamps, gyro, accel)


def _chunks(imu: ik.ImuData, edges: list[int], scheme: str) -> ik.PreintegratedImu:
    pim = ik.PreintegratedImu(noise=NOISE, scheme=scheme)
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        pim.integrate(imu[lo:hi])
    return pim


@pytest.mark.parametrize("scheme", ["lie_euler", "midpoint"])
@pytest.mark.parametrize("ns", [False, True])
def test_chunked_stream_equals_one_batch_when_chunks_share_their_boundary_sample(scheme: str, ns: bool) -> None:
    imu = _imu(ns=ns)
    whole = ik.preintegrate(imu, noise=NOISE, scheme=scheme)
    pim = ik.PreintegratedImu(noise=NOISE, scheme=scheme)
    for lo, hi in [(0, 51), (50, 101), (100, 151), (150, 200)]:
        pim.integrate(imu[lo:hi])
    assert pim.delta_t == pytest.approx(whole.delta_t, abs=1e-12)
    assert np.abs(pim.delta_position - whole.delta_position).max() < 1e-12
    assert np.abs(pim.delta_velocity - whole.delta_velocity).max() < 1e-12
    assert np.abs(pim.covariance - whole.covariance).max() < 1e-12 * np.abs(whole.covariance).max()


@pytest.mark.parametrize("scheme", ["lie_euler", "midpoint"])
@pytest.mark.parametrize(
    ("edges", "label"),
    [
        ([(0, 50), (50, 100)], "disjoint chunks (the interval 49 → 50 would be dropped)"),
        ([(0, 50), (0, 50)], "a repeated batch"),
        ([(50, 101), (0, 51)], "batches out of order"),
        ([(0, 50), (60, 100)], "a gap"),
    ],
)
def test_batches_that_do_not_continue_are_refused(scheme: str, edges: list[tuple[int, int]], label: str) -> None:
    for moving in (True, False):  # at rest the readings repeat: the stamps tell
        imu = _imu(moving=moving)
        pim = ik.PreintegratedImu(noise=NOISE, scheme=scheme)
        pim.integrate(imu[edges[0][0] : edges[0][1]])
        before = pim.snapshot()
        with pytest.raises(ik.ParameterError, match="imu: expected a continuation starting with") as info:
            pim.integrate(imu[edges[1][0] : edges[1][1]])
        assert info.value.argument == "imu", label
        after = pim.snapshot()  # nothing was added
        assert np.array_equal(after.delta_position, before.delta_position)
        assert after.delta_t[0] == before.delta_t[0]
        # The same pieces as separate preintegrations do not merge either.
        a = ik.preintegrate(imu[edges[0][0] : edges[0][1]], noise=NOISE, scheme=scheme)
        b = ik.preintegrate(imu[edges[1][0] : edges[1][1]], noise=NOISE, scheme=scheme)
        with pytest.raises(ik.ParameterError, match="other: expected a continuation") as info:
            a.merge(b)
        assert info.value.argument == "other"


@pytest.mark.parametrize("scheme", ["lie_euler", "midpoint"])
def test_merges_of_pieces_sharing_their_boundary_equal_one_batch(scheme: str) -> None:
    imu = _imu()
    whole = ik.preintegrate(imu, noise=NOISE, scheme=scheme)
    merged = ik.preintegrate(imu[0:81], noise=NOISE, scheme=scheme).merge(
        ik.preintegrate(imu[80:], noise=NOISE, scheme=scheme)
    )
    assert np.abs(merged.delta_position - whole.delta_position).max() < 1e-12
    # Windows of preintegrate_windows share their boundary: on a sample (then they equal one
    # batch), or between two (a point of the scheme's signal model, so they merge).
    first, second = ik.preintegrate_windows(imu, [imu.t[0], imu.t[80], imu.t[-1]], noise=NOISE, scheme=scheme)
    assert np.abs(first.merge(second).delta_position - whole.delta_position).max() < 1e-12
    first, second = ik.preintegrate_windows(imu, [imu.t[0], 0.4025, imu.t[-1]], noise=NOISE, scheme=scheme)
    assert first.merge(second).delta_t == pytest.approx(whole.delta_t, abs=1e-12)


def test_lie_euler_streaming_after_a_batch_holds_its_last_sample() -> None:
    imu = _imu()
    whole = ik.preintegrate(imu[:101], noise=NOISE, scheme="lie_euler")
    pim = ik.preintegrate(imu[:100], noise=NOISE, scheme="lie_euler")
    with pytest.raises(ik.ParameterError, match="accel / gyro: the sample must be a continuation"):
        pim.integrate_measurement(imu.accel[100], imu.gyro[100], 0.005)  # would skip sample 99
    pim.integrate_measurement(imu.accel[99], imu.gyro[99], 0.005)
    assert np.abs(pim.delta_position - whole.delta_position).max() < 1e-12
