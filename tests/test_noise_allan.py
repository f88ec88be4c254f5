"""Allan variance and the N/B/K fit (``imukit.noise``): agreement with allantools, analytic
expectations within their derived statistical error, simulate-and-recover, interval coverage,
errors, the plot."""

from __future__ import annotations

import sys

import allantools
import numpy as np
import pytest

import imukit as ik
from imukit import noise
from imukit.noise import _fit

RATE = 200.0


def simulate(seed: int, seconds: float, rate: float, density: float, walk: float, columns: int = 3) -> np.ndarray:
    """The gyro of imukit's simulator at rest: white noise of density N (σ = N √rate per sample)
    plus a bias random walk of density K (step σ = K / √rate per sample)."""
    imu, _ = ik.sim.simulate(
        ik.sim.Static(), rate=rate, duration=seconds, noise=ik.ImuNoise(density, 0.0, walk, 0.0), seed=seed
    )
    return np.array(imu.gyro[:, :columns])


def white_kernel_autocovariance(m: int) -> np.ndarray:
    """Autocovariance R(h), h = 0…2m, of d_k = Σ_{i<m} (y_{k+m+i} − y_{k+i}) for unit white y:
    the autocorrelation of the weights (−1 × m, +1 × m)."""
    h = np.arange(2 * m + 1)
    return np.where(h <= m, 2 * m - 3 * h, -(2 * m - h)).astype(float)


def walk_kernel_autocovariance(m: int) -> np.ndarray:
    """Same for y a random walk of unit steps: d_k = Σ_j G(j − k) w_j with G the tent
    min(l, 2m − l), l = 0…2m (Σ of the weights after each step)."""
    j = np.arange(2 * m + 1)
    g = np.minimum(j, 2 * m - j).astype(float)
    return np.correlate(g, g, "full")[len(g) - 1 :]


def exact_avar_sd(r: np.ndarray, m: int, n: int) -> tuple[float, float]:
    """Mean and standard deviation of the overlapping AVAR estimate Σ d_k² / (2 m² n) for
    Gaussian d with autocovariance r: Var Σ d² = 2 Σ_{j,k} R(j − k)² = 2 Σ_h (n − |h|) R(h)²."""
    h = np.arange(len(r))
    weights = np.where(h == 0, n, 2 * np.maximum(n - h, 0))
    mean = r[0] / (2 * m * m)
    var = 2 * np.sum(weights * r**2) / (2 * m * m * n) ** 2
    return float(mean), float(np.sqrt(var))


# ---- agreement with allantools -----------------------------------------------------------------


@pytest.fixture(scope="module")
def imu_like() -> np.ndarray:
    """Gyro-like and accelerometer-like columns with offsets (the accelerometer's 9.81)."""
    x = simulate(1, 1000.0, RATE, 2e-3, 1e-4)
    return x + np.array([0.01, -0.02, 9.81])


@pytest.mark.parametrize("overlapping", [True, False])
def test_equals_allantools_on_the_same_grid(imu_like: np.ndarray, overlapping: bool) -> None:
    peer = allantools.oadev if overlapping else allantools.adev
    allan = noise.allan_deviation(imu_like, RATE, overlapping=overlapping)
    assert allan.deviation.shape == (len(allan.taus), 3)
    assert allan.taus[0] == 1 / RATE and allan.taus[-1] * RATE * 4 <= len(imu_like)
    for c in range(3):
        taus, dev, _, ns = peer(imu_like[:, c], rate=RATE, data_type="freq", taus=allan.taus)
        np.testing.assert_array_equal(taus, allan.taus)
        np.testing.assert_array_equal(ns, allan.clusters)
        np.testing.assert_allclose(allan.deviation[:, c], dev, rtol=1e-10, atol=0)
        single = noise.allan_deviation(imu_like[:, c], RATE, overlapping=overlapping)
        assert single.deviation.shape == (len(allan.taus),)
        np.testing.assert_array_equal(single.deviation, allan.deviation[:, c])


