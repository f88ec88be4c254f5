"""ROS bag reading (imukit.io.read_rosbag): bags written here with rosbags' own writers (ROS 1,
ROS 2 sqlite3, ROS 2 mcap, bare .mcap) read back value for value; frames, topic choice, skips."""

from __future__ import annotations

import math
import re
import sqlite3
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import imukit as ik
from euroc import GT_CSV, IMU_CSV, requires_euroc
from imukit.io import ReadReport, SkippedLine, SkippedLinesWarning, list_rosbag_topics, read_rosbag
from imukit.io._rosbag import is_bag_path

rosbags = pytest.importorskip("rosbags", reason="rosbags is the optional [ros] extra")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

IMU = "sensor_msgs/msg/Imu"
POSE = "geometry_msgs/msg/PoseStamped"
TF = "geometry_msgs/msg/TransformStamped"
ODOM = "nav_msgs/msg/Odometry"
KINDS = ["ros1", "ros1-bz2", "ros1-lz4", "sqlite3", "sqlite3-zstd", "mcap", "mcap-file"]
EPOCH_S = 1_403_715_523  # EuRoC V1_02's epoch second


class Bag:
    """Messages built with the typestore of one bag kind (ROS 1 headers carry ``seq``)."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self.ros1 = kind.startswith("ros1")
        self.store = get_typestore(Stores.ROS1_NOETIC if self.ros1 else Stores.ROS2_HUMBLE)

    def _t(self, name: str) -> Any:
        return self.store.types[name]

    def header(self, sec: int, nanosec: int, frame: str = "world") -> Any:
        stamp = self._t("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec)
        extra = {"seq": 0} if self.ros1 else {}
        return self._t("std_msgs/msg/Header")(**extra, stamp=stamp, frame_id=frame)

    def vec(self, v: Sequence[float]) -> Any:
        return self._t("geometry_msgs/msg/Vector3")(x=v[0], y=v[1], z=v[2])

    def point(self, v: Sequence[float]) -> Any:
        return self._t("geometry_msgs/msg/Point")(x=v[0], y=v[1], z=v[2])

    def quat(self, q: Sequence[float]) -> Any:
        return self._t("geometry_msgs/msg/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3])

    def imu(
        self,
        stamp: tuple[int, int],
        gyro: Sequence[float],
        accel: Sequence[float],
        *,
        orientation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
        covariances: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> Any:
        c_q, c_w, c_a = (np.full(9, c) for c in covariances)
        return self._t(IMU)(
            header=self.header(*stamp, frame="imu"),
            orientation=self.quat(orientation),
            orientation_covariance=c_q,
            angular_velocity=self.vec(gyro),
            angular_velocity_covariance=c_w,
            linear_acceleration=self.vec(accel),
            linear_acceleration_covariance=c_a,
        )

    def pose_msg(self, p: Sequence[float], q: Sequence[float]) -> Any:
        return self._t("geometry_msgs/msg/Pose")(position=self.point(p), orientation=self.quat(q))

    def pose(self, stamp: tuple[int, int], p: Sequence[float], q: Sequence[float]) -> Any:
        return self._t(POSE)(header=self.header(*stamp), pose=self.pose_msg(p, q))

    def transform(self, stamp: tuple[int, int], p: Sequence[float], q: Sequence[float]) -> Any:
        tf = self._t("geometry_msgs/msg/Transform")(translation=self.vec(p), rotation=self.quat(q))
        return self._t(TF)(header=self.header(*stamp), child_frame_id="body", transform=tf)

    def odometry(self, stamp: tuple[int, int], p: Sequence[float], q: Sequence[float], v_body: Sequence[float]) -> Any:
        pose = self._t("geometry_msgs/msg/PoseWithCovariance")(pose=self.pose_msg(p, q), covariance=np.full(36, 7.0))
        twist = self._t("geometry_msgs/msg/Twist")(linear=self.vec(v_body), angular=self.vec((5.0, 6.0, 7.0)))
        twist_cov = self._t("geometry_msgs/msg/TwistWithCovariance")(twist=twist, covariance=np.full(36, 8.0))
        return self._t(ODOM)(header=self.header(*stamp), child_frame_id="body", pose=pose, twist=twist_cov)

    def write(self, base: Path, topics: dict[str, tuple[str, list[tuple[int, Any]]]]) -> Path:
        """Write ``{topic: (msgtype, [(record time ns, message or raw bytes), ...])}``; the path to read back."""
        if self.ros1:
            path = base.with_suffix(".bag")
            writer: Any = Writer1(path)
            if self.kind != "ros1":
                writer.set_compression(Writer1.CompressionFormat[self.kind[5:].upper()])
            serialize = self.store.serialize_ros1
        else:
            path = base
            plugin = StoragePlugin.SQLITE3 if self.kind.startswith("sqlite3") else StoragePlugin.MCAP
            writer = Writer2(path, version=9, storage_plugin=plugin)
            if self.kind == "sqlite3-zstd":
                writer.set_compression(CompressionMode.MESSAGE, CompressionFormat.ZSTD)
            serialize = self.store.serialize_cdr
        with writer:
            for topic, (msgtype, messages) in topics.items():
                connection = writer.add_connection(topic, msgtype, typestore=self.store)
                for record_ns, msg in messages:
                    writer.write(connection, record_ns, msg if isinstance(msg, bytes) else serialize(msg, msgtype))
        return next(path.glob("*.mcap")) if self.kind == "mcap-file" else path


def bits(a: Any) -> bytes:
    """The exact bytes of a float64 array: equal bytes means equal bit for bit (-0.0 and NaN included)."""
    return np.ascontiguousarray(a, dtype=np.float64).tobytes()


def unit_quats(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


@pytest.mark.parametrize("kind", KINDS)
def test_every_storage_reads_back_bit_for_bit(kind: str, tmp_path: Path, rng: np.random.Generator) -> None:
    bag = Bag(kind)
    imu_ns = [EPOCH_S * 10**9 + 912_140_001 + k * 5_000_003 for k in range(6)]
    gyro = rng.normal(size=(6, 3))
    accel = rng.normal(size=(6, 3)) * 10.0
    gyro[0] = (-0.0, 5e-324, 1.7976931348623157e308)  # signed zero, subnormal, largest float
    truth_ns = [EPOCH_S * 10**9 + 999_999_999 + k * 10**9 for k in range(3)]
    position = rng.normal(size=(3, 3))
    quat = unit_quats(rng, 3)
    # Record times are the recorder's receive times: later than the stamps and jittered.
    imu_msgs = [
        (ns + 400_000 + 7_919 * k, bag.imu(divmod(ns, 10**9), g, a))
        for k, (ns, g, a) in enumerate(zip(imu_ns, gyro, accel))
    ]
    pose_msgs = [(ns + 1_000_000, bag.pose(divmod(ns, 10**9), p, q)) for ns, p, q in zip(truth_ns, position, quat)]
    path = bag.write(tmp_path / "b", {"/imu0": (IMU, imu_msgs), "/vicon/pose": (POSE, pose_msgs)})

    imu, truth = read_rosbag(path)

    assert imu.t_ns is not None and imu.t_ns.dtype == np.int64
    assert imu.t_ns.tolist() == imu_ns  # header stamps to the ns, not the record times
    assert bits(imu.gyro) == bits(gyro) and bits(imu.accel) == bits(accel)
    assert truth is not None and truth.t_ns is not None
    assert truth.t_ns.tolist() == truth_ns
    assert bits(truth.position) == bits(position)
    assert bits(truth.rotation.as_quat()) == bits(quat)  # unit to rounding: kept as written
    assert truth.velocity is None and truth.gyro_bias is None
    topics = {"/imu0": IMU, "/vicon/pose": POSE}
    assert list_rosbag_topics(path) == topics


def test_odometry_twist_is_rotated_from_body_to_world(tmp_path: Path) -> None:
    """nav_msgs/Odometry: twist in child_frame_id (body) coordinates; by hand, v_w = R_wb v_b."""
    bag = Bag("sqlite3")
    h = math.sqrt(0.5)
    samples = [
        # yaw +90°: body x is world y
        ((0, 0, h, h), (2.0, 0.0, 0.0), (0.0, 2.0, 0.0)),
        # roll +90° about x: body y is world z, body z is world -y
        ((h, 0, 0, h), (0.0, 3.0, 4.0), (0.0, -4.0, 3.0)),
        # identity
        ((0, 0, 0, 1.0), (1.5, -2.5, 0.25), (1.5, -2.5, 0.25)),
    ]
    odom = [
        (k * 10**8, bag.odometry((7, k * 10**8), (k, 2.0 * k, -1.0), q, v_b)) for k, (q, v_b, _) in enumerate(samples)
    ]
    imu = [(k * 10**7, bag.imu((7, k * 10**7), (0.0, 0.0, 0.0), (0.0, 0.0, 9.81))) for k in range(2)]
    path = bag.write(tmp_path / "b", {"/imu": (IMU, imu), "/odom": (ODOM, odom)})

    _, truth = read_rosbag(path)

    assert truth is not None and truth.velocity is not None
    np.testing.assert_allclose(truth.velocity, [v_w for _, _, v_w in samples], rtol=0, atol=1e-15)
    assert truth.position.tolist() == [[0.0, 0.0, -1.0], [1.0, 2.0, -1.0], [2.0, 4.0, -1.0]]
    assert truth.t_ns is not None and truth.t_ns.tolist() == [7 * 10**9 + k * 10**8 for k in range(3)]
    # The pose's R_wb maps body x onto world y in the first sample.
    np.testing.assert_allclose(truth.rotation[0].apply([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)


def test_transform_stamped_is_the_body_pose_in_its_parent_frame(tmp_path: Path) -> None:
    bag = Bag("mcap")
    h = math.sqrt(0.5)
    tf = [(k, bag.transform((1, k * 10**7), (1.0 + k, 2.0, 3.0), (0.0, 0.0, h, h))) for k in range(1, 3)]
    imu = [(k, bag.imu((1, k * 10**7), (0.0, 0.0, 0.0), (0.0, 0.0, 9.81))) for k in range(1, 3)]
    path = bag.write(tmp_path / "b", {"/imu": (IMU, imu), "/vicon/body": (TF, tf)})

    _, truth = read_rosbag(path)

    assert truth is not None and truth.velocity is None
    assert truth.position.tolist() == [[2.0, 2.0, 3.0], [3.0, 2.0, 3.0]]
    # translation = the child (body) origin in the parent frame; rotation maps child vectors to parent
    np.testing.assert_allclose(truth.rotation.apply([1.0, 0.0, 0.0]), [[0.0, 1.0, 0.0]] * 2, atol=1e-15)


def test_covariances_and_imu_orientation_are_not_read(tmp_path: Path) -> None:
    bag = Bag("ros1")
    imu = [
        (
            k + 1,
            bag.imu(
                (3, k * 10**6),
                (0.5, k, 0.25),
                (1.0, 2.0, k),
                orientation=(0.0, 0.0, 1.0, 0.0),
                covariances=(9.0, 1e-3, 4.0),
            ),
        )
        for k in range(3)
    ]
    path = bag.write(tmp_path / "b", {"/imu": (IMU, imu)})

    data, truth = read_rosbag(path)

    assert truth is None  # no ground-truth topic
    assert data.gyro.tolist() == [[0.5, 0.0, 0.25], [0.5, 1.0, 0.25], [0.5, 2.0, 0.25]]
    assert data.accel.tolist() == [[1.0, 2.0, 0.0], [1.0, 2.0, 1.0], [1.0, 2.0, 2.0]]


def raise_then_skip(path: Path, message: str) -> tuple[ik.ImuData, ik.Trajectory | None, ReadReport]:
    """``read_rosbag(path)`` must raise ``path: <path>, topic …`` + the regex ``message``; then the
    same read with ``on_bad_line="skip"`` and a report, returned."""
    with pytest.raises(ik.io.FileFormatError, match=f"^path: {re.escape(str(path))}, {message}") as info:
        read_rosbag(path)
    assert isinstance(info.value, ValueError)
    report = ReadReport()
    imu, truth = read_rosbag(path, on_bad_line="skip", report=report)
    return imu, truth, report


def test_a_field_flagged_absent_is_a_bad_message(tmp_path: Path) -> None:
    """sensor_msgs/Imu: covariance element 0 = -1 means "not provided": never read it as zeros."""
    bag = Bag("sqlite3")
    imu = [
        (k + 1, bag.imu((3, k * 10**6), (0.0, 0.0, 0.0), (0.0, 0.0, 9.8), covariances=(-1.0, 0.0, 0.0)))
        for k in range(2)
    ]
    imu.append((3, bag.imu((3, 2 * 10**6), (0.0, 0.0, 0.0), (0.0, 0.0, 9.8), covariances=(0.0, -1.0, 0.0))))
    imu.append((4, bag.imu((3, 3 * 10**6), (0.0, 0.0, 0.0), (0.0, 0.0, 9.8), covariances=(0.0, 0.0, -1.0))))
    path = bag.write(tmp_path / "b", {"/imu": (IMU, imu)})

    data, _, report = raise_then_skip(
        path,
        r"topic /imu, message 3: no angular velocity \(angular_velocity_covariance\[0\] = -1\): header\.stamp 3\.002",
    )
    assert data.t_ns is not None and data.t_ns.tolist() == [3 * 10**9, 3 * 10**9 + 10**6]  # orientation -1 is fine
    assert [(s.line, s.reason, s.text) for s in report.skipped] == [
        (
            3,
            "missing field: topic /imu, message 3: no angular velocity (angular_velocity_covariance[0] = -1)",
            "header.stamp 3.002000000",
        ),
        (
            4,
            "missing field: topic /imu, message 4: no linear acceleration (linear_acceleration_covariance[0] = -1)",
            "header.stamp 3.003000000",
        ),
    ]


def _topics_bag(tmp_path: Path, topics: dict[str, str]) -> Path:
    bag = Bag("mcap")
    make = {
        IMU: lambda k, v: bag.imu((1, k), (v, 0.0, 0.0), (0.0, 0.0, v)),
        POSE: lambda k, v: bag.pose((1, k), (v, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
        ODOM: lambda k, v: bag.odometry((1, k), (v, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
        TF: lambda k, v: bag.transform((1, k), (v, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
        "std_msgs/msg/String": lambda k, v: bag.store.types["std_msgs/msg/String"](data="x"),
    }
    content = {
        topic: (msgtype, [(k, make[msgtype](k * 10**7, float(i))) for k in range(1, 3)])
        for i, (topic, msgtype) in enumerate(topics.items())
    }
    return bag.write(tmp_path / "b", content)


def test_topic_choice(tmp_path: Path) -> None:
    path = _topics_bag(
        tmp_path, {"/a/imu": IMU, "/b/imu": IMU, "/gt/pose": POSE, "/gt/odom": ODOM, "/chatter": "std_msgs/msg/String"}
    )
    listing = re.escape("/a/imu (sensor_msgs/msg/Imu), /b/imu (sensor_msgs/msg/Imu)")
    with pytest.raises(ik.ParameterError, match=f"^imu_topic: the bag has 2 candidate topics, pass one: {listing}$"):
        read_rosbag(path)
    gts = re.escape("/gt/odom (nav_msgs/msg/Odometry), /gt/pose (geometry_msgs/msg/PoseStamped)")
    with pytest.raises(
        ik.ParameterError, match=f"^groundtruth_topic: the bag has 2 candidate topics, pass one: {gts}$"
    ):
        read_rosbag(path, imu_topic="/b/imu")
    imu, truth = read_rosbag(path, imu_topic="/b/imu", groundtruth_topic="/gt/odom")
    assert imu.gyro[:, 0].tolist() == [1.0, 1.0]  # /b/imu was written with value 1, /a/imu with 0
    assert truth is not None and truth.position[:, 0].tolist() == [3.0, 3.0] and truth.velocity is not None
    _, truth = read_rosbag(path, imu_topic="/a/imu", groundtruth_topic="/gt/pose")
    assert truth is not None and truth.position[:, 0].tolist() == [2.0, 2.0] and truth.velocity is None

    every = re.escape(
        "/a/imu (sensor_msgs/msg/Imu), /b/imu (sensor_msgs/msg/Imu), /chatter (std_msgs/msg/String), "
        "/gt/odom (nav_msgs/msg/Odometry), /gt/pose (geometry_msgs/msg/PoseStamped)"
    )
    with pytest.raises(ik.ParameterError, match=f"^imu_topic: topic '/imu' is not in the bag; its topics: {every}$"):
        read_rosbag(path, imu_topic="/imu")
    with pytest.raises(
        ik.ParameterError,
        match=r"^imu_topic: topic '/gt/pose' has type geometry_msgs/msg/PoseStamped, expected sensor_msgs/msg/Imu$",
    ):
        read_rosbag(path, imu_topic="/gt/pose")
    with pytest.raises(
        ik.ParameterError,
        match=r"^groundtruth_topic: topic '/a/imu' has type sensor_msgs/msg/Imu, expected "
        r"geometry_msgs/msg/PoseStamped or geometry_msgs/msg/TransformStamped or nav_msgs/msg/Odometry$",
    ):
        read_rosbag(path, imu_topic="/a/imu", groundtruth_topic="/a/imu")


def test_a_ros1_topic_with_two_types_is_no_candidate(tmp_path: Path) -> None:
    bag = Bag("ros1")
    path = tmp_path / "mixed.bag"
    with Writer1(path) as writer:
        for msgtype, msg in (
            (IMU, bag.imu((1, 0), (0.0, 0.0, 0.0), (0.0, 0.0, 9.81))),
            (POSE, bag.pose((1, 0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))),
        ):
            connection = writer.add_connection("/mixed", msgtype, typestore=bag.store)
            writer.write(connection, 1, bag.store.serialize_ros1(msg, msgtype))
    assert list_rosbag_topics(path) == {"/mixed": f"{POSE} | {IMU}"}
    with pytest.raises(ik.ParameterError, match=r"^imu_topic: the bag has no sensor_msgs/msg/Imu topic with messages"):
        read_rosbag(path)
    with pytest.raises(
        ik.ParameterError, match=f"^imu_topic: topic '/mixed' has type {POSE} [|] {IMU}, expected {IMU}$"
    ):
        read_rosbag(path, imu_topic="/mixed")
    with pytest.raises(ik.ParameterError, match=r"^imu_topic: expected a topic name or None, got int$"):
        read_rosbag(path, imu_topic=0)  # type: ignore[arg-type]


def test_bag_without_imu_topic(tmp_path: Path) -> None:
    path = _topics_bag(tmp_path, {"/gt/pose": POSE, "/chatter": "std_msgs/msg/String"})
    listing = re.escape("/chatter (std_msgs/msg/String), /gt/pose (geometry_msgs/msg/PoseStamped)")
    with pytest.raises(
        ik.ParameterError,
        match=f"^imu_topic: the bag has no sensor_msgs/msg/Imu topic with messages; its topics: {listing}$",
    ):
        read_rosbag(path)


def _stamped_imu_bag(tmp_path: Path, kind: str, stamps: list[tuple[int, int]]) -> tuple[Path, list[Any]]:
    """IMU message k (1-based) has gyro x = k, so the kept messages can be told apart."""
    bag = Bag(kind)
    messages = [(10**6 * (k + 1), bag.imu(s, (k + 1.0, 0.0, 0.0), (0.0, 0.0, 9.81))) for k, s in enumerate(stamps)]
    return bag.write(tmp_path / "b", {"/imu0": (IMU, messages)}), messages


@pytest.mark.parametrize("kind", ["ros1", "mcap"])
def test_duplicate_and_decreasing_stamps(kind: str, tmp_path: Path) -> None:
    stamps = [(5, 0), (5, 10**6), (5, 10**6), (5, 5 * 10**5), (5, 2 * 10**6), (5, 2 * 10**6), (5, 3 * 10**6)]
    path, _ = _stamped_imu_bag(tmp_path, kind, stamps)
    imu, _, report = raise_then_skip(
        path,
        r"topic /imu0, message 3: time must increase strictly, but 5\.001000000 follows 5\.001000000 \(message 2\): "
        r"header\.stamp 5\.001000000, angular_velocity 3\.0 0\.0 0\.0, linear_acceleration 0\.0 0\.0 9\.81$",
    )
    assert imu.t_ns is not None
    assert imu.t_ns.tolist() == [5_000_000_000, 5_001_000_000, 5_002_000_000, 5_003_000_000]
    assert imu.gyro[:, 0].tolist() == [1.0, 2.0, 5.0, 7.0]  # the first of equal stamps is kept
    assert report.skipped == [
        SkippedLine(
            str(path),
            3,
            "duplicate stamp: topic /imu0, message 3: time must increase strictly, but 5.001000000 follows "
            "5.001000000 (message 2)",
            "header.stamp 5.001000000, angular_velocity 3.0 0.0 0.0, linear_acceleration 0.0 0.0 9.81",
        ),
        SkippedLine(
            str(path),
            4,
            "stamp going back: topic /imu0, message 4: time must increase strictly, but 5.000500000 follows "
            "5.001000000 (message 2)",
            "header.stamp 5.000500000, angular_velocity 4.0 0.0 0.0, linear_acceleration 0.0 0.0 9.81",
        ),
        SkippedLine(
            str(path),
            6,
            "duplicate stamp: topic /imu0, message 6: time must increase strictly, but 5.002000000 follows "
            "5.002000000 (message 5)",
            "header.stamp 5.002000000, angular_velocity 6.0 0.0 0.0, linear_acceleration 0.0 0.0 9.81",
        ),
    ]

    with pytest.warns(SkippedLinesWarning) as caught:
        again, _ = read_rosbag(path, on_bad_line="skip")
    assert [str(w.message) for w in caught] == [f"3 lines skipped in {path}: 2 duplicate stamps, 1 stamp going back"]
    assert again.t_ns is not None and again.t_ns.tolist() == imu.t_ns.tolist()


def test_header_stamp_problems(tmp_path: Path) -> None:
    """A zero header stamp (publisher left it unset) and a nanosec field ≥ 10⁹ are bad messages;
    time_source="record" reads the recorder's receive times instead."""
    path, _ = _stamped_imu_bag(tmp_path, "sqlite3", [(0, 0), (8, 0), (8, 1_500_000_000), (8, 10**6)])
    imu, _, report = raise_then_skip(path, r"topic /imu0, message 1: header stamp is zero .*time_source='record'")
    assert imu.t_ns is not None and imu.t_ns.tolist() == [8 * 10**9, 8 * 10**9 + 10**6]
    assert imu.gyro[:, 0].tolist() == [2.0, 4.0]
    assert [(s.line, s.reason) for s in report.skipped] == [
        (
            1,
            "zero stamp: topic /imu0, message 1: header stamp is zero (unset by the publisher; "
            "time_source='record' reads record times)",
        ),
        (3, "malformed: topic /imu0, message 3: header.stamp.nanosec = 1500000000 is not below 10^9"),
    ]
    by_record, _ = read_rosbag(path, time_source="record")
    assert by_record.t_ns is not None and by_record.t_ns.tolist() == [10**6, 2 * 10**6, 3 * 10**6, 4 * 10**6]
    with pytest.raises(ik.ParameterError, match=r"^time_source: expected 'header' or 'record', got 'bag'$"):
        read_rosbag(path, time_source="bag")  # type: ignore[arg-type]


