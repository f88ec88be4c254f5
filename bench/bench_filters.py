"""Attitude filters, batch ``run`` on 10^6 samples: imukit's Mahony and Madgwick, 6D and 9D, against
``vqf.VQF.updateBatch`` and ``imufusion.Ahrs`` (per-sample loop, its only API), in one run.

Usage: ``python bench/bench_filters.py [--n 1000000] [--repeats 5] [--loop-n 50000] [--no-robust | --only-robust]
[--cpu] [--imu-mag]``; to compare with another build, alternate runs with ``PYTHONPATH`` set to a
copy of its ``python/`` folder (``imukit`` with its ``_core``).
Prints the median time per sample (including the glue and building the returned ``Rotation``) and
the ratio peer / imukit (> 1: imukit faster). Peers that are not installed are skipped; imufusion is
timed on ``--loop-n`` samples and reported per sample. Targets (issue 20): 6D ≤ 35 ns, 9D ≤ 50 ns
per sample, and 9D ≥ 7× vqf 9D in the same run (the ratio is what counts on a loaded machine).
``imukit.filters.Robust`` online and offline against ``vqf.VQF.updateBatch`` and ``vqf.offlineVQF``
(issue 15's targets: ≥ 3× faster than each, but online 6D, which has none).
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from collections.abc import Callable

import numpy as np

import imukit as ik
from _timing import Paired, median_s, paired, synthetic_imu

TARGET_NS = {"6D": 35.0, "9D": 50.0}
TARGET_RATIO_9D = 7.0
# Flops and bytes (inputs read + outputs written) per sample of the steady-state step at the
# defaults, counted from the code (docs/performance.md, "Filters, simulator and Allan: work per
# sample"), and the floor at one core's FMA peak (48 flops/ns); the step is a dependent chain of
# ~60 cycles (Mahony, Madgwick), so the chain, not the flops, is the realistic bound.
WORK = {"Mahony 6D": (310, 112), "Mahony 9D": (390, 136), "Madgwick 6D": (310, 112), "Madgwick 9D": (390, 136)}
FLOPS_PER_NS = 48.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--loop-n", type=int, default=50_000)
    parser.add_argument("--repeats", type=int, default=5)
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--no-robust", action="store_true", help="skip Robust against vqf")
    which.add_argument("--only-robust", action="store_true", help="only Robust against vqf (issue 15's rows)")
    parser.add_argument("--cpu", action="store_true", help="CPU time (process_time) instead of wall time")
    parser.add_argument("--imu-mag", action="store_true", help="9D from imu.mag (read in place) instead of mag=")
    args = parser.parse_args()
    clock = time.process_time if args.cpu else time.perf_counter

    t, gyro, accel = synthetic_imu(args.n)
    mag = np.stack([20.0 * np.cos(0.2 * t), 20.0 * np.sin(0.2 * t), np.full_like(t, -40.0)], axis=-1)
    imu = ik.ImuData(t, gyro, accel, mag=mag if args.imu_mag else None)
    dt = float(t[1] - t[0])
    if args.only_robust:
        robust_vs_vqf(imu, mag, args.repeats, clock)
        return

    g, a, mg = (np.ascontiguousarray(x) for x in (gyro, accel, mag))
    vqf_run: dict[str, Callable[[], object]] = {}
    if importlib.util.find_spec("vqf") is not None:
        from vqf import VQF

        vqf_run = {"6D": lambda: VQF(dt).updateBatch(g, a), "9D": lambda: VQF(dt).updateBatch(g, a, mg)}
    else:
        print("vqf not installed: skipped")
    # Each filter is timed in pairs with vqf of the same sensor set (`paired`): the 9D ratio is a
    # target, and a ratio of medians taken apart follows the other tenants' load.
    ours: dict[str, float] = {}
    pairs: dict[str, Paired] = {}
    print(f"{'filter':<18} {'ns/sample':>10} {'target':>8}")
    for name, make in (("Mahony", ik.filters.Mahony), ("Madgwick", ik.filters.Madgwick)):
        f = make()
        for dim, m in (("6D", None), ("9D", mag)):
            use: np.ndarray | bool | None = m
            if args.imu_mag:
                use = False if m is None else None  # None: imu.mag
            run = lambda f=f, use=use: f.run(imu, mag=use)  # noqa: E731
            if dim in vqf_run:
                pair = paired(run, vqf_run[dim], args.repeats, clock)
                pairs[f"{name} {dim}"], s = pair, pair.a_s
            else:
                s = median_s(run, args.repeats, clock)
            ns = s / args.n * 1e9
            ours[f"{name} {dim}"] = ns
            flag = "ok" if ns <= TARGET_NS[dim] else "MISSED"
            print(f"{name + ' ' + dim:<18} {ns:10.1f} {TARGET_NS[dim]:6.0f}   {flag}")

    for dim in vqf_run:
        ratios = ", ".join(f"{pairs[f'{x} {dim}'].ratio_text()} vs {x}" for x in ("Mahony", "Madgwick"))
        ns = np.mean([pairs[f"{x} {dim}"].b_s for x in ("Mahony", "Madgwick")]) / args.n * 1e9
        print(f"{f'vqf {dim} (updateBatch)':<24} {ns:10.1f} ns/sample   ({ratios}, per pair)")
    peers: dict[str, float] = {}
    if importlib.util.find_spec("imufusion") is not None:
        import imufusion

        k = min(args.loop_n, args.n)
        g_deg = np.degrees(gyro[:k])
        a_g = accel[:k] / 9.81

        def fusion(nine: bool) -> None:
            ahrs = imufusion.Ahrs()
            ahrs.set_sample_period(dt)
            # Read the output each sample, as a user must (imufusion 1.3 API).
            if nine:
                for i in range(k):
                    ahrs.update(g_deg[i], a_g[i], mag[i])
                    ahrs.get_quaternion()
            else:
                for i in range(k):
                    ahrs.update_no_magnetometer(g_deg[i], a_g[i])
                    ahrs.get_quaternion()

        peers["imufusion 6D (loop)"] = median_s(lambda: fusion(False), 3) / k * 1e9
        peers["imufusion 9D (loop)"] = median_s(lambda: fusion(True), 3) / k * 1e9
    else:
        print("imufusion not installed: skipped")

    for peer, ns in peers.items():
        dim = "9D" if "9D" in peer else "6D"
        ratios = ", ".join(f"{ns / ours[f'{name} {dim}']:.1f}x vs {name}" for name in ("Mahony", "Madgwick"))
        print(f"{peer:<24} {ns:10.1f} ns/sample   ({ratios})")
    issue20_table(ours, pairs, args.n)
    if not args.no_robust:
        robust_vs_vqf(imu, mag, args.repeats, clock)


def issue20_table(ours: dict[str, float], pairs: dict[str, Paired], n: int) -> None:
    """Issue 20's rows of the filters, as its table: ns/sample, vqf of the same sensor set timed in
    pairs with it, the ratio per pair (median and range), and whether the targets (ns, and ≥ 7× vqf
    for 9D, on the median ratio) are met."""
    print("\n| kernel | flops | bytes | floor ns | ns/sample | vqf, paired | vqf / ours per pair | target |")
    print("|---|---|---|---|---|---|---|---|")
    for name in ("Mahony", "Madgwick"):
        for dim in ("6D", "9D"):
            ns, pair = ours[f"{name} {dim}"], pairs.get(f"{name} {dim}")
            target = f"≤ {TARGET_NS[dim]:.0f}" + (f", ≥ {TARGET_RATIO_9D:.0f}× vqf" if dim == "9D" else "")
            met = ns <= TARGET_NS[dim] and (dim == "6D" or (pair is not None and pair.ratio >= TARGET_RATIO_9D))
            shown = ("—", "—") if pair is None else (f"{pair.b_s / n * 1e9:.0f}", pair.ratio_text())
            flops, nbytes = WORK[f"{name} {dim}"]
            work = f"{flops} | {nbytes} | {flops / FLOPS_PER_NS:.1f}"
            verdict = "met" if met else "MISSED"
            print(f"| {name} {dim} | {work} | {ns:.1f} | {shown[0]} | {shown[1]} | {target}: {verdict} |")


def robust_vs_vqf(imu: ik.ImuData, mag: np.ndarray, repeats: int, clock: Callable[[], float]) -> None:
    """``Robust`` online / offline against vqf's online / offline filter, same data, same run, on
    ``clock``. The smoother runs its forward and backward passes on two threads: with ``--cpu`` its
    row counts both threads' time (the work), without it the wall time (what a user waits)."""
    if importlib.util.find_spec("vqf") is None:
        return
    import vqf

    g, a, mg = (np.ascontiguousarray(x) for x in (imu.gyro, imu.accel, mag))
    dt, n, f = float(imu.t[1] - imu.t[0]), len(imu.t), ik.filters.Robust()
    for dim, m in (("6D", None), ("9D", mg)):
        for offline in (False, True):
            if offline:
                peer = lambda m=m: vqf.offlineVQF(g, a, m, dt)  # noqa: E731
            else:
                args = (g, a) if m is None else (g, a, m)
                peer = lambda args=args: vqf.VQF(dt).updateBatch(*args)  # noqa: E731
            # With --imu-mag the field is imu.mag (read in place), else the mag= array (copied).
            use = False if m is None else (None if imu.mag is not None else m)
            ours = lambda use=use, o=offline: f.run(imu, mag=use, offline=o)  # noqa: E731
            pair = paired(ours, peer, repeats, clock)
            name = f"Robust {'offline' if offline else 'online'} {dim}"
            times = f"{pair.a_s / n * 1e9:8.1f} ns/sample, vqf {pair.b_s / n * 1e9:8.1f}"
            # Issue 15 sets ≥ 3× for offline (6D and 9D) and online 9D; none for online 6D.
            if offline or dim == "9D":
                target = f"(target 3x) {'ok' if pair.ratio >= 3.0 else 'MISSED'}"
            else:
                target = "(no target)"
            print(f"{name:<20} {times}: {pair.ratio_text()} per pair {target}")


if __name__ == "__main__":
    main()
