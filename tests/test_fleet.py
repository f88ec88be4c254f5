"""imukit.fleet.run on a real LocalCluster (2 worker processes over loopback): rows, failures,
agreement with the in-process job, a worker killed mid-run, resume."""

from __future__ import annotations

import json
import os
import shutil
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("distributed", reason="imukit.fleet needs dask[distributed] (pip install 'imukit[fleet]')")
pytest.importorskip("pyarrow", reason="imukit.fleet needs pyarrow (pip install 'imukit[fleet]')")

import pyarrow.dataset
import pyarrow.parquet
from distributed import Client

import imukit as ik
from fleet_logs import rigidly_moved, write_broken, write_logs
from imukit import fleet
from imukit.fleet._run import _client

# Columns that differ between two runs of the same work.
_VOLATILE = {"elapsed_s"}


@pytest.fixture(scope="module")
def client() -> Iterator[Client]:
    with _client(None, 2) as c:  # the local cluster run() starts without a client
        yield c


@pytest.fixture(scope="module")
def fleet_logs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Path], dict[Path, str]]:
    folder = tmp_path_factory.mktemp("logs")
    return folder, write_logs(folder, 40), write_broken(folder)


@pytest.fixture(scope="module")
def undisturbed(client: Client, fleet_logs: Any, tmp_path_factory: pytest.TempPathFactory) -> Any:
    folder, _, _ = fleet_logs
    return fleet.run("report", str(folder / "*"), out=tmp_path_factory.mktemp("out"), client=client)


def _stable(table: Any) -> dict[str, dict[str, Any]]:
    return {row["path"]: {k: v for k, v in row.items() if k not in _VOLATILE} for row in table.to_pylist()}


def test_forty_logs_a_corrupt_and_an_empty_one(undisturbed: Any, fleet_logs: Any) -> None:
    _, logs, broken = fleet_logs
    rows = {row["path"]: row for row in undisturbed.to_pylist()}
    assert len(undisturbed) == 42 and len(rows) == 42
    assert sum(row["status"] == "ok" for row in rows.values()) == 40
    for path, reason in broken.items():
        row = rows[str(path)]
        assert row["status"] == "failed" and reason in row["error"] and "\n" not in row["error"]
    # The same numbers as the job called in this process, to the bit.
    for path in logs[:3] + logs[-2:]:
        row = rows[str(path)]
        assert row["status"] == "ok" and row["error"] is None
        expected = fleet.report(path).scalars
        assert {k: row[k] for k in expected} == expected
    meta = undisturbed.schema.metadata[b"imukit"].decode()
    assert '"job": "report"' in meta and "imukit_version" in meta and "R_wb" in meta


def test_summary_file_is_the_returned_table(undisturbed: Any, client: Client, fleet_logs: Any, tmp_path: Path) -> None:
    _, logs, broken = fleet_logs
    calls: list[tuple[int, int, int]] = []
    inputs = [str(p) for p in [*logs[:4], *broken]]
    table = fleet.run("report", inputs, out=tmp_path, client=client, progress=lambda *a: calls.append(a))
    assert pyarrow.parquet.read_table(tmp_path / "summary.parquet").equals(table)
    assert not list(tmp_path.glob(".*"))  # no temporary left behind
    # The progress: each log once as it is done, out of all, with the failures so far.
    assert [(done, total) for done, total, _ in calls] == [(k, 6) for k in range(1, 7)]
    failed = [f for _, _, f in calls]
    assert failed == sorted(failed) and failed[-1] == 2


