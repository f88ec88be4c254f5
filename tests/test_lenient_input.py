"""Foreign exceptions for bad arguments and lenient parsing, settled (issue 17, items 13 and 16).

- Ragged nested lists raised numpy's ``ValueError``: a :class:`ShapeError` naming the argument.
- Masked arrays: ``np.asarray`` used the values under the mask; a masked value is a
  :class:`DTypeError` (an array without masked values is its data).
- ``sim.Waypoints`` whose positive steps overflow the splines (1e-300 s next to 2 s) raised scipy's
  ``ValueError``: a :class:`ParameterError` naming ``times``.
- Bools are not numbers: ``dt=True``, ``Trajectory.state(True)`` (its check came after
  ``operator.index`` had turned True into 1) and ``standard_gravity=True`` are refused, and so is a
  numeric string, ``standard_gravity="9.8"``, as every numeric option refuses one.
- ``Mahony(kp=True)`` / ``Madgwick(beta=True)`` (and ``gravity=True``, a bool in a ``gain_ramp``
  tuple) were gains of 1: refused as every numeric option refuses a bool.
- Readers read numbers as data files write them (ASCII, no ``_``): ``1_000``, ``١`` and a no-break
  space around a number, which ``float()`` reads, make their line ``malformed``.
- Float boundaries taken from an int64-ns recording's ``imu.t`` (epoch seconds, 0.24 µs apart)
  refused the last sample and gave 0.10000014 s windows; a boundary equal to a sample's time is that
  sample now, so they equal the integer-ns boundaries exactly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)


@pytest.mark.parametrize(
    ("call", "argument"),
    [
        (lambda: ik.so3.exp([[1.0, 2.0, 3.0], [1.0, 2.0]]), "phi"),
        (lambda: ik.quat.multiply([[0, 0, 0, 1.0], [0, 0, 1.0]], [0, 0, 0, 1.0]), "q"),
        (lambda: ik.ImuData([0.0, 1.0], [[1, 2, 3], [1, 2]], np.zeros((2, 3))), "gyro"),
        (lambda: ik.ImuData([[0.0], [1.0, 2.0]], np.zeros((2, 3)), np.zeros((2, 3))), "t"),
    ],
)
def test_ragged_lists_are_a_shape_error_naming_the_argument(call, argument: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ik.ShapeError, match="rectangular") as info:
        call()
    assert info.value.argument == argument


def test_masked_values_are_refused_unmasked_arrays_are_data() -> None:
    phi = np.ma.masked_array([[0.1, 0.2, 0.3]], mask=[[0, 1, 0]])
    with pytest.raises(ik.DTypeError, match="phi: expected plain numbers, got a masked array with 1 masked"):
        ik.so3.exp(phi)
    clean = np.ma.masked_array([[0.1, 0.2, 0.3]], mask=False)
    assert np.array_equal(ik.so3.exp(clean), ik.so3.exp(np.array([[0.1, 0.2, 0.3]])))
    t = np.ma.masked_array([0.0, 0.005, 0.01], mask=[0, 0, 1])
    with pytest.raises(ik.DTypeError, match="masked") as info:
        ik.ImuData(t, np.zeros((3, 3)), np.zeros((3, 3)))
    assert info.value.argument == "t"


@pytest.mark.parametrize("times", [[0.0, 1e-300, 2.0], [0.0, 1e-200, 2.0], [0.0, 1e300, 2e300]])
def test_waypoints_whose_splines_overflow_name_times(times: list[float]) -> None:
    positions = [[0.0, 0, 0], [1, 0, 0], [2, 0, 0]]
    rotations = Rotation.from_rotvec([[0.0, 0, 0], [0, 0, 0.5], [0, 0.2, 1]])
    with pytest.raises(ik.ParameterError, match="cannot be fitted by a spline") as info:
        ik.sim.Waypoints(times, positions, rotations)
    assert info.value.argument == "times"
    ik.sim.Waypoints([0.0, 1.0, 2.0], positions, rotations)  # an ordinary spacing fits


@pytest.mark.parametrize(
    ("times", "options", "error", "argument", "message"),
    [
        ([0, 10**9, 2 * 10**9], {}, ik.DTypeError, "times", "integer times are nanoseconds elsewhere"),
        ([0.0, 1.0, 2.0], {"bc_type": "foo"}, ik.ParameterError, "bc_type", "expected one of"),
        ([0.0, 1.0, 2.0], {"bc_type": 3}, ik.ParameterError, "bc_type", "expected one of"),
        ([0.0, 1.0, 2.0], {"bc_type": "periodic"}, ik.ParameterError, "bc_type", "'periodic' needs the last position"),
    ],
)
def test_waypoints_name_the_argument_at_fault(
    times: list[float], options: dict[str, object], error: type[Exception], argument: str, message: str
) -> None:
    """Integer times were taken as seconds (3e9 s of spline for 3 s of nanoseconds), and a bad
    ``bc_type`` was reported as ``times`` whose spline overflows (before 2026-12-07)."""
    positions = [[0.0, 0, 0], [1, 0, 0], [2, 0, 0]]
    rotations = Rotation.from_rotvec([[0.0, 0, 0], [0, 0, 0.5], [0, 0.2, 1]])
    with pytest.raises(error, match=message) as info:
        ik.sim.Waypoints(times, positions, rotations, **options)  # type: ignore[arg-type]
    assert getattr(info.value, "argument", None) == argument
    closed = [[0.0, 0, 0], [1, 0, 0], [0, 0, 0]]
    ik.sim.Waypoints([0.0, 1.0, 2.0], closed, rotations, bc_type="periodic")  # a closed path is periodic


def test_bools_are_not_numbers() -> None:
    pim = ik.PreintegratedImu(noise=NOISE)
    with pytest.raises(ik.ParameterError, match="dt: expected a step in seconds, got True"):
        pim.integrate_measurement([0.0, 0, 9.81], [0.0, 0, 0], True)
    traj = ik.integrate(
        ik.ImuData(np.arange(3) * 0.01, np.zeros((3, 3)), np.tile([0.0, 0, 9.81], (3, 1))),
        initial=ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity()),
    )
    for k in (True, np.bool_(False)):
        with pytest.raises(ik.ParameterError, match="k: expected an integer sample index"):
            traj.state(k)  # type: ignore[arg-type]
    assert np.array_equal(traj.state(1).position, traj.position[1])


@pytest.mark.parametrize(
    ("make", "argument"),
    [
        (lambda: ik.filters.Mahony(kp=True), "kp"),
        (lambda: ik.filters.Mahony(ki=np.bool_(True)), "ki"),
        (lambda: ik.filters.Mahony(kp="0.3"), "kp"),
        (lambda: ik.filters.Madgwick(beta=True), "beta"),
        (lambda: ik.filters.Madgwick(gravity=True), "gravity"),
        (lambda: ik.filters.Mahony(gain_ramp=(True, 10.0)), "gain_ramp"),
        # the core's value classes themselves, built directly
        (lambda: ik.filters.GainRamp(True, 10.0), "gain_ramp.duration_s"),
        (lambda: ik.filters.AccelRejection(np.bool_(True)), "acc_rejection.norm"),
        (lambda: ik._core.RobustParams(tau_acc_s=True), "tau_acc_s"),
    ],
)
def test_filter_gains_refuse_bools(make, argument: str) -> None:  # type: ignore[no-untyped-def]
    """``Mahony(kp=True)`` was a gain of 1 (PyO3 reads a bool as a float)."""
    with pytest.raises(ik.ParameterError, match="expected a real number") as info:
        make()
    assert info.value.argument == argument
    assert ik.filters.Mahony(kp=np.float64(0.5), ki=1).kp == 0.5  # numpy and int numbers are numbers


@pytest.mark.parametrize("euroc", [True, False])
def test_numbers_python_alone_reads_are_malformed(tmp_path: Path, euroc: bool) -> None:
    """``float()`` reads ``1_000``, Unicode digits and a no-break space around a number; the readers do
    not (no logger writes them: a damaged field), on the fast path and the Python path alike."""
    path = tmp_path / "data.csv"
    rows = ["1_000", "\u0661", "\u00a00.5", "0.5"]
    lines = [f"{1_000_000_000 + 5_000_000 * k},{v},0,0,0,0,9.81" for k, v in enumerate(rows)]
    path.write_text("#timestamp [ns],wx,wy,wz,ax,ay,az\n" + "\n".join(lines) + "\n", encoding="utf-8")
    report = ik.io.ReadReport()
    if euroc:
        imu = ik.io.read_euroc_imu(path, on_bad_line="skip", report=report)
    else:
        columns = {"gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}
        imu = ik.io.read_imu_csv(path, time_column=0, time_unit="ns", on_bad_line="skip", report=report, **columns)  # type: ignore[arg-type]
    assert [(r.line, r.kind) for r in report.skipped] == [(2, "malformed"), (3, "malformed"), (4, "malformed")]
    assert imu.gyro[:, 0].tolist() == [0.5]


@pytest.mark.parametrize("gravity", ["9.8", True, b"9.8"])
def test_standard_gravity_refuses_strings_and_bools(tmp_path: Path, gravity: object) -> None:
    path = tmp_path / "imu.csv"
    path.write_text("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,1\n0.01,0,0,0,0,0,1\n")
    columns = {"time_column": "t", "gyro_columns": ["gx", "gy", "gz"], "accel_columns": ["ax", "ay", "az"]}
    with pytest.raises(ik.ParameterError) as info:
        ik.io.read_imu_csv(path, **columns, accel_unit="g", standard_gravity=gravity)  # type: ignore[arg-type]
    assert info.value.argument == "standard_gravity"
    imu = ik.io.read_imu_csv(path, **columns, accel_unit="g", standard_gravity=9.8)  # type: ignore[arg-type]
    assert imu.accel[0, 2] == 9.8


def test_float_boundaries_from_ns_stamps_equal_the_ns_boundaries() -> None:
    n = 2001
    ns = 1_400_000_000_000_000_000 + np.arange(n, dtype=np.int64) * 5_000_000
    imu = ik.ImuData(ns, np.tile([0.1, -0.2, 0.3], (n, 1)), np.tile([0.0, 0, 9.81], (n, 1)))
    params = ik.PreintParams(NOISE)
    from_floats = ik.preintegrate_windows(imu, imu.t[::20], params)  # the last boundary is the last sample
    from_ns = ik.preintegrate_windows(imu, imu.t_ns[::20], params)
    assert np.allclose(from_floats.delta_t, 0.1, rtol=0, atol=1e-13)  # was 0.10000014
    for name in ("delta_t", "delta_rotation", "delta_velocity", "delta_position", "covariance"):
        assert np.array_equal(getattr(from_floats, name), getattr(from_ns, name)), name
    assert np.array_equal(from_floats.t_start_ns, from_ns.t_start_ns)