def test_ros1_stamps_after_2038(tmp_path: Path) -> None:
    """ROS 1 time is unsigned 32-bit seconds; rosbags gives them as ROS 2's int32, so a stamp from
    2038-01-19 on read 2^32 s early (negative) before 2026-12-07. The seconds are written into the
    serialized header (seq at bytes 0-3, sec at 4-7) as a recorder after 2038 would."""
    import struct

    bag = Bag("ros1")
    sec0 = 2**31 + 86_400 * 30
    messages = []
    for k in range(4):
        raw = bytearray(bag.store.serialize_ros1(bag.imu((0, 5_000_000 * k), (1.0, 0, 0), (0, 0, 9.81)), IMU))
        raw[4:8] = struct.pack("<I", sec0)
        messages.append((10**6 * (k + 1), bytes(raw)))
    imu, _ = read_rosbag(bag.write(tmp_path / "b", {"/imu0": (IMU, messages)}))
    assert imu.t_ns is not None and imu.t_ns.tolist() == [sec0 * 10**9 + 5_000_000 * k for k in range(4)]


def test_two_publishers_on_one_ros1_topic_are_named(tmp_path: Path) -> None:
    """Two IMUs publishing on one topic read as one stream alternating between them (gyro +0.1,
    -0.1, ...) without a word before 2026-12-07; the bag's connection records name the publishers."""
    bag = Bag("ros1")
    path = tmp_path / "two.bag"
    with Writer1(path) as writer:
        ends = [writer.add_connection("/imu", IMU, typestore=bag.store, callerid=c) for c in ("/a", "/b")]
        for k in range(10):
            for j, connection in enumerate(ends):
                msg = bag.imu((5, 10_000_000 * k + 5_000_000 * j), ((-1.0) ** j, 0, 0), (0, 0, 9.81))
                writer.write(connection, 10**6 * (2 * k + j + 1), bag.store.serialize_ros1(msg, IMU))
    with pytest.warns(UserWarning, match=r"topic /imu: 2 publishers \(/a, /b\); their messages are read as one"):
        imu, _ = read_rosbag(path)
    assert imu.gyro[:4, 0].tolist() == [1.0, -1.0, 1.0, -1.0]


