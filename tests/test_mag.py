"""The magnetometer in the data model: ``ImuData.mag`` through slicing, the CSV and EuRoC-layout round
trip, ROS bags' ``sensor_msgs/MagneticField``, BROAD, the CLI and the filters' 9D default."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit.cli import main
from imukit.io import read_euroc, read_imu_csv, write_euroc

# Earth's field in ENU at mid latitude [µT]: north +y, dipping down (−z): dip 63.4°.
FIELD_ENU = np.array([0.0, 20.0, -40.0])
START = Rotation.from_euler("ZYX", [60.0, 5.0, -3.0], degrees=True)  # yaw 60°: a 6D start at yaw 0 is off by it


def _moving(rate: float = 100.0, duration: float = 20.0) -> tuple[ik.ImuData, ik.Trajectory, np.ndarray]:
    """A body turning in place (exact readings, no linear acceleration to mislead the tilt) and the
    field it reads, ``R_wbᵀ m_w`` [µT]."""
    motion = ik.sim.ConstantTwist(body_velocity=(0.0, 0.0, 0.0), body_rate=(0.05, -0.03, 0.3), rotation=START)
    imu, truth = ik.sim.simulate(motion, rate=rate, duration=duration)
    return imu, truth, truth.rotation.inv().apply(FIELD_ENU)


def test_mag_is_validated_sliced_and_shown() -> None:
    imu, _, mag = _moving(duration=1.0)
    with_mag = ik.ImuData(imu.t, imu.gyro, imu.accel, mag=mag)
    assert with_mag.mag is not None and not with_mag.mag.flags.writeable
    assert np.array_equal(with_mag.mag, mag) and not np.shares_memory(with_mag.mag, mag)
    part = with_mag[10:20:2]
    assert part.mag is not None and np.array_equal(part.mag, mag[10:20:2])
    assert imu[3:5].mag is None and "with mag" in repr(with_mag) and "mag" not in repr(imu)
    # Equality is by value, the magnetometer included.
    assert with_mag == ik.ImuData(imu.t, imu.gyro, imu.accel, mag=mag.copy()) and with_mag != imu
    other = mag.copy()
    other[3, 2] += 1e-9
    assert with_mag != ik.ImuData(imu.t, imu.gyro, imu.accel, mag=other)
    assert with_mag[10:20:2] == with_mag[10:20][::2]
    with pytest.raises(ik.ShapeError, match=r"mag: expected shape \(N, 3\) with N = len\(t\) = 101"):
        ik.ImuData(imu.t, imu.gyro, imu.accel, mag=mag[:-1])
    bad = mag.copy()
    bad[7, 1] = np.nan
    with pytest.raises(ik.NonFiniteError, match="mag") as info:
        ik.ImuData(imu.t, imu.gyro, imu.accel, mag=bad)
    assert info.value.argument == "mag"


def test_csv_to_euroc_folder_and_back_bit_for_bit(tmp_path: Path, rng: np.random.Generator) -> None:
    n = 50
    t_ns = 1_403_715_523_000_000_000 + np.arange(n) * 5_000_000
    gyro, accel, mag = rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), 40.0 * rng.normal(size=(n, 3))
    lines = ["time,mx,my,mz,gx,gy,gz,ax,ay,az,temp"]
    lines += [
        ",".join([str(t), *map(repr, [*m, *g, *a]), "21.5"])
        for t, g, a, m in zip(t_ns.tolist(), gyro.tolist(), accel.tolist(), mag.tolist())
    ]
    csv = tmp_path / "log.csv"
    csv.write_text("\n".join(lines) + "\n")

    imu = read_imu_csv(
        csv,
        time_column="time",
        gyro_columns=["gx", "gy", "gz"],
        accel_columns=[7, 8, 9],
        mag_columns=["mx", "my", "mz"],
        time_unit="ns",
    )
    assert imu.mag is not None and imu.mag.tobytes() == mag.tobytes()
    write_euroc(tmp_path / "mav0", imu)
    written = (tmp_path / "mav0" / "mag0" / "data.csv").read_text().splitlines()
    assert written[0] == "#timestamp [ns],m_S_x [uT],m_S_y [uT],m_S_z [uT]"
    assert written[1].split(",")[0] == str(t_ns[0])
    back, truth = read_euroc(tmp_path)
    assert truth is None and back.t_ns is not None and back.t_ns.tolist() == t_ns.tolist()
    for name in ("gyro", "accel", "mag"):
        assert getattr(back, name).tobytes() == getattr(imu, name).tobytes(), name
    # Without mag_columns the same file reads as before, and the EuRoC folder without mag0/ too.
    assert read_imu_csv(csv, time_column=0, gyro_columns=[4, 5, 6], accel_columns=[7, 8, 9]).mag is None
    write_euroc(tmp_path / "plain", ik.ImuData(back.t_ns[:10], back.gyro[:10], back.accel[:10]))
    assert read_euroc(tmp_path / "plain")[0].mag is None


def test_euroc_mag_file_not_covering_the_imu_is_refused(tmp_path: Path) -> None:
    imu, _, mag = _moving(duration=0.5)
    t_ns = np.rint(imu.t * 1e9).astype(np.int64) + 10**18
    write_euroc(tmp_path, ik.ImuData(t_ns[:-5], imu.gyro[:-5], imu.accel[:-5], mag=mag[:-5]))
    write_euroc(tmp_path / "more", ik.ImuData(t_ns, imu.gyro, imu.accel))
    (tmp_path / "more" / "mag0").mkdir()
    (tmp_path / "more" / "mag0" / "data.csv").write_text((tmp_path / "mag0" / "data.csv").read_text())
    with pytest.raises(ik.FileFormatError, match=r"IMU sample 46 .* outside the magnetometer's span .* 4 more of 51"):
        read_euroc(tmp_path / "more")


def test_broad_trial_sets_imu_mag() -> None:
    from imukit._demo import broad_excerpt_path
    from imukit.cli._attitude_input import read_broad

    data = read_broad(broad_excerpt_path())
    with np.load(broad_excerpt_path()) as npz:
        expected = npz["imu_mag"]
    assert data.imu.mag is not None and np.array_equal(data.imu.mag, expected)
    assert data.mag is data.imu.mag


def _heading_error_deg(estimate: Rotation, truth: Rotation) -> np.ndarray:
    error = ik.eval.attitude_error(estimate, truth)
    return np.degrees(np.abs(error.heading))


@pytest.mark.parametrize("method", ["Mahony", "Madgwick"])
def test_filters_use_imu_mag_by_default(method: str) -> None:
    imu, truth, mag = _moving()
    nine = ik.ImuData(imu.t, imu.gyro, imu.accel, mag=mag)
    cls = getattr(ik.filters, method)
    default = cls().run(nine)
    explicit = cls().run(imu, mag=mag)
    assert default.rotation.as_quat().tobytes() == explicit.rotation.as_quat().tobytes()
    assert cls().run(nine, mag=True).rotation.as_quat().tobytes() == explicit.rotation.as_quat().tobytes()
    six = cls().run(nine, mag=False)
    assert six.rotation.as_quat().tobytes() == cls().run(imu).rotation.as_quat().tobytes()
    # The 9D heading is right from the first sample; 6D starts at yaw 0, 60° off.
    assert _heading_error_deg(default.rotation, truth.rotation).max() < 0.5
    assert _heading_error_deg(six.rotation[:1], truth.rotation[:1])[0] == pytest.approx(60.0, abs=0.5)
    with pytest.raises(ik.ParameterError, match="mag=True, but imu has no magnetometer"):
        cls().run(imu, mag=True)


rosbags = pytest.importorskip("rosbags", reason="rosbags is the optional [ros] extra")
from rosbags.rosbag2 import StoragePlugin  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

STORE = get_typestore(Stores.ROS2_HUMBLE)
EPOCH_NS = 1_700_000_000 * 10**9


def _msg(name: str, **fields: object) -> object:
    return STORE.types[name](**fields)


def _header(ns: int) -> object:
    sec, nanosec = divmod(int(ns), 10**9)
    stamp = _msg("builtin_interfaces/msg/Time", sec=sec, nanosec=nanosec)
    return _msg("std_msgs/msg/Header", stamp=stamp, frame_id="imu")


def _vec(v: np.ndarray) -> object:
    return _msg("geometry_msgs/msg/Vector3", x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _write_bag(path: Path, imu: ik.ImuData, mag_ns: np.ndarray, mag_tesla: np.ndarray) -> Path:
    """A ROS 2 MCAP bag with /imu (sensor_msgs/Imu) and /imu/mag (sensor_msgs/MagneticField)."""
    imu_ns = EPOCH_NS + np.rint(imu.t * 1e9).astype(np.int64)
    zeros = np.zeros(9)
    with Writer2(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        c_imu = writer.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=STORE)
        c_mag = writer.add_connection("/imu/mag", "sensor_msgs/msg/MagneticField", typestore=STORE)
        for ns, w, a in zip(imu_ns, imu.gyro, imu.accel):
            msg = _msg(
                "sensor_msgs/msg/Imu",
                header=_header(ns),
                orientation=_msg("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=zeros,
                angular_velocity=_vec(w),
                angular_velocity_covariance=zeros,
                linear_acceleration=_vec(a),
                linear_acceleration_covariance=zeros,
            )
            writer.write(c_imu, int(ns), STORE.serialize_cdr(msg, "sensor_msgs/msg/Imu"))
        for ns, m in zip(mag_ns, mag_tesla):
            field = {"magnetic_field": _vec(m), "magnetic_field_covariance": zeros}
            msg = _msg("sensor_msgs/msg/MagneticField", header=_header(ns), **field)
            writer.write(c_mag, int(ns), STORE.serialize_cdr(msg, "sensor_msgs/msg/MagneticField"))
    return path


def test_mcap_bag_with_magnetic_field_runs_9d_with_the_right_heading(tmp_path: Path) -> None:
    imu, truth, mag = _moving()
    imu_ns = EPOCH_NS + np.rint(imu.t * 1e9).astype(np.int64)
    bag = _write_bag(tmp_path / "bag", imu, imu_ns, mag * 1e-6)  # the message is in tesla

    read, _ = ik.io.read_rosbag(bag)
    assert read.mag is not None
    np.testing.assert_allclose(read.mag, mag, rtol=1e-15, atol=0)  # back in µT
    result = ik.filters.Madgwick().run(read)  # 9D: imu.mag is used
    assert _heading_error_deg(result.rotation, truth.rotation).max() < 0.5
    assert ik.io.read_rosbag(bag, mag_topic=False)[0].mag is None
    # read_imu detects the bag and gets the magnetometer too.
    assert ik.io.read_imu(bag)[0].mag is not None


def test_bag_magnetometer_at_another_rate_is_interpolated_and_never_extrapolated(tmp_path: Path) -> None:
    imu, _, _ = _moving(rate=100.0, duration=1.0)
    imu_ns = EPOCH_NS + np.rint(imu.t * 1e9).astype(np.int64)
    # A 40 Hz magnetometer whose stamps fall between the IMU's, spanning them.
    mag_ns = np.arange(imu_ns[0] - 3_000_000, imu_ns[-1] + 25_000_000, 25_000_000)
    field = np.stack([np.arange(len(mag_ns)), 2.0 * np.arange(len(mag_ns)), np.full(len(mag_ns), -4.0)], axis=-1)
    bag = _write_bag(tmp_path / "bag", imu, mag_ns, field * 1e-6)

    read, _ = ik.io.read_rosbag(bag)
    # A linear field in time is reproduced exactly by linear interpolation: x = (t − t_m0) / 25 ms.
    x = (imu_ns - mag_ns[0]) / 25e6
    assert read.mag is not None
    np.testing.assert_allclose(read.mag, np.stack([x, 2 * x, np.full_like(x, -4.0)], axis=-1), rtol=1e-12, atol=1e-12)

    late = _write_bag(tmp_path / "late", imu, mag_ns[1:], field[1:] * 1e-6)
    with pytest.raises(ik.FileFormatError, match=r"topic /imu/mag: IMU sample 0 .* outside the magnetometer's span"):
        ik.io.read_rosbag(late, mag_topic="/imu/mag")
    # Found but not asked for: the bag still reads, without the magnetometer, saying why.
    with pytest.warns(UserWarning, match="magnetometer not read: .* IMU sample 0 .* outside the magnetometer's span"):
        assert ik.io.read_rosbag(late)[0].mag is None
    gap = np.delete(np.arange(len(mag_ns)), range(10, 22))  # 13 steps: over GAP_FACTOR = 10
    holed = _write_bag(tmp_path / "holed", imu, mag_ns[gap], field[gap] * 1e-6)
    with pytest.raises(ik.FileFormatError, match="in a gap of 325000000 ns between magnetometer samples"):
        ik.io.read_rosbag(holed, mag_topic="/imu/mag")


def test_cli_filter_9d_from_a_csv_with_mag_columns(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    imu, _, mag = _moving(duration=5.0)
    rows = np.column_stack([imu.t, imu.gyro, imu.accel, mag])
    csv = tmp_path / "log.csv"
    np.savetxt(csv, rows, delimiter=",", header="t,gx,gy,gz,ax,ay,az,mx,my,mz", comments="", fmt="%.17g")
    out = tmp_path / "q.csv"
    columns = ["--csv-time-column", "t", "--csv-gyro-columns", "gx,gy,gz", "--csv-accel-columns", "ax,ay,az"]
    code = main(["filter", str(csv), *columns, "--csv-mag-columns", "mx,my,mz", "--mag", "--out", str(out)])
    assert code == 0 and "Robust 9D" in capsys.readouterr().out
    written = np.loadtxt(out, delimiter=",", skiprows=1)
    expected = ik.filters.Robust().run(ik.ImuData(imu.t, imu.gyro, imu.accel, mag=mag)).rotation.as_quat()
    assert np.abs(written[:, 1:5] - expected).max() < 1e-12
    assert main(["filter", str(csv), *columns, "--mag"]) != 0  # no magnetometer without the columns
    assert "--mag:" in capsys.readouterr().err
    assert math.isfinite(float(written[-1, 1]))


def test_a_found_magnetometer_whose_messages_are_bad_is_dropped_with_a_warning(tmp_path: Path) -> None:
    """Its stamps all zero: the bag did not read at all before 2026-12-07 (raise: the mag's message 1;
    skip: "no valid messages"), though the docs promise a found magnetometer that cannot be used
    is left out, so that a bag read before still reads. Asked for by name, it is still an error.
    Its skipped messages are not reported as skipped lines of what was read (they were, 101 of them,
    before 2026-12-07: a report of an IMU read whole)."""
    imu, _, mag = _moving(rate=100.0, duration=1.0)
    bag = _write_bag(tmp_path / "bag", imu, np.zeros(len(imu), dtype=np.int64), mag * 1e-6)
    with pytest.warns(UserWarning, match="magnetometer not read: .* topic /imu/mag, message 1: header stamp is zero"):
        read, _ = ik.io.read_rosbag(bag)
    assert read.mag is None and len(read) == len(imu)
    with pytest.warns(UserWarning) as caught:
        assert ik.io.read_rosbag(bag, on_bad_line="skip")[0].mag is None
    messages = [str(w.message) for w in caught]
    assert any(re.search(r"magnetometer not read: .*no valid messages \(all 101 skipped\)", m) for m in messages)
    assert not any("lines skipped" in m for m in messages)
    report = ik.io.ReadReport()
    with pytest.warns(UserWarning, match="magnetometer not read"):
        assert ik.io.read_rosbag(bag, on_bad_line="skip", report=report)[0].mag is None
    assert report.skipped == []
    with pytest.raises(ik.FileFormatError, match="topic /imu/mag, message 1: header stamp is zero"):
        ik.io.read_rosbag(bag, mag_topic="/imu/mag")
