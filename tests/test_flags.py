"""Flag options take a bool and nothing else: ``scalar_first="no"`` is truthy, and before 2026-12-07
it returned wxyz quaternions; ``degrees="no"`` read radians as degrees, ``combined="no"`` tracked
the 15×15 covariance, ``final_only="no"`` returned one rotation. One rule (``_arrays.flag``) for
every flag: a ``ParameterError`` naming the option."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

T = np.arange(5) * 0.01
GYRO = np.tile([0.0, 0.0, 0.1], (5, 1))
NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
FLAGGED: dict[str, tuple[str, Callable[[object], object]]] = {
    "quat.exp": ("scalar_first", lambda v: ik.quat.exp([0.0, 0.0, 1.0], scalar_first=v)),
    "quat.multiply": ("scalar_first", lambda v: ik.quat.multiply([0, 0, 0, 1.0], [0, 0, 0, 1.0], scalar_first=v)),
    "euler.to_rotation": ("degrees", lambda v: ik.euler.to_rotation([90.0, 0.0, 0.0], degrees=v)),
    "euler.from_rotation": ("degrees", lambda v: ik.euler.from_rotation(np.eye(3), degrees=v)),
    "integrate_attitude": ("final_only", lambda v: ik.integrate_attitude(T, GYRO, final_only=v)),
    "PreintParams": ("combined", lambda v: ik.PreintParams(NOISE, combined=v)),
    "allan_deviation": ("overlapping", lambda v: ik.noise.allan_deviation(np.arange(100.0), 100.0, overlapping=v)),
    "attitude_error": (
        "scalar_first",
        lambda v: ik.eval.attitude_error(
            np.tile([0, 0, 0, 1.0], (3, 1)), np.tile([0, 0, 0, 1.0], (3, 1)), scalar_first=v
        ),
    ),
    "Robust.run": (
        "offline",
        lambda v: ik.filters.Robust().run(ik.ImuData(T, GYRO, np.tile([0, 0, 9.81], (5, 1))), offline=v),
    ),
}


@pytest.mark.parametrize("name", sorted(FLAGGED))
@pytest.mark.parametrize("value", ["no", 1, 0, None, np.array([1, 2])])
def test_a_flag_that_is_not_a_bool_is_refused_naming_the_option(name: str, value: object) -> None:
    option, call = FLAGGED[name]
    with pytest.raises(ik.ParameterError, match=rf"^{option}: expected a bool, got ") as e:
        call(value)
    assert e.value.argument == option
    call(False)
    call(np.bool_(True))  # numpy's bool is a bool


OPTION_FIELDS = {
    "gain_ramp": ("duration_s", "factor"),
    "acc_lowpass": ("tau_s",),
    "acc_rejection": ("norm", "angle_rad", "recovery_s", "filtered_norm", "drift_s"),
    "mag_rejection": ("norm_fraction", "dip_rad", "recovery_s"),
    "rest_detection": ("gyro", "accel", "duration_s", "tau_s", "max_bias"),
}


@pytest.mark.parametrize(("option", "field"), [(o, f) for o, fields in OPTION_FIELDS.items() for f in fields])
def test_an_option_out_of_its_domain_is_named_by_its_field(option: str, field: str) -> None:
    """``gain_ramp.duration`` was named for the field ``duration_s`` (and four others alike) before
    2026-12-07: the name in an error is the one a user passes; and it is raised where the value is
    written, not at the filter that uses it (since the eighth session of 2026-12-07)."""
    default = getattr(ik._core.FilterOptions.default(), option)
    values = {name: getattr(default, name) for name in OPTION_FIELDS[option]}
    with pytest.raises(ik.ParameterError, match=rf"^{option}\.{field}: ") as e:
        type(default)(**{**values, field: -1.0})
    assert e.value.argument == f"{option}.{field}"
    assert isinstance(ik.filters.Mahony(**{option: type(default)(**values)}), ik.filters.Mahony)


def test_window_boundaries_off_the_samples_clock_are_named_on_it() -> None:
    """Boundaries 1 to 3 s on an epoch clock were reported as ``[-1403715522.9, …] outside the
    samples' [0, 39.99]``, and int64 ones near -2^63 wrapped in the message (before 2026-12-07)."""
    t_ns = 1_403_715_523_912_140_000 + np.arange(401) * 5_000_000
    imu = ik.ImuData(t_ns, np.zeros((401, 3)), np.tile([0.0, 0.0, 9.81], (401, 1)))
    params = ik.PreintParams(NOISE)
    with pytest.raises(
        ik.ParameterError, match=r"got 0\.5 to 1\.5: they fit the span counted from the first sample"
    ) as e:
        ik.preintegrate_windows(imu, [0.5, 1.0, 1.5], params)
    assert e.value.argument == "boundaries"
    with pytest.raises(ik.ParameterError, match=r"\(integer ns\) .* got -9223372036854775808 to 0$"):
        ik.preintegrate_windows(imu, np.array([-(2**63), 0]), params)
    with pytest.raises(ik.ParameterError, match=r"got 18446744073709551615 to 18446744073709551615$"):
        ik.preintegrate_windows(imu, np.array([2**64 - 1], dtype=np.uint64), params)
    assert len(ik.preintegrate_windows(imu, imu.t[0] + np.array([0.5, 1.0, 1.5]), params)) == 2