def test_non_finite_values_and_zero_quaternions(tmp_path: Path) -> None:
    bag = Bag("ros1")
    imu = [
        (k + 1, bag.imu((2, k * 10**6), (0.1, math.nan if k == 1 else 0.2, 0.3), (0.0, 0.0, 9.81))) for k in range(3)
    ]
    imu.append((9, bag.imu((2, 3 * 10**6), (0.1, 0.2, 0.3), (0.0, -math.inf, 9.81))))
    poses = [
        (1, bag.pose((2, 0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))),
        (2, bag.pose((2, 10**6), (1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0))),
        (3, bag.pose((2, 2 * 10**6), (2.0, 0.0, 0.0), (0.0, 0.0, 0.0, 2.0))),  # not unit: normalised
    ]
    path = bag.write(tmp_path / "b", {"/imu": (IMU, imu), "/pose": (POSE, poses)})
    data, truth, report = raise_then_skip(
        path, r"topic /imu, message 2: non-finite value: header\.stamp 2\.001000000, angular_velocity 0\.1 nan 0\.3"
    )
    assert data.t_ns is not None and data.t_ns.tolist() == [2 * 10**9, 2 * 10**9 + 2 * 10**6]
    assert truth is not None and truth.position[:, 0].tolist() == [0.0, 2.0]
    assert truth.rotation.as_quat().tolist() == [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]]
    # ordered by message index within the bag, as ReadReport orders lines within a file
    assert [(s.line, s.reason) for s in report.skipped] == [
        (2, "non-finite: topic /imu, message 2: non-finite value"),
        (2, "zero quaternion: topic /pose, message 2: zero quaternion"),
        (4, "non-finite: topic /imu, message 4: non-finite value"),
    ]
    assert report.skipped[1].text == "header.stamp 2.001000000, position 1.0 0.0 0.0, orientation 0.0 0.0 0.0 0.0"


