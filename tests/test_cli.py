"""The ``imukit`` command line, end to end through subprocess: exit codes, files written, numbers
checked against the library (or hand-computed truth), one-line errors on bad input."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from euroc import GT_CSV, IMU_CSV, requires_euroc
from imukit._demo import broad_excerpt_path

matplotlib_image = pytest.importorskip("matplotlib.image", reason="the --plot checks decode PNGs with matplotlib")

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
RATE = 200.0  # 1e9 / RATE is a whole number of ns: float and integer stamps agree exactly
DURATION = 20.0
SEED = 3
COMMANDS = ("integrate", "preintegrate", "filter", "simulate", "allan", "evaluate", "fleet", "demo")


def cli(*args: str | os.PathLike[str], code: int = 0) -> subprocess.CompletedProcess[str]:
    """Run ``python -m imukit ARGS``; assert its exit code."""
    run = subprocess.run(
        [sys.executable, "-m", "imukit", *map(str, args)], capture_output=True, text=True, timeout=300, check=False
    )
    assert run.returncode == code, f"exit {run.returncode}, stdout:\n{run.stdout}\nstderr:\n{run.stderr}"
    return run


def assert_one_line_error(run: subprocess.CompletedProcess[str], *pieces: str) -> None:
    """stderr is exactly one line ``imukit: error: ...`` naming ``pieces``, with no traceback."""
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("imukit: error: "), run.stderr
    assert "Traceback" not in run.stderr
    for piece in pieces:
        assert piece in lines[0], (piece, lines[0])


def assert_png(path: Path) -> None:
    """A non-empty PNG that matplotlib decodes into an RGBA image of plausible size."""
    assert path.stat().st_size > 10_000
    image = matplotlib_image.imread(path)
    assert image.ndim == 3 and image.shape[2] == 4 and min(image.shape[:2]) > 300
    assert image[..., :3].std() > 0.05  # not a blank canvas


def number_after(text: str, label: str) -> float:
    match = re.search(re.escape(label) + r"\s+([-+0-9.eE]+)", text)
    assert match, f"{label!r} not in:\n{text}"
    return float(match.group(1))


def rmse_in_row(table: str, label: str) -> float:
    """The RMSE cell of the row starting with ``label`` in ``imukit evaluate``'s table."""
    for line in table.splitlines():
        cells = [c.strip() for c in re.split(r"[│|]", line)]
        if len(cells) > 3 and cells[1] == label:
            return float(cells[3])
    raise AssertionError(f"no row {label!r} in:\n{table}")


@pytest.fixture(scope="module")
def noise_yaml(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("noise") / "imu.yaml"
    ik.io.write_kalibr_imu(path, NOISE, rate_hz=RATE)
    return path


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory, noise_yaml: Path) -> Path:
    """``imukit simulate figure-eight`` with noise: the folder holding mav0/."""
    folder = tmp_path_factory.mktemp("sim") / "fig8"
    run = cli("simulate", "figure-eight", "--duration", DURATION, "--rate", RATE, "--noise", noise_yaml,
              "--seed", SEED, "--out", folder)  # fmt: skip
    assert "4001 samples" in run.stdout
    return folder


def in_memory() -> tuple[ik.ImuData, ik.Trajectory]:
    return ik.sim.simulate(ik.sim.FigureEight(), rate=RATE, duration=DURATION, noise=NOISE, seed=SEED)


def test_help_teaches_every_command() -> None:
    top = cli("--help").stdout
    for command in COMMANDS:
        assert command in top
        text = cli(command, "--help").stdout
        assert "Example:" in text and f"imukit {command}" in text, command
        assert "Writes" in text or "Prints" in text, command


def test_simulate_writes_the_simulation_as_euroc(simulated: Path) -> None:
    imu, truth = in_memory()
    read_imu, read_truth = ik.io.read_euroc(simulated)
    assert read_imu.t_ns is not None and read_truth is not None
    assert np.array_equal(read_imu.t_ns, np.arange(len(imu)) * 5_000_000)
    assert np.array_equal(read_imu.gyro, imu.gyro) and np.array_equal(read_imu.accel, imu.accel)
    assert np.array_equal(read_truth.position, truth.position)
    assert np.array_equal(read_truth.gyro_bias, truth.gyro_bias)
    assert ik.io.read_kalibr_imu(simulated / "mav0" / "imu0" / "sensor.yaml").noise == NOISE


