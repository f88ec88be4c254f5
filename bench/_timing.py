"""Shared timing helper of the bench scripts (run them as ``python bench/NAME.py``)."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np


def median_s(f: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``f()`` in seconds over ``repeats`` runs, after one warm-up run."""
    f()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return float(np.median(times))
