"""Mahony and Madgwick outputs pinned to main's build before issue 20's speed work: a fixed 45 s
input through every branch of the shared step (rest, bursts, sustained acceleration and the drift
rule, a magnetic disturbance and its recovery; ``tests/fixtures/make_filters_pinned.py``), three
option sets, 6D and 9D. The expected values were computed once, on main at 3f23077, and saved in
``tests/fixtures/filters_pinned.npz``: a faster step must give the same outputs within 1e-12."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

import imukit as ik

FIXTURE = Path(__file__).parent / "fixtures" / "filters_pinned.npz"
CONFIGS = {
    "defaults": {},
    "bare": {"acc_lowpass": None, "rest_detection": None, "mag_rejection": None, "gain_ramp": None},
    "ned": {"world": "NED"},
}
LAWS = {"Mahony": ik.filters.Mahony, "Madgwick": ik.filters.Madgwick}


@pytest.fixture(scope="module")
def pinned() -> dict[str, np.ndarray]:
    with np.load(FIXTURE) as data:
        return {k: data[k] for k in data.files}


@pytest.mark.parametrize(("law", "config", "dim"), itertools.product(LAWS, CONFIGS, ("6D", "9D")))
def test_outputs_equal_mains(pinned: dict[str, np.ndarray], law: str, config: str, dim: str) -> None:
    imu = ik.ImuData(pinned["t"], pinned["gyro"], pinned["accel"])
    res = LAWS[law](**CONFIGS[config]).run(imu, mag=pinned["mag"] if dim == "9D" else None)
    keep, key = pinned["keep"], f"{law}_{config}_{dim}"
    np.testing.assert_allclose(res.rotation.as_quat(canonical=False)[keep], pinned[f"{key}_q"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.gyro_bias[keep], pinned[f"{key}_bias"], rtol=0, atol=1e-12)


def test_fixture_moves() -> None:
    """The pinned runs are not trivial: the attitude turns and the bias is learned (a step that
    ignored its input would not match, but neither would it pass this)."""
    with np.load(FIXTURE) as data:
        q = data["Mahony_defaults_9D_q"]
        assert np.ptp(q, axis=0).min() > 0.5
        assert np.abs(data["Mahony_defaults_6D_bias"][-1]).max() > 0.01