def test_round_trip_library_exact(tmp_path: Path) -> None:
    """simulate → write_euroc → read_euroc → integrate equals integrating the simulation in memory, bit for bit."""
    imu, truth = in_memory()
    ik.io.write_euroc(tmp_path, imu, truth)
    read_imu, read_truth = ik.io.read_euroc(tmp_path)
    assert read_truth is not None
    for scheme in ik.strapdown.SCHEMES:
        direct = ik.integrate(imu, initial=truth.state(0), scheme=scheme)
        again = ik.integrate(read_imu, initial=read_truth.state(0), scheme=scheme)
        assert np.array_equal(again.position, direct.position), scheme
        assert np.array_equal(again.rotation.as_quat(), direct.rotation.as_quat()), scheme


@pytest.mark.parametrize("scheme", ["midpoint", "rk4"])
def test_round_trip_cli_exact(simulated: Path, tmp_path: Path, scheme: str) -> None:
    """imukit simulate → imukit integrate (initial state from the written truth) → TUM equals the
    in-memory integration exactly; the printed final error is the in-memory one."""
    out = tmp_path / "traj.txt"
    run = cli("integrate", simulated, "--scheme", scheme, "--out", out)
    imu, truth = in_memory()
    direct = ik.integrate(imu, initial=truth.state(0), scheme=scheme)
    written = ik.io.read_tum(out)
    assert np.array_equal(written.position, direct.position)
    assert np.array_equal(written.rotation.as_quat(), direct.rotation.as_quat())
    assert written.t_ns is not None and np.array_equal(written.t_ns, np.arange(len(imu)) * 5_000_000)
    final = float(np.linalg.norm(direct.position[-1] - truth.position[-1]))
    assert number_after(run.stdout, "final position error") == pytest.approx(final, rel=1e-3)


def test_integrate_without_truth_starts_levelled(tmp_path: Path) -> None:
    """No ground truth: the start is levelled from the accelerometer (roll 0.2, pitch −0.1 rad here,
    yaw set to 0), and a noise-free rest stays at the origin."""
    tilt = Rotation.from_euler("ZYX", [0.7, -0.1, 0.2])
    imu, _ = ik.sim.simulate(ik.sim.Static(rotation=tilt), rate=RATE, duration=5.0)
    ik.io.write_euroc(tmp_path / "mav0", imu)
    out = tmp_path / "traj.tum"
    run = cli("integrate", tmp_path, "--static-seconds", "1", "--out", out)
    assert "no ground truth" in run.stderr
    traj = ik.io.read_tum(out)
    yaw, pitch, roll = traj.rotation[0].as_euler("ZYX")
    assert (yaw, pitch, roll) == pytest.approx((0.0, -0.1, 0.2), abs=1e-12)
    assert np.abs(traj.position).max() < 1e-9


def test_integrate_refuses_bias_without_truth(tmp_path: Path) -> None:
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=RATE, duration=2.0)
    ik.io.write_euroc(tmp_path, imu)
    assert_one_line_error(cli("integrate", tmp_path, "--bias-from-groundtruth", code=1), "--bias-from-groundtruth")


@requires_euroc
def test_integrate_real_euroc_with_plot(tmp_path: Path) -> None:
    """EuRoC V1_02 excerpt: the truth starts at ...524907143168 ns, 3168 ns after IMU sample 199, so
    200 samples are skipped; with the truth's biases the dead reckoning drifts less than without."""
    folder = tmp_path / "V1_02" / "mav0"
    for csv, target in ((IMU_CSV, "imu0"), (GT_CSV, "state_groundtruth_estimate0")):
        (folder / target).mkdir(parents=True)
        (folder / target / "data.csv").symlink_to(csv)
    png = tmp_path / "top.png"
    with_bias = cli("integrate", folder.parent, "--bias-from-groundtruth", "--plot", png)
    without = cli("integrate", folder.parent)
    assert "skipped the first 200 IMU samples" in with_bias.stderr
    ate_with = number_after(with_bias.stdout, "ATE RMSE")
    ate_without = number_after(without.stdout, "ATE RMSE")
    assert ate_with < ate_without
    assert_png(png)


