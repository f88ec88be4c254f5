"""Two variants of the dispatched kernels alternated in fresh processes, for a ratio that the load of
this noisy 2-core host moves least: two instruction-set paths (``IMUKIT_SIMD``), or this build
against another one (a copy of ``python/imukit`` with its ``_core``, put first on ``PYTHONPATH``).

Each round runs one process per variant (their order alternating from round to round); a process
times every kernel (median of ``--repeats`` calls, one thread unless the kernel's name says
otherwise) on ``--n`` samples of ``_timing.synthetic_imu``. Printed per kernel: the median over the
rounds of each variant's ns/sample and the median (min–max) over the rounds of the second
variant's time over the first's.

Usage: ``python bench/simd_ab.py avx2 avx512 [--rounds 8] [--kernels mahony6 robust6 ...]``;
a variant is a path name (``baseline``, ``avx2``, ``avx512``, ``auto``) or a folder holding another
build's ``imukit`` package (``python bench/simd_ab.py /tmp/base auto``); ``--simd PATH`` runs both
builds of such a pair on that path (``python bench/simd_ab.py /tmp/base /tmp/new --simd baseline``;
a path-name variant sets its own).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik
from _timing import median_s, synthetic_imu

PATHS = ("baseline", "avx2", "avx512", "auto")


def kernels(n: int) -> dict[str, Callable[[], object]]:
    """Every dispatched kernel, by short name."""
    t, gyro, accel = synthetic_imu(n)
    mag = np.stack([20.0 * np.cos(0.2 * t), 20.0 * np.sin(0.2 * t), np.full_like(t, -40.0)], axis=-1)
    imu = ik.ImuData(t, gyro, accel)
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    initial = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    mahony, madgwick, robust = ik.filters.Mahony(), ik.filters.Madgwick(), ik.filters.Robust()
    euler, midpoint = (ik.PreintParams(noise, scheme=s) for s in ("lie_euler", "midpoint"))
    return {
        "mahony6": lambda: mahony.run(imu),
        "mahony9": lambda: mahony.run(imu, mag=mag),
        "madgwick6": lambda: madgwick.run(imu),
        "madgwick9": lambda: madgwick.run(imu, mag=mag),
        "robust6": lambda: robust.run(imu, threads=1),
        "robust9": lambda: robust.run(imu, mag=mag, threads=1),
        "robust9_2threads": lambda: robust.run(imu, mag=mag, threads=2),
        "robust6_offline": lambda: robust.run(imu, offline=True, threads=1),
        "robust9_offline": lambda: robust.run(imu, mag=mag, offline=True, threads=1),
        "euler": lambda: ik.preintegrate(imu, noise=noise, scheme="lie_euler", threads=1),
        "midpoint": lambda: ik.preintegrate(imu, noise=noise, scheme="midpoint", threads=1),
        "combined": lambda: ik.preintegrate(imu, noise=noise, scheme="lie_euler", combined=True, threads=1),
        "windows": lambda: ik.preintegrate_windows(imu, t[::200], euler, threads=1),
        "windows_midpoint": lambda: ik.preintegrate_windows(imu, t[::200], midpoint, threads=1),
        "propagate": lambda: ik.propagate(imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise),
        "propagate_every1000": lambda: ik.propagate(
            imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise, covariance_every=1000
        ),
        "integrate": lambda: ik.integrate(imu, initial=initial, scheme="midpoint", threads=1),
        "integrate_attitude": lambda: ik.integrate_attitude(t, gyro, threads=1),
        "allan": lambda: ik.noise.allan_deviation(gyro[:, 0], 200.0, threads=1),
        "simulate": lambda: ik.sim.simulate(
            ik.sim.FigureEight(), rate=200.0, duration=n / 200.0, noise=noise, threads=1
        ),
    }


def child(n: int, repeats: int, names: list[str]) -> None:
    """One process's times, as JSON on stdout."""
    cases = kernels(n)
    print(json.dumps({k: median_s(cases[k], repeats, time.perf_counter) / n * 1e9 for k in names}))


def environment(variant: str, simd: str) -> dict[str, str]:
    env = dict(os.environ, IMUKIT_SIMD=simd)
    if variant in PATHS:
        env["IMUKIT_SIMD"] = variant
    else:
        env["PYTHONPATH"] = os.pathsep.join([variant, env.get("PYTHONPATH", "")])
    return env


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("variants", nargs=2, help="two paths or build folders")
    parser.add_argument("--rounds", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--n", type=int, default=200_000)
    parser.add_argument("--kernels", nargs="+", default=None, help="short names (default: all)")
    parser.add_argument("--simd", choices=PATHS, default="auto", help="the path of a build-folder variant")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    names = args.kernels or list(kernels(16))
    if args.child:
        child(args.n, args.repeats, names)
        return
    for v in args.variants:
        if v not in PATHS and not (Path(v) / "imukit").is_dir():
            parser.error(f"variant {v!r}: expected one of {PATHS} or a folder holding an imukit package")
    command = [sys.executable, __file__, *args.variants, "--child", "--n", str(args.n)]
    command += ["--repeats", str(args.repeats), "--kernels", *names]
    times: dict[str, list[dict[str, float]]] = {v: [] for v in args.variants}
    for r in range(args.rounds):
        for v in args.variants if r % 2 == 0 else args.variants[::-1]:
            out = subprocess.run(command, env=environment(v, args.simd), capture_output=True, text=True, check=True)
            times[v].append(json.loads(out.stdout))
    a, b = args.variants
    print(
        f"{args.rounds} alternated rounds, n = {args.n:,}, builds on path {args.simd}, ns/sample (median over rounds)"
    )
    print(f"| kernel | {a} | {b} | {b} / {a} per round: median (min–max) |")
    print("|---|---|---|---|")
    for k in names:
        ratios = [y[k] / x[k] for x, y in zip(times[a], times[b], strict=True)]
        ma, mb = (statistics.median(row[k] for row in times[v]) for v in (a, b))
        print(f"| {k} | {ma:.1f} | {mb:.1f} | {statistics.median(ratios):.3f} ({min(ratios):.2f}–{max(ratios):.2f}) |")


if __name__ == "__main__":
    main()
