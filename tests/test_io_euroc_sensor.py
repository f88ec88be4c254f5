"""imukit.io.read_euroc_sensor: EuRoC's published imu0/sensor.yaml read to the digit from a folder, its
mav0/ or the data.csv beside it; None without one; the ground-truth sensor's yaml and broken T_BS refused;
read_imu's bag options refused for every other source."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

import imukit as ik
from euroc import DATA, requires_euroc
from test_io_kalibr import EUROC_SENSOR_YAML as EUROC_IMU0_SENSOR_YAML  # as EuRoC publishes it

IDENTITY = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]


def euroc_sequence(root: Path, sensor_yaml: str | None = EUROC_IMU0_SENSOR_YAML) -> Path:
    """``root/mav0/imu0/`` with two samples in data.csv and ``sensor_yaml`` (if any); returns imu0/."""
    imu0 = root / "mav0" / "imu0"
    imu0.mkdir(parents=True)
    (imu0 / "data.csv").write_text("1000,0,0,0,0,0,9.81\n5001000,0,0,0,0,0,9.81\n")
    if sensor_yaml is not None:
        (imu0 / "sensor.yaml").write_text(sensor_yaml)
    return imu0


def test_eurocs_published_values_from_every_path(tmp_path: Path) -> None:
    imu0 = euroc_sequence(tmp_path / "V1_02_medium")
    for path in (tmp_path / "V1_02_medium", tmp_path / "V1_02_medium" / "mav0", imu0 / "data.csv"):
        sensor = ik.io.read_euroc_sensor(path)
        assert sensor is not None, path
        # The digits of the file, as Python reads them: nothing rescaled, nothing rounded.
        assert sensor.noise.gyro_density == 1.6968e-04
        assert sensor.noise.gyro_random_walk == 1.9393e-05
        assert sensor.noise.accel_density == 2.0e-3
        assert sensor.noise.accel_random_walk == 3.0e-3
        assert sensor.rate_hz == 200.0
        assert sensor.extra["T_BS"] == {"cols": 4, "rows": 4, "data": IDENTITY}
        assert sensor.extra["sensor_type"] == "imu"


def test_no_sensor_yaml_is_none_and_a_missing_path_is_an_error(tmp_path: Path) -> None:
    imu0 = euroc_sequence(tmp_path / "seq", sensor_yaml=None)
    for path in (tmp_path / "seq", tmp_path / "seq" / "mav0", imu0 / "data.csv"):
        assert ik.io.read_euroc_sensor(path) is None
    # A folder's parent is not searched: the sequences of a dataset folder are not one sensor.
    euroc_sequence(tmp_path / "all" / "MH_01", sensor_yaml=EUROC_IMU0_SENSOR_YAML)
    assert ik.io.read_euroc_sensor(tmp_path / "all") is None
    with pytest.raises(FileNotFoundError, match=r"^path: .*nowhere does not exist$"):
        ik.io.read_euroc_sensor(tmp_path / "nowhere")


def test_imu0_is_found_before_mav0(tmp_path: Path) -> None:
    """A folder with both imu0/ and mav0/imu0/: imu0/ is the one read_euroc reads, so its yaml is used."""
    euroc_sequence(tmp_path, sensor_yaml=EUROC_IMU0_SENSOR_YAML.replace("rate_hz: 200", "rate_hz: 100"))
    (tmp_path / "imu0").mkdir()
    (tmp_path / "imu0" / "sensor.yaml").write_text(EUROC_IMU0_SENSOR_YAML)
    sensor = ik.io.read_euroc_sensor(tmp_path)
    assert sensor is not None and sensor.rate_hz == 200.0


def test_non_identity_t_bs_is_reported_not_applied(tmp_path: Path) -> None:
    """T_BS = a 90° turn about z and a 0.1 m offset: kept in extra as written; the samples are untouched."""
    turned = "[0.0, -1.0, 0.0, 0.1,\n         1.0, 0.0, 0.0, 0.0,\n         0.0, 0.0, 1.0, 0.0,\n         0, 0, 0, 1]"
    text = re.sub(r"data: \[[^\]]*\]", "data: " + turned, EUROC_IMU0_SENSOR_YAML)
    imu0 = euroc_sequence(tmp_path, sensor_yaml=text)
    sensor = ik.io.read_euroc_sensor(tmp_path)
    assert sensor is not None
    assert sensor.extra["T_BS"]["data"] == [0.0, -1.0, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0, *IDENTITY[8:]]
    imu, _ = ik.io.read_euroc(tmp_path)
    assert imu.accel[0].tolist() == [0.0, 0.0, 9.81]  # not rotated into another frame
    assert (imu0 / "sensor.yaml").read_text() == text


@pytest.mark.parametrize(
    ("t_bs", "shown"),
    [
        (
            "T_BS:\n  cols: 4\n  rows: 3\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]",
            "'rows': 3",
        ),
        ("T_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0]", "'data': [1.0, 0.0]"),
        ("T_BS:\n  cols: 4\n  rows: 4\n  data: [" + ", ".join(["1.0"] * 15 + [".nan"]) + "]", "nan"),
        ("T_BS: identity", "'identity'"),
    ],
)
def test_malformed_t_bs_names_file_and_key(tmp_path: Path, t_bs: str, shown: str) -> None:
    text = re.sub(r"T_BS:\n(  .*\n|         .*\n)*", t_bs + "\n", EUROC_IMU0_SENSOR_YAML)
    assert "T_BS" in text and "cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0,\n" not in text
    imu0 = euroc_sequence(tmp_path, sensor_yaml=text)
    message = f"^path: {re.escape(str(imu0 / 'sensor.yaml'))}, key 'T_BS': expected rows: 4, cols: 4 and 16 finite"
    with pytest.raises(ik.io.FileFormatError, match=message) as info:
        ik.io.read_euroc_sensor(tmp_path)
    assert shown in str(info.value)


@requires_euroc
def test_the_ground_truth_sensors_yaml_is_not_an_imu_file(tmp_path: Path) -> None:
    """EuRoC's state_groundtruth_estimate0/sensor.yaml (only T_BS) put where imu0's goes: refused,
    naming the keys an IMU sensor.yaml has."""
    imu0 = euroc_sequence(tmp_path, sensor_yaml=None)
    shutil.copy(DATA / "gt0_sensor.yaml", imu0 / "sensor.yaml")
    message = (
        f"^path: {re.escape(str(imu0 / 'sensor.yaml'))}: missing key accelerometer_noise_density, "
        "accelerometer_random_walk, gyroscope_noise_density, gyroscope_random_walk, update_rate$"
    )
    with pytest.raises(ik.io.FileFormatError, match=message):
        ik.io.read_euroc_sensor(imu0 / "data.csv")


def test_bag_options_are_refused_for_other_sources(tmp_path: Path) -> None:
    imu0 = euroc_sequence(tmp_path)
    for source in (tmp_path, imu0 / "data.csv"):
        for option, value in (("imu_topic", "/imu0"), ("groundtruth_topic", "/gt"), ("time_source", "record")):
            with pytest.raises(ik.ParameterError, match=f"^{option}: '{value}' is for ROS bags, but .* is not one"):
                ik.io.read_imu(source, **{option: value})  # type: ignore[arg-type]
    imu, truth = ik.io.read_imu(tmp_path)  # without them it reads
    assert imu.t_ns is not None and imu.t_ns.tolist() == [1000, 5001000] and truth is None
    with pytest.raises(FileNotFoundError, match=r"^path: .*nowhere does not exist$"):
        ik.io.read_imu(tmp_path / "nowhere", imu_topic="/imu0")
