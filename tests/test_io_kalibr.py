"""Kalibr imu.yaml: exact round trips, files that other YAML readers read as numbers, EuRoC's and Kalibr's
own layouts, and errors that name the file and the key."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

import imukit as ik
from euroc import DATA

from conftest import assert_file_error

EUROC_NOISE = ik.ImuNoise(
    gyro_density=1.6968e-04, accel_density=2.0e-3, gyro_random_walk=1.9393e-05, accel_random_walk=3.0e-3
)
KEYS = ("accelerometer_noise_density", "accelerometer_random_walk", "gyroscope_noise_density", "gyroscope_random_walk")

# EuRoC's imu0/sensor.yaml as the dataset ships it (V1_02_medium's own is not in shared/data).
EUROC_SENSOR_YAML = """\
#Default imu sensor yaml file
sensor_type: imu
comment: VI-Sensor IMU (ADIS16448)

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0,
         0.0, 1.0, 0.0, 0.0,
         0.0, 0.0, 1.0, 0.0,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 200

# inertial sensor noise model parameters (static)
gyroscope_noise_density: 1.6968e-04     # [ rad / s / sqrt(Hz) ]   ( gyro "white noise" )
gyroscope_random_walk: 1.9393e-05       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )
accelerometer_noise_density: 2.0000e-3  # [ m / s^2 / sqrt(Hz) ]   ( accel "white noise" )
accelerometer_random_walk: 3.0000e-3    # [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )
"""


def test_file_content(tmp_path: Path) -> None:
    path = tmp_path / "imu.yaml"
    ik.io.write_kalibr_imu(path, EUROC_NOISE, rate_hz=200.0, rostopic="/imu0")
    assert path.read_text() == (
        "# Kalibr IMU noise model (continuous-time densities), written by imukit\n"
        "accelerometer_noise_density: 0.002  # [m/s^2/sqrt(Hz)] white noise\n"
        "accelerometer_random_walk: 0.003  # [m/s^3/sqrt(Hz)] bias random walk\n"
        "gyroscope_noise_density: 0.00016968  # [rad/s/sqrt(Hz)] white noise\n"
        "gyroscope_random_walk: 1.9393e-05  # [rad/s^2/sqrt(Hz)] bias random walk\n"
        "rostopic: /imu0\n"
        "update_rate: 200.0  # [Hz]\n"
    )


def test_round_trip_is_exact_and_plain_yaml_reads_floats(tmp_path: Path, rng: np.random.Generator) -> None:
    path = tmp_path / "imu.yaml"
    specials = [1e-05, 5e-324, 1e16, 0.0, 0.1 + 0.2, 2.2250738585072014e-308]
    for k in range(50):
        values = specials[k : k + 4] if k < 3 else list(10.0 ** rng.uniform(-12, 3, 4) * rng.uniform(1, 10, 4))
        rate = float(rng.uniform(1.0, 4000.0)) if k % 2 else 200.0
        noise = ik.ImuNoise(*values)
        ik.io.write_kalibr_imu(path, noise, rate_hz=rate)
        read = ik.io.read_kalibr_imu(path)
        assert read.noise == noise and read.rate_hz == rate and read.extra == {}
        # Kalibr, OpenVINS and friends load the file with a YAML 1.1 parser and no conversion:
        # every value must be a float to it ("1e-05" would be a string).
        plain = yaml.safe_load(path.read_text())
        assert all(type(plain[key]) is float for key in (*KEYS, "update_rate")), plain


def test_extra_keys_round_trip(tmp_path: Path) -> None:
    extra = {"T_i_b": np.eye(4).tolist(), "time_offset": 1e-05, "model": "calibrated", "note": "ü: #1"}
    path = tmp_path / "imu.yaml"
    ik.io.write_kalibr_imu(path, EUROC_NOISE, rate_hz=400.0, rostopic="/dev/imu: 0", extra=extra)
    read = ik.io.read_kalibr_imu(path)
    assert read.extra == {"rostopic": "/dev/imu: 0", **extra}
    assert read.noise == EUROC_NOISE and read.rate_hz == 400.0


def test_reads_eurocs_sensor_yaml(tmp_path: Path) -> None:
    path = tmp_path / "sensor.yaml"
    path.write_text(EUROC_SENSOR_YAML)
    read = ik.io.read_kalibr_imu(path)
    assert read.noise == EUROC_NOISE  # 2.0000e-3 is 0.002, 1.6968e-04 is 0.00016968, exactly
    assert read.rate_hz == 200.0 and isinstance(read.rate_hz, float)
    assert read.extra["sensor_type"] == "imu" and read.extra["comment"] == "VI-Sensor IMU (ADIS16448)"
    assert read.extra["T_BS"]["data"] == np.eye(4).ravel().tolist()
    # What was read can be written again as a Kalibr file: the same noise, rate and other keys.
    ik.io.write_kalibr_imu(tmp_path / "imu.yaml", read.noise, rate_hz=read.rate_hz, extra=read.extra)
    assert ik.io.read_kalibr_imu(tmp_path / "imu.yaml") == read


def test_reads_kalibr_numbers_that_yaml_leaves_as_text_and_sections(tmp_path: Path) -> None:
    path = tmp_path / "imu.yaml"
    body = "accelerometer_noise_density: 1e-3\naccelerometer_random_walk: 2E-4\n"
    body += "gyroscope_noise_density: 7e-5\ngyroscope_random_walk: 0\nrostopic: /imu0\nupdate_rate: 100\n"
    path.write_text(body)
    assert yaml.safe_load(body)["accelerometer_noise_density"] == "1e-3"  # YAML 1.1: a string
    read = ik.io.read_kalibr_imu(path)
    assert read.noise == ik.ImuNoise(
        gyro_density=7e-5, accel_density=1e-3, gyro_random_walk=0.0, accel_random_walk=2e-4
    )
    assert read.rate_hz == 100.0 and read.extra == {"rostopic": "/imu0"}
    # kalibr_calibrate_imu_camera writes the model under "imu0:".
    path.write_text("imu0:\n" + "".join(f"  {line}\n" for line in body.splitlines()) + "other: 1\n")
    with pytest.raises(ik.io.FileFormatError, match=r"\(found under 'imu0': pass section='imu0'\)$"):
        ik.io.read_kalibr_imu(path)
    assert ik.io.read_kalibr_imu(path, section="imu0") == read
    with pytest.raises(ik.io.FileFormatError, match=r": no section 'imu1' at the top level$"):
        ik.io.read_kalibr_imu(path, section="imu1")


def test_opencv_directive_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "sensor.yaml"
    path.write_text("%YAML:1.0\n" + EUROC_SENSOR_YAML)
    assert ik.io.read_kalibr_imu(path).noise == EUROC_NOISE
    path.write_text("%YAML:1.0\nrate_hz: [200\n")
    message = r", line 3: not valid YAML: expected ',' or '\]', but got '<stream end>' \(while parsing a flow sequence"
    with pytest.raises(ik.io.FileFormatError, match=message):  # line numbers as in the file
        ik.io.read_kalibr_imu(path)


@pytest.mark.skipif(not (DATA / "gt0_sensor.yaml").exists(), reason=f"gt0_sensor.yaml not found in {DATA}")
def test_real_opencv_style_file_parses_and_lacks_the_noise_keys() -> None:
    # The shared EuRoC folder's gt0_sensor.yaml starts with OpenCV's %YAML:1.0, which PyYAML refuses.
    path = DATA / "gt0_sensor.yaml"
    with pytest.raises(yaml.YAMLError):
        yaml.safe_load(path.read_text())
    missing = f"^path: {re.escape(str(path))}: missing key {', '.join(KEYS)}, update_rate$"
    with pytest.raises(ik.io.FileFormatError, match=missing):
        ik.io.read_kalibr_imu(path)


NON_NEGATIVE = "expected a finite number ≥ 0"
GOOD = dict.fromkeys(KEYS, "1.0e-3") | {"update_rate": "200.0"}


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"gyroscope_random_walk": None}, r": missing key gyroscope_random_walk$"),
        ({"update_rate": None}, r": missing key update_rate$"),
        ({"accelerometer_noise_density": "abc"}, rf", key 'accelerometer_noise_density': {NON_NEGATIVE}, got 'abc'$"),
        ({"gyroscope_random_walk": "-1.0e-3"}, rf", key 'gyroscope_random_walk': {NON_NEGATIVE}, got -0\.001$"),
        ({"accelerometer_random_walk": ".nan"}, rf", key 'accelerometer_random_walk': {NON_NEGATIVE}, got nan$"),
        ({"gyroscope_noise_density": "yes"}, rf", key 'gyroscope_noise_density': {NON_NEGATIVE}, got True$"),
        ({"gyroscope_noise_density": "[1.0e-3]"}, r", key 'gyroscope_noise_density': expected .*got \[0\.001\]$"),
        ({"update_rate": "0"}, r", key 'update_rate': expected a positive, finite number, got 0$"),
        ({"rate_hz": "100"}, r", key 'rate_hz': 100\.0 disagrees with update_rate 200\.0$"),
    ],
)  # fmt: skip
def test_bad_keys_name_file_and_key(tmp_path: Path, changes: dict[str, str | None], message: str) -> None:
    entries = {key: value for key, value in (GOOD | changes).items() if value is not None}
    text = "".join(f"{key}: {value}\n" for key, value in entries.items())
    assert_file_error(tmp_path / "imu.yaml", text, ik.io.read_kalibr_imu, message)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("- 1\n- 2\n", r": expected a mapping of Kalibr keys, got list$"),
        ("", r": expected a mapping of Kalibr keys, got NoneType$"),
        ("a: 1\n b: 2\n", r", line 2: not valid YAML: mapping values are not allowed here$"),
    ],
)
def test_bad_documents_name_the_file(tmp_path: Path, text: str, message: str) -> None:
    assert_file_error(tmp_path / "imu.yaml", text, ik.io.read_kalibr_imu, message)


def test_write_errors_name_the_argument(tmp_path: Path) -> None:
    path = tmp_path / "imu.yaml"
    with pytest.raises(ik.ParameterError, match=r"^rate_hz: expected a positive, finite rate in Hz, got 0"):
        ik.io.write_kalibr_imu(path, EUROC_NOISE, rate_hz=0)
    with pytest.raises(ik.ParameterError, match=r"^rate_hz: .*got inf"):
        ik.io.write_kalibr_imu(path, EUROC_NOISE, rate_hz=math.inf)
    with pytest.raises(TypeError, match=r"^noise: expected an imukit ImuNoise, got dict"):
        ik.io.write_kalibr_imu(path, {"gyro_density": 1.0}, rate_hz=200.0)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^rostopic: expected a string"):
        ik.io.write_kalibr_imu(path, EUROC_NOISE, rate_hz=200.0, rostopic=0)  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^extra: keys \['rostopic', 'update_rate'\] are written from"):
        ik.io.write_kalibr_imu(
            path, EUROC_NOISE, rate_hz=200.0, extra={"update_rate": 1.0, "rostopic": "/a"}, rostopic="/b"
        )
    with pytest.raises(ik.ParameterError, match=r"^extra: cannot be written as YAML"):
        ik.io.write_kalibr_imu(path, EUROC_NOISE, rate_hz=200.0, extra={"T_i_b": np.eye(4)})
    assert not path.exists()


def test_bytes_that_are_not_utf8_name_their_line(tmp_path: Path) -> None:
    path = tmp_path / "imu.yaml"
    path.write_bytes(b"rostopic: /imu0\nupdate_rate: \xff200.0\n")
    with pytest.raises(
        ik.io.FileFormatError, match=rf"^path: {re.escape(str(path))}, line 2: not UTF-8 text \(byte 0xff\)$"
    ):
        ik.io.read_kalibr_imu(path)


def test_byte_order_mark_is_dropped(tmp_path: Path) -> None:
    # Before an OpenCV directive (which PyYAML refuses unless it is stripped) and before a bad byte.
    path = tmp_path / "sensor.yaml"
    path.write_bytes(b"\xef\xbb\xbf%YAML:1.0\n" + EUROC_SENSOR_YAML.encode())
    assert ik.io.read_kalibr_imu(path).noise == EUROC_NOISE
    path.write_bytes(b"\xef\xbb\xbfrostopic: /imu0\nupdate_rate: \xfe200.0\n")
    with pytest.raises(ik.io.FileFormatError, match=r", line 2: not UTF-8 text \(byte 0xfe\)$"):
        ik.io.read_kalibr_imu(path)
