"""ROS bags through the ``rosbags`` library: :func:`read_rosbag`, :func:`list_rosbag_topics`.

ROS 1 ``.bag`` files, ROS 2 bag folders (``metadata.yaml`` with sqlite3 or mcap storage) and bare
ROS 2 ``.mcap`` / ``.db3`` files. ``rosbags`` is an optional dependency (``pip install "imukit[ros]"``),
imported on the first call, not with :mod:`imukit.io`. Fields, frames and stamps: ``docs/io.md``.
"""

from __future__ import annotations

import math
import os
import tempfile
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Literal, NamedTuple, Union

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray
from imukit._errors import FileFormatError, ImukitError, MissingDependencyError, ParameterError
from imukit.imu import ImuData
from imukit.io._format import Format, Head
from imukit.io._lines import (
    NS_PER_S,
    Problem,
    as_file_error,
    in_order,
    ns_text,
    public_reader,
    read_into,
    rotations_from_rows,
    zero_quaternion,
)
from imukit.io._mag import with_mag
from imukit.io._report import BadLines, ReadReport
from imukit.state import Trajectory

__all__ = ["is_bag_path", "list_rosbag_topics", "read_rosbag"]

IMU_TYPE = "sensor_msgs/msg/Imu"
MAG_TYPE = "sensor_msgs/msg/MagneticField"
TESLA_TO_MICROTESLA = 1e6  # sensor_msgs/MagneticField is in tesla, ImuData.mag in µT
POSE_TYPES = ("geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/TransformStamped", "nav_msgs/msg/Odometry")
_SUFFIXES = (".bag", ".mcap", ".db3")


class _Sample(NamedTuple):
    """One message: its stamp [ns], its numbers, and what disqualifies it (None if nothing)."""

    stamp_ns: int
    clock: str
    """Where ``stamp_ns`` comes from: ``header.stamp`` or ``record time``."""
    values: tuple[float, ...]
    problem: Problem | None


_Values = tuple[tuple[float, ...], Union[Problem, None]]


def _imu_values(msg: Any) -> _Values:
    w, a = msg.angular_velocity, msg.linear_acceleration
    # sensor_msgs/Imu: element 0 of a covariance set to -1 means "this field is not provided".
    if msg.angular_velocity_covariance[0] == -1.0:
        return (), ("missing field", "no angular velocity (angular_velocity_covariance[0] = -1)")
    if msg.linear_acceleration_covariance[0] == -1.0:
        return (), ("missing field", "no linear acceleration (linear_acceleration_covariance[0] = -1)")
    return (w.x, w.y, w.z, a.x, a.y, a.z), None


def _pose_values(position: Any, orientation: Any, linear: Any = None) -> _Values:
    q = (orientation.x, orientation.y, orientation.z, orientation.w)
    velocity = () if linear is None else (linear.x, linear.y, linear.z)
    return (position.x, position.y, position.z, *q, *velocity), zero_quaternion(q)


# msgtype -> (its numbers and any problem, how they are printed in messages)
_DECODERS: dict[str, tuple[Callable[[Any], _Values], str]] = {
    IMU_TYPE: (_imu_values, "angular_velocity {0} {1} {2}, linear_acceleration {3} {4} {5}"),
    MAG_TYPE: (
        lambda m: ((m.magnetic_field.x, m.magnetic_field.y, m.magnetic_field.z), None),
        "magnetic_field {0} {1} {2}",
    ),
    "geometry_msgs/msg/PoseStamped": (
        lambda m: _pose_values(m.pose.position, m.pose.orientation),
        "position {0} {1} {2}, orientation {3} {4} {5} {6}",
    ),
    "geometry_msgs/msg/TransformStamped": (
        lambda m: _pose_values(m.transform.translation, m.transform.rotation),
        "translation {0} {1} {2}, rotation {3} {4} {5} {6}",
    ),
    "nav_msgs/msg/Odometry": (
        lambda m: _pose_values(m.pose.pose.position, m.pose.pose.orientation, m.twist.twist.linear),
        "position {0} {1} {2}, orientation {3} {4} {5} {6}, twist.linear {7} {8} {9}",
    ),
}


