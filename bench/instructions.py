"""Instructions per sample of the preintegration and propagate kernels, counted with valgrind's
callgrind (exact, independent of the machine's load; this host has no hardware counters for
``perf stat``), per dispatch path (``IMUKIT_SIMD``; valgrind cannot run AVX-512).

Each kernel runs once on ``--n`` samples (the inputs of ``bench/_timing.synthetic_imu``, one thread)
under ``valgrind --tool=callgrind --toggle-collect=<entry>``, so only the entry's call tree is
counted, inclusive of its callees (preintegration: ``Preintegrator::integrate_samples_cancellable``,
i.e. the validation, the dispatched loop and the finiteness check; propagate: the whole Rust call
under the glue's interruptible runner);
the count is divided by the number of samples.

Usage: ``python bench/instructions.py [--n 50000] [--paths baseline avx2]``.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

# The kernel's call and the function (callgrind pattern) whose call tree is counted.
KERNELS = {
    "preintegrate euler": ("dict(scheme='lie_euler')", "*integrate_samples_cancellable*"),
    "preintegrate midpoint": ("dict(scheme='midpoint')", "*integrate_samples_cancellable*"),
    "preintegrate combined": ("dict(scheme='lie_euler', combined=True)", "*integrate_samples_cancellable*"),
    # The whole Rust call: a pattern on propagate_model would also match its closures, and
    # callgrind toggles collection off again on entering them.
    "propagate": (None, "*_core::threads::interruptible*"),
}

CHILD = """
import sys
import numpy as np
from scipy.spatial.transform import Rotation
import imukit as ik
sys.path.insert(0, {bench!r})
from _timing import synthetic_imu
t, gyro, accel = synthetic_imu({n})
imu = ik.ImuData(t, gyro, accel)
noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
kwargs = {kwargs}
if kwargs is None:
    initial = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    ik.propagate(imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise, covariance_every=1000)
else:
    ik.preintegrate(imu, noise=noise, threads=1, **kwargs)
"""


def count(kernel: str, path: str, n: int) -> float:
    """Instructions per sample of one kernel on one path."""
    kwargs, entry = KERNELS[kernel]
    code = CHILD.format(bench=str(Path(__file__).parent), n=n, kwargs=kwargs)
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "callgrind.out"
        command = [
            "valgrind",
            "--tool=callgrind",
            f"--callgrind-out-file={out}",
            f"--toggle-collect={entry}",
            sys.executable,
            "-c",
            code,
        ]
        env = dict(os.environ, IMUKIT_SIMD=path, RAYON_NUM_THREADS="1")
        subprocess.run(command, env=env, check=True, capture_output=True)
        summary = re.search(r"^summary: (\d+)", out.read_text(), re.MULTILINE)
        if summary is None:
            raise RuntimeError(f"no summary in callgrind's output for {kernel} on {path}")
        if int(summary.group(1)) == 0:
            raise RuntimeError(f"{entry} matched no call for {kernel} on {path}: the kernel was renamed?")
        return int(summary.group(1)) / n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50_000)
    parser.add_argument("--paths", nargs="+", default=["baseline", "avx2"])
    args = parser.parse_args()
    print(f"instructions per sample (callgrind, n = {args.n:,}, one thread)")
    print("| kernel | " + " | ".join(args.paths) + " |")
    print("|---|" + "---|" * len(args.paths))
    for kernel in KERNELS:
        cells = [f"{count(kernel, p, args.n):,.0f}" for p in args.paths]
        print(f"| {kernel} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
