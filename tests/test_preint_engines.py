"""Conformance of the preintegration engines (``imukit._engines.ENGINES``, the registry: an engine
joins these tests by its line there) to the Rust engine, field by field, on simulated data with
several windows (boundaries on and between samples), both schemes, non-uniform dt, clipped
samples and the combined covariance. Tolerances: 1e-12 relative (to the field's largest entry) on
the deltas and the bias Jacobian, 1e-10 on the covariances, Δt and the window times exact."""

from __future__ import annotations

import copy
import pickle
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit import _core
from imukit._engines import ENGINES
from imukit.preint import Preintegration, PreintParams, preintegrate_windows

NOISE = ik.ImuNoise(gyro_density=1.7e-4, accel_density=2e-3, gyro_random_walk=1.9e-5, accel_random_walk=3e-3)
BIAS = ik.ImuBias(gyro=[0.01, -0.005, 0.02], accel=[0.1, -0.05, 0.02])
TOLERANCE = {
    "delta_rotation": 1e-12,
    "delta_velocity": 1e-12,
    "delta_position": 1e-12,
    "bias_jacobian": 1e-12,
    "covariance": 1e-10,
    "covariance_combined": 1e-10,
}
EXACT = ("delta_t", "t_start", "t_end", "t_start_ns", "t_end_ns")


def recording(*, ns: bool) -> ik.ImuData:
    """300 samples at a jittered ~200 Hz, turning and accelerating, some of each sensor clipped."""
    rng = np.random.default_rng(7)
    step_ns = rng.integers(4_000_000, 6_000_000, 299)
    t_ns = 1_403_636_579_758_555_392 + np.concatenate([[0], np.cumsum(step_ns)])
    t = (t_ns - t_ns[0]) / 1e9
    gyro = 0.6 * np.sin(np.outer(t, [1.0, 2.3, 3.1])) + 0.1
    accel = np.array([0.0, 0.0, 9.81]) + 2.0 * np.cos(np.outer(t, [2.0, 1.1, 0.5]))
    stamps = t_ns if ns else t + 12.5
    gyro_range = float(np.percentile(np.abs(gyro).max(axis=1), 90))
    accel_range = float(np.percentile(np.abs(accel).max(axis=1), 90))
    imu = ik.ImuData(stamps, gyro, accel, gyro_range=gyro_range, accel_range=accel_range)
    assert 0 < imu.gyro_saturated.sum() < 300 and 0 < imu.accel_saturated.sum() < 300
    return imu


def edges(imu: ik.ImuData) -> Any:
    """Five windows: on samples and between them (the interpolated boundary model)."""
    if imu.t_ns is not None:
        t = imu.t_ns
        return np.array([t[3] + 1_300_000, t[60], t[100] + 7, t[180], t[250] + 2_000_000, t[-2]], dtype=np.int64)
    t = imu.t
    return np.array([t[3] + 0.0013, t[60], t[100] + 1e-6, t[180], t[250] + 0.002, t[-2]])


@pytest.mark.parametrize("engine", sorted(ENGINES))
@pytest.mark.parametrize("scheme", ["lie_euler", "midpoint"])
@pytest.mark.parametrize("combined", [False, True])
@pytest.mark.parametrize("ns", [False, True])
def test_every_engine_matches_the_rust_engine(engine: str, scheme: str, combined: bool, ns: bool) -> None:
    imu = recording(ns=ns)
    params = PreintParams(NOISE, BIAS, scheme=scheme, combined=combined, saturation_noise_factor=30.0)
    reference = preintegrate_windows(imu, edges(imu), params)
    got = preintegrate_windows(imu, edges(imu), params, engine=engine)
    assert isinstance(got, Preintegration) and len(got) == len(reference) == 5
    assert got.params == params
    for name, tol in TOLERANCE.items():
        want, have = getattr(reference, name), getattr(got, name)
        if name == "covariance_combined" and not combined:
            assert want is None and have is None
            continue
        assert have.shape == want.shape, name
        assert np.abs(have - want).max() <= tol * np.abs(want).max(), name
    for name in EXACT:
        want, have = getattr(reference, name), getattr(got, name)
        assert (want is None and have is None) if not ns and name.endswith("_ns") else np.array_equal(want, have), name


