"""The dispatched kernels per instruction-set path (``IMUKIT_SIMD``), with their flop and byte
counts, the floor on this CPU and the peers, in one table (``docs/performance.md``).

Each path runs in its own process (the choice is made once per process), one thread, alternated
``--rounds`` times; each cell is the median over rounds of the median over ``--repeats`` calls, in
ns per sample. The peer rows (GTSAM's per-sample Python loop for preintegration, the euler and
combined forms) run in the parent, between the rounds, so the ratios compare the same load.
The ``preintegrate_windows`` rows time windows of ``WINDOW`` samples on one and two threads (the
floor of a two-thread row is per two cores).

With ``--cpu`` every cell (the peers' too) is the process's CPU time (``time.process_time``), what a
loaded machine inflates least.

Usage: ``python bench/bench_simd.py [--n 200000] [--gtsam-n 20000] [--rounds 3] [--repeats 5]
[--only windows] [--cpu]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik
from _timing import median_s, synthetic_imu

try:
    import gtsam
except ImportError:  # a dev peer; the imukit rows run without it
    gtsam = None

PATHS = ("baseline", "avx2", "avx512")
# Floating-point operations and bytes moved per sample, counted from the kernels' code (3×3
# products 45 flops, symmetric ones 30, axpys 18; docs/performance.md), and the target of issue 20.
KERNELS = {
    "preintegrate euler (9×9 + 9×6)": (950, 56, 100),
    "preintegrate midpoint": (2400, 56, 150),
    "preintegrate combined (15×15)": (1650, 56, 180),
    "propagate (15×15 each sample)": (2000, 136, 150),
    # The same step with one covariance in 1000 written: the step without the output's 1.8 kB a sample.
    "propagate (15×15, every 1000th kept)": (2000, 136, None),
    # Records over 65,537 samples run in chunks on the threads (strapdown/chunks.rs): on one thread
    # that adds the rows' turn into the world; the target is the default call's, on every core.
    "integrate midpoint, 1 thread": (200, 136, None),
    "integrate midpoint, 2 threads": (200, 136, 25),
    "integrate_attitude": (120, 64, None),
    "preintegrate_windows euler, 1 thread": (950, 56, None),
    "preintegrate_windows euler, 2 threads": (950, 56, None),
    # The same windows with one sample each flagged as clipped, which keeps them off the SIMD lanes
    # of the AVX paths (`preint/lanes/`): the per-window kernel, for the lanes' gain.
    "preintegrate_windows euler, per-window kernel, 1 thread": (950, 56, None),
    "preintegrate_windows midpoint, 1 thread": (2400, 56, None),
    "preintegrate_windows midpoint, per-window kernel, 1 thread": (2400, 56, None),
}
# The rows with a GTSAM peer.
PEER_ROWS = ("preintegrate euler (9×9 + 9×6)", "preintegrate combined (15×15)")
# Samples per window of the ``preintegrate_windows`` rows (keyframes at 1 Hz of 200 Hz data).
WINDOW = 200
# Rows whose floor is shared by two cores.
TWO_THREADS = {name for name in KERNELS if name.endswith("2 threads")}
# One core's double-precision peak at the clock of this host's EPYC (2 FMA pipes × 4 lanes × 2
# flops at ~3 GHz): the floor is flops / FLOPS_PER_NS, the byte traffic is far below bandwidth.
FLOPS_PER_NS = 48.0


def cases(n: int) -> dict[str, Callable[[], object]]:
    t, gyro, accel = synthetic_imu(n)
    imu = ik.ImuData(t, gyro, accel)
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    initial = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    names = list(KERNELS)
    return {
        names[0]: lambda: ik.preintegrate(imu, noise=noise, scheme="lie_euler", threads=1),
        names[1]: lambda: ik.preintegrate(imu, noise=noise, scheme="midpoint", threads=1),
        names[2]: lambda: ik.preintegrate(imu, noise=noise, scheme="lie_euler", combined=True, threads=1),
        names[3]: lambda: ik.propagate(imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise),
        names[4]: lambda: ik.propagate(
            imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise, covariance_every=1000
        ),
        names[5]: lambda: ik.integrate(imu, initial=initial, scheme="midpoint", threads=1),
        names[6]: lambda: ik.integrate(imu, initial=initial, scheme="midpoint", threads=2),
        names[7]: lambda: ik.integrate_attitude(t, gyro, threads=1),
        **windows_cases(t, gyro, accel, noise, names[8:]),
    }


def windows_cases(
    t: np.ndarray, gyro: np.ndarray, accel: np.ndarray, noise: ik.ImuNoise, names: list[str]
) -> dict[str, Callable[[], object]]:
    """``preintegrate_windows`` over windows of ``WINDOW`` samples: euler on one and two threads,
    and on one thread with one sample of each window at the gyro's range (the per-window kernel);
    midpoint on one thread, both ways."""
    imu = ik.ImuData(t, gyro, accel)
    flagged = gyro.copy()
    flagged[WINDOW // 2 :: WINDOW, 0] = 100.0
    clipped = ik.ImuData(t, flagged, accel, gyro_range=100.0)
    boundaries = t[::WINDOW]
    euler, midpoint = (ik.PreintParams(noise, scheme=s) for s in ("lie_euler", "midpoint"))
    runs = ((euler, imu, 1), (euler, imu, 2), (euler, clipped, 1), (midpoint, imu, 1), (midpoint, clipped, 1))
    return {
        name: (lambda p=p, d=d, k=k: ik.preintegrate_windows(d, boundaries, p, threads=k))
        for name, (p, d, k) in zip(names, runs, strict=True)
    }


def child(n: int, repeats: int, only: str, clock: Callable[[], float]) -> None:
    """One path's row, as JSON on stdout."""
    row = {"path": ik.simd_path()}
    row.update({name: median_s(f, repeats, clock) / n * 1e9 for name, f in cases(n).items() if only in name})
    print(json.dumps(row))


