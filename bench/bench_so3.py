"""so3.exp / so3.log on 10^6 rotation vectors: imukit against scipy, side by side in one run.

Usage: ``python bench/bench_so3.py [--n 1000000] [--repeats 15]``. Prints the median of each and
the ratio scipy / imukit (> 1 means imukit is faster). Timings on a shared machine are noisy:
compare only ratios measured in the same run.
"""

from __future__ import annotations

import argparse
import os
import platform
from collections.abc import Callable

import numpy as np
import scipy
from scipy.spatial.transform import Rotation

import imukit as ik
from _timing import median_s


def median_ms(f: Callable[[], object], repeats: int) -> float:
    return 1e3 * median_s(f, repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    phi = Rotation.random(args.n, rng=rng).as_rotvec()
    matrices = Rotation.from_rotvec(phi).as_matrix()
    rotations = Rotation.from_rotvec(phi)
    assert np.abs(ik.so3.exp(phi) - matrices).max() < 1e-12
    assert np.abs(ik.so3.log(matrices) - phi).max() < 1e-12

    cases = [
        ("exp: rotvec -> matrix", lambda: ik.so3.exp(phi), lambda: Rotation.from_rotvec(phi).as_matrix()),
        ("log: matrix -> rotvec", lambda: ik.so3.log(matrices), lambda: Rotation.from_matrix(matrices).as_rotvec()),
        (
            "log: vs Rotation.as_rotvec (scipy already holds quaternions)",
            lambda: ik.so3.log(matrices),
            rotations.as_rotvec,
        ),
    ]
    print(
        f"n = {args.n:,}, median of {args.repeats}; numpy {np.__version__}, scipy {scipy.__version__}, "
        f"imukit {ik.__version__}, {platform.machine()}, {os.cpu_count()} cpus"
    )
    print(f"{'case':62s} {'imukit ms':>10s} {'scipy ms':>10s} {'scipy/imukit':>13s}")
    for name, ours, theirs in cases:
        t_ours, t_theirs = median_ms(ours, args.repeats), median_ms(theirs, args.repeats)
        print(f"{name:62s} {t_ours:10.1f} {t_theirs:10.1f} {t_theirs / t_ours:12.2f}x")


if __name__ == "__main__":
    main()
