"""Coverage-guided fuzzing of imukit's file readers with atheris (issue 9, ``make fuzz``).

Every input is one file (or folder) handed to one reader:

- byte 0 picks the reader (:data:`READERS`, modulo their number);
- byte 1 holds option bits: bit 0 ``on_bad_line="skip"`` (else ``"raise"``), bits 1-7 the options of
  :func:`imukit.io.read_imu_csv` (units, delimiter, columns by name or index); bit 1 also picks the
  file name of the detecting readers (``.txt`` or ``.csv``) and of :func:`imukit.io.read_rosbag`
  (``.mcap`` or ``.bag``);
- the rest is the file content; readers of two files (folders with ground truth, KITTI poses and
  times) split it at the first NUL byte.

The contract checked (:func:`check_input`): a reader either returns a valid result (finite samples
and poses, strictly increasing stamps) or raises an :class:`imukit.ImukitError`; any other
exception, and any numpy ``RuntimeWarning`` (a silent overflow or NaN), is a finding.

Usage::

    .venv/bin/python fuzz/python/fuzz_readers.py -max_total_time=60 fuzz/corpus/readers

Without corpus files the seeds of :func:`seeds` (valid files of every format) are written to the
first corpus folder given. ``tests/test_fuzz_regressions.py`` replays the inputs kept in
``fuzz/python/regressions/`` through :func:`check_input`.
"""

from __future__ import annotations

import inspect
import os
import shutil
import sys
import tempfile
import traceback
import types
import warnings
from pathlib import Path
from typing import Any, Callable, Literal, NamedTuple, TypedDict

import numpy as np

from imukit import ImuData, ImukitError, Trajectory, io

Result = object


class Case(NamedTuple):
    """The reader's arguments decoded from one input."""

    folder: Path
    first: bytes
    second: bytes
    skip: bool
    options: int
    whole: bytes
    """The content unsplit (a bag holds NUL bytes)."""


def _file(case: Case, name: str, content: bytes) -> Path:
    path = case.folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(content)
    return path


class _ReadOptions(TypedDict):
    on_bad_line: Literal["raise", "skip"]
    report: io.ReadReport


def _kwargs(case: Case) -> _ReadOptions:
    return {"on_bad_line": "skip" if case.skip else "raise", "report": io.ReadReport()}


def _euroc_imu(case: Case) -> Result:
    return io.read_euroc_imu(_file(case, "data.csv", case.first), **_kwargs(case))


def _euroc_groundtruth(case: Case) -> Result:
    return io.read_euroc_groundtruth(_file(case, "data.csv", case.first), **_kwargs(case))


def _folder(case: Case, truth: str) -> Path:
    # A downloaded-sequence layout: mav0/imu0/data.csv and, when given, the ground-truth CSV.
    _file(case, "mav0/imu0/data.csv", case.first)
    if case.second:
        _file(case, f"mav0/{truth}/data.csv", case.second)
    return case.folder


def _euroc_folder(case: Case) -> Result:
    return io.read_euroc(_folder(case, "state_groundtruth_estimate0"), **_kwargs(case))


def _tum(case: Case) -> Result:
    return io.read_tum(_file(case, "traj.txt", case.first), **_kwargs(case))


def _kalibr(case: Case) -> Result:
    return io.read_kalibr_imu(_file(case, "imu.yaml", case.first))


def _gtsam(case: Case) -> Result:
    return io.read_gtsam_imu(_file(case, "imu.txt", case.first), **_kwargs(case))


def _tumvi(case: Case) -> Result:
    return io.read_tumvi(_folder(case, "mocap0"), **_kwargs(case))


def _kitti(case: Case) -> Result:
    poses = _file(case, "poses.txt", case.first)
    times = _file(case, "times.txt", case.second)
    return io.read_kitti_poses(poses, times, **_kwargs(case))


_TIME_UNITS: tuple[Literal["s", "ms", "us", "ns"], ...] = ("s", "ms", "us", "ns")
_DELIMITERS = (None, ",", ";", "\t", " ", None, None, None)