def test_the_clipped_samples_reach_the_covariance() -> None:
    # Guards the conformance test: with the flags ignored (factor 1) the covariance must change.
    imu = recording(ns=False)
    inflated = preintegrate_windows(imu, edges(imu), PreintParams(NOISE, saturation_noise_factor=30.0))
    plain = preintegrate_windows(imu, edges(imu), PreintParams(NOISE, saturation_noise_factor=1.0))
    assert (
        np.trace(inflated.covariance, axis1=1, axis2=2).max() > 2 * np.trace(plain.covariance, axis1=1, axis2=2).max()
    )


def test_the_rust_engine_is_one_native_call(monkeypatch: pytest.MonkeyPatch) -> None:
    imu = recording(ns=True)
    calls: list[str] = []
    for name in dir(_core):
        value = getattr(_core, name)
        if callable(value) and not name.startswith("__"):

            def counted(*args: Any, _name: str = name, _f: Any = value, **kwargs: Any) -> Any:
                calls.append(_name)
                return _f(*args, **kwargs)

            monkeypatch.setattr(_core, name, counted)
    params = PreintParams(NOISE, combined=True)
    calls.clear()
    record = preintegrate_windows(imu, edges(imu), params)
    # One call fills every window, reading the samples and the options by attribute name.
    assert calls == ["preint_windows_record"]
    assert len(record) == 5


def test_the_record_slices_pickles_and_deep_copies_exactly() -> None:
    imu = recording(ns=True)
    record = preintegrate_windows(imu, edges(imu), PreintParams(NOISE, BIAS, scheme="lie_euler", combined=True))
    fields = [f for f in vars(record) if f != "params"]
    for back in (pickle.loads(pickle.dumps(record)), copy.deepcopy(record)):
        assert back.params == record.params
        for name in fields:
            assert np.array_equal(getattr(back, name), getattr(record, name)), name
            assert not getattr(back, name).flags.writeable, name
    one, tail = record[2], record[-2:]
    assert len(one) == 1 and len(tail) == 2
    assert np.array_equal(one.covariance[0], record.covariance[2])
    assert np.array_equal(tail.t_end_ns, record.t_end_ns[3:])
    assert [len(w) for w in record] == [1] * 5
    with pytest.raises(IndexError):
        record[5]


def test_batched_functions_equal_the_streaming_object_per_window() -> None:
    imu = recording(ns=False)
    params = PreintParams(NOISE, BIAS)
    record = preintegrate_windows(imu, edges(imu), params)
    other = ik.ImuBias(gyro=[0.012, -0.004, 0.018], accel=[0.12, -0.06, 0.0])
    rng = np.random.default_rng(3)
    m = len(record)
    states = ik.preint.States(rng.normal(size=(m, 3)), rng.normal(size=(m, 3)), ik.so3.exp(rng.normal(size=(m, 3))))
    later = ik.preint.predict(record, states, other)
    res = ik.preint.residual(record, states, later, other)
    assert np.abs(res).max() < 1e-12  # the prediction has no residual
    jac = ik.preint.residual_jacobians(record, states, later, other)
    for k in range(m):
        lo, hi = record.t_start[k], record.t_end[k]
        (single,) = preintegrate_windows(imu, [lo, hi], noise=NOISE, bias=BIAS)  # the list form
        x_i = ik.NavState(states.position[k], states.velocity[k], Rotation.from_matrix(states.rotation[k]))
        x_j = single.predict(x_i, other)
        assert np.abs(x_j.position - later.position[k]).max() < 1e-12
        np.testing.assert_allclose(single.residual_jacobians(x_i, x_j, other).bias, jac.bias[k], atol=1e-12)