def test_a_trajectory_given_as_attitudes_says_how_to_pass_them() -> None:
    """``attitude_error(estimate, trajectory)`` was "expected real numbers, got dtype object" before
    2026-12-07."""
    _, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=2.0)
    for args, name in (((truth.rotation, truth), "truth"), ((truth, truth.rotation), "estimate")):
        with pytest.raises(ik.ParameterError, match=r"a Trajectory: pass its attitudes .*truth_at_imu") as e:
            ik.eval.attitude_error(*args)
        assert e.value.argument == name
    assert ik.eval.attitude_error(truth.rotation, truth.rotation).rmse().total < 1e-15


@pytest.mark.parametrize(
    ("options", "argument"),
    [
        ({"longer_than": "1"}, "longer_than"),
        ({"longer_than": 0}, "longer_than"),
        ({"factor": float("nan")}, "factor"),
        ({"factor": -2.0}, "factor"),
    ],
)
def test_find_gaps_checks_its_thresholds(options: dict[str, object], argument: str) -> None:
    """``factor=nan`` returned no gap at all, ``longer_than="1"`` a numpy UFuncTypeError (before 2026-12-07)."""
    imu = ik.ImuData([0.0, 0.01, 0.02, 0.5, 0.51], np.zeros((5, 3)), np.tile([0.0, 0.0, 9.81], (5, 1)))
    with pytest.raises(ik.ParameterError, match=rf"^{argument}: expected a positive") as e:
        ik.io.find_gaps(imu, **options)  # type: ignore[arg-type]
    assert e.value.argument == argument
    assert [g.sample for g in ik.io.find_gaps(imu)] == [3]


@pytest.mark.parametrize("cls", [ik.filters.Mahony, ik.filters.Madgwick])
def test_an_unknown_filter_option_is_named(cls: type) -> None:
    """``Mahony(bogus=1)`` was a TypeError naming ``_Filter.__init__()`` (Robust already said "unknown
    field") before 2026-12-07; ``Madgwick(kp=...)`` is a gain of the other law."""
    for name in ("bogus", "kp" if cls is ik.filters.Madgwick else "beta"):
        with pytest.raises(ik.ParameterError, match=rf"^{name}: unknown option of {cls.__name__}; it takes ") as e:
            cls(**{name: 1.0})
        assert e.value.argument == name