def gtsam_rows(n: int, clock: Callable[[], float]) -> dict[str, float]:
    """ns per sample of GTSAM's Python loops (euler: the manifold class; combined)."""
    if gtsam is None:
        return {}
    t, gyro, accel = synthetic_imu(n)
    steps = np.diff(t).tolist()
    params = gtsam.PreintegrationCombinedParams.MakeSharedU(9.81)
    for name in ("setGyroscopeCovariance", "setAccelerometerCovariance", "setIntegrationCovariance"):
        getattr(params, name)(1e-6 * np.eye(3))

    def loop(make: Callable[[], object]) -> float:
        pim = make()
        step = pim.integrateMeasurement  # type: ignore[attr-defined]
        start = clock()
        for k in range(n - 1):
            step(accel[k], gyro[k], steps[k])
        return (clock() - start) / (n - 1) * 1e9

    return {
        "preintegrate euler (9×9 + 9×6)": loop(lambda: gtsam.PreintegratedImuMeasurementsManifold(params)),
        "preintegrate combined (15×15)": loop(lambda: gtsam.PreintegratedCombinedMeasurements(params)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200_000)
    parser.add_argument("--gtsam-n", type=int, default=20_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--only", default="", help="run the kernels whose name contains this")
    parser.add_argument("--cpu", action="store_true", help="time CPU, not wall-clock, time")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    clock = time.process_time if args.cpu else time.perf_counter
    if args.child:
        child(args.n, args.repeats, args.only, clock)
        return
    runs: dict[str, list[dict[str, float]]] = {p: [] for p in PATHS}
    peers: list[dict[str, float]] = []
    used: dict[str, str] = {}
    for _ in range(args.rounds):
        for path in PATHS:
            env = dict(os.environ, IMUKIT_SIMD=path, RAYON_NUM_THREADS="1")
            command = [sys.executable, __file__, "--child", f"--n={args.n}", f"--repeats={args.repeats}"]
            command.append(f"--only={args.only}")
            command += ["--cpu"] if args.cpu else []
            out = subprocess.run(command, env=env, check=True, capture_output=True, text=True).stdout
            row = json.loads(out)
            used[path] = row.pop("path")
            runs[path].append(row)
        if any(args.only in name for name in PEER_ROWS):
            peers.append(gtsam_rows(args.gtsam_n, clock))
    what = "CPU" if args.cpu else "wall-clock"
    print(f"paths in use: {used}; n = {args.n:,}, {args.rounds} alternated rounds, one thread, {what} time")
    header = "| kernel | flops | bytes | floor ns | " + " | ".join(PATHS) + " | target | peer ns | peer/best |"
    print(header)
    print("|" + "---|" * (header.count("|") - 1))
    for name, (flops, nbytes, target) in KERNELS.items():
        if args.only not in name:
            continue
        cells = [float(np.median([r[name] for r in runs[p]])) for p in PATHS]
        peer = [p[name] for p in peers if name in p]
        peer_ns = float(np.median(peer)) if peer else None
        ratio = f"{peer_ns / min(cells):.1f}×" if peer_ns else "—"
        print(
            f"| {name} | {flops} | {nbytes} | {flops / FLOPS_PER_NS / (2 if name in TWO_THREADS else 1):.0f} | "
            + " | ".join(f"{c:.0f}" for c in cells)
            + f" | {target or '—'} | {f'{peer_ns:.0f}' if peer_ns else '—'} | {ratio} |"
        )


if __name__ == "__main__":
    main()
