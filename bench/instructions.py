"""Instructions per sample of the preintegration, propagate and filter kernels, counted with valgrind's
callgrind (exact, independent of the machine's load; this host has no hardware counters for
``perf stat``), per dispatch path (``IMUKIT_SIMD``; valgrind cannot run AVX-512).

Each kernel runs once on ``--n`` samples (the inputs of ``bench/_timing.synthetic_imu``, one thread)
under ``valgrind --tool=callgrind --toggle-collect=<entry>``, so only the entry's call tree is
counted, inclusive of its callees (preintegration: ``Preintegrator::integrate_samples_cancellable``,
i.e. the validation, the dispatched loop and the finiteness check; propagate: the whole Rust call
under the glue's interruptible runner; the filters (Mahony, Madgwick, 6D and 9D): their batch loop
``Filter::run_cancellable``);
the count is divided by the number of samples.

Usage: ``python bench/instructions.py [--n 50000] [--paths baseline avx2] [--kernels "Mahony 9D" ...]``.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

# The kernel's call (a statement on the CHILD's inputs) and the function (callgrind pattern)
# whose call tree is counted.
PREINT = "ik.preintegrate(imu, noise=noise, threads=1, {})"
WINDOWS = "ik.preintegrate_windows({}, t[::200], ik.PreintParams(noise, scheme='lie_euler'), threads=1)"
KERNELS = {
    "preintegrate euler": (PREINT.format("scheme='lie_euler'"), "*integrate_samples_cancellable*"),
    "preintegrate midpoint": (PREINT.format("scheme='midpoint'"), "*integrate_samples_cancellable*"),
    "preintegrate combined": (PREINT.format("scheme='lie_euler', combined=True"), "*integrate_samples_cancellable*"),
    # Keyframe windows of 200 samples: four at a time in the SIMD lanes on the AVX paths; the
    # second form flags one sample per window, which keeps every window on the per-window kernel.
    "preintegrate_windows euler": (WINDOWS.format("imu"), "*preintegrate_windows_cancellable*"),
    "preintegrate_windows euler, per-window kernel": (
        WINDOWS.format("flagged"),
        "*preintegrate_windows_cancellable*",
    ),
    # The whole Rust call: a pattern on propagate_model would also match its closures, and
    # callgrind toggles collection off again on entering them.
    "propagate": (
        "ik.propagate(imu, initial=ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity()),"
        " covariance=np.eye(15) * 1e-4, noise=noise, covariance_every=1000)",
        "*_core::threads::interruptible*",
    ),
    # The filters' batch loop (issue 20), as bench/bench_filters.py runs it (9D from imu.mag). Not
    # the glue's `interruptible`: from 65,536 samples it runs the kernel on a thread of its own,
    # whose calls are outside its call tree (the rows counted 0 there).
    **{
        f"{law} {dim}": (f"ik.filters.{law}().run(imu_mag, mag={use})", "*Filter<L>::run_cancellable*")
        for law in ("Mahony", "Madgwick")
        for dim, use in (("6D", "False"), ("9D", "None"))
    },
    # Issue 15's online filter, the same way (bench_filters.py --only-robust --imu-mag).
    **{
        f"Robust online {dim}": (f"ik.filters.Robust().run(imu_mag, mag={use})", "*Robust::run_checked*")
        for dim, use in (("6D", "False"), ("9D", "None"))
    },
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
mag = np.stack([20.0 * np.cos(0.2 * t), 20.0 * np.sin(0.2 * t), np.full_like(t, -40.0)], axis=-1)
imu_mag = ik.ImuData(t, gyro, accel, mag=mag)
clip = gyro.copy()
clip[100::200, 0] = 100.0
flagged = ik.ImuData(t, clip, accel, gyro_range=100.0)
noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
{call}
"""


def count(kernel: str, path: str, n: int) -> float | None:
    """Instructions per sample of one kernel on one path; None where valgrind cannot decode an
    instruction of that path."""
    call, entry = KERNELS[kernel]
    code = CHILD.format(bench=str(Path(__file__).parent), n=n, call=call)
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
        run = subprocess.run(command, env=env, capture_output=True, text=True)
        if run.returncode != 0 and "unhandled instruction" in run.stderr:
            # valgrind 3.19 cannot decode some VEX forms (e.g. propagate's `vmovq xmm, xmm` on the
            # AVX2 path): that cell has no count rather than the table none.
            return None
        run.check_returncode()
        summary = re.search(r"^summary: (\d+)", out.read_text(), re.MULTILINE)
        if summary is None:
            raise RuntimeError(f"no summary in callgrind's output for {kernel} on {path}")
        if int(summary.group(1)) < n:
            raise RuntimeError(
                f"{entry} counted under one instruction per sample for {kernel} on {path}: the kernel was"
                " renamed, or ran on a thread outside the entry's call tree (the glue's interruptible runner"
                " does from 65,536 samples)?"
            )
        return int(summary.group(1)) / n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50_000)
    parser.add_argument("--paths", nargs="+", default=["baseline", "avx2"])
    parser.add_argument("--kernels", nargs="+", default=list(KERNELS), choices=list(KERNELS))
    args = parser.parse_args()
    print(f"instructions per sample (callgrind, n = {args.n:,}, one thread)")
    print("| kernel | " + " | ".join(args.paths) + " |")
    print("|---|" + "---|" * len(args.paths))
    for kernel in args.kernels:
        counts = (count(kernel, p, args.n) for p in args.paths)
        cells = ["— (valgrind: unhandled instruction)" if c is None else f"{c:,.0f}" for c in counts]
        print(f"| {kernel} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
