""":func:`run`: a job over many recordings on Dask distributed, results in Parquet (``docs/fleet.md``).

One task per recording. The task runs the job, writes the log's rows (if the job has any) to
``out/<job>/log=<id>/part-0.parquet`` through a temporary file renamed into place, and returns
only the log's summary row, so the client never holds per-sample data and a task run twice (Dask
re-runs the tasks of a worker that died) leaves the same files. Any exception in the job becomes a
``failed`` row with a one-line error; so does a task Dask gives up on (a log that kills every
worker it lands on). ``summary.parquet`` has each input exactly once.

Resume: rows of a previous ``summary.parquet`` in ``out`` whose ``path``, ``size_bytes`` and
``mtime_ns`` (:func:`imukit.fleet._inputs.stamp`, over the recording and the manifest's
``reference``) and manifest columns still match are kept, failed ones too unless ``retry_failed``;
only the other inputs are processed. A previous run with other job options (or another imukit
version) keeps none: its numbers answer another question (before 2026-12-07 they were kept, and
labelled with the new options).

Files a folder search leaves out (no format reads them as an IMU recording) are named in the
summary's metadata (``left_out``) and by a :class:`LeftOutWarning`.

Per-log options: a manifest column named as one of the job's keyword options is that log's value of
it (over ``job_options``): ``reference`` for ``evaluate``, ``gyro_range`` per unit type for ``report``.
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import json
import os
import time
import uuid
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imukit._arrays import flag
from imukit._core import __version__
from imukit._errors import ParameterError
from imukit.fleet._inputs import PATH_COLUMNS, Input, scan, stamp
from imukit.fleet._jobs import JOBS
from imukit.fleet._load import Scalar

if TYPE_CHECKING:
    import pyarrow
    from distributed import Client

__all__ = ["SUMMARY", "LeftOutWarning", "log_id", "run"]

SUMMARY = "summary.parquet"
Progress = Callable[[int, int, int], None]
"""``progress(done, total, failed)``, called after each log."""

# What the schema metadata says about the columns (b"imukit" key, JSON).
_CONVENTIONS = {
    "units": "SI, in each column's name: _s seconds, _ns, _hz, _rad_s, _m_s2, _sqrt_hz densities, _m, _m_s, "
    "_deg degrees; preintegrate's rows are imukit.preint.window_arrays' (seconds, m/s, m)",
    "frames": "body frame of the IMU; world ENU, z up, gravity (0, 0, -9.81) m/s^2 (NED with the filter job's "
    "world='NED'); rotations R_wb (body to world), quaternions xyzw",
}


def log_id(path: str) -> str:
    """The partition key of a recording: 16 hex digits of the SHA-1 of its path."""
    return hashlib.sha1(path.encode()).hexdigest()[:16]


def run(
    job: str,
    inputs: str | os.PathLike[str] | Iterable[str | os.PathLike[str]],
    *,
    out: str | os.PathLike[str],
    client: Client | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: Progress | None = None,
    **job_options: Any,
) -> pyarrow.Table:
    """Run ``job`` (a name in :data:`imukit.fleet.JOBS`) on every recording of ``inputs``
    (:func:`imukit.fleet.find_inputs`) and return the summary, also written to ``out/summary.parquet``.

    ``client``: a ``dask.distributed.Client``; without one a ``LocalCluster`` of ``workers`` worker
    processes (default: one per core), one thread each, is started and closed again.
    ``job_options`` go to the job function.
    """

    if job not in JOBS:
        raise ParameterError(f"expected one of {', '.join(JOBS)}, got {job!r}", argument="job")
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    found = scan(inputs)
    todo = [(item, _stamp(item)) for item in found.found]
    kept = _previous(folder, job, flag(retry_failed, "retry_failed"), job_options)
    rows: dict[str, dict[str, Scalar]] = {}
    pending = []
    for item, key in todo:
        old = kept.get(item.path)
        if old is not None and (old["size_bytes"], old["mtime_ns"]) == key and _same_columns(old, item):
            rows[item.path] = old
        else:
            pending.append((item, key))
    if pending:
        with _client(client, workers) as dask:
            for row in _compute(dask, job, pending, folder, job_options, progress, len(todo) - len(pending), len(todo)):
                rows[str(row["path"])] = row
    ordered = [rows[item.path] for item, _ in todo]
    table = _table(ordered, job, job_options, found.left_out)
    _write_atomically(table, folder / SUMMARY)
    if found.left_out:
        shown = ", ".join(found.left_out[:3]) + (
            f" and {len(found.left_out) - 3} more" if len(found.left_out) > 3 else ""
        )
        warnings.warn(
            f"left out {len(found.left_out)} files under the folders given that no format reads as an IMU recording: "
            f"{shown} (named alone as an input, one is a failed row saying why; listed in the summary's metadata)",
            LeftOutWarning,
            stacklevel=2,
        )
    return table


def _same_columns(row: dict[str, Scalar], item: Input) -> bool:
    """Whether a kept row has the manifest columns ``item`` has now (a per-log option among them)."""
    return all(row.get(k) == v for k, v in item.metadata.items())


class LeftOutWarning(UserWarning):
    """Files under an input folder that :func:`run` left out: no format reads them as a recording."""


def _stamp(item: Input) -> tuple[int, int]:
    """The resume key of the files the log's task reads: the recording and its manifest's reference."""
    try:
        return stamp(item.path, *(str(item.metadata[c]) for c in PATH_COLUMNS[1:] if item.metadata.get(c) is not None))
    except OSError:
        return -1, -1  # the task's read fails and says why


def _previous(folder: Path, job: str, retry_failed: bool, options: dict[str, Any]) -> dict[str, dict[str, Scalar]]:
    """Rows of ``folder``'s summary that a re-run with ``options`` may keep, by path (module doc)."""
    import pyarrow.parquet

    path = folder / SUMMARY
    if not path.exists():
        return {}
    table = pyarrow.parquet.read_table(path)
    done = json.loads((table.schema.metadata or {}).get(b"imukit", b"{}"))
    if done.get("job") != job:
        raise ParameterError(
            f"{folder} holds the results of job {done.get('job')!r}, not {job!r}: choose another", argument="out"
        )
    now = json.loads(_metadata(job, options)[b"imukit"])
    if (done.get("options"), done.get("imukit_version")) != (now["options"], now["imukit_version"]):
        return {}
    return {row["path"]: row for row in table.to_pylist() if row["status"] == "ok" or not retry_failed}


# Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536, which also pins glibc's mmap
# threshold at 128 kB: every array of a 60 s log is then mmap'd and unmapped, ~4,900 page faults
# and +12 ms of system CPU per log, +26% worker CPU in all (bench/bench_fleet.py); without it the
# workers' peak RSS was lower too (155 vs 210 MB over 100 logs). A None leaves it out (distributed's
# rule); a process that started a cluster with the default before has it in its environment already.
_LOCAL_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


@contextlib.contextmanager
def _client(client: Client | None, workers: int | None) -> Iterator[Client]:
    """``client``, or a local cluster of ``workers`` worker processes (default one per core) and its
    client, closed on exit."""
    if client is not None:
        yield client
        return
    import dask
    from distributed import Client, LocalCluster

    cores = os.cpu_count() or 1
    n = workers if workers is not None else cores
    # imukit's kernels share the cores with the other workers: each worker's pool gets its share
    # (rayon reads RAYON_NUM_THREADS), as Dask gives BLAS one thread. A pool of every core in each
    # worker oversubscribed them: Robust's online run alone keeps two threads busy.
    environ = {"distributed.nanny.pre-spawn-environ.RAYON_NUM_THREADS": str(max(1, cores // n))}
    with dask.config.set({**_LOCAL_CONFIG, **environ}):  # read as each nanny is made, for its worker and its restarts
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:  # type: ignore[no-untyped-call]
            with Client(cluster) as local:  # type: ignore[no-untyped-call]
                yield local


def _compute(
    client: Client,
    job: str,
    pending: list[tuple[Input, tuple[int, int]]],
    folder: Path,
    options: dict[str, Any],
    progress: Progress | None,
    done: int,
    total: int,
) -> Iterator[dict[str, Scalar]]:
    from distributed import as_completed

    keys = [f"imukit-{job}-{log_id(item.path)}-{key[0]}-{key[1]}-{uuid.uuid4().hex[:8]}" for item, key in pending]
    futures = client.map(
        _task,
        [item for item, _ in pending],
        [key for _, key in pending],
        job=job,
        out=str(folder),
        options=options,
        key=keys,
    )
    by_future = {f.key: item for f, (item, _) in zip(futures, pending)}
    failed = 0
    for future in as_completed(futures):  # type: ignore[no-untyped-call]
        try:
            row = future.result()
        except Exception as exc:  # Dask gave up on it (e.g. KilledWorker): still one row
            item = by_future[future.key]
            row = _row(item, _stamp(item), "failed", _one_line(exc), 0.0, {})
        future.release()
        done += 1
        failed += row["status"] == "failed"
        if progress is not None:
            progress(done, total, failed)
        yield row


def _task(item: Input, key: tuple[int, int], *, job: str, out: str, options: dict[str, Any]) -> dict[str, Scalar]:
    """One recording: the job, its rows written, its summary row (module doc)."""
    start = time.perf_counter()
    function = JOBS[job]
    accepted = inspect.signature(function).parameters
    own = {k: v for k, v in item.metadata.items() if k in accepted and v is not None}  # a null: the run's option
    try:
        result = function(item.path, **{**options, **own})
        if result.rows is not None:
            _write_rows(result.rows, Path(out) / job, log_id(item.path), _metadata(job, options))
        status, error, scalars = "ok", None, result.scalars
    except Exception as exc:  # a failed row, never an aborted run
        status, error, scalars = "failed", _one_line(exc), {}
    return _row(item, key, status, error, time.perf_counter() - start, scalars)


def _row(
    item: Input, key: tuple[int, int], status: str, error: str | None, elapsed: float, scalars: dict[str, Scalar]
) -> dict[str, Scalar]:
    return {
        "path": item.path,
        "log": log_id(item.path),
        "size_bytes": key[0],
        "mtime_ns": key[1],
        "status": status,
        "error": error,
        "elapsed_s": elapsed,
        **item.metadata,
        **scalars,
    }


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


def _write_rows(rows: dict[str, Any], dataset: Path, log: str, metadata: dict[bytes, bytes]) -> None:
    """The log's rows as ``dataset/log=<log>/part-0.parquet``, renamed into place (the dataset's
    readers skip the ``.``-prefixed temporary), with the summary's schema metadata."""
    import numpy as np
    import pyarrow

    columns = {}
    for name, values in rows.items():
        array = np.asarray(values)
        columns[name] = pyarrow.array(list(array)) if array.ndim > 1 else pyarrow.array(array)
    partition = dataset / f"log={log}"
    partition.mkdir(parents=True, exist_ok=True)
    _write_atomically(pyarrow.table(columns).replace_schema_metadata(metadata), partition / "part-0.parquet")


def _table(rows: list[dict[str, Scalar]], job: str, options: dict[str, Any], left_out: list[str]) -> pyarrow.Table:
    import pyarrow

    names = list(dict.fromkeys(name for row in rows for name in row)) or ["path", "status", "error"]
    table = pyarrow.table({name: [row.get(name) for row in rows] for name in names})
    return table.replace_schema_metadata(_metadata(job, options, left_out=left_out))


def _metadata(job: str, options: dict[str, Any], **more: Any) -> dict[bytes, bytes]:
    """The schema metadata of every file a run writes: key ``imukit``, JSON (the summary's also has
    ``left_out``)."""
    meta = {"imukit_version": __version__, "job": job, "options": options, **_CONVENTIONS, **more}
    return {b"imukit": json.dumps(meta, default=str).encode()}


def _write_atomically(table: pyarrow.Table, target: Path) -> None:
    import pyarrow.parquet

    temporary = target.with_name(f".{target.name}.{uuid.uuid4().hex}")
    pyarrow.parquet.write_table(table, temporary)
    os.replace(temporary, target)
