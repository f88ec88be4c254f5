"""Every public data type and result is data: pickle and ``copy.deepcopy`` round trip it exactly.

``FACTORIES`` maps each public class of ``imukit`` and its submodules to a non-trivial instance;
:func:`test_every_public_class_is_registered` fails when a new public class has neither a factory nor
a reasoned entry in ``NOT_DATA``. Equality is field by field and bit for bit: arrays keep their
bytes, dtype, shape and read-only flag, rotations their quaternions, floats their bits.
"""

from __future__ import annotations

import copy
import dataclasses
import importlib
import inspect
import math
import pickle
import struct
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
import imukit.fleet
from imukit.io import ReadReport, SkippedLine

try:
    import torch

    import imukit.torch
except ImportError:  # imukit[torch] absent (the Makefile skips it on a small disk): its classes go unchecked
    torch = None
TORCH_ABSENT = "imukit.torch needs torch (pip install imukit[torch])"

MODULES = [
    "imukit",
    "imukit.attitude",
    "imukit.euler",
    "imukit.eval",
    "imukit.filters",
    "imukit.fleet",
    "imukit.imu",
    "imukit.io",
    "imukit.noise",
    "imukit.preint",
    "imukit.quat",
    "imukit.sim",
    "imukit.so3",
    "imukit.state",
    "imukit.strapdown",
    *(["imukit.torch"] if torch is not None else []),
]

# Public classes that are not data, each with the reason. Keep this list short.
NOT_DATA: dict[str, str] = {
    # io detection plumbing: a context manager and a lazily read file head, not values.
    "Registration": "a context manager that unregisters a format on exit",
    "Format": "a registry entry of functions (sniff, reader): a worker imports the same registry",
    "Head": "a lazy view of one file's first lines while it is being sniffed",
    "LeftOutWarning": "a warning category (imukit.fleet.run's), not a value",
}

NOISE = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)


def _sim(duration: float = 3.0) -> tuple[ik.ImuData, ik.Trajectory]:
    errors = ik.sim.SensorErrors(turn_on_sigma=1e-3, range=30.0, resolution=1e-4)
    return ik.sim.simulate(
        ik.sim.FigureEight(),
        rate=100.0,
        duration=duration,
        noise=NOISE,
        bias=ik.ImuBias([1e-3, -2e-3, 3e-3], [0.05, -0.02, 0.01]),
        gyro_errors=errors,
        seed=7,
    )


def _imu_ns() -> ik.ImuData:
    imu, _ = _sim()
    t_ns = 1_403_636_579_758_555_392 + np.arange(len(imu)) * 10_000_000
    return ik.ImuData(t_ns, imu.gyro, imu.accel, gyro_range=20.0)


def _trajectory() -> ik.Trajectory:
    _, truth = _sim()
    n, m = len(truth), 4
    a = np.random.default_rng(1).standard_normal((m, 15, 15))
    t_ns = 1_403_636_579_758_555_392 + np.arange(n) * 10_000_000
    return ik.Trajectory(
        None,
        truth.position,
        truth.velocity,
        truth.rotation,
        t_ns=t_ns,
        covariance=a @ np.swapaxes(a, 1, 2),
        covariance_t=np.linspace(1.0, 2.0, m),
        gyro_bias=truth.gyro_bias,
        accel_bias=truth.accel_bias,
    )


def _estimate() -> tuple[ik.Trajectory, ik.Trajectory]:
    _, truth = _sim()
    drift = truth.position + np.outer(truth.t, [0.01, -0.02, 0.005])
    tilt = Rotation.from_rotvec(np.outer(truth.t, [0.0, 0.001, 0.01])) * truth.rotation
    return ik.Trajectory(truth.t, drift, None, tilt), truth


def _allan() -> ik.noise.AllanDeviation:
    rng = np.random.default_rng(0)
    return ik.noise.allan_deviation(1e-3 * np.sqrt(200.0) * rng.standard_normal((20_000, 3)), 200.0)


def _filter_result() -> ik.filters.FilterResult:
    imu, _ = _sim()
    return ik.filters.Mahony().run(imu)


def _robust_result() -> ik.filters.RobustResult:
    imu, _ = _sim()
    return ik.filters.Robust().run(imu)


