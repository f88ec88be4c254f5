"""Preintegration from Python, 10^6 samples at 200 Hz, euler scheme, 9×9 covariance and bias
Jacobians: ``imukit.preintegrate`` (one call, GIL released) against the streaming
``PreintegratedImu.integrate_measurement`` loop over a subset, measured in the same run.

Usage: ``python bench/bench_preint.py [--n 1000000] [--repeats 7]``; medians per sample. Compare
with ``cargo bench -p imukit --bench preint`` for the Rust figure.
"""

from __future__ import annotations

import argparse

import numpy as np

import imukit as ik
from _timing import median_s, synthetic_imu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--loop-n", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()

    t, gyro, accel = synthetic_imu(args.n)
    imu = ik.ImuData(t, gyro, accel)
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)

    def stream(m: int) -> ik.PreintegratedImu:
        pim = ik.PreintegratedImu(noise=noise)
        for k in range(m - 1):
            pim.integrate_measurement(accel[k], gyro[k], 0.005)
        return pim

    m = args.loop_n
    gap = np.abs(stream(m).delta_position - ik.preintegrate(imu[:m], noise=noise).delta_position).max()
    rows = [
        ("preintegrate (batch)", median_s(lambda: ik.preintegrate(imu, noise=noise), args.repeats) / args.n),
        ("preintegrate combined=True", median_s(lambda: ik.preintegrate(imu, noise=noise, combined=True), 3) / args.n),
        ("integrate_measurement loop", median_s(lambda: stream(m), 1) / m),
    ]
    print(f"n = {args.n:,}; batch vs streaming over {m:,} samples: max |Δp| gap = {gap:.1e} m")
    base = rows[0][1]
    print(f"{'case':30s} {'ns/sample':>10s} {'÷ batch':>9s}")
    for name, seconds in rows:
        print(f"{name:30s} {seconds * 1e9:10.1f} {seconds / base:8.1f}x")


if __name__ == "__main__":
    main()
