"""Errors raised by the Rust core carry the argument and the sample index as fields (decision 1):
the glue builds ``cls(message, argument=..., index=...)``, and ``str(exc)`` is unchanged."""

from __future__ import annotations

import inspect
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

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


def test_scheme_lists_come_from_the_core_and_old_names_warn_but_give_the_same_result() -> None:
    assert ik.attitude.SCHEMES == _core.ATTITUDE_SCHEMES == ("euler", "exp", "rk2", "rk4", "magnus")
    assert ik.strapdown.SCHEMES == _core.STRAPDOWN_SCHEMES == ("lie_euler", "midpoint", "rk4", "exp")
    assert ik.attitude.SCHEME_ALIASES == {"midpoint": "rk2"}
    assert ik.strapdown.SCHEME_ALIASES == {"euler": "lie_euler"}
    assert ik.preint.SCHEMES == _core.PREINT_SCHEMES == ("midpoint", "lie_euler")
    assert ik.preint.SCHEME_ALIASES == {"euler": "lie_euler"}
    assert ik.filters.WORLDS == _core.FILTER_WORLDS == ("ENU", "NED")
    t = np.arange(20) * 0.01
    gyro = np.random.default_rng(3).normal(size=(20, 3))
    with pytest.warns(DeprecationWarning, match="scheme='midpoint' is deprecated, use scheme='rk2'") as record:
        old = ik.integrate_attitude(t, gyro, scheme="midpoint")
    assert record[0].filename == __file__  # points at the caller's line
    np.testing.assert_array_equal(old.as_quat(), ik.integrate_attitude(t, gyro, scheme="rk2").as_quat())
    imu = ik.ImuData(t, gyro, np.tile([0.0, 0.0, 9.81], (20, 1)))
    x0 = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    with pytest.warns(DeprecationWarning, match="use scheme='lie_euler'") as record:
        old_traj = ik.integrate(imu, initial=x0, scheme="euler")
    assert record[0].filename == __file__
    np.testing.assert_array_equal(old_traj.position, ik.integrate(imu, initial=x0, scheme="lie_euler").position)


def test_the_defaults_do_not_warn() -> None:
    t = np.arange(5) * 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ik.integrate_attitude(t, np.zeros((5, 3)))
        imu = ik.ImuData(t, np.zeros((5, 3)), np.zeros((5, 3)))
        ik.integrate(imu, initial=ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity()))


def test_gravity_default_is_the_core_constant() -> None:
    for fn in (ik.integrate, ik.propagate):
        assert inspect.signature(fn).parameters["gravity"].default == _core.GRAVITY == (0.0, 0.0, -9.81)


def _imu() -> ik.ImuData:
    t = np.arange(50) * 0.01
    return ik.ImuData(t, np.tile([0.1, -0.2, 0.3], (50, 1)), np.tile([0.0, 0.0, 9.81], (50, 1)))


NOISE = ik.ImuNoise(1e-3, 1e-2, 1e-4, 1e-3)
REST = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
DEPRECATED: dict[str, Callable[[Path], object]] = {
    "preintegrate(scheme='euler')": lambda tmp: ik.preintegrate(_imu(), noise=NOISE, scheme="euler"),
    "PreintegratedImu(scheme='euler')": lambda tmp: ik.PreintegratedImu(noise=NOISE, scheme="euler"),
    "preintegrate_windows(noise=...)": lambda tmp: ik.preintegrate_windows(_imu(), [0.0, 0.2, 0.4], noise=NOISE),
    "reintegrate(bias)": lambda tmp: ik.preintegrate(_imu(), noise=NOISE).reintegrate(ik.ImuBias()),
    "integrate(scheme='euler')": lambda tmp: ik.integrate(_imu(), initial=REST, scheme="euler"),
    "integrate_attitude(scheme='midpoint')": lambda tmp: ik.integrate_attitude(
        _imu().t, _imu().gyro, scheme="midpoint"
    ),
    "FilterState.values": lambda tmp: ik.filters.Mahony().run(_imu()).state.values,
    "Trajectory.write_tum": lambda tmp: ik.integrate(_imu(), initial=REST).write_tum(tmp / "t.tum"),
}


@pytest.mark.parametrize("name", list(DEPRECATED))
def test_every_deprecation_points_at_the_users_line(name: str, tmp_path: Path) -> None:
    """However deep in imukit the check sits, the warning names this file (imukit's own calls of a
    deprecated name would name an imukit file, and pyproject makes those an error)."""
    with pytest.warns(DeprecationWarning) as record:
        DEPRECATED[name](tmp_path)
    assert [w.filename for w in record if issubclass(w.category, DeprecationWarning)] == [__file__]


def test_scheme_defaults_are_the_cores() -> None:
    # Each default is written once, in the core's `Default`; Python's signatures read it.
    assert (_core.ATTITUDE_DEFAULT_SCHEME, _core.STRAPDOWN_DEFAULT_SCHEME, _core.PREINT_DEFAULT_SCHEME) == (
        "rk2",
        "midpoint",
        "midpoint",
    )
    assert inspect.signature(ik.integrate_attitude).parameters["scheme"].default == "rk2"
    for f in (ik.integrate, ik.propagate):
        assert inspect.signature(f).parameters["scheme"].default == "midpoint"
    noise = ik.ImuNoise(gyro_density=1e-3, accel_density=1e-2, gyro_random_walk=1e-5, accel_random_walk=1e-4)
    assert ik.PreintParams(noise).scheme == "midpoint"
