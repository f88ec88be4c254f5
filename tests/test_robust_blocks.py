"""Streaming = batch for imukit.filters.Robust across block-sized stretches of a record: bit for
bit on jittered stamps with rest, a rejected field and bias updates, and a refused row named. What
a batch loop that prepares its input-only values for blocks of rows ahead of the step (tried and
not merged: docs/filters_robust.md "Speed, seventh round"; blocks of rows 1–256, 257–512, …) must
keep at its block boundaries; the Rust side: `crates/imukit/tests/robust.rs`,
`a_refused_row_inside_a_block_ends_the_run_after_the_rows_before`."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

RATE = 100.0
N = 1237  # not a multiple of the block (256)
BIAS = np.radians([0.3, -0.2, 0.1])


def _record() -> tuple[ik.ImuData, np.ndarray]:
    """Rest for 4 s (rows 0–399: rest is declared after 1.5 s, across the boundary 256 | 257), then
    turning; the field's norm 1.5× from 6 s to 9 s (rows 600–899, across 768 | 769); stamps jittered
    by up to ±0.2 ms, so that nearly every step takes new coefficients."""
    rng = np.random.default_rng(15)
    t = np.arange(N) / RATE + rng.uniform(-2e-4, 2e-4, N)
    w = np.stack([0.5 * np.sin(0.9 * t), 0.4 * np.cos(0.6 * t), 0.6 * np.sin(0.4 * t + 1.0)], 1)
    w[t < 4.0] = 0.0
    q = [Rotation.from_euler("xyz", [0.2, -0.1, 0.5])]
    for k in range(1, N):
        q.append(q[-1] * Rotation.from_rotvec(w[k] * (t[k] - t[k - 1])))
    truth = Rotation.concatenate(q)
    accel = truth.inv().apply([0.0, 0.0, 9.81]) + rng.normal(0.0, 0.02, (N, 3))
    mag = truth.inv().apply([0.0, 20.0, -40.0])
    mag[(t >= 6.0) & (t < 9.0)] *= 1.5
    gyro = w + BIAS + rng.normal(0.0, 0.002, (N, 3))
    return ik.ImuData(t, gyro, accel), mag


def test_streaming_equals_batch_across_blocks() -> None:
    imu, mag = _record()
    f = ik.filters.Robust()
    batch = f.run(imu, mag=mag)
    # The record crosses the boundaries it is meant to: rest on both sides of 256 | 257, the field
    # rejected on both sides of 768 | 769, and the bias estimate changing inside a block (where
    # increments computed ahead with the old bias would have to be redone).
    assert batch.rest[256] and batch.rest[257]
    assert batch.mag_disturbed[768] and batch.mag_disturbed[769]
    changed = np.flatnonzero((batch.gyro_bias[1:] != batch.gyro_bias[:-1]).any(axis=1)) + 1
    assert any((k - 1) % 256 != 0 for k in changed if k > 1)
    q, bias, sigma, rest, disturbed = [], [], [], [], []
    sec = imu.seconds  # the clock the batch run reads (relative to the first stamp)
    for k in range(N):
        dt = 0.0 if k == 0 else sec[k] - sec[k - 1]
        q.append(f.update(imu.gyro[k], imu.accel[k], dt, mag=mag[k]).as_quat())
        s = f.get_state()
        fields = dict(s.fields())
        bias.append(s.gyro_bias)
        sigma.append(s.gyro_bias_sigma)
        rest.append(fields["rest"] != 0.0)
        disturbed.append(fields["mag_disturbed"] != 0.0)
    assert np.array_equal(np.array(q), batch.rotation.as_quat())
    assert np.array_equal(np.array(bias), batch.gyro_bias)
    assert np.array_equal(np.array(sigma), batch.gyro_bias_sigma)
    assert np.array_equal(np.array(rest), batch.rest)
    assert np.array_equal(np.array(disturbed), batch.mag_disturbed)
    # The final state (rest detection's low passes included) is the streamed one.
    # (The clocks differ: the batch state's is the stamp, the streamed one sums the steps.)
    ends = [{k: v for k, v in dict(s.fields()).items() if k != "time"} for s in (batch.state, f.get_state())]
    assert ends[0] == ends[1]


@pytest.mark.parametrize("row", [300, 700])
def test_a_refused_row_inside_a_block_is_named(row: int) -> None:
    imu, mag = _record()
    gyro = imu.gyro.copy()
    gyro[row, 2] = np.nan
    with pytest.raises(ik.NonFiniteError, match=str(row)):
        ik.filters.Robust().run(ik.ImuData(imu.t, gyro, imu.accel), mag=mag)
