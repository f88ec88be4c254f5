"""imukit.plot: the PNGs decode, the axes carry units, the data drawn is the data given, bad input
is refused by name, and a missing matplotlib is a MissingDependencyError naming the extra."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit import plot

image = pytest.importorskip("matplotlib.image", reason="imukit.plot needs matplotlib")


def decoded(path: Path) -> np.ndarray:
    rgba = image.imread(path)
    assert rgba.ndim == 3 and rgba.shape[2] == 4 and rgba[..., :3].std() > 0.05
    return rgba


@pytest.fixture(scope="module")
def flight() -> tuple[ik.Trajectory, ik.Trajectory]:
    """A simulated figure-eight and its dead reckoning from noisy samples."""
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=30.0, noise=noise, seed=2)
    return ik.integrate(imu, initial=truth.state(0)), truth


def test_trajectory_top_view(tmp_path: Path, flight: tuple[ik.Trajectory, ik.Trajectory]) -> None:
    estimate, truth = flight
    fig = plot.trajectory_top_view(tmp_path / "top.png", {"midpoint": estimate}, truth=truth, title="figure-eight")
    decoded(tmp_path / "top.png")
    (ax,) = fig.axes
    assert ax.get_aspect() == 1.0  # equal scales: a circle looks like a circle
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) == ("x [m]", "y [m]", "figure-eight")
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["ground truth", "midpoint"]
    lines = [line for line in ax.get_lines() if len(line.get_xdata()) > 1]
    assert np.array_equal(lines[0].get_xydata(), truth.position[:, :2])
    assert np.array_equal(lines[1].get_xydata(), estimate.position[:, :2])


def test_attitude_error_plot(tmp_path: Path) -> None:
    """Three panels in degrees; the legend carries each RMSE, here of a constant 2° tilt about x."""
    t = np.arange(100) * 0.01
    tilt = ik.eval.attitude_error(
        np.tile(ik.quat.exp([np.radians(2.0), 0.0, 0.0]), (100, 1)), np.tile([0, 0, 0, 1.0], (100, 1))
    )
    fig = plot.attitude_error_plot(tmp_path / "err.png", t, {"tilted": tilt}, title="constant tilt")
    decoded(tmp_path / "err.png")
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["heading error [deg]", "inclination error [deg]", "total error [deg]"]
    assert fig.axes[-1].get_xlabel() == "time [s]"
    inclination = fig.axes[1].get_lines()[0]
    np.testing.assert_allclose(inclination.get_ydata(), 2.0, rtol=1e-12)
    assert fig.axes[1].get_legend().get_texts()[0].get_text() == "tilted (RMSE 2.00°)"
    assert fig.axes[0].get_legend().get_texts()[0].get_text() == "tilted (RMSE 0.00°)"


def test_convergence_plot_guides_have_their_slopes(tmp_path: Path) -> None:
    h = np.array([0.04, 0.02, 0.01, 0.005])
    fig = plot.convergence_plot(tmp_path / "c.png", h, {"second order": 3.0 * h**2}, title="t", ylabel="error [m]")
    decoded(tmp_path / "c.png")
    (ax,) = fig.axes
    assert ax.get_xscale() == ax.get_yscale() == "log"
    assert ax.get_xlabel() == "step size h [s]"
    guides = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
    slopes = [np.diff(np.log(g.get_ydata())) / np.diff(np.log(g.get_xdata())) for g in guides]
    np.testing.assert_allclose(np.concatenate(slopes), [1.0, 2.0, 4.0], rtol=1e-12)


def test_bad_input_is_refused_by_name(tmp_path: Path) -> None:
    with pytest.raises(ik.ShapeError, match=r"^errors\['a'\]: expected shape \(3,\)"):
        plot.convergence_plot(tmp_path / "c.png", [0.1, 0.2, 0.3], {"a": [1.0, 2.0]}, title="t", ylabel="e")
    with pytest.raises(ik.ShapeError, match=r"^step_sizes: "):
        plot.convergence_plot(tmp_path / "c.png", [0.1], {"a": [1.0]}, title="t", ylabel="e")
    with pytest.raises(ik.ShapeError, match=r"^estimates\['x'\]: expected a Trajectory or \(N, 3\)"):
        plot.trajectory_top_view(tmp_path / "t.png", {"x": np.zeros((5, 2))}, title="t")
    with pytest.raises(ik.ParameterError, match=r"^estimates: "):
        plot.trajectory_top_view(tmp_path / "t.png", {}, title="t")
    error = ik.eval.attitude_error(np.tile([0, 0, 0, 1.0], (4, 1)), np.tile([0, 0, 0, 1.0], (4, 1)))
    with pytest.raises(ik.ShapeError, match=r"^errors\['e'\]: 4 samples, but t has 3"):
        plot.attitude_error_plot(tmp_path / "e.png", [0.0, 1.0, 2.0], {"e": error}, title="t")
    assert not list(tmp_path.iterdir())  # nothing written on refusal


def test_missing_matplotlib(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)  # makes the import raise ImportError
    with pytest.raises(ik.MissingDependencyError, match=r'^convergence_plot: .*pip install "imukit\[plot\]"'):
        plot.convergence_plot(tmp_path / "c.png", [0.1, 0.2], {"a": [1.0, 2.0]}, title="t", ylabel="e")
