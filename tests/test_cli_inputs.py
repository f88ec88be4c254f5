"""The CLI's inputs: evaluate's alignment reaching the RPE, gaps in IMU stamps (noted, or refused with
--max-dt), reference attitudes not bridged across ground-truth gaps, generic CSV options, and library
argument names shown as the options the user typed."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from euroc import IMU_CSV, requires_euroc
from test_cli import assert_one_line_error, cli, rmse_in_row

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data"
XIO = SHARED / "xio_fusion_example" / "sensor_data.csv"
KITTI = SHARED / "kitti_gtsam" / "KittiEquivBiasedImu.txt"
EUROC_HEADER = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"  # noqa: E501


@pytest.fixture(scope="module")
def noise_yaml(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("noise") / "imu.yaml"
    ik.io.write_kalibr_imu(path, ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3), rate_hz=200.0)
    return path


def write_euroc_csv(path: Path, t_ns: np.ndarray, gyro: np.ndarray, accel: np.ndarray) -> None:
    with open(path, "w", encoding="utf-8") as f:
        f.write(EUROC_HEADER + "\n")
        for k in range(len(t_ns)):
            f.write(f"{t_ns[k]}," + ",".join(repr(float(v)) for v in (*gyro[k], *accel[k])) + "\n")


def test_evaluate_rpe_uses_the_alignment(tmp_path: Path) -> None:
    """EST = GT scaled x2, turned 30 deg about z and shifted: a similarity, so after sim3 every relative
    pose agrees (RPE 0); unaligned, each 1 m of GT is 2 m of EST, an RPE of 1 m per pair."""
    _, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=50.0, duration=20.0)
    yaw = Rotation.from_euler("z", 30, degrees=True)
    position = yaw.apply(2.0 * truth.position) + np.array([3.0, -1.0, 0.5])
    estimate = ik.Trajectory(truth.t, position, None, yaw * truth.rotation)
    est, gt = tmp_path / "est.txt", tmp_path / "gt.txt"
    estimate.write_tum(est)
    truth.write_tum(gt)
    sim3 = cli("evaluate", est, gt, "--align", "sim3", "--delta", "1").stdout
    none = cli("evaluate", est, gt, "--align", "none", "--delta", "1").stdout
    assert rmse_in_row(sim3, "ATE translation") < 1e-6
    assert rmse_in_row(sim3, "RPE translation / 1 m") < 1e-6  # was 1 m: the RPE ignored --align
    assert rmse_in_row(none, "RPE translation / 1 m") == pytest.approx(1.0, rel=0.05)
    library = ik.eval.rpe(estimate, truth, delta=1.0, align="none").translation_stats.rmse
    assert rmse_in_row(none, "RPE translation / 1 m") == pytest.approx(library, rel=1e-3)  # 4 printed digits


def test_library_argument_names_become_option_names(tmp_path: Path) -> None:
    _, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=50.0, duration=20.0)
    gt = tmp_path / "gt.txt"
    truth.write_tum(gt)
    run = cli("evaluate", gt, gt, "--delta", "2.5", "--delta-unit", "frames", code=1)
    assert_one_line_error(run, "imukit: error: --delta: expected a whole number")
    run = cli("evaluate", gt, gt, "--offset", "100", code=1)
    assert_one_line_error(run, "imukit: error: --offset: no estimate sample can be paired")
    sparse = ik.Trajectory(truth.t[::50], truth.position[::50], None, truth.rotation[::50])  # 1 s apart
    sparse_path = tmp_path / "sparse.txt"
    sparse.write_tum(sparse_path)
    shifted = ik.Trajectory(truth.t[25:-25:50], truth.position[25:-25:50], None, truth.rotation[25:-25:50])
    est = tmp_path / "est.txt"
    shifted.write_tum(est)  # every pose mid-way between two GT poses 1 s apart: bridged by GT's own rate,
    run = cli("evaluate", est, sparse_path, "--max-dt", "0.5", code=1)  # not under a limit of half a step
    assert_one_line_error(run, "imukit: error: --max-dt: no estimate sample can be paired")


@pytest.fixture(scope="module")
def gappy_csv(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, ik.ImuData]:
    """200 Hz at rest for 10 s with samples 500..699 missing: one 1.005 s step into (new) sample 500."""
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=200.0, duration=10.0)
    keep = np.r_[0:500, 700 : len(imu)]
    t_ns = np.round(imu.t * 1e9).astype(np.int64)[keep]
    path = tmp_path_factory.mktemp("gap") / "imu.csv"
    write_euroc_csv(path, t_ns, imu.gyro[keep], imu.accel[keep])
    return path, imu


def test_a_large_gap_is_named_on_stderr(gappy_csv: tuple[Path, ik.ImuData]) -> None:
    path, _ = gappy_csv
    run = cli("integrate", path)
    notes = [line for line in run.stderr.splitlines() if "step into sample" in line]
    assert notes == [
        "imukit: the step into sample 500 (t = 3.5 s) is 1.005 s, 201 x the median 0.005 s; "
        "integrated across (--max-gap S refuses it)"
    ]


def test_max_gap_refuses_a_larger_gap(gappy_csv: tuple[Path, ik.ImuData]) -> None:
    path, _ = gappy_csv
    run = cli("preintegrate", path, "--window", "1", "--max-gap", "0.5", code=1)
    expected = (
        "imukit: error: --max-gap: the step into sample 500 (t = 3.5 s) is 1.005 s, longer than --max-gap = 0.5 s"
    )
    assert_one_line_error(run, expected)
    cli("integrate", path, "--max-gap", "1.1")  # a limit above the gap: accepted


def test_no_gap_note_on_even_stamps(tmp_path: Path) -> None:
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=200.0, duration=5.0)
    path = tmp_path / "imu.csv"
    write_euroc_csv(path, np.round(imu.t * 1e9).astype(np.int64), imu.gyro, imu.accel)
    assert "step into sample" not in cli("integrate", path).stderr


@pytest.mark.skipif(not KITTI.is_file(), reason=f"{KITTI} absent (../shared/data)")
def test_kittis_orphan_first_sample_is_named() -> None:
    noted = cli("integrate", KITTI)
    assert "imukit: the step into sample 1 (t = 46536.398 s) is 1.9196 s, 192 x the median" in noted.stderr
    refused = cli("integrate", KITTI, "--max-gap", "0.5", code=1)
    assert_one_line_error(refused, "--max-gap: the step into sample 1 (t = 46536.398 s) is 1.9196 s")


def test_filter_does_not_score_samples_in_a_truth_gap(tmp_path: Path) -> None:
    """Truth rows 1000..1599 removed (a 3 s mocap dropout at 200 Hz): the 600 IMU samples inside it get
    no reference (they were slerped across before); the score is attitude_error over the rest."""
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=20.0, seed=2)
    keep = np.r_[0:1000, 1600 : len(truth)]
    t_ns = np.round(truth.t * 1e9).astype(np.int64)
    imu_ns = ik.ImuData(t_ns, imu.gyro, imu.accel)
    gappy = ik.Trajectory(None, truth.position[keep], truth.velocity[keep], truth.rotation[keep], t_ns=t_ns[keep])
    ik.io.write_euroc(tmp_path / "seq", imu_ns, gappy, truth_bias=ik.ImuBias())
    run = cli("filter", tmp_path / "seq", "--out", tmp_path / "q.csv")
    assert (
        f"scored {len(imu) - 600} of {len(imu)} IMU samples ({(len(imu) - 600) / len(imu):.2%}); left out 0 outside "
        "the ground truth's span (before its first or after its last stamp), 600 in its gaps longer than "
        "0.0125 s (2.5 x its median step; --max-dt sets it)"
    ) in run.stdout
    reference = truth.rotation.as_quat()
    reference[1000:1600] = np.nan
    estimate = ik.filters.Robust().run(imu_ns).rotation
    rmse = ik.eval.attitude_error(estimate, reference, align_heading=True).rmse(degrees=True)
    assert rmse.n_samples == len(imu) - 600
    assert f"attitude error RMSE over {len(imu) - 600} samples: total {rmse.total:.3f} deg" in run.stdout
    wide = cli("filter", tmp_path / "seq", "--max-dt", "3.1")  # a limit over the dropout bridges it
    assert f"over {len(imu)} samples" in wide.stdout and "left out" not in wide.stdout
    assert f"scored {len(imu)} of {len(imu)} IMU samples (100.00%)" in wide.stdout


def test_filter_on_a_generic_csv_equals_the_library(tmp_path: Path) -> None:
    """A CSV in deg/s and g with named and numbered columns: the CLI's attitudes are the library's on
    read_imu_csv's samples, and those are the simulated ones (hand conversion: x pi/180, x 9.80665)."""
    imu, _ = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=10.0, seed=4)
    path = tmp_path / "log.csv"
    rows = np.column_stack([imu.t * 1e3, np.degrees(imu.gyro), imu.accel / 9.80665])
    np.savetxt(path, rows, delimiter=";", fmt="%.17g", header="ms;gx;gy;gz;ax;ay;az", comments="")
    out = tmp_path / "q.csv"
    options = ["--csv-time-column", "ms", "--csv-gyro-columns", "gx,gy,gz", "--csv-accel-columns", "4,5,6"]
    units = ["--csv-time-unit", "ms", "--gyro-unit", "deg/s", "--accel-unit", "g"]
    cli("filter", path, *options, *units, "--out", out)
    read = ik.io.read_imu_csv(
        path,
        time_column="ms",
        gyro_columns=["gx", "gy", "gz"],
        accel_columns=[4, 5, 6],
        time_unit="ms",
        gyro_unit="deg/s",
        accel_unit="g",
    )
    assert np.abs(read.gyro - imu.gyro).max() < 1e-12 and np.abs(read.accel - imu.accel).max() < 1e-12
    written = np.loadtxt(out, delimiter=",")
    # one rounding: the CLI rebuilds its Rotation from the quaternions (a renormalisation)
    assert np.abs(written[:, 1:5] - ik.filters.Robust().run(read).rotation.as_quat()).max() < 1e-15
    missing = cli("filter", path, "--csv-time-column", "ms", code=1)
    assert_one_line_error(missing, "imukit: error: --csv-gyro-columns: needed with --csv-time-column")
    wrong = cli("filter", path, *options[:2], "--csv-gyro-columns", "gx,gy,nope", *options[4:], code=1)
    assert_one_line_error(wrong, "imukit: error: ", "nope")
    semicolon = cli("filter", path, *options, *units, "--csv-delimiter", "semicolon").stdout
    assert semicolon.startswith("Robust 6D: 1001 samples")
    comma = cli("filter", path, *options, *units, "--csv-delimiter", "comma", code=1)  # the line is one field
    assert_one_line_error(comma, "imukit: error: --csv-time-column: no column named 'ms' in the header")