def is_bag_path(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a file named like a bag: ``.bag``, ``.mcap`` or ``.db3``, in any case."""
    bag = Path(path)
    return bag.is_file() and bag.suffix.lower() in _SUFFIXES


@contextmanager
def _open(path: str | os.PathLike[str], caller: str) -> Iterator[Any]:
    """The bag at ``path`` opened with ``rosbags``' AnyReader; errors become :class:`FileFormatError`."""
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError as e:
        raise MissingDependencyError(
            'needs the rosbags package, which is not installed (pip install "imukit[ros]")', argument=caller
        ) from e
    bag = Path(path)
    if not bag.exists():
        raise FileNotFoundError(f"path: {bag}: no such file or folder")
    if not (bag.is_dir() or is_bag_path(bag)):
        raise FileFormatError(
            f"{bag}: not a ROS bag; expected a ROS 1 .bag file, a ROS 2 bag folder (with metadata.yaml), "
            "or a ROS 2 .mcap / .db3 file",
            argument="path",
        )
    with _lower_case_suffix(bag) as readable:
        # Humble-era ROS 2 bags store no message definitions: fall back on the standard ones.
        try:
            reader = AnyReader([readable], default_typestore=get_typestore(Stores.LATEST))
            reader.open()
        # rosbags' parsers meet untrusted bytes here and fail with many kinds of exception on a
        # corrupt file (fuzzing found MemoryError for a huge record length, TypeError for a
        # truncated MCAP): each one means "not a bag we can open".
        except Exception as e:
            mcap = bag.suffix.lower() == ".mcap"
            hint = " (rosbags reads MCAP files of the ros2 profile, CDR-encoded, only)" if mcap else ""
            raise FileFormatError(f"{bag}: cannot open as a ROS bag{hint}: {e}", argument="path") from e
        try:
            yield reader
        except ImukitError:
            raise
        # Message data is as untrusted as the headers: a flipped byte in a chunk makes rosbags, its
        # decompressors and storage back ends raise KeyError, AssertionError, UnicodeDecodeError,
        # RuntimeError (LZ4), OSError (bz2), OverflowError (MCAP), apsw.CorruptError (sqlite3), ...
        # while the messages are iterated (16 % of bags with one flipped byte, issue 17).
        except Exception as e:
            raise FileFormatError(f"{bag}: corrupt ROS bag: {_cause(e)}", argument="path") from e
        finally:
            try:
                reader.close()
            except Exception:  # closing a corrupt bag can fail too; what was read stands or fell above
                pass


def _cause(e: BaseException) -> str:
    """``TypeName: message`` of a foreign exception, its message cut to 200 characters."""
    text = str(e)
    return f"{type(e).__name__}: {text if len(text) <= 200 else text[:197] + '...'}"


@contextmanager
def _lower_case_suffix(bag: Path) -> Iterator[Path]:
    """``bag``, or for a file named ``.BAG``, ``.Mcap``, … a link to it named with the lower-case suffix:
    rosbags tells ROS 1 from ROS 2, and the storage, by the suffix, case-sensitively."""
    suffix = bag.suffix.lower()
    if bag.is_dir() or bag.suffix == suffix:
        yield bag
        return
    with tempfile.TemporaryDirectory(prefix="imukit-bag-") as folder:
        link = Path(folder) / f"bag{suffix}"
        try:
            os.symlink(bag.resolve(), link)
        except OSError as e:  # e.g. Windows without the right to make links
            raise FileFormatError(
                f"{bag}: rosbags needs the suffix {suffix}, rename the file ({e})", argument="path"
            ) from e
        yield link


def _topics(reader: Any) -> dict[str, str]:
    return {
        topic: " | ".join(sorted({c.msgtype for c in info.connections}))
        for topic, info in sorted(reader.topics.items())
    }


def list_rosbag_topics(path: str | os.PathLike[str]) -> dict[str, str]:
    """The topics of a ROS bag and their message types, ``{"/imu0": "sensor_msgs/msg/Imu", ...}``.

    Sorted by topic; types are written the ROS 2 way (``pkg/msg/Type``), for ROS 1 bags too. A topic
    recorded with several types (possible in ROS 1) maps to them joined by ``" | "``. Accepts what
    :func:`read_rosbag` accepts and raises what it raises when opening the bag.
    """
    with _open(path, "list_rosbag_topics") as reader:
        return _topics(reader)


def _listing(topics: dict[str, str]) -> str:
    return ", ".join(f"{t} ({m})" for t, m in topics.items()) or "none"


def _select(
    reader: Any, topics: dict[str, str], requested: str | None, name: str, wanted: tuple[str, ...]
) -> str | None:
    """The topic to read for ``name`` (``imu_topic`` / ``groundtruth_topic``), or None when there is none.

    Only topics with messages are candidates: a recording often has an empty topic of a sensor that was off.
    """
    if requested is not None:
        if not isinstance(requested, str):
            raise ParameterError(f"expected a topic name or None, got {type(requested).__name__}", argument=name)
        if requested not in topics:
            raise ParameterError(
                f"topic {requested!r} is not in the bag; its topics: {_listing(topics)}", argument=name
            )
        if topics[requested] not in wanted:
            raise ParameterError(
                f"topic {requested!r} has type {topics[requested]}, expected {' or '.join(wanted)}", argument=name
            )
        return requested
    counts = {t: info.msgcount for t, info in reader.topics.items()}
    candidates = {t: m for t, m in topics.items() if m in wanted and counts[t] > 0}
    if len(candidates) > 1:
        raise ParameterError(
            f"the bag has {len(candidates)} candidate topics, pass one: {_listing(candidates)}", argument=name
        )
    return next(iter(candidates), None)


def _sample(reader: Any, msgtype: str, record_ns: int, raw: bytes, time_source: str, ros1: bool) -> _Sample:
    try:
        msg = reader.deserialize(raw, msgtype)
        values, problem = _DECODERS[msgtype][0](msg)
        sec, nanosec = int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)
        if ros1:  # ROS 1 time is unsigned; rosbags gives it as ROS 2's int32, negative after 2038-01-19
            sec %= 2**32
        values = tuple(map(float, values))
    except Exception as e:  # rosbags raises several types on corrupt data, none of them ours
        return _Sample(record_ns, "record time", (), ("malformed", f"cannot decode it ({_cause(e)})"))
    if problem is None and not all(map(math.isfinite, values)):
        problem = ("non-finite", "non-finite value")
    if time_source == "record":
        return _Sample(record_ns, "record time", values, problem)
    stamp_ns = sec * NS_PER_S + nanosec
    if problem is None and not 0 <= nanosec < NS_PER_S:
        problem = ("malformed", f"header.stamp.nanosec = {nanosec} is not below 10^9")
    if problem is None and stamp_ns == 0:
        problem = (
            "zero stamp",
            "header stamp is zero (unset by the publisher; time_source='record' reads record times)",
        )
    return _Sample(stamp_ns, "header.stamp", values, problem)


