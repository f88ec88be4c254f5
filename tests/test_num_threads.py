"""imukit.set_num_threads / get_num_threads: the process-wide pool of the parallel kernels."""

from __future__ import annotations

import functools
import inspect
import multiprocessing
import os
import queue
import threading
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

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


@pytest.mark.usefixtures("restore_threads")
@pytest.mark.parametrize("nine", [False, True])
def test_robust_online_runs_its_window_half_on_a_second_thread_with_the_same_result(nine: bool) -> None:
    # An online run of 1024 samples and more puts each step's window half (bias-window sums, the
    # heading loop, the output) on a second thread of the pool: 12,000 samples, three parts of the
    # glue, rest and motion bias updates; every output and the final state equal bit for bit.
    n = 12_000
    rng = np.random.default_rng(5)
    t = np.arange(n) / 200.0
    turning = (t % 20.0) > 5.0
    gyro = np.where(turning[:, None], np.sin(np.outer(t, [1.3, 0.7, 0.3])), 0.0) + rng.normal(0.0, 0.01, (n, 3))
    q = ik.integrate_attitude(t, gyro)
    accel = q.inv().apply([0.0, 0.0, 9.81]) + rng.normal(0.0, 0.05, (n, 3))
    mag = q.inv().apply([0.0, 20.0, -40.0]) + rng.normal(0.0, 0.3, (n, 3)) if nine else None
    imu = ik.ImuData(t, gyro, accel)
    results = []
    for threads in (1, 2, 3):
        ik.set_num_threads(threads)
        results.append(ik.filters.Robust().run(imu, mag=mag))
    results.append(ik.filters.Robust().run(imu, mag=mag, threads=2))
    one = results[0]
    assert one.rest.any() and not one.rest.all()
    for other in results[1:]:
        np.testing.assert_array_equal(other.rotation.as_quat(), one.rotation.as_quat())
        for name in ("gyro_bias", "gyro_bias_sigma", "rest", "mag_disturbed"):
            np.testing.assert_array_equal(getattr(other, name), getattr(one, name), err_msg=name)
        assert other.state == one.state


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


# ----------------------------------------------------------------------------- threads= per call
# Each entry runs one public entry point on an input of `rows` rows: with ROWS it takes the kernel's
# parallel path (ffi row maps from 8192 rows; attitude's exp / magnus chunks of 4096 samples; the
# simulator's motion chunks of 4096 rows and sensor chunks of 65,536 samples; the Allan variance's
# tasks per cluster size and its 65,536-value check chunks; strapdown's chunks of 32,768 steps).
ROWS = 70_000
SMALL = 8


@functools.cache
def _data(kind: str, rows: int) -> np.ndarray:
    rng = np.random.default_rng(7)
    if kind == "matrix":
        return Rotation.random(rows, rng=rng).as_matrix()
    width = {"vec3": 3, "quat": 4}[kind]
    return 0.5 * rng.standard_normal((rows, width))


def _batch(fn: Callable[..., Any], *kinds: str) -> Callable[..., Any]:
    return lambda rows, **kw: fn(*(_data(k, rows) for k in kinds), **kw)


_ENTRIES: dict[str, Callable[..., Any]] = {
    **{f"so3.{n}": _batch(getattr(ik.so3, n), "vec3") for n in ik.so3.__all__ if n not in ("vee", "log")},
    "so3.vee": _batch(ik.so3.vee, "matrix"),
    "so3.log": _batch(ik.so3.log, "matrix"),
    **{f"quat.{n}": _batch(getattr(ik.quat, n), "quat") for n in ("conjugate", "inverse", "normalize", "log")},
    **{f"quat.{n}": _batch(getattr(ik.quat, n), "quat") for n in ("left_matrix", "right_matrix")},
    "quat.multiply": _batch(ik.quat.multiply, "quat", "quat"),
    "quat.rotate": _batch(ik.quat.rotate, "quat", "vec3"),
    "quat.omega_matrix": _batch(ik.quat.omega_matrix, "vec3"),
    "quat.exp": _batch(ik.quat.exp, "vec3"),
    "euler.to_rotation": lambda rows, **kw: ik.euler.to_rotation(_data("vec3", rows), **kw).as_matrix(),
    "euler.from_rotation": _batch(ik.euler.from_rotation, "matrix"),
    "euler.rate_matrix": _batch(ik.euler.rate_matrix, "vec3"),
    "euler.rate_matrix_inv": _batch(ik.euler.rate_matrix_inv, "vec3"),
    "integrate_attitude": lambda rows, **kw: ik.integrate_attitude(
        np.arange(rows) * 0.01, _data("vec3", rows), scheme="magnus", **kw
    ).as_quat(),
    "noise.allan_deviation": lambda rows, **kw: ik.noise.allan_deviation(_data("vec3", rows), 100.0, **kw).deviation,
    "sim.simulate": lambda rows, **kw: _simulated(rows, **kw),
    "preintegrate": lambda rows, **kw: _preintegrated(rows, **kw),
    "PreintegratedImu.integrate": lambda rows, **kw: _integrated(rows, **kw),
    "preintegrate_windows": lambda rows, **kw: _windows(rows, **kw),
    "reintegrate": lambda rows, **kw: _reintegrated(rows, **kw),
    "integrate": lambda rows, **kw: _strapdown(rows, **kw),
    "filters.Robust.run": lambda rows, **kw: _robust(rows, **kw),
    "filters.Robust.run offline": lambda rows, **kw: _robust(rows, offline=True, **kw),
}
_PARAMS = ik.PreintParams(noise=ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3), scheme="lie_euler")