def _imu_csv(case: Case) -> Result:
    bits = case.options >> 1
    by_name = bool(bits & 1)
    names = ("t", ["wx", "wy", "wz"], ["ax", "ay", "az"])
    time_column, gyro_columns, accel_columns = names if by_name else (0, [1, 2, 3], [4, 5, 6])
    return io.read_imu_csv(
        _file(case, "imu.csv", case.first),
        time_column=time_column,
        gyro_columns=gyro_columns,
        accel_columns=accel_columns,
        time_unit=_TIME_UNITS[(bits >> 1) & 3],
        gyro_unit="deg/s" if bits & 8 else "rad/s",
        accel_unit="g" if bits & 16 else "m/s^2",
        delimiter=_DELIMITERS[(bits >> 5) & 7] if bits & 64 else None,
        **_kwargs(case),
    )


def _detect_imu_file(case: Case) -> Result:
    return io.read_imu(_file(case, "imu.txt" if case.options & 2 else "data.csv", case.first), **_kwargs(case))


def _detect_trajectory(case: Case) -> Result:
    return io.read_trajectory(_file(case, "traj.txt" if case.options & 2 else "data.csv", case.first), **_kwargs(case))


def _rosbag(case: Case) -> Result:
    # The extension picks the container: ROS 1 bag, MCAP or ROS 2 sqlite3 (rosbags parses all three).
    name = "imu.mcap" if case.options & 2 else "imu.db3" if case.options & 4 else "imu.bag"
    return io.read_rosbag(_file(case, name, case.whole), **_kwargs(case))


READERS: tuple[tuple[str, Callable[[Case], Result]], ...] = (
    ("read_euroc_imu", _euroc_imu),
    ("read_euroc_groundtruth", _euroc_groundtruth),
    ("read_euroc", _euroc_folder),
    ("read_tum", _tum),
    ("read_kalibr_imu", _kalibr),
    ("read_gtsam_imu", _gtsam),
    ("read_tumvi", _tumvi),
    ("read_kitti_poses", _kitti),
    ("read_imu_csv", _imu_csv),
    ("read_imu", _detect_imu_file),
    ("read_trajectory", _detect_trajectory),
    ("read_rosbag", _rosbag),
)


class ContractError(AssertionError):
    """A reader broke the contract: a valid-looking result that is not valid."""


def _increasing(t: np.ndarray, what: str) -> None:
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise ContractError(f"{what}: stamps not strictly increasing")


def _check_imu(imu: ImuData) -> None:
    if len(imu) < 1:
        raise ContractError("ImuData without samples")
    for name in ("t", "gyro", "accel"):
        if not np.all(np.isfinite(getattr(imu, name))):
            raise ContractError(f"ImuData.{name} holds a non-finite value")
    _increasing(imu.t if imu.t_ns is None else imu.t_ns, "ImuData")


def _check_trajectory(trajectory: Trajectory) -> None:
    if not np.all(np.isfinite(trajectory.position)):
        raise ContractError("Trajectory.position holds a non-finite value")
    quat = trajectory.rotation.as_quat()
    if not np.all(np.isfinite(quat)):
        raise ContractError("Trajectory.rotation holds a non-finite value")
    _increasing(trajectory.t if trajectory.t_ns is None else trajectory.t_ns, "Trajectory")


def _check_result(result: Result) -> None:
    parts = result if isinstance(result, tuple) else (result,)
    for part in parts:
        if isinstance(part, ImuData):
            _check_imu(part)
        elif isinstance(part, Trajectory):
            _check_trajectory(part)


def decode(data: bytes, folder: Path) -> tuple[str, Callable[[Case], Result], Case]:
    """The reader an input selects and its arguments (module docs)."""
    name, reader = READERS[data[0] % len(READERS)] if data else READERS[0]
    options = data[1] if len(data) > 1 else 0
    first, _, second = data[2:].partition(b"\0")
    return name, reader, Case(folder, first, second, bool(options & 1), options, data[2:])


def check_input(data: bytes) -> None:
    """Runs one input; raises (a finding) unless the reader returns a valid result or an ImukitError."""
    folder = Path(tempfile.mkdtemp(prefix="imukit-fuzz-", dir=_scratch()))
    try:
        _, reader, case = decode(data, folder)
        with warnings.catch_warnings():
            # numpy's overflow / invalid-value warnings mean a silent inf or NaN: make them raise.
            warnings.simplefilter("error", RuntimeWarning)
            try:
                result = reader(case)
            except ImukitError:
                return
        _check_result(result)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _scratch() -> str | None:
    # RAM-backed where available: the fuzzer writes a file per input.
    return "/dev/shm" if os.path.isdir("/dev/shm") else None


