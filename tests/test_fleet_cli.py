"""``imukit fleet`` end to end against a Dask scheduler and worker started here on 127.0.0.1."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="imukit fleet needs dask[distributed] (pip install 'imukit[fleet]')")
pytest.importorskip("pyarrow", reason="imukit fleet needs pyarrow")

import pyarrow.parquet

from fleet_logs import write_broken, write_logs
from imukit.cli import main


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _dask(*args: str) -> subprocess.Popen[bytes]:
    dask = Path(sys.executable).with_name("dask")
    command = [str(dask), *args] if dask.exists() else [sys.executable, "-m", "dask", *args]
    return subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)


@pytest.fixture
def scheduler() -> Iterator[str]:
    address = f"tcp://127.0.0.1:{_free_port()}"
    port = address.rsplit(":", 1)[1]
    started = [_dask("scheduler", "--host", "127.0.0.1", "--port", port, "--dashboard-address", ":0")]
    try:
        started.append(_dask("worker", address, "--nworkers", "1", "--nthreads", "1", "--host", "127.0.0.1"))
        from distributed import Client

        deadline = time.monotonic() + 60
        while True:  # until the worker has joined
            try:
                with Client(address, timeout=5) as client:
                    client.wait_for_workers(1, timeout=max(1.0, deadline - time.monotonic()))
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.5)
        yield address
    finally:
        for process in reversed(started):
            process.terminate()
            process.wait(timeout=30)


def test_fleet_cli_on_a_scheduler(scheduler: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    logs = write_logs(tmp_path, 4)
    broken = write_broken(tmp_path)
    out = tmp_path / "out"
    code = main(
        ["fleet", "report", str(tmp_path / "log*"), *map(str, broken), "--out", str(out), "--scheduler", scheduler]
    )
    printed = capsys.readouterr().out
    assert code == 1  # some recordings failed
    assert "6 recordings: 4 ok, 2 failed" in printed
    assert all(path.name in printed for path in broken) and "empty file" in printed  # the table of failures
    table = pyarrow.parquet.read_table(out / "summary.parquet")
    assert sorted(table.column("path").to_pylist()) == sorted(str(p) for p in logs + list(broken))
    # The tasks ran on that scheduler.
    from distributed import Client

    with Client(scheduler) as client:
        prefixes = client.run_on_scheduler(lambda dask_scheduler: list(dask_scheduler.task_prefixes))
    assert any(prefix.startswith("imukit") for prefix in prefixes), prefixes
    # A re-run with the same --out processes nothing new.
    assert main(["fleet", "report", *map(str, logs), "--out", str(out), "--scheduler", scheduler]) == 0
    assert "4 recordings: 4 ok, 0 failed" in capsys.readouterr().out


def test_fleet_cli_refuses_an_option_of_another_job(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["fleet", "report", str(tmp_path), "--out", str(tmp_path / "o"), "--window-s", "1"]) == 1
    assert "--window-s: is not an option of the report job" in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "o")
