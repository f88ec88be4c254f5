"""What :func:`imukit.fleet.run` processes: :func:`find_inputs` (:func:`scan`) and the resume key
:func:`stamp`.

An input is one of: a path (a recording file or folder), a glob (``logs/*.csv``), a folder holding
recordings (every path under it that a registered :class:`imukit.io.Format` detects, a recording
folder such as EuRoC's counted once; the other files are left out, and :func:`scan` names them), or
a manifest: a ``.parquet`` file, or a ``.csv`` whose header has a ``path`` column, one recording per
row with its other columns (``unit_id`` …) carried into the summary (a path in two rows that differ
is refused); a column named as one of the job's options (``reference`` for ``evaluate``,
``gyro_range`` for ``report`` …) is also that log's value of the option. Relative paths in a
manifest's ``path`` and ``reference`` columns are relative to the manifest's folder.
"""

from __future__ import annotations

import glob
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any, NamedTuple

from imukit._errors import ParameterError
from imukit.fleet._load import Scalar
from imukit.io import formats
from imukit.io._format import Head

__all__ = ["PATH_COLUMNS", "Input", "Scan", "find_inputs", "scan", "stamp"]

PATH_COLUMNS = ("path", "reference")
"""The manifest columns that name files: relative paths in them are relative to the manifest."""

_GLOB = set("*?[")


class Input(NamedTuple):
    """One recording to process and the metadata its manifest row gave it."""

    path: str
    metadata: dict[str, Scalar]


class Scan(NamedTuple):
    """What :func:`scan` found: the recordings, and the files under the folders given that no format
    reads as an IMU recording (left out, and said so by :func:`imukit.fleet.run`)."""

    found: list[Input]
    left_out: list[str]


def find_inputs(inputs: str | os.PathLike[str] | Iterable[str | os.PathLike[str]]) -> list[Input]:
    """The recordings ``inputs`` name (module doc), each once, in the order given (a folder's and a
    glob's sorted). A path named twice with different manifest columns is a ParameterError: which
    row's options would hold?"""
    return scan(inputs).found


def scan(inputs: str | os.PathLike[str] | Iterable[str | os.PathLike[str]]) -> Scan:
    """:func:`find_inputs`, and the files its folder searches left out (hidden ones not counted)."""
    items = [inputs] if isinstance(inputs, (str, os.PathLike)) else list(inputs)
    found: dict[str, Input] = {}
    left_out: list[str] = []
    for item in items:
        for one in _expand(os.fspath(item), left_out):
            first = found.setdefault(one.path, one)
            if first.metadata != one.metadata:
                raise ParameterError(
                    f"{one.path} is named twice, with {first.metadata} and {one.metadata}: a recording is run "
                    "once, with one row's options",
                    argument="inputs",
                )
    return Scan(list(found.values()), left_out)


def _expand(item: str, left_out: list[str]) -> Iterator[Input]:
    if _GLOB & set(item):
        yield from (Input(p, {}) for p in sorted(glob.glob(item, recursive=True)))
    elif _is_manifest(Path(item)):
        yield from _manifest(Path(item))
    elif Path(item).is_dir() and not _detected(Path(item)):
        yield from (Input(os.fspath(p), {}) for p in _recordings(Path(item), left_out))
    else:
        yield Input(item, {})


def _detected(path: Path) -> bool:
    head = Head(path)
    return any(fmt.sniff(path, head) for fmt in formats("imu"))


def _recordings(folder: Path, left_out: list[str]) -> Iterator[Path]:
    """Paths under ``folder`` that a format detects, folder by folder from the top (its recording
    folders, then its recording files, each sorted); a detected folder is not searched further. The
    other files (not hidden ones) go to ``left_out``."""
    for root, dirs, files in os.walk(folder):
        dirs.sort()
        for name in list(dirs):
            if _detected(Path(root, name)):
                dirs.remove(name)
                yield Path(root, name)
        for name in sorted(files):
            if _detected(Path(root, name)):
                yield Path(root, name)
            elif not name.startswith("."):
                left_out.append(os.fspath(Path(root, name)))


def _is_manifest(path: Path) -> bool:
    if not path.is_file():
        return False
    if path.suffix.lower() == ".parquet":
        return True
    return path.suffix.lower() == ".csv" and "path" in Head(path).fields(",")


def _manifest(path: Path) -> Iterator[Input]:
    import pyarrow.csv
    import pyarrow.parquet

    table = pyarrow.parquet.read_table(path) if path.suffix.lower() == ".parquet" else pyarrow.csv.read_csv(path)
    if "path" not in table.column_names:
        raise ParameterError(f"{path}: a manifest needs a 'path' column, got {table.column_names}", argument="inputs")
    for row in table.to_pylist():
        for column in PATH_COLUMNS[1:]:
            if row.get(column) is not None:
                row[column] = _beside(path, row[column])
        yield Input(_beside(path, row.pop("path")), row)


def _beside(manifest: Path, value: Any) -> str:
    """A path named in ``manifest``: relative ones are relative to its folder."""
    named = Path(str(value))
    return os.fspath(named if named.is_absolute() else manifest.parent / named)


def stamp(*paths: str) -> tuple[int, int]:
    """``(size in bytes, latest mtime in ns)`` of files, or of every file under a folder: a changed
    recording changes it (the resume key, with the path)."""
    stats: list[Any] = []
    for target in map(Path, paths):
        files: Iterable[Path] = [target]
        if target.is_dir():
            files = (Path(root, name) for root, _, names in os.walk(target) for name in names)
        stats += [f.stat() for f in files]
    return sum(s.st_size for s in stats), max((s.st_mtime_ns for s in stats), default=0)
