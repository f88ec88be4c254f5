"""Errors raised by the Rust core carry the argument and the sample index as fields (decision 1):
the glue builds ``cls(message, argument=..., index=...)``, and ``str(exc)`` is unchanged."""

from __future__ import annotations

import numpy as np
import pytest

import imukit as ik
from imukit import _core


def test_a_non_finite_sample_names_its_argument_and_index() -> None:
    t = np.arange(6) * 0.01
    gyro = np.zeros((6, 3))
    gyro[4, 1] = np.nan
    with pytest.raises(ik.NonFiniteError) as info:
        ik.integrate_attitude(t, gyro)
    assert (info.value.argument, info.value.index) == ("gyro", 4)
    assert str(info.value) == f"gyro: {info.value.message}"
    assert not info.value.message.startswith("gyro:")


def test_a_batch_row_error_names_the_row() -> None:
    q = np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])
    with pytest.raises(ik.InvalidQuaternionError) as info:
        ik.quat.normalize(q)
    assert info.value.index == 1
    assert info.value.argument is not None
    assert str(info.value).startswith(f"{info.value.argument}: ")


def test_an_unknown_name_is_a_parameter_error_without_an_index() -> None:
    with pytest.raises(ik.ParameterError) as info:
        _core.quat_multiply(np.zeros((1, 8)), "q", "nope")
    assert info.value.argument == "convention"
    assert info.value.index is None