@pytest.mark.skipif(not XIO.is_file(), reason=f"{XIO} absent (../shared/data)")
def test_filter_on_the_xio_example(tmp_path: Path) -> None:
    gyro = ["Gyroscope X (deg/s)", "Gyroscope Y (deg/s)", "Gyroscope Z (deg/s)"]
    accel = ["Accelerometer X (g)", "Accelerometer Y (g)", "Accelerometer Z (g)"]
    out = tmp_path / "q.csv"
    options = ["--csv-time-column", "Time (s)", "--csv-gyro-columns", ",".join(gyro)]
    options += ["--csv-accel-columns", ",".join(accel), "--gyro-unit", "deg/s", "--accel-unit", "g"]
    run = cli("filter", XIO, *options, "--out", out)
    read = ik.io.read_imu_csv(
        XIO, time_column="Time (s)", gyro_columns=gyro, accel_columns=accel, gyro_unit="deg/s", accel_unit="g"
    )
    assert re.search(rf"Robust 6D: {len(read)} samples over", run.stdout)
    written = np.loadtxt(out, delimiter=",")
    # one rounding: the CLI rebuilds its Rotation from the quaternions (a renormalisation)
    assert np.abs(written[:, 1:5] - ik.filters.Robust().run(read).rotation.as_quat()).max() < 1e-15


