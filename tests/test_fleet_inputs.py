"""imukit.fleet.find_inputs: lists, globs, folders (by the Format registry's detection), manifests."""

from __future__ import annotations

from pathlib import Path

import pytest

import imukit as ik
from fleet_logs import write_broken, write_logs
from imukit import fleet


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("inputs")
    (root / "a").mkdir()
    write_logs(root / "a", 3)  # log000/ (EuRoC), log001.csv, log002/
    write_logs(root, 1, first=7)  # log007.csv at the top
    write_broken(root)
    (root / "notes.txt").write_text("not a recording\n")
    return root


def test_folder_lists_each_detected_recording_once(folder: Path) -> None:
    found = [Path(i.path).relative_to(folder).as_posix() for i in fleet.find_inputs(folder)]
    # A EuRoC folder is one recording (its imu0/data.csv is not listed again); files no format
    # accepts (corrupt, empty, notes) are not recordings.
    # Folder by folder from the top: its recording folders, then its recording files, sorted.
    assert found == ["log007.csv", "a/log000", "a/log002", "a/log001.csv"]
    # ... and scan names them: a log that lost its header is not dropped without a word.
    left_out = sorted(Path(p).relative_to(folder).as_posix() for p in fleet.scan(folder).left_out)
    assert "notes.txt" in left_out and len(left_out) >= 2  # the broken ones too (write_broken's)
    assert not set(left_out) & set(found)


def test_glob_list_and_duplicates(folder: Path) -> None:
    found = fleet.find_inputs([str(folder / "a" / "log*"), str(folder / "a" / "log000")])
    assert [Path(i.path).name for i in found] == ["log000", "log001.csv", "log002"]


def test_parquet_manifest_relative_paths_and_metadata(folder: Path) -> None:
    pytest.importorskip("pyarrow", reason="manifests need pyarrow")
    import pyarrow
    import pyarrow.parquet

    manifest = folder / "a" / "m.parquet"
    table = pyarrow.table({"path": ["log001.csv", "log000"], "unit_id": [7, 9]})
    pyarrow.parquet.write_table(table, manifest)
    found = fleet.find_inputs(manifest)
    assert [(i.path, i.metadata) for i in found] == [
        (str(folder / "a" / "log001.csv"), {"unit_id": 7}),
        (str(folder / "a" / "log000"), {"unit_id": 9}),
    ]


def test_a_path_in_two_manifest_rows_that_differ_is_refused(folder: Path) -> None:
    """Two rows naming one log with other columns (another reference): the second row vanished
    without a failed row before 2026-12-07; rows that agree are one input."""
    manifest = folder / "a" / "twice.csv"
    manifest.write_text("path,reference\nlog001.csv,log000\nlog001.csv,nonexistent\n")
    with pytest.raises(ik.ParameterError, match=r"^inputs: .*log001\.csv is named twice") as raised:
        fleet.find_inputs(manifest)
    assert raised.value.argument == "inputs"
    manifest.write_text("path,unit\nlog001.csv,7\nlog001.csv,7\n")
    assert len(fleet.find_inputs(manifest)) == 1
