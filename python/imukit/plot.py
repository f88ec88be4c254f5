"""Plots for reports, written straight to PNG files (matplotlib's Agg canvas; no window, no pyplot).

Each function writes the PNG and returns the matplotlib ``Figure`` (to adjust and save again).
matplotlib is an optional dependency (``pip install "imukit[plot]"``), imported when a function is
called; without it they raise :class:`imukit.MissingDependencyError`. The Allan plot is
:func:`imukit.noise.plot_allan`.

=============================  ==============================================================
:func:`trajectory_top_view`    x–y positions [m] of estimates and the truth, equal axes
:func:`attitude_error_plot`    heading, inclination and total error [deg] over time [s]
:func:`attitude_plot`          yaw, pitch and roll [deg] over time [s] (no reference needed)
:func:`convergence_plot`       error against step size on log-log axes, with slope guides
=============================  ==============================================================
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit._arrays import as_float_array
from imukit._errors import MissingDependencyError, ParameterError, ShapeError
from imukit.eval import AttitudeError
from imukit.state import Trajectory

__all__ = ["attitude_error_plot", "attitude_plot", "convergence_plot", "trajectory_top_view"]


def _figure(name: str, rows: int = 1, height: float = 5.0) -> tuple[Any, list[Any]]:
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as e:
        raise MissingDependencyError(
            'needs matplotlib, which is not installed (pip install "imukit[plot]")', argument=name
        ) from e
    fig = Figure(figsize=(7.5, height), dpi=120, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    return fig, list(axes)


def _save(fig: Any, path: str | os.PathLike[str]) -> Any:
    fig.savefig(os.fspath(path), format="png")
    return fig


def _save_panels(fig: Any, axes: list[Any], ylabels: list[str], title: str, path: str | os.PathLike[str]) -> Any:
    """Label, grid and legend panels stacked over a shared time axis, then :func:`_save`."""
    for ax, ylabel in zip(axes, ylabels):
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    axes[-1].set_xlabel("time [s]")
    axes[0].set_title(title)
    return _save(fig, path)


def _positions(value: Trajectory | ArrayLike, name: str) -> np.ndarray:
    p = value.position if isinstance(value, Trajectory) else as_float_array(value, name)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ShapeError(f"expected a Trajectory or (N, 3) positions [m], got shape {p.shape}", argument=name)
    return np.asarray(p)


def trajectory_top_view(
    path: str | os.PathLike[str],
    estimates: Mapping[str, Trajectory | ArrayLike],
    *,
    truth: Trajectory | ArrayLike | None = None,
    title: str,
) -> Any:
    """Top view (world x east / y north, metres, equal scales) of each estimate, labelled by its key,
    and the truth as a black line; start marked with a circle. Written as a PNG to ``path``."""
    if not estimates and truth is None:
        raise ParameterError("expected at least one trajectory to draw", argument="estimates")
    fig, (ax,) = _figure("trajectory_top_view", height=6.0)
    if truth is not None:
        p = _positions(truth, "truth")
        ax.plot(p[:, 0], p[:, 1], "k-", lw=2.0, alpha=0.6, label="ground truth")
        ax.plot(p[0, 0], p[0, 1], "ko", ms=6)
    for label, estimate in estimates.items():
        p = _positions(estimate, f"estimates[{label!r}]")
        (line,) = ax.plot(p[:, 0], p[:, 1], lw=1.2, label=label)
        ax.plot(p[0, 0], p[0, 1], "o", color=line.get_color(), ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)


def attitude_error_plot(
    path: str | os.PathLike[str],
    t: ArrayLike,
    errors: Mapping[str, AttitudeError],
    *,
    title: str,
) -> Any:
    """Three panels over time ``t`` [s]: heading, inclination and total error [deg] of each
    :class:`imukit.eval.AttitudeError`, labelled by its key (samples without truth left blank)."""
    time = as_float_array(t, "t")
    if not errors:
        raise ParameterError("expected at least one AttitudeError to draw", argument="errors")
    fig, axes = _figure("attitude_error_plot", rows=3, height=7.0)
    for label, error in errors.items():
        if len(error.total) != len(time):
            raise ShapeError(f"errors[{label!r}]: {len(error.total)} samples, but t has {len(time)}")
        rmse = error.rmse(degrees=True)
        for ax, values, rms in zip(
            axes, (error.heading, error.inclination, error.total), (rmse.heading, rmse.inclination, rmse.total)
        ):
            ax.plot(time, np.degrees(np.abs(values)), lw=0.8, label=f"{label} (RMSE {rms:.2f}°)")
    return _save_panels(fig, axes, [f"{name} error [deg]" for name in ("heading", "inclination", "total")], title, path)


def attitude_plot(
    path: str | os.PathLike[str],
    t: ArrayLike,
    rotations: Mapping[str, Rotation],
    *,
    title: str,
) -> Any:
    """Three panels over time ``t`` [s]: yaw, pitch and roll [deg] (intrinsic z-y'-x'') of each
    ``R_wb``, labelled by its key: what a filter run shows without a reference to score it against."""
    time = as_float_array(t, "t")
    if not rotations:
        raise ParameterError("expected at least one Rotation to draw", argument="rotations")
    fig, axes = _figure("attitude_plot", rows=3, height=7.0)
    for label, rotation in rotations.items():
        if len(rotation) != len(time):
            raise ShapeError(f"rotations[{label!r}]: {len(rotation)} samples, but t has {len(time)}")
        angles = rotation.as_euler("ZYX", degrees=True)
        for ax, k in zip(axes, range(3)):
            ax.plot(time, angles[:, k], lw=0.8, label=label)
    return _save_panels(fig, axes, ["yaw [deg]", "pitch [deg]", "roll [deg]"], title, path)


def convergence_plot(
    path: str | os.PathLike[str],
    step_sizes: ArrayLike,
    errors: Mapping[str, ArrayLike],
    *,
    title: str,
    ylabel: str,
    orders: Sequence[int] = (1, 2, 4),
) -> Any:
    """Error against step size ``step_sizes`` [s] on log-log axes, one line per scheme (the keys),
    with dashed guides of slope ``orders`` (error ∝ hᵖ) fanning out from the largest step."""
    h = as_float_array(step_sizes, "step_sizes")
    if h.ndim != 1 or len(h) < 2:
        raise ShapeError(f"expected (M,) with M ≥ 2, got shape {h.shape}", argument="step_sizes")
    fig, (ax,) = _figure("convergence_plot")
    finite: list[float] = []
    for label, values in errors.items():
        e = as_float_array(values, f"errors[{label!r}]")
        if e.shape != h.shape:
            raise ShapeError(f"errors[{label!r}]: expected shape {h.shape} like step_sizes, got {e.shape}")
        ax.loglog(h, e, "o-", ms=4, label=label)
        finite.extend(e[e > 0].tolist())
    if finite:
        # A fan from one point at the largest step: the guides part towards small steps, where the
        # orders differ most, and their labels do not overlap.
        h_max, h_min = float(h.max()), float(h.min())
        anchor = float(np.exp(np.log(finite).mean()))
        guide_h = np.array([h_min, h_max])
        for p in orders:
            ax.loglog(guide_h, anchor * (guide_h / h_max) ** p, "k--", lw=0.7, alpha=0.5)
            ax.annotate(f"slope {p}", (h_min, anchor * (h_min / h_max) ** p), fontsize=7, alpha=0.7)
    ax.set_xlabel("step size h [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)
