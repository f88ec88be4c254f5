"""Issue 17, item 14: the compiled fast path of the line readers (imukit::text, io/_blocks.py) reads every
file exactly as the pure-Python reference parser does: the same rows bit for bit, the same skip report,
the same first error; across block boundaries and whatever junk the lines hold."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from euroc import GT_CSV, IMU_CSV, requires_euroc
from imukit import io
from imukit.io import _blocks, _euroc, _tum
from imukit.io._lines import ns_text
from imukit.io._report import ReadReport

JUNK = [
    "",
    "# a comment",
    "   ",
    "{t},1_0,0,0,0,0,9.81",  # an underscore: Python's float() reads it, the core defers it
    "{t},\u0661,0,0,0,0,9.81",  # an Arabic-Indic digit: float() reads it
    "{t},\u00a00.5,0,0,0,0,9.81",  # a non-breaking space
    "{t},0.5 ,0 , 0,0,0,9.81",  # spaces around fields
    "{t},inf,0,0,0,0,9.81",
    "{t},nan,0,0,0,0,9.81",
    "{t},0,0,0,0,0",
    "{t},0,0,0,0,0,0,0",
    "{t},x,0,0,0,0,9.81",
    "+{t},0,0,0,0,0,9.81",
    "{t}.5,0,0,0,0,0,9.81",
    "99999999999999999999,0,0,0,0,0,9.81",
    "{t},0,0,0,0,0,9.81\r",
    "\x1f{t},0,0,0,0,0,9.81",
    "{t},1e308,1E-308,-0.0,+.5,5.,9.81",
    "\ufeff{t},0,0,0,0,0,9.81",
    "{back},0,0,0,0,0,9.81",  # a stamp going back
    "{t},0,0,0,0,0,9.81",  # a duplicate stamp (the same t as the line before)
]


def _messy(rng: np.random.Generator, n: int) -> bytes:
    lines, t = ["#timestamp [ns],wx,wy,wz,ax,ay,az"], 1_403_636_579_758_555_392
    for _ in range(n):
        t += int(rng.integers(1_000_000, 10_000_000))
        if rng.random() < 0.3:
            lines.append(JUNK[int(rng.integers(len(JUNK)))].format(t=t, back=t - 50_000_000))
        else:
            lines.append(f"{t}," + ",".join(repr(float(x)) for x in rng.normal(size=6)))
    text = "\n".join(lines).encode("utf-8", "surrogatepass")
    if rng.random() < 0.5:
        text += b"\n"
    if rng.random() < 0.3:  # bytes that are not UTF-8 inside one line
        k = text.rfind(b",", 0, len(text) // 2)
        text = text[:k] + b"\xff\xfe" + text[k:]
    return text


def _both(path: Path, read: Callable[..., object], module: object, monkeypatch: pytest.MonkeyPatch) -> list[object]:
    """What ``read`` gives (result or error text, and the report) by the fast path and by the reference
    (``module``'s ``read_table`` replaced by the pure-Python one)."""
    outcomes = []
    for fast in (True, False):
        if not fast:
            monkeypatch.setattr(module, "read_table", _blocks._pure_python)
        for mode in ("skip", "raise"):
            report = ReadReport()
            try:
                result = read(path, on_bad_line=mode, report=report)
            except ik.ImukitError as exc:
                result = str(exc)
            outcomes.append((mode, _bits(result), report.skipped))
        monkeypatch.undo()
    return outcomes


def _bits(result: object) -> object:
    if isinstance(result, ik.ImuData):
        return (
            result.t_ns.tobytes() if result.t_ns is not None else None,
            result.gyro.tobytes(),
            result.accel.tobytes(),
        )
    if isinstance(result, ik.Trajectory):
        stamps = result.t_ns.tobytes() if result.t_ns is not None else result.t.tobytes()
        return (stamps, result.position.tobytes(), result.rotation.as_quat().tobytes())
    return result


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("block", [64, 1 << 24])
def test_euroc_fast_path_equals_the_reference(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed: int, block: int
) -> None:
    rng = np.random.default_rng(seed)
    path = tmp_path / "data.csv"
    path.write_bytes(_messy(rng, 300))
    monkeypatch.setattr(_blocks, "BLOCK_BYTES", block)
    outcomes = _both(path, io.read_euroc_imu, _euroc, monkeypatch)
    monkeypatch.setattr(_blocks, "BLOCK_BYTES", block)
    assert outcomes[:2] == outcomes[2:]
    assert outcomes[0][2], "the file had junk: the report must not be empty"


@pytest.mark.parametrize("seed", range(8))
def test_tum_fast_path_equals_the_reference(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    lines = []
    for k in range(200):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        stamp = f"{1403636579 + k // 100}.{(k % 100) * 10_000_000:09d}" if seed % 2 else repr(k * 0.01 + 0.005)
        row = [stamp, *map(repr, rng.normal(size=3)), *map(repr, q)]
        if rng.random() < 0.15:
            row[int(rng.integers(8))] = ["0", "1_0", "nan", "x", "\u0661"][int(rng.integers(5))]
        if rng.random() < 0.05:
            row[4:8] = ["0", "0.0", "-0", "0e0"]  # a zero quaternion the core reads, the mask flags
        lines.append(("\t" if rng.random() < 0.2 else " ").join(row))
    path = tmp_path / "traj.txt"
    path.write_text("\n".join(lines) + "\n")
    monkeypatch.setattr(_blocks, "BLOCK_BYTES", 256)
    outcomes = _both(path, io.read_tum, _tum, monkeypatch)
    assert outcomes[:2] == outcomes[2:]


# The generic reader's stamp texts per time unit, from nanoseconds.
_STAMPS: dict[str, Callable[[int], str]] = {
    "ns": str,
    "us": lambda ns: str(ns // 1000),
    "ms": lambda ns: repr(ns / 1e6),
    "s": ns_text,
}


@pytest.mark.parametrize("seed", range(8))
def test_generic_csv_fast_path_equals_the_reference(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed: int) -> None:
    """read_imu_csv / read_trajectory_csv (headers, trailing delimiters, units, ``g`` overflowing, zero
    quaternions): the blocks read by the core give what the reference parser gives, bit for bit."""
    rng = np.random.default_rng(200 + seed)
    unit, sep = ["ns", "us", "ms", "s"][seed % 4], [",", ";", "\t", " "][seed // 2 % 4]
    trailing = sep in ",;" and seed % 3 == 0
    header = ["# exported by a logger", "time" + sep + sep.join("abcdefg")][seed % 2 :]
    lines, t = [*header], 1_403_636_579_758_555_392
    for _ in range(300):
        t += int(rng.integers(1_000_000, 10_000_000))
        row = [_STAMPS[unit](t), *map(repr, rng.normal(size=7).tolist())]
        if rng.random() < 0.25:
            k = int(rng.integers(8))
            row[k] = ["1_0", "\u0661", "nan", "x", "1e308", "0", "", "\u00a00.5"][int(rng.integers(8))]
        if rng.random() < 0.05:
            row[4:8] = ["0", "0.0", "-0", "0e0"]
        lines.append(sep.join(row) + (sep if trailing else ""))
    path = tmp_path / "data.csv"
    path.write_text("\n".join(lines) + ("\n" if seed % 2 else ""))
    monkeypatch.setattr(_blocks, "BLOCK_BYTES", 512)
    delimiter = {"delimiter": sep, "time_unit": unit}

    def imu(path: Path, **options: object) -> object:
        columns = {"gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6]}
        return io.read_imu_csv(path, time_column=0, accel_unit="g", **columns, **delimiter, **options)  # type: ignore[arg-type]

    def trajectory(path: Path, **options: object) -> object:
        columns = {"position_columns": [1, 2, 3], "quaternion_columns": [4, 5, 6, 7]}
        return io.read_trajectory_csv(path, time_column=0, **columns, **delimiter, **options)  # type: ignore[arg-type]

    for read in (imu, trajectory):
        outcomes = _both(path, read, _blocks, monkeypatch)
        assert outcomes[:2] == outcomes[2:]
        assert outcomes[0][2], "the file had junk: the report must not be empty"


def test_a_lone_carriage_return_is_read_as_python_reads_it(tmp_path: Path) -> None:
    path = tmp_path / "data.csv"
    path.write_bytes(b"#t,a,b,c,d,e,f\r1000000000,0,0,0,0,0,9.81\r1005000000,0,0,0,0,0,9.81\r")
    imu = io.read_euroc_imu(path)
    assert imu.t_ns.tolist() == [1_000_000_000, 1_005_000_000]  # type: ignore[union-attr]


@requires_euroc
def test_real_euroc_files_read_the_same_by_both_paths(monkeypatch: pytest.MonkeyPatch) -> None:
    """EuRoC V1_02's IMU (first 40 s) and ground truth: fast path = reference, every field bit for bit."""
    fast = io.read_euroc_imu(IMU_CSV), io.read_euroc_groundtruth(GT_CSV)
    monkeypatch.setattr(_euroc, "read_table", _blocks._pure_python)
    reference = io.read_euroc_imu(IMU_CSV), io.read_euroc_groundtruth(GT_CSV)
    assert len(fast[0]) == 7999 and len(fast[1]) == 16702
    for a, b in zip(fast, reference):
        for field in ("t_ns", "gyro", "accel", "position", "velocity", "gyro_bias", "accel_bias"):
            if hasattr(a, field):
                assert getattr(a, field).tobytes() == getattr(b, field).tobytes(), field
    assert fast[1].rotation.as_quat().tobytes() == reference[1].rotation.as_quat().tobytes()
