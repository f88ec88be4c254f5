"""Shared helpers of the bench scripts (run them as ``python bench/NAME.py``)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import NamedTuple

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


class Paired(NamedTuple):
    """Medians of two calls timed in alternation, and of their per-pair ratio ``b / a``."""

    a_s: float
    b_s: float
    ratio: float
    ratio_low: float
    ratio_high: float

    def ratio_text(self) -> str:
        """``"3.1× (2.8–3.4)"``: the median ratio and its range over the pairs."""
        return f"{self.ratio:.1f}× ({self.ratio_low:.1f}–{self.ratio_high:.1f})"


def paired(
    a: Callable[[], object], b: Callable[[], object], repeats: int, clock: Callable[[], float] = time.perf_counter
) -> Paired:
    """``a()`` and ``b()`` timed as ``repeats`` adjacent pairs (after one warm-up each), the order
    inside a pair alternating: a ratio of two medians taken seconds apart follows another tenant's
    load (on this 2-core VM vqf's own time moved 395–776 ns/sample between runs), while the two
    calls of a pair see the same load."""
    if repeats < 1:
        raise ValueError(f"repeats must be at least 1, got {repeats}")
    a()
    b()
    ta, tb = [], []
    for k in range(repeats):
        for f, times in ((a, ta), (b, tb)) if k % 2 == 0 else ((b, tb), (a, ta)):
            start = clock()
            f()
            times.append(clock() - start)
    ratios = np.array(tb) / np.array(ta)
    return Paired(
        float(np.median(ta)), float(np.median(tb)), float(np.median(ratios)), float(ratios.min()), float(ratios.max())
    )


def synthetic_imu(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t, gyro, accel)`` of n smooth 200 Hz samples, the input every strapdown-style bench uses."""
    t = np.arange(n) * 0.005
    gyro = np.stack([0.3 * np.sin(1.1 * t), 0.2 * np.cos(0.7 * t), 0.5 * np.sin(1.3 * t)], axis=-1)
    accel = np.stack([0.5 * np.sin(0.9 * t), 0.4 * np.cos(0.3 * t), 9.81 + 0.2 * np.sin(1.7 * t)], axis=-1)
    return t, gyro, accel