@functools.cache
def _imu(rows: int) -> ik.ImuData:
    # Over 2 × 32,768 intervals: a lie_euler batch without combined runs as parallel chunks.
    accel = np.array([0.0, 0.0, 9.81]) + _data("vec3", rows)
    return ik.ImuData(np.arange(rows) * 0.005, _data("vec3", rows), accel)


def _deltas(pim: ik.PreintegratedImu) -> list[np.ndarray]:
    s = pim.snapshot()
    return [s.delta_rotation, s.delta_velocity, s.delta_position, s.covariance, s.bias_jacobian]


def _preintegrated(rows: int, **kw: Any) -> list[np.ndarray]:
    return _deltas(ik.preintegrate(_imu(rows), _PARAMS, **kw))


def _integrated(rows: int, **kw: Any) -> list[np.ndarray]:
    pim = ik.PreintegratedImu(_PARAMS)
    pim.integrate(_imu(rows), **kw)
    return _deltas(pim)


def _windows(rows: int, **kw: Any) -> list[np.ndarray]:
    imu = _imu(rows)
    r = ik.preintegrate_windows(imu, np.linspace(imu.t[0], imu.t[-1], 5), _PARAMS, **kw)
    return [r.delta_rotation, r.delta_velocity, r.delta_position, r.covariance, r.bias_jacobian]


def _reintegrated(rows: int, **kw: Any) -> list[np.ndarray]:
    imu = _imu(rows)
    record = ik.preintegrate_windows(imu, np.linspace(imu.t[0], imu.t[-1], 5), _PARAMS)
    r = ik.preint.reintegrate(record, imu, ik.ImuBias([0.01, 0.0, 0.0], [0.0, 0.1, 0.0]), **kw)
    return [r.delta_rotation, r.delta_velocity, r.delta_position, r.covariance, r.bias_jacobian]


def _strapdown(rows: int, **kw: Any) -> list[np.ndarray]:
    # Over 65,537 samples in an inertial world: parallel chunks (strapdown/chunks.rs).
    initial = ik.NavState([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], Rotation.identity())
    x = ik.integrate(_imu(rows), initial=initial, scheme="midpoint", **kw)
    return [x.position, x.velocity, x.rotation.as_quat()]


def _simulated(rows: int, **kw: Any) -> list[np.ndarray]:
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    imu, truth = ik.sim.simulate(ik.sim.Helix(), rate=100.0, duration=(rows - 1) / 100.0, noise=noise, seed=3, **kw)
    return [imu.gyro, imu.accel, truth.position, truth.velocity, truth.rotation.as_quat(), truth.gyro_bias]


def _robust(rows: int, **kw: Any) -> list[np.ndarray]:
    # 9D, the field turning with the gyro's noise: the online run's window half on a second thread.
    imu = _imu(min(rows, 20_000))
    mag = np.array([0.0, 20.0, -40.0]) + 0.1 * _data("vec3", len(imu.t))
    r = ik.filters.Robust().run(imu, mag=mag, **kw)
    return [r.rotation.as_quat(), r.gyro_bias, r.gyro_bias_sigma, r.rest, r.mag_disturbed]


def _arrays(result: Any) -> list[np.ndarray]:
    return [np.asarray(a) for a in result] if isinstance(result, list) else [np.asarray(result)]