def test_preintegrate_windows_match_the_library(simulated: Path, tmp_path: Path) -> None:
    csv, npz = tmp_path / "w.csv", tmp_path / "w.npz"
    run = cli("preintegrate", simulated, "--window", "0.5", "--out", csv)  # noise from mav0/imu0/sensor.yaml
    cli("preintegrate", simulated, "--window", "0.5", "--out", npz, "--noise", simulated / "mav0/imu0/sensor.yaml")
    assert run.stdout.startswith(f"{int(DURATION / 0.5)} windows")
    imu, _ = ik.io.read_euroc(simulated)
    edges = np.arange(41) * 500_000_000  # integer ns, as the stamps
    pims = ik.preintegrate_windows(imu, edges, noise=NOISE)
    rows = np.loadtxt(csv, delimiter=",")
    assert rows.shape == (40, 24)
    exact = np.loadtxt(csv, delimiter=",", usecols=(22, 23), dtype=np.int64)  # t_start_ns, t_end_ns
    assert np.array_equal(exact, np.column_stack([edges[:-1], edges[1:]]))
    assert np.array_equal(rows[:, 2], [p.delta_t for p in pims])
    assert np.array_equal(rows[:, 3:7], [p.delta_rotation.as_quat() for p in pims])
    assert np.array_equal(rows[:, 10:13], [p.delta_position for p in pims])
    assert np.array_equal(rows[:, 13:22], [np.diag(p.covariance) for p in pims])
    with np.load(npz) as data:
        assert np.array_equal(data["covariance"], [p.covariance for p in pims])
        assert np.array_equal(data["dv"], [p.delta_velocity for p in pims])
        assert np.array_equal(data["t_start"], np.arange(40) * 0.5)
        assert data["t_end_ns"].dtype == np.int64 and np.array_equal(data["t_end_ns"], edges[1:])


def test_preintegrate_at_rest_is_gravity(tmp_path: Path, noise_yaml: Path) -> None:
    """At rest, level: Δv = (0, 0, g·Δt) and Δp = ½ g Δt² (gravity is not in the deltas)."""
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=RATE, duration=2.0)
    ik.io.write_euroc(tmp_path, imu)
    out = tmp_path / "w.npz"
    cli("preintegrate", tmp_path, "--window", "0.25", "--noise", noise_yaml, "--out", out)
    with np.load(out) as data:
        assert data["dv"].shape == (8, 3)
        np.testing.assert_allclose(data["dv"], np.tile([0.0, 0.0, 9.81 * 0.25], (8, 1)), atol=1e-12)
        np.testing.assert_allclose(data["dp"], np.tile([0.0, 0.0, 0.5 * 9.81 * 0.25**2], (8, 1)), atol=1e-12)
        np.testing.assert_allclose(data["dR_xyzw"], np.tile([0.0, 0.0, 0.0, 1.0], (8, 1)), atol=1e-15)


def test_preintegrate_needs_a_noise_model(tmp_path: Path) -> None:
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=RATE, duration=2.0)
    ik.io.write_euroc(tmp_path, imu)  # no sensor.yaml
    assert_one_line_error(cli("preintegrate", tmp_path, "--window", "0.5", code=1), "--noise")


def test_filter_broad_excerpt_9d(tmp_path: Path) -> None:
    """The shipped BROAD excerpt has a magnetometer: the printed errors are the library's."""
    csv, png = tmp_path / "q.csv", tmp_path / "err.png"
    path = broad_excerpt_path()
    run = cli("filter", path, "--method", "madgwick", "--mag", "--out", csv, "--plot", png)
    with np.load(path) as d:
        rate = float(d["sampling_rate"])
        imu = ik.ImuData(np.arange(len(d["imu_gyr"])) / rate, d["imu_gyr"], d["imu_acc"])
        result = ik.filters.Madgwick().run(imu, mag=d["imu_mag"])
        truth, movement = d["opt_quat"], d["movement"]
    rmse = ik.eval.attitude_error(result.rotation, truth, scalar_first=True, mask=movement).rmse(degrees=True)
    assert number_after(run.stdout, "total") == pytest.approx(rmse.total, abs=1e-3)
    assert number_after(run.stdout, "inclination") == pytest.approx(rmse.inclination, abs=1e-3)
    rows = np.loadtxt(csv, delimiter=",")
    np.testing.assert_allclose(rows[:, 1:5], result.rotation.as_quat(), atol=1e-12)
    np.testing.assert_array_equal(rows[:, 0], imu.t)
    assert_png(png)


