"""The smaller points of issue 16: `preintegrate` with a bias (constant, or the ground truth's at
each window start), `filter --plot` without a reference, `read_euroc_sensor` of any yaml name,
`ImuData` sliced as Python slices."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from test_cli import assert_one_line_error, assert_png, cli

B_G = np.array([0.01, -0.02, 0.03])  # rad/s
B_A = np.array([0.1, 0.2, -0.3])  # m/s^2
NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)


@pytest.fixture(scope="module")
def biased(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A 200 Hz figure eight written twice: clean, and with B_G + 1e-3 t and B_A added to the readings,
    its ground truth carrying exactly those biases (so each window start has a different gyro bias)."""
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=6.0, seed=9)
    t_ns = np.round(imu.t * 1e9).astype(np.int64)
    drift = B_G + 1e-3 * imu.t[:, None]
    root = tmp_path_factory.mktemp("bias")
    noisy = ik.ImuData(t_ns, imu.gyro + drift, imu.accel + B_A)
    with_bias = ik.Trajectory(
        None,
        truth.position,
        truth.velocity,
        truth.rotation,
        t_ns=t_ns,
        gyro_bias=drift,
        accel_bias=np.tile(B_A, (len(imu), 1)),
    )
    ik.io.write_euroc(root / "biased", noisy, with_bias, noise=NOISE, rate_hz=200.0)
    ik.io.write_euroc(root / "clean", ik.ImuData(t_ns, imu.gyro, imu.accel), noise=NOISE, rate_hz=200.0)
    return {"biased": root / "biased", "clean": root / "clean", "root": root}


def _windows(path: Path, out: Path, *options: str) -> dict[str, np.ndarray]:
    cli("preintegrate", path, "--window", "0.5", "--out", out, *options)
    with np.load(out) as data:
        return dict(data)


def test_constant_bias_removes_a_constant_offset(biased: dict[str, Path]) -> None:
    root = biased["root"]
    clean = _windows(biased["clean"], root / "clean.npz")
    offset = ik.ImuData(np.arange(1201) * 0.005, np.tile(B_G, (1201, 1)), np.tile(B_A, (1201, 1)))
    ik.io.write_euroc(root / "offset", offset, noise=NOISE, rate_hz=200.0)  # a static offset alone
    zero = _windows(
        root / "offset", root / "offset.npz", "--gyro-bias", "0.01,-0.02,0.03", "--accel-bias", "0.1,0.2,-0.3"
    )
    np.testing.assert_allclose(zero["dv"], 0.0, atol=1e-15)  # readings minus the bias: nothing moves
    np.testing.assert_allclose(zero["dR_xyzw"][:, :3], 0.0, atol=1e-15)
    assert zero["bias_gyro"].tolist() == [B_G.tolist()] * len(zero["dv"])
    assert "bias_gyro" not in clean


def test_groundtruth_bias_at_each_window_start(biased: dict[str, Path]) -> None:
    root = biased["root"]
    clean = _windows(biased["clean"], root / "clean.npz")
    raw = _windows(biased["biased"], root / "raw.npz")
    fixed = _windows(biased["biased"], root / "fixed.npz", "--bias-from-groundtruth")
    starts = fixed["t_start"]
    np.testing.assert_allclose(fixed["bias_gyro"], B_G + 1e-3 * starts[:, None], rtol=0, atol=1e-15)
    np.testing.assert_allclose(fixed["bias_accel"], np.tile(B_A, (len(starts), 1)), rtol=0, atol=0)
    # held at the start's value, the bias left over a window grows as 1e-3 rad/s² x s on each axis:
    # its angle is the integral, 1e-3 * 0.5² / 2 per axis, √3 times that in norm (to first order)
    assert np.max(np.abs(fixed["dv"] - clean["dv"])) < 1e-3 < np.min(np.abs(raw["dv"] - clean["dv"]).max(axis=1))
    assert np.max(np.abs(fixed["dp"] - clean["dp"])) < 1e-4
    error = Rotation.from_quat(clean["dR_xyzw"]).inv() * Rotation.from_quat(fixed["dR_xyzw"])
    np.testing.assert_allclose(error.magnitude(), 1e-3 * 0.5**2 / 2 * np.sqrt(3), rtol=0.01)
    assert np.min((Rotation.from_quat(clean["dR_xyzw"]).inv() * Rotation.from_quat(raw["dR_xyzw"])).magnitude()) > 4e-3