def seeds() -> list[bytes]:
    """Valid inputs of every reader (byte 0: reader, byte 1: options, then the content)."""
    index = {name: i for i, (name, _) in enumerate(READERS)}
    imu = (
        b"#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
        b"a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
        b"1403636579758555392,-0.099,0.14,0.025,8.1,-0.37,-2.4\n"
        b"1403636579763555584,-0.098,0.13,0.026,8.2,-0.38,-2.5\n"
        b"1403636579768555520,-0.097,0.12,0.027,8.3,-0.39,-2.3\n"
    )
    groundtruth = (
        b"#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [],"
        b" v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1],"
        b" b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2],"
        b" b_a_RS_S_z [m s^-2]\n"
        b"1403636580838555648,4.688,-1.786,0.783,0.534,-0.153,-0.827,-0.082,-0.027,0.033,-0.8,"
        b"-0.003,0.021,0.078,-0.025,0.136,0.076\n"
        b"1403636580843555328,4.688,-1.786,0.783,0.534,-0.153,-0.827,-0.082,-0.026,0.034,-0.8,"
        b"-0.003,0.021,0.078,-0.025,0.136,0.076\n"
    )
    mocap = b"#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n"
    mocap += b"1403636579758555392,1.0,2.0,3.0,1.0,0.0,0.0,0.0\n1403636579768555520,1.1,2.0,3.0,1.0,0.0,0.0,0.0\n"
    tum = b"# timestamp tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.01 0.1 0 0 0 0 0.0499792 0.9987503\n"
    kalibr = (
        b"rostopic: /imu0\nupdate_rate: 200.0\naccelerometer_noise_density: 2.0e-3\n"
        b"accelerometer_random_walk: 3.0e-3\ngyroscope_noise_density: 1.7e-4\ngyroscope_random_walk: 1.9e-5\n"
    )
    gtsam = b"Time dt accelX accelY accelZ omegaX omegaY omegaZ\n0.00 0.01 0.1 0.2 9.8 0.01 0.02 0.03\n"
    gtsam += b"0.01 0.01 0.1 0.2 9.8 0.01 0.02 0.03\n0.02 0.01 0.1 0.2 9.8 0.01 0.02 0.03\n"
    kitti_poses = b"1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0.5 0 1 0 0 0 0 1 0\n"
    kitti_times = b"0.0\n0.1\n"
    csv_named = b"t,wx,wy,wz,ax,ay,az\n0.0,0.1,0.2,0.3,0,0,9.8\n0.01,0.1,0.2,0.3,0,0,9.8\n"
    csv_plain = b"0;0.1;0.2;0.3;0;0;9.8\n1;0.1;0.2;0.3;0;0;9.8\n"

    def make(name: str, options: int, *files: bytes) -> bytes:
        return bytes([index[name], options]) + b"\0".join(files)

    return [
        make("read_euroc_imu", 0, imu),
        make("read_euroc_imu", 1, imu + b"1403636579768555520,nan,0,0,0,0,0\n"),
        make("read_euroc_groundtruth", 0, groundtruth),
        make("read_euroc", 1, imu, groundtruth),
        make("read_tum", 0, tum),
        make("read_kalibr_imu", 0, kalibr),
        make("read_gtsam_imu", 1, gtsam),
        make("read_tumvi", 0, imu, mocap),
        make("read_kitti_poses", 0, kitti_poses, kitti_times),
        make("read_imu_csv", 0b10, csv_named),
        make("read_imu_csv", 0b1000_0101, csv_plain),
        make("read_imu", 2, gtsam),
        make("read_imu", 0, imu),
        make("read_trajectory", 2, tum),
        make("read_trajectory", 0, groundtruth),
    ]