def test_filter_scores_a_ned_estimate_against_the_z_up_truth_in_ned() -> None:
    """BROAD's motion capture is z up: `--world NED` printed 175° (before 2026-12-07); the same
    physical attitudes score the same in either world."""
    path = broad_excerpt_path()
    enu, ned = (cli("filter", path, "--mag", "--world", w).stdout for w in ("ENU", "NED"))
    assert number_after(enu, "total") < 10.0
    for name in ("total", "heading", "inclination"):
        assert number_after(ned, name) == pytest.approx(number_after(enu, name), abs=1e-3), name


def test_filter_tum_output_has_zero_positions(simulated: Path, tmp_path: Path) -> None:
    out = tmp_path / "att.txt"
    run = cli("filter", simulated, "--out", out)
    assert "constant heading offset removed" in run.stdout  # 6D, scored against the simulated truth
    imu, _ = ik.io.read_euroc(simulated)
    written = ik.io.read_tum(out)
    assert np.array_equal(written.position, np.zeros((len(imu), 3)))
    np.testing.assert_allclose(written.rotation.as_quat(), ik.filters.Robust().run(imu).rotation.as_quat(), atol=1e-12)


def test_filter_refuses_mag_without_magnetometer(simulated: Path) -> None:
    assert_one_line_error(cli("filter", simulated, "--mag", code=1), "--mag", "no magnetometer")


def test_chunked_filter_equals_one_call() -> None:
    """The CLI's chunked run (state carried across pieces) gives one call's attitudes to rounding."""
    from imukit.cli._attitude_input import read_broad
    from imukit.cli._filter import run_chunked

    data = read_broad(broad_excerpt_path())
    for cls in (ik.filters.Mahony, ik.filters.Madgwick, ik.filters.Robust):
        whole = cls().run(data.imu, mag=data.mag)
        pieces = run_chunked(cls(), data, use_mag=True, chunk=997)
        assert len(pieces.rotation) == len(whole.rotation)
        assert np.abs(pieces.rotation.as_quat() - whole.rotation.as_quat()).max() < 1e-12
        assert np.abs(pieces.gyro_bias - whole.gyro_bias).max() < 1e-15
        if cls is ik.filters.Robust:
            fields = pieces.state.fields(), whole.state.fields()
            for name, value in fields[1].items():
                assert np.allclose(np.asarray(fields[0][name], float), np.asarray(value, float), rtol=0, atol=1e-12), (
                    name
                )
        else:
            assert np.allclose(pieces.state.values, whole.state.values, rtol=0, atol=1e-12)
    smoothed = ik.filters.Robust().run(data.imu, mag=data.mag, offline=True)
    offline = run_chunked(ik.filters.Robust(), data, use_mag=True, chunk=997, offline=True)  # one piece
    assert np.abs(offline.rotation.as_quat() - smoothed.rotation.as_quat()).max() < 1e-15  # Rotation round trip


def test_filter_robust_and_its_smoother_from_the_command_line(tmp_path: Path) -> None:
    """``--method robust`` (``--offline``: the smoother) reaches the filter the docs rank first; the
    printed RMSE is the library's on the same data."""
    from imukit.cli._attitude_input import read_broad

    path = broad_excerpt_path()
    data = read_broad(path)
    for offline in (False, True):
        result = cli("filter", path, "--method", "robust", "--mag", *(["--offline"] if offline else []))
        expected = ik.eval.attitude_error(
            ik.filters.Robust().run(data.imu, mag=data.mag, offline=offline).rotation, data.truth_xyzw, mask=data.mask
        ).rmse(degrees=True)
        assert f"Robust{' offline' if offline else ''} 9D: {len(data.imu)} samples" in result.stdout
        assert f"total {expected.total:.3f} deg" in result.stdout
    assert "Robust 6D:" in cli("filter", path).stdout  # the default method
    assert_one_line_error(
        cli("filter", path, "--method", "madgwick", "--offline", code=1), "--offline", "only --method robust"
    )


