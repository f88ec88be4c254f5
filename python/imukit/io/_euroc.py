"""EuRoC / ASL dataset folders: :func:`write_euroc`, :func:`read_euroc` and its two CSV readers.

Frames (``docs/io.md``): ``R`` is EuRoC's world (the motion-capture reference), ``S`` the IMU
sensor, which is imukit's body frame ``b``; ``q_RS`` is imukit's ``R_wb`` written scalar first.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray
from imukit._errors import FileFormatError, ParameterError, TimestampError
from imukit.imu import ImuBias, ImuData, ImuNoise, _rate
from imukit.io._blocks import Layout, increasing_table, read_table, zero_quaternions
from imukit.io._format import Format, Head
from imukit.io._kalibr import KalibrImu, noise_lines, read_kalibr_imu, shown, yaml_float
from imukit.io._lines import (
    INT64_MAX,
    INT64_MIN,
    Problem,
    as_file_error,
    atomic,
    integer_stamp,
    public_reader,
    rotations_from_rows,
    write_rows,
    zero_quaternion,
)
from imukit.io._mag import with_mag
from imukit.io._named_csv import FixedLayout, departure, header_names, imu_roles
from imukit.io._report import BadLines, OnBadLine, ReadReport
from imukit.io._trajectory_csv import trajectory_columns
from imukit.state import Trajectory

__all__ = ["read_euroc", "read_euroc_groundtruth", "read_euroc_imu", "read_euroc_sensor", "write_euroc"]

# The header lines of the EuRoC files, character for character.
IMU_HEADER = (
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
)
GROUNDTRUTH_HEADER = (
    "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
    "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], "
    "b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], "
    "b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]"
)


def _pose_roles(names: list[str]) -> dict[str, list[int]] | None:
    """``trajectory_columns``' time, position and quaternion (x, y, z, w) columns, or None."""
    found = trajectory_columns(names)
    if found is None:
        return None
    return {
        "time": [found["time_column"]],
        "position": found["position_columns"],
        "quaternion": found["quaternion_columns"],
    }


# The layouts as headers naming their columns would say them: a file whose header names others (its
# own account of its columns: `#timestamp,acc_x,…` or `[deg/s]`) is not read by position.
IMU_NAMES = FixedLayout(
    imu_roles,
    {"time": [0], "gyro": [1, 2, 3], "accel": [4, 5, 6]},
    {"time": "ns", "gyro": "rad/s", "accel": "m/s^2"},
    "imukit.io.read_imu (or read_imu_csv)",
)
POSE_NAMES = FixedLayout(
    _pose_roles,
    {"time": [0], "position": [1, 2, 3], "quaternion": [5, 6, 7, 4]},
    {"time": "ns"},
    "imukit.io.read_trajectory (or read_trajectory_csv)",
)

# imukit's magnetometer file (EuRoC has none): one row per IMU row, same stamps, body frame S.
MAG_HEADER = "#timestamp [ns],m_S_x [uT],m_S_y [uT],m_S_z [uT]"
IMU_CSV = Path("imu0", "data.csv")
MAG_CSV = Path("mag0", "data.csv")
GROUNDTRUTH_CSV = Path("state_groundtruth_estimate0", "data.csv")
SENSOR_YAML = Path("imu0", "sensor.yaml")

# EuRoC's imu0/sensor.yaml layout; the IMU is the body frame, so T_BS is the identity.
_SENSOR_YAML_HEAD = """\
# EuRoC / ASL imu0 sensor file, written by imukit
sensor_type: imu
comment: written by imukit

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0,
         0.0, 1.0, 0.0, 0.0,
         0.0, 0.0, 1.0, 0.0,
         0.0, 0.0, 0.0, 1.0]
"""