def _streaming(cls: type[Any]) -> Any:
    """A filter mid-stream: its options not the defaults and its state after 50 updates (what a
    worker would be sent to continue a stream)."""
    imu, _ = _sim()
    f = cls(world="NED") if cls is ik.filters.Robust else cls(rest_detection=ik.filters.RestDetection(), gain_ramp=None)
    for k in range(50):
        f.update(imu.gyro[k], imu.accel[k], 0.01, mag=[0.2, 0.0, -0.4])
    return f


def _report() -> ReadReport:
    report = ReadReport()
    report.skipped.append(SkippedLine("imu.csv", 3, "duplicate stamp: 5 follows 5", "5,0,0,0,0,0,0"))
    return report


def _preint_params() -> ik.PreintParams:
    return ik.PreintParams(
        noise=NOISE, bias=ik.ImuBias([1e-3, 0.0, -1e-3], [0.01, 0.02, 0.0]), scheme="lie_euler", combined=True
    )


def _windows() -> ik.Preintegration:
    imu = _imu_ns()
    return ik.preintegrate_windows(imu, ik.preint.regular_boundaries(imu, 0.5), _preint_params())


def _windows_states() -> ik.preint.States:
    m = len(_windows())
    rotation = Rotation.from_rotvec(np.outer(np.arange(m), [0.0, 0.1, 0.2])).as_matrix()
    return ik.preint.States(np.arange(3.0 * m).reshape(m, 3), np.ones((m, 3)), rotation)


def _calibration() -> ik.noise.NoiseCalibration:
    """Residuals of the windows against states off their prediction by a rotation, a velocity, a position."""
    p, v, r = ik.preint.predict(_windows(), _windows_states())
    m = len(p)
    turn = Rotation.from_rotvec(1e-4 * np.cos(np.outer(np.arange(m), [1.0, 2.0, 3.0]))).as_matrix()
    wobble = 1e-3 * np.sin(np.outer(np.arange(m), [3.0, 1.0, 2.0]))
    return ik.noise.calibrate_from_residuals(
        _windows(), _windows_states(), ik.preint.States(p + wobble, v - wobble, r @ turn)
    )


def _error(cls: type[ik.ImukitError]) -> Callable[[], ik.ImukitError]:
    return lambda: cls("expected shape (N, 3), got (2,)", argument="gyro", index=4)


def _torch_preintegrated() -> Any:
    g = torch.Generator().manual_seed(1)
    w, a = (
        torch.randn(2, 5, 3, generator=g, dtype=torch.float64),
        torch.randn(2, 5, 3, generator=g, dtype=torch.float64),
    )
    return imukit.torch.preintegrate(0.005, w, a, noise=NOISE, return_covariance=True, return_jacobian=True)


TORCH_FACTORIES: dict[str, Callable[[], Any]] = {
    "Preintegrated": _torch_preintegrated,
    "State": lambda: imukit.torch.State(torch.eye(3), torch.tensor([1.0, 2.0, 3.0]), torch.zeros(3)),
}

