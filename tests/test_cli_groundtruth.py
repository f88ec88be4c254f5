"""`--groundtruth FILE` on any input and the `--gt-*` columns (issue 16, item 2): a bare IMU CSV
scored against a transform CSV found by its names, or a pose file of another layout read by columns;
`evaluate`'s GT read the same way; the options' mistakes named as the options."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from test_cli import assert_one_line_error, cli, rmse_in_row

TF_HEADER = "Time," + ",".join(f"transform.translation.{a}" for a in "xyz") + ","
TF_HEADER += ",".join(f"transform.rotation.{a}" for a in "xyzw")
GT_COLUMNS = ["--gt-time-column", "0", "--gt-position-columns", "1,2,3", "--gt-quaternion-columns", "4,5,6,7"]
GT_WXYZ = [*GT_COLUMNS, "--gt-quaternion-order", "wxyz", "--gt-time-unit", "ns"]


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A 200 Hz IMU as a bare EuRoC imu0 CSV (no truth), its truth at 20 Hz as a transform CSV (float
    seconds, xyzw) and as a `;` file `stamp;x;y;z;qw;qx;qy;qz` (ns, wxyz), and the 200 Hz truth as TUM."""
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=10.0, seed=7)
    root = tmp_path_factory.mktemp("gt")
    t_ns = np.round(truth.t * 1e9).astype(np.int64)
    ik.io.write_euroc(root / "seq", ik.ImuData(t_ns, imu.gyro, imu.accel))
    sub = slice(None, None, 10)
    q = truth.rotation[sub].as_quat()
    rows = [
        ",".join([repr(float(t)), *map(repr, p.tolist()), *map(repr, r.tolist())])
        for t, p, r in zip(truth.t[sub], truth.position[sub], q)
    ]
    (root / "vicon.csv").write_text(TF_HEADER + "\n" + "\n".join(rows) + "\n")
    rows = [
        ";".join([str(int(t)), *map(repr, p.tolist()), *map(repr, r[[3, 0, 1, 2]].tolist())])
        for t, p, r in zip(t_ns[sub], truth.position[sub], q)
    ]
    (root / "poses.txt").write_text("stamp;x;y;z;qw;qx;qy;qz\n" + "\n".join(rows) + "\n")
    ik.Trajectory(None, truth.position, None, truth.rotation, t_ns=t_ns).write_tum(root / "est.txt")
    return {
        "imu": next((root / "seq").rglob("data.csv")),
        "vicon": root / "vicon.csv",
        "poses": root / "poses.txt",
        "est": root / "est.txt",
    }


def _scored(stdout: str) -> tuple[int, int]:
    match = re.search(r"scored (\d+) of (\d+) ", stdout)
    assert match is not None, stdout
    return int(match[1]), int(match[2])


def test_integrate_a_bare_imu_file_against_a_transform_csv(files: dict[str, Path]) -> None:
    run = cli("integrate", files["imu"], "--groundtruth", files["vicon"])
    assert _scored(run.stdout) == (2001, 2001)
    ate = float(re.search(r"ATE RMSE (\S+) m", run.stdout)[1])  # type: ignore[index]
    assert ate < 0.05  # the truth's start and the exact IMU: drift from the 20 Hz velocity only


def test_filter_against_a_pose_file_read_by_its_columns(files: dict[str, Path]) -> None:
    run = cli("filter", files["imu"], "--groundtruth", files["poses"], *GT_WXYZ)
    assert _scored(run.stdout) == (2001, 2001)
    total = float(re.search(r"total (\S+) deg", run.stdout)[1])  # type: ignore[index]
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=200.0, duration=10.0, seed=7)
    library = ik.eval.attitude_error(
        ik.filters.Robust().run(imu).rotation, truth.rotation.as_quat(), align_heading=True
    )
    # against the 200 Hz truth: 3.698 deg; the 20 Hz file slerped agrees to print precision (w read as x: 130 deg)
    assert total == pytest.approx(library.rmse(degrees=True).total, abs=2e-3)
    same = cli("filter", files["imu"], "--groundtruth", files["vicon"])  # the same truth, found by its names
    assert re.search(r"total (\S+) deg", same.stdout)[1] == f"{total:.3f}"  # type: ignore[index]


def test_evaluate_reads_gt_by_its_columns(files: dict[str, Path]) -> None:
    run = cli("evaluate", files["est"], files["poses"], *GT_WXYZ, "--align", "none")
    assert rmse_in_row(run.stdout, "ATE translation") < 1e-3  # chords of a 20 Hz truth against 200 Hz poses
    assert rmse_in_row(run.stdout, "ATE rotation") < 0.1
    assert _scored(run.stdout) == (2001, 2001)


def test_groundtruth_option_mistakes_name_the_option(files: dict[str, Path]) -> None:
    run = cli("integrate", files["imu"], "--gt-time-column", "0", code=1)
    assert_one_line_error(run, "imukit: error: --gt-position-columns: needed with --gt-time-column")
    run = cli("integrate", files["imu"], *GT_COLUMNS, code=1)
    assert_one_line_error(run, "imukit: error: --gt-time-column: needs --groundtruth FILE")
    run = cli(
        "integrate",
        files["imu"],
        "--groundtruth",
        files["poses"],
        *GT_COLUMNS[:4],
        "--gt-quaternion-columns",
        "4,5,6",
        code=1,
    )
    assert_one_line_error(run, "imukit: error: --gt-quaternion-columns: expected 4 comma-separated columns")
    named = ["--gt-time-column", "stamp", "--gt-position-columns", "px,y,z", "--gt-quaternion-columns", "4,5,6,7"]
    run = cli("integrate", files["imu"], "--groundtruth", files["poses"], *named, code=1)
    assert_one_line_error(run, "imukit: error: --gt-position-columns: no column named 'px' in the header")


def test_a_broad_trial_keeps_its_own_reference(files: dict[str, Path]) -> None:
    broad = Path(ik.__file__).parent / "_data" / "broad_excerpt.npz"
    run = cli("filter", broad, "--groundtruth", files["vicon"], code=1)
    assert_one_line_error(run, "imukit: error: --groundtruth: ", "is a BROAD trial, with a reference of its own")