def test_allan_recovers_the_simulated_noise(tmp_path: Path, noise_yaml: Path) -> None:
    folder = tmp_path / "static"
    cli(
        "simulate",
        "static",
        "--duration",
        "600",
        "--rate",
        "100",
        "--noise",
        noise_yaml,
        "--seed",
        "5",
        "--out",
        folder,
    )
    png = tmp_path / "allan.png"
    run = cli("allan", folder, "--out", png)
    assert "not still" not in run.stderr
    fitted = ik.io.read_kalibr_imu(tmp_path / "allan.yaml")
    assert fitted.rate_hz == 100.0  # 60000 intervals of 10 ms, counted in integer ns
    assert fitted.noise.gyro_density == pytest.approx(NOISE.gyro_density, rel=0.05)
    assert fitted.noise.accel_density == pytest.approx(NOISE.accel_density, rel=0.05)
    assert_png(tmp_path / "allan_gyro.png")
    assert_png(tmp_path / "allan_accel.png")


def test_allan_says_when_the_recording_moves(simulated: Path, tmp_path: Path) -> None:
    """A moving recording's Allan deviation measures its motion: said, not only fitted."""
    run = cli("allan", simulated, "--out", tmp_path / "allan.png")
    assert "is not still for" in run.stderr and "measures that motion too" in run.stderr


def test_a_reader_that_leaves_does_not_cost_the_written_files(simulated: Path, tmp_path: Path) -> None:
    """``imukit integrate … | head -1``: the pipe's reader gone before the summary lines, the command
    ended with exit 1 and without its trajectory file (before 2026-12-07)."""
    target = tmp_path / "x.txt"
    read, write = os.pipe()
    os.close(read)  # the reader has left before the first line
    try:
        run = subprocess.run(
            [sys.executable, "-m", "imukit", "integrate", str(simulated), "--out", str(target)],
            stdout=write,
            stderr=subprocess.PIPE,
            text=True,
            timeout=300,
            check=False,
        )
    finally:
        os.close(write)
    assert run.returncode == 0, run.stderr
    assert "Traceback" not in run.stderr and "Broken pipe" not in run.stderr
    assert len(ik.io.read_tum(target)) == int(RATE) * int(DURATION) + 1


def test_evaluate_known_offset(tmp_path: Path) -> None:
    """An estimate = truth shifted by (1, 2, 2) m: ATE 3 m without alignment, 0 after se3."""
    _, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=50.0, duration=20.0)
    shifted = ik.Trajectory(truth.t, truth.position + np.array([1.0, 2.0, 2.0]), None, truth.rotation)
    est, gt, png = tmp_path / "est.txt", tmp_path / "gt.txt", tmp_path / "ate.png"
    shifted.write_tum(est)
    truth.write_tum(gt)
    none = cli("evaluate", est, gt, "--align", "none")
    se3 = cli("evaluate", est, gt, "--align", "se3", "--delta", "1", "--plot", png)
    assert rmse_in_row(none.stdout, "ATE translation") == pytest.approx(3.0, abs=1e-9)
    assert rmse_in_row(se3.stdout, "ATE translation") < 1e-6
    assert "RPE translation / 1 m" in se3.stdout
    assert_png(png)


def test_evaluate_finds_the_clock_offset(tmp_path: Path) -> None:
    """An estimate whose stamps are 37 ms late (EST time t is GT time t − 0.037): ``--offset auto``
    prints −0.037 s from the angular speeds and pairs by it (ATE rotation near 0); without it
    the poses are compared 37 ms apart."""
    _, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=40.0)
    late = ik.Trajectory(truth.t + 0.037, truth.position, None, truth.rotation)
    est, gt = tmp_path / "est.txt", tmp_path / "gt.txt"
    late.write_tum(est)
    truth.write_tum(gt)
    auto = cli("evaluate", est, gt, "--align", "none", "--offset", "auto", "--max-offset", "0.2")
    found = re.search(r"clock offset from the angular speeds: ([-+0-9.e]+) s", auto.stdout)
    assert found is not None, auto.stdout
    assert float(found.group(1)) == pytest.approx(-0.037, abs=2e-4)
    plain = cli("evaluate", est, gt, "--align", "none")
    assert rmse_in_row(auto.stdout, "ATE rotation") < 0.02 * rmse_in_row(plain.stdout, "ATE rotation")
    bad = cli("evaluate", est, gt, "--offset", "soon", code=2)
    assert "expected a number of seconds or 'auto'" in bad.stderr
    wide = cli("evaluate", est, gt, "--offset", "auto", "--max-offset", "100", code=1)
    assert_one_line_error(wide, "--max-offset: expected well below the shared span")
    given = cli("evaluate", est, gt, "--offset", "0.01", "--max-offset", "0.2", code=1)
    assert_one_line_error(given, "--max-offset: only with --offset auto")
    still = tmp_path / "still.txt"
    ik.Trajectory(truth.t, truth.position, None, Rotation.identity(len(truth))).write_tum(still)
    flat = cli("evaluate", still, gt, "--offset", "auto", code=1)
    assert_one_line_error(flat, "EST: expected a change of angular speed")


