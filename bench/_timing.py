"""Shared helpers of the bench scripts (run them as ``python bench/NAME.py``)."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np


def median_s(f: Callable[[], object], repeats: int, clock: Callable[[], float] = time.perf_counter) -> float:
    """Median time of ``f()`` in seconds over ``repeats`` runs, after one warm-up run: wall time, or
    with ``clock=time.process_time`` the process's CPU time (what a loaded machine inflates least)."""
    f()
    times = []
    for _ in range(repeats):
        start = clock()
        f()
        times.append(clock() - start)
    return float(np.median(times))


def synthetic_imu(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t, gyro, accel)`` of n smooth 200 Hz samples, the input every strapdown-style bench uses."""
    t = np.arange(n) * 0.005
    gyro = np.stack([0.3 * np.sin(1.1 * t), 0.2 * np.cos(0.7 * t), 0.5 * np.sin(1.3 * t)], axis=-1)
    accel = np.stack([0.5 * np.sin(0.9 * t), 0.4 * np.cos(0.3 * t), 9.81 + 0.2 * np.sin(1.7 * t)], axis=-1)
    return t, gyro, accel
