"""``imukit demo``: runs with no arguments' data in well under a minute, writes its four plots, and its
table's numbers are the library's (recomputed here with direct calls) and the theory's (orders)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import imukit as ik

image = pytest.importorskip("matplotlib.image", reason="the demo draws with matplotlib")

NOISE = ik.ImuNoise(1.6968e-4, 2.0e-3, 1.9393e-5, 3.0e-3)
EXCERPT = Path(ik.__file__).parent / "_data" / "broad_excerpt.npz"


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[tuple[str, str], dict[str, float]], float]:
    folder = tmp_path_factory.mktemp("demo")
    start = time.perf_counter()
    run = subprocess.run(
        [sys.executable, "-m", "imukit", "demo", "--out", str(folder)], capture_output=True, text=True, timeout=600
    )
    wall = time.perf_counter() - start
    assert run.returncode == 0, run.stderr
    assert f"written to {folder}" in run.stdout
    (folder / "stdout.txt").write_text(run.stdout, encoding="utf-8")
    results = json.loads((folder / "results.json").read_text())
    assert results["parameters"]["noise"] == {
        "gyro_density": NOISE.gyro_density,
        "accel_density": NOISE.accel_density,
        "gyro_random_walk": NOISE.gyro_random_walk,
        "accel_random_walk": NOISE.accel_random_walk,
    }
    rows = {(r["method"], r["metric"]): r for r in results["rows"]}
    return folder, rows, wall


def test_runs_in_under_a_minute(demo: tuple[Path, dict, float]) -> None:
    folder, _, wall = demo
    print(f"imukit demo: {wall:.1f} s wall time")
    assert wall < 60.0  # the bound; it takes about 5 s here
    for name in ("trajectory_top_view", "attitude_error", "scheme_convergence", "allan_gyro"):
        rgba = image.imread(folder / f"{name}.png")
        assert rgba.shape[0] > 300 and rgba[..., :3].std() > 0.05, name


def test_strapdown_and_attitude_rows_are_the_library_calls(demo: tuple[Path, dict, float]) -> None:
    _, rows, _ = demo
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=60.0, noise=NOISE, seed=1)
    for scheme in ("lie_euler", "midpoint", "rk4", "exp"):
        traj = ik.integrate(imu, initial=truth.state(0), scheme=scheme)
        final = np.linalg.norm(traj.position[-1] - truth.position[-1])
        assert rows[(f"strapdown {scheme}", "final position error")]["value"] == final
    for scheme in ("euler", "exp", "rk2", "rk4", "magnus"):
        r = ik.integrate_attitude(imu.t, imu.gyro, initial=truth.rotation[0], scheme=scheme)
        # the same error by scipy rather than imukit.eval: angle of R_true⁻¹ R_est
        angles = (truth.rotation.inv() * r).magnitude()
        rms = np.degrees(np.sqrt(np.mean(angles**2)))
        assert rows[(f"attitude {scheme}", "total attitude RMSE")]["value"] == pytest.approx(rms, rel=1e-9)


def test_preintegration_rows_are_the_library_calls(demo: tuple[Path, dict, float]) -> None:
    _, rows, _ = demo
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=60.0, noise=NOISE, seed=1)
    for scheme in ("lie_euler", "midpoint"):
        pims = ik.preintegrate_windows(imu, np.arange(121) * 0.5, noise=NOISE, scheme=scheme)
        misses = [
            np.linalg.norm(p.predict(truth.state(100 * m)).position - truth.position[100 * (m + 1)])
            for m, p in enumerate(pims)
        ]
        value = rows[(f"preintegration {scheme}", "RMS position miss per 0.5 s window")]["value"]
        assert value == pytest.approx(np.sqrt(np.mean(np.square(misses))), rel=1e-12)


def test_convergence_orders_are_the_schemes_orders(demo: tuple[Path, dict, float]) -> None:
    """Theory: lie_euler and exp (zero-order hold) are first order, midpoint second, rk4 fourth."""
    _, rows, _ = demo
    for scheme, order in (("lie_euler", 1), ("exp", 1), ("midpoint", 2), ("rk4", 4)):
        assert rows[(f"strapdown {scheme}", "observed order (log-log slope)")]["value"] == pytest.approx(order, abs=0.1)


def test_allan_rows_recover_the_simulated_density(demo: tuple[Path, dict, float]) -> None:
    _, rows, _ = demo
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=200.0, duration=1800.0, noise=NOISE, seed=1)
    fit = ik.noise.fit_allan(ik.noise.allan_deviation(imu.gyro, 200.0), sensor="gyro")
    n_row = rows[("Allan fit, gyro", "white noise N / true")]
    assert n_row["value"] == fit.noise_density / NOISE.gyro_density
    assert n_row["interval"] == [x / NOISE.gyro_density for x in fit.noise_density_interval]
    assert n_row["value"] == pytest.approx(1.0, abs=0.02)  # 1800 s of 3-axis white noise pins N to ~0.3%
    assert n_row["interval"][0] <= 1.0 <= n_row["interval"][1]


def test_allan_random_walk_row_and_why_it_is_low(demo: tuple[Path, dict, float]) -> None:
    """K rests on the few longest clusters of an 1800 s record: over seeds 1..10 K/true came out
    0.89 to 1.08 (mean 0.99, std 0.057; 7200 s: std 0.037), so seed 1's 0.89 is scatter, not the
    fit's few-percent low bias (docs/noise.md); its 95% interval holds the truth. The bound 0.2 is
    3.5 of those standard deviations."""
    _, rows, _ = demo
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=200.0, duration=1800.0, noise=NOISE, seed=1)
    fit = ik.noise.fit_allan(ik.noise.allan_deviation(imu.gyro, 200.0), sensor="gyro")
    k_row = rows[("Allan fit, gyro", "random walk K / true")]
    assert k_row["value"] == fit.random_walk / NOISE.gyro_random_walk
    assert k_row["interval"] == [x / NOISE.gyro_random_walk for x in fit.random_walk_interval]
    assert k_row["interval"][0] <= 1.0 <= k_row["interval"][1]
    assert k_row["value"] == pytest.approx(1.0, abs=0.2)


def test_table_heading_and_sections(demo: tuple[Path, dict, float]) -> None:
    folder, _, _ = demo
    text = (folder / "stdout.txt").read_text(encoding="utf-8")
    header = next(line for line in text.splitlines() if "data" in line and "method" in line)
    cells = [c.strip() for c in re.split(r"[┃│|]", header) if c.strip()]
    assert cells == ["data", "method", "error", "value [95% interval]", "time (best of 3)"]
    for label in ("figure-eight 60 s, noisy", "figure-eight 30 s, noise-free", "static 1800 s, noisy"):
        assert label in text
    # The simulator's random stream changed in issue 20 (ChaCha8 -> xoshiro256++, docs/simulation.md):
    # 0.8918 [0.7336, 1.026] before, on another draw of the same noise; the truth is inside both.
    assert re.search(r"random walk K / true\s*│\s*0\.8882 \[0\.7241, 1\.026\]", text)


def test_broad_rows_are_the_library_calls(demo: tuple[Path, dict, float]) -> None:
    _, rows, _ = demo
    with np.load(EXCERPT) as d:
        rate = float(d["sampling_rate"])
        imu = ik.ImuData(np.arange(len(d["imu_gyr"])) / rate, d["imu_gyr"], d["imu_acc"])
        mag, truth, movement = d["imu_mag"], d["opt_quat"], d["movement"]
    assert 11_000 < len(imu) and imu.duration == pytest.approx(40.0, abs=0.01)
    for cls in (ik.filters.Robust, ik.filters.Mahony, ik.filters.Madgwick):
        for nine in (False, True):
            est = cls().run(imu, mag=mag if nine else None).rotation
            error = ik.eval.attitude_error(est, truth, scalar_first=True, align_heading=not nine, mask=movement)
            rmse = error.rmse(degrees=True)
            name = f"{cls.__name__} {'9D' if nine else '6D'}"
            assert rows[(name, "inclination RMSE")]["value"] == rmse.inclination
            assert rmse.inclination < 1.5  # BROAD-tuned defaults: docs/filters_accuracy.md
            heading = rows[(name, "heading RMSE" + ("" if nine else " (offset removed)"))]["value"]
            assert heading == rmse.heading
            # 3.4-3.5 deg but Madgwick 9D's 1.03 here; a heading gone wrong (mag unused in 9D, the
            # offset not removed in 6D, a wrong world frame) is tens of degrees
            assert heading < 5.0


def test_the_excerpt_is_small_and_attributed() -> None:
    """CC BY 4.0 asks for the authors, the source and the changes: ATTRIBUTION.md names them."""
    assert EXCERPT.stat().st_size < 1_500_000
    text = (EXCERPT.parent / "ATTRIBUTION.md").read_text(encoding="utf-8")
    for piece in ("Laidig", "Seel", "Data* 6(7):72", "CC BY 4.0", "06_undisturbed_fast_rotation_A", "7896"):
        assert piece in text, piece
    with np.load(EXCERPT) as d:
        assert int(d["first_sample"]) == 7896 and str(d["trial"]) == "06_undisturbed_fast_rotation_A"
        assert d["movement"][: 10_753 - 7896].sum() == 0 and d["movement"][10_753 - 7896]  # 10 s rest, then motion
