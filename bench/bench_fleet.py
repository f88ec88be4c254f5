"""``imukit.fleet.run("report", ...)`` on a local Dask cluster against a plain serial loop, same run.

Usage: ``python bench/bench_fleet.py [--logs 1000] [--seconds 60] [--rate 200] [--workers N]``.
Writes ``--logs`` simulated static logs (EuRoC folders, the noise of an ADIS-class IMU) to a
temporary folder, then times (1) ``imukit.fleet.report`` over all of them in a loop in this
process, before and after (the faster counts: other load on a shared machine only slows), and
(2) ``imukit.fleet.run`` on a ``LocalCluster`` of ``--workers`` processes started beforehand (its
start-up is printed apart). Prints logs/s and samples/s of each, the speed-up, the
Dask overhead per log, ``(wall_cluster * workers - wall_serial) / logs`` (the time a worker spent
on a log beyond the job itself), the wall time per task of as many no-op tasks (Dask's own cost,
free of the job), and the peak RSS of each worker and of this process.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import tempfile
import time
from pathlib import Path

import imukit as ik
from imukit import fleet, sim


def _peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux


def _noop(k: int) -> int:
    return k


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=int, default=1000)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--rate", type=float, default=200.0)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()

    from distributed import Client, LocalCluster

    noise = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        start = time.perf_counter()
        for k in range(args.logs):
            imu, truth = sim.simulate(sim.Static(), rate=args.rate, duration=args.seconds, noise=noise, seed=k)
            ik.io.write_euroc(folder / f"log{k:05d}", imu, truth, noise=noise, rate_hz=args.rate)
        written = time.perf_counter() - start
        samples = args.logs * (int(args.seconds * args.rate) + 1)

        paths = sorted(folder.iterdir())

        def serial_loop() -> float:
            start = time.perf_counter()
            for path in paths:
                fleet.report(path)
            return time.perf_counter() - start

        before = serial_loop()

        start = time.perf_counter()
        with LocalCluster(
            n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster:
            with Client(cluster) as client:
                up = time.perf_counter() - start
                start = time.perf_counter()
                table = fleet.run("report", str(folder / "log*"), out=folder / "out", client=client)
                wall_cluster = time.perf_counter() - start
                rss = client.run(_peak_rss_mb)
                start = time.perf_counter()
                client.gather(client.map(_noop, range(args.logs)))
                per_task = (time.perf_counter() - start) / args.logs
        wall_serial = min(before, serial_loop())  # before and after: other load on a shared machine

    ok = table.column("status").to_pylist().count("ok")
    print(f"# imukit.fleet report: {args.logs} logs of {args.seconds:g} s at {args.rate:g} Hz ({samples} samples)")
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores; logs written in {written:.1f} s")
    rates = f"{args.logs / wall_serial:8.2f} logs/s  {samples / wall_serial:12.0f} samples/s"
    print(f"serial loop, 1 process : {wall_serial:8.2f} s  {rates}")
    print(
        f"LocalCluster, {args.workers} workers: {wall_cluster:8.2f} s  {args.logs / wall_cluster:8.2f} logs/s  "
        f"{samples / wall_cluster:12.0f} samples/s  ({ok} ok; cluster start-up {up:.1f} s, not counted)"
    )
    print(f"speed-up: {wall_serial / wall_cluster:.2f}x")
    print(f"Dask overhead per log: {1e3 * (wall_cluster * args.workers - wall_serial) / args.logs:.1f} ms")
    print(f"Dask round trip of a no-op task: {1e3 * per_task:.2f} ms per task ({args.logs} tasks)")
    print(f"peak RSS: workers {', '.join(f'{v:.0f}' for v in rss.values())} MB; this process {_peak_rss_mb():.0f} MB")


if __name__ == "__main__":
    main()
