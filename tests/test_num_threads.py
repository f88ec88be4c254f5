"""imukit.set_num_threads / get_num_threads: the process-wide pool of the parallel kernels."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import imukit as ik
from imukit import _core


@pytest.fixture
def restore_threads() -> object:
    before = ik.get_num_threads()
    yield
    ik.set_num_threads(before)


@pytest.mark.usefixtures("restore_threads")
def test_set_num_threads_is_what_get_num_threads_reports_and_results_do_not_change() -> None:
    phi = np.random.default_rng(1).normal(size=(20_000, 3))
    ik.set_num_threads(1)
    assert ik.get_num_threads() == 1
    one = ik.so3.exp(phi)
    ik.set_num_threads(3)
    assert ik.get_num_threads() == 3
    np.testing.assert_array_equal(ik.so3.exp(phi), one)


@pytest.mark.usefixtures("restore_threads")
def test_kernels_run_on_the_threads_set() -> None:
    # Attitude integration is parallel over chunks of samples: 2 threads and 1 agree bit for bit.
    ik.set_num_threads(2)
    t = np.arange(5000) * 0.01
    gyro = np.random.default_rng(2).normal(size=(5000, 3))
    two = ik.integrate_attitude(t, gyro).as_quat()
    ik.set_num_threads(1)
    np.testing.assert_array_equal(ik.integrate_attitude(t, gyro).as_quat(), two)


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2", None, 10**30])
def test_set_num_threads_refuses_what_is_not_a_positive_int(bad: object) -> None:
    before = ik.get_num_threads()
    with pytest.raises(ik.ParameterError, match=r"^n: expected an int in \[1, 4096\]") as info:
        ik.set_num_threads(bad)  # type: ignore[arg-type]
    assert info.value.argument == "n"
    assert ik.get_num_threads() == before


def test_set_num_threads_from_several_threads_at_once_leaves_a_valid_count() -> None:
    before = ik.get_num_threads()
    try:
        workers = [threading.Thread(target=ik.set_num_threads, args=(k,)) for k in (1, 2, 3, 4)]
        for w in workers:
            w.start()
        for w in workers:
            w.join()
        assert ik.get_num_threads() in (1, 2, 3, 4)
    finally:
        ik.set_num_threads(before)


def test_gravity_is_the_core_constant() -> None:
    assert _core.GRAVITY == (0.0, 0.0, -9.81)
    assert ik.GRAVITY is _core.GRAVITY
