"""``imukit.fleet.run("report", ...)`` on a local Dask cluster against a plain serial loop, same run.

Usage: ``python bench/bench_fleet.py [--logs 1000] [--seconds 60] [--rate 200] [--workers N]``.
Writes ``--logs`` simulated static logs (EuRoC folders, the noise of an ADIS-class IMU) to a
temporary folder (or ``--folder``, kept and reused), then times (1) ``imukit.fleet.report`` over
them in a loop in this process and (2) ``imukit.fleet.run`` on a ``LocalCluster`` of ``--workers``
processes started beforehand (its start-up and one warm-up log per worker and in this process are
printed apart), interleaved: the logs in ``--rounds`` blocks, each block serial then on the
cluster, so that both see the same load on a shared machine; the totals are summed. Prints logs/s
and samples/s of each, the speed-up, the Dask overhead per log, ``(wall_cluster * workers - sum of
the tasks' own elapsed_s) / logs`` (the time a worker slot spent on a log outside the job:
scheduling, transfer, the summary row), the wall time per task of as many no-op tasks (Dask's own
cost, free of the job), the peak RSS of each worker and of this process, and the load average
before and after each round (the machine may be shared).

On a shared machine the wall times measure the share of the CPU the run got: Linux's autogroup
scheduler gives each session (this script with its workers) a fair share of the cores however
many processes it runs. So the CPU seconds of each phase are printed too (this process's for the
serial loop; the workers', the scheduler's and the client's for the cluster), the cores each phase
got on average (CPU / wall), Dask's CPU cost per log (cluster CPU − serial CPU, per log: free of the
load), and the speed-up the cluster would reach with ``--workers`` cores to itself, CPU-bound:
``workers × serial CPU / cluster CPU``.

BLAS threads: Dask's nanny starts every worker with ``OMP_NUM_THREADS=OPENBLAS_NUM_THREADS=
MKL_NUM_THREADS=1`` (``distributed.nanny.pre-spawn-environ``); this script gives the serial loop
the same (``--blas-threads`` to change it), so that the two compare the scheduling, not BLAS's
threading of the Allan fit's small solves (which, threaded on a loaded 2-core machine, made a log
several times slower).
"""

from __future__ import annotations

import argparse
import os
import sys


def _blas_threads(argv: list[str]) -> None:
    """Set the BLAS thread count of this process from ``--blas-threads`` (default 1) before numpy loads."""
    value = argv[argv.index("--blas-threads") + 1] if "--blas-threads" in argv else "1"
    if value != "default":
        for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ[name] = value


_blas_threads(sys.argv)

import platform  # noqa: E402 (after the BLAS threads are set)
import resource  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import pyarrow  # noqa: E402

import imukit as ik  # noqa: E402
from imukit import fleet, sim  # noqa: E402
from imukit.fleet._run import _client  # noqa: E402


def _peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux


def _noop(k: int) -> int:
    return k


