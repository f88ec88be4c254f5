"""Real data: EuRoC V1_02_medium gyro, bias-corrected with the ground-truth bias, integrated from
the ground-truth attitude, stays within 1° of the ground truth over the whole 38 s overlap."""

from __future__ import annotations

import numpy as np
import pytest

import imukit as ik
from euroc import load, requires_euroc

pytestmark = requires_euroc


@pytest.mark.parametrize("scheme", ["midpoint", "rk4", "magnus"])
def test_euroc_attitude_error_under_one_degree(scheme: str) -> None:
    data = load()
    assert data.seconds[-1] > 38.0  # the whole overlap is used
    truth = data.rotation
    estimate = ik.integrate_attitude(data.t_ns, data.gyro - data.gyro_bias, initial=truth[0], scheme=scheme)
    error_deg = np.degrees((truth.inv() * estimate).magnitude())
    worst = error_deg.argmax()
    assert error_deg.max() < 1.0, f"{scheme}: max error {error_deg.max():.3f}° at {data.seconds[worst]:.1f} s"
    # and the test can fail: without the bias correction the error is several degrees
    raw = ik.integrate_attitude(data.t_ns, data.gyro, initial=truth[0], scheme=scheme)
    assert np.degrees((truth.inv() * raw).magnitude()).max() > 5.0
