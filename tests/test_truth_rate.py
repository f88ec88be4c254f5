"""Ground truth associated by its own rate (issue 16, item 1): a gap-free 20 Hz truth scores every
200 Hz IMU sample in `integrate`, `filter` and `evaluate`, while a real 1 s gap in the same truth
excludes exactly the IMU samples strictly inside it (counted by hand: 199 at 200 Hz)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from test_cli import cli

RATE, DURATION = 200.0, 10.0
N = int(RATE * DURATION) + 1  # 2001 IMU samples, 0 … 10 s
IN_GAP = 199  # IMU stamps strictly between 4.0 and 5.0 s at 200 Hz


def _scored(stdout: str, what: str) -> tuple[int, int]:
    match = re.search(rf"scored (\d+) of (\d+) {what} \(", stdout)
    assert match is not None, stdout
    return int(match[1]), int(match[2])


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """EuRoC folders with a 20 Hz truth (every 10th 200 Hz pose), gap-free and with its stamps
    strictly inside (4, 5) s removed; the 200 Hz truth and both 20 Hz truths as TUM files."""
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=RATE, duration=DURATION, seed=3)
    t_ns = np.round(truth.t * 1e9).astype(np.int64)
    imu_ns = ik.ImuData(t_ns, imu.gyro, imu.accel)
    root = tmp_path_factory.mktemp("rate")
    sub = np.arange(0, N, 10)
    gappy = sub[(t_ns[sub] <= 4 * 10**9) | (t_ns[sub] >= 5 * 10**9)]
    paths = {}
    for name, rows in (("even", sub), ("gap", gappy)):
        t20 = ik.Trajectory(None, truth.position[rows], truth.velocity[rows], truth.rotation[rows], t_ns=t_ns[rows])
        ik.io.write_euroc(root / name, imu_ns, t20, truth_bias=ik.ImuBias())
        t20.write_tum(root / f"{name}.txt")
        paths[name], paths[f"{name}.txt"] = root / name, root / f"{name}.txt"
    ik.Trajectory(None, truth.position, None, truth.rotation, t_ns=t_ns).write_tum(root / "est.txt")
    paths["est.txt"] = root / "est.txt"
    return paths


def test_library_default_follows_the_references_rate(recordings: dict[str, Path]) -> None:
    est, even, gap = (ik.io.read_tum(recordings[k]) for k in ("est.txt", "even.txt", "gap.txt"))
    assert ik.io.reference_max_dt(even) == pytest.approx(2.5 * 0.05, rel=1e-12)
    pair = ik.eval.associate(est, even)
    assert (pair.n_dropped, pair.scored, pair.max_dt) == (0, 1.0, pytest.approx(0.125))
    holed = ik.eval.associate(est, gap)
    assert (holed.n_outside_span, holed.n_in_gaps) == (0, IN_GAP)
    inside = (est.t_ns > 4 * 10**9) & (est.t_ns < 5 * 10**9)
    np.testing.assert_array_equal(holed.mask, ~inside)  # exactly the samples inside the gap are out
    assert ik.eval.associate(est, even, max_dt=0.02).n_in_gaps == N - len(even)  # the old fixed limit


@pytest.mark.parametrize("command", ["integrate", "filter"])
def test_a_20_hz_truth_scores_every_imu_sample(recordings: dict[str, Path], command: str) -> None:
    kept, total = _scored(cli(command, recordings["even"]).stdout, "(?:IMU )?samples")
    assert total == N and kept / total >= 0.99 and kept == N


@pytest.mark.parametrize("command", ["integrate", "filter"])
def test_a_1_s_gap_still_excludes_exactly_its_samples(recordings: dict[str, Path], command: str) -> None:
    run = cli(command, recordings["gap"])
    assert _scored(run.stdout, "(?:IMU )?samples") == (N - IN_GAP, N)
    assert f"left out 0 outside the ground truth's span (before its first or after its last stamp), {IN_GAP} in " in (
        run.stdout
    )


def test_evaluate_against_a_20_hz_truth(recordings: dict[str, Path]) -> None:
    even = cli("evaluate", recordings["est.txt"], recordings["even.txt"], "--align", "none").stdout
    assert _scored(even, "estimate poses") == (N, N)
    gap = cli("evaluate", recordings["est.txt"], recordings["gap.txt"], "--align", "none").stdout
    assert _scored(gap, "estimate poses") == (N - IN_GAP, N)
    assert f"{IN_GAP} in its gaps longer than 0.125 s (2.5 x its median step" in gap
    fixed = cli("evaluate", recordings["est.txt"], recordings["even.txt"], "--max-dt", "0.02").stdout
    assert _scored(fixed, "estimate poses") == (len(ik.io.read_tum(recordings["even.txt"])), N)


def test_spans_print_as_plain_seconds(tmp_path: Path) -> None:
    """Unix-epoch stamps in the no-pairing error: decimals, not 1.40371527e+09."""
    t = 1403715273.0 + np.arange(10) * 0.05
    for name, stamps in (("a", t), ("b", t + 100.0)):
        ik.Trajectory(stamps, np.zeros((10, 3)), None, Rotation.identity(10)).write_tum(tmp_path / name)
    run = cli("evaluate", tmp_path / "a", tmp_path / "b", code=1)
    assert "the estimate spans [1403715273, 1403715273.45] s" in run.stderr
    assert "e+09" not in run.stderr


EUROC = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "euroc_v1_02_medium"


@pytest.mark.skipif(not (EUROC / "gt0_kimera_subsampled.csv").is_file(), reason=f"{EUROC} absent (../shared/data)")
def test_real_40_hz_euroc_truth_scores_every_sample_in_its_span() -> None:
    """EuRoC V1_02's first 40 s of IMU (7999 samples) against its 40 Hz ground truth, which starts
    1.01 s (202 samples) after the IMU: every other sample scored (a fixed 0.02 s scored 1560)."""
    args = (EUROC / "imu0_data_first40s.csv", "--groundtruth", EUROC / "gt0_kimera_subsampled.csv")
    run = cli("filter", *args)
    assert _scored(run.stdout, "IMU samples") == (7797, 7999)
    assert "left out 202 outside the ground truth's span" in run.stdout and ", 0 in its gaps longer" in run.stdout
    assert _scored(cli("filter", *args, "--max-dt", "0.02").stdout, "IMU samples") == (1560, 7999)
    integrated = cli("integrate", *args).stdout  # starts at the truth: the 202 before it count as unscored
    assert _scored(integrated, "samples") == (7797, 7999) and "left out 202 outside" in integrated