@requires_euroc
def test_a_static_euroc_start_with_gyro_bias_is_not_flagged() -> None:
    """EuRoC V1_02 rests on the ground for its first seconds with a 0.078 rad/s z gyro bias, which a
    mean-rate test took for motion; its spreads (gyro std 0.036 rad/s, RMS of |a| - g 0.16 m/s^2
    from rotor vibration) are under the thresholds."""
    run = cli("integrate", IMU_CSV)
    assert "starting at rest, levelled from the first 2.0 s" in run.stderr
    assert "do not look static" not in run.stderr


@pytest.mark.parametrize(
    ("trajectory", "sign"),
    [
        (ik.sim.VioEllipse(), "RMS of |accel| - 9.81 6.665 m/s^2 > 0.5"),  # 6.7 m/s^2 of vertical bobbing
        (ik.sim.FigureEight(angular_rate=1.0), "gyro std 0.815 rad/s > 0.1"),  # the heading rate swings
        (ik.sim.Circle(), "mean rate 0.500 rad/s > 0.3"),  # a steady 0.5 rad/s turn: no spread at all
    ],
)
def test_a_moving_start_is_flagged(trajectory: object, sign: str, tmp_path: Path) -> None:
    imu, _ = ik.sim.simulate(trajectory, rate=200.0, duration=4.0)
    path = tmp_path / "imu.csv"
    write_euroc_csv(path, np.round(imu.t * 1e9).astype(np.int64), imu.gyro, imu.accel)
    notes = [line for line in cli("integrate", path).stderr.splitlines() if "do not look static" in line]
    assert len(notes) == 1 and sign in notes[0], notes