def _assert_identical(a: Any, b: Any) -> None:
    for x, y in zip(_arrays(a), _arrays(b), strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.usefixtures("restore_threads")
@pytest.mark.parametrize("name", sorted(_ENTRIES))
def test_threads_do_not_change_a_result_and_none_is_the_process_setting(name: str) -> None:
    call = _ENTRIES[name]
    one = call(ROWS, threads=1)
    _assert_identical(call(ROWS, threads=3), one)
    _assert_identical(call(ROWS), one)
    ik.set_num_threads(1)
    _assert_identical(call(ROWS), one)
    _assert_identical(call(ROWS, threads=None), one)


@pytest.mark.parametrize("bad", [0, -1, 2.5, "2", True, 10**30])
@pytest.mark.parametrize("name", sorted(_ENTRIES))
def test_a_bad_threads_is_a_parameter_error_naming_threads(name: str, bad: object) -> None:
    with pytest.raises(ik.ParameterError, match=r"^threads: expected an int in \[1, 4096\]") as info:
        _ENTRIES[name](SMALL, threads=bad)
    assert info.value.argument == "threads"


def test_every_parallel_entry_point_takes_threads_as_a_keyword_only_none() -> None:
    batch = [getattr(m, n) for m in (ik.so3, ik.quat, ik.euler) for n in m.__all__]
    others = (ik.integrate_attitude, ik.noise.allan_deviation, ik.sim.simulate, ik.preintegrate, ik.integrate)
    methods = (ik.PreintegratedImu.integrate, ik.preintegrate_windows, ik.preint.reintegrate, ik.filters.Robust.run)
    for fn in (*batch, *others, *methods):
        threads = inspect.signature(fn).parameters["threads"]
        assert (threads.kind, threads.default) == (inspect.Parameter.KEYWORD_ONLY, None), fn.__qualname__
    assert len([n for n in _ENTRIES if n.startswith(("so3.", "quat.", "euler."))]) == len(batch)


# ----------------------------------------------------------------------------- fork()
_FORKED_ENTRIES = ("integrate", "preintegrate", "sim.simulate")


def _smoothed() -> np.ndarray:
    # The smoother's two passes run side by side on the process's pool (no `threads=` of its own).
    return ik.filters.Robust().run(_imu(ROWS), offline=True).rotation.as_quat()


def _in_forked_child(results: Any) -> None:
    # Each entry on the process setting (the global pool when unset) and on a pool of 2.
    runs = [(name, threads) for name in _FORKED_ENTRIES for threads in (None, 2)]
    got = {(name, threads): _ENTRIES[name](ROWS, threads=threads) for name, threads in runs}
    results.put({**got, ("smoother", None): _smoothed()})


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork() exists on POSIX systems only")
@pytest.mark.usefixtures("restore_threads")
@pytest.mark.parametrize("setting", [None, 2])
def test_a_forked_child_runs_the_parallel_kernels_on_pools_of_its_own(setting: int | None) -> None:
    # The parent's pools exist when it forks (built by the calls below), but their threads are not
    # copied into the child: a kernel sent to one waited for ever there (a ProcessPoolExecutor
    # worker on Linux's default start method hung in `integrate`, 2026-12-06).
    if setting is not None:
        ik.set_num_threads(setting)
    want = {name: _ENTRIES[name](ROWS, threads=2) for name in _FORKED_ENTRIES} | {"smoother": _smoothed()}
    for name in _FORKED_ENTRIES:
        _ENTRIES[name](ROWS)
    context = multiprocessing.get_context("fork")
    results = context.Queue()
    child = context.Process(target=_in_forked_child, args=(results,))
    child.start()
    try:
        got = results.get(timeout=120)
    except queue.Empty:
        child.kill()
        pytest.fail("the forked child did not finish its kernels within 120 s")
    finally:
        child.join(timeout=30)
    assert child.exitcode == 0
    for (name, _), value in got.items():
        _assert_identical(value, want[name])


@pytest.mark.usefixtures("restore_threads")
@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one CPU: the glue starts no helper thread to compare against")
def test_outputs_faulted_in_ahead_by_a_helper_thread_are_the_same() -> None:
    """The single-threaded kernels with 8 MiB of output or more have a helper thread fault their
    output pages in while they write them (`threads::prefaulting`); with one thread set there is no
    helper. The arrays must be the same bit for bit."""
    rng = np.random.default_rng(7)
    n = 200_000
    t = np.arange(n) * 0.005
    gyro = 0.3 * np.sin(np.outer(t, [1.1, 0.7, 1.3])) + 1e-3 * rng.normal(size=(n, 3))
    accel = np.array([0.0, 0.0, 9.81]) + 0.3 * np.cos(np.outer(t, [0.9, 0.3, 1.7])) + 0.02 * rng.normal(size=(n, 3))
    mag = np.column_stack([20.0 * np.cos(0.2 * t), 20.0 * np.sin(0.2 * t), np.full(n, -40.0)])
    imu = ik.ImuData(t, gyro, accel)
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    short = imu[:6000]  # propagate: 1.8 kB of covariance a sample, 10.8 MB
    initial = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())

    def outputs() -> list[np.ndarray]:
        mahony = ik.filters.Mahony().run(imu, mag=mag)
        robust = ik.filters.Robust().run(imu, mag=mag)
        track = ik.propagate(short, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise)
        return [
            mahony.rotation.as_quat(canonical=False),
            mahony.gyro_bias,
            robust.rotation.as_quat(canonical=False),
            robust.gyro_bias_sigma,
            robust.rest,
            track.position,
            track.covariance,
        ]

    ik.set_num_threads(1)
    alone = outputs()
    ik.set_num_threads(2)
    helped = outputs()
    for a, b in zip(alone, helped, strict=True):
        np.testing.assert_array_equal(a, b)