def write_euroc(
    folder: str | os.PathLike[str],
    imu: ImuData,
    truth: Trajectory | None = None,
    *,
    epoch_ns: int | None = None,
    truth_bias: ImuBias | None = None,
    noise: ImuNoise | None = None,
    rate_hz: float | None = None,
) -> None:
    """Write ``imu`` (and ``truth``) as an EuRoC / ASL folder: ``imu0/data.csv`` and
    ``state_groundtruth_estimate0/data.csv``, with EuRoC's header lines (columns in ``docs/io.md``),
    and ``imu.mag`` when present as ``mag0/data.csv`` (``#timestamp [ns],m_S_x [uT],…``, the IMU's
    stamps; imukit's layout, EuRoC has no magnetometer).

    Parameters
    ----------
    folder
        Created if needed (EuRoC's own folders are called ``mav0``); the files are overwritten and
        other files left alone, so without ``truth`` an older ground-truth file would stay.
    imu
        The samples. Stamps are ``imu.t_ns`` when present, else ``t`` converted as below.
    truth
        Ground truth at its own stamps (``t_ns``, else ``t`` converted as below). It needs a
        velocity, and bias histories (``gyro_bias``, ``accel_bias``) unless ``truth_bias`` is given.
        Quaternions are written scalar first, as stored by the ``Rotation`` (not canonicalised).
    epoch_ns
        Integer nanoseconds added to float-second stamps: ``t_ns = epoch_ns + round(t · 10⁹)``,
        rounded to the nearest nanosecond (``t`` split into whole seconds and fraction first, so
        epoch seconds lose nothing more). Default 0. Stamps that already are ``t_ns`` are written
        as they are; passing ``epoch_ns`` when there is no float stamp to offset is an error.
    truth_bias
        A constant bias written in every ground-truth row, for a ``truth`` without bias histories
        (``ImuBias()`` writes zeros); an error when ``truth`` has histories.
    noise, rate_hz
        Give both to also write ``imu0/sensor.yaml`` in EuRoC's layout (Kalibr's noise keys,
        ``rate_hz``; read back with :func:`imukit.io.read_kalibr_imu`).

    Floats are printed with ``repr``, so :func:`read_euroc` gives back every value bit for bit.

    Raises
    ------
    ParameterError, TimestampError
        Before anything is written: a missing velocity or bias, ``noise`` without ``rate_hz``,
        ``epoch_ns`` not an integer or unused, stamps outside int64 nanoseconds, or two float stamps
        on the same nanosecond.
    TypeError
        ``imu``, ``truth``, ``truth_bias`` or ``noise`` of the wrong type.
    """
    if not isinstance(imu, ImuData):
        raise TypeError(f"imu: expected an imukit ImuData, got {type(imu).__name__}")
    if truth is not None and not isinstance(truth, Trajectory):
        raise TypeError(f"truth: expected an imukit Trajectory or None, got {type(truth).__name__}")
    if (noise is None) != (rate_hz is None):
        raise ParameterError("give noise and rate_hz together (for imu0/sensor.yaml), or neither", argument="noise")
    rate = None if rate_hz is None else _rate(rate_hz)
    if noise is not None and not isinstance(noise, ImuNoise):
        raise TypeError(f"noise: expected an imukit ImuNoise, got {type(noise).__name__}")
    if epoch_ns is not None and imu.t_ns is not None and (truth is None or truth.t_ns is not None):
        raise ParameterError(
            "offsets float-second stamps, but every stream given has t_ns already", argument="epoch_ns"
        )
    epoch = _epoch(epoch_ns)
    imu_ns = _stamps_ns(imu.t_ns, imu.t, epoch, "imu")
    gt_rows = None if truth is None else _groundtruth_rows(truth, truth_bias, epoch)
    if truth is None and truth_bias is not None:
        raise ParameterError("given without truth", argument="truth_bias")

    root = Path(folder)
    (root / IMU_CSV).parent.mkdir(parents=True, exist_ok=True)
    # Each file under a temporary name, renamed when complete; imu0/data.csv, which makes the folder a
    # dataset, last: an interrupted write (Ctrl-C in `imukit simulate`) never reads back as a valid,
    # shorter dataset without its ground truth.
    if noise is not None and rate is not None:
        _write_sensor_yaml(root / SENSOR_YAML, noise, rate)
    if imu.mag is not None:
        (root / MAG_CSV).parent.mkdir(parents=True, exist_ok=True)
        write_rows(root / MAG_CSV, MAG_HEADER, map(str, imu_ns.tolist()), imu.mag, ",")
    if gt_rows is not None:
        (root / GROUNDTRUTH_CSV).parent.mkdir(parents=True, exist_ok=True)
        write_rows(root / GROUNDTRUTH_CSV, GROUNDTRUTH_HEADER, map(str, gt_rows[0].tolist()), gt_rows[1], ",")
    write_rows(root / IMU_CSV, IMU_HEADER, map(str, imu_ns.tolist()), np.hstack([imu.gyro, imu.accel]), ",")


