"""The ``report`` job on a simulated static log with known bias, noise, gaps, saturated samples and
bad lines (no Dask: the job is a plain function)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit import fleet, sim
from imukit.fleet._report import report_imu

RATE_HZ = 200.0
DURATION_S = 120.0
NOISE = ik.ImuNoise(1.7e-4, 2.0e-3, 0.0, 0.0)  # white noise only: σ at rest is N·√rate exactly
BIAS = ik.ImuBias([0.01, -0.02, 0.005], [0.05, 0.02, -0.03])
GYRO_RANGE = 1.0
ACCEL_RANGE = 16.0
# Steps removed (gaps) and saturated readings, all in the first 45 s, leaving one ~77 s rest segment.
CUTS = [(1000, 1050), (3000, 3100), (5000, 5030)]
SATURATED = {0: [6000, 6400, 6800], 1: [7000, 7200]}  # axis -> samples read at ±GYRO_RANGE
ACCEL_SATURATED = {2: [7400, 8200, 8600]}  # axis -> samples read at ±ACCEL_RANGE


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    imu, _ = sim.simulate(sim.Static(), rate=RATE_HZ, duration=DURATION_S, noise=NOISE, bias=BIAS, seed=3)
    gyro = imu.gyro.copy()
    for axis, samples in SATURATED.items():
        gyro[samples, axis] = GYRO_RANGE * (-1) ** axis
    gyro[6600, 2] = 0.999 * GYRO_RANGE  # near the limit, not at it
    accel = imu.accel.copy()
    for axis, samples in ACCEL_SATURATED.items():
        accel[samples, axis] = -ACCEL_RANGE
    accel[7800, 0] = 0.999 * ACCEL_RANGE
    keep = np.ones(len(imu), dtype=bool)
    for a, b in CUTS:
        keep[a:b] = False
    kept = ik.ImuData(np.asarray(imu.t)[keep], gyro[keep], accel[keep])
    folder = tmp_path_factory.mktemp("report") / "log"
    ik.io.write_euroc(folder, kept, epoch_ns=10**18, noise=NOISE, rate_hz=RATE_HZ)
    csv = next(folder.rglob("imu0/data.csv"))
    lines = csv.read_text().splitlines()
    lines += [lines[-1], "oops,1,2,3,4,5,6"]  # a duplicate stamp and a malformed line
    csv.write_text("\n".join(lines) + "\n")
    return folder


@pytest.fixture(scope="module")
def result(log: Path) -> dict[str, object]:
    return fleet.report(log, gyro_range=GYRO_RANGE, accel_range=ACCEL_RANGE).scalars


def test_counts_are_exact(result: dict[str, object]) -> None:
    n = int(DURATION_S * RATE_HZ) + 1 - sum(b - a for a, b in CUTS)
    assert result["samples"] == n
    assert result["gaps"] == len(CUTS)
    assert result["longest_gap_s"] == pytest.approx((100 + 1) / RATE_HZ, abs=1e-9)
    assert result["dt_jitter_s"] < 1e-9  # the steps that are not gaps are all 1/rate
    assert [result[f"gyro_saturated_{a}_samples"] for a in "xyz"] == [3, 2, 0]
    assert [result[f"accel_saturated_{a}_samples"] for a in "xyz"] == [0, 0, 3]
    assert result["skipped_duplicate_stamp_lines"] == 1
    assert result["skipped_malformed_lines"] == 1
    assert result["skipped_non_finite_lines"] == 0


def test_bias_gravity_and_noise_at_rest(result: dict[str, object]) -> None:
    rest_n = float(result["rest_s"]) * RATE_HZ  # type: ignore[arg-type]
    assert 0.95 * DURATION_S < float(result["rest_s"]) < DURATION_S  # type: ignore[arg-type]
    sigma_g = NOISE.gyro_density * np.sqrt(RATE_HZ)
    sigma_a = NOISE.accel_density * np.sqrt(RATE_HZ)
    # The mean of n white samples has standard error σ/√n: 5 of them.
    for k, axis in enumerate("xyz"):
        assert result[f"gyro_bias_{axis}_rad_s"] == pytest.approx(BIAS.gyro[k], abs=5 * sigma_g / np.sqrt(rest_n))
    # Level and still: the accelerometer reads (0, 0, g) + b_a, whose norm is the gravity at rest.
    g = float(np.linalg.norm(ik.GRAVITY))
    expected = float(np.linalg.norm(np.array([0.0, 0.0, g]) + BIAS.accel))
    assert result["gravity_at_rest_m_s2"] == pytest.approx(expected, abs=5 * sigma_a / np.sqrt(rest_n))
    assert result["accel_bias_vertical_m_s2"] == pytest.approx(expected - g, abs=5 * sigma_a / np.sqrt(rest_n))
    # A pooled σ over 3(n - segments) degrees of freedom has relative standard error 1/√(2 dof): 5 of them.
    tolerance = 5 / np.sqrt(2 * 3 * rest_n)
    assert result["gyro_noise_density_rad_s_sqrt_hz"] == pytest.approx(NOISE.gyro_density, rel=tolerance)
    assert result["accel_noise_density_m_s2_sqrt_hz"] == pytest.approx(NOISE.accel_density, rel=tolerance)


def test_allan_fit_on_the_long_rest_segment(result: dict[str, object]) -> None:
    assert result["rest_segments"] >= 2  # type: ignore[operator]
    # σ(τ₀) over the ~15,400 samples of the segment has relative standard error 1/√(2n) ≈ 0.6%; the
    # fit spreads N over the τ it uses and shares it with B and K: 3% is five of those.
    assert result["gyro_allan_N_rad_s_sqrt_hz"] == pytest.approx(NOISE.gyro_density, rel=0.03)
    assert result["accel_allan_N_m_s2_sqrt_hz"] == pytest.approx(NOISE.accel_density, rel=0.03)


def test_no_allan_fit_below_its_minimum(log: Path) -> None:
    short = fleet.report(log, allan_min_s=DURATION_S).scalars
    assert short["gyro_allan_N_rad_s_sqrt_hz"] is None
    assert short["gyro_saturated_x_samples"] is None  # no range given: unknown, not 0


def test_rest_segments_split_at_motion() -> None:
    imu, _ = sim.simulate(sim.Static(), rate=RATE_HZ, duration=10.0, noise=NOISE, seed=1)
    gyro = imu.gyro.copy()
    gyro[800:1000] += [0.0, 0.0, 0.5]  # a turn from 4 s to 5 s
    segments = fleet.rest_segments(ik.ImuData(imu.t, gyro, imu.accel))
    assert [(s.start, s.stop) for s in segments] == [(0, 800), (1000, 2001)]
    assert segments[0].duration_s == pytest.approx(799 / RATE_HZ)


def test_one_sample_is_refused_naming_the_argument() -> None:
    from imukit.fleet._report import report_imu

    with pytest.raises(ik.ShapeError, match=r"^imu: 1 sample, a report needs at least 2$"):
        report_imu(ik.ImuData([0.0], [[0.0, 0.0, 0.0]], [[0.0, 0.0, 9.81]]))


def test_noise_density_leaves_out_the_bias_random_walk() -> None:
    """Half an hour at rest with EuRoC's sensor.yaml densities: the accelerometer's random walk K adds
    K²T/6 to the variance about a T-second mean, 3.4× the white noise's over 30 min (the σ about each
    segment's mean read 2.1 N before 2026-12-07), 0.4 % over the 1 s windows (0.2 % in σ). The
    estimate's own relative standard error is 1/√(2·3n) ≈ 0.1 %: 1 % fails a doubled or halved K
    term by far and passes the windows' known 0.2 %."""
    noise = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)
    imu, _ = sim.simulate(sim.Static(), rate=100.0, duration=1800.0, noise=noise, seed=4)
    result = report_imu(imu, allan_min_s=1e9)
    assert float(result["rest_s"]) > 0.99 * 1800.0  # type: ignore[arg-type]
    assert result["accel_noise_density_m_s2_sqrt_hz"] == pytest.approx(noise.accel_density, rel=0.01)
    assert result["gyro_noise_density_rad_s_sqrt_hz"] == pytest.approx(noise.gyro_density, rel=0.01)
