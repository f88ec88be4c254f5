"""The CLI on ROS bags, end to end through subprocess: `imukit integrate` and `imukit filter` on a ROS 2
MCAP bag written here with rosbags' writer give the library's result on the same bag; --imu-topic,
--groundtruth-topic and --time-source reach the reader; topic trouble and bag options on other inputs
are one-line errors naming the option."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit._demo import broad_excerpt_path

pytest.importorskip("rosbags", reason="rosbags is the optional [ros] extra")
from test_cli import assert_one_line_error, cli
from test_io_rosbag import EPOCH_S, IMU, ODOM, Bag

RATE = 200.0
STEP_NS = 5_000_000  # 1 / RATE
START_NS = EPOCH_S * 10**9 + 912_140_000
RECEIVED_NS = 1_000_000  # the recorder gets each message 1 ms (plus jitter) after its stamp
JITTER_NS = 7_919


def record_ns(k: int) -> int:
    """Record time of IMU message k: later than its stamp, jittered (never a multiple of the step)."""
    return START_NS + k * STEP_NS + RECEIVED_NS + (k * JITTER_NS) % 100_000


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A ROS 2 MCAP bag folder: a noisy 6 s figure-eight on /imu0, the same samples × 2 on /imu1 (a
    second IMU), and the truth as nav_msgs/Odometry at 100 Hz on /gt/odom from the first IMU stamp."""
    noise = ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4)
    imu, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=RATE, duration=6.0, noise=noise, seed=5)
    writer = Bag("mcap")
    stamps = [divmod(START_NS + k * STEP_NS, 10**9) for k in range(len(imu))]
    quat = truth.rotation.as_quat()
    v_body = truth.rotation.inv().apply(np.array(truth.velocity))  # Odometry: body-frame twist
    topics = {
        "/imu0": (IMU, [(record_ns(k), writer.imu(stamps[k], imu.gyro[k], imu.accel[k])) for k in range(len(imu))]),
        "/imu1": (IMU, [(record_ns(k), writer.imu(stamps[k], 2 * imu.gyro[k], 2 * imu.accel[k])) for k in range(3)]),
        ODOM: (
            ODOM,
            [
                (record_ns(k) + 1, writer.odometry(stamps[k], truth.position[k], quat[k], v_body[k]))
                for k in range(0, len(imu), 2)
            ],
        ),
    }
    topics["/gt/odom"] = topics.pop(ODOM)
    return writer.write(tmp_path_factory.mktemp("bags") / "figure8", topics)


def test_integrate_a_bag_equals_the_library(bag: Path, tmp_path: Path) -> None:
    """The written trajectory is, bit for bit, imukit.integrate from the bag's truth at the first
    IMU stamp (the truth starts there, so no interpolation), and the printed ATE is ape's."""
    out = tmp_path / "traj.txt"
    run = cli("integrate", bag, "--imu-topic", "/imu0", "--scheme", "rk4", "--out", out)
    imu, truth = ik.io.read_rosbag(bag, imu_topic="/imu0")
    assert truth is not None and truth.velocity is not None and imu.t_ns is not None and truth.t_ns is not None
    assert truth.t_ns[0] == imu.t_ns[0] == START_NS and len(imu) == 1201 and len(truth) == 601
    initial = ik.NavState(truth.position[0], truth.velocity[0], truth.rotation[0])
    expected = ik.integrate(imu, initial=initial, scheme="rk4")
    written = ik.io.read_tum(out)
    assert written.t_ns is not None and np.array_equal(written.t_ns, imu.t_ns)
    assert np.array_equal(written.position, expected.position)
    assert np.array_equal(written.rotation.as_quat(), expected.rotation.as_quat())
    ate = ik.eval.ape(expected, truth, align="none")
    assert f"ATE RMSE {ate.translation_stats.rmse:.4g} m" in run.stdout
    assert f"over {ate.translation_stats.n} samples" in run.stdout and ate.translation_stats.n == 1201
    assert "left out" not in run.stdout  # the truth spans every sample, without gaps


def test_filter_a_bare_mcap_file_equals_the_library(bag: Path, tmp_path: Path) -> None:
    out = tmp_path / "q.csv"
    (mcap,) = bag.glob("*.mcap")
    run = cli("filter", mcap, "--imu-topic", "/imu0", "--groundtruth-topic", "/gt/odom", "--out", out)
    imu, _ = ik.io.read_rosbag(mcap, imu_topic="/imu0")
    expected = ik.filters.Robust().run(imu)
    rows = np.loadtxt(out, delimiter=",")
    assert rows.shape == (1201, 8)
    assert np.array_equal(rows[:, 0], imu.t)
    # One native call, quaternions normalised once more by Rotation.from_quat: equal to the last bit or two.
    np.testing.assert_allclose(rows[:, 1:5], expected.rotation.as_quat(), rtol=0, atol=4e-16)
    assert np.array_equal(rows[:, 5:8], expected.gyro_bias)
    assert "attitude error RMSE over 1201 samples" in run.stdout  # the truth was read and used


