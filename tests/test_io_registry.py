"""The format registry: a reader written in a test plugs into read_imu / read_trajectory, their error
text and the CLI's help and errors, with no edit to imukit; unregistering restores the built-in
behaviour. Also the read step of a pipeline (read_imu with csv=, find_gaps) and the CLI's option
names from structured errors."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit.cli import build_parser, main
from imukit.cli._common import error_line
from imukit.io import Format, Head, ReadReport
from imukit.io._report import BadLines
from test_io_detect import TRIED_IMU, TRIED_TRAJECTORY

TOY_HEADER = "TOY-IMU v1"
BUILT_IN = (
    "tumvi-folder",
    "euroc-folder",
    "euroc-imu-csv",
    "gtsam-text",
    "rosbag",
    "named-csv",
    "tum",
    "euroc-groundtruth-folder",
    "euroc-groundtruth",
    "named-trajectory-csv",
    "tumvi-mocap-folder",
    "tumvi-mocap",
)


def toy_sniff(path: Path, head: Head) -> bool:
    lines = head.lines or []
    return bool(lines) and lines[0][1] == TOY_HEADER


def toy_read(path: str | os.PathLike[str], bad: BadLines) -> tuple[ik.ImuData, ik.Trajectory | None]:
    """``t gx gy gz ax ay az x y z`` lines: IMU samples, and positions at rest as the ground truth; a line
    of another width is a bad line (raised or skipped as ``bad`` says)."""
    rows = []
    for number, line in enumerate(Path(path).read_text().splitlines()[1:], start=2):
        fields = line.split()
        if len(fields) != 10:
            bad.bad(path, number, "wrong column count", f"expected 10 fields, got {len(fields)}", line)
            continue
        rows.append([float(f) for f in fields])
    data = np.array(rows)
    imu = ik.ImuData(data[:, 0], data[:, 1:4], data[:, 4:7])
    truth = ik.Trajectory(data[:, 0], data[:, 7:10], None, Rotation.identity(len(data)))
    return imu, truth


TOY = Format("toy", "both", toy_sniff, toy_read, "toy IMU text")


@pytest.fixture
def toy_file(tmp_path: Path) -> Path:
    path = tmp_path / "run.toy"
    lines = [f"{0.01 * k!r} 0.1 0.2 0.3 0.0 0.0 9.81 {k!r} 0.0 0.0" for k in range(50)]
    path.write_text("\n".join([TOY_HEADER, *lines[:20], "1 2 3", *lines[20:]]) + "\n")
    return path


def test_built_in_formats_in_detection_order() -> None:
    assert tuple(f.name for f in ik.io.formats()) == BUILT_IN
    assert [f.name for f in ik.io.formats("imu")] == list(BUILT_IN[:6])
    assert [f.name for f in ik.io.formats("trajectory")] == list(BUILT_IN[6:])
    assert "tried " + ik.io.listing("imu") == TRIED_IMU
    assert "tried " + ik.io.listing("trajectory") == TRIED_TRAJECTORY


def test_a_registered_reader_is_detected_listed_and_removed_again(toy_file: Path) -> None:
    with pytest.raises(ik.FileFormatError, match=re.escape(TRIED_IMU)):
        ik.io.read_imu(toy_file)
    with ik.io.register_format(TOY) as registered:
        assert registered is TOY and ik.io.formats()[-1] is TOY
        report = ReadReport()
        imu, truth = ik.io.read_imu(toy_file, on_bad_line="skip", report=report)
        assert len(imu) == 50 and truth is not None and len(truth) == 50
        np.testing.assert_array_equal(imu.gyro[7], [0.1, 0.2, 0.3])
        assert [(s.line, s.reason) for s in report.skipped] == [(22, "wrong column count: expected 10 fields, got 3")]
        with pytest.raises(ik.FileFormatError, match=rf"^path: {re.escape(str(toy_file))}, line 22: expected 10"):
            ik.io.read_imu(toy_file)
        # kind "both": read_trajectory takes the reader's ground truth
        trajectory = ik.io.read_trajectory(toy_file, on_bad_line="skip", report=ReadReport())
        np.testing.assert_array_equal(trajectory.position, truth.position)
        unknown = toy_file.with_suffix(".txt")
        unknown.write_text("something else\n")
        with pytest.raises(
            ik.FileFormatError,
            match=re.escape("ROS bag, CSV with named IMU columns, toy IMU text; other layouts: read_imu_csv"),
        ):
            ik.io.read_imu(unknown)
        with pytest.raises(ik.FileFormatError, match=re.escape("TUM-VI mocap, toy IMU text (or their folders)")):
            ik.io.read_trajectory(unknown)
    assert tuple(f.name for f in ik.io.formats()) == BUILT_IN
    with pytest.raises(ik.FileFormatError, match=re.escape(TRIED_IMU)):
        ik.io.read_imu(toy_file)


def test_a_format_placed_before_a_built_in_one_takes_its_files(tmp_path: Path) -> None:
    path = tmp_path / "gt.txt"
    ik.io.write_tum(ik.sim.simulate(ik.sim.Static(), rate=10.0, duration=1.0)[1], path)
    claims = Format("claims-all", "trajectory", lambda path, head: True, lambda path, bad: "claimed", "anything")
    ik.io.register_format(claims, before="tum")
    try:
        assert ik.io.formats("trajectory")[0] is claims
        assert ik.io.read_trajectory(path) == "claimed"
    finally:
        assert ik.io.unregister_format("claims-all") is claims
    assert isinstance(ik.io.read_trajectory(path), ik.Trajectory)


def test_registering_twice_or_before_an_unknown_format_is_refused() -> None:
    with ik.io.register_format(TOY):
        with pytest.raises(ik.ParameterError, match=r"^fmt: a format named 'toy' is registered already$") as raised:
            ik.io.register_format(TOY)
        assert raised.value.argument == "fmt"
    with pytest.raises(ik.ParameterError, match=r"^before: no format named 'nope'; registered: tumvi-folder, "):
        ik.io.register_format(TOY, before="nope")
    with pytest.raises(ik.ParameterError, match=r"^name: no format named 'toy' is registered$"):
        ik.io.unregister_format("toy")
    assert tuple(f.name for f in ik.io.formats()) == BUILT_IN


def test_the_cli_lists_and_reads_a_registered_format(
    toy_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def help_of(*argv: str) -> str:
        with pytest.raises(SystemExit):
            build_parser().parse_args([*argv, "--help"])
        return " ".join(capsys.readouterr().out.split())

    assert "toy IMU text" not in help_of() + help_of("integrate")
    with ik.io.register_format(TOY):
        assert (
            "GTSAM / KITTI text, ROS bag, CSV with named IMU columns, toy IMU text; other layouts: the --csv-* options"
            in help_of()
        )
        assert "ROS bag, CSV with named IMU columns, toy IMU text; other layouts: the --csv-* options" in help_of(
            "integrate"
        )
        out = tmp_path / "traj.txt"
        assert main(["--skip-bad-lines", "integrate", str(toy_file), "--out", str(out)]) == 0
        assert len(ik.io.read_tum(out)) == 50
        unknown = tmp_path / "other.csv"
        unknown.write_text("a,b\n1,2\n")
        assert main(["integrate", str(unknown)]) == 1
        error = capsys.readouterr().err.strip().splitlines()[-1]
        assert error == (
            f"imukit: error: path: {unknown}: not an IMU format imukit knows; tried EuRoC / TUM-VI folder or "
            "imu0/data.csv, GTSAM / KITTI text, ROS bag, CSV with named IMU columns, toy IMU text; other layouts: "
            "the --csv-* options"
        )
    assert "toy IMU text" not in help_of("integrate")


def test_cli_errors_name_options_from_the_argument_field() -> None:
    # The option comes from exc.argument, never from the text: a message that happens to start with
    # another argument's name is left alone.
    assert (
        error_line(ik.ParameterError("expected a whole number", argument="delta")) == "--delta: expected a whole number"
    )
    assert error_line(ik.ParameterError("max_dt: looks like a name")) == "max_dt: looks like a name"
    assert error_line(ik.ParameterError("a\n  folded   message", argument="not_an_option")) == (
        "not_an_option: a folded message"
    )
    assert error_line(ik.TimestampError("not a ParameterError", argument="offset")) == "offset: not a ParameterError"


def test_read_imu_reads_a_csv_by_its_columns_when_given_them(tmp_path: Path) -> None:
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=100.0, duration=1.0)
    euroc = tmp_path / "seq"
    ik.io.write_euroc(euroc, imu)
    detected, truth = ik.io.read_imu(euroc)
    assert truth is None and len(detected) == len(imu)
    columns = {"time_column": 0, "gyro_columns": [1, 2, 3], "accel_columns": [4, 5, 6], "time_unit": "ns"}
    by_columns, none = ik.io.read_imu(euroc / "imu0" / "data.csv", csv=columns)
    assert none is None and np.array_equal(by_columns.t_ns, detected.t_ns)
    with pytest.raises(ik.ParameterError, match=r"^imu_topic: '/imu0' is for ROS bags, not for a CSV") as raised:
        ik.io.read_imu(euroc / "imu0" / "data.csv", csv=columns, imu_topic="/imu0")
    assert raised.value.argument == "imu_topic"


def test_find_gaps_names_the_steps_longer_than_the_limit() -> None:
    t = np.r_[np.arange(100) * 0.01, 1.5 + np.arange(100) * 0.01, 3.2 + np.arange(10) * 0.01]
    imu = ik.ImuData(t, np.zeros((len(t), 3)), np.zeros((len(t), 3)))
    gaps = ik.io.find_gaps(imu)
    assert [(g.sample, g.t) for g in gaps] == [(100, 1.5), (200, 3.2)]
    assert gaps[0].step == pytest.approx(0.51) and gaps[0].median == pytest.approx(0.01)
    assert [g.sample for g in ik.io.find_gaps(imu, longer_than=0.6)] == [200]
    assert ik.io.find_gaps(imu, factor=100.0) == []
    assert ik.io.find_gaps(imu[:1]) == []