def test_a_topic_without_valid_messages(tmp_path: Path) -> None:
    path, _ = _stamped_imu_bag(tmp_path, "mcap", [(0, 0), (0, 0)])
    with pytest.raises(ik.io.FileFormatError, match=r"^path: .*, topic /imu0: no valid messages \(all 2 skipped\)$"):
        read_rosbag(path, on_bad_line="skip", report=ReadReport())


def test_undecodable_and_empty_topics(tmp_path: Path) -> None:
    bag = Bag("sqlite3")
    good = bag.imu((6, 0), (1.0, 2.0, 3.0), (4.0, 5.0, 6.0))
    path = bag.write(
        tmp_path / "b", {"/imu": (IMU, [(11, good), (22, b"\x00\x01\x00\x00 truncated")]), "/pose": (POSE, [])}
    )
    imu, truth, report = raise_then_skip(
        path, r"topic /imu, message 2: cannot decode it \(.+\): record time 0\.000000022$"
    )
    assert truth is None  # the empty /pose topic is no candidate
    assert imu.gyro.tolist() == [[1.0, 2.0, 3.0]]
    assert [(s.line, s.kind, s.text) for s in report.skipped] == [(2, "malformed", "record time 0.000000022")]
    with pytest.raises(ik.io.FileFormatError, match=f"^path: {re.escape(str(path))}, topic /pose: no messages$"):
        read_rosbag(path, groundtruth_topic="/pose", on_bad_line="skip", report=report)
    (tmp_path / "empty").mkdir()
    path, _ = _stamped_imu_bag(tmp_path / "empty", "ros1", [])
    with pytest.raises(
        ik.ParameterError, match=r"^imu_topic: the bag has no sensor_msgs/msg/Imu topic with messages; "
    ):
        read_rosbag(path)