def test_imu_data_takes_a_boolean_mask_and_refuses_a_zero_step() -> None:
    """``imu[mask]`` was refused and ``imu[::0]`` raised Python's own ValueError (before 2026-12-07)."""
    t_ns = np.arange(5, dtype=np.int64) * 5_000_000
    gyro, mag = np.arange(15.0).reshape(5, 3), np.arange(15.0).reshape(5, 3) + 100
    imu = ik.ImuData(t_ns, gyro, np.zeros((5, 3)), mag=mag)
    mask = np.array([True, False, True, True, False])
    picked = imu[mask]
    assert picked.t_ns is not None and picked.t_ns.tolist() == [0, 10_000_000, 15_000_000]
    np.testing.assert_array_equal(picked.gyro, gyro[mask])
    np.testing.assert_array_equal(picked.mag, mag[mask])
    for index, message in (
        (slice(None, None, 0), "positive step"),
        (np.zeros(5, bool), "selects no sample"),
        (np.ones(4, bool), r"shape \(5,\)"),
    ):
        with pytest.raises(ik.ShapeError, match=message) as e:
            imu[index]  # type: ignore[index]
        assert e.value.argument == "index"


@pytest.mark.parametrize("scale", [1e-300, 1e-120, 1e154, 1e250])
def test_allan_deviation_scales_with_its_data(scale: float) -> None:
    """``x * 1e-300`` gave deviations of exactly 0 (squares underflowed) and ``x * 1e154`` a
    NonFiniteError (before 2026-12-07); the deviation is linear in the data."""
    x = np.random.default_rng(0).normal(size=(4000, 2))
    base = ik.noise.allan_deviation(x, 100.0)
    scaled = ik.noise.allan_deviation(x * scale, 100.0)
    np.testing.assert_allclose(scaled.deviation, base.deviation * scale, rtol=1e-12)
    with pytest.raises(ik.NonFiniteError):
        ik.noise.allan_deviation(np.where(np.arange(4000)[:, None] == 7, np.nan, x * scale), 100.0)


def test_a_preintegration_given_no_state_names_it() -> None:
    """``pim.predict(None)`` was an AttributeError (before 2026-12-07)."""
    imu = ik.ImuData(np.arange(5) * 0.01, np.zeros((5, 3)), np.tile([0.0, 0.0, 9.81], (5, 1)))
    pim = ik.preintegrate(imu, noise=NOISE)
    state = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    for call, name in ((lambda: pim.predict(None), "state_i"), (lambda: pim.residual(state, None), "state_j")):
        with pytest.raises(ik.ParameterError, match=rf"^{name}: expected an imukit.NavState, got NoneType") as e:
            call()  # type: ignore[no-untyped-call]
        assert e.value.argument == name


def test_batches_that_do_not_broadcast_name_both_inputs() -> None:
    with pytest.raises(
        ik.ShapeError, match=r"^q / p: leading dimensions do not broadcast: q \(3, 4\), p \(2, 4\)"
    ) as e:
        ik.quat.multiply(np.tile([0, 0, 0, 1.0], (3, 1)), np.tile([0, 0, 0, 1.0], (2, 1)))
    assert e.value.argument == "q / p"  # None before 2026-12-07


def test_allan_fit_bounds_and_a_discrete_overflow_name_their_arguments() -> None:
    """``fit_allan(tau_min=1, tau_max=0.5)`` named ``allan``, and ``ImuNoise.discrete``'s overflow had
    no argument (before 2026-12-07)."""
    allan = ik.noise.allan_deviation(np.random.default_rng(0).normal(size=4000), 100.0)
    with pytest.raises(ik.ParameterError, match=r"^tau_min / tau_max: expected tau_min ≤ tau_max") as e:
        ik.noise.fit_allan(allan, tau_min=1.0, tau_max=0.5)
    assert e.value.argument == "tau_min / tau_max"
    with pytest.raises(ik.ParameterError, match=r"^tau_min / tau_max: fitting 3 parameters needs at least 4"):
        ik.noise.fit_allan(allan, tau_min=0.5, tau_max=0.6)
    with pytest.raises(ik.NonFiniteError, match=r"^gyro_density / dt: 1e\+300 with dt = 1e-300 s") as e:
        ik.ImuNoise(1e300, 0.0, 0.0, 0.0).discrete(1e-300)
    assert e.value.argument == "gyro_density / dt"
