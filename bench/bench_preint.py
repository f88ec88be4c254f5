"""Preintegration from Python, 10^6 samples at 200 Hz, euler scheme, 9×9 covariance and bias
Jacobians (``lie_euler``): ``imukit.preintegrate`` (one call, GIL released; with ``threads=1`` on one
core, its chunks four at a time in the SIMD lanes, and on all cores), the 15×15 and midpoint
variants, one window over the whole record (the per-window kernel, sample after sample),
``preintegrate_windows`` over 10^4 windows on 1 and 2 threads, against the streaming
``PreintegratedImu.integrate_measurement`` loop over a subset, and against GTSAM's
``integrateMeasurement`` called per sample from Python (``PreintegratedImuMeasurementsManifold``, the
same Forster scheme, and the default ``PreintegratedImuMeasurements``, which in the PyPI wheels is the
tangent scheme), all measured in the same run.

GTSAM has no batch fast path from Python: the C++ ``integrateMeasurements(accs, omegas, dts)`` (a
loop over matrix columns) is not wrapped in gtsam 4.3.0, so per-sample calls are the only way in.

Usage: ``python bench/bench_preint.py [--n 1000000] [--loop-n 20000] [--gtsam-n 100000]
[--repeats 7] [--windows 10000]``; medians per sample. ``--record-vs-list`` times only the windows
result, old against new, alternated (a noisy shared machine): the deprecated list of
``PreintegratedImu`` (one core handle per window) read into arrays property by property as the CLI
did, the list alone, and the one ``Preintegration`` record filled by one native call. Compare with
``cargo bench -p imukit-bench --bench preint`` for the Rust figure.
"""

from __future__ import annotations

import argparse
import time
import warnings
from collections.abc import Callable

import numpy as np

import imukit as ik
from _timing import median_s, synthetic_imu

try:
    import gtsam