@pytest.mark.parametrize(
    ("args", "pieces"),
    [
        (["integrate", "/no/such/folder"], ["/no/such/folder"]),
        (["integrate", "{broad}", "--out", "traj.csv"], ["--out", ".txt"]),
        (["simulate", "spiral", "--out", "x"], ["TRAJECTORY", "spiral"]),
        (["filter", "{broad}", "--plot", "/no/such/dir/e.png"], ["--plot", "does not exist"]),
        (["preintegrate", "{broad}", "--window", "0.5"], ["broad_excerpt.npz: not a text file"]),
    ],
)
def test_bad_input_one_line(args: list[str], pieces: list[str], tmp_path: Path) -> None:
    broad = str(broad_excerpt_path())
    run = cli(*(a.format(broad=broad) for a in args), code=1)
    assert_one_line_error(run, *pieces)


def test_bad_usage_exit_2_and_debug_traceback() -> None:
    assert cli(code=2).returncode == 2
    assert "--window" in cli("preintegrate", "x", code=2).stderr  # required option missing
    assert "expected a positive number" in cli("integrate", "x", "--static-seconds", "-1", code=2).stderr
    debug = cli("--debug", "integrate", "/no/such/folder", code=1)
    assert "Traceback" in debug.stderr and debug.stderr.strip().splitlines()[-1].startswith("imukit: error: ")


def test_bad_lines_end_the_command_or_are_skipped_and_listed(tmp_path: Path) -> None:
    """A malformed line and a repeated stamp: without --skip-bad-lines the first ends the command
    naming file and line; with it (before or after the command) both are listed and the 99 good
    samples integrated."""
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=RATE, duration=0.495)  # 100 samples
    ik.io.write_euroc(tmp_path, imu)
    csv = tmp_path / "imu0" / "data.csv"
    lines = csv.read_text().splitlines()
    lines[11] = lines[11].replace(",", ";", 1)  # line 12 of the file: malformed
    lines.insert(31, lines[30])  # line 32 repeats the stamp of line 31
    csv.write_text("\n".join(lines) + "\n")
    out = tmp_path / "t.txt"
    assert_one_line_error(cli("integrate", tmp_path, code=1), str(csv), "line 12")
    for args in (["--skip-bad-lines", "integrate", tmp_path], ["integrate", tmp_path, "--skip-bad-lines"]):
        run = cli(*args, "--out", out)
        assert "2 lines skipped" in run.stderr and "line 12" in run.stderr and "line 32" in run.stderr
        assert len(ik.io.read_tum(out)) == 99


def test_simulate_from_a_tum_file_passes_through_its_poses(tmp_path: Path) -> None:
    """A TUM file becomes a C² spline through its poses: the simulated truth at the file's stamps
    is the file's poses, and the run spans the file from its first stamp."""
    _, path = ik.sim.simulate(ik.sim.FigureEight(), rate=2.0, duration=10.0, start=100.0)  # 21 poses
    tum = tmp_path / "path.tum"
    ik.Trajectory(path.t, path.position, None, path.rotation).write_tum(tum)
    run = cli("simulate", tum, "--rate", "100", "--out", tmp_path / "sim")
    assert "1001 samples at 100 Hz over 10 s" in run.stdout
    _, truth = ik.io.read_euroc(tmp_path / "sim")
    assert truth is not None and truth.t_ns is not None
    assert truth.t_ns[0] == 100_000_000_000 and truth.t_ns[-1] == 110_000_000_000
    at_poses = truth.position[::50]  # every 0.5 s
    np.testing.assert_allclose(at_poses, path.position, atol=1e-9)
    angles = (truth.rotation[::50].inv() * path.rotation).magnitude()
    assert angles.max() < 1e-9
    assert np.abs(truth.velocity[[0, -1]]).max() < 1e-12  # clamped: at rest at both ends


