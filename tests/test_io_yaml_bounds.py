"""Issue 17, item 11: the YAML readers (read_kalibr_imu, read_euroc_sensor) are bounded in time, memory and
message size, refuse aliases and duplicate keys, and end deep nesting and bad arguments in imukit errors."""

from __future__ import annotations

import resource
import subprocess
import sys
import time
from pathlib import Path

import pytest

import imukit as ik
from imukit import io

VALID = """gyroscope_noise_density: 1.6968e-04
gyroscope_random_walk: 1.9393e-05
accelerometer_noise_density: 2.0000e-3
accelerometer_random_walk: 3.0000e-3
update_rate: 200.0
"""


def _bomb(levels: int) -> str:
    """A "billion laughs" document: each level a list of 9 aliases of the one before (9**levels leaves)."""
    lines = ['a0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    lines += [f"a{k}: &a{k} [{','.join([f'*a{k - 1}'] * 9)}]" for k in range(1, levels)]
    return VALID.replace("update_rate: 200.0", f"update_rate: *a{levels - 1}") + "\n".join(lines) + "\n"


def test_an_alias_bomb_is_refused_fast_and_small(tmp_path: Path) -> None:
    """9 levels (~600 bytes, 387 M leaves) in a child process under a 1 GiB address-space limit: refused
    within 10 s with a message of one line (it took 7-8 s, 1.6 GB and a 522 MB message before)."""
    path = tmp_path / "imu.yaml"
    path.write_text(_bomb(9).replace("update_rate: *a8\n", "") + "update_rate: 200.0\nbomb: *a8\n")
    code = (
        "import resource, sys\n"
        "resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))\n"
        "import imukit.io as io\n"
        "try:\n"
        f"    io.read_kalibr_imu({str(path)!r})\n"
        "except Exception as e:\n"
        "    print(type(e).__name__, len(str(e)), str(e))\n"
    )
    start = time.monotonic()
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False)
    assert time.monotonic() - start < 10.0
    name, size, message = run.stdout.split(" ", 2)
    assert name == "FileFormatError" and int(size) < 300, run.stdout + run.stderr
    assert "aliases (*name) are not accepted" in message and ", line 6:" in message  # a1, the first alias


def test_aliases_duplicate_keys_and_deep_nesting_are_file_format_errors(tmp_path: Path) -> None:
    path = tmp_path / "imu.yaml"
    path.write_text(VALID + "rostopic: &t /imu0\nother: *t\n")
    with pytest.raises(ik.FileFormatError, match=r"line 7: not valid YAML: aliases \(\*name\) are not accepted"):
        io.read_kalibr_imu(path)
    path.write_text(VALID + "update_rate: 100.0\n")
    with pytest.raises(ik.FileFormatError, match=r"line 6: not valid YAML: duplicate key 'update_rate'"):
        io.read_kalibr_imu(path)
    path.write_text(VALID + "deep: " + "[" * 20_000 + "]" * 20_000 + "\n")
    with pytest.raises(ik.FileFormatError, match=r"not valid YAML: nested too deeply"):
        io.read_kalibr_imu(path)
    assert resource.getrlimit(resource.RLIMIT_AS)  # this process was not limited


def test_messages_quote_values_bounded(tmp_path: Path) -> None:
    path = tmp_path / "imu.yaml"
    path.write_text(VALID.replace("200.0", "[" + ", ".join(["1"] * 10_000) + "]"))
    with pytest.raises(ik.FileFormatError) as caught:
        io.read_kalibr_imu(path)
    # Bounded apart from the file's path, whose length is the temporary folder's (longer under xdist).
    message = str(caught.value).replace(str(path), "")
    assert len(message) < 150 and "key 'update_rate': expected a positive, finite number" in message
    (tmp_path / "imu0").mkdir()
    (tmp_path / "imu0" / "sensor.yaml").write_text(
        VALID.replace("update_rate", "rate_hz") + "T_BS:\n  rows: 4\n  cols: 4\n  data: [" + "1, " * 10_000 + "1]\n"
    )
    with pytest.raises(ik.FileFormatError, match="key 'T_BS'") as caught:
        io.read_euroc_sensor(tmp_path)
    assert len(str(caught.value).replace(str(tmp_path), "")) < 250


@pytest.mark.parametrize("section", [[], {}, 3, b"imu0"])
def test_section_of_the_wrong_type_is_a_parameter_error(tmp_path: Path, section: object) -> None:
    path = tmp_path / "imu.yaml"
    path.write_text(VALID)
    with pytest.raises(ik.ParameterError, match=r"^section: expected a top-level key \(str\) or None"):
        io.read_kalibr_imu(path, section=section)  # type: ignore[arg-type]
