"""Overlapping Allan deviation of 10^7 samples x 3 axes on octave τ: imukit against allantools.

Usage: ``python bench/bench_allan.py [--n 10000000] [--repeats 5]``. Prints the median of each
(allantools.oadev is called once per axis, the way it is used) and the ratio allantools / imukit
(> 1 means imukit is faster). Compare only ratios measured in the same run.
"""

from __future__ import annotations

import argparse
import os
import platform

import allantools
import numpy as np

import imukit as ik
from _timing import median_s

FLOPS_PER_TERM = 19


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    rate = 200.0
    rng = np.random.default_rng(0)
    x = 1e-3 * np.sqrt(rate) * rng.standard_normal((args.n, 3)) + np.array([0.01, -0.02, 9.81])
    allan = ik.noise.allan_deviation(x, rate)

    def peer() -> list[np.ndarray]:
        return [allantools.oadev(x[:, c], rate=rate, data_type="freq", taus=allan.taus)[1] for c in range(3)]

    worst = max(float(np.max(np.abs(allan.deviation[:, c] / d - 1.0))) for c, d in enumerate(peer()))
    ours = median_s(lambda: ik.noise.allan_deviation(x, rate), args.repeats)
    theirs = median_s(peer, max(1, args.repeats // 2))
    m_max = allan.cluster_sizes[-1]
    print(f"# Allan deviation, {args.n} samples x 3 axes, {len(allan.taus)} octave taus (m = 1 … {m_max})")
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, allantools {allantools.__version__}"
    )
    print(f"# largest relative difference to allantools: {worst:.1e}")
    # Work per input row, counted from the code (docs/performance.md, "Filters, simulator and Allan:
    # work per sample"): 19 flops per column per cluster term (compensated sums), N − 2m + 1 terms.
    terms = float(np.sum((args.n - 2 * allan.cluster_sizes + 1) / args.n))
    flops = 3 * FLOPS_PER_TERM * terms
    print(f"# work: {flops:.0f} flops per row (3 columns x {terms:.1f} terms), 24 B read; floor {flops / 48:.0f} ns")
    print("| method | median [s] |")
    print("|---|---|")
    print(f"| imukit.noise.allan_deviation | {ours:.3f} |")
    print(f"| allantools.oadev (3 calls) | {theirs:.3f} |")
    print(f"| ratio allantools / imukit | {theirs / ours:.1f} |")


if __name__ == "__main__":
    main()
