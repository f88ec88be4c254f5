"""Threads (issue 9): the batch APIs release the GIL and are safe to call from several threads.

What the glue does (imukit-py/src): every batch entry point takes its arrays as read-only
borrows (``PyReadonlyArray``), copies them with ``ndarray.copy()`` while it still holds the GIL
(``private_copy``), and only then releases the GIL (``py.detach``) to run the kernel on the
private copies and write into output arrays it has just allocated. So a Python thread that writes
into an input array while a call runs cannot change what the kernel reads (rust-numpy issue 497):
the call computes on the array as it was when the call began. The one writable borrow in the
glue, ``sim_measure``, is on arrays ``imukit.sim.simulate`` allocates itself and shares with no one.

The tests prove, for every batch API: (1) the GIL is released while the kernel runs (another
Python thread makes progress in the middle of the call); (2) 6 threads at once, some on their own
inputs and some on one shared input object, give bit-identical results to serial calls; (3) an
input overwritten with NaN after the glue copied it and before the kernel ran leaves the result
bit-identical to the call on the untouched array (deterministic ordering through a hook on
``copy()``), while the caller's array does end up overwritten.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit import _core, filters, noise, sim
from malformed_strategies import identical

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
THREADS = 6


def _imu(seed: int, n: int) -> ik.ImuData:
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.004, 0.006, n))
    gyro = 0.3 * rng.standard_normal((n, 3))
    accel = np.array([0.0, 0.0, 9.81]) + 0.3 * rng.standard_normal((n, 3))
    return ik.ImuData(t, gyro, accel)


def _state() -> ik.NavState:
    return ik.NavState([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], Rotation.identity())


# name -> (make input from a seed and a size, call on that input, a size for a call of 0.1 s or more)
Batch = tuple[Callable[[int, int], Any], Callable[[Any], Any], int]

BATCH_APIS: dict[str, Batch] = {
    "so3.exp": (lambda s, n: np.random.default_rng(s).standard_normal((n, 3)), ik.so3.exp, 1_500_000),
    "so3.log": (
        lambda s, n: Rotation.random(n, rng=np.random.default_rng(s)).as_matrix(),
        ik.so3.log,
        600_000,
    ),
    "quat.multiply": (
        lambda s, n: np.random.default_rng(s).standard_normal((n, 2, 4)),
        lambda q: ik.quat.multiply(q[:, 0], q[:, 1]),
        1_500_000,
    ),
    "integrate_attitude": (
        lambda s, n: (np.arange(n) * 0.005, np.random.default_rng(s).standard_normal((n, 3))),
        lambda x: ik.integrate_attitude(x[0], x[1], scheme="rk4"),
        1_000_000,
    ),
    "integrate": (_imu, lambda imu: ik.integrate(imu, initial=_state(), scheme="rk4"), 1_000_000),
    "propagate": (
        _imu,
        lambda imu: ik.propagate(
            imu, initial=_state(), covariance=np.eye(15) * 1e-4, noise=NOISE, covariance_every=1000
        ),
        200_000,
    ),
    "preintegrate": (_imu, lambda imu: ik.preintegrate(imu, noise=NOISE, combined=True), 300_000),
    "preintegrate_windows": (
        _imu,
        lambda imu: ik.preintegrate_windows(imu, imu.t[:: len(imu) // 20], noise=NOISE, threads=1),
        300_000,
    ),
    "sim.simulate": (
        lambda s, n: (s, n / 1000.0),
        lambda x: sim.simulate(sim.FigureEight(), rate=1000.0, duration=x[1], noise=NOISE, seed=x[0]),
        400_000,
    ),
    "filters.Mahony.run": (_imu, lambda imu: filters.Mahony().run(imu), 1_200_000),
    "filters.Madgwick.run": (_imu, lambda imu: filters.Madgwick().run(imu), 400_000),
    "noise.allan_deviation": (
        lambda s, n: np.random.default_rng(s).standard_normal((n, 3)),
        lambda x: noise.allan_deviation(x, 100.0, taus=np.arange(1, 200) / 100.0),
        100_000,
    ),
}


def _ticks_inside(call: Callable[[], Any]) -> tuple[int, float]:
    """How often a counting Python thread ran in the middle 80 % of ``call()``, and its duration."""
    ticks: list[float] = []
    stop = threading.Event()

    def count() -> None:
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0)  # yield between ticks, so the main thread is not starved meanwhile

    counter = threading.Thread(target=count)
    counter.start()
    time.sleep(0.01)
    start = time.perf_counter()
    call()
    end = time.perf_counter()
    stop.set()
    counter.join()
    lo, hi = start + 0.1 * (end - start), end - 0.1 * (end - start)
    return sum(lo < t < hi for t in ticks), end - start


@pytest.mark.parametrize("api", sorted(BATCH_APIS))
def test_batch_api_releases_the_gil(api: str) -> None:
    """A Python thread counting in a loop advances while the call is in its middle 80 %: with the
    GIL held for the whole native call it could not run there at all."""
    make, call, n = BATCH_APIS[api]
    x = make(1, n)
    inside, seconds = _ticks_inside(lambda: call(x))
    assert inside > 0, f"{api}: no other thread ran during {1e3 * seconds:.0f} ms of the call"


def test_gil_check_detects_a_call_that_holds_the_gil() -> None:
    """The check above can fail: list.sort runs in C holding the GIL, and the counter stalls."""
    values = np.random.default_rng(3).random(2_000_000).tolist()
    inside, seconds = _ticks_inside(lambda: sorted(values))
    assert seconds > 0.05 and inside == 0


@pytest.mark.parametrize("api", sorted(BATCH_APIS))
def test_concurrent_calls_equal_serial_calls(api: str) -> None:
    """6 calls at once (3 on their own inputs, 3 on one shared input object) are bit-identical to
    the same calls made one after another."""
    make, call, n = BATCH_APIS[api]
    size = max(n // 20, 2000)
    own = [make(seed, size) for seed in (11, 12, 13)]
    shared = make(14, size)
    inputs = [*own, shared, shared, shared]
    serial = [call(x) for x in inputs]
    with ThreadPoolExecutor(max_workers=THREADS) as pool:
        concurrent = list(pool.map(call, inputs))
    for k, (a, b) in enumerate(zip(concurrent, serial)):
        diff = identical(a, b)
        assert diff is None, f"{api}, call {k}: {diff}"
    assert identical(serial[0], serial[1]) is not None, "different inputs must give different results"


class _CopyHook(np.ndarray):
    """An array whose ``copy()`` (what the glue calls to make its private copy) runs a callback
    after copying, while the glue waits in it (so before the kernel starts)."""

    after_copy: Callable[[], None] | None = None

    def copy(self, order: Any = "C") -> np.ndarray:  # type: ignore[override]
        out = np.asarray(self).copy(order=order)
        if _CopyHook.after_copy is not None:
            _CopyHook.after_copy()
        return out


def _overwrite_between_copy_and_kernel(x: np.ndarray, native: Callable[[np.ndarray], Any]) -> tuple[Any, np.ndarray]:
    """Call ``native`` on a hooked view of ``x`` while another thread overwrites ``x`` with NaN right
    after the glue copied it (the hook waits for the writer): the ordering copy → overwrite →
    kernel is fixed, not left to timing."""
    hooked = x.view(_CopyHook)
    written = threading.Event()
    started = threading.Event()

    def writer() -> None:
        started.wait()
        x[...] = np.nan  # a plain Python thread writing into the caller's array
        written.set()

    def after_copy() -> None:
        started.set()
        assert written.wait(10.0), "the writer thread did not run"

    thread = threading.Thread(target=writer)
    thread.start()
    _CopyHook.after_copy = after_copy
    try:
        result = native(hooked)
    finally:
        _CopyHook.after_copy = None
        started.set()
        thread.join()
    return result, x


def test_kernel_reads_the_private_copy_not_the_callers_array() -> None:
    rng = np.random.default_rng(5)
    phi = rng.standard_normal((50_000, 3))
    expected = ik.so3.exp(phi)
    out, after = _overwrite_between_copy_and_kernel(phi.copy(), lambda x: _core.so3_exp(x, "phi"))
    assert np.isnan(after).all(), "the caller's array was overwritten before the kernel ran"
    assert identical(out.reshape(-1, 3, 3), expected) is None


def test_integrators_read_the_private_copy_not_the_callers_array() -> None:
    """The same for the multi-array kernels: integrate_attitude's t and gyro."""
    rng = np.random.default_rng(6)
    t, gyro = np.linspace(0.0, 0.005 * 19_999, 20_000), rng.standard_normal((20_000, 3))
    expected = ik.integrate_attitude(t, gyro).as_quat()
    start = np.array([0.0, 0.0, 0.0, 1.0])

    def native(g: np.ndarray) -> Any:
        return _core.attitude_integrate(t, g, start, "midpoint", "quaternion", 1e-6, False)

    out, after = _overwrite_between_copy_and_kernel(gyro.copy(), native)
    assert np.isnan(after).all()
    assert identical(out, expected) is None


def test_public_api_passes_the_callers_buffer_to_the_glue(monkeypatch: pytest.MonkeyPatch) -> None:
    """Why the glue's copy matters: for a C-contiguous float64 input the Python layer makes no copy
    of its own, so the array the glue borrows is the caller's (shares its memory)."""
    seen: list[bool] = []
    phi = np.random.default_rng(7).standard_normal((100, 3))
    original = _core.so3_exp

    def spy(x: np.ndarray, name: str, **threads: Any) -> Any:
        seen.append(np.shares_memory(x, phi))
        return original(x, name, **threads)

    monkeypatch.setattr(_core, "so3_exp", spy)
    ik.so3.exp(phi)
    assert seen == [True]
