"""Strapdown from Python, 10^6 samples, every state kept: ``imukit.integrate`` (each scheme) and
``imukit.propagate`` (15×15 covariance every sample, stored every 100), against a per-sample
numpy/scipy loop of the same midpoint step measured in the same run.

Usage: ``python bench/bench_strapdown.py [--n 1000000] [--repeats 7]``. Times are medians per
sample, including the array conversion and building the returned ``Trajectory``; ``ImuData``
construction (validation, read-only copies) is reported on its own line.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik
from _timing import median_s, synthetic_imu


def python_midpoint(imu: ik.ImuData, x0: ik.NavState) -> np.ndarray:
    """The VINS midpoint step as a plain per-sample loop (the baseline users write first)."""
    g = np.array([0.0, 0.0, -9.81])
    p, v, r = x0.position.copy(), x0.velocity.copy(), x0.rotation
    out = np.empty((len(imu), 3))
    out[0] = p
    t, w, a = imu.seconds, imu.gyro.copy(), imu.accel.copy()  # scipy refuses read-only buffers
    for k in range(len(imu) - 1):
        h = t[k + 1] - t[k]
        r1 = r * Rotation.from_rotvec(0.5 * (w[k] + w[k + 1]) * h)
        acc = 0.5 * (r.apply(a[k]) + r1.apply(a[k + 1])) + g
        p = p + v * h + 0.5 * acc * h * h
        v = v + acc * h
        r = r1
        out[k + 1] = p
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--loop-n", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()

    t, gyro, accel = synthetic_imu(args.n)
    imu = ik.ImuData(t, gyro, accel)
    x0 = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)

    m = args.loop_n
    small = imu[:m]
    gap = np.abs(python_midpoint(small, x0) - ik.integrate(small, initial=x0).position).max()
    print(f"n = {args.n:,}; imukit midpoint vs the Python loop over {m:,} samples: max |Δp| = {gap:.1e} m")

    rows: list[tuple[str, float]] = [
        ("ImuData construction", median_s(lambda: ik.ImuData(t, gyro, accel), args.repeats) / args.n)
    ]
    for scheme in ik.strapdown.SCHEMES:
        f = lambda s=scheme: ik.integrate(imu, initial=x0, scheme=s)  # noqa: E731
        rows.append((f"integrate {scheme}", median_s(f, args.repeats) / args.n))
    cov = np.eye(15) * 1e-4
    f = lambda: ik.propagate(imu, initial=x0, covariance=cov, noise=noise, covariance_every=100)  # noqa: E731
    rows.append(("propagate midpoint, cov every 100", median_s(f, 3) / args.n))
    rows.append(("Python loop midpoint", median_s(lambda: python_midpoint(small, x0), 1) / m))
    base = dict(rows)["integrate midpoint"]
    print(f"{'case':36s} {'ns/sample':>10s} {'÷ integrate midpoint':>21s}")
    for name, seconds in rows:
        print(f"{name:36s} {seconds * 1e9:10.1f} {seconds / base:20.1f}x")


if __name__ == "__main__":
    main()
