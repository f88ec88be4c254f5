"""The log-log Allan-deviation plot (matplotlib, imported when called)."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from imukit._errors import MissingDependencyError, ParameterError
from imukit.noise._allan import AllanDeviation
from imukit.noise._fit import _UNITS, AllanFit, _design, _edf


def plot_allan(
    allan: AllanDeviation,
    path: str | os.PathLike[str],
    *,
    fit: AllanFit | None = None,
    title: str | None = None,
) -> None:
    """Draw σ(τ) on log-log axes to a PNG at ``path``, with the fit and its three terms if given.

    Needs matplotlib (imported here, not with imukit); without it, :class:`imukit.MissingDependencyError`.
    Each column is drawn as points; with ``fit``, the points get ``confidence`` error bars from
    the χ² distribution with the model's degrees of freedom, and the fitted σ(τ) and its white,
    flicker and random-walk terms are drawn as lines, labelled with N, B, K and their intervals.
    """
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as e:
        # No argument is at fault: the function names itself in the text.
        raise MissingDependencyError(
            "plot_allan: needs matplotlib, which is not installed (pip install matplotlib)"
        ) from e
    if not isinstance(allan, AllanDeviation):
        raise ParameterError(
            f"expected the AllanDeviation of allan_deviation(), got {type(allan).__name__}", argument="allan"
        )
    if fit is not None and not isinstance(fit, AllanFit):
        raise ParameterError(f"expected an AllanFit or None, got {type(fit).__name__}", argument="fit")
    unit, density, walk = _UNITS[fit.sensor if fit is not None else None]
    fig = Figure(figsize=(7.0, 5.0), dpi=120)
    FigureCanvasAgg(fig)
    ax: Any = fig.add_subplot()
    dev = np.asarray(allan.deviation).reshape(len(allan.taus), -1)
    bars = None
    if fit is not None:
        from scipy import stats

        parts = _design(allan.taus) * np.array([fit.noise_density, fit.bias_instability, fit.random_walk]) ** 2
        model = parts.sum(axis=1)
        fractions = parts / np.where(model > 0.0, model, 1.0)[:, None]
        edf = _edf(allan, np.where(model[:, None] > 0.0, fractions, [1.0, 0.0, 0.0]))
        tail = (1.0 - fit.confidence) / 2.0
        bars = np.sqrt(edf / stats.chi2.ppf(1.0 - tail, edf)), np.sqrt(edf / stats.chi2.ppf(tail, edf))
    for c in range(dev.shape[1]):
        label = "σ(τ)" if dev.shape[1] == 1 else f"σ(τ), column {c}"
        if bars is None:
            ax.loglog(allan.taus, dev[:, c], "o", ms=4, label=label)
        else:
            err = [dev[:, c] * (1.0 - bars[0]), dev[:, c] * (bars[1] - 1.0)]
            ax.errorbar(allan.taus, dev[:, c], yerr=err, fmt="o", ms=4, capsize=2, label=label)
    if fit is not None:
        t = np.geomspace(allan.taus.min(), allan.taus.max(), 200)
        level = f"{100 * fit.confidence:g}%"
        names = (
            ("N", fit.noise_density, fit.noise_density_interval, density, "--"),
            ("B", fit.bias_instability, fit.bias_instability_interval, unit, ":"),
            ("K", fit.random_walk, fit.random_walk_interval, walk, "-."),
        )
        ax.loglog(t, fit.deviation(t), "k-", lw=1.5, label="fit")
        for (symbol, value, (lo, hi), u, style), part in zip(names, fit.components(t).T):
            if value > 0.0:
                ax.loglog(t, part, style, lw=1, label=f"{symbol} = {value:.3g} {u} ({level}: {lo:.3g}…{hi:.3g})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("τ [s]")
    ax.set_ylabel(f"Allan deviation σ(τ) [{unit}]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if title is not None:
        ax.set_title(title)
    fig.tight_layout()
    fig.savefig(os.fspath(path), format="png")
