"""read_imu / read_trajectory: each format found from the path alone (real files where present), ROS bags
handed to imukit.io.read_rosbag, and unknown files refused with the list of formats tried."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
import imukit.io._rosbag
from euroc import GT_CSV, IMU_CSV, requires_euroc
from imukit.io import ReadReport
from test_io_gtsam import KITTI_IMU, requires_kitti
from test_io_tumvi import MOCAP, dataset

TRIED_IMU = (
    "tried EuRoC / TUM-VI folder or imu0/data.csv, GTSAM / KITTI text, ROS bag, CSV with named IMU columns; "
    "other layouts: read_imu_csv"
)
TRIED_TRAJECTORY = (
    "tried TUM, EuRoC ground truth, CSV with named pose columns, TUM-VI mocap (or their folders); KITTI poses: "
    "read_kitti_poses; other layouts: read_trajectory_csv"
)
EUROC_IMU_HEADER = (
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
)


def simulated(n: int = 20) -> tuple[ik.ImuData, ik.Trajectory]:
    t_ns = 1_403_715_523_912_140_000 + 5_000_000 * np.arange(n)
    rng = np.random.default_rng(3)
    imu = ik.ImuData(t_ns, rng.normal(size=(n, 3)), rng.normal(size=(n, 3)))
    truth = ik.Trajectory(
        None, rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), Rotation.random(n, rng=rng), t_ns=t_ns + 3168,
        gyro_bias=np.zeros((n, 3)), accel_bias=np.zeros((n, 3)),
    )  # fmt: skip
    return imu, truth


def test_euroc_folder_mav0_and_csv(tmp_path: Path) -> None:
    imu, truth = simulated()
    ik.io.write_euroc(tmp_path / "seq" / "mav0", imu, truth)
    for path in (tmp_path / "seq", tmp_path / "seq" / "mav0"):
        back, back_truth = ik.io.read_imu(path)
        assert back_truth is not None and back_truth.velocity is not None  # EuRoC's, not TUM-VI's
        np.testing.assert_array_equal(back.gyro, imu.gyro)
        np.testing.assert_array_equal(back_truth.position, truth.position)
    back, none = ik.io.read_imu(tmp_path / "seq" / "mav0" / "imu0" / "data.csv")
    assert none is None and np.array_equal(back.accel, imu.accel)
    # read_trajectory: the folder gives its ground truth, the CSV itself too.
    for path in (tmp_path / "seq", tmp_path / "seq" / "mav0" / "state_groundtruth_estimate0" / "data.csv"):
        traj = ik.io.read_trajectory(path)
        assert traj.t_ns is not None and np.array_equal(traj.t_ns, truth.t_ns)  # type: ignore[arg-type]
        np.testing.assert_array_equal(traj.rotation.as_quat(), truth.rotation.as_quat())


def test_tumvi_folder_and_mocap_csv(tmp_path: Path) -> None:
    root = dataset(tmp_path / "room1")
    imu, truth = ik.io.read_imu(root)
    assert len(imu) == 2 and truth is not None and truth.velocity is None and len(truth) == 2
    for path in (root, root / "mav0" / "mocap0" / "data.csv"):
        traj = ik.io.read_trajectory(path)
        assert traj.t_ns is not None and traj.t_ns.tolist() == [int(line.split(",")[0]) for line in MOCAP[1:]]


def test_tum_file(tmp_path: Path) -> None:
    _, truth = simulated()
    truth.write_tum(tmp_path / "traj.txt")
    traj = ik.io.read_trajectory(tmp_path / "traj.txt")
    assert traj.velocity is None and np.array_equal(traj.position, truth.position)
    # A TUM file is not IMU data: 8 white-space fields without GTSAM's header are not guessed at.
    with pytest.raises(
        ik.io.FileFormatError,
        match=r"^path: .*traj\.txt: this is a trajectory \(TUM: t x y z qx qy qz qw\), not IMU samples$",
    ):
        ik.io.read_imu(tmp_path / "traj.txt")


def test_gtsam_text(tmp_path: Path) -> None:
    path = tmp_path / "imu.txt"
    path.write_text("Time dt accelX accelY accelZ omegaX omegaY omegaZ\n1.0 1.0 1 2 3 4 5 6\n1.01 0.01 1 2 3 4 5 6\n")
    imu, truth = ik.io.read_imu(path)
    assert truth is None and imu.t.tolist() == [1.0, 1.01] and imu.gyro[0].tolist() == [4.0, 5.0, 6.0]


@requires_euroc
def test_real_euroc_files() -> None:
    imu, truth = ik.io.read_imu(IMU_CSV)
    assert truth is None and np.array_equal(imu.t_ns, ik.io.read_euroc_imu(IMU_CSV).t_ns)  # type: ignore[arg-type]
    traj = ik.io.read_trajectory(GT_CSV)
    assert traj.velocity is not None and len(traj) == 16702


@requires_kitti
def test_real_kitti_imu() -> None:
    imu, truth = ik.io.read_imu(KITTI_IMU)
    assert truth is None and len(imu) == 46968


def test_bags_go_to_read_rosbag(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[tuple[Path, dict[str, object]]] = []
    imu, _ = simulated()

    def fake(path: Path, **options: object) -> tuple[ik.ImuData, None]:
        calls.append((path, options))
        return imu, None

    monkeypatch.setattr(imukit.io._rosbag, "read_rosbag", fake)
    (tmp_path / "ros2").mkdir()
    (tmp_path / "ros2" / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    report = ReadReport()
    paths = [tmp_path / "ros2", tmp_path / "run.bag", tmp_path / "run.MCAP", tmp_path / "run_0.db3"]
    for path in paths[1:]:
        path.write_bytes(b"\x89BAG")
    for path in paths:
        assert ik.io.read_imu(path, on_bad_line="skip", report=report) == (imu, None)
    assert calls == [(path, {"on_bad_line": "skip", "report": report}) for path in paths]


def test_unknown_files_list_the_formats_tried(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("time,u,v,w,p,q,r\n0,1,2,3,4,5,6\n")  # names that say nothing
    message = rf"^path: {re.escape(str(path))}: not an IMU format imukit knows; {re.escape(TRIED_IMU)}$"
    with pytest.raises(ik.io.FileFormatError, match=message):
        ik.io.read_imu(path)
    path.write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(ik.io.FileFormatError, match=rf"^path: {re.escape(str(path))}: not a text file; tried EuRoC"):
        ik.io.read_imu(path)
    with pytest.raises(
        ik.io.FileFormatError, match=rf"^path: .*: a folder of no known layout; {re.escape(TRIED_IMU)}$"
    ):
        ik.io.read_imu(tmp_path)
    with pytest.raises(FileNotFoundError, match=r"^path: .*missing\.csv does not exist"):
        ik.io.read_imu(tmp_path / "missing.csv")
    poses = tmp_path / "00.txt"
    poses.write_text("1 0 0 0 0 1 0 0 0 0 1 0\n")
    message = rf"^path: {re.escape(str(poses))}: not a trajectory format imukit knows; {re.escape(TRIED_TRAJECTORY)}$"
    with pytest.raises(ik.io.FileFormatError, match=message):
        ik.io.read_trajectory(poses)


def test_folder_without_ground_truth(tmp_path: Path) -> None:
    imu, _ = simulated()
    ik.io.write_euroc(tmp_path, imu)
    with pytest.raises(ik.io.FileFormatError, match=r"^path: .*: a dataset folder without ground truth \(no state_"):
        ik.io.read_trajectory(tmp_path)


def test_options_reach_the_reader_chosen(tmp_path: Path) -> None:
    path = tmp_path / "traj.txt"
    path.write_text("0.0 0 0 0 0 0 0 1\n0.1 1 2 3\n0.2 0 0 0 0 0 0 1\n")
    report = ReadReport()
    traj = ik.io.read_trajectory(path, on_bad_line="skip", report=report)
    assert traj.t.tolist() == [0.0, 0.2] and [(s.line, s.kind) for s in report.skipped] == [(2, "wrong column count")]
    with pytest.raises(ik.io.FileFormatError, match=r", line 2: expected 8 fields"):
        ik.io.read_trajectory(path)


def test_skip_warning_points_at_the_caller(tmp_path: Path) -> None:
    imu, truth = simulated()
    ik.io.write_euroc(tmp_path, imu)
    csv = tmp_path / "imu0" / "data.csv"
    csv.write_text(csv.read_text() + "1,2\n")
    truth.write_tum(tmp_path / "traj.txt")
    with open(tmp_path / "traj.txt", "a") as f:
        f.write("1 2 3\n")
    calls = [
        (lambda: ik.io.read_imu(tmp_path, on_bad_line="skip"), csv),
        (lambda: ik.io.read_imu(csv, on_bad_line="skip"), csv),
        (lambda: ik.io.read_trajectory(tmp_path / "traj.txt", on_bad_line="skip"), tmp_path / "traj.txt"),
    ]
    for call, path in calls:
        with pytest.warns(ik.io.SkippedLinesWarning) as caught:
            call()
        assert [str(w.message) for w in caught] == [f"1 line skipped in {path}: 1 wrong column count"]
        assert caught[0].filename == __file__


@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap", "mcap-file"])
def test_real_bags_end_to_end(kind: str, tmp_path: Path) -> None:
    pytest.importorskip("rosbags", reason="rosbags (the imukit[ros] extra) is not installed")
    from test_io_rosbag import Bag

    bag = Bag(kind)
    stamps = [(1_403_715_523, 912_140_000), (1_403_715_523, 917_140_000)]
    messages = [(s * 10**9 + ns, bag.imu((s, ns), (0.1 * k, 0.2, 0.3), (9.1, 9.2, 9.3 + k))) for k, (s, ns) in
                enumerate(stamps)]  # fmt: skip
    path = bag.write(tmp_path / "run", {"/imu0": ("sensor_msgs/msg/Imu", messages)})
    imu, truth = ik.io.read_imu(path)
    assert truth is None and imu.t_ns is not None
    assert imu.t_ns.tolist() == [1_403_715_523_912_140_000, 1_403_715_523_917_140_000]
    np.testing.assert_array_equal(imu.gyro, [[0.0, 0.2, 0.3], [0.1, 0.2, 0.3]])
    np.testing.assert_array_equal(imu.accel, [[9.1, 9.2, 9.3], [9.1, 9.2, 10.3]])


def test_empty_and_header_only_files_are_said_to_be(tmp_path: Path) -> None:
    for text in ("", "\n  \n\n"):
        path = tmp_path / "empty.csv"
        path.write_text(text)
        with pytest.raises(ik.io.FileFormatError, match=rf"^path: {re.escape(str(path))}: empty file, expected IMU"):
            ik.io.read_imu(path)
        with pytest.raises(ik.io.FileFormatError, match=r"^path: .*: empty file, expected a trajectory$"):
            ik.io.read_trajectory(path)
    path = tmp_path / "imu0.csv"
    path.write_text(EUROC_IMU_HEADER + "\n")
    with pytest.raises(ik.io.FileFormatError) as raised:
        ik.io.read_imu(path)
    message = str(raised.value)
    assert message.startswith(f"path: {path}: no data lines, only the header '#timestamp [ns],w_RS_S_x")
    assert message.endswith("...', expected IMU samples") and len(message) < 200 + len(str(path))


def test_trajectories_given_for_imu_samples_are_named(tmp_path: Path) -> None:
    _, truth = simulated()
    ik.io.write_euroc(tmp_path / "seq", simulated()[0], truth)
    gt = tmp_path / "seq" / "mav0" / "state_groundtruth_estimate0" / "data.csv"
    if not gt.is_file():
        gt = tmp_path / "seq" / "state_groundtruth_estimate0" / "data.csv"
    with pytest.raises(ik.io.FileFormatError, match=r"this is a trajectory \(EuRoC ground truth, 17 comma-separated"):
        ik.io.read_imu(gt)
    mocap = tmp_path / "mocap.csv"
    mocap.write_text("\n".join(MOCAP) + "\n")
    with pytest.raises(ik.io.FileFormatError, match=r"this is a trajectory \(TUM-VI mocap or another pose CSV"):
        ik.io.read_imu(mocap)


def test_unknown_format_message_is_short(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_text("time,u,v,w,p,q,r\n0,1,2,3,4,5,6\n")  # names that say nothing (`gx, …` would be read)
    with pytest.raises(ik.io.FileFormatError) as raised:
        ik.io.read_imu(path)
    assert len(str(raised.value)) - len(str(path)) < 180  # was ~520 characters; 30 more per format listed


def test_a_byte_order_mark_does_not_hide_the_header(tmp_path: Path) -> None:
    """Excel's UTF-8 BOM before EuRoC's '#timestamp' header: detected as EuRoC, read like the file without."""
    imu, _ = simulated()
    ik.io.write_euroc(tmp_path / "seq", imu)
    plain = next(tmp_path.glob("seq/**/imu0/data.csv"))
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())
    back, truth = ik.io.read_imu(bom)
    assert truth is None and np.array_equal(back.t_ns, imu.t_ns) and np.array_equal(back.gyro, imu.gyro)  # type: ignore[arg-type]
    mocap = tmp_path / "mocap_bom.csv"
    mocap.write_bytes(b"\xef\xbb\xbf" + ("\n".join(MOCAP) + "\n").encode())
    assert len(ik.io.read_trajectory(mocap)) == 2


def test_eight_comma_fields_need_a_header_naming_w_first(tmp_path: Path) -> None:
    """TUM-VI mocap is t, p, q w x y z; a t,x,y,z,qx,qy,qz,qw export read that way would be silently wrong."""
    w_last = tmp_path / "w_last.csv"
    w_last.write_text("t_ns,x,y,z,qx,qy,qz,qw\n1000,0,0,0,0,0,0.7071,0.7071\n2000,0,0,0,0,0,0.7071,0.7071\n")
    with pytest.raises(ik.io.FileFormatError, match=r"^path: .*w_last\.csv: the header puts the quaternion w last"):
        ik.io.read_trajectory(w_last)
    headerless = tmp_path / "headerless.csv"
    headerless.write_text("\n".join(MOCAP[1:]) + "\n")
    with pytest.raises(ik.io.FileFormatError, match=r"^path: .*: 8 comma-separated fields and no header line to tell"):
        ik.io.read_trajectory(headerless)
    named = tmp_path / "named.csv"
    named.write_text("# t_ns, x, y, z, qw, qx, qy, qz\n" + "\n".join(MOCAP[1:]) + "\n")
    traj = ik.io.read_trajectory(named)  # qw as the 5th name: w first, as TUM-VI
    np.testing.assert_allclose(traj.rotation[0].as_quat(), [0.5, -0.5, 0.5, 0.5])  # the row's w x y z = .5 .5 -.5 .5
