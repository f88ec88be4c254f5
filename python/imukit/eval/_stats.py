"""Summary statistics of a per-sample (or per-pair) error, as evo reports them."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from imukit._arrays import FloatArray


class ErrorStats(NamedTuple):
    """Statistics of non-negative errors ``e`` (N,), in the unit of ``e`` ([m] or [rad]).

    ``rmse = √(Σ e² / N)``, ``mean``, ``median``, ``std`` (population: ``√(Σ (e − mean)² / N)``, as
    ``numpy.std`` and evo), ``min``, ``max``, and ``n`` = N.
    """

    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float
    n: int


def error_stats(e: FloatArray) -> ErrorStats:
    """:class:`ErrorStats` of ``e``; the callers guarantee ``len(e) ≥ 1``."""
    # Scaled by the largest error: e * e overflows from 1.3e154 (a finite norm) and underflows.
    top = float(np.max(np.abs(e)))
    rmse = top * float(np.sqrt(np.mean((e / top) ** 2))) if top > 0 else 0.0
    return ErrorStats(
        rmse=rmse,
        mean=float(np.mean(e)),
        median=float(np.median(e)),
        std=top * float(np.std(e / top)) if top > 0 else 0.0,
        min=float(np.min(e)),
        max=float(np.max(e)),
        n=len(e),
    )