except ImportError:  # a dev peer (requirements/dev.txt); the imukit rows still run without it
    gtsam = None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--loop-n", type=int, default=20_000)
    parser.add_argument("--gtsam-n", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--windows", type=int, default=10_000)
    parser.add_argument("--record-vs-list", action="store_true", help="only the windows result, old vs new")
    args = parser.parse_args()

    t, gyro, accel = synthetic_imu(args.n)
    imu = ik.ImuData(t, gyro, accel)
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    euler = ik.PreintParams(noise, scheme="lie_euler")
    if args.record_vs_list:
        record_vs_list(imu, noise, imu.t[:: max(1, args.n // args.windows)], args.repeats)
        return

    def stream(m: int) -> ik.PreintegratedImu:
        pim = ik.PreintegratedImu(noise=noise, scheme="lie_euler")
        for k in range(m - 1):
            pim.integrate_measurement(accel[k], gyro[k], 0.005)
        return pim

    m = args.loop_n
    gap = np.abs(stream(m).delta_position - ik.preintegrate(imu[:m], euler).delta_position).max()
    whole = [imu.t[0], imu.t[-1]]  # one window: the per-window kernel, sample after sample
    rows = [
        (
            # The batch on one thread: chunks of the record four at a time in the SIMD lanes.
            "preintegrate, 1 core",
            median_s(lambda: ik.preintegrate(imu, euler, threads=1), args.repeats) / args.n,
        ),
        (
            "one window, 1 core",
            median_s(lambda: ik.preintegrate_windows(imu, whole, euler, threads=1), args.repeats) / args.n,
        ),
        (
            "preintegrate (all cores)",
            median_s(lambda: ik.preintegrate(imu, euler), args.repeats) / args.n,
        ),
        (
            "preintegrate combined=True",
            median_s(lambda: ik.preintegrate(imu, ik.PreintParams(noise, scheme="lie_euler", combined=True)), 3)
            / args.n,
        ),
        (
            "preintegrate midpoint",
            median_s(lambda: ik.preintegrate(imu, ik.PreintParams(noise, scheme="midpoint")), 3) / args.n,
        ),
        ("integrate_measurement loop", median_s(lambda: stream(m), 1) / m),
    ]
    bounds = imu.t[:: max(1, args.n // args.windows)]
    for threads in (1, 2):
        seconds = median_s(
            lambda: ik.preintegrate_windows(imu, bounds, euler, threads=threads),  # noqa: B023
            args.repeats,
        )
        rows.append((f"{len(bounds) - 1:,} windows, {threads} thread(s)", seconds / args.n))
    print(f"n = {args.n:,}; batch vs streaming over {m:,} samples: max |Δp| gap = {gap:.1e} m")
    if gtsam is not None:
        g = min(args.gtsam_n, args.n)
        params = gtsam.PreintegrationParams.MakeSharedU(9.81)
        params.setGyroscopeCovariance(noise.gyro_density**2 * np.eye(3))
        params.setAccelerometerCovariance(noise.accel_density**2 * np.eye(3))
        params.setIntegrationCovariance(np.zeros((3, 3)))

        steps = np.diff(t[:g]).tolist()  # the batch's own intervals, as Python floats

        def gtsam_loop(cls: type) -> object:
            pim = cls(params)
            for k in range(g - 1):
                pim.integrateMeasurement(accel[k], gyro[k], steps[k])
            return pim

        manifold = gtsam_loop(gtsam.PreintegratedImuMeasurementsManifold)
        ours = ik.preintegrate(imu[:g], euler)
        gtsam_gap = np.abs(manifold.deltaPij() - ours.delta_position).max() / np.abs(ours.delta_position).max()
        print(f"imukit batch vs GTSAM manifold over {g:,} samples: max |Δp| gap = {gtsam_gap:.1e} relative")
        rows += [
            (
                "GTSAM manifold loop (Python)",
                median_s(lambda: gtsam_loop(gtsam.PreintegratedImuMeasurementsManifold), 1) / g,
            ),
            ("GTSAM default (tangent) loop", median_s(lambda: gtsam_loop(gtsam.PreintegratedImuMeasurements), 1) / g),
        ]
    else:
        print("gtsam not installed (pip install -r requirements/dev.txt): GTSAM rows skipped")
    base = rows[0][1]
    print(f"{'case':30s} {'ns/sample':>10s} {'÷ 1 core':>9s}")
    for name, seconds in rows:
        print(f"{name:30s} {seconds * 1e9:10.1f} {seconds / base:8.1f}x")
    if gtsam is not None:
        manifold_loop = dict(rows)["GTSAM manifold loop (Python)"]
        for name in ("preintegrate, 1 core", "preintegrate (all cores)"):
            ratio = dict(rows)[name] / manifold_loop
            print(f"imukit {name} / GTSAM manifold loop = {ratio:.3f} (imukit {1 / ratio:.1f}x faster)")


def record_vs_list(imu: ik.ImuData, noise: ik.ImuNoise, bounds: np.ndarray, repeats: int) -> None:
    """Old (list of handles, then 7 property reads per window) vs new (one record), alternated."""
    params = ik.PreintParams(noise, scheme="lie_euler")

    def as_arrays(pims: list[ik.PreintegratedImu]) -> list[np.ndarray]:
        return [
            np.array([p.delta_rotation.as_matrix() for p in pims]),
            np.array([p.delta_velocity for p in pims]),
            np.array([p.delta_position for p in pims]),
            np.array([p.delta_t for p in pims]),
            np.array([p.covariance for p in pims]),
            np.array([p.bias_jacobian for p in pims]),
        ]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        cases: dict[str, Callable[[], object]] = {
            "list + arrays (old CLI)": lambda: as_arrays(
                ik.preintegrate_windows(imu, bounds, noise=noise, scheme="euler")
            ),
            "list of handles only": lambda: ik.preintegrate_windows(imu, bounds, noise=noise, scheme="euler"),
            "Preintegration record": lambda: ik.preintegrate_windows(imu, bounds, params),
        }
        times: dict[str, list[float]] = {name: [] for name in cases}
        for f in cases.values():
            f()  # warm-up
        for _ in range(repeats):
            for name, f in cases.items():
                start = time.perf_counter()
                f()
                times[name].append(time.perf_counter() - start)
    print(f"{len(bounds) - 1:,} windows over {len(imu):,} samples, medians of {repeats} alternated runs")
    for name, ts in times.items():
        print(f"{name:28s} {np.median(ts) * 1e3:9.2f} ms  ({np.median(ts) / (len(bounds) - 1) * 1e6:.2f} us/window)")


if __name__ == "__main__":
    main()