def test_bias_options_refused_where_they_cannot_work(biased: dict[str, Path]) -> None:
    run = cli("preintegrate", biased["clean"], "--window", "1", "--bias-from-groundtruth", code=1)
    assert_one_line_error(run, "imukit: error: --bias-from-groundtruth: PATH has no ground truth")
    run = cli(
        "preintegrate", biased["biased"], "--window", "1", "--bias-from-groundtruth", "--gyro-bias", "0,0,0", code=1
    )
    assert_one_line_error(run, "not both")
    run = cli("preintegrate", biased["clean"], "--window", "1", "--gyro-bias", "1,2", code=2)
    assert "expected 3 comma-separated finite numbers, got '1,2'" in run.stderr


def test_filter_plot_without_a_reference_writes_out_and_the_attitude(biased: dict[str, Path], tmp_path: Path) -> None:
    out, png = tmp_path / "q.csv", tmp_path / "a.png"
    run = cli("filter", biased["clean"], "--out", out, "--plot", png)
    assert f"wrote attitudes: {out}" in run.stdout and f"wrote attitude plot: {png}" in run.stdout
    assert_png(png)
    rows = np.loadtxt(out, delimiter=",")
    imu, _ = ik.io.read_euroc(biased["clean"])
    np.testing.assert_allclose(rows[:, 1:5], ik.filters.Robust().run(imu).rotation.as_quat(), atol=1e-12)


def test_attitude_plot_draws_yaw_pitch_roll(tmp_path: Path) -> None:
    from imukit import plot

    t = np.arange(50) * 0.1
    rotation = Rotation.from_euler("ZYX", np.c_[10 * t, 0 * t + 5, 0 * t - 3], degrees=True)
    fig = plot.attitude_plot(tmp_path / "a.png", t, {"turn": rotation}, title="turn")
    assert [ax.get_ylabel() for ax in fig.axes] == ["yaw [deg]", "pitch [deg]", "roll [deg]"]
    np.testing.assert_allclose(fig.axes[0].get_lines()[0].get_ydata(), 10 * t, atol=1e-9)
    np.testing.assert_allclose(fig.axes[2].get_lines()[0].get_ydata(), -3.0, atol=1e-9)


def test_read_euroc_sensor_of_any_yaml_name(tmp_path: Path) -> None:
    imu = ik.ImuData(np.arange(5) * 0.005, np.zeros((5, 3)), np.zeros((5, 3)))
    ik.io.write_euroc(tmp_path / "seq", imu, noise=NOISE, rate_hz=200.0)
    renamed = tmp_path / "imu0_sensor.yaml"
    renamed.write_bytes(next((tmp_path / "seq").rglob("sensor.yaml")).read_bytes())
    sensor = ik.io.read_euroc_sensor(renamed)
    assert sensor is not None and sensor.noise == NOISE and sensor.rate_hz == 200.0
    camera = tmp_path / "cam0_sensor.yaml"
    camera.write_text("sensor_type: camera\ncomment: VI-Sensor cam0\nrate_hz: 20\nresolution: [752, 480]\n")
    with pytest.raises(
        ik.FileFormatError,
        match=r"cam0_sensor\.yaml: not an IMU sensor file \(sensor_type 'camera'; missing key",
    ):
        ik.io.read_euroc_sensor(camera)
    assert ik.io.read_euroc_sensor(tmp_path) is None  # a folder without one: None, as before


def test_imudata_slices_take_negative_indices_as_python() -> None:
    imu = ik.ImuData(np.arange(10) * 0.1, np.arange(30.0).reshape(10, 3), np.zeros((10, 3)))
    assert imu[-3:].t.tolist() == pytest.approx([0.7, 0.8, 0.9])
    assert imu[-1:].gyro.tolist() == [[27.0, 28.0, 29.0]]
    assert imu[-5:-2].t.tolist() == pytest.approx([0.5, 0.6, 0.7])
    assert imu[-100:2].t.tolist() == pytest.approx([0.0, 0.1])  # clipped, as a list slice is
    with pytest.raises(ik.ShapeError, match=r"^index: slice\(-2, -5, None\) selects no sample of 10"):
        imu[-2:-5]  # was "need a positive step", which its step is
    with pytest.raises(TypeError, match=r"imu\[k:k \+ 1\] for sample k"):
        imu[-1]  # type: ignore[index]