def test_reintegrate_takes_the_samples() -> None:
    imu = recording(ns=True)
    record = preintegrate_windows(imu, edges(imu), PreintParams(NOISE, BIAS))
    other = ik.ImuBias(gyro=[0.0, 0.01, 0.0])
    again = ik.preint.reintegrate(record, imu, other)
    fresh = preintegrate_windows(imu, edges(imu), PreintParams(NOISE, other))
    assert np.array_equal(again.delta_position, fresh.delta_position)
    assert np.array_equal(again.t_start_ns, record.t_start_ns)
    pim = ik.preintegrate(imu, PreintParams(NOISE, BIAS, scheme="lie_euler"))
    exact = pim.reintegrate(imu, other)
    assert np.array_equal(
        exact.covariance, ik.preintegrate(imu, noise=NOISE, bias=other, scheme="lie_euler").covariance
    )


def test_scheme_names_come_from_the_core_and_euler_is_a_deprecated_alias() -> None:
    assert ik.preint.SCHEMES == tuple(_core.PREINT_SCHEMES) == ("midpoint", "lie_euler")
    with pytest.warns(DeprecationWarning, match="scheme='euler' is deprecated, use scheme='lie_euler'"):
        params = PreintParams(NOISE, scheme="euler")
    assert params.scheme == "lie_euler"
    assert PreintParams(NOISE).saturation_noise_factor == _core.DEFAULT_SATURATION_NOISE_FACTOR
    with pytest.raises(ik.ParameterError, match="scheme"):
        PreintParams(NOISE, scheme="rk4")


def test_params_pickle_and_the_streaming_snapshot_is_one_read(monkeypatch: pytest.MonkeyPatch) -> None:
    params = PreintParams(NOISE, BIAS, gravity=(0.0, 0.0, -9.8), combined=True)
    assert pickle.loads(pickle.dumps(params)) == params == copy.deepcopy(params)
    imu = recording(ns=False)
    pim = ik.preintegrate(imu, params)
    reads: list[int] = []
    state = type(pim._core).state
    monkeypatch.setattr(pim, "_core", _Counting(pim._core, reads, state))
    _ = (pim.delta_rotation, pim.delta_velocity, pim.delta_position, pim.delta_t, pim.covariance, pim.bias_jacobian)
    assert pim.covariance_combined is not None
    assert reads == [1]
    snap = pim.snapshot()
    assert snap.t_start[0] == imu.t[0] and snap.t_end[0] == imu.t[-1]


class _Counting:
    """A core preintegrator whose ``state()`` reads are counted."""

    def __init__(self, core: Any, reads: list[int], state: Any) -> None:
        self._core, self._reads, self._state = core, reads, state

    def state(self) -> Any:
        self._reads.append(1)
        return self._state(self._core)


@pytest.mark.parametrize("scheme", ["lie_euler", "midpoint"])
def test_the_streaming_accumulator_pickles_and_continues_exactly(scheme: str) -> None:
    imu = recording(ns=False)
    pim = ik.PreintegratedImu(PreintParams(NOISE, BIAS, scheme=scheme, combined=True, saturation_noise_factor=30.0))
    pim.integrate(imu[:100])  # midpoint: the copy must remember the last sample and its noise
    for back in (pickle.loads(pickle.dumps(pim)), copy.deepcopy(pim)):
        assert back.params == pim.params and back.scheme == pim.scheme
        for part in (back, pim):
            part.integrate(imu[99:200])
        snap, want = back.snapshot(), pim.snapshot()
        for name in TOLERANCE:
            assert np.array_equal(getattr(snap, name), getattr(want, name)), name
        assert snap.delta_t == want.delta_t and snap.t_start == want.t_start
        pim = ik.PreintegratedImu(PreintParams(NOISE, BIAS, scheme=scheme, combined=True, saturation_noise_factor=30.0))
        pim.integrate(imu[:100])
    # The deprecated reintegrate(bias) replays the copy's own log: the same result as the original's.
    other = ik.ImuBias(BIAS.gyro + 1e-3, BIAS.accel - 1e-2)
    with pytest.warns(DeprecationWarning):
        replayed, want = (
            pickle.loads(pickle.dumps(pim)).reintegrate(other).snapshot(),
            pim.reintegrate(other).snapshot(),
        )
    for name in TOLERANCE:
        assert np.array_equal(getattr(replayed, name), getattr(want, name)), name
