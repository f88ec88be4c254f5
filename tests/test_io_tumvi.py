"""TUM-VI exported folders: EuRoC's IMU file plus mocap0/data.csv poses (w-first quaternions), written
here by hand in TUM-VI's layout; bad mocap lines raised or reported."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import imukit as ik
from imukit.io import ReadReport, SkippedLine

from conftest import assert_file_error

MOCAP_HEADER = "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []"
IMU = (
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
    "1520530308199447626,-0.0418879,0.0663225,0.0052360,9.4591,0.0719,-2.8195\n"
    "1520530308204447626,-0.0401426,0.0645772,0.0034907,9.4735,0.0479,-2.8147\n"
)
# Quaternion w, x, y, z = 0.5, 0.5, -0.5, 0.5 (unit): scipy's xyzw is 0.5, -0.5, 0.5, 0.5.
MOCAP = [
    MOCAP_HEADER,
    "1520530308201447626,0.9264,-0.2447,1.3781,0.5,0.5,-0.5,0.5",
    "1520530308211447626,0.9265,-0.2446,1.3782,0.7071,0.0,0.0,0.7071",
]


def dataset(root: Path, mocap: list[str] | None = MOCAP) -> Path:
    (root / "mav0" / "imu0").mkdir(parents=True)
    (root / "mav0" / "imu0" / "data.csv").write_text(IMU)
    if mocap is not None:
        (root / "mav0" / "mocap0").mkdir()
        (root / "mav0" / "mocap0" / "data.csv").write_text("\n".join(mocap) + "\n")
    return root


def test_imu_and_mocap(tmp_path: Path) -> None:
    imu, truth = ik.io.read_tumvi(dataset(tmp_path / "dataset-room1_512_16"))
    assert imu.t_ns is not None and imu.t_ns.tolist() == [1520530308199447626, 1520530308204447626]
    np.testing.assert_array_equal(imu.gyro[1], [-0.0401426, 0.0645772, 0.0034907])
    np.testing.assert_array_equal(imu.accel[0], [9.4591, 0.0719, -2.8195])
    assert truth is not None and truth.t_ns is not None and truth.velocity is None and truth.gyro_bias is None
    assert truth.t_ns.tolist() == [1520530308201447626, 1520530308211447626]
    np.testing.assert_array_equal(truth.position, [[0.9264, -0.2447, 1.3781], [0.9265, -0.2446, 1.3782]])
    np.testing.assert_array_equal(truth.rotation[0].as_quat(), [0.5, -0.5, 0.5, 0.5])  # unit: kept exactly
    q = np.array([0.0, 0.0, 0.7071, 0.7071])  # 4 digits: normalised
    np.testing.assert_allclose(truth.rotation[1].as_quat(), q / np.linalg.norm(q), rtol=0, atol=1e-16)
    # The mav0 folder itself works too.
    _, again = ik.io.read_tumvi(tmp_path / "dataset-room1_512_16" / "mav0")
    assert again is not None and np.array_equal(again.position, truth.position)


def test_without_mocap_the_truth_is_none(tmp_path: Path) -> None:
    imu, truth = ik.io.read_tumvi(dataset(tmp_path, mocap=None))
    assert truth is None and len(imu) == 2
    with pytest.raises(FileNotFoundError, match=r"^folder: no imu0/data\.csv in .*nowhere \(nor in its mav0/\)"):
        ik.io.read_tumvi(tmp_path / "nowhere")


def test_skip_mode_reports_bad_mocap_lines(tmp_path: Path) -> None:
    mocap = [
        *MOCAP[:2],
        "1520530308206447626,0.9,-0.2,1.3,0,0,0,0",
        "1520530308201447626,0.9,-0.2,1.3,1,0,0,0",
        "1520530308208447626,0.9,-0.2,1.3,1,0,0",
        MOCAP[2],
    ]
    root = dataset(tmp_path, mocap)
    report = ReadReport()
    _, truth = ik.io.read_tumvi(root, on_bad_line="skip", report=report)
    assert truth is not None and truth.t_ns is not None
    assert truth.t_ns.tolist() == [1520530308201447626, 1520530308211447626]
    p = str(root / "mav0" / "mocap0" / "data.csv")
    assert report.skipped == [
        SkippedLine(p, 3, "zero quaternion: zero quaternion", mocap[2]),
        SkippedLine(
            p, 4, "duplicate stamp: time must increase strictly, but 1520530308201447626 follows 1520530308201447626 "
            "(line 2)", mocap[3],
        ),
        SkippedLine(p, 5, "wrong column count: expected 8 comma-separated fields (TUM-VI mocap0/data.csv), got 7",
                    mocap[4]),
    ]  # fmt: skip


@pytest.mark.parametrize(
    ("lines", "message"),
    [
        ([MOCAP[1], "1520530308211447626,0.9,-0.2,1.3,1,0"], r", line 3: expected 8 comma-separated fields \(TUM-VI"),
        ([], r": no data lines$"),
        ([MOCAP[1], "1520530308211447626,0.9,-0.2,1.3,1,0,0,0,5"], r", line 3: expected 8 .*got 9$"),
        (["1520530308.2,0.9,-0.2,1.3,1,0,0,0"], r", line 2: timestamp '1520530308\.2' is not an integer number of ns"),
        ([MOCAP[1], "1520530308211447626,0.9,y,1.3,1,0,0,0"], r", line 3: not a number in "),
        (["1520530308211447626,0.9,inf,1.3,1,0,0,0"], r", line 2: non-finite value in "),
        ([MOCAP[2], MOCAP[1]], r", line 3: time must increase strictly, but 1520530308201447626 follows 152053030821"),
        (["1520530308211447626,0.9,0.2,1.3,0,0,0,0"], r", line 2: zero quaternion$"),
    ],
)
def test_malformed_mocap_names_file_and_line(tmp_path: Path, lines: list[str], message: str) -> None:
    root = dataset(tmp_path, [MOCAP_HEADER, *lines])
    path = root / "mav0" / "mocap0" / "data.csv"
    message = message.replace("number of ns", "number of nanoseconds")
    assert_file_error(path, path.read_text(), lambda p: ik.io.read_tumvi(root), message)