def rosbag_seeds() -> list[bytes]:
    """Valid bags for :func:`imukit.io.read_rosbag`, written by rosbags, one per container: ROS 1
    plain, LZ4 and BZ2 chunks, ROS 2 sqlite3 and MCAP (bare files), each an Imu and a PoseStamped
    topic, so that mutations reach the chunk, index and message data (issue 17), not only the headers.
    """
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    index = [name for name, _ in READERS].index("read_rosbag")
    found = []
    with tempfile.TemporaryDirectory() as folder:
        for container, option in (("ros1", 0), ("lz4", 0), ("bz2", 0), ("sqlite3", 4), ("mcap", 2)):
            ros1 = option == 0
            store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
            path = Path(folder, container + (".bag" if ros1 else ""))
            plugin = None if ros1 else StoragePlugin[container.upper()]
            writer = Writer1(path) if ros1 else Writer2(path, version=9, storage_plugin=plugin)
            if container in ("lz4", "bz2"):
                writer.set_compression(Writer1.CompressionFormat[container.upper()])
            serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
            with writer:
                for topic, msgtype, make in (("/imu0", "sensor_msgs/msg/Imu", _imu_msg), ("/pose", _POSE, _pose_msg)):
                    connection = writer.add_connection(topic, msgtype, typestore=store)
                    for k in range(4):
                        stamp = 1_403_636_579_758_555_392 + k * 5_000_000
                        writer.write(connection, stamp, serialize(make(store, stamp, k, ros1), msgtype))
            data = path if ros1 else next(p for p in path.iterdir() if p.suffix in (".db3", ".mcap"))
            found.append(bytes([index, option]) + data.read_bytes())
    return found


_POSE = "geometry_msgs/msg/PoseStamped"


def _header(store: Any, stamp: int, ros1: bool) -> Any:
    time = store.types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9)
    return store.types["std_msgs/msg/Header"](**({"seq": 0} if ros1 else {}), stamp=time, frame_id="imu")


def _imu_msg(store: Any, stamp: int, k: int, ros1: bool) -> Any:
    t = store.types
    vector, quat = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Quaternion"]
    return t["sensor_msgs/msg/Imu"](
        header=_header(store, stamp, ros1),
        orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.zeros(9),
        angular_velocity=vector(x=0.1 * k, y=-0.2, z=0.3),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=vector(x=0.0, y=0.1, z=9.81),
        linear_acceleration_covariance=np.zeros(9),
    )


def _pose_msg(store: Any, stamp: int, k: int, ros1: bool) -> Any:
    t = store.types
    pose = t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=float(k), y=0.0, z=1.0),
        orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
    )
    return t[_POSE](header=_header(store, stamp, ros1), pose=pose)


def signature(error: BaseException) -> str:
    """``Type at file:line`` of the innermost imukit frame of a finding (one line per distinct bug)."""
    frames = traceback.extract_tb(error.__traceback__)
    inside = [f for f in frames if "imukit" in f.filename and "fuzz_readers" not in f.filename] or frames
    last = inside[-1]
    return f"{type(error).__name__} at {Path(last.filename).name}:{last.lineno}"


def _known() -> set[str]:
    # IMUKIT_FUZZ_KNOWN names a file of signatures already reported: keep fuzzing past them.
    path = os.environ.get("IMUKIT_FUZZ_KNOWN")
    return set(Path(path).read_text().splitlines()) if path and os.path.exists(path) else set()


_KNOWN = _known()


def _test_one_input(data: bytes) -> None:
    try:
        check_input(data)
    except Exception as error:
        if signature(error) in _KNOWN:
            return
        print(f"FINDING {signature(error)}", file=sys.stderr)
        raise


def _instrument_imukit(atheris: types.ModuleType) -> None:
    # Coverage of imukit's own Python code only: instrumenting numpy and scipy as well
    # (atheris.instrument_all) takes minutes and steers the fuzzer into their internals.
    for name, module in list(sys.modules.items()):
        if not name.startswith("imukit") or module is None:
            continue
        for _, member in inspect.getmembers(module):
            owned = getattr(member, "__module__", None) == name
            if inspect.isfunction(member) and owned:
                atheris.instrument_func(member)
            elif inspect.isclass(member) and owned:
                for _, method in inspect.getmembers(member, inspect.isfunction):
                    if method.__module__ == name:
                        atheris.instrument_func(method)


def main(argv: list[str]) -> None:
    """Fuzz with libFuzzer flags and corpus folders as in ``argv``."""
    # Imported here: only the fuzzer needs it, not the regression tests.
    import atheris  # type: ignore[import-untyped]

    corpora = [Path(a) for a in argv[1:] if not a.startswith("-")]
    if corpora and not any(corpora[0].glob("*")):
        corpora[0].mkdir(parents=True, exist_ok=True)
        for i, seed in enumerate(seeds() + rosbag_seeds()):
            (corpora[0] / f"seed-{i:02d}").write_bytes(seed)
    _instrument_imukit(atheris)
    atheris.Setup(argv, _test_one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main(sys.argv)