FACTORIES: dict[str, Callable[[], Any]] = {
    **(TORCH_FACTORIES if torch is not None else {}),
    "ImuData": lambda: _sim()[0],
    "ImuBias": lambda: ik.ImuBias([1e-3, -2e-3, 3e-3], [0.05, -0.02, 0.01]),
    "ImuNoise": lambda: NOISE,
    "DiscreteNoise": lambda: NOISE.discrete(0.005),
    "DiscreteSigmas": lambda: NOISE.to_discrete_sigmas(200.0),
    "NavState": lambda: _sim()[1].state(17),
    "LocalLevel": lambda: ik.LocalLevel(48.0, 350.0, "ned", degrees=True, transport=True),
    "Trajectory": _trajectory,
    "PreintParams": lambda: _preint_params(),
    "Preintegration": lambda: _windows(),
    "PreintegratedImu": lambda: ik.preintegrate(_sim()[0], noise=NOISE, bias=_preint_params().bias, combined=True),
    "Deltas": lambda: ik.preint.corrected(_windows(), _preint_params().bias),
    "States": lambda: ik.preint.predict(_windows(), _windows_states()),
    "ResidualJacobians": lambda: ik.preint.ResidualJacobians(np.eye(9), -np.eye(9), np.arange(54.0).reshape(9, 6)),
    # imukit.sim
    "Static": lambda: ik.sim.Static((1.0, 2.0, 3.0), Rotation.from_rotvec([0.1, 0.2, 0.3])),
    "ConstantTwist": lambda: ik.sim.ConstantTwist(body_rate=(0.1, -0.2, 0.3)),
    "Helix": lambda: ik.sim.Helix(radius=3.0, climb_rate=0.5),
    "Circle": lambda: ik.sim.Circle(radius=2.0),
    "FigureEight": lambda: ik.sim.FigureEight(roll=0.1),
    "VioEllipse": lambda: ik.sim.VioEllipse(pitch=0.3),
    "Waypoints": lambda: ik.sim.Waypoints(
        [0.0, 1.0, 2.5], [[0, 0, 0], [1, 2, 0], [3, 1, 1]], Rotation.from_rotvec([[0, 0, 0], [0, 0, 1], [0.2, 0, 2]])
    ),
    "SensorErrors": lambda: ik.sim.SensorErrors.from_scale_misalignment(
        [1e-3, -2e-3, 5e-4], [[0, 1e-3, 0], [0, 0, -2e-3], [1e-3, 0, 0]], gauss_markov_sigma=1e-3, gauss_markov_tau=50.0
    ),
    # imukit.noise
    "AllanDeviation": _allan,
    "AllanFit": lambda: ik.noise.fit_allan(_allan(), sensor="gyro", axis=0),
    "NoiseCalibration": _calibration,
    # imukit.eval
    "Association": lambda: ik.eval.associate(*_estimate()),
    "Alignment": lambda: ik.eval.align(*_estimate(), method="sim3"),
    "AbsoluteError": lambda: ik.eval.ape(*_estimate()),
    "RelativeError": lambda: ik.eval.rpe(*_estimate(), delta=0.5, unit="s"),
    "ErrorStats": lambda: ik.eval.ape(*_estimate()).translation_stats,
    "AttitudeError": lambda: ik.eval.attitude_error(*(t.rotation for t in _estimate()), align_heading=True),
    "AttitudeRmse": lambda: ik.eval.attitude_error(*(t.rotation for t in _estimate())).rmse(),
    "TimeOffset": lambda: ik.eval.time_offset(*_sim(duration=30.0), max_offset=0.05),
    # imukit.io
    "ReadReport": _report,
    "SkippedLine": lambda: _report().skipped[0],
    "SkippedLinesWarning": lambda: ik.io.SkippedLinesWarning("1 line skipped in imu.csv: 1 malformed"),
    "Gap": lambda: ik.io.find_gaps(ik.ImuData([0.0, 0.01, 0.02, 0.5], [[0.0] * 3] * 4, [[0.0, 0.0, 9.81]] * 4))[0],
    "KalibrImu": lambda: ik.io.KalibrImu(NOISE, 200.0, {"rostopic": "/imu0", "T_BS": [[1.0, 0.0], [0.0, 1.0]]}),
    # imukit.filters: options, the saved state and the result
    "GainRamp": lambda: ik.filters.GainRamp(),
    "AccelLowPass": lambda: ik.filters.AccelLowPass(0.5),
    "AccelRejection": lambda: ik.filters.AccelRejection(),
    "MagRejection": lambda: ik.filters.MagRejection(),
    "RestDetection": lambda: ik.filters.RestDetection(),
    "FilterState": lambda: _filter_result().state,
    "FilterResult": _filter_result,
    "RobustState": lambda: _robust_result().state,
    "RobustResult": _robust_result,
    "Mahony": lambda: _streaming(ik.filters.Mahony),
    "Madgwick": lambda: _streaming(ik.filters.Madgwick),
    "Robust": lambda: _streaming(ik.filters.Robust),
    # imukit.fleet: what a Dask task takes and returns
    "Input": lambda: ik.fleet.Input("logs/unit7.csv", {"unit_id": "unit-7", "km": 12.5}),
    "JobOutput": lambda: ik.fleet.JobOutput({"samples": 3, "rate_hz": 200.0, "error": None}, {"dp": np.eye(3)}),
    "RestSegment": lambda: ik.fleet.RestSegment(10, 250, 1.195),
    "Scan": lambda: ik.fleet.Scan([ik.fleet.Input("logs/unit7.csv", {"unit_id": "unit-7"})], ["logs/notes.txt"]),
    "RestRule": lambda: ik.fleet.RestRule(0.02, 0.1, 2.0),
    "Recording": lambda: ik.fleet.Recording(*_sim(), _report()),
    # Exceptions carry their fields.
    **{
        name: _error(getattr(ik, name))
        for name in ik.__all__
        if inspect.isclass(getattr(ik, name)) and issubclass(getattr(ik, name), ik.ImukitError)
    },
}

XFAIL: dict[str, str] = {}


