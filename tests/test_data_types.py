"""ImuData, ImuBias, ImuNoise, NavState, Trajectory: validation, exact time, noise conversions."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

N = 10


def imu_arrays(n: int = N) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = 100.0 + 0.005 * np.arange(n)
    gyro = np.arange(3 * n, dtype=float).reshape(n, 3) * 0.01
    accel = np.tile([0.0, 0.0, 9.81], (n, 1))
    return t, gyro, accel


# ---------------------------------------------------------------- ImuData: contents and time


def test_float_input_keeps_t_and_gives_relative_seconds() -> None:
    t, gyro, accel = imu_arrays()
    imu = ik.ImuData(t, gyro, accel)
    assert imu.t_ns is None
    np.testing.assert_array_equal(imu.t, t)
    np.testing.assert_array_equal(imu.gyro, gyro)
    np.testing.assert_array_equal(imu.seconds, t - 100.0)
    assert len(imu) == N
    assert imu.rate_hz == pytest.approx(200.0, rel=1e-9)
    assert imu.duration == pytest.approx(0.045, abs=1e-12)
    np.testing.assert_allclose(imu.dt, np.full(N - 1, 0.005), rtol=1e-9)
    for arr in (imu.t, imu.gyro, imu.accel, imu.seconds):
        assert arr.dtype == np.float64 and arr.flags.c_contiguous


def test_integer_nanoseconds_at_a_1e18_epoch_keep_exact_seconds() -> None:
    # Offsets 0, 5_000_192, 10_000_128, 15_000_001 ns from a 1.4e18 ns epoch (EuRoC-like jitter).
    t_ns = np.array(
        [1_400_000_000_000_000_000, 1_400_000_000_005_000_192, 1_400_000_000_010_000_128, 1_400_000_000_015_000_001]
    )
    imu = ik.ImuData(t_ns, np.zeros((4, 3)), np.zeros((4, 3)))
    assert imu.t_ns is not None and imu.t_ns.dtype == np.int64
    np.testing.assert_array_equal(imu.t_ns, t_ns)
    # Each offset / 1e9 rounded once: the float nearest the decimal value.
    np.testing.assert_array_equal(imu.seconds, [0.0, 0.005000192, 0.010000128, 0.015000001])
    np.testing.assert_allclose(imu.dt, [0.005000192, 0.004999936, 0.004999873], rtol=0, atol=1e-17)
    # Absolute float seconds: the nearest float to the decimal value, not float(t_ns) * 1e-9.
    np.testing.assert_array_equal(
        imu.t, [1400000000.0, 1400000000.005000192, 1400000000.010000128, 1400000000.015000001]
    )
    # What the exact path avoids: differencing epoch floats is off by up to ~0.24 µs per step.
    naive = np.diff(t_ns * 1e-9)
    assert np.abs(naive - [0.005000192, 0.004999936, 0.004999873]).max() > 1e-8


def test_unsigned_nanoseconds_are_accepted() -> None:
    t_ns = np.array([1_400_000_000_000_000_000, 1_400_000_000_005_000_000], dtype=np.uint64)
    imu = ik.ImuData(t_ns, np.zeros((2, 3)), np.zeros((2, 3)))
    np.testing.assert_array_equal(imu.seconds, [0.0, 0.005])


def test_single_sample() -> None:
    imu = ik.ImuData([3.0], [[0.1, 0.2, 0.3]], [[0.0, 0.0, 9.81]])
    assert len(imu) == 1 and imu.duration == 0.0 and imu.dt.shape == (0,)
    with pytest.raises(ik.ShapeError, match=r"^rate_hz: a single sample"):
        _ = imu.rate_hz


def test_slicing_returns_imudata() -> None:
    t, gyro, accel = imu_arrays()
    imu = ik.ImuData(t, gyro, accel)
    part = imu[2:5]
    assert isinstance(part, ik.ImuData) and len(part) == 3
    np.testing.assert_array_equal(part.t, t[2:5])
    np.testing.assert_array_equal(part.gyro, gyro[2:5])
    np.testing.assert_array_equal(part.accel, accel[2:5])
    assert part.seconds[0] == 0.0
    every_other = imu[::2]
    np.testing.assert_array_equal(every_other.t, t[::2])
    assert every_other.rate_hz == pytest.approx(100.0, rel=1e-9)


def test_slicing_keeps_nanoseconds() -> None:
    t_ns = 1_400_000_000_000_000_000 + 5_000_000 * np.arange(N)
    imu = ik.ImuData(t_ns, np.zeros((N, 3)), np.zeros((N, 3)))
    part = imu[-3:]
    assert part.t_ns is not None
    np.testing.assert_array_equal(part.t_ns, t_ns[-3:])
    np.testing.assert_array_equal(part.seconds, [0.0, 0.005, 0.01])


@pytest.mark.parametrize(
    ("index", "message"),
    [
        (slice(None, None, -1), r"^index: ImuData slices need a positive step, got slice\(None, None, -1\)$"),
        (slice(5, 2), r"^index: slice\(5, 2, None\) selects no sample of 10 \(it runs from 5 to 2\)"),
        (slice(20, None), r"^index: slice\(20, None, None\) selects no sample of 10 \(it runs from 10 to 10\)"),
        (slice(-3, -5), r"^index: slice\(-3, -5, None\) selects no sample of 10 \(it runs from 7 to 5\)"),
    ],
)
def test_bad_slices(index: slice, message: str) -> None:
    imu = ik.ImuData(*imu_arrays())
    with pytest.raises(ik.ShapeError, match=message):  # an empty slice is not blamed on its (positive) step
        imu[index]


def test_integer_index_is_refused() -> None:
    imu = ik.ImuData(*imu_arrays())
    with pytest.raises(TypeError, match="slices"):
        imu[3]  # type: ignore[index]


def test_imudata_is_immutable_and_owns_its_arrays() -> None:
    t, gyro, accel = imu_arrays()
    imu = ik.ImuData(t, gyro, accel)
    with pytest.raises(ValueError, match="read-only"):
        imu.gyro[0, 0] = 1.0
    for arr in (imu.t, imu.accel, imu.seconds):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 1.0
    with pytest.raises(AttributeError):
        imu.gyro = gyro  # type: ignore[misc]
    gyro[0, 0] = 123.0
    t[0] = -5.0
    assert imu.gyro[0, 0] == 0.0 and imu.t[0] == 100.0


def test_immutable_inputs_are_read_in_place_and_the_rest_copied(tmp_path: Path) -> None:
    """Issue 20 (no avoidable copies): C-contiguous float64 arrays nothing can write (frozen and
    owning their memory, views of read-only ``bytes``, another ImuData's arrays) are kept as they
    are; a read-only view of a writeable array is copied, since its owner can still write it, and so
    are memory maps (the file under a read-only one can be rewritten), strided and other-dtype
    inputs."""
    t, gyro, accel = (a.copy() for a in imu_arrays(1000))  # np.tile's result is a view of a writeable array
    for a in (t, gyro, accel):
        a.flags.writeable = False
    imu = ik.ImuData(t, gyro, accel)
    assert imu.t is t and imu.gyro is gyro and imu.accel is accel
    again = ik.ImuData(imu.t, imu.gyro, imu.accel, mag=imu.accel)
    assert again.gyro is imu.gyro and again.mag is imu.accel
    raw = ik.ImuData(t, np.frombuffer(gyro.tobytes()).reshape(-1, 3), accel)
    assert raw.gyro.base is not None and np.array_equal(raw.gyro, gyro)
    assert not raw.gyro.flags.owndata and not raw.gyro.flags.writeable
    path = tmp_path / "gyro.npy"
    np.save(path, gyro)
    mapped = np.load(path, mmap_mode="r")
    assert not np.shares_memory(ik.ImuData(t, mapped, accel).gyro, mapped)
    # can still be written through its owner: copied, and the ImuData does not see the write
    owner = gyro.copy()
    view = owner[:]
    view.flags.writeable = False
    held = ik.ImuData(t, view, accel)
    owner[0, 0] = 123.0
    assert not np.shares_memory(held.gyro, owner) and held.gyro[0, 0] == gyro[0, 0]
    assert not np.shares_memory(ik.ImuData(t, np.load(path, mmap_mode="c"), accel).gyro, mapped)
    wide = np.zeros((1000, 6))
    wide[:, :3] = gyro
    wide.flags.writeable = False
    assert not np.shares_memory(ik.ImuData(t, wide[:, :3], accel).gyro, wide)  # strided
    f32 = gyro.astype(np.float32)
    f32.flags.writeable = False
    assert ik.ImuData(t, f32, accel).gyro.dtype == np.float64


def test_repr_is_short() -> None:
    text = repr(ik.ImuData(*imu_arrays()))
    assert text == "ImuData(10 samples, 0.045 s, 200 Hz, t in float s)"


# ---------------------------------------------------------------- ImuData: bad input


def test_nan_in_gyro_names_the_sample() -> None:
    t, gyro, accel = imu_arrays()
    gyro[5, 1] = np.nan
    gyro[7, 0] = np.inf
    with pytest.raises(ik.NonFiniteError, match=r"^gyro: non-finite value at sample 5\b"):
        ik.ImuData(t, gyro, accel)


def test_inf_in_accel_and_t_names_the_sample() -> None:
    t, gyro, accel = imu_arrays()
    accel[8, 2] = -np.inf
    with pytest.raises(ik.NonFiniteError, match=r"^accel: non-finite value at sample 8\b"):
        ik.ImuData(t, gyro, accel)
    t[3] = np.nan
    with pytest.raises(ik.NonFiniteError, match=r"^t: non-finite value at sample 3\b"):
        ik.ImuData(t, gyro, accel)


def test_decreasing_time_names_the_sample() -> None:
    t, gyro, accel = imu_arrays()
    t[6] = t[5] - 0.001
    with pytest.raises(
        ik.TimestampError, match=r"^t: time must increase strictly: step into sample 6 has dt = -0\.001"
    ):
        ik.ImuData(t, gyro, accel)


def test_duplicate_time_names_the_sample() -> None:
    t, gyro, accel = imu_arrays()
    t[6] = t[5]
    with pytest.raises(ik.TimestampError, match=r"^t: time must increase strictly: step into sample 6 has dt = 0\.0 s"):
        ik.ImuData(t, gyro, accel)
    t_ns = 1_400_000_000_000_000_000 + 5_000_000 * np.arange(N)
    t_ns[4] = t_ns[3]
    with pytest.raises(ik.TimestampError, match=r"step into sample 4 has dt = 0 ns"):
        ik.ImuData(t_ns, gyro, accel)


@pytest.mark.parametrize(
    ("name", "shape"),
    [("gyro", (N, 4)), ("gyro", (N - 1, 3)), ("gyro", (3, N)), ("accel", (N,)), ("accel", (N, 3, 1))],
)
def test_wrong_shapes(name: str, shape: tuple[int, ...]) -> None:
    t, gyro, accel = imu_arrays()
    args = {"t": t, "gyro": gyro, "accel": accel, name: np.zeros(shape)}
    expected = rf"^{name}: expected shape \(N, 3\) with N = len\(t\) = {N}, got \({', '.join(map(str, shape))},?\)"
    with pytest.raises(ik.ShapeError, match=expected):
        ik.ImuData(**args)


def test_t_must_be_one_dimensional_and_non_empty() -> None:
    with pytest.raises(ik.ShapeError, match=r"^t: expected shape \(N,\) with N ≥ 1, got \(0,\)"):
        ik.ImuData(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))
    with pytest.raises(ik.ShapeError, match=r"^t: expected shape \(N,\)"):
        ik.ImuData(np.zeros((2, 1)), np.zeros((2, 3)), np.zeros((2, 3)))


@pytest.mark.parametrize("bad", [np.array([1j] * N), np.array(["a"] * N), np.ones(N, dtype=bool)])
def test_bad_dtypes(bad: np.ndarray) -> None:
    t, gyro, accel = imu_arrays()
    with pytest.raises(ik.DTypeError, match=r"^t: expected float seconds or integer nanoseconds"):
        ik.ImuData(bad, gyro, accel)
    with pytest.raises(ik.DTypeError, match=r"^accel: expected real numbers"):
        ik.ImuData(t, gyro, np.broadcast_to(bad[:, None], (N, 3)))


def test_integer_steps_under_a_microsecond_are_refused() -> None:
    _, gyro, accel = imu_arrays()
    with pytest.raises(ik.ParameterError, match=r"^t: integer timestamps are read as nanoseconds"):
        ik.ImuData(np.arange(N), gyro, accel)


def test_max_gap() -> None:
    t, gyro, accel = imu_arrays()
    t[7:] += 0.02  # a 25 ms step into sample 7
    assert len(ik.ImuData(t, gyro, accel)) == N  # allowed unless a limit is stated
    assert len(ik.ImuData(t, gyro, accel, max_gap=0.03)) == N
    with pytest.raises(
        ik.TimestampError, match=r"^t: gap into sample 7 has dt = 0\.025 s, larger than max_gap = 0\.01 s"
    ):
        ik.ImuData(t, gyro, accel, max_gap=0.01)
    for bad in (0.0, -1.0, np.nan, [0.01]):
        with pytest.raises(ik.ParameterError, match=r"^max_gap:"):
            ik.ImuData(t, gyro, accel, max_gap=bad)  # type: ignore[arg-type]


def test_max_gap_with_nanoseconds() -> None:
    t_ns = 1_400_000_000_000_000_000 + 5_000_000 * np.arange(N)
    t_ns[3:] += 1  # 5_000_001 ns into sample 3
    with pytest.raises(
        ik.TimestampError, match=r"^t: gap into sample 3 has dt = 5000001 ns, larger than max_gap = 0\.005 s"
    ):
        ik.ImuData(t_ns, np.zeros((N, 3)), np.zeros((N, 3)), max_gap=0.005)


# ---------------------------------------------------------------- ImuBias


def test_bias_defaults_and_values() -> None:
    zero = ik.ImuBias()
    np.testing.assert_array_equal(zero.gyro, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(zero.accel, [0.0, 0.0, 0.0])
    bias = ik.ImuBias(gyro=[0.01, -0.02, 0.03], accel=(1, 2, 3))
    assert bias.accel.dtype == np.float64
    assert bias == ik.ImuBias([0.01, -0.02, 0.03], [1.0, 2.0, 3.0])
    assert bias != zero
    with pytest.raises(ValueError, match="read-only"):
        bias.gyro[0] = 1.0
    with pytest.raises(AttributeError):
        bias.accel = np.zeros(3)  # type: ignore[misc]


def test_bias_validation() -> None:
    with pytest.raises(ik.ShapeError, match=r"^accel: expected shape \(3,\), got \(4,\)"):
        ik.ImuBias(accel=[1, 2, 3, 4])
    with pytest.raises(ik.NonFiniteError, match=r"^gyro: non-finite value at element 0"):
        ik.ImuBias(gyro=[np.nan, 0, 0])


# ---------------------------------------------------------------- ImuNoise

EUROC = {
    "gyroscope_noise_density": 1.6968e-04,
    "accelerometer_noise_density": 2.0000e-3,
    "gyroscope_random_walk": 1.9393e-05,
    "accelerometer_random_walk": 3.0000e-3,
}


def test_kalibr_names_map_without_conversion() -> None:
    noise = ik.ImuNoise.from_kalibr(**EUROC)
    assert noise == ik.ImuNoise(
        gyro_density=1.6968e-04, accel_density=2.0e-3, gyro_random_walk=1.9393e-05, accel_random_walk=3.0e-3
    )


def test_euroc_per_sample_sigmas_at_200_hz() -> None:
    # √200 = 14.142135623730951; white σ_d = σ_c √200, walk step σ = σ_w / √200.
    s = ik.ImuNoise.from_kalibr(**EUROC).to_discrete_sigmas(200.0)
    assert s.gyro_sigma == pytest.approx(2.3996375726e-03, rel=1e-10)
    assert s.accel_sigma == pytest.approx(2.8284271247e-02, rel=1e-10)
    assert s.gyro_walk_sigma == pytest.approx(1.3712921808e-06, rel=1e-10)
    assert s.accel_walk_sigma == pytest.approx(2.1213203436e-04, rel=1e-10)
    # and to the 5 digits of docs/conventions.md, row 11
    assert s == pytest.approx((2.3996e-03, 2.8284e-02, 1.3713e-06, 2.1213e-04), rel=5e-5)


def test_discrete_variances_by_hand() -> None:
    noise = ik.ImuNoise(0.01, 0.1, 0.001, 0.02)
    d = noise.discrete(0.01)
    assert d.gyro_var == pytest.approx(1e-4 / 0.01, rel=1e-15)  # 0.01
    assert d.accel_var == pytest.approx(1.0, rel=1e-15)  # 0.1² / 0.01
    assert d.gyro_bias_var == pytest.approx(1e-8, rel=1e-15)  # 0.001² · 0.01
    assert d.accel_bias_var == pytest.approx(4e-6, rel=1e-15)  # 0.02² · 0.01


def test_discrete_uses_the_actual_step() -> None:
    noise = ik.ImuNoise.from_kalibr(**EUROC)
    at_5ms = noise.discrete(0.005)
    assert math.sqrt(at_5ms.gyro_var) == pytest.approx(2.3996375726e-03, rel=1e-10)
    at_10ms = noise.discrete(0.010)  # a dropped sample: σ = 1.6968e-04 / √0.01, walk step 1.9393e-05 · 0.1
    assert math.sqrt(at_10ms.gyro_var) == pytest.approx(1.6968e-03, rel=1e-12)
    assert math.sqrt(at_10ms.gyro_bias_var) == pytest.approx(1.9393e-06, rel=1e-12)


def test_from_discrete_inverts_to_discrete_sigmas() -> None:
    noise = ik.ImuNoise(gyro_density=1.7e-4, accel_density=2e-3, gyro_random_walk=1.9e-5, accel_random_walk=3e-3)
    for rate in (100.0, 200.0, 400.0, 1234.5):
        back = ik.ImuNoise.from_discrete(**noise.to_discrete_sigmas(rate)._asdict(), rate_hz=rate)
        for field in dataclasses.fields(ik.ImuNoise):
            assert getattr(back, field.name) == pytest.approx(getattr(noise, field.name), rel=1e-15)


def test_from_discrete_by_hand() -> None:
    # rate 100 Hz: σ_c = σ_d / 10, σ_w = σ_step · 10
    noise = ik.ImuNoise.from_discrete(
        gyro_sigma=0.004, accel_sigma=0.08, gyro_walk_sigma=2e-6, accel_walk_sigma=4e-5, rate_hz=100.0
    )
    assert noise.gyro_density == pytest.approx(4e-4, rel=1e-15)
    assert noise.accel_density == pytest.approx(8e-3, rel=1e-15)
    assert noise.gyro_random_walk == pytest.approx(2e-5, rel=1e-15)
    assert noise.accel_random_walk == pytest.approx(4e-4, rel=1e-15)


def test_noise_validation() -> None:
    with pytest.raises(ik.ParameterError, match=r"^gyro_density: expected a finite, non-negative number"):
        ik.ImuNoise(-1.0, 0.0, 0.0, 0.0)
    with pytest.raises(ik.ParameterError, match=r"^accel_random_walk:"):
        ik.ImuNoise(0.0, 0.0, 0.0, np.nan)
    with pytest.raises(ik.ParameterError, match=r"^rate_hz:"):
        ik.ImuNoise.from_discrete(gyro_sigma=1, accel_sigma=1, gyro_walk_sigma=1, accel_walk_sigma=1, rate_hz=0)
    with pytest.raises(ik.ParameterError, match=r"^accel_sigma:"):
        ik.ImuNoise.from_discrete(gyro_sigma=1, accel_sigma=-1, gyro_walk_sigma=1, accel_walk_sigma=1, rate_hz=1)
    noise = ik.ImuNoise(1.0, 1.0, 1.0, 1.0)
    for bad in (0.0, -0.005, np.inf, None):
        with pytest.raises(ik.ParameterError, match=r"^dt: expected a positive, finite step"):
            noise.discrete(bad)  # type: ignore[arg-type]
    with pytest.raises(dataclasses.FrozenInstanceError):
        noise.gyro_density = 2.0  # type: ignore[misc]


# ---------------------------------------------------------------- NavState, Trajectory


def test_navstate() -> None:
    r = Rotation.from_rotvec([0.1, 0.2, 0.3])
    s = ik.NavState([1, 2, 3], np.array([0.5, 0.0, -0.5]), r)
    assert s.position.dtype == np.float64
    np.testing.assert_array_equal(s.velocity, [0.5, 0.0, -0.5])
    assert s.rotation is r
    with pytest.raises(ValueError, match="read-only"):
        s.position[0] = 0.0
    with pytest.raises(AttributeError):
        s.rotation = r  # type: ignore[misc]
    with pytest.raises(ik.ShapeError, match=r"^velocity: expected shape \(3,\), got \(2,\)"):
        ik.NavState([1, 2, 3], [0, 0], r)
    with pytest.raises(ik.NonFiniteError, match=r"^position: non-finite value at element 2"):
        ik.NavState([1, 2, np.nan], [0, 0, 0], r)
    with pytest.raises(ik.ParameterError, match=r"^rotation: expected a single scipy Rotation"):
        ik.NavState([1, 2, 3], [0, 0, 0], Rotation.identity(2))
    with pytest.raises(ik.ParameterError, match=r"^rotation: expected a single scipy Rotation"):
        ik.NavState([1, 2, 3], [0, 0, 0], np.eye(3))  # type: ignore[arg-type]


def make_trajectory(n: int = 5, **kwargs: object) -> ik.Trajectory:
    t = 0.1 * np.arange(n)
    pos = np.arange(3 * n, dtype=float).reshape(n, 3)
    return ik.Trajectory(t, pos, -pos, Rotation.from_rotvec(0.01 * pos), **kwargs)  # type: ignore[arg-type]


def test_trajectory_state() -> None:
    traj = make_trajectory()
    assert len(traj) == 5 and traj.t_ns is None and traj.covariance is None
    s = traj.state(-1)
    np.testing.assert_array_equal(s.position, [12.0, 13.0, 14.0])
    np.testing.assert_array_equal(s.velocity, [-12.0, -13.0, -14.0])
    np.testing.assert_allclose(s.rotation.as_rotvec(), [0.12, 0.13, 0.14], atol=1e-15)
    with pytest.raises(IndexError):
        traj.state(5)
    no_velocity = ik.Trajectory(traj.t, traj.position, None, traj.rotation)
    with pytest.raises(ik.ParameterError, match="no velocity"):
        no_velocity.state(0)


def test_trajectory_with_covariance() -> None:
    cov = np.broadcast_to(np.eye(15), (2, 15, 15))
    traj = make_trajectory(covariance=cov, covariance_t=[0.0, 0.4])
    assert traj.covariance is not None and traj.covariance.shape == (2, 15, 15)
    with pytest.raises(ValueError, match="read-only"):
        traj.covariance[0, 0, 0] = 2.0
    with pytest.raises(ik.ParameterError, match=r"^covariance: give covariance and covariance_t together"):
        make_trajectory(covariance=cov)
    with pytest.raises(
        ik.ShapeError, match=r"^covariance: expected shape \(M, 15, 15\) with M = len\(covariance_t\) = 3"
    ):
        make_trajectory(covariance=cov, covariance_t=[0.0, 0.1, 0.2])
    with pytest.raises(ik.TimestampError, match=r"^covariance_t: time must increase strictly: step into sample 1"):
        make_trajectory(covariance=cov, covariance_t=[0.4, 0.0])


def test_trajectory_validation() -> None:
    traj = make_trajectory()
    t, pos, rot = traj.t, traj.position, traj.rotation
    with pytest.raises(ik.ShapeError, match=r"^position: expected shape \(N, 3\) with N = len\(t\) = 5, got \(4, 3\)"):
        ik.Trajectory(t, pos[:4], None, rot)
    with pytest.raises(
        ik.ShapeError,
        match=r"^rotation: expected a scipy Rotation of length N = len\(t\) = 5, got a Rotation of length 4",
    ):
        ik.Trajectory(t, pos, None, rot[:4])
    with pytest.raises(ik.ShapeError, match=r"^rotation: .*got a single Rotation"):
        ik.Trajectory(t, pos, None, rot[0])
    with pytest.raises(ik.DTypeError, match=r"^t: expected float seconds, got an array of dtype int64; pass integer"):
        ik.Trajectory(np.arange(5), pos, None, rot)
    with pytest.raises(ik.TimestampError, match=r"^t: time must increase strictly: step into sample 3"):
        ik.Trajectory(t[[0, 1, 2, 2, 4]], pos, None, rot)
    with pytest.raises(ik.NonFiniteError, match=r"^velocity: non-finite value at sample 2"):
        ik.Trajectory(t, pos, np.where(np.arange(15).reshape(5, 3) == 7, np.nan, pos), rot)


def test_trajectory_nanoseconds() -> None:
    t_ns = 1_400_000_000_000_000_000 + 5_000_192 * np.arange(3)
    pos, rot = np.zeros((3, 3)), Rotation.identity(3)
    traj = ik.Trajectory(None, pos, None, rot, t_ns=t_ns)
    np.testing.assert_array_equal(traj.t, [1400000000.0, 1400000000.005000192, 1400000000.010000384])
    assert ik.Trajectory(traj.t, pos, None, rot, t_ns=t_ns).t_ns is not None
    with pytest.raises(ik.TimestampError, match=r"^t_ns: sample 0 is 1400000000000000000 ns but t\[0\] = 0\.0 s"):
        ik.Trajectory(np.array([0.0, 0.005000192, 0.010000384]), pos, None, rot, t_ns=t_ns)
    with pytest.raises(ik.ParameterError, match=r"^t: .*only when t_ns is given"):
        ik.Trajectory(None, pos, None, rot)
    with pytest.raises(ik.DTypeError, match=r"^t_ns: expected integer nanoseconds"):
        ik.Trajectory(None, pos, None, rot, t_ns=t_ns * 1.0)


def test_trajectory_carries_optional_bias_histories() -> None:
    t = np.array([0.0, 0.1, 0.2])
    rot = Rotation.identity(3)
    plain = ik.Trajectory(t, np.zeros((3, 3)), None, rot)
    assert plain.gyro_bias is None and plain.accel_bias is None
    bg, ba = np.full((3, 3), 1e-3), np.full((3, 3), 0.05)
    traj = ik.Trajectory(t, np.zeros((3, 3)), None, rot, gyro_bias=bg, accel_bias=ba)
    assert traj.gyro_bias is not None and traj.accel_bias is not None
    assert np.array_equal(traj.gyro_bias, bg) and np.array_equal(traj.accel_bias, ba)
    assert not traj.gyro_bias.flags.writeable
    assert "gyro_bias" in repr(traj)
    with pytest.raises(ik.ParameterError, match="gyro_bias: give gyro_bias and accel_bias together"):
        ik.Trajectory(t, np.zeros((3, 3)), None, rot, gyro_bias=bg)
    with pytest.raises(ik.ShapeError, match=r"accel_bias: expected shape \(N, 3\) with N = len\(t\) = 3"):
        ik.Trajectory(t, np.zeros((3, 3)), None, rot, gyro_bias=bg, accel_bias=np.zeros((2, 3)))


def test_trajectory_write_tum_is_a_deprecated_alias_of_io_write_tum(tmp_path: Path) -> None:
    traj = make_trajectory()
    with pytest.warns(DeprecationWarning, match=r"use imukit\.io\.write_tum\(trajectory, path\)"):
        traj.write_tum(tmp_path / "alias.txt")
    ik.io.write_tum(traj, tmp_path / "io.txt")
    assert (tmp_path / "alias.txt").read_text() == (tmp_path / "io.txt").read_text()


def test_trajectory_takes_integer_nanoseconds_as_t_like_imudata() -> None:
    t_ns = 1_400_000_000_000_000_000 + 5_000_192 * np.arange(3)
    pos, rot = np.arange(9.0).reshape(3, 3), Rotation.identity(3)
    by_dtype = ik.Trajectory(t_ns, pos, None, rot)
    by_keyword = ik.Trajectory(None, pos, None, rot, t_ns=t_ns)
    assert by_dtype.t_ns is not None and by_dtype.t_ns.dtype == np.int64
    assert np.array_equal(by_dtype.t_ns, t_ns) and np.array_equal(by_dtype.t, by_keyword.t)
    imu = ik.ImuData(t_ns, np.zeros((3, 3)), np.zeros((3, 3)))
    assert np.array_equal(by_dtype.t, imu.t)
    with pytest.raises(ik.ParameterError, match=r"^t_ns: integer timestamps are read as nanoseconds"):
        ik.Trajectory(None, pos, None, rot, t_ns=np.arange(3))


def test_the_nanosecond_rule_is_one_constant() -> None:
    from imukit._arrays import MIN_NS_STEP

    step = np.arange(4) * MIN_NS_STEP
    with pytest.warns(UserWarning, match=r"^t: integer stamps are nanoseconds, but their median step is 1000 ns"):
        assert ik.ImuData(step, np.zeros((4, 3)), np.zeros((4, 3))).t_ns is not None
    assert ik.Trajectory(step, np.zeros((4, 3)), None, Rotation.identity(4)).t_ns is not None
    assert len(ik.integrate_attitude(step, np.zeros((4, 3)))) == 4
    finer = np.arange(4) * (MIN_NS_STEP - 1)
    with pytest.raises(ik.ParameterError, match=r"^t: integer timestamps are read as nanoseconds"):
        ik.ImuData(finer, np.zeros((4, 3)), np.zeros((4, 3)))
    with pytest.raises(ik.ParameterError, match=r"^t: integer timestamps are read as nanoseconds"):
        ik.integrate_attitude(finer, np.zeros((4, 3)))
    with pytest.raises(ik.DTypeError, match=r"^t: expected float seconds, got an array of dtype int64"):
        ik.Trajectory(finer, np.zeros((4, 3)), None, Rotation.identity(4))