def test_simulate_from_epoch_stamps_keeps_the_rate_exact(tmp_path: Path) -> None:
    """At epoch stamps float seconds resolve 238 ns: the start carried as seconds gave steps of
    5,000,114 ns and 4,999,876 ns at 200 Hz (before 2026-12-07). The stamps are the file's first
    one plus k·5 ms exactly, and the truth at the file's stamps is its poses."""
    tum = tmp_path / "epoch.tum"
    lines = [
        f"{1403636579 + k}.763555527 {0.1 * k} {0.02 * k * k} 0 0 0 {np.sin(0.05 * k)} {np.cos(0.05 * k)}"
        for k in range(11)
    ]
    tum.write_text("\n".join(lines) + "\n")
    cli("simulate", tum, "--rate", "200", "--out", tmp_path / "sim")
    imu, truth = ik.io.read_euroc(tmp_path / "sim")
    assert imu.t_ns is not None and truth is not None and truth.t_ns is not None
    expected = 1403636579763555527 + 5_000_000 * np.arange(2001)
    assert np.array_equal(imu.t_ns, expected) and np.array_equal(truth.t_ns, expected)
    poses = ik.io.read_tum(tum)
    np.testing.assert_allclose(truth.position[::200], poses.position, atol=1e-9)
    assert (truth.rotation[::200].inv() * poses.rotation).magnitude().max() < 1e-9


def test_chunked_preintegration_equals_one_call(monkeypatch: pytest.MonkeyPatch) -> None:
    """The CLI's windows, computed 7 per call, are bit for bit those of one call."""
    from imukit.cli import _preintegrate

    imu, _ = in_memory()
    edges = _preintegrate.boundaries(imu, 0.3)
    assert len(edges) == 67 and edges[-1] == pytest.approx(19.8)  # the partial last 0.2 s is dropped
    monkeypatch.setattr(_preintegrate, "WINDOWS_PER_CALL", 7)
    pieces = _preintegrate.windows(imu, edges, NOISE, "midpoint")
    whole = ik.preintegrate_windows(imu, edges, ik.PreintParams(NOISE, scheme="midpoint"))
    assert len(pieces) == len(whole) == 66
    for name in ("delta_rotation", "delta_position", "covariance", "t_start", "t_end"):
        assert np.array_equal(getattr(pieces, name), getattr(whole, name)), name


def test_console_script_is_the_same_main() -> None:
    from importlib.metadata import entry_points

    from imukit.cli import main

    (script,) = [e for e in entry_points(group="console_scripts") if e.name == "imukit"]
    assert script.value == "imukit.cli:main" and script.load() is main


def test_plot_without_matplotlib_is_a_one_line_error(tmp_path: Path) -> None:
    """No matplotlib: --plot ends with one line naming the extra to install (the samples are not lost:
    --out is written first)."""
    blocked = (
        "import sys; sys.modules['matplotlib.figure'] = None; from imukit.cli import main; "
        "raise SystemExit(main(sys.argv[1:]))"
    )
    out, png = tmp_path / "q.csv", tmp_path / "e.png"
    args = ["filter", str(broad_excerpt_path()), "--out", str(out), "--plot", str(png)]
    run = subprocess.run([sys.executable, "-c", blocked, *args], capture_output=True, text=True, timeout=120)
    assert run.returncode == 1
    assert_one_line_error(run, 'pip install "imukit[plot]"')
    assert not png.exists()
    assert len(np.loadtxt(out, delimiter=",")) == 11_428


def test_preintegrate_finds_sensor_yaml_beside_a_bare_csv(simulated: Path, tmp_path: Path) -> None:
    out = tmp_path / "w.npz"
    cli("preintegrate", simulated / "mav0" / "imu0" / "data.csv", "--window", "1", "--out", out)
    with np.load(out) as data:
        assert data["covariance"].shape == (20, 9, 9) and data["covariance"][0, 0, 0] > 0.0  # the noise was found


