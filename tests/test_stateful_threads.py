"""Stateful objects shared across threads (issue 17, item 9) are safe: each holds a lock, so calls
from several threads run one after another and none is lost. Before, ``Mahony.update`` from 4
threads lost updates silently (state time 14.9–24.9 s instead of 39.995 s) and
``PreintegratedImu.integrate`` raised PyO3's "Already borrowed" ``RuntimeError``.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import pytest

import imukit as ik

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
THREADS = 4


def _together(work: Callable[[int], object]) -> list[object]:
    """``work(k)`` on THREADS threads started at once; what each returned or raised."""
    start = threading.Barrier(THREADS)
    out: list[object] = [None] * THREADS

    def run(k: int) -> None:
        start.wait()
        try:
            out[k] = work(k)
        except BaseException as e:
            out[k] = e

    threads = [threading.Thread(target=run, args=(k,)) for k in range(THREADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return out


@pytest.mark.parametrize("cls", [ik.filters.Mahony, ik.filters.Madgwick, ik.filters.Robust])
def test_filter_updates_from_four_threads_are_all_counted(cls: type) -> None:
    """``Robust.update`` had no lock before 2026-12-07 (Mahony's and Madgwick's since issue 17)."""
    f = cls()
    steps, dt = 2000, 0.005

    def work(k: int) -> None:
        for _ in range(steps):
            f.update([0.01, 0.02, 0.03], [0.0, 0.0, 9.81], dt)

    assert all(r is None for r in _together(work))
    # The first update initialises (its dt is ignored); every other one adds dt.
    assert f.get_state().time == pytest.approx((THREADS * steps - 1) * dt, abs=1e-9)


def test_preintegration_measurements_from_four_threads_are_all_counted() -> None:
    pim = ik.PreintegratedImu(noise=NOISE, scheme="lie_euler")
    steps, dt, accel = 500, 0.005, np.array([0.5, -0.25, 9.81])

    def work(k: int) -> None:
        for _ in range(steps):
            pim.integrate_measurement(accel, [0.0, 0.0, 0.0], dt)

    assert all(r is None for r in _together(work))
    total = THREADS * steps * dt
    assert pim.delta_t == pytest.approx(total, rel=1e-12)
    assert np.allclose(pim.delta_velocity, accel * total, rtol=1e-12, atol=0)


def test_preintegration_batches_from_four_threads_run_one_after_another() -> None:
    n = 200_001  # long enough that the calls overlap while the GIL is released
    t = np.arange(n) * 0.005
    imu = ik.ImuData(t, np.column_stack([np.sin(t), np.cos(t), 0.1 * t]), np.tile([0.0, 0.0, 9.81], (n, 1)))
    alone = ik.preintegrate(imu, noise=NOISE, scheme="lie_euler")
    pim = ik.PreintegratedImu(noise=NOISE, scheme="lie_euler")
    out = _together(lambda k: pim.integrate(imu))
    # One call adds the batch; the others come after it and start where it started, so the
    # continuity rule refuses them (a ParameterError naming imu, never "Already borrowed").
    assert sum(r is None for r in out) == 1
    refused = [r for r in out if r is not None]
    assert all(isinstance(r, ik.ParameterError) and r.argument == "imu" for r in refused), refused
    assert np.array_equal(pim.delta_position, alone.delta_position)
    assert np.array_equal(pim.covariance, alone.covariance)