def _write_sensor_yaml(path: Path, noise: ImuNoise, rate: float) -> None:
    """EuRoC's ``imu0/sensor.yaml``: its layout and key order, imukit's exact floats."""
    rate_text = str(int(rate)) if rate.is_integer() else yaml_float(rate)  # EuRoC writes "rate_hz: 200"
    keys = ["gyroscope_noise_density", "gyroscope_random_walk", "accelerometer_noise_density"]
    body = [f"rate_hz: {rate_text}", "", "# inertial sensor noise model parameters (static)"]
    body += noise_lines(noise, [*keys, "accelerometer_random_walk"])
    with atomic(path) as temporary, open(temporary, "w", encoding="ascii", newline="\n") as f:
        f.write(_SENSOR_YAML_HEAD + "\n".join(body) + "\n")


def _groundtruth_rows(
    truth: Trajectory, truth_bias: ImuBias | None, epoch: int
) -> tuple[NDArray[np.int64], FloatArray]:
    if truth.velocity is None:
        raise ParameterError("has no velocity, but EuRoC's ground truth has v_RS_R columns", argument="truth")
    if truth.gyro_bias is None or truth.accel_bias is None:
        if truth_bias is None:
            raise ParameterError(
                "has no gyro_bias / accel_bias histories for EuRoC's b_w_RS_S / b_a_RS_S columns; "
                "pass truth_bias=ImuBias(...) to write a constant bias (ImuBias() for zeros)",
                argument="truth",
            )
        if not isinstance(truth_bias, ImuBias):
            raise TypeError(f"truth_bias: expected an imukit ImuBias, got {type(truth_bias).__name__}")
        n = len(truth)
        biases = [np.broadcast_to(truth_bias.gyro, (n, 3)), np.broadcast_to(truth_bias.accel, (n, 3))]
    elif truth_bias is not None:
        raise ParameterError("truth has bias histories already; pass one or the other", argument="truth_bias")
    else:
        biases = [truth.gyro_bias, truth.accel_bias]
    quat_wxyz = truth.rotation.as_quat()[:, [3, 0, 1, 2]]
    values = np.hstack([truth.position, quat_wxyz, truth.velocity, *biases])
    return _stamps_ns(truth.t_ns, truth.t, epoch, "truth"), values


def _epoch(epoch_ns: int | None) -> int:
    if epoch_ns is None:
        return 0
    if not isinstance(epoch_ns, (int, np.integer)) or isinstance(epoch_ns, bool):
        raise ParameterError(f"expected an integer number of nanoseconds, got {epoch_ns!r}", argument="epoch_ns")
    if not INT64_MIN <= int(epoch_ns) <= INT64_MAX:
        raise ParameterError(f"{epoch_ns} is outside the int64 range", argument="epoch_ns")
    return int(epoch_ns)


