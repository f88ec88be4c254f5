"""The q / -q aware comparison helper must itself be able to fail."""

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