def test_given_taus_equal_allantools(imu_like: np.ndarray) -> None:
    taus = np.array([0.005, 0.015, 0.5, 3.0, 0.01])  # m = 1, 3, 100, 600, 2, in that order
    allan = noise.allan_deviation(imu_like[:, 2], RATE, taus=taus)
    np.testing.assert_array_equal(allan.cluster_sizes, [1, 3, 100, 600, 2])
    order = np.argsort(taus)
    _, dev, _, ns = allantools.oadev(imu_like[:, 2], rate=RATE, data_type="freq", taus=taus[order])
    np.testing.assert_allclose(allan.deviation[order], dev, rtol=1e-10, atol=0)
    np.testing.assert_array_equal(allan.clusters[order], ns)
    nonover = noise.allan_deviation(imu_like[:, 2], RATE, taus=taus, overlapping=False)
    _, dev, _, ns = allantools.adev(imu_like[:, 2], rate=RATE, data_type="freq", taus=taus[order])
    np.testing.assert_allclose(nonover.deviation[order], dev, rtol=1e-10, atol=0)
    np.testing.assert_array_equal(nonover.clusters[order], ns)


# ---- analytic truths ----------------------------------------------------------------------------


def test_white_noise_gives_density_over_root_tau() -> None:
    density, rate, n = 1e-3, 100.0, 1_000_000
    x = density * np.sqrt(rate) * np.random.default_rng(2).standard_normal(n)
    allan = noise.allan_deviation(x, rate)
    z = []
    for m, terms, var in zip(allan.cluster_sizes, allan.clusters, allan.variance):
        # The per-sample variance q = N² rate scales R; the mean is N²/τ exactly.
        mean, sd = exact_avar_sd(density**2 * rate * white_kernel_autocovariance(int(m)), int(m), int(terms))
        assert mean == pytest.approx(density**2 / (m / rate), rel=1e-12)
        z.append((var - mean) / sd)
    assert np.max(np.abs(z)) < 4.0, z
    # Not a vacuous bound: the errors are of the size derived (a wrong sd would show here).
    assert 0.4 < np.std(z) < 2.0, z


def test_random_walk_gives_k_squared_tau_over_three() -> None:
    walk, rate, n = 2e-3, 100.0, 1_000_000
    x = np.cumsum(walk / np.sqrt(rate) * np.random.default_rng(3).standard_normal(n))
    allan = noise.allan_deviation(x, rate, taus=np.array([1, 4, 16, 64, 256, 1024]) / rate)
    z = []
    for m, terms, var in zip(allan.cluster_sizes, allan.clusters, allan.variance):
        step = walk**2 / rate
        mean, sd = exact_avar_sd(step * walk_kernel_autocovariance(int(m)), int(m), int(terms))
        # Discrete: K² τ0 (2m² + 1)/(6m) = K² τ/3 · (1 + 1/(2m²)).
        tau = m / rate
        assert mean == pytest.approx(walk**2 * tau / 3 * (1 + 1 / (2 * m * m)), rel=1e-12)
        z.append((var - mean) / sd)
    assert np.max(np.abs(z)) < 4.0, z


@pytest.mark.parametrize("overlapping", [True, False])
def test_edf_formulas_match_the_exact_gaussian_values(overlapping: bool) -> None:
    """The literature edf used for the weights, against 2 E² / Var computed from the kernels."""
    n = 100_000
    allan = noise.allan_deviation(np.random.default_rng(4).standard_normal(n), 1.0, overlapping=overlapping)
    for kind, autocov, tolerance in ((0, white_kernel_autocovariance, 0.05), (2, walk_kernel_autocovariance, 0.15)):
        fractions = np.zeros((len(allan.taus), 3))
        fractions[:, kind] = 1.0
        edf = _fit._edf(allan, fractions)
        for m, terms, value in zip(allan.cluster_sizes, allan.clusters, edf):
            r = autocov(int(m))
            if not overlapping:  # d at stride m: only lags that are multiples of m remain
                r = r[:: int(m)]
                terms_lag = np.arange(len(r))
                weights = np.where(terms_lag == 0, terms, 2 * np.maximum(terms - terms_lag, 0))
                exact = terms**2 * r[0] ** 2 / np.sum(weights * r**2)
            else:
                mean, sd = exact_avar_sd(r, int(m), int(terms))
                exact = 2 * mean**2 / sd**2
            assert value == pytest.approx(exact, rel=tolerance), (kind, m)