def _read_topic(
    reader: Any, topic: str, msgtype: str, time_source: str, where: str, bad: BadLines
) -> tuple[NDArray[np.int64], FloatArray]:
    """Stamps [ns] and value rows of the valid messages of ``topic``, in bag order; of their stamps, the
    longest strictly increasing subsequence is kept (:func:`imukit.io._lines.in_order`, as for text files)."""
    from rosbags.interfaces import ConnectionExtRosbag1  # imported: the bag is open

    connections = [c for c in reader.connections if c.topic == topic]
    publishers = sorted({str(c.ext.callerid) for c in connections if isinstance(c.ext, ConnectionExtRosbag1)})
    if len(publishers) > 1:
        # Two sensors on one topic would read as one stream alternating between them.
        warnings.warn(
            f"{where}, topic {topic}: {len(publishers)} publishers ({', '.join(publishers)}); their messages "
            "are read as one stream",
            stacklevel=4,
        )
    samples: list[_Sample] = []
    indices: list[int] = []  # the 1-based message index of each of samples
    index = 0
    for index, (connection, record_ns, raw) in enumerate(reader.messages(connections), start=1):
        ros1 = isinstance(connection.ext, ConnectionExtRosbag1)
        sample = _sample(reader, connection.msgtype, record_ns, raw, time_source, ros1)
        problem = sample.problem
        if problem is None and not bad.skip and samples and not samples[-1].stamp_ns < sample.stamp_ns:
            # "raise": the first message not after its predecessor, as the line readers report it.
            _, (disorder,) = in_order([samples[-1].stamp_ns, sample.stamp_ns], first=True)
            shown = [ns_text(samples[-1].stamp_ns), ns_text(sample.stamp_ns)]
            problem = disorder.kind, disorder.detail(shown, lambda _: f"message {indices[-1]}")
        if problem is None:
            samples.append(sample)
            indices.append(index)
        else:
            _bad_message(bad, where, topic, msgtype, index, sample, problem)
    keep, out = in_order([s.stamp_ns for s in samples])
    shown = [ns_text(s.stamp_ns) for s in samples]
    for d in out:
        detail = d.detail(shown, lambda k: f"message {indices[k]}")
        _bad_message(bad, where, topic, msgtype, indices[d.at], samples[d.at], (d.kind, detail))
    if not keep:
        left = f"no valid messages (all {index} skipped)" if index else "no messages"
        raise FileFormatError(f"{where}, topic {topic}: {left}", argument="path")
    stamps = np.array([samples[k].stamp_ns for k in keep], dtype=np.int64)
    return stamps, np.array([samples[k].values for k in keep], dtype=np.float64)