def test_not_a_bag(tmp_path: Path) -> None:
    text = tmp_path / "imu.txt"
    text.write_text("1 2 3\n")
    with pytest.raises(
        ik.io.FileFormatError, match=f"^path: {re.escape(str(text))}: not a ROS bag; expected a ROS 1 .bag"
    ):
        read_rosbag(text)
    folder = tmp_path / "folder"
    folder.mkdir()
    for broken, hint in (
        (tmp_path / "broken.bag", ":"),
        (tmp_path / "broken.mcap", r" \(rosbags reads MCAP files of the ros2 profile"),
        (folder, ": Expected metadata file"),
    ):
        if broken != folder:
            broken.write_bytes(b"#ROSBAG V2.0\n garbage")
        with pytest.raises(
            ik.io.FileFormatError, match=f"^path: {re.escape(str(broken))}: cannot open as a ROS bag{hint}"
        ):
            list_rosbag_topics(broken)
    with pytest.raises(FileNotFoundError, match="no such file or folder"):
        read_rosbag(tmp_path / "absent.bag")
    with pytest.raises(ik.ParameterError, match=r"^on_bad_line: "):
        read_rosbag(text, on_bad_line="ignore")  # type: ignore[arg-type]


def test_humble_bag_without_message_definitions(tmp_path: Path) -> None:
    """ROS 2 Humble's sqlite3 bags store no message definitions: the standard ones are used."""
    path, _ = _stamped_imu_bag(tmp_path, "sqlite3", [(4, 0), (4, 10**6)])
    with sqlite3.connect(next(path.glob("*.db3"))) as db:
        db.execute("DELETE FROM message_definitions")
    metadata = path / "metadata.yaml"
    metadata.write_text(re.sub(r"type_description_hash: \S+", "type_description_hash: ''", metadata.read_text()))
    imu, _ = read_rosbag(path)
    assert imu.t_ns is not None and imu.t_ns.tolist() == [4 * 10**9, 4 * 10**9 + 10**6]
    assert imu.gyro[:, 0].tolist() == [1.0, 2.0]


