"""Bad input: every public function raises an imukit exception that names the argument."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import imukit as ik

# (call, argument name in the message, trailing shape it expects)
VEC3 = [
    (ik.so3.hat, "phi"),
    (ik.so3.exp, "phi"),
    (ik.so3.right_jacobian, "phi"),
    (ik.so3.right_jacobian_inv, "phi"),
    (ik.so3.left_jacobian, "phi"),
    (ik.so3.left_jacobian_inv, "phi"),
    (ik.quat.exp, "phi"),
    (ik.quat.omega_matrix, "w"),
    (ik.euler.rate_matrix, "angles"),
    (ik.euler.rate_matrix_inv, "angles"),
    (ik.euler.to_rotation, "angles"),
]
MAT3 = [(ik.so3.vee, "matrix"), (ik.so3.log, "rotation"), (ik.euler.from_rotation, "rotation")]
QUAT = [
    (ik.quat.conjugate, "q"),
    (ik.quat.inverse, "q"),
    (ik.quat.normalize, "q"),
    (ik.quat.log, "q"),
    (ik.quat.left_matrix, "q"),
    (ik.quat.right_matrix, "p"),
]
ALL = [(f, n, (3,)) for f, n in VEC3] + [(f, n, (3, 3)) for f, n in MAT3] + [(f, n, (4,)) for f, n in QUAT]
IDS = [f"{f.__module__.split('.')[-1]}.{f.__name__}" for f, _, _ in ALL]


def _good(tail: tuple[int, ...]) -> np.ndarray:
    return np.broadcast_to(np.eye(3), (5, 3, 3)).copy() if tail == (3, 3) else np.tile(np.eye(4)[3, : tail[0]], (5, 1))


@pytest.mark.parametrize(("func", "name", "tail"), ALL, ids=IDS)
def test_wrong_trailing_shape(func: Callable[..., Any], name: str, tail: tuple[int, ...]) -> None:
    bad = np.zeros((5, tail[-1] + 1))
    with pytest.raises(ik.ShapeError, match=rf"^{name}: expected shape \(\.\.\., {', '.join(map(str, tail))}\)"):
        func(bad)
    with pytest.raises(ValueError):  # ShapeError is also a ValueError
        func(np.float64(1.0))


@pytest.mark.parametrize(("func", "name", "tail"), ALL, ids=IDS)
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_names_the_first_bad_element(
    func: Callable[..., Any], name: str, tail: tuple[int, ...], bad: float
) -> None:
    x = _good(tail)
    x[3].flat[0] = bad
    x[4].flat[0] = bad
    with pytest.raises(ik.NonFiniteError, match=rf"^{name}: element 3 contains a NaN or infinite value"):
        func(x)


@pytest.mark.parametrize(("func", "name", "tail"), ALL, ids=IDS)
@pytest.mark.parametrize("dtype", [object, complex, str, bool])
def test_non_real_dtypes(func: Callable[..., Any], name: str, tail: tuple[int, ...], dtype: type) -> None:
    x = np.zeros((2, *tail)).astype(dtype)
    with pytest.raises(ik.DTypeError, match=rf"^{name}: expected real numbers"):
        func(x)


def test_large_batch_reports_first_bad_row() -> None:
    """Above the parallel threshold the error still names the first bad row, not any bad row."""
    phi = np.zeros((50_000, 3))
    phi[[9_000, 20_000, 45_000], 1] = np.nan
    with pytest.raises(ik.NonFiniteError, match="element 9000 "):
        ik.so3.exp(phi)


def test_overflow_is_reported_not_returned_as_nan() -> None:
    with pytest.raises(ik.NonFiniteError, match="too large"):
        ik.so3.exp([1e300, 1e300, 1e300])


def test_not_a_rotation() -> None:
    with pytest.raises(ik.InvalidRotationError, match=r"^rotation: element 0 is not a rotation matrix"):
        ik.so3.log(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ik.InvalidRotationError, match="element 1 "):
        ik.euler.from_rotation(np.stack([np.eye(3), 2 * np.eye(3)]))


def test_bad_options() -> None:
    with pytest.raises(ik.ParameterError, match="convention"):
        ik.quat.multiply([0, 0, 0, 1], [0, 0, 0, 1], convention="JPL")
    with pytest.raises(ik.ParameterError, match="convention"):
        ik.quat.omega_matrix([0, 0, 1], convention="shuster")
    with pytest.raises(TypeError):
        ik.quat.multiply([0, 0, 0, 1], [0, 0, 0, 1], True)  # type: ignore[misc]  # keyword-only


def test_non_broadcastable_pair() -> None:
    with pytest.raises(ik.ShapeError, match="do not broadcast"):
        ik.quat.multiply(np.zeros((3, 4)), np.zeros((2, 4)))


def test_every_error_is_an_imukit_error() -> None:
    for cls in (
        ik.ShapeError,
        ik.NonFiniteError,
        ik.InvalidQuaternionError,
        ik.GimbalLockError,
        ik.ParameterError,
    ):
        assert issubclass(cls, ik.ImukitError)
        assert issubclass(cls, ValueError)
    assert issubclass(ik.DTypeError, TypeError)