def test_killed_worker_every_input_once_same_results(
    undisturbed: Any, client: Client, fleet_logs: Any, tmp_path: Path
) -> None:
    folder, _, _ = fleet_logs
    pids = client.run(os.getpid)
    victim = sorted(pids.values())[0]
    killed = []

    def progress(done: int, total: int, failed: int) -> None:
        if done == 3 and not killed:
            os.kill(victim, signal.SIGKILL)
            killed.append(victim)

    table = fleet.run("report", str(folder / "*"), out=tmp_path, client=client, progress=progress)
    assert killed
    assert victim not in client.run(os.getpid).values()  # the nanny started a new process
    # The local cluster's workers, the restarted one too, keep glibc's adaptive malloc (_run._LOCAL_CONFIG).
    client.wait_for_workers(2, timeout=60)
    assert list(client.run(os.environ.get, "MALLOC_TRIM_THRESHOLD_").values()) == [None, None]
    # Two workers share the cores: each one's kernels get half of them.
    share = max(1, (os.cpu_count() or 1) // 2)
    assert list(client.run(ik.get_num_threads).values()) == [share, share]
    paths = table.column("path").to_pylist()
    assert len(paths) == 42 and len(set(paths)) == 42
    assert _stable(table) == _stable(undisturbed)


def test_resume_processes_only_new_logs(client: Client, fleet_logs: Any, tmp_path: Path) -> None:
    folder = tmp_path / "logs"
    folder.mkdir()
    write_logs(folder, 6)
    out = tmp_path / "out"
    first = fleet.run("report", str(folder / "*"), out=out, client=client)
    new = write_logs(folder, 5, first=6)
    calls: list[tuple[int, int, int]] = []
    second = fleet.run("report", str(folder / "*"), out=out, client=client, progress=lambda *a: calls.append(a))
    assert len(second) == 11 and set(second.column("status").to_pylist()) == {"ok"}
    assert [c[0] for c in calls] == list(range(7, 12)) and {c[1] for c in calls} == {11}
    # Old rows kept as they were (their elapsed_s too: not recomputed); the new ones present.
    old = {row["path"]: row for row in first.to_pylist()}
    rows = {row["path"]: row for row in second.to_pylist()}
    assert all(rows[path] == row for path, row in old.items())
    assert {str(p) for p in new} == set(rows) - set(old)
    # A changed log is processed again.
    os.utime(new[1], ns=(1, 1))  # a CSV file
    calls.clear()
    fleet.run("report", str(folder / "*"), out=out, client=client, progress=lambda *a: calls.append(a))
    assert len(calls) == 1


def test_a_rerun_with_other_options_recomputes_every_log(client: Client, fleet_logs: Any, tmp_path: Path) -> None:
    """Kept rows answer the options they were run with: a re-run with others kept them all and
    labelled them with the new options (before 2026-12-07); so did a changed manifest column."""
    _, logs, _ = fleet_logs
    out, inputs = tmp_path / "out", [str(p) for p in logs[:2]]
    mahony = fleet.run("filter", inputs, out=out, client=client, method="mahony")
    madgwick = fleet.run("filter", inputs, out=out, client=client, method="madgwick")
    alone = fleet.run("filter", inputs, out=tmp_path / "alone", client=client, method="madgwick")
    assert madgwick.column("rmse_total_deg").to_pylist() == alone.column("rmse_total_deg").to_pylist()
    assert madgwick.column("rmse_total_deg").to_pylist() != mahony.column("rmse_total_deg").to_pylist()
    # The same log with another per-log option in its manifest row is run again.
    manifest = tmp_path / "manifest.csv"
    calls: list[Any] = []
    for value in (0.01, 100.0, 100.0):
        manifest.write_text(f"path,gyro_range\n{logs[0]},{value}\n")
        table = fleet.run(
            "report", manifest, out=tmp_path / "ranges", client=client, progress=lambda *a: calls.append(a)
        )
        assert table.column("gyro_range").to_pylist() == [value]
    assert len(calls) == 2  # the third run kept the second's row


def test_files_a_folder_search_leaves_out_are_named(client: Client, tmp_path: Path) -> None:
    folder = tmp_path / "logs"
    folder.mkdir()
    write_logs(folder, 2)
    (folder / "headerless.csv").write_text("0,1,2\n3,4,5\n")
    with pytest.warns(fleet.LeftOutWarning, match=r"left out 1 files .*headerless\.csv"):
        table = fleet.run("report", folder, out=tmp_path / "out", client=client)
    assert len(table) == 2
    meta = json.loads(pyarrow.parquet.read_schema(tmp_path / "out" / "summary.parquet").metadata[b"imukit"])
    assert meta["left_out"] == [str(folder / "headerless.csv")]


def test_preintegrate_rows_partitioned_by_log(client: Client, fleet_logs: Any, tmp_path: Path) -> None:
    _, logs, _ = fleet_logs
    table = fleet.run("preintegrate", [str(p) for p in logs[:4:2]], out=tmp_path, client=client, window_s=0.5)
    assert table.column("status").to_pylist() == ["ok", "ok"]
    rows = pyarrow.dataset.dataset(tmp_path / "preintegrate", partitioning="hive").to_table()
    assert rows.num_rows == 2 * 10 and set(rows.column("log").to_pylist()) == set(table.column("log").to_pylist())
    local = fleet.preintegrate(logs[0], window_s=0.5).rows
    assert local is not None
    mine = rows.filter(pyarrow.compute.equal(rows.column("log"), table.column("log")[0]))
    assert mine.column("dp").to_pylist() == local["dp"].tolist()


def test_manifest_metadata_carried(client: Client, fleet_logs: Any, tmp_path: Path) -> None:
    _, logs, _ = fleet_logs
    manifest = tmp_path / "manifest.csv"
    manifest.write_text("path,unit_id\n" + "".join(f"{p},unit-{k}\n" for k, p in enumerate(logs[:3])))
    table = fleet.run("report", manifest, out=tmp_path / "out", client=client)
    assert table.column("unit_id").to_pylist() == ["unit-0", "unit-1", "unit-2"]
    assert table.column("path").to_pylist() == [str(p) for p in logs[:3]]


def test_evaluate_takes_each_logs_reference_from_the_manifest(client: Client, fleet_logs: Any, tmp_path: Path) -> None:
    _, logs, _ = fleet_logs
    reference = shutil.copytree(logs[0], tmp_path / "truth" / "log")  # a EuRoC folder: its ground truth
    truth = ik.io.read_trajectory(reference)
    offsets = {"a.txt": [0.5, 0.0, 0.0], "b.txt": [0.0, 0.0, 0.2], "c.txt": [0.0, 0.0, 0.0]}
    for name, offset in offsets.items():
        ik.io.write_tum(rigidly_moved(truth, 10, 0.0, offset), tmp_path / name)
    manifest = tmp_path / "manifest.csv"
    manifest.write_text("path,reference,unit_id\na.txt,truth/log,u1\nb.txt,truth/log,u2\nc.txt,missing.txt,u3\n")
    out = tmp_path / "out"
    calls: list[tuple[int, int, int]] = []

    def evaluate() -> Any:
        return fleet.run(
            "evaluate", manifest, out=out, client=client, align="none", progress=lambda *a: calls.append(a)
        )

    rows = evaluate().to_pylist()
    assert [(row["unit_id"], row["status"]) for row in rows] == [("u1", "ok"), ("u2", "ok"), ("u3", "failed")]
    assert [row["reference"] for row in rows] == [str(reference)] * 2 + [str(tmp_path / "missing.txt")]
    assert "missing.txt" in rows[2]["error"]
    assert [row["ate_rmse_m"] for row in rows[:2]] == pytest.approx([0.5, 0.2], rel=1e-6)
    parts = pyarrow.dataset.dataset(out / "evaluate", partitioning="hive")
    assert parts.count_rows() == sum(row["scored_samples"] for row in rows[:2])
    for piece in parts.files:  # every file a run writes says its version, units and frames
        meta = json.loads(pyarrow.parquet.read_schema(piece).metadata[b"imukit"])
        assert meta["imukit_version"] == ik.__version__ and meta["job"] == "evaluate"
        assert "_deg degrees" in meta["units"] and "R_wb" in meta["frames"]
    # The resume key covers the reference: a changed ground truth redoes the logs scored against it.
    calls.clear()
    evaluate()
    assert calls == []
    data = next(Path(reference).rglob("state_groundtruth_estimate0/data.csv"))
    os.utime(data)  # rewritten now
    evaluate()
    assert [c[0] for c in calls] == [2, 3]  # two of three redone, the failed one kept