def test_missing_rosbags_names_the_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # None in sys.modules makes `import rosbags...` raise ImportError, as if it were not installed.
    for name in [m for m in sys.modules if m == "rosbags" or m.startswith("rosbags.")]:
        monkeypatch.setitem(sys.modules, name, None)
    path = tmp_path / "any.bag"
    for call in (lambda: read_rosbag(path), lambda: list_rosbag_topics(path)):
        with pytest.raises(ik.MissingDependencyError, match=re.escape('pip install "imukit[ros]"')) as info:
            call()
        assert isinstance(info.value, ImportError)


@requires_euroc
@pytest.mark.parametrize("kind", ["ros1", "mcap"])
def test_euroc_excerpt_through_a_bag(kind: str, tmp_path: Path) -> None:
    """The real 40 s EuRoC excerpt (7 999 samples) written as sensor_msgs/Imu reads back identical; its
    ground truth over the same span, written as nav_msgs/Odometry with the twist in the body frame as
    ROS publishes it (v_b = R_wbᵀ v_w, by scipy), comes back with EuRoC's world-frame velocity."""
    euroc = ik.io.read_euroc_imu(IMU_CSV)
    gt = ik.io.read_euroc_groundtruth(GT_CSV)
    assert euroc.t_ns is not None and gt.t_ns is not None and gt.velocity is not None
    span = np.flatnonzero(gt.t_ns <= euroc.t_ns[-1])
    bag = Bag(kind)
    imu_msgs = [
        (int(ns), bag.imu(divmod(int(ns), 10**9), g, a)) for ns, g, a in zip(euroc.t_ns, euroc.gyro, euroc.accel)
    ]
    q_wb = gt.rotation[span].as_quat()
    v_body = gt.rotation[span].inv().apply(gt.velocity[span])
    odom_msgs = [
        (int(ns), bag.odometry(divmod(int(ns), 10**9), p, q, v))
        for ns, p, q, v in zip(gt.t_ns[span], gt.position[span], q_wb, v_body)
    ]
    path = bag.write(tmp_path / "euroc", {"/imu0": (IMU, imu_msgs), "/vicon/odom": (ODOM, odom_msgs)})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        imu, truth = read_rosbag(path)
    assert imu.t_ns is not None and np.array_equal(imu.t_ns, euroc.t_ns) and len(imu) == 7999
    assert bits(imu.gyro) == bits(euroc.gyro) and bits(imu.accel) == bits(euroc.accel)
    assert truth is not None and truth.t_ns is not None and truth.velocity is not None
    assert np.array_equal(truth.t_ns, gt.t_ns[span]) and len(span) > 7000
    assert bits(truth.position) == bits(gt.position[span]) and bits(truth.rotation.as_quat()) == bits(q_wb)
    # R (Rᵀ v) = v up to rounding; without the rotation back to the world the error is ~|v| (up to 1.6 m/s)
    assert np.abs(gt.velocity[span]).max() > 1.0
    np.testing.assert_allclose(truth.velocity, gt.velocity[span], rtol=0, atol=1e-14)