def public_classes() -> dict[str, type]:
    found: dict[str, type] = {}
    for module_name in MODULES:
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", []):
            value = getattr(module, name)
            if inspect.isclass(value):
                found[value.__name__] = value
    return found


def test_every_public_class_is_registered() -> None:
    classes = public_classes()
    missing = sorted(set(classes) - set(FACTORIES) - set(NOT_DATA))
    assert not missing, f"public classes with no pickle factory (add one to FACTORIES): {missing}"
    stale = sorted(name for name in FACTORIES if name not in classes)
    assert not stale, f"factories for names that are not public classes: {stale}"


def test_torch_classes_are_registered() -> None:
    if torch is None:
        pytest.skip(f"{TORCH_ABSENT}: Preintegrated and State are not checked")
    assert set(TORCH_FACTORIES) <= set(public_classes())
    assert {name for name, cls in public_classes().items() if cls.__module__.startswith("imukit.torch")} == set(
        TORCH_FACTORIES
    )


def _bits(x: float) -> bytes:
    return struct.pack("<d", x)


def assert_same(a: Any, b: Any, path: str = "x", *, copied: bool = False) -> None:
    """``a`` and ``b`` equal field by field, bit for bit; with ``copied``, no array shared."""
    assert type(a) is type(b), f"{path}: {type(a).__name__} != {type(b).__name__}"
    if torch is not None and isinstance(a, torch.Tensor):
        assert (a.dtype, a.shape, a.device) == (b.dtype, b.shape, b.device), (
            f"{path}: {a.dtype}{a.shape} != {b.dtype}{b.shape}"
        )
        assert torch.equal(a, b), f"{path}: tensors differ"
        assert not (copied and a.untyped_storage().data_ptr() == b.untyped_storage().data_ptr()), f"{path}: shared"
    elif isinstance(a, np.ndarray):
        assert (a.dtype, a.shape) == (b.dtype, b.shape), f"{path}: {a.dtype}{a.shape} != {b.dtype}{b.shape}"
        assert a.flags.writeable == b.flags.writeable, f"{path}: writeable {a.flags.writeable} != {b.flags.writeable}"
        assert a.tobytes() == b.tobytes(), f"{path}: the bytes differ"
        assert not (copied and np.shares_memory(a, b)), f"{path}: the copy shares memory with the original"
    elif isinstance(a, Rotation):
        assert a.single == b.single, f"{path}: single {a.single} != {b.single}"
        assert_same(a.as_quat(canonical=False), b.as_quat(canonical=False), f"{path}.as_quat()")
    elif isinstance(a, float):
        assert _bits(a) == _bits(b), f"{path}: {a!r} != {b!r}"
    elif isinstance(a, BaseException):
        assert (a.args, str(a)) == (b.args, str(b)), f"{path}: {a!r} != {b!r}"
        for name in ("message", "argument", "index"):
            if hasattr(a, name):
                assert_same(getattr(a, name), getattr(b, name), f"{path}.{name}")
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b), f"{path}: length {len(a)} != {len(b)}"
        for k, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{path}[{k}]", copied=copied)
    elif isinstance(a, dict):
        assert list(a) == list(b), f"{path}: keys {list(a)} != {list(b)}"
        for key in a:
            assert_same(a[key], b[key], f"{path}[{key!r}]", copied=copied)
    elif inspect.isroutine(a) or inspect.isclass(a):  # pickled by reference (scipy's spline internals)
        assert a is b, f"{path}: {a!r} is not {b!r}"
    elif isinstance(a, (str, bytes, int, type(None), bool)):
        assert a == b, f"{path}: {a!r} != {b!r}"
    elif "_lock" in getattr(a, "__dict__", {}):  # its lock is its own, not data: a copy gets a new one
        assert type(a._lock) is type(b._lock) and a._lock is not b._lock, f"{path}._lock: shared or missing"
        data = [{k: v for k, v in sorted(vars(x).items()) if k != "_lock"} for x in (a, b)]
        assert_same(*data, f"{path}.__dict__", copied=copied)
    else:
        fields = _fields(a)
        if not fields:  # an opaque native object (the Preintegrator accumulator, a core filter): what it pickles
            words = next(w for w in ("__getnewargs_ex__", "__getnewargs__", "__reduce__") if hasattr(a, w))
            assert_same(getattr(a, words)(), getattr(b, words)(), f"{path}.{words}()", copied=copied)
            return
        for name in fields:
            assert_same(getattr(a, name), getattr(b, name), f"{path}.{name}", copied=copied)


