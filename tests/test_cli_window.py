"""``imukit preintegrate --window`` asking for more windows than samples (issue 17, item 2): on a
20 s recording ``--window 1e-6`` exhausted a 24 GB machine, ``1e-9`` ended in numpy's
``_ArrayMemoryError`` traceback and ``1e308`` in an ``OverflowError``. Each is one ``--window:``
line now, from :func:`imukit.preint.regular_boundaries` (the library refuses the same periods).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from test_cli import assert_one_line_error, cli

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """20 s at 200 Hz in EuRoC form (integer ns stamps) with its noise model."""
    folder = tmp_path_factory.mktemp("rec")
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=200.0, duration=20.0)
    ik.io.write_euroc(folder, imu)
    ik.io.write_kalibr_imu(folder / "imu.yaml", NOISE, rate_hz=200.0)
    return folder


@pytest.mark.parametrize(
    ("window", "says"),
    [
        ("1e-6", "shorter than the sample step (0.005 s)"),
        ("1e-9", "shorter than the sample step (0.005 s)"),
        ("0.004", "shorter than the sample step (0.005 s)"),
        ("1e308", "longer than the recording (20 s)"),
        ("21", "longer than the recording (20 s)"),
    ],
)
def test_window_giving_more_windows_than_samples_is_one_line(recording: Path, window: str, says: str) -> None:
    run = cli("preintegrate", recording, "--window", window, "--noise", recording / "imu.yaml", code=1)
    assert_one_line_error(run, "--window: ", says)


def test_shortest_window_is_the_sample_step() -> None:
    n = 4001
    ns = 1_400_000_000_000_000_000 + np.arange(n, dtype=np.int64) * 5_000_000
    gyro, accel = np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1))
    for imu in (ik.ImuData(ns, gyro, accel), ik.ImuData(np.arange(n) * 0.005, gyro, accel)):
        edges = ik.preint.regular_boundaries(imu, 0.005)
        assert len(edges) == n and np.array_equal(edges, imu.t if imu.t_ns is None else imu.t_ns)
        for period in (1e-9, 0.00499):
            with pytest.raises(ik.ParameterError, match=r"period: .* shorter than the sample step"):
                ik.preint.regular_boundaries(imu, period)