@pytest.mark.parametrize(
    ("milliseconds", "skipped"),
    [
        # 10 s in the future: only that message goes (the old rule kept it and dropped all after it).
        ([0, 1, 2, 10_003, 4, 5, 6], [(4, "stamp out of order")]),
        ([0, 1, 2, -4_000, 4, 5], [(4, "stamp going back")]),  # 4 s in the past
        ([0, 1, 1, 1, 2], [(3, "duplicate stamp"), (4, "duplicate stamp")]),
        # A block shifted back: the shorter side goes, whichever side that is.
        ([0, 1, 2, 3, 4, 5, 1.5, 2.5, 6], [(7, "stamp going back"), (8, "stamp going back")]),
        ([0, 1, 8, 9, 2, 3, 4, 5, 10], [(3, "stamp out of order"), (4, "stamp out of order")]),
    ],
)  # fmt: skip
def test_stamps_out_of_order_cost_only_the_fewest_messages(
    tmp_path: Path, milliseconds: list[float], skipped: list[tuple[int, str]]
) -> None:
    stamps_ns = [10 * 10**9 + round(ms * 10**6) for ms in milliseconds]
    path, _ = _stamped_imu_bag(tmp_path, "ros1", [divmod(ns, 10**9) for ns in stamps_ns])
    report = ReadReport()
    imu, _ = read_rosbag(path, on_bad_line="skip", report=report)
    assert [(s.line, s.kind) for s in report.skipped] == skipped
    kept = [k for k in range(len(stamps_ns)) if k + 1 not in {line for line, _ in skipped}]
    assert imu.gyro[:, 0].tolist() == [k + 1.0 for k in kept]  # message k + 1 has gyro x = k + 1
    assert imu.t_ns is not None and imu.t_ns.tolist() == [stamps_ns[k] for k in kept]