def _bad_message(
    bad: BadLines, where: str, topic: str, msgtype: str, index: int, sample: _Sample, problem: Problem
) -> None:
    """Message ``index`` of ``topic`` is bad: raise ``path: <bag>, topic <t>, message <n>: <detail>: <text>``,
    or record it with its stamp and values as the text."""
    text = f"{sample.clock} {ns_text(sample.stamp_ns)}"
    if sample.values:
        text += ", " + _DECODERS[msgtype][1].format(*map(repr, sample.values))
    detail = f"topic {topic}, message {index}: {problem[1]}"
    if not bad.skip:
        raise FileFormatError(f"{where}, {detail}: {text}", argument="path")
    bad.bad(where, index, problem[0], detail, text)


def _trajectory(where: str, t_ns: NDArray[np.int64], pose: FloatArray) -> Trajectory:
    # No line list: zero quaternions were skipped or raised already, message by message.
    rotation = rotations_from_rows(np.ascontiguousarray(pose[:, 3:7]), [], "")
    # nav_msgs/Odometry's twist is in child_frame_id (body) coordinates: v_w = R_wb v_b.
    velocity = rotation.apply(pose[:, 7:10]) if pose.shape[1] == 10 else None
    return as_file_error(where, lambda: Trajectory(None, pose[:, :3], velocity, rotation, t_ns=t_ns))


def rosbag(
    path: str | os.PathLike[str],
    bad: BadLines,
    *,
    imu_topic: str | None,
    groundtruth_topic: str | None,
    time_source: str,
    mag_topic: str | Literal[False] | None = None,
) -> tuple[ImuData, Trajectory | None]:
    """:func:`read_rosbag` reporting to ``bad``."""
    if time_source not in ("header", "record"):
        raise ParameterError(f"expected 'header' or 'record', got {time_source!r}", argument="time_source")
    where = os.fspath(path)
    with _open(path, "read_rosbag") as reader:
        topics = _topics(reader)
        imu_name = _select(reader, topics, imu_topic, "imu_topic", (IMU_TYPE,))
        if imu_name is None:
            raise ParameterError(
                f"the bag has no {IMU_TYPE} topic with messages; its topics: {_listing(topics)}", argument="imu_topic"
            )
        truth_name = _select(reader, topics, groundtruth_topic, "groundtruth_topic", POSE_TYPES)
        mag_name = _mag_topic(reader, topics, mag_topic)
        t_ns, rows = _read_topic(reader, imu_name, IMU_TYPE, time_source, where, bad)
        imu = as_file_error(where, lambda: ImuData(t_ns, rows[:, :3], rows[:, 3:]))
        if mag_name is not None:
            hint = "pass mag_topic=False to read the bag without its magnetometer"
            mark = len(bad.records)
            try:
                m_ns, m_rows = _read_topic(reader, mag_name, MAG_TYPE, time_source, where, bad)
                imu = with_mag(imu, m_ns, m_rows * TESLA_TO_MICROTESLA, f"{where}, topic {mag_name}", hint)
            except FileFormatError as e:
                if mag_topic is not None:
                    raise
                # Found, not asked for: the IMU (and ground truth) read as before this reader knew
                # magnetometers; the report is of what was read, so the topic's skipped messages
                # leave it.
                del bad.records[mark:]
                warnings.warn(f"magnetometer not read: {e.message}", stacklevel=3)
        truth = None
        if truth_name is not None:
            truth = _trajectory(where, *_read_topic(reader, truth_name, topics[truth_name], time_source, where, bad))
    return imu, truth


def _mag_topic(reader: Any, topics: dict[str, str], requested: str | Literal[False] | None) -> str | None:
    """The magnetometer topic to read: ``requested``, none for False, else the bag's only one with
    messages (several: none, with a warning naming them, so that a bag read before still reads)."""
    if requested is False:
        return None
    if requested is not None:
        return _select(reader, topics, requested, "mag_topic", (MAG_TYPE,))
    found = [t for t, m in topics.items() if m == MAG_TYPE and reader.topics[t].msgcount > 0]
    if len(found) > 1:
        warnings.warn(
            f"the bag has {len(found)} {MAG_TYPE} topics ({', '.join(found)}): none read; pass mag_topic=",
            stacklevel=4,
        )
    return found[0] if len(found) == 1 else None


