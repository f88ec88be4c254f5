"""``imukit.noise.calibrate_from_residuals``: density inflation factors from preintegration residuals
against ground truth, checked on simulated data with known true densities, against a generic
optimiser of the same likelihood, and by the analytic property of its optimum (mean χ² = 9)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import optimize

import imukit as ik
from euroc import requires_euroc
from imukit.cli import main
from imukit.preint import PreintParams, States, preintegrate_windows

GIVEN = ik.ImuNoise(1.6968e-4, 2.0e-3, 0.0, 0.0)  # EuRoC's datasheet densities
BIAS = ik.ImuBias(gyro=(0.01, -0.02, 0.005), accel=(0.1, -0.05, 0.2))
STEP = 20  # samples per window: 0.1 s at 200 Hz, EuRoC's 10 Hz keyframes


def _windows(
    gyro_factor: float, accel_factor: float, scheme: str = "midpoint", duration: float = 60.0
) -> tuple[ik.preint.Preintegration, States, States, ik.ImuData]:
    """Readings with densities ``factor ×`` GIVEN, preintegrated with GIVEN; the true states at the edges."""
    true = ik.ImuNoise(gyro_factor * GIVEN.gyro_density, accel_factor * GIVEN.accel_density, 0.0, 0.0)
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=duration, noise=true, bias=BIAS, seed=1)
    idx = np.arange(0, len(imu), STEP)
    rec = preintegrate_windows(imu, imu.t[idx], PreintParams(GIVEN, bias=BIAS, scheme=scheme))
    rot = truth.rotation.as_matrix()
    state_i = States(truth.position[idx[:-1]], truth.velocity[idx[:-1]], rot[idx[:-1]])
    state_j = States(truth.position[idx[1:]], truth.velocity[idx[1:]], rot[idx[1:]])
    return rec, state_i, state_j, imu


def _chi2(rec: ik.preint.Preintegration, state_i: States, state_j: States) -> np.ndarray:
    r = ik.preint.residual(rec, state_i, state_j)
    return np.einsum("mi,mij,mj->m", r, np.linalg.inv(rec.covariance), r)


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_densities_four_times_the_given_ones_are_found(scheme: str) -> None:
    rec, state_i, state_j, imu = _windows(4.0, 4.0, scheme)
    cal = ik.noise.calibrate_from_residuals(rec, state_i, state_j)

    for f in (*cal.block_factors, cal.gyro_factor, cal.accel_factor):
        assert f == pytest.approx(4.0, rel=0.1)
    for lo, hi in (*cal.block_intervals, cal.gyro_interval, cal.accel_interval):
        assert lo < 4.0 < hi  # 99% intervals (independent windows here)
    # Before: σ 4× too small, χ² 16× too large (600 windows: within 10% of 144).
    assert cal.chi2_before.mean() == pytest.approx(16 * 9, rel=0.1)
    assert cal.chi2_before.mean() > cal.mean_interval[1]
    # After, re-preintegrated with the corrected densities (what a user of the yaml gets): the mean
    # within the 99% interval of a mean of 600 χ²₉ values, and about 1% of windows over χ²₉'s 99% bound.
    again = _chi2(
        preintegrate_windows(imu, imu.t[::STEP], PreintParams(cal.noise, bias=BIAS, scheme=scheme)), state_i, state_j
    )
    lo, hi = cal.mean_interval
    assert lo < again.mean() < hi
    assert np.mean(again > cal.chi2_bound) < 0.03
    assert (lo, hi) == pytest.approx((8.56, 9.452), abs=5e-3) and cal.chi2_bound == pytest.approx(21.666, abs=1e-3)
    assert cal.noise.gyro_density == GIVEN.gyro_density * cal.gyro_factor
    assert cal.noise.accel_random_walk == GIVEN.accel_random_walk


def test_each_block_is_identified_on_its_own() -> None:
    """Gyro 4×, accelerometer 2×: θ finds 4, v and p find 2."""
    rec, state_i, state_j, _ = _windows(4.0, 2.0)
    cal = ik.noise.calibrate_from_residuals(rec, state_i, state_j)
    assert cal.block_factors[0] == pytest.approx(4.0, rel=0.1) and cal.gyro_factor == pytest.approx(4.0, rel=0.1)
    assert cal.block_factors[1] == pytest.approx(2.0, rel=0.1) and cal.block_factors[2] == pytest.approx(2.0, rel=0.1)
    assert cal.accel_factor == pytest.approx(2.0, rel=0.1)


def test_maximum_likelihood_against_a_generic_optimiser_and_its_analytic_optimum() -> None:
    rec, state_i, state_j, _ = _windows(3.0, 1.5, duration=20.0)
    cal = ik.noise.calibrate_from_residuals(rec, state_i, state_j)
    r = ik.preint.residual(rec, state_i, state_j)
    cov = rec.covariance

    def nll(log_f: np.ndarray, tie: bool) -> float:
        f = np.exp(log_f[[0, 1, 1]] if tie else log_f)
        d = np.repeat(f, 3)
        scaled = cov * np.outer(d, d)
        _, logdet = np.linalg.slogdet(scaled)
        return float(np.sum(logdet) + np.einsum("mi,mi->", r, np.linalg.solve(scaled, r[..., None])[..., 0]))

    for tie, expected in ((False, cal.block_factors), (True, (cal.gyro_factor, cal.accel_factor))):
        start = np.zeros(2 if tie else 3)
        best = optimize.minimize(nll, start, args=(tie,), method="BFGS", options={"gtol": 1e-10})
        np.testing.assert_allclose(np.exp(best.x), expected, rtol=1e-5)
    # At the optimum u_k (Q u)_k = M d_k, so the mean χ² after the correction is 9 exactly.
    assert cal.chi2_after.mean() == pytest.approx(9.0, abs=1e-9)


def test_a_bias_per_window_is_the_same_as_one_bias() -> None:
    rec, state_i, state_j, _ = _windows(2.0, 2.0, duration=5.0)
    one = ik.noise.calibrate_from_residuals(rec, state_i, state_j, bias=BIAS)
    each = ik.noise.calibrate_from_residuals(rec, state_i, state_j, bias=[BIAS] * len(rec))
    np.testing.assert_allclose(each.chi2_before, one.chi2_before, rtol=1e-12)
    # A wrong bias shows as larger residuals (the per-window path applies it).
    off = ik.ImuBias(gyro=BIAS.gyro + 5e-3, accel=BIAS.accel)  # 5e-4 rad over a window: ~5 σ_θ
    worse = ik.noise.calibrate_from_residuals(rec, state_i, state_j, bias=[off] * len(rec))
    assert worse.block_factors[0] > 2 * one.block_factors[0]


def test_refusals() -> None:
    rec, state_i, state_j, _ = _windows(2.0, 2.0, duration=2.0)
    with pytest.raises(ik.ParameterError, match=r"bias: expected one ImuBias or 20 \(one per window\), got 3"):
        ik.noise.calibrate_from_residuals(rec, state_i, state_j, bias=[BIAS] * 3)
    with pytest.raises(ik.ParameterError, match="confidence: expected a number in"):
        ik.noise.calibrate_from_residuals(rec, state_i, state_j, confidence=1.0)
    with pytest.raises(ik.ParameterError, match=r"windows: expected an imukit\.preint\.Preintegration"):
        ik.noise.calibrate_from_residuals([rec], state_i, state_j)  # type: ignore[arg-type]
    zero = ik.ImuNoise(0.0, GIVEN.accel_density, 0.0, 0.0)
    imu, _ = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=2.0)
    singular = preintegrate_windows(imu, imu.t[::STEP], PreintParams(zero))
    with pytest.raises(ik.ParameterError, match="singular"):
        ik.noise.calibrate_from_residuals(singular, state_i, state_j)


def test_cli_preintegrate_calibrate_writes_the_inflated_densities(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    true = ik.ImuNoise(4 * GIVEN.gyro_density, 4 * GIVEN.accel_density, 0.0, 0.0)
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=40.0, noise=true, bias=BIAS, seed=2)
    ik.io.write_euroc(tmp_path / "sim", imu, truth, epoch_ns=10**18)
    given = tmp_path / "given.yaml"
    ik.io.write_kalibr_imu(given, ik.ImuNoise(GIVEN.gyro_density, GIVEN.accel_density, 1.9393e-5, 3e-3), rate_hz=200.0)
    out = tmp_path / "calibrated.yaml"
    args = ["preintegrate", str(tmp_path / "sim"), "--window", "0.1", "--noise", str(given), "--calibrate", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "windows: 400" in printed and "chi2 after: mean 9 " in printed
    fitted = ik.io.read_kalibr_imu(out)
    assert fitted.noise.gyro_density == pytest.approx(4 * GIVEN.gyro_density, rel=0.1)
    assert fitted.noise.accel_density == pytest.approx(4 * GIVEN.accel_density, rel=0.1)
    assert fitted.noise.gyro_random_walk == 1.9393e-5 and fitted.rate_hz == 200.0  # as given, not calibrated
    text = out.read_text()
    assert "# whitened chi2 mean" in text and "(theta block)" in text
    # Without ground truth (a bare IMU file) the option is refused.
    bare = tmp_path / "sim" / "imu0" / "data.csv"
    assert main(["preintegrate", str(bare), "--window", "0.1", "--noise", str(given), "--calibrate", str(out)]) == 1
    assert "--calibrate: needs ground truth" in capsys.readouterr().err


@requires_euroc
def test_euroc_datasheet_densities_are_inflated() -> None:
    """EuRoC V1_02 (40 s excerpt), 10 Hz keyframes, midpoint: the datasheet densities give χ² ≈ 212;
    the numbers of docs/noise.md."""
    from euroc import load

    data = load()
    imu = ik.ImuData(data.t_ns, data.gyro, data.accel)
    idx = np.arange(0, len(imu), STEP)
    mean_bias = ik.ImuBias(data.gyro_bias.mean(axis=0), data.accel_bias.mean(axis=0))
    rec = preintegrate_windows(imu, imu.t_ns[idx], PreintParams(GIVEN, bias=mean_bias))
    rot = data.rotation.as_matrix()
    state_i = States(data.position[idx[:-1]], data.velocity[idx[:-1]], rot[idx[:-1]])
    state_j = States(data.position[idx[1:]], data.velocity[idx[1:]], rot[idx[1:]])
    biases = [ik.ImuBias(g, a) for g, a in zip(data.gyro_bias[idx[:-1]], data.accel_bias[idx[:-1]])]
    cal = ik.noise.calibrate_from_residuals(rec, state_i, state_j, bias=biases)
    assert cal.chi2_before.mean() == pytest.approx(212, rel=0.05)
    assert cal.gyro_factor == pytest.approx(4.37, rel=0.05) and cal.accel_factor == pytest.approx(5.07, rel=0.05)