# ---- simulate and recover -----------------------------------------------------------------------


@pytest.fixture(scope="module")
def gyro_3h() -> noise.AllanDeviation:
    return noise.allan_deviation(simulate(10, 3 * 3600.0, RATE, 1e-3, 2e-5), RATE)


def within(value: float, interval: tuple[float, float]) -> bool:
    return interval[0] <= value <= interval[1]


def test_recovers_gyro_noise_from_3_hours(gyro_3h: noise.AllanDeviation) -> None:
    fit = noise.fit_allan(gyro_3h, sensor="gyro")
    # N is determined by ~2e6 samples: 0.04% statistical error, far inside 5%.
    assert fit.noise_density == pytest.approx(1e-3, rel=0.005)
    assert within(1e-3, fit.noise_density_interval)
    # K rests on the ~5 octaves above the 87 s crossover of N and K: ~6% per axis at best
    # (T / τ_c ≈ 124 independent increments), ~4-6% for three axes jointly, and B ≥ 0 pulls it low
    # (seeds 10, 11, 13: −2.6%, −2.2%, −3.0%; seed 12: −18%, outside its 95% interval, the 1-in-20
    # case). The 5% holds for this seeded record of imukit's simulator, not for every record.
    assert fit.random_walk == pytest.approx(2e-5, rel=0.05)
    assert within(2e-5, fit.random_walk_interval)
    assert fit.bias_instability_interval[0] == 0.0
    interval_width = fit.random_walk_interval[1] / fit.random_walk_interval[0]
    assert interval_width < 1.6
    for axis in range(3):
        one = noise.fit_allan(gyro_3h, sensor="gyro", axis=axis)
        assert one.noise_density == pytest.approx(1e-3, rel=0.01)
        assert within(2e-5, one.random_walk_interval)
        assert one.bias_instability_interval[0] == 0.0
        # One axis has a third of the data: wider intervals than the joint fit.
        assert one.random_walk_interval[1] / one.random_walk_interval[0] > interval_width


def test_recovers_accelerometer_noise_and_builds_imu_noise(gyro_3h: noise.AllanDeviation) -> None:
    accel = simulate(11, 3 * 3600.0, RATE, 2e-3, 3e-3) + np.array([0.0, 0.0, 9.81])
    fit = noise.fit_allan(noise.allan_deviation(accel, RATE), sensor="accel")
    assert fit.noise_density == pytest.approx(2e-3, rel=0.01)
    # Crossover at √3 N/K = 1.2 s: a long random-walk range, K to a few %.
    assert fit.random_walk == pytest.approx(3e-3, rel=0.05)
    assert within(3e-3, fit.random_walk_interval) and within(2e-3, fit.noise_density_interval)
    assert fit.bias_instability_interval[0] == 0.0
    assert "m/s²/√Hz" in str(fit) and "m/s³/√Hz" in str(fit)
    gyro = noise.fit_allan(gyro_3h, sensor="gyro")
    imu = noise.to_imu_noise(gyro=gyro, accel=fit)
    assert isinstance(imu, ik.ImuNoise)
    assert (imu.gyro_density, imu.gyro_random_walk) == (gyro.noise_density, gyro.random_walk)
    assert (imu.accel_density, imu.accel_random_walk) == (fit.noise_density, fit.random_walk)
    with pytest.raises(ik.ParameterError, match=r"^gyro: expected a fit made with sensor='gyro'"):
        noise.to_imu_noise(gyro=fit, accel=gyro)


def test_model_curve_and_components(gyro_3h: noise.AllanDeviation) -> None:
    fit = noise.fit_allan(gyro_3h, sensor="gyro")
    taus = np.array([0.01, 1.0, 100.0])
    terms = fit.components(taus)
    np.testing.assert_allclose(terms[:, 0], fit.noise_density / np.sqrt(taus))
    np.testing.assert_allclose(terms[:, 1], fit.bias_instability * np.sqrt(2 * np.log(2) / np.pi))
    np.testing.assert_allclose(terms[:, 2], fit.random_walk * np.sqrt(taus / 3))
    np.testing.assert_allclose(fit.variance(taus), np.sum(terms**2, axis=1))
    # The fitted curve follows the data: every point within 3 of its own standard errors.
    parts = _fit._design(gyro_3h.taus) * np.array([fit.noise_density, fit.bias_instability, fit.random_walk]) ** 2
    edf = _fit._edf(gyro_3h, parts / parts.sum(axis=1, keepdims=True))
    rel = gyro_3h.variance / fit.variance(gyro_3h.taus)[:, None] - 1
    assert np.all(np.abs(rel) < 3 * np.sqrt(2 / edf)[:, None] + 0.01)


