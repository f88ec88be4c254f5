"""``imukit fleet``: a job over many recordings on Dask, results in Parquet (imukit.fleet)."""

from __future__ import annotations

import argparse
import inspect
import warnings
from pathlib import Path
from typing import Any

from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from imukit.cli._common import CliError, err, note, out, positive, wrote
from imukit.cli._evaluate import ALIGNMENTS
from imukit.fleet import JOBS, LeftOutWarning
from imukit.fleet import run as run_fleet
from imukit.fleet._jobs import FILTERS

DESCRIPTION = """\
Run JOB on every recording of INPUTS, one Dask task per recording, and write the results under
--out (docs/fleet.md): summary.parquet (one row per input: path, status ok|failed, error, the
job's numbers with units in the column names) and, for jobs with rows, a dataset partitioned by
log (DIR/JOB/log=<id>/part-0.parquet).

Jobs: report (duration, rate and jitter, gaps, skipped lines, saturation, rest segments, bias and
noise density at rest, Allan fit), filter (attitude per sample as rows, RMSE against the log's
ground truth), integrate (dead reckoning from the log's ground truth, ATE / RPE against it; the
trajectory as rows), evaluate (an estimate, e.g. a VIO output per log, against its reference:
ATE / RPE after --align; the errors per pose as rows), preintegrate (windows of --window-s seconds
as rows).
INPUTS: recording files or folders, globs ('logs/*.csv'), folders of recordings (every recording
found under them), or a manifest (.parquet, or .csv with a `path` column; its other columns are
copied into the summary, and a column named as a job option is that log's value of it: evaluate's
`reference`). Bad lines in inputs are skipped and counted.
Without --scheduler a local cluster of --workers worker processes runs the tasks; with it, an
existing Dask cluster (a `dask scheduler`, dask-jobqueue on SLURM, Kubernetes) does.
Re-running with the same --out skips the recordings already done (same path, size and mtime).
Writes: DIR/summary.parquet, DIR/JOB/log=<id>/part-0.parquet. Prints the counts and a table of the
failed recordings; exit code 1 when some recording failed.

Example:
  imukit fleet report 'logs/*' --out fleet_report --gyro-range 34.9
  imukit fleet evaluate estimates.csv --out scores --align yaw   # columns path, reference"""

# Job option -> (flag, argparse keywords); each goes to the jobs whose signature takes it.
_OPTIONS: dict[str, tuple[str, dict[str, Any]]] = {
    "gyro_range": ("--gyro-range", {"type": positive, "metavar": "RAD_S", "help": "report: gyro full scale"}),
    "accel_range": ("--accel-range", {"type": positive, "metavar": "M_S2", "help": "report: accel full scale"}),
    "allan_min_s": (
        "--allan-min-s",
        {"type": positive, "metavar": "S", "help": "report: shortest rest segment given an Allan fit (default 60)"},
    ),
    "method": ("--method", {"choices": tuple(FILTERS), "help": "filter: the filter (default robust)"}),
    "world": ("--world", {"choices": ("ENU", "NED"), "help": "filter: the world frame (default ENU)"}),
    "max_dt": (
        "--max-dt",
        {
            "type": positive,
            "metavar": "S",
            "help": "filter, integrate, evaluate: longest truth gap bridged (default: 2.5 x its median step)",
        },
    ),
    "window_s": ("--window-s", {"type": positive, "metavar": "S", "help": "preintegrate: window length (default 0.1)"}),
    "scheme": ("--scheme", {"metavar": "NAME", "help": "integrate, preintegrate: the scheme (default: the core's)"}),
    "bias_from_truth": (
        "--bias-from-truth",
        {"action": "store_const", "const": True, "help": "integrate: correct by the truth's initial biases"},
    ),
    "rpe_delta_s": (
        "--rpe-delta-s",
        {"type": positive, "metavar": "S", "help": "integrate, evaluate: RPE interval (default 1)"},
    ),
    "reference": (
        "--reference",
        {"metavar": "GT", "help": "evaluate: the reference of every log (default: the manifest's reference column)"},
    ),
    "align": ("--align", {"choices": ALIGNMENTS, "help": "evaluate: alignment before scoring (default se3)"}),
    "noise_yaml": ("--noise", {"metavar": "YAML", "help": "preintegrate: Kalibr imu.yaml (default: sensor.yaml)"}),
}


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "fleet",
        help="run a job (report, filter, integrate, evaluate, preintegrate) over many recordings on Dask, to Parquet",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("job", metavar="JOB", choices=tuple(JOBS), help=f"one of {', '.join(JOBS)}")
    p.add_argument("inputs", metavar="INPUTS", nargs="+", help="recordings, globs, folders or a manifest")
    p.add_argument("--out", required=True, metavar="DIR", help="the results folder (created)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, metavar="N", help="local cluster size (default: one per core)")
    p.add_argument("--retry-failed", action="store_true", help="on a re-run, process failed recordings again")
    for name, (flag, keywords) in _OPTIONS.items():
        p.add_argument(flag, dest=name, **keywords)
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    accepted = inspect.signature(JOBS[args.job]).parameters
    options = {name: getattr(args, name) for name in _OPTIONS if getattr(args, name) is not None}
    for name in options:
        if name not in accepted:
            raise CliError(f"is not an option of the {args.job} job", argument=_OPTIONS[name][0])
    if args.scheduler is not None and args.workers is not None:
        raise CliError("sizes a local cluster; a --scheduler has its own workers", argument="--workers")
    bar = Progress(
        TextColumn(f"{args.job}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[failed]} failed"),
        TimeElapsedColumn(),
        console=err,
        transient=True,
        disable=not err.is_terminal,
    )
    task = bar.add_task(args.job, total=None, failed=0)

    def progress(done: int, total: int, failed: int) -> None:
        bar.update(task, completed=done, total=total, failed=failed)

    with bar, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LeftOutWarning)
        if args.scheduler is None:
            table = run_fleet(
                args.job,
                args.inputs,
                out=args.out,
                workers=args.workers,
                retry_failed=args.retry_failed,
                progress=progress,
                **options,
            )
        else:
            from distributed import Client

            with Client(args.scheduler) as client:  # type: ignore[no-untyped-call]
                table = run_fleet(
                    args.job,
                    args.inputs,
                    out=args.out,
                    client=client,
                    retry_failed=args.retry_failed,
                    progress=progress,
                    **options,
                )
    for w in caught:
        if issubclass(w.category, LeftOutWarning):
            note(str(w.message))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    rows = table.select(["path", "status", "error"]).to_pylist()
    failed = [row for row in rows if row["status"] == "failed"]
    out.print(f"{len(rows)} recordings: {len(rows) - len(failed)} ok, {len(failed)} failed", markup=False)
    if failed:
        listing = Table(title="failed recordings")
        listing.add_column("path", no_wrap=True)  # whole, to be copied; the error wraps
        listing.add_column("error")
        for row in failed:
            listing.add_row(row["path"], row["error"])
        out.print(listing)
    wrote("summary", Path(args.out) / "summary.parquet")
    return 1 if failed else 0
