"""Filters as data (issue 14): the options, the gains and the state pickle and deep-copy exactly,
a restored state continues a run bit for bit, every default read from Python is the Rust
``Default`` (and the documented number), and the deprecated flat-layout state still works."""

from __future__ import annotations

import copy
import math
import pickle
from typing import Any

import numpy as np
import pytest

import imukit as ik
from imukit import _core
from imukit.filters import (
    AccelLowPass,
    AccelRejection,
    FilterState,
    GainRamp,
    Madgwick,
    MagRejection,
    Mahony,
    RestDetection,
)

FIELD = np.array([0.0, 22.0, -42.0])


def roundtrips(x: Any) -> list[Any]:
    return [pickle.loads(pickle.dumps(x)), copy.deepcopy(x), copy.copy(x)]


@pytest.fixture(scope="module")
def moving() -> tuple[ik.ImuData, np.ndarray]:
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200, duration=10, seed=4)
    return imu, truth.rotation.inv().apply(FIELD)


OPTIONS = [
    GainRamp(2.0, 4.0),
    AccelRejection(norm=1.5, angle_rad=0.2, recovery_s=3.0),
    MagRejection(norm_fraction=0.2, dip_rad=0.1, recovery_s=7.0),
    RestDetection(gyro=0.1, accel=0.3, duration_s=0.5, tau_s=2.0),
    _core.MahonyGains(kp=0.7, ki=0.02),
    _core.MadgwickGains(beta=0.1, full_rate_angle_rad=0.05),
    _core.FilterOptions.default(),
]


@pytest.mark.parametrize("option", OPTIONS, ids=lambda o: type(o).__name__)
def test_options_round_trip_field_by_field(option: Any) -> None:
    for back in roundtrips(option):
        assert type(back) is type(option)
        assert back == option
        if not isinstance(option, _core.FilterOptions):  # options holding options are not hashed
            assert hash(back) == hash(option)
        for name in dir(option):
            if not name.startswith("_") and not callable(getattr(option, name)):
                assert getattr(back, name) == getattr(option, name), name
    if not isinstance(option, _core.FilterOptions):  # not the defaults: the round trip kept each field
        assert option != type(option)()


@pytest.mark.parametrize("nine", [False, True])
@pytest.mark.parametrize("cls", [Mahony, Madgwick])
def test_state_round_trips_and_continues_bit_identically(
    cls: type[Mahony], nine: bool, moving: tuple[ik.ImuData, np.ndarray]
) -> None:
    imu, mag = moving
    cut = 900
    m = mag if nine else None
    f = cls(rest_detection=RestDetection())
    first = f.run(imu[:cut], mag=None if m is None else m[:cut])
    rest = imu[cut:]
    expected = f.run(rest, mag=None if m is None else m[cut:], initial=first.state)
    for state in roundtrips(first.state):
        assert isinstance(state, FilterState) and state == first.state
        np.testing.assert_array_equal(state.quaternion, first.state.quaternion)
        np.testing.assert_array_equal(state.gyro_bias, first.state.gyro_bias)
        for name in ("initialized", "time", "ramp_elapsed", "accel_rejected", "mag_rejected", "rest", "mag_norm"):
            assert getattr(state, name) == getattr(first.state, name), name
        again = f.run(rest, mag=None if m is None else m[cut:], initial=state)
        np.testing.assert_array_equal(again.rotation.as_quat(), expected.rotation.as_quat())
        np.testing.assert_array_equal(again.gyro_bias, expected.gyro_bias)


@pytest.mark.parametrize("cls", [Mahony, Madgwick])
def test_filters_round_trip_with_their_streaming_state(
    cls: type[Mahony], moving: tuple[ik.ImuData, np.ndarray]
) -> None:
    imu, mag = moving
    f = cls(acc_rejection=AccelRejection(norm=2.0), rest_detection=RestDetection(), gain_ramp=None)
    dts = np.diff(imu.seconds, prepend=0.0)
    for k in range(500):
        f.update(imu.gyro[k], imu.accel[k], dts[k], mag=mag[k])
    copies = roundtrips(f)
    expected = [f.update(imu.gyro[k], imu.accel[k], dts[k], mag=mag[k]).as_quat() for k in range(500, 800)]
    for g in copies:
        assert type(g) is cls and g.options == f.options and g.gains == f.gains
        got = [g.update(imu.gyro[k], imu.accel[k], dts[k], mag=mag[k]).as_quat() for k in range(500, 800)]
        assert np.array_equal(np.array(got), np.array(expected))
        assert g.get_state() == f.get_state()


# The documented defaults (docs/filters.md), read back through the core's Default impls.
DOCUMENTED = {
    GainRamp: {"duration_s": 3.0, "factor": 10.0},
    AccelLowPass: {"tau_s": 1.0},
    AccelRejection: {
        "norm": 2.0,
        "angle_rad": math.radians(3.0),
        "recovery_s": 15.0,
        "filtered_norm": 0.3,
        "drift_s": 2.0,
    },
    MagRejection: {"norm_fraction": 0.1, "dip_rad": math.radians(10.0), "recovery_s": 10.0},
    RestDetection: {"gyro": 0.05, "accel": 1.0, "duration_s": 1.0, "tau_s": 1.0, "max_bias": 0.1},
    _core.MahonyGains: {"kp": 0.3, "ki": 0.01},
    _core.MadgwickGains: {"beta": 0.035, "full_rate_angle_rad": 0.08},
}