def test_intervals_cover_the_truth_across_seeds() -> None:
    """20 independent 1 h records at 100 Hz: the 95% intervals cover N and K in most of them, and
    N's standardised errors have unit spread. Weights that ignore the correlation between τ values
    give N intervals ~1.6x too narrow (spread ~1.6, coverage ~78%); weights from the white-noise
    edf alone give K intervals that cover in ~20% of records."""
    truth = np.array([1e-3**2, 0.0, 2e-5**2])
    covered = np.zeros(3, dtype=int)
    z = []
    for seed in range(20):
        allan = noise.allan_deviation(simulate(100 + seed, 3600.0, 100.0, 1e-3, 2e-5, columns=1)[:, 0], 100.0)
        fit = noise.fit_allan(allan, sensor="gyro")
        covered += [
            within(1e-3, fit.noise_density_interval),
            fit.bias_instability_interval[0] == 0.0,
            within(2e-5, fit.random_walk_interval),
        ]
        z.append((fit.noise_density**2 - truth[0]) / np.sqrt(fit.covariance[0, 0]))
    assert covered[0] >= 17 and covered[1] >= 17 and covered[2] >= 16, covered
    assert 0.5 < np.std(z) < 1.4, z


# ---- errors -------------------------------------------------------------------------------------


def test_bad_input_names_the_argument() -> None:
    x = np.zeros(100)
    with pytest.raises(ik.ShapeError, match=r"^x: expected shape \(N,\) or \(N, C\)"):
        noise.allan_deviation(np.zeros((10, 3, 1)), RATE)
    with pytest.raises(ik.ShapeError, match=r"^x: expected shape"):
        noise.allan_deviation(np.zeros((10, 0)), RATE)
    with pytest.raises(ik.DTypeError, match=r"^x:"):
        noise.allan_deviation(x.astype(complex), RATE)
    with pytest.raises(ik.ShapeError, match=r"^x: the default τ grid .* needs N ≥ 4 samples, got 3"):
        noise.allan_deviation(x[:3], RATE)
    bad = np.zeros((100, 3))
    bad[42, 1] = np.nan
    with pytest.raises(ik.NonFiniteError, match=r"^x: element 42"):
        noise.allan_deviation(bad, RATE)
    for rate in (0.0, -1.0, np.nan, np.inf, "fast", None):
        with pytest.raises(ik.ParameterError, match=r"^rate: expected a positive, finite sample rate"):
            noise.allan_deviation(x, rate)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^taus: every τ must be a whole multiple of 1/rate = 0\.005 s"):
        noise.allan_deviation(x, RATE, taus=[0.005, 0.0075])
    with pytest.raises(ik.ParameterError, match=r"^taus: taus\[0\] = 0\.255 s is m = 51 samples; two clusters"):
        noise.allan_deviation(x, RATE, taus=[0.255])
    with pytest.raises(ik.ParameterError, match=r"^taus: expected positive, finite seconds"):
        noise.allan_deviation(x, RATE, taus=[0.0])
    with pytest.raises(ik.ShapeError, match=r"^taus: expected a non-empty"):
        noise.allan_deviation(x, RATE, taus=[])
    # At the edge: m = N/2 is the largest cluster size with a term.
    edge = noise.allan_deviation(np.arange(100.0), RATE, taus=[0.25])
    assert edge.clusters.tolist() == [1]


