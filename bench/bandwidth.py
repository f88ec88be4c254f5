"""The memory floor of ``imukit.propagate``'s every-sample output: numpy writing an ``(n, 225)``
float64 array (1.8 kB a sample), fresh (first-touch page faults, as propagate's output) and warm
(pages already mapped), next to propagate itself, in ns per sample, back to back
(``docs/performance.md``, issue 20).

With ``--pages``: the first touch of fresh rows of 48 B a sample (the Robust smoother's backward
track) on 4 KiB pages against 2 MiB transparent huge pages (numpy's advice switched off and on),
the cost ``crates/imukit/src/pages.rs`` avoids.

Usage: ``python bench/bandwidth.py [--n 200000] [--repeats 5] [--pages]``.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik
from _timing import median_s, synthetic_imu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--pages", action="store_true", help="first touch on 4 KiB against huge pages")
    args = parser.parse_args()
    n = args.n
    if args.pages:
        first_touch(n, args.repeats)
        return
    source = np.ones((n, 225))
    warm = np.zeros((n, 225))
    t, gyro, accel = synthetic_imu(n)
    imu = ik.ImuData(t, gyro, accel)
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    initial = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    rows = {
        "fill, fresh np.empty": lambda: np.empty((n, 225)).fill(1.0),
        "fill, fresh np.zeros": lambda: np.zeros((n, 225)).fill(1.0),
        "fill, warm": lambda: warm.fill(1.0),
        "copy, into fresh np.empty": lambda: np.copyto(np.empty((n, 225)), source),
        "copy, into warm": lambda: np.copyto(warm, source),
        "propagate, every sample": lambda: ik.propagate(
            imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise
        ),
    }
    print(f"n = {n:,}, {args.repeats} repeats, ns per sample (one 15×15 float64 row = 1800 B)")
    for name, f in rows.items():
        ns = median_s(f, args.repeats) / n * 1e9
        print(f"| {name} | {ns:.0f} | {1800 / ns:.1f} GB/s |")


def first_touch(n: int, repeats: int) -> None:
    from numpy._core.multiarray import _set_madvise_hugepage

    print(f"n = {n:,}, {repeats} repeats, ns per sample to write fresh (n, 6) float64 rows (48 B)")
    for huge in (False, True):
        was = _set_madvise_hugepage(huge)
        try:
            ns = median_s(lambda: np.zeros((n, 6)).fill(1.0), repeats) / n * 1e9
        finally:
            _set_madvise_hugepage(was)
        print(f"| {'2 MiB huge pages' if huge else '4 KiB pages'} | {ns:.1f} |")


if __name__ == "__main__":
    main()