def _fields(x: Any) -> list[str]:
    if dataclasses.is_dataclass(x):
        return [f.name for f in dataclasses.fields(x)]
    slots = [s for cls in type(x).__mro__ for s in getattr(cls, "__slots__", ()) if s != "__weakref__"]
    # Rust value classes (#[pyclass(get_all)]) expose their fields as getset descriptors.
    native = [
        n
        for cls in type(x).__mro__
        for n, v in vars(cls).items()
        if inspect.isgetsetdescriptor(v) and not n.startswith("__")
    ]
    return slots + native + list(getattr(x, "__dict__", {}))


def _cases() -> list[Any]:
    return [
        pytest.param(name, marks=pytest.mark.xfail(strict=True, reason=XFAIL[name])) if name in XFAIL else name
        for name in FACTORIES
    ]


@pytest.mark.parametrize("name", _cases())
def test_pickle_round_trip(name: str) -> None:
    original = FACTORIES[name]()
    assert type(original).__name__ == name
    for protocol in (2, pickle.HIGHEST_PROTOCOL):
        assert_same(original, pickle.loads(pickle.dumps(original, protocol=protocol)))


def test_merged_preintegration_round_trip() -> None:
    imu = _sim()[0]
    merged = ik.preintegrate(imu[:150], noise=NOISE).merge(ik.preintegrate(imu[149:], noise=NOISE))
    assert_same(merged, pickle.loads(pickle.dumps(merged)))
    assert_same(merged, copy.deepcopy(merged), copied=True)


@pytest.mark.parametrize("name", _cases())
def test_deepcopy_is_exact_and_shares_nothing(name: str) -> None:
    original = FACTORIES[name]()
    assert_same(original, copy.deepcopy(original), copied=True)


def test_copies_stay_immutable() -> None:
    imu = FACTORIES["ImuData"]()
    for clone in (pickle.loads(pickle.dumps(imu)), copy.deepcopy(imu)):
        with pytest.raises(AttributeError, match="ImuData is immutable"):
            clone.gyro = clone.accel
        with pytest.raises(ValueError, match="read-only"):
            clone.gyro[0, 0] = 1.0
        assert not clone.seconds.flags.writeable


def test_integer_stamps_survive_the_round_trip() -> None:
    imu = _imu_ns()
    clone = pickle.loads(pickle.dumps(imu))
    assert clone.t_ns is not None and clone.t_ns.dtype == np.int64
    assert_same(imu.seconds, clone.seconds)
    assert clone.gyro_range == 20.0
    np.testing.assert_array_equal(clone.gyro_saturated, imu.gyro_saturated)


def test_magnetometer_survives_the_round_trip() -> None:
    imu = _imu_ns()
    with_mag = ik.ImuData(imu.t_ns, imu.gyro, imu.accel, mag=imu.accel * 3.0 + 1.0)
    for clone in (pickle.loads(pickle.dumps(with_mag)), copy.deepcopy(with_mag)):
        assert_same(with_mag, clone)  # field by field: mag included, bit for bit and read-only
        assert clone.mag is not None and not clone.mag.flags.writeable
    assert pickle.loads(pickle.dumps(imu)).mag is None


def test_exception_fields_survive_the_round_trip() -> None:
    exc = ik.TimestampError("time must increase strictly", argument="t", index=3)
    clone = pickle.loads(pickle.dumps(exc))
    assert (type(clone), clone.argument, clone.index, str(clone)) == (
        ik.TimestampError,
        "t",
        3,
        "t: time must increase strictly",
    )


def _echo(value: Any) -> Any:
    return value


def _integrated(imu: ik.ImuData, initial: ik.NavState) -> ik.Trajectory:
    """What a Dask / multiprocessing worker does: compute on the data it was sent, send back a result."""
    return ik.integrate(imu, initial=initial)


@pytest.mark.parametrize("name", ["ImuData", "Trajectory"])
def test_process_pool_round_trip(name: str) -> None:
    original = FACTORIES[name]()
    with ProcessPoolExecutor(max_workers=1) as pool:
        assert_same(original, pool.submit(_echo, original).result())


def test_worker_computes_as_the_parent() -> None:
    imu, truth = _sim()
    with ProcessPoolExecutor(max_workers=1) as pool:
        remote = pool.submit(_integrated, imu, truth.state(0)).result()
    assert_same(_integrated(imu, truth.state(0)), remote)
    assert math.isfinite(float(remote.position[-1, 0]))