@pytest.mark.parametrize("cls", list(DOCUMENTED), ids=lambda c: c.__name__)
def test_python_defaults_are_the_rust_defaults(cls: type) -> None:
    value = cls()
    for name, number in DOCUMENTED[cls].items():
        assert getattr(value, name) == pytest.approx(number, rel=1e-15), name
    # Omitted and None fields both take the Rust Default; the public names are the core's classes.
    assert cls(*[None] * len(DOCUMENTED[cls])) == value
    assert getattr(ik.filters, cls.__name__, cls) is cls


def test_filter_keyword_defaults_come_from_the_core() -> None:
    core = _core.FilterOptions.default()
    assert (core.world, core.gravity, core.rest_detection) == ("ENU", 9.81, RestDetection())
    assert (core.gain_ramp, core.acc_rejection, core.mag_rejection) == (GainRamp(), AccelRejection(), MagRejection())
    assert core.acc_lowpass == AccelLowPass()
    for f in (Mahony(), Madgwick()):
        assert f.options == core and (f.world, f.gravity) == ("ENU", 9.81)
    assert (Mahony().kp, Mahony().ki, Madgwick().beta, Madgwick().full_rate_angle_rad) == (0.3, 0.01, 0.035, 0.08)
    # Switching an option off is None; a plain tuple of the fields is still an option.
    assert Mahony(gain_ramp=None).options.gain_ramp is None
    assert Mahony(gain_ramp=(1.0, 2.0)).options.gain_ramp == GainRamp(1.0, 2.0)  # type: ignore[arg-type]


def test_option_type_errors_name_the_field() -> None:
    with pytest.raises(ik.ParameterError, match=r"^acc_rejection\.angle_rad: expected a real number"):
        AccelRejection(angle_rad="wide")  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^kp: "):
        Mahony(kp="fast")  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^gain_ramp: expected a GainRamp"):
        Mahony(gain_ramp="slow")  # type: ignore[arg-type]


def test_a_state_copies_a_state_and_refuses_a_state_with_fields(moving: tuple[ik.ImuData, np.ndarray]) -> None:
    imu, _ = moving
    state = Madgwick().run(imu).state
    copy = FilterState(state)
    assert type(copy) is FilterState and copy == state and copy.fields() == state.fields()
    assert FilterState(**state.fields()) == state
    assert FilterState(ik._core.FilterState(state)) == state
    for make in (FilterState, ik._core.FilterState):
        with pytest.raises(ik.ParameterError, match=r"^state: expected a state or its fields") as e:
            make(state, time=1.0)
        assert e.value.argument == "state"
    # Without a state, the fields up to mag_dip_cos are required.
    fields = state.fields()
    del fields["mag_norm"]
    with pytest.raises(ik.ParameterError, match=r"^state: expected a state, or the fields"):
        FilterState(**fields)
    # A held field is used as a field: one whose squared norm overflows is refused like one given
    # to `update`; the world is one of the two.
    for held in ({"mag_held": [1e200, 0.0, 0.0]}, {"mag_held": [np.nan, 0.0, 0.0]}, {"mag_held_s": np.inf}):
        with pytest.raises(ik.NonFiniteError, match=r"^state: "):
            FilterState(**{**state.fields(), **held})
    with pytest.raises(ik.ParameterError, match=r"^state: "):  # a negative age would hold it for ever
        FilterState(**{**state.fields(), "mag_held_s": -1.0})
    with pytest.raises(ik.ParameterError, match=r"^world: "):
        FilterState(**{**state.fields(), "world": "NWU"})


def test_deprecated_flat_layout_still_works(moving: tuple[ik.ImuData, np.ndarray]) -> None:
    imu, _ = moving
    state = Mahony().run(imu).state
    with pytest.warns(DeprecationWarning, match="values"):
        values = state.values
    assert values.shape == (16,) and not values.flags.writeable
    with pytest.warns(DeprecationWarning, match="deprecated"):
        rebuilt = FilterState(values)
    # the flat layout predates the accelerometer low pass, rest detection's means and the drift
    # rule's clock: they restart at the next sample; and the world and the held field, which the
    # flat layout never had (no world: the taking filter's own; no held field: none)
    lp = ("acc_lp1", "acc_lp2", "gyro_lp", "rest_gyro_ms", "rest_accel_lp", "rest_accel_ms", "accel_calm", "world")
    assert {k: v for k, v in rebuilt.fields().items() if k not in lp} == {
        k: v for k, v in state.fields().items() if k not in lp
    }
    assert not rebuilt.acc_lp2.any() and state.acc_lp2.any()
    assert rebuilt.world is None and state.world == "ENU"
    np.testing.assert_array_equal(values[:4], state.quaternion)
    assert values[8] == state.time
    with pytest.warns(DeprecationWarning), pytest.raises(ik.ShapeError, match=r"^state: "):
        FilterState(np.zeros(15))