@public_reader(rosbag)
def read_rosbag(  # type: ignore[empty-body]
    path: str | os.PathLike[str],
    *,
    imu_topic: str | None = None,
    groundtruth_topic: str | None = None,
    time_source: Literal["header", "record"] = "header",
    mag_topic: str | Literal[False] | None = None,
    on_bad_line: Literal["raise", "skip"] = "raise",
    report: ReadReport | None = None,
) -> tuple[ImuData, Trajectory | None]:
    """Read IMU samples (with the magnetometer, and ground truth, when the bag has them) from a ROS 1
    or ROS 2 bag.

    Parameters
    ----------
    path
        A ROS 1 ``.bag`` file, a ROS 2 bag folder (``metadata.yaml`` and sqlite3 or mcap storage),
        or a bare ROS 2 ``.mcap`` / ``.db3`` file.
    imu_topic
        The ``sensor_msgs/msg/Imu`` topic to read. None: the bag's only Imu topic; none or several
        is a :class:`ParameterError` listing the topics with their types.
    groundtruth_topic
        A ``geometry_msgs/msg/PoseStamped``, ``geometry_msgs/msg/TransformStamped`` or
        ``nav_msgs/msg/Odometry`` topic. None: the bag's only such topic, or no ground truth when it
        has none; several is a :class:`ParameterError` listing them.
    time_source
        ``"header"``: each message's ``header.stamp``, the acquisition time the driver wrote; a zero
        stamp is a bad message. ``"record"``: the time the recorder received the message, for bags
        whose driver leaves ``header.stamp`` unset (transport delay and jitter then enter every dt).
    mag_topic
        A ``sensor_msgs/msg/MagneticField`` topic, read into ``imu.mag`` [µT] (the message is in
        tesla) and matched to the IMU stamps: linear interpolation between the magnetometer messages
        around each IMU stamp, the message itself where the stamps coincide; an IMU sample outside the
        magnetometer's span or in a gap over ``GAP_FACTOR`` median steps is a
        :class:`FileFormatError`. None: the bag's only MagneticField topic with messages (none, or
        several, or one that does not cover the IMU samples: no magnetometer, with a warning saying
        why in the last two cases); False: no magnetometer.
    on_bad_line
        ``"raise"``: the first bad message is a :class:`FileFormatError` ``path: <bag>, topic <t>,
        message <n>: …``, n being the 1-based index of the message on its topic in bag order.
        ``"skip"``: bad messages are skipped and recorded as :class:`SkippedLine` (``line`` = that
        index, ``text`` = the stamp and values) in ``report``, or summarised in one
        :class:`SkippedLinesWarning` without one. Bad: undecodable (``malformed``), a non-finite
        value, a field flagged absent (covariance element 0 = -1: ``missing field``), a zero
        quaternion, a zero stamp, ``nanosec`` ≥ 10⁹ (``malformed``), and stamps out of order: of the
        stamps of the other messages, the longest strictly increasing subsequence is kept (the earliest
        messages among equally long ones), the rest are ``duplicate stamp``, ``stamp going back`` or
        ``stamp out of order`` (a stamp from the future: it alone is skipped), as in the text readers.
    report
        A :class:`ReadReport` that receives the skipped messages.

    Returns
    -------
    imu
        :class:`imukit.ImuData` with int64 ``t_ns``: ``angular_velocity`` → ``gyro`` [rad/s],
        ``linear_acceleration`` → ``accel`` [m/s²], in the message's (body) frame, and ``mag`` [µT]
        (see ``mag_topic``). The message's orientation and covariances are not read (except the -1
        flag above).
    truth
        :class:`imukit.Trajectory` with ``t_ns``, or None: the pose (``PoseStamped.pose``,
        ``Odometry.pose.pose``, or the ``TransformStamped`` transform, which maps ``child_frame_id``
        coordinates to ``header.frame_id``) as ``position`` and ``rotation`` ``R_wb``. A velocity only
        from Odometry, whose twist is in ``child_frame_id`` (body) coordinates (REP 103,
        nav_msgs/Odometry): it is rotated to the world, ``v_w = R_wb v_b``.

    Raises
    ------
    MissingDependencyError
        ``rosbags`` is not installed.
    FileNotFoundError, FileFormatError, ParameterError
        No such path; not a readable bag, a bad message, a topic without valid messages; a topic
        that is missing, of the wrong type or ambiguous, or a bad option.
    """


def _detected(path: str | os.PathLike[str], bad: BadLines, **options: Any) -> tuple[ImuData, Trajectory | None]:
    """:func:`read_rosbag` for :func:`imukit.io.read_imu`, looked up when called (tests replace it)."""
    return read_into(bad, read_rosbag, path, **options)


def _bag_like(path: Path, head: Head) -> bool:
    return (path.is_dir() and (path / "metadata.yaml").is_file()) or is_bag_path(path)


ROSBAG = Format(
    "rosbag", "imu", _bag_like, _detected, "ROS bag", options=("imu_topic", "groundtruth_topic", "time_source")
)