def _stamps_ns(t_ns: NDArray[np.int64] | None, t: FloatArray, epoch: int, name: str) -> NDArray[np.int64]:
    """``t_ns``, else float seconds ``t`` as ``epoch + nearest ns`` (exact whole seconds, rounded fraction)."""
    if t_ns is not None:
        return t_ns
    whole = np.floor(t)
    frac_ns = np.rint((t - whole) * 1e9)  # in [0, 1e9]; t - floor(t) is exact for t ≥ 0
    epoch_s, epoch_rest = divmod(epoch, 10**9)
    first = (int(whole[0]) + epoch_s) * 10**9 + int(frac_ns[0]) + epoch_rest
    last = (int(whole[-1]) + epoch_s) * 10**9 + int(frac_ns[-1]) + epoch_rest
    if first < INT64_MIN or last > INT64_MAX:
        raise ParameterError(
            f"float stamps {float(t[0])!r} … {float(t[-1])!r} s with epoch_ns = {epoch} do not fit int64 nanoseconds",
            argument=name,
        )
    ns = (whole.astype(np.int64) + epoch_s) * 10**9 + (frac_ns.astype(np.int64) + epoch_rest)
    same = np.flatnonzero(np.diff(ns) <= 0)
    if same.size:
        k = int(same[0])
        raise TimestampError(
            f"samples {k} and {k + 1} ({float(t[k])!r} and {float(t[k + 1])!r} s) "
            f"fall on the same nanosecond {int(ns[k])}",
            argument=name,
        )
    return ns


def euroc_folder(folder: str | os.PathLike[str], bad: BadLines) -> tuple[ImuData, Trajectory | None]:
    """:func:`read_euroc` reporting to ``bad``."""
    root = mav0_root(folder)
    truth, mag = root / GROUNDTRUTH_CSV, root / MAG_CSV
    imu = euroc_imu(root / IMU_CSV, bad)
    # lexists: a dangling link or a folder where the file should be is an error, not "no ground truth".
    if os.path.lexists(mag):
        t_ns, values, _ = read_stamped_csv(mag, bad, MAG_HEADER, f"imukit {MAG_CSV.as_posix()}")
        imu = with_mag(imu, t_ns, values, os.fspath(mag), f"move {MAG_CSV.parent} away to read without it")
    return imu, euroc_groundtruth(truth, bad) if os.path.lexists(truth) else None


