"""Saturated (clipped) IMU samples (issue 9): flagged from the sensor's range, and what consumers do.

- :class:`imukit.ImuData` takes ``gyro_range`` / ``accel_range`` (per-axis full scale) and flags the
  samples with an axis at or beyond it (``gyro_saturated``, ``accel_saturated``).
- :func:`imukit.sim.simulate` passes a finite ``SensorErrors.range`` on, so simulated clipping is
  flagged exactly where the ideal reading exceeds the range.
- The attitude filters never correct with a clipped accelerometer sample when the range exceeds
  ``g + AccelRejection.norm`` (every accelerometer of ±2 g or more with the defaults): an axis at
  ±range makes ``‖a‖ ≥ range``, which the norm test rejects.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import imukit as ik
from imukit import filters, sim


def _imu(gyro: list[list[float]], **ranges: float | None) -> ik.ImuData:
    n = len(gyro)
    return ik.ImuData(np.arange(n) * 0.01, gyro, np.tile([0.0, 0.0, 9.81], (n, 1)), **ranges)


def test_samples_at_or_beyond_the_range_are_flagged() -> None:
    gyro = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.999, 0.0, 0.0], [0.0, 0.0, 2.0]]
    imu = _imu(gyro, gyro_range=1.0)
    assert imu.gyro_saturated.tolist() == [False, True, True, False, True]
    assert imu.accel_saturated.tolist() == [False] * 5  # no accel_range: unknown, nothing flagged
    assert not imu.gyro_saturated.flags.writeable
    assert imu[1:4].gyro_saturated.tolist() == [True, True, False]  # slices keep the range
    assert imu[1:4].gyro_range == 1.0
    at_rest = _imu(gyro, accel_range=9.81)
    assert at_rest.accel_saturated.all() and not at_rest.gyro_saturated.any()


def test_an_int16_gyro_pinned_at_either_limit_is_flagged_with_the_documented_range() -> None:
    # ±2000 °/s on 16 bits: raw −32768 and +32767 are both the limits the sensor reports.
    lsb = np.deg2rad(2000.0) / 32768
    readings = [[32767 * lsb, 0.0, 0.0], [0.0, -32768 * lsb, 0.0], [0.0, 0.0, 32766 * lsb]]
    documented = _imu(readings, gyro_range=np.deg2rad(2000.0) * 32767 / 32768)
    assert documented.gyro_saturated.tolist() == [True, True, False]
    datasheet = _imu(readings, gyro_range=np.deg2rad(2000.0))  # the pitfall the docstring names
    assert datasheet.gyro_saturated.tolist() == [False, True, False]


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf, "16", 10**400])
@pytest.mark.parametrize("name", ["gyro_range", "accel_range"])
def test_a_range_must_be_positive_and_finite(name: str, bad: object) -> None:
    with pytest.raises(ik.ParameterError, match=rf"^{name}: expected a positive, finite full-scale range"):
        _imu([[0.0, 0.0, 0.0]], **{name: bad})  # type: ignore[arg-type]


@pytest.mark.parametrize("resolution", [0.0, 0.25])
def test_simulated_clipping_is_flagged_where_the_ideal_reading_exceeds_the_range(resolution: float) -> None:
    """Noise-free, so the readings are the ideal ones clamped to ±2 rad/s, then rounded to the step:
    the flags must be exactly the samples whose ideal rate reads 2 after that, i.e. reaches
    2 − step/2 (a reading at full scale cannot tell a clipped rate from one that rounded up)."""
    motion = sim.FigureEight(angular_rate=1.0)  # yaw rate up to 3 rad/s
    ideal, _ = sim.simulate(motion, rate=100.0, duration=20.0)
    errors = sim.SensorErrors(range=2.0, resolution=resolution)
    imu, _ = sim.simulate(motion, rate=100.0, duration=20.0, gyro_errors=errors)
    expected = (np.abs(ideal.gyro) >= 2.0 - resolution / 2).any(axis=1)
    assert 0 < expected.sum() < len(expected)  # the motion clips some samples, not all
    assert imu.gyro_range == 2.0 and imu.accel_range is None
    assert np.array_equal(imu.gyro_saturated, expected)
    assert np.array_equal(np.abs(imu.gyro[expected]).max(axis=1), np.full(expected.sum(), 2.0))


def test_quantised_full_scale_is_what_the_sensor_reports() -> None:
    """With a step that does not divide the range, the clipped reading is the range rounded to the
    step (2.0 with 0.3 → 7 × 0.3 = 2.1), and that is the flagged full scale."""
    motion = sim.ConstantTwist(body_rate=(3.0, 0.0, 0.0))
    imu, _ = sim.simulate(motion, rate=100.0, duration=1.0, gyro_errors=sim.SensorErrors(range=2.0, resolution=0.3))
    assert imu.gyro_range == 7 * 0.3
    assert np.array_equal(imu.gyro[:, 0], np.full(len(imu), 7 * 0.3)) and imu.gyro_saturated.all()


def _at_rest_with(accel_rows: list[float]) -> ik.ImuData:
    n = 400
    accel = np.tile([0.0, 0.0, 9.81], (n, 1))
    accel[200:210] = accel_rows
    gyro = np.zeros((n, 3))
    gyro[:, 2] = 0.01  # something to integrate, identical in every variant
    return ik.ImuData(np.arange(n) / 200.0, gyro, accel, accel_range=2 * 9.81)


@pytest.mark.parametrize(
    "make",
    [
        lambda: filters.Mahony(gain_ramp=None, acc_lowpass=None),
        lambda: filters.Madgwick(gain_ramp=None, acc_lowpass=None),
    ],
)
def test_filters_do_not_correct_with_clipped_accelerometer_samples(make: object) -> None:
    """Two different clipped readings (an axis at ±2 g) give bit-identical attitudes: neither is
    used. A control sample of the same size of change but within the norm test does change it.
    (Without the accelerometer low pass: with it, every sample enters the filtered vector, see
    ``imukit.filters``.)"""
    r = 2 * 9.81
    clipped_a, clipped_b = _at_rest_with([r, 0.0, 9.81]), _at_rest_with([-r, r, r])
    control = _at_rest_with([0.0, 0.4, 9.81])  # 2.3°, within the default 3° angle test
    assert clipped_a.accel_saturated.sum() == 10 and not control.accel_saturated.any()
    run = lambda imu: make().run(imu).rotation.as_quat()  # type: ignore[operator]  # noqa: E731
    assert np.array_equal(run(clipped_a), run(clipped_b))
    assert not np.array_equal(run(clipped_a), run(control))
