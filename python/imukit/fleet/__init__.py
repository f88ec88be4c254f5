"""Many recordings at once: jobs on one log each, run over a fleet of logs on Dask (``docs/fleet.md``).

=====================  ===========================================================================
jobs                   plain functions on one recording (a path), usable without Dask, returning
                       :class:`JobOutput` (scalars with units in their names, optional row arrays):
                       :func:`report` (timing, gaps, skipped lines, saturation, rest, bias, noise),
                       ``filter``, ``integrate``, :func:`evaluate` (an estimate against its
                       reference: ATE, RPE) and :func:`preintegrate` (rows per sample or window);
                       :data:`JOBS` maps names to them
:func:`run`            ``run(job, inputs, *, out, client=None, **job_options)`` → ``pyarrow.Table``:
                       one Dask task per log, ``summary.parquet`` and a dataset partitioned by log
                       under ``out``; failures become rows, a re-run with the same options skips
                       the logs already done; files a folder search left out: a
                       :class:`LeftOutWarning`
:func:`find_inputs`    a list of paths, a glob, a folder (every recording the Format registry
                       detects under it; :func:`scan` also names the files it left out) or a
                       manifest (CSV / Parquet with ``path``, metadata, per-log job options such as
                       ``reference``)
:func:`rest_segments`  the still stretches of a recording
=====================  ===========================================================================

Dask and pyarrow (``pip install 'imukit[fleet]'``) are imported by :func:`run` only, never by
``import imukit``.
"""

from __future__ import annotations

from imukit.fleet._inputs import Input, Scan, find_inputs, scan
from imukit.fleet._jobs import JOBS, preintegrate
from imukit.fleet._load import JobOutput, Recording, load
from imukit.fleet._report import ALLAN_MIN_S, report
from imukit.fleet._rest import RestRule, RestSegment, rest_segments
from imukit.fleet._run import LeftOutWarning, run
from imukit.fleet._score import evaluate

__all__ = [
    "ALLAN_MIN_S",
    "JOBS",
    "Input",
    "JobOutput",
    "LeftOutWarning",
    "Recording",
    "RestRule",
    "RestSegment",
    "Scan",
    "evaluate",
    "find_inputs",
    "load",
    "preintegrate",
    "report",
    "rest_segments",
    "run",
    "scan",
]
