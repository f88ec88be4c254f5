"""Inputs the reader fuzzer (``fuzz/python/fuzz_readers.py``, ``make fuzz``) found, replayed.

Each file in ``fuzz/python/regressions/`` made a reader raise something other than an imukit
exception; the fuzzer's own contract check (:func:`check_input`) must now pass on it. The seeds
(valid files of every format) must parse, and the check must flag a foreign exception, so that a
regression cannot pass unnoticed.
"""

from __future__ import annotations

import importlib.util
import sys
import tempfile
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from imukit import FileFormatError, io

_FUZZ = Path(__file__).resolve().parents[1] / "fuzz" / "python"
_REGRESSIONS = sorted((_FUZZ / "regressions").glob("*.bin"))


def _harness() -> ModuleType:
    spec = importlib.util.spec_from_file_location("fuzz_readers", _FUZZ / "fuzz_readers.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_readers"] = module
    spec.loader.exec_module(module)
    return module


fuzz_readers = _harness()


def test_the_regression_inputs_are_there() -> None:
    assert [p.name for p in _REGRESSIONS] == [
        "read_euroc-stamp-control-char.bin",
        "read_kalibr_imu-not-utf8.bin",
        "read_rosbag-mcap-huge-record-size.bin",
        "read_rosbag-mcap-truncated.bin",
    ]


@pytest.mark.parametrize("path", _REGRESSIONS, ids=[p.stem for p in _REGRESSIONS])
def test_regression_input_meets_the_contract(path: Path) -> None:
    if path.stem.startswith("read_rosbag"):
        pytest.importorskip("rosbags", reason="read_rosbag needs imukit[ros]")
    data = path.read_bytes()
    # The file name says which reader the input drives (byte 0).
    assert fuzz_readers.decode(data, Path())[0] == path.stem.split("-")[0]
    fuzz_readers.check_input(data)


def test_kalibr_bytes_that_are_not_utf8_are_a_file_format_error_naming_the_line(tmp_path: Path) -> None:
    # The minimal form of read_kalibr_imu-not-utf8.bin (a UnicodeDecodeError escaped before).
    path = tmp_path / "imu.yaml"
    path.write_bytes(b"update_rate: 200.0\naccelerometer_noise_density: \xdb\xce\n")
    with pytest.raises(FileFormatError, match=r"^path: .*imu\.yaml, line 2: "):
        io.read_kalibr_imu(path)


def test_every_seed_parses_to_a_valid_result() -> None:
    # Valid files of each format reach the result checks (not only the error paths).
    seeds = fuzz_readers.seeds()
    names = {fuzz_readers.decode(seed, Path())[0] for seed in seeds}
    assert names == {name for name, _ in fuzz_readers.READERS} - {"read_rosbag"}
    for seed in seeds + _bag_seeds():
        with tempfile.TemporaryDirectory() as folder:
            _, reader, case = fuzz_readers.decode(seed, Path(folder))
            fuzz_readers._check_result(reader(case))


def test_the_check_flags_a_foreign_exception(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(case: object) -> None:
        raise ValueError("not an imukit error")

    monkeypatch.setattr(fuzz_readers, "READERS", (("broken", broken),))
    with pytest.raises(ValueError, match="not an imukit error"):
        fuzz_readers.check_input(b"\0\0content")


def test_the_check_flags_stamps_that_do_not_increase() -> None:
    # ImuData and Trajectory refuse such stamps themselves; the check is the fuzzer's second look.
    fuzz_readers._increasing(np.array([0, 10, 20]), "ImuData")
    with pytest.raises(fuzz_readers.ContractError, match="not strictly increasing"):
        fuzz_readers._increasing(np.array([0, 10, 10]), "ImuData")


def _bag_seeds() -> list[bytes]:
    """The valid bags the fuzzer starts read_rosbag from, one per container (checked valid above)."""
    pytest.importorskip("rosbags", reason="rosbags is the optional [ros] extra")
    bags = fuzz_readers.rosbag_seeds()
    assert [b[1] for b in bags] == [0, 0, 0, 4, 2]  # ROS 1 plain / lz4 / bz2, .db3, .mcap
    return bags