def test_a_future_stamp_message_names_the_stamp_it_comes_before(tmp_path: Path) -> None:
    path, _ = _stamped_imu_bag(tmp_path, "mcap", [(5, 0), (15, 10**6), (5, 2 * 10**6), (5, 3 * 10**6)])
    imu, _, report = raise_then_skip(  # "raise" names message 3, the first not after its predecessor
        path, r"topic /imu0, message 3: time must increase strictly, but 5\.002000000 follows 15\.001000000 "
        r"\(message 2\): header\.stamp 5\.002000000, angular_velocity 3\.0 ",
    )  # fmt: skip
    assert imu.gyro[:, 0].tolist() == [1.0, 3.0, 4.0]
    assert report.skipped == [
        SkippedLine(
            str(path),
            2,
            "stamp out of order: topic /imu0, message 2: time must increase strictly, but 15.001000000 comes "
            "before 5.002000000 (message 3)",
            "header.stamp 15.001000000, angular_velocity 2.0 0.0 0.0, linear_acceleration 0.0 0.0 9.81",
        )
    ]


@requires_euroc
def test_euroc_excerpt_bag_with_one_future_stamp_loses_only_that_message(tmp_path: Path) -> None:
    euroc = ik.io.read_euroc_imu(IMU_CSV)
    assert euroc.t_ns is not None
    stamps = euroc.t_ns.tolist()
    stamps[99] += 10 * 10**9  # message 100, 10 s late
    bag = Bag("ros1")
    # Record times in sample order: a bag is read in record-time order, the header stamp is the wild one.
    msgs = [
        (int(record), bag.imu(divmod(ns, 10**9), g, a))
        for record, ns, g, a in zip(euroc.t_ns, stamps, euroc.gyro, euroc.accel)
    ]
    path = bag.write(tmp_path / "euroc", {"/imu0": (IMU, msgs)})
    report = ReadReport()
    imu, _ = read_rosbag(path, on_bad_line="skip", report=report)
    assert [(s.line, s.kind) for s in report.skipped] == [(100, "stamp out of order")]
    others = np.delete(np.arange(len(euroc)), 99)
    assert len(imu) == 7998 and imu.t_ns is not None and np.array_equal(imu.t_ns, euroc.t_ns[others])
    assert bits(imu.gyro) == bits(euroc.gyro[others]) and bits(imu.accel) == bits(euroc.accel[others])


@pytest.mark.parametrize(("kind", "suffix"), [("ros1", ".BAG"), ("mcap-file", ".MCAP")])
def test_upper_case_suffixes_are_bags(kind: str, suffix: str, tmp_path: Path) -> None:
    # rosbags picks its reader by the suffix, case-sensitively; Windows copies often have .BAG.
    written, _ = _stamped_imu_bag(tmp_path, kind, [(4, 0), (4, 10**6)])
    path = written.rename(tmp_path / f"copy{suffix}")
    assert is_bag_path(path) and is_bag_path(str(path))
    assert not is_bag_path(tmp_path) and not is_bag_path(tmp_path / "absent.bag")  # a folder; no such file
    assert list_rosbag_topics(path) == {"/imu0": IMU}
    imu, _ = read_rosbag(path)
    assert imu.t_ns is not None and imu.t_ns.tolist() == [4 * 10**9, 4 * 10**9 + 10**6]


def test_data_the_imu_type_refuses_is_an_error_naming_the_bag(tmp_path: Path) -> None:
    # Stamps 1 ns apart are valid messages but not an IMU's nanoseconds (ImuData refuses a median step < 1 µs).
    path, _ = _stamped_imu_bag(tmp_path, "sqlite3", [(4, k) for k in range(3)])
    with pytest.raises(
        ik.io.FileFormatError, match=rf"^path: {re.escape(str(path))}: t: integer timestamps are read as nanoseconds"
    ):
        read_rosbag(path)
