"""Median wall time of the hot public entry points, for before/after comparisons of two builds.

Times whichever ``imukit`` is first on ``sys.path`` and prints one JSON object (seconds), so two
builds are compared by alternating processes, one thread each::

    for i in 1 2 3 4 5; do for b in OLD NEW; do
      echo -n "$b "; RAYON_NUM_THREADS=1 PYTHONPATH=$b/python python bench/hot_paths.py
    done; done

2e5 samples at 200 Hz; entry points a build lacks are skipped.
"""

from __future__ import annotations

import json
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik

N = 200_000


def median_time(f: Callable[[], Any], repeats: int = 7) -> float:
    f()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main() -> None:
    warnings.simplefilter("ignore", DeprecationWarning)
    t = np.arange(N) * 0.005
    gyro = np.stack([0.3 * np.sin(1.1 * t), 0.2 * np.cos(0.7 * t), 0.5 * np.sin(1.3 * t)], -1)
    accel = np.stack([0.5 * np.sin(0.9 * t), 0.4 * np.cos(0.3 * t), 9.81 + 0.2 * np.sin(1.7 * t)], -1)
    imu = ik.ImuData(t, gyro, accel)
    noise = ik.ImuNoise(gyro_density=1.7e-4, accel_density=2e-3, gyro_random_walk=2e-5, accel_random_walk=3e-3)
    phi = np.random.default_rng(0).normal(size=(N, 3))
    quats = np.c_[phi, np.ones(N)]
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    rotations = ik.so3.exp(phi)
    initial = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    bounds = t[::100]
    cases: dict[str, Callable[[], Any]] = {
        "so3.exp": lambda: ik.so3.exp(phi),
        "so3.log": lambda: ik.so3.log(rotations),
        "so3.right_jacobian": lambda: ik.so3.right_jacobian(phi),
        "quat.multiply": lambda: ik.quat.multiply(quats, quats),
        "quat.exp": lambda: ik.quat.exp(phi),
        "integrate_attitude": lambda: ik.integrate_attitude(t, gyro),
        "integrate": lambda: ik.integrate(imu, initial=initial),
        "propagate": lambda: ik.propagate(imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise),
        "preintegrate": lambda: ik.preintegrate(imu, noise=noise),
        "mahony": lambda: ik.filters.Mahony().run(imu),
        "madgwick": lambda: ik.filters.Madgwick().run(imu),
    }
    if hasattr(ik, "PreintParams"):
        params = ik.PreintParams(noise)
        cases["preintegrate_windows (2000)"] = lambda: ik.preintegrate_windows(imu, bounds, params)
    else:
        cases["preintegrate_windows (2000)"] = lambda: ik.preintegrate_windows(imu, bounds, noise=noise)
    print(json.dumps({name: median_time(f) for name, f in cases.items()}))


if __name__ == "__main__":
    main()