def test_bad_fit_options_name_the_argument(gyro_3h: noise.AllanDeviation) -> None:
    with pytest.raises(ik.ParameterError, match=r"^sensor: expected one of"):
        noise.fit_allan(gyro_3h, sensor="magnetometer")
    for level in (0.0, 1.0, 95, "high"):
        with pytest.raises(ik.ParameterError, match=r"^confidence: expected a number in"):
            noise.fit_allan(gyro_3h, confidence=level)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^axis: expected None or a column index below 3, got 3"):
        noise.fit_allan(gyro_3h, axis=3)
    with pytest.raises(ik.ParameterError, match=r"^tau_min: expected a non-negative number"):
        noise.fit_allan(gyro_3h, tau_min=-1.0)
    narrow = r"^tau_min / tau_max: fitting 3 parameters needs at least 4 τ values, got 2"
    with pytest.raises(ik.ParameterError, match=narrow):
        noise.fit_allan(gyro_3h, axis=0, tau_min=1.0, tau_max=2.6)
    with pytest.raises(ik.ParameterError, match=r"^allan: expected the AllanDeviation"):
        noise.fit_allan((gyro_3h.taus, gyro_3h.deviation))  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^allan: the Allan variance is 0 at every τ"):
        noise.fit_allan(noise.allan_deviation(np.ones(1000), RATE))
    narrow = noise.fit_allan(gyro_3h, tau_max=1.0)  # white noise only: K and B unresolved, N still right
    assert narrow.noise_density == pytest.approx(1e-3, rel=0.01)


# ---- plot ---------------------------------------------------------------------------------------


def test_plot_writes_a_png(gyro_3h: noise.AllanDeviation, tmp_path: object) -> None:
    import pathlib

    out = pathlib.Path(str(tmp_path))
    fit = noise.fit_allan(gyro_3h, sensor="gyro")
    noise.plot_allan(gyro_3h, out / "allan.png", fit=fit, title="gyro, 3 h at 200 Hz")
    noise.plot_allan(gyro_3h, out / "data_only.png")
    for name in ("allan.png", "data_only.png"):
        data = (out / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_plot_without_matplotlib_says_so(gyro_3h: noise.AllanDeviation, monkeypatch: pytest.MonkeyPatch) -> None:
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(ik.MissingDependencyError, match=r"^plot_allan: needs matplotlib"):
        noise.plot_allan(gyro_3h, "never.png")


def test_mean_rate_counts_the_intervals_over_the_span_for_float_stamps_too() -> None:
    """100 Hz with a 1 s dropout: 999 intervals over 10.99 s, 90.9 Hz, whatever the stamps' type;
    float stamps gave the median rate (100 Hz) before 2026-12-07."""
    t_ns = np.concatenate([np.arange(500), np.arange(600, 1100)]) * 10_000_000
    rows = np.tile([0.0, 0.0, 9.81], (len(t_ns), 1))
    exact = 999 / 10.99
    by_ns = ik.noise.mean_rate_hz(ik.ImuData(t_ns, rows, rows))
    by_s = ik.noise.mean_rate_hz(ik.ImuData(t_ns / 1e9, rows, rows))
    assert by_ns == pytest.approx(exact, rel=1e-15)
    assert by_s == pytest.approx(exact, rel=1e-12)
    with pytest.raises(ik.ShapeError, match=r"^imu: "):
        ik.noise.mean_rate_hz(ik.ImuData([0.0], rows[:1], rows[:1]))


def test_moving_seconds_finds_the_turn_not_the_bias_or_the_noise() -> None:
    """A still 200 Hz record (consumer-grade noise, a 0.1 rad/s bias: still) with a 5 s turn at
    0.2 rad/s in its middle: 5 s moving, to a window either side; 0 without the turn."""
    rng = np.random.default_rng(3)
    n, rate = 120_000, 200.0
    t = np.arange(n) / rate
    gyro = 0.1 + 1e-2 * np.sqrt(rate) * rng.standard_normal((n, 3))  # N = 1e-2 rad/s/√Hz
    accel = np.array([0.3, -0.2, 9.8]) + 2e-3 * np.sqrt(rate) * rng.standard_normal((n, 3))
    assert ik.noise.moving_seconds(ik.ImuData(t, gyro, accel)) == 0.0
    turning = (t >= 300.0) & (t < 305.0)
    gyro[turning, 2] += 0.2
    assert 4.0 <= ik.noise.moving_seconds(ik.ImuData(t, gyro, accel)) <= 6.0
    with pytest.raises(ik.ParameterError, match=r"^gyro: "):
        ik.noise.moving_seconds(ik.ImuData(t, gyro, accel), gyro=0.0)