def test_evaluate_counts_poses_outside_the_span_apart_from_those_in_gaps(tmp_path: Path) -> None:
    """GT at 10 Hz over [0, 10] s without its stamps 5.0 … 6.0 (a 1.2 s gap from 4.9 to 6.1); EST at
    20 Hz from −0.475 to 10.475 s (220 poses, none on a GT stamp). By hand: 10 before 0 and 10 after
    10 s are outside the span; 4.925 … 6.075 s, 24 poses, fall in the gap (longer than --max-dt 0.2)."""
    gt_t = np.arange(101) / 10
    gt_t = gt_t[(gt_t < 4.95) | (gt_t > 6.05)]
    est_t = -0.475 + np.arange(220) / 20
    for t, path in ((gt_t, tmp_path / "gt.txt"), (est_t, tmp_path / "est.txt")):
        ik.Trajectory(t, np.column_stack([t, 0 * t, 0 * t]), None, Rotation.identity(len(t))).write_tum(path)
    run = cli("evaluate", tmp_path / "est.txt", tmp_path / "gt.txt", "--align", "none", "--max-dt", "0.2")
    assert (
        "scored 176 of 220 estimate poses (80.00%); left out 20 outside the ground truth's span (before its first "
        "or after its last stamp), 24 in its gaps longer than --max-dt = 0.2 s" in run.stdout
    )
    assert rmse_in_row(run.stdout, "ATE translation") < 1e-12  # x = t on both: the kept 176 poses agree
    (row,) = [line for line in run.stdout.splitlines() if "ATE translation" in line]
    assert row.rstrip(" │|").split()[-1] == "176"  # the samples column: 220 − 44


def test_integrate_counts_samples_after_the_truth_apart_from_those_in_gaps(tmp_path: Path) -> None:
    """IMU at 200 Hz over [0, 5] s; the ground truth stops at 3 s and lacks its 19 stamps strictly
    between 1.0 and 1.1 s. By hand: 400 samples (3.005 … 5 s) are after its span, 19 in the gap
    (longer than 2.5 x the truth's 0.005 s step), and the ATE is over 1001 − 419 = 582 samples."""
    imu, truth = ik.sim.simulate(ik.sim.Circle(), rate=RATE, duration=5.0)
    keep = np.flatnonzero(
        (np.arange(len(truth)) <= 600) & ~((np.arange(len(truth)) > 200) & (np.arange(len(truth)) < 220))
    )
    cut = ik.Trajectory(truth.t[keep], truth.position[keep], truth.velocity[keep], truth.rotation[keep])
    ik.io.write_euroc(tmp_path, imu, cut, truth_bias=ik.ImuBias())
    run = cli("integrate", tmp_path)
    assert (
        "scored 582 of 1001 samples (58.14%); left out 400 outside the ground truth's span (before its first or "
        "after its last stamp), 19 in its gaps longer than 0.0125 s (2.5 x its median step; --max-dt sets it)"
        in run.stdout
    )
    assert "over 582 samples (no alignment)" in run.stdout


def test_preintegrate_notes_a_t_bs_it_does_not_apply(tmp_path: Path) -> None:
    """A sensor.yaml whose T_BS turns the sensor 90° about z: the noise is used, the note says T_BS is
    not applied, and the deltas are the same as with the identity (level rest: Δv = (0, 0, g·Δt))."""
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=RATE, duration=1.0)
    ik.io.write_euroc(tmp_path, imu, noise=NOISE, rate_hz=RATE)
    yaml = tmp_path / "imu0" / "sensor.yaml"
    out = tmp_path / "w.npz"
    identity = cli("preintegrate", tmp_path, "--window", "0.5", "--out", out)
    assert "T_BS" not in identity.stderr
    with np.load(out) as data:
        dv_identity = data["dv"]
    yaml.write_text(
        yaml.read_text().replace(
            "data: [1.0, 0.0, 0.0, 0.0,\n         0.0, 1.0,", "data: [0.0, -1.0, 0.0, 0.0,\n         1.0, 0.0,"
        )
    )
    turned = cli("preintegrate", tmp_path, "--window", "0.5", "--out", out)
    assert "imukit: the sensor.yaml's T_BS is not the identity; it is not applied" in turned.stderr
    with np.load(out) as data:
        assert np.array_equal(data["dv"], dv_identity)
        np.testing.assert_allclose(data["dv"], np.tile([0.0, 0.0, 9.81 * 0.5], (2, 1)), atol=1e-12)
        assert data["covariance"][0, 0, 0] > 0.0
