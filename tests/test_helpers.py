"""Test and library helpers: the q / -q aware comparison must itself be able to fail; ns → s conversion."""

import numpy as np
import pytest

from conftest import assert_quat_close, quat_distance


def test_sign_flip_counts_as_equal() -> None:
    q = np.array([0.1, -0.2, 0.3, np.sqrt(1 - 0.14)])
    assert quat_distance(q, -q) == 0.0
    assert_quat_close(q, -q, atol=0.0)


def test_different_rotations_fail() -> None:
    q = np.array([0.0, 0.0, 0.0, 1.0])
    p = np.array([0.0, 0.0, np.sin(1e-6), np.cos(1e-6)])
    with pytest.raises(AssertionError, match="differ"):
        assert_quat_close(q, p, atol=1e-9)


def test_seconds_from_ns_is_the_nearest_float_for_relative_times() -> None:
    """Exact rational reference: below 2⁵³ ns the result is the float nearest t_ns / 1e9; epoch stamps
    are within one unit in the last place."""
    from fractions import Fraction

    from imukit._arrays import seconds_from_ns

    rng = np.random.default_rng(5)
    small = np.concatenate([[1_140_000_000, 5_000_000, 0, -7_500_000_001], rng.integers(0, 2**53, 2000)])
    got = seconds_from_ns(small.astype(np.int64))
    assert [float(Fraction(int(ns), 10**9)) for ns in small] == got.tolist()
    epochs = rng.integers(10**18, 2 * 10**18, 500).astype(np.int64)
    exact = np.array([float(Fraction(int(ns), 10**9)) for ns in epochs])
    np.testing.assert_array_max_ulp(seconds_from_ns(epochs), exact, maxulp=1)