@public_reader(euroc_folder)
def read_euroc(  # type: ignore[empty-body]
    folder: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> tuple[ImuData, Trajectory | None]:
    """Read the IMU and ground truth of an EuRoC / ASL folder (as :func:`write_euroc` writes it).

    ``folder`` holds ``imu0/data.csv`` and, optionally, ``state_groundtruth_estimate0/data.csv`` and
    ``mag0/data.csv`` (imukit's magnetometer file, see :func:`write_euroc`; it becomes ``imu.mag``,
    matched to the IMU's stamps as in :mod:`imukit.io._mag`); a folder whose ``mav0/`` holds them (a
    downloaded sequence) works too. The ground truth keeps
    its own stamps (it is not interpolated to the IMU's); it is None when its file is absent. The
    noise model and rate of ``imu0/sensor.yaml`` are read by :func:`read_euroc_sensor`.

    ``on_bad_line`` and ``report`` as in :func:`read_euroc_imu`, for both files (one warning for both).

    Raises
    ------
    FileNotFoundError
        No ``imu0/data.csv``.
    FileFormatError
        As :func:`read_euroc_imu` and :func:`read_euroc_groundtruth`.
    """


def read_euroc_sensor(path: str | os.PathLike[str]) -> KalibrImu | None:
    """The noise model and rate of the EuRoC ``imu0/sensor.yaml`` that goes with ``path``, or None.

    Parameters
    ----------
    path
        An EuRoC / ASL folder (``sensor.yaml`` looked for in ``imu0/``, then in ``mav0/imu0/``), a
        ``.yaml`` / ``.yml`` file of any name (``imu0_sensor.yaml``: read itself), or another file,
        typically ``imu0/data.csv`` (``sensor.yaml`` looked for beside it). A folder's parent is
        never searched.

    Returns
    -------
    KalibrImu or None
        None when a folder or data file has no such ``sensor.yaml`` (a yaml file given by name is
        read or refused, never None). Else, as :func:`imukit.io.read_kalibr_imu` reads
        it: ``noise`` from ``gyroscope_noise_density`` [rad/s/√Hz], ``gyroscope_random_walk``
        [rad/s²/√Hz], ``accelerometer_noise_density`` [m/s²/√Hz], ``accelerometer_random_walk``
        [m/s³/√Hz]; ``rate_hz`` [Hz]; ``extra`` every other key as PyYAML parsed it, among them
        ``T_BS`` (``{"rows": 4, "cols": 4, "data": [16 numbers, row-major]}``), the sensor's pose in
        EuRoC's body frame. imukit's body frame is the IMU frame, so ``T_BS`` is reported there and
        never applied: the samples are used in the sensor's own axes (EuRoC's ``imu0`` has the
        identity; ``np.reshape(np.asarray(extra["T_BS"]["data"], float), (4, 4))`` is the matrix).

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    FileFormatError
        The ``sensor.yaml`` found or given is not an IMU sensor file (as
        :func:`imukit.io.read_kalibr_imu`: missing noise keys or rate, a value that is not a finite
        number, naming the keys missing; a file whose ``sensor_type`` is another sensor's says so), or
        its ``T_BS`` is not a 4×4 matrix of finite numbers.
    """
    source = Path(path)
    if not source.exists():
        raise FileNotFoundError(f"path: {os.fspath(path)} does not exist")
    if source.is_file() and source.suffix.lower() in (".yaml", ".yml"):
        return _sensor_yaml(source)
    folders = [source / "imu0", source / "mav0" / "imu0"] if source.is_dir() else [source.parent]
    for folder in folders:
        candidate = folder / "sensor.yaml"
        if candidate.is_file():
            return _sensor_yaml(candidate)
    return None


def _sensor_yaml(path: Path) -> KalibrImu:
    """An EuRoC IMU ``sensor.yaml`` (any name) read, or refused saying what it is instead."""
    try:
        sensor = read_kalibr_imu(path)
    except FileFormatError as exc:
        kind = _sensor_type(path)
        if kind is None or kind == "imu":  # read_kalibr_imu's message names the keys missing
            raise
        why = exc.message.removeprefix(f"{os.fspath(path)}: ")
        raise FileFormatError(
            f"{os.fspath(path)}: not an IMU sensor file (sensor_type {kind!r}; {why})", argument="path"
        ) from exc
    euroc_extrinsics(sensor, where=os.fspath(path))  # a malformed T_BS is refused here
    return sensor


def _sensor_type(path: Path) -> str | None:
    """The ``sensor_type:`` line of a yaml file (EuRoC writes one per sensor), None without one."""
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            key, _, value = line.partition(":")
            if key.strip() == "sensor_type":
                return value.strip().strip("'\"")
    return None


def euroc_extrinsics(sensor: KalibrImu, *, where: str = "sensor.yaml") -> FloatArray | None:
    """``T_BS`` of a ``sensor.yaml`` read by :func:`read_euroc_sensor` as a (4, 4) array, None
    without one; a malformed one is a :class:`FileFormatError` naming ``where``."""
    if "T_BS" not in sensor.extra:
        return None
    entry: Any = sensor.extra["T_BS"]
    data = entry.get("data") if isinstance(entry, dict) else None
    shape = (entry.get("rows"), entry.get("cols")) if isinstance(entry, dict) else None
    numbers = [_finite(x) for x in data] if isinstance(data, list) else []
    if shape != (4, 4) or len(numbers) != 16 or None in numbers:
        raise FileFormatError(
            f"{where}, key 'T_BS': expected rows: 4, cols: 4 and 16 finite numbers in data, got {shown(entry)}",
            argument="path",
        )
    return np.array(numbers, dtype=np.float64).reshape(4, 4)


def _finite(x: object) -> float | None:
    """``x`` as a finite float (YAML 1.1 reads ``1e-3`` as text), else None."""
    if isinstance(x, bool) or not isinstance(x, (int, float, str)):
        return None
    try:
        value = float(x)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def mav0_root(folder: str | os.PathLike[str]) -> Path:
    """``folder`` or its ``mav0/``: the one holding ``imu0/data.csv``, else FileNotFoundError."""
    root = Path(folder)
    if not (root / IMU_CSV).is_file() and (root / "mav0" / IMU_CSV).is_file():
        root = root / "mav0"
    if not (root / IMU_CSV).is_file():
        raise FileNotFoundError(f"folder: no {IMU_CSV.as_posix()} in {os.fspath(folder)} (nor in its mav0/)")
    return root


def euroc_imu(path: str | os.PathLike[str], bad: BadLines) -> ImuData:
    """:func:`read_euroc_imu` reporting to ``bad``."""
    t_ns, values, _ = read_stamped_csv(path, bad, IMU_HEADER, f"EuRoC {IMU_CSV.as_posix()}", names=IMU_NAMES)
    return as_file_error(path, lambda: ImuData(t_ns, values[:, 0:3], values[:, 3:6]))


@public_reader(euroc_imu)
def read_euroc_imu(  # type: ignore[empty-body]
    path: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> ImuData:
    """Read an EuRoC ``imu0/data.csv``: ``timestamp [ns], ω_x,y,z [rad/s], a_x,y,z [m/s²]`` rows.

    Returns an :class:`imukit.ImuData` with exact int64 ``t_ns`` (parsed as integers: float64
    would round 19-digit stamps to 256 ns). ``#`` lines (the header) and blank lines are skipped.

    Parameters
    ----------
    path
        The CSV file.
    on_bad_line
        ``"raise"`` (default): the first bad line is a :class:`FileFormatError`. ``"skip"``: bad
        lines are left out and reported (``docs/io.md``): not 7 fields, a stamp that is not an
        integer, a value that is not a finite number, and stamps out of order: the longest strictly
        increasing subsequence of stamps is kept (the first of equal ones), so one wild stamp costs
        its own line only.
    report
        An :class:`imukit.io.ReadReport` that receives the skipped lines; without one, skipping
        emits one :class:`imukit.io.SkippedLinesWarning`.

    Raises
    ------
    FileFormatError
        (a ``ValueError``) naming the file and line: not 7 fields, a stamp that is not an integer,
        a value that is not a finite number, time not strictly increasing, or no data.
    """


def euroc_groundtruth(path: str | os.PathLike[str], bad: BadLines) -> Trajectory:
    """:func:`read_euroc_groundtruth` reporting to ``bad``."""
    t_ns, values, lines = read_stamped_csv(
        path, bad, GROUNDTRUTH_HEADER, f"EuRoC {GROUNDTRUTH_CSV.as_posix()}", quaternion=3, names=POSE_NAMES
    )
    rotation = rotations_from_rows(np.ascontiguousarray(values[:, [4, 5, 6, 3]]), lines, os.fspath(path))
    return as_file_error(
        path,
        lambda: Trajectory(
            None,
            values[:, 0:3],
            values[:, 7:10],
            rotation,
            t_ns=t_ns,
            gyro_bias=values[:, 10:13],
            accel_bias=values[:, 13:16],
        ),
    )


@public_reader(euroc_groundtruth)
def read_euroc_groundtruth(  # type: ignore[empty-body]
    path: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> Trajectory:
    """Read an EuRoC ``state_groundtruth_estimate0/data.csv`` into a :class:`imukit.Trajectory`.

    Columns: ``timestamp [ns]``, ``p_RS_R`` [m], ``q_RS`` (w, x, y, z), ``v_RS_R`` [m/s],
    ``b_w_RS_S`` [rad/s], ``b_a_RS_S`` [m/s²]; they become ``t_ns`` (exact), ``position``,
    ``rotation`` (``R_wb``), ``velocity``, ``gyro_bias`` and ``accel_bias``. Quaternions unit to
    1e-15 are kept bit for bit, others normalised (EuRoC prints 6 decimals: norms off by up to
    1.5e-4).

    ``on_bad_line`` and ``report`` as in :func:`read_euroc_imu`; a zero quaternion is a bad line too.

    Raises
    ------
    FileFormatError
        As :func:`read_euroc_imu` (17 fields), and for a zero quaternion.
    """


def read_stamped_csv(
    path: str | os.PathLike[str],
    bad: BadLines,
    header: str,
    what: str,
    *,
    quaternion: int | None = None,
    names: FixedLayout | None = None,
) -> tuple[NDArray[np.int64], FloatArray, NDArray[np.int64]]:
    """Integer stamps, ``(N, columns - 1)`` floats and line numbers of an EuRoC-style CSV file with
    ``header``'s columns.

    ``what`` names the file in messages; ``quaternion``: the first of four value columns (after the
    stamp) holding a quaternion, which must not be zero; ``names``: the layout as a header would name
    it, a FileFormatError when the file's header names another (:func:`departure`).
    """
    width = header.count(",") + 1
    if names is not None and (why := departure(header_names(Head(Path(path))), names)) is not None:
        raise FileFormatError(
            f"{os.fspath(path)}: its header {why}, not the {what} layout, read by position "
            f"({header.split(',')[0]},{header.split(',')[1]},…): read it with {names.by_names}, which reads "
            "the columns by their names",
            argument="path",
        )

    def check(fields: list[str], row: list[float]) -> Problem | None:
        stamp = fields[0].strip()
        if integer_stamp(stamp) is None:
            return "malformed", f"timestamp {stamp!r} is not an integer number of nanoseconds (int64)"
        return None if quaternion is None else zero_quaternion(row[quaternion : quaternion + 4])

    layout = Layout(
        ",",
        width,
        f"comma-separated fields ({what})",
        range(1, width),
        0,
        "integer",
        integer_stamp,
        True,
        check,
        None if quaternion is None else zero_quaternions(quaternion),
    )
    table = read_table(path, bad, layout)
    # Integer stamps are required (a line without one is a bad line), so every row has one.
    stamps = cast(NDArray[np.int64], table.stamps)
    table = increasing_table(table, stamps, path, bad, layout)
    if not len(table.lines):
        raise FileFormatError(f"{os.fspath(path)}: no data lines{bad.skipped_in(path)}", argument="path")
    return cast(NDArray[np.int64], table.stamps), table.values, table.lines


def dataset_root(path: str | os.PathLike[str]) -> Path | None:
    """``path`` or its ``mav0/`` when it is a folder holding ``imu0/data.csv``, else None."""
    folder = Path(path)
    for root in (folder, folder / "mav0"):
        if folder.is_dir() and (root / IMU_CSV).is_file():
            return root
    return None


def dataset_file(name: str, file: Path, read: Callable[..., Any], description: str) -> Format:
    """The trajectory format of a dataset folder (or its ``mav0/``) holding ``file``, read by ``read``."""

    def holds(path: Path, head: Head) -> bool:
        root = dataset_root(path)
        return root is not None and (root / file).is_file()

    return Format(name, "trajectory", holds, lambda folder, bad: read(mav0_root(folder) / file, bad), description)


def _imu_csv_like(path: Path, head: Head) -> bool:
    """7 fields, an integer stamp, and no header naming other columns (the named CSV's then)."""
    fields = head.fields(",")
    return (
        len(fields) == 7
        and integer_stamp(fields[0].strip()) is not None
        and departure(header_names(head), IMU_NAMES) is None
    )


def _groundtruth_like(path: Path, head: Head) -> bool:
    """17 fields and no header naming other columns."""
    return len(head.fields(",")) == 17 and departure(header_names(head), POSE_NAMES) is None


# The descriptions of the formats (folders and files share one: listed once).
DATASET = "EuRoC / TUM-VI folder or imu0/data.csv"
GROUNDTRUTH = "EuRoC ground truth"
EUROC_FOLDER = Format("euroc-folder", "imu", lambda path, head: dataset_root(path) is not None, euroc_folder, DATASET)
EUROC_IMU_CSV = Format("euroc-imu-csv", "imu", _imu_csv_like, euroc_imu, DATASET)
EUROC_GROUNDTRUTH_FOLDER = dataset_file("euroc-groundtruth-folder", GROUNDTRUTH_CSV, euroc_groundtruth, GROUNDTRUTH)
EUROC_GROUNDTRUTH = Format("euroc-groundtruth", "trajectory", _groundtruth_like, euroc_groundtruth, GROUNDTRUTH)