def _cpu_s() -> float:
    """CPU seconds (user + system) this process has used, all its threads."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _load() -> str:
    return "/".join(f"{v:.1f}" for v in os.getloadavg())


def _write_logs(folder: Path, args: argparse.Namespace) -> list[Path]:
    """The simulated logs under ``folder``, written unless there already (``--folder`` keeps them)."""
    noise = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)
    paths = [folder / f"log{k:05d}" for k in range(args.logs)]
    for k, path in enumerate(paths):
        if not path.exists():
            imu, truth = sim.simulate(sim.Static(), rate=args.rate, duration=args.seconds, noise=noise, seed=k)
            ik.io.write_euroc(path, imu, truth, noise=noise, rate_hz=args.rate)
    return paths


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--logs", type=int, default=1000)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--rate", type=float, default=200.0)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--rounds", type=int, default=5, help="blocks of logs, each timed serial then on the cluster")
    parser.add_argument("--folder", type=Path, help="keep the logs here (and reuse them) instead of a temporary folder")
    parser.add_argument("--blas-threads", default="1", help="BLAS threads of the serial loop ('default': unset)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        folder = args.folder or Path(tmp)
        start = time.perf_counter()
        paths = _write_logs(folder, args)
        written = time.perf_counter() - start
        samples = args.logs * (int(args.seconds * args.rate) + 1)
        out = Path(tmp) / "out"

        start = time.perf_counter()
        with _client(None, args.workers) as client:  # the local cluster imukit.fleet.run starts
            client.run(fleet.report, os.fspath(paths[0]))  # warm-up: imports in every worker
            fleet.report(paths[0])  # and in this process
            up = time.perf_counter() - start
            wall_serial = cpu_serial = wall_cluster = cpu_here = cpu_workers = 0.0
            tables = []
            for r in range(args.rounds):
                block = paths[r * len(paths) // args.rounds : (r + 1) * len(paths) // args.rounds]
                load = _load()
                start, cpu = time.perf_counter(), _cpu_s()
                for path in block:
                    fleet.report(path)
                wall, cpu = time.perf_counter() - start, _cpu_s() - cpu
                wall_serial, cpu_serial = wall_serial + wall, cpu_serial + cpu
                before = client.run(_cpu_s)
                start, cpu = time.perf_counter(), _cpu_s()
                tables.append(fleet.run("report", [str(p) for p in block], out=out / f"round{r}", client=client))
                wall_c, cpu_c = time.perf_counter() - start, _cpu_s() - cpu
                wall_cluster, cpu_here = wall_cluster + wall_c, cpu_here + cpu_c
                cpu_workers += sum(client.run(_cpu_s).values()) - sum(before.values())
                print(
                    f"round {r + 1}/{args.rounds}: {len(block)} logs, serial {wall:.1f} s, cluster {wall_c:.1f} s "
                    f"(load avg {load} -> {_load()})",
                    flush=True,
                )
            rss = client.run(_peak_rss_mb)
            start = time.perf_counter()
            client.gather(client.map(_noop, range(args.logs)))
            per_task = (time.perf_counter() - start) / args.logs

    table = pyarrow.concat_tables(tables)
    ok = table.column("status").to_pylist().count("ok")
    in_tasks = sum(table.column("elapsed_s").to_pylist())
    print(f"# imukit.fleet report: {args.logs} logs of {args.seconds:g} s at {args.rate:g} Hz ({samples} samples)")
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores; logs written in {written:.1f} s; "
        f"serial loop BLAS threads: {args.blas_threads}"
    )
    rates = f"{args.logs / wall_serial:8.2f} logs/s  {samples / wall_serial:12.0f} samples/s"
    print(f"serial loop, 1 process : {wall_serial:8.2f} s  {rates}")
    print(
        f"LocalCluster, {args.workers} workers: {wall_cluster:8.2f} s  {args.logs / wall_cluster:8.2f} logs/s  "
        f"{samples / wall_cluster:12.0f} samples/s  ({ok} ok; cluster start-up and warm-up {up:.1f} s, not counted)"
    )
    print(f"speed-up: {wall_serial / wall_cluster:.2f}x")
    print(
        f"Dask overhead per log: {1e3 * (wall_cluster * args.workers - in_tasks) / args.logs:.1f} ms "
        f"(worker time outside the job; the job itself {1e3 * in_tasks / args.logs:.1f} ms per log in the workers, "
        f"{1e3 * wall_serial / args.logs:.1f} ms in the serial loop)"
    )
    print(f"Dask round trip of a no-op task: {1e3 * per_task:.2f} ms per task ({args.logs} tasks)")
    cpu_cluster = cpu_workers + cpu_here
    print(
        f"CPU: serial {cpu_serial:.1f} s ({cpu_serial / wall_serial:.2f} cores on average); cluster: workers "
        f"{cpu_workers:.1f} s + scheduler and client {cpu_here:.1f} s ({cpu_cluster / wall_cluster:.2f} cores)"
    )
    print(
        f"Dask CPU cost per log: {1e3 * (cpu_cluster - cpu_serial) / args.logs:.1f} ms "
        f"({1e3 * cpu_serial / args.logs:.1f} ms per log serial, {1e3 * cpu_cluster / args.logs:.1f} ms on the cluster)"
    )
    print(
        f"speed-up with {args.workers} cores to itself (CPU-bound, from the CPU seconds above): "
        f"{args.workers * cpu_serial / cpu_cluster:.2f}x"
    )
    print(f"peak RSS: workers {', '.join(f'{v:.0f}' for v in rss.values())} MB; this process {_peak_rss_mb():.0f} MB")


if __name__ == "__main__":
    main()
