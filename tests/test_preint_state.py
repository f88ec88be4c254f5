"""Euler preintegrator states of the earlier layout (body-frame blocks, scheme word 0), written by
main's build before the euler blocks moved to frame i (``tests/fixtures/make_preint_euler_state_v0.py``),
load and resume to the result of an uninterrupted run, with and without the bias walk."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit import _core

FIXTURE = Path(__file__).parent / "fixtures" / "preint_euler_state_v0.npz"
# As in tests/fixtures/make_preint_euler_state_v0.py.
NOISE = ik.ImuNoise(2e-3, 2e-2, 4e-4, 3e-3)
BIAS = ik.ImuBias(gyro=[0.01, 0.0, -0.02], accel=[0.1, 0.0, -0.05])
FACTOR = 20.0


def feed(core: _core.Preintegrator, data: np.lib.npyio.NpzFile, samples: range) -> None:
    for k in samples:
        core.integrate_measurement(
            list(data["accel"][k]),
            list(data["gyro"][k]),
            float(data["dt"][k]),
            bool(data["gyro_saturated"][k]),
            bool(data["accel_saturated"][k]),
        )


def assert_same_state(got: _core.Preintegrator, want: _core.Preintegrator) -> None:
    names = ("delta_rotation", "delta_velocity", "delta_position", "delta_t", "covariance", "bias_jacobian", "combined")
    for name, a, b in zip(names, got.state(), want.state(), strict=True):
        if b is None:
            assert a is None, name
            continue
        a, b = np.asarray(a), np.asarray(b)
        # Rounding only: the two runs hold the blocks in different frames until the split.
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b)), name


@pytest.mark.parametrize(("key", "combined"), [("words", False), ("words_combined", True)])
def test_an_euler_state_of_the_earlier_layout_resumes_as_an_uninterrupted_run(key: str, combined: bool) -> None:
    data = np.load(FIXTURE)
    words, split, n = list(data[key]), int(data["split"]), len(data["dt"])
    assert words[0] == 0.0  # the earlier euler layout
    params = ik.PreintParams(NOISE, BIAS, scheme="lie_euler", combined=combined, saturation_noise_factor=FACTOR)
    whole = params._template()
    feed(whole, data, range(split))
    loaded = _core.Preintegrator.from_state(words)
    assert_same_state(loaded, whole)
    feed(loaded, data, range(split, n))
    feed(whole, data, range(split, n))
    assert_same_state(loaded, whole)
    # A state this version writes is in the new layout and round-trips bit for bit.
    again = loaded.__reduce__()[1][0]
    assert again[0] == 3.0
    assert _core.Preintegrator.from_state(again).__reduce__()[1][0] == again
