"""TUM trajectory files: exact text, bit-exact round trips, reading other writers' files, bad lines."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

from conftest import assert_file_error


def two_samples(**kwargs: object) -> ik.Trajectory:
    position = [[1.0, -2.5, 0.1], [1e-05, 0.0, 3.0]]
    rotation = Rotation.from_quat([[0.0, 0.0, 0.0, 1.0], [0.5, -0.5, 0.5, 0.5]])
    return ik.Trajectory(kwargs.pop("t", None), position, None, rotation, **kwargs)  # type: ignore[arg-type]


def test_file_content_with_nanoseconds(tmp_path: Path) -> None:
    path = tmp_path / "traj.txt"
    ik.io.write_tum(two_samples(t_ns=[1403636579758555392, 1403636579763555584]), path)
    assert path.read_text() == (
        "1403636579.758555392 1.0 -2.5 0.1 0.0 0.0 0.0 1.0\n1403636579.763555584 1e-05 0.0 3.0 0.5 -0.5 0.5 0.5\n"
    )


def test_file_content_with_float_seconds(tmp_path: Path) -> None:
    path = tmp_path / "traj.txt"
    two_samples(t=np.array([0.0, 0.005])).write_tum(path)
    assert path.read_text() == "0.0 1.0 -2.5 0.1 0.0 0.0 0.0 1.0\n0.005 1e-05 0.0 3.0 0.5 -0.5 0.5 0.5\n"


def test_negative_and_small_nanosecond_stamps(tmp_path: Path) -> None:
    path = tmp_path / "traj.txt"
    ik.io.write_tum(two_samples(t_ns=[-1_500_000_000, 7]), path)
    assert [line.split()[0] for line in path.read_text().splitlines()] == ["-1.500000000", "0.000000007"]
    back = ik.io.read_tum(path)
    assert back.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, [-1_500_000_000, 7])
    np.testing.assert_array_equal(back.t, [-1.5, 7e-9])


def random_trajectory(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, Rotation]:
    t = 1.4e9 + np.cumsum(rng.uniform(1e-3, 1e-2, n))
    position = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-8, 6, size=(n, 3))
    return t, position, Rotation.random(n, rng=rng)


def test_round_trip_is_bit_exact_with_float_seconds(tmp_path: Path, rng: np.random.Generator) -> None:
    t, position, rotation = random_trajectory(rng, 500)
    velocity = rng.normal(size=(500, 3))
    path = tmp_path / "traj.txt"
    ik.Trajectory(t, position, velocity, rotation).write_tum(path)
    back = ik.io.read_tum(path)
    assert back.velocity is None and back.t_ns is None
    np.testing.assert_array_equal(back.t, t)
    np.testing.assert_array_equal(back.position, position)
    np.testing.assert_array_equal(back.rotation.as_quat(), rotation.as_quat())


def test_round_trip_is_bit_exact_with_nanoseconds(tmp_path: Path, rng: np.random.Generator) -> None:
    t_ns = 1_403_636_579_758_555_392 + np.cumsum(rng.integers(4_999_000, 5_001_000, 300))
    _, position, rotation = random_trajectory(rng, 300)
    written = ik.Trajectory(None, position, None, rotation, t_ns=t_ns)
    path = tmp_path / "traj.txt"
    written.write_tum(path)
    back = ik.io.read_tum(path)
    assert back.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, t_ns)
    np.testing.assert_array_equal(back.t, written.t)
    np.testing.assert_array_equal(back.position, position)
    np.testing.assert_array_equal(back.rotation.as_quat(), rotation.as_quat())


def test_reads_comments_blank_lines_and_short_quaternions(tmp_path: Path) -> None:
    # TUM RGB-D ground truth style: a header, 6-digit stamps, 4-digit quaternions (norm ≠ 1).
    path = tmp_path / "groundtruth.txt"
    path.write_text(
        "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n\n"
        "1305031102.175304 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248\n"
        "1305031102.185304\t1.3404 0.6263 1.6575 0.6572 0.6127 -0.2950 -0.3250\n"
    )
    traj = ik.io.read_tum(path)
    assert len(traj) == 2 and traj.t_ns is None and traj.velocity is None
    np.testing.assert_array_equal(traj.t, [1305031102.175304, 1305031102.185304])
    np.testing.assert_array_equal(traj.position[1], [1.3404, 0.6263, 1.6575])
    q = np.array([0.6574, 0.6126, -0.2949, -0.3248])
    np.testing.assert_allclose(traj.rotation[0].as_quat(), q / np.linalg.norm(q), rtol=0, atol=1e-15)
    assert np.abs(np.linalg.norm(traj.rotation.as_quat(), axis=1) - 1.0).max() < 1e-15


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n", r"line 2: expected 8 fields 'timestamp tx ty tz qx qy qz qw', got 7"),
        ("# h\n0.0 0 0 0 0 0 0 1 9\n", r"line 2: expected 8 fields .*got 9"),
        ("0.0 0 0 0 0 0 0 1\n0.1 0 x 0 0 0 0 1\n", r"line 2: not a number in '0\.1 0 x 0 0 0 0 1'"),
        ("0.0 0 0 nan 0 0 0 1\n", r"line 1: non-finite value"),
        (
            "0.0 0 0 0 0 0 0 1\n\n0.0 0 0 0 0 0 0 1\n",
            r"line 3: time must increase strictly, but 0\.0 follows 0\.0 \(line 1\)",
        ),
        ("1.000000002 0 0 0 0 0 0 1\n1.000000001 0 0 0 0 0 0 1\n", r"line 2: time must increase strictly"),
        ("0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 0\n", r"line 2: zero quaternion"),
        ("# only a comment\n\n", r": no data lines"),
    ],
)
def test_malformed_files_name_file_and_line(tmp_path: Path, text: str, message: str) -> None:
    assert_file_error(tmp_path / "bad.txt", text, ik.io.read_tum, f"(, )?{message}")


def test_write_refuses_other_objects(tmp_path: Path) -> None:
    with pytest.raises(TypeError, match=r"^trajectory: expected an imukit Trajectory"):
        ik.io.write_tum(np.zeros((2, 8)), tmp_path / "x.txt")  # type: ignore[arg-type]


def test_quaternions_of_extreme_magnitude_are_normalised(tmp_path: Path) -> None:
    # Squaring 1e308 overflows and 1e-160 or 5e-324 underflow: these rows are rescaled before the norm.
    path = tmp_path / "traj.txt"
    path.write_text(
        "0.0 0 0 0 1e308 1e308 0 0\n0.1 0 0 0 1e-160 -1e-160 0 0\n0.2 0 0 0 0 0 5e-324 0\n0.3 0 0 0 0 0 0 -3\n"
    )
    with np.errstate(all="raise"):
        quat = ik.io.read_tum(path).rotation.as_quat(canonical=False)
    half = np.sqrt(0.5)
    np.testing.assert_allclose(quat[:2], [[half, half, 0, 0], [half, -half, 0, 0]], rtol=0, atol=1.2e-16)
    np.testing.assert_array_equal(quat[2:], [[0, 0, 1, 0], [0, 0, 0, -1]])


def test_byte_order_mark_before_a_comment_line(tmp_path: Path) -> None:
    path = tmp_path / "traj.txt"
    path.write_bytes(b"\xef\xbb\xbf# timestamp tx ty tz qx qy qz qw\n1.000000000 1 2 3 0 0 0 1\n")
    traj = ik.io.read_tum(path)  # "raise" mode: the comment must not read as a bad line
    assert traj.t_ns is not None and traj.t_ns.tolist() == [1_000_000_000]
    assert traj.position.tolist() == [[1.0, 2.0, 3.0]]