def test_time_source_record_reaches_the_reader(bag: Path, tmp_path: Path) -> None:
    """--time-source record: the stamps written are the recorder's receive times, not header.stamp."""
    out = tmp_path / "q.txt"
    cli("filter", bag, "--imu-topic", "/imu0", "--time-source", "record", "--out", out)
    written = ik.io.read_tum(out)
    assert written.t_ns is not None
    assert written.t_ns.tolist() == [record_ns(k) for k in range(1201)]


def test_several_imu_topics_is_one_line_listing_them(bag: Path) -> None:
    for command in (["integrate"], ["filter"], ["allan", "--out", "a.png"]):
        run = cli(command[0], bag, *command[1:], code=1)
        assert_one_line_error(
            run,
            "imukit: error: --imu-topic: the bag has 2 candidate topics, pass one: "
            "/imu0 (sensor_msgs/msg/Imu), /imu1 (sensor_msgs/msg/Imu)",
        )
    assert_one_line_error(
        cli("integrate", bag, "--imu-topic", "/imu", code=1),
        "imukit: error: --imu-topic: topic '/imu' is not in the bag; its topics: /gt/odom (nav_msgs/msg/Odometry), ",
    )
    assert_one_line_error(
        cli("integrate", bag, "--imu-topic", "/imu0", "--groundtruth-topic", "/imu1", code=1),
        "imukit: error: --groundtruth-topic: topic '/imu1' has type sensor_msgs/msg/Imu, expected ",
    )


def test_bag_options_on_other_inputs_are_refused(tmp_path: Path) -> None:
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=RATE, duration=1.0)
    ik.io.write_euroc(tmp_path, imu, noise=ik.ImuNoise(1e-3, 1e-2, 1e-5, 1e-4), rate_hz=RATE)
    for command in (["integrate"], ["preintegrate", "--window", "0.5"], ["filter"], ["allan", "--out", "a.png"]):
        run = cli(command[0], tmp_path, *command[1:], "--imu-topic", "/imu0", code=1)
        assert_one_line_error(run, f"imukit: error: --imu-topic: '/imu0' is for ROS bags, but {tmp_path} is not one")
    run = cli("integrate", tmp_path, "--time-source", "record", code=1)
    assert_one_line_error(run, "imukit: error: --time-source: 'record' is for ROS bags")
    broad = broad_excerpt_path()
    run = cli("filter", broad, "--groundtruth-topic", "/gt", code=1)
    expected = f"imukit: error: --groundtruth-topic: '/gt' is for ROS bags, but {broad} is a BROAD trial"
    assert_one_line_error(run, expected)


def test_bag_options_documented_in_help() -> None:
    for command in ("integrate", "preintegrate", "filter", "allan"):
        text = cli(command, "--help").stdout
        assert "--imu-topic TOPIC" in text and "--groundtruth-topic TOPIC" in text, command
        assert "--time-source {header,record}" in text, command


def test_levelled_start_from_a_bag_without_truth(tmp_path: Path) -> None:
    """A bag with one IMU topic and no ground truth needs no option: a static, tilted sensor
    integrates from the levelled start and stays at the origin (noise-free)."""
    tilt = Rotation.from_euler("ZYX", [0.0, 0.05, -0.1])
    imu, _ = ik.sim.simulate(ik.sim.Static(rotation=tilt), rate=RATE, duration=3.0)
    writer = Bag("mcap")
    messages = [
        (START_NS + k * STEP_NS, writer.imu(divmod(START_NS + k * STEP_NS, 10**9), imu.gyro[k], imu.accel[k]))
        for k in range(len(imu))
    ]
    path = writer.write(tmp_path / "static", {"/imu": (IMU, messages)})
    out = tmp_path / "t.txt"
    run = cli("integrate", path, "--static-seconds", "1", "--out", out)
    assert "no ground truth" in run.stderr
    written = ik.io.read_tum(out)
    _, pitch, roll = written.rotation[0].as_euler("ZYX")
    assert (pitch, roll) == pytest.approx((0.05, -0.1), abs=1e-12)
    assert np.abs(written.position).max() < 1e-9
