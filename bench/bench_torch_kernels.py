"""CPU time of ``imukit.torch``'s Rust kernels alone (``crates/imukit/src/adjoint``), no torch.

The call ``imukit.torch.preintegrate`` makes on CPU, ``_core.preint_adjoint``, forward (the final
record) and backward (the re-run and the reverse sweep, given a random cotangent), on one thread
(``imukit.set_num_threads(1)``), timed with ``time.process_time`` so that other processes' load
does not enter; ns per interval, the median of ``--repeats``. Batch ``--batch`` × ``--samples``
windows with the bench's inputs (``bench_torch.py``: unit-normal rates and forces, 5 ms steps),
noise as densities (``noise=[1e-2, 1e-2]``), the covariance on, the bias Jacobian with ``--jacobian``.
To compare builds, run it back to back under each (``PYTHONPATH=<other build's python>``).

Usage: ``python bench/bench_torch_kernels.py [--batch 32] [--samples 1023] [--repeats 7]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import imukit
from imukit import _core


def per_interval(f: Callable[..., object], kwargs: dict[str, Any], repeats: int, intervals: int) -> float:
    f(**kwargs)
    times = []
    for _ in range(repeats):
        start = time.process_time()
        f(**kwargs)
        times.append(time.process_time() - start)
    return statistics.median(times) / intervals * 1e9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--batch", type=int, default=32)
    parser.add_argument("--samples", type=int, default=1023)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--jacobian", action="store_true", help="also return the bias Jacobian")
    args = parser.parse_args()
    imukit.set_num_threads(1)
    b, n = args.batch, args.samples
    rng = np.random.default_rng(0)
    h = np.full((b, n), 0.005)
    w = rng.standard_normal((b, n, 3))
    a = rng.standard_normal((b, n, 3)) + np.array([0.0, 0.0, 9.81])
    q = np.full((b, 2), 1e-4)
    print(f"Rust kernels, 1 thread, CPU time, batch {b} × {n}, ns per interval (median of {args.repeats})")
    for scheme in ("lie_euler", "midpoint"):
        opts = {
            "a_end": a.copy() if scheme == "midpoint" else None,
            "gyro_cov": None,
            "accel_cov": None,
            "noise_density": q,
            "per_step": False,
            "covariance": True,
            "jacobian": args.jacobian,
        }
        out = _core.preint_adjoint(h, w, a, bar=None, **opts)
        bar = rng.standard_normal(out.shape)
        call = {"h": h, "w": w, "a": a, **opts}
        fwd = per_interval(_core.preint_adjoint, {**call, "bar": None}, args.repeats, b * n)
        bwd = per_interval(_core.preint_adjoint, {**call, "bar": bar}, args.repeats, b * n)
        print(f"{scheme:<10} forward {fwd:>7.0f}   backward {bwd:>7.0f}", flush=True)


if __name__ == "__main__":
    main()
