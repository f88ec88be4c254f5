"""Flag options take a bool and nothing else: ``scalar_first="no"`` is truthy, and before 2026-12-07
it returned wxyz quaternions; ``degrees="no"`` read radians as degrees, ``combined="no"`` tracked
the 15×15 covariance, ``final_only="no"`` returned one rotation. One rule (``_arrays.flag``) for
every flag: a ``ParameterError`` naming the option."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

import imukit as ik

T = np.arange(5) * 0.01
GYRO = np.tile([0.0, 0.0, 0.1], (5, 1))
NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
FLAGGED: dict[str, tuple[str, Callable[[object], object]]] = {
    "quat.exp": ("scalar_first", lambda v: ik.quat.exp([0.0, 0.0, 1.0], scalar_first=v)),
    "quat.multiply": ("scalar_first", lambda v: ik.quat.multiply([0, 0, 0, 1.0], [0, 0, 0, 1.0], scalar_first=v)),
    "euler.to_rotation": ("degrees", lambda v: ik.euler.to_rotation([90.0, 0.0, 0.0], degrees=v)),
    "euler.from_rotation": ("degrees", lambda v: ik.euler.from_rotation(np.eye(3), degrees=v)),
    "integrate_attitude": ("final_only", lambda v: ik.integrate_attitude(T, GYRO, final_only=v)),
    "PreintParams": ("combined", lambda v: ik.PreintParams(NOISE, combined=v)),
    "allan_deviation": ("overlapping", lambda v: ik.noise.allan_deviation(np.arange(100.0), 100.0, overlapping=v)),
    "attitude_error": (
        "scalar_first",
        lambda v: ik.eval.attitude_error(
            np.tile([0, 0, 0, 1.0], (3, 1)), np.tile([0, 0, 0, 1.0], (3, 1)), scalar_first=v
        ),
    ),
    "Robust.run": (
        "offline",
        lambda v: ik.filters.Robust().run(ik.ImuData(T, GYRO, np.tile([0, 0, 9.81], (5, 1))), offline=v),
    ),
}


@pytest.mark.parametrize("name", sorted(FLAGGED))
@pytest.mark.parametrize("value", ["no", 1, 0, None, np.array([1, 2])])
def test_a_flag_that_is_not_a_bool_is_refused_naming_the_option(name: str, value: object) -> None:
    option, call = FLAGGED[name]
    with pytest.raises(ik.ParameterError, match=rf"^{option}: expected a bool, got ") as e:
        call(value)
    assert e.value.argument == option
    call(False)
    call(np.bool_(True))  # numpy's bool is a bool