def test_preintegrate_window_edges_in_integer_ns(tmp_path: Path, noise_yaml: Path) -> None:
    """Unix-epoch ns stamps at 200 Hz, the last one 50 ns short of 200 s: --window 100 is one whole
    window [0, 100 s] (the float count put a second edge at 200 s, past the last sample, and the
    library refused `boundaries`), the edges exact in the t_*_ns columns."""
    start = 1_403_636_579_000_000_000
    t_ns = np.append(np.arange(0, 200 * 10**9, 5_000_000, dtype=np.int64), 200 * 10**9 - 50) + start
    n = len(t_ns)
    ik.io.write_euroc(tmp_path / "seq", ik.ImuData(t_ns, np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1))))
    out = tmp_path / "w.csv"
    run = cli("preintegrate", tmp_path / "seq", "--window", "100", "--noise", noise_yaml, "--out", out)
    assert run.stdout.startswith("1 windows of 100.0 s")
    with open(out, encoding="utf-8") as f:
        header, row = f.readline(), f.readline().strip().split(",")
    assert header.rstrip().endswith(",t_start_ns,t_end_ns") and len(row) == 24
    assert (int(row[22]), int(row[23])) == (start, start + 100 * 10**9)
    assert float(row[2]) == 100.0  # delta_t
    assert float(row[0]) == start / 1e9 and float(row[1]) == (start + 100 * 10**9) / 1e9


def test_preintegrate_float_stamps_keep_the_last_edge_inside(tmp_path: Path, noise_yaml: Path) -> None:
    """Float-second stamps (GTSAM text): 0.1 s steps to 0.3 s with --window 0.1: 0.1 * 3 rounds to
    0.30000000000000004, past the last sample, so 2 windows, not a refusal."""
    path = tmp_path / "imu.txt"
    lines = ["Time dt accelX accelY accelZ omegaX omegaY omegaZ"]
    lines += [f"{t!r} 0.1 0 0 9.81 0 0 0" for t in (0.0, 0.1, 0.2, 0.3)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    run = cli("preintegrate", path, "--window", "0.1", "--noise", noise_yaml)
    assert run.stdout.startswith("2 windows of 0.1 s")


def test_unknown_and_trajectory_inputs_are_one_short_line(tmp_path: Path) -> None:
    other = tmp_path / "log.csv"
    other.write_text("time,u,v,w,p,q,r\n0,1,2,3,4,5,6\n", encoding="utf-8")  # names that say nothing
    run = cli("filter", other, code=1)
    assert_one_line_error(run, f"imukit: error: path: {other}: not an IMU format imukit knows; tried ")
    assert run.stderr.rstrip().endswith("other layouts: the --csv-* options")
    assert len(run.stderr) - len(str(other)) < 200  # 30 more per format listed
    _, truth = ik.sim.simulate(ik.sim.Static(), rate=10.0, duration=1.0)
    tum = tmp_path / "traj.txt"
    truth.write_tum(tum)
    run = cli("integrate", tum, code=1)
    assert_one_line_error(run, f"imukit: error: path: {tum}: this is a trajectory (TUM: t x y z qx qy qz qw), not IMU")
