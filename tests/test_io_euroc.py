"""EuRoC / ASL folders: EuRoC's exact headers, bit-exact round trips, the stamp rule for float seconds,
the real V1_02_medium files read as tests/euroc.py reads them, and errors that name what is wrong."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

import imukit as ik
from euroc import GT_CSV, IMU_CSV, load, requires_euroc

from conftest import assert_file_error, assert_quat_close

EPOCH = 1_403_715_523_912_140_000
NOISE = ik.ImuNoise(gyro_density=1.6968e-04, accel_density=2.0e-3, gyro_random_walk=1.9393e-05, accel_random_walk=3e-3)


def awkward_values(rng: np.random.Generator, n: int, width: int) -> np.ndarray:
    """Floats over 24 orders of magnitude, with the extremes whose text is easy to get wrong."""
    x = rng.normal(size=(n, width)) * 10.0 ** rng.integers(-12, 12, size=(n, width))
    x.flat[:6] = [-0.0, 5e-324, 1.7976931348623157e308, 1e-05, 0.1 + 0.2, -2.2250738585072014e-308]
    return x


def random_imu(rng: np.random.Generator, n: int = 400) -> ik.ImuData:
    t_ns = EPOCH + np.cumsum(rng.integers(4_999_000, 5_001_000, n))
    return ik.ImuData(t_ns, awkward_values(rng, n, 3), awkward_values(rng, n, 3)[::-1])


def random_truth(rng: np.random.Generator, n: int = 300, **kwargs: object) -> ik.Trajectory:
    t_ns = EPOCH + 3168 + np.cumsum(rng.integers(4_999_680, 5_000_193, n))
    biases = {"gyro_bias": rng.normal(size=(n, 3)) * 1e-3, "accel_bias": awkward_values(rng, n, 3)}
    return ik.Trajectory(
        None,
        awkward_values(rng, n, 3),
        rng.normal(size=(n, 3)),
        Rotation.random(n, rng=rng),
        t_ns=t_ns,
        **{**biases, **kwargs},  # type: ignore[arg-type]
    )


def float_truth(t: np.ndarray, **kwargs: object) -> ik.Trajectory:
    n = len(t)
    return ik.Trajectory(t, np.zeros((n, 3)), np.ones((n, 3)), Rotation.identity(n), **kwargs)  # type: ignore[arg-type]


def test_round_trip_is_bit_exact(tmp_path: Path, rng: np.random.Generator) -> None:
    imu, truth = random_imu(rng), random_truth(rng)
    ik.io.write_euroc(tmp_path, imu, truth)
    back, back_truth = ik.io.read_euroc(tmp_path)
    assert back.t_ns is not None and back_truth is not None and back_truth.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, imu.t_ns)
    np.testing.assert_array_equal(back.t, imu.t)
    np.testing.assert_array_equal(back.gyro, imu.gyro)
    np.testing.assert_array_equal(back.accel, imu.accel)
    np.testing.assert_array_equal(back_truth.t_ns, truth.t_ns)
    np.testing.assert_array_equal(back_truth.position, truth.position)
    np.testing.assert_array_equal(back_truth.velocity, truth.velocity)
    np.testing.assert_array_equal(back_truth.rotation.as_quat(), truth.rotation.as_quat())
    np.testing.assert_array_equal(back_truth.gyro_bias, truth.gyro_bias)
    np.testing.assert_array_equal(back_truth.accel_bias, truth.accel_bias)
    assert np.signbit(back.gyro.flat[0])  # -0.0 stays negative


def test_every_written_value_reads_back_with_float_and_int(tmp_path: Path, rng: np.random.Generator) -> None:
    # Independent of read_euroc: the text itself, parsed by Python, gives every value back.
    imu, truth = random_imu(rng), random_truth(rng)
    ik.io.write_euroc(tmp_path, imu, truth)
    assert truth.velocity is not None and truth.gyro_bias is not None and truth.accel_bias is not None
    gt = [truth.position, truth.rotation.as_quat(scalar_first=True), truth.velocity, truth.gyro_bias, truth.accel_bias]
    for name, stamps, values in [
        ("imu0/data.csv", imu.t_ns, np.hstack([imu.gyro, imu.accel])),
        ("state_groundtruth_estimate0/data.csv", truth.t_ns, np.hstack(gt)),
    ]:
        assert stamps is not None
        rows = [line.split(",") for line in (tmp_path / name).read_text().splitlines()[1:]]
        assert [int(row[0]) for row in rows] == list(stamps)
        text_values = np.array([[float(x) for x in row[1:]] for row in rows])
        assert np.array_equal(text_values.view(np.int64), values.view(np.int64)), name  # bit for bit


@requires_euroc
def test_header_lines_are_eurocs(tmp_path: Path, rng: np.random.Generator) -> None:
    ik.io.write_euroc(tmp_path, random_imu(rng), random_truth(rng))
    for ours, real in [("imu0/data.csv", IMU_CSV), ("state_groundtruth_estimate0/data.csv", GT_CSV)]:
        with open(real, encoding="ascii") as f:
            expected = f.readline().rstrip("\r\n")
        assert (tmp_path / ours).read_text().splitlines()[0] == expected


def test_quaternions_are_written_scalar_first(tmp_path: Path) -> None:
    truth = float_truth(np.array([0.0]), gyro_bias=[[1.0, 2.0, 3.0]], accel_bias=[[4.0, 5.0, 6.0]])
    truth = ik.Trajectory(
        truth.t, [[7.0, 8.0, 9.0]], [[-1.0, -2.0, -3.0]], Rotation.from_quat([[0.5, -0.5, 0.5, 0.5]]),
        gyro_bias=truth.gyro_bias, accel_bias=truth.accel_bias,
    )  # fmt: skip
    ik.io.write_euroc(tmp_path, ik.ImuData([0.0], [[0.0, 0.0, 0.0]], [[0.0, 0.0, 9.81]]), truth)
    row = (tmp_path / "state_groundtruth_estimate0/data.csv").read_text().splitlines()[1]
    assert row == "0,7.0,8.0,9.0,0.5,0.5,-0.5,0.5,-1.0,-2.0,-3.0,1.0,2.0,3.0,4.0,5.0,6.0"


def test_float_seconds_from_zero_with_epoch(tmp_path: Path) -> None:
    t = np.arange(1000) / 200.0  # a simulation's clock
    imu = ik.ImuData(t, np.zeros((1000, 3)), np.zeros((1000, 3)))
    zeros = np.zeros((500, 3))
    ik.io.write_euroc(tmp_path, imu, float_truth(t[::2] + 0.0025, gyro_bias=zeros, accel_bias=zeros), epoch_ns=EPOCH)
    back, truth = ik.io.read_euroc(tmp_path)
    assert back.t_ns is not None and truth is not None and truth.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, EPOCH + 5_000_000 * np.arange(1000))
    np.testing.assert_array_equal(truth.t_ns, EPOCH + 2_500_000 + 10_000_000 * np.arange(500))
    # Back on the ns grid; ImuData's ns → s conversion (whole seconds + fraction) may be 1 ulp off the nearest float.
    np.testing.assert_array_max_ulp(back.seconds, t, maxulp=1)


@pytest.mark.parametrize("offset", [0.0, 1.4037155239e9, -7.5])
def test_float_seconds_round_to_the_nearest_nanosecond(tmp_path: Path, rng: np.random.Generator, offset: float) -> None:
    t = offset + np.sort(rng.uniform(0.0, 100.0, 2000))
    t = np.concatenate([[offset - 1.0, offset - 0.5 - 2e-10, offset - 0.3], t])
    ik.io.write_euroc(tmp_path, ik.ImuData(t, np.zeros((len(t), 3)), np.zeros((len(t), 3))))
    back = ik.io.read_euroc_imu(tmp_path / "imu0" / "data.csv")
    assert back.t_ns is not None
    exact = [round(Fraction(float(s)) * 10**9) for s in t]  # the float's exact value, rounded
    assert back.t_ns.tolist() == exact


def test_stamp_rule_examples(tmp_path: Path) -> None:
    t = np.array([-1.5, -1e-10, 1 / 1024, 0.1, 1 / 3, 2.0000000004, 2.0000000006])
    ik.io.write_euroc(tmp_path, ik.ImuData(t, np.zeros((7, 3)), np.zeros((7, 3))), epoch_ns=10**9)
    stamps = [line.split(",")[0] for line in (tmp_path / "imu0/data.csv").read_text().splitlines()[1:]]
    # 1/1024 s is exactly 976562.5 ns: a tie, rounded to even.
    assert stamps == ["-500000000", "1000000000", "1000976562", "1100000000", "1333333333", "3000000000", "3000000001"]


def test_stamps_on_the_same_nanosecond_are_refused(tmp_path: Path) -> None:
    imu = ik.ImuData(np.array([0.0, 4e-10, 1.0]), np.zeros((3, 3)), np.zeros((3, 3)))
    with pytest.raises(
        ik.TimestampError, match=r"^imu: samples 0 and 1 \(0\.0 and 4e-10 s\) fall on the same nanosecond 0"
    ):
        ik.io.write_euroc(tmp_path / "out", imu)
    assert not (tmp_path / "out").exists()


def test_epoch_ns_errors(tmp_path: Path, rng: np.random.Generator) -> None:
    imu = random_imu(rng)
    float_imu = ik.ImuData(np.array([0.0, 1.0]), np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ik.ParameterError, match=r"^epoch_ns: offsets float-second stamps, but every stream"):
        ik.io.write_euroc(tmp_path, imu, random_truth(rng), epoch_ns=EPOCH)
    with pytest.raises(ik.ParameterError, match=r"^epoch_ns: expected an integer number of nanoseconds, got 1\.5"):
        ik.io.write_euroc(tmp_path, float_imu, epoch_ns=1.5)  # type: ignore[arg-type]
    with pytest.raises(
        ik.ParameterError, match=r"^imu: float stamps 0\.0 … 1\.0 s with epoch_ns = 9223372036000000000"
    ):
        ik.io.write_euroc(tmp_path, float_imu, epoch_ns=9_223_372_036_000_000_000)
    # t_ns streams are written as they are; epoch_ns offsets only the float one.
    truth = float_truth(np.array([0.5]), gyro_bias=[[0.0] * 3], accel_bias=[[0.0] * 3])
    ik.io.write_euroc(tmp_path, imu, truth, epoch_ns=EPOCH)
    back, back_truth = ik.io.read_euroc(tmp_path)
    assert back.t_ns is not None and back_truth is not None and back_truth.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, imu.t_ns)
    assert back_truth.t_ns.tolist() == [EPOCH + 500_000_000]


def test_truth_needs_biases_and_velocity(tmp_path: Path, rng: np.random.Generator) -> None:
    imu, out = random_imu(rng), tmp_path / "out"
    no_bias = float_truth(np.array([0.0, 0.005]))
    with pytest.raises(ik.ParameterError, match=r"^truth: has no gyro_bias / accel_bias .*pass truth_bias=ImuBias"):
        ik.io.write_euroc(out, imu, no_bias)
    no_velocity = ik.Trajectory(np.array([0.0]), [[0.0, 0.0, 0.0]], None, Rotation.identity(1))
    with pytest.raises(ik.ParameterError, match=r"^truth: has no velocity"):
        ik.io.write_euroc(out, imu, no_velocity, truth_bias=ik.ImuBias())
    with pytest.raises(ik.ParameterError, match=r"^truth_bias: truth has bias histories already"):
        ik.io.write_euroc(out, imu, random_truth(rng), truth_bias=ik.ImuBias())
    with pytest.raises(ik.ParameterError, match=r"^truth_bias: given without truth"):
        ik.io.write_euroc(out, imu, truth_bias=ik.ImuBias())
    assert not out.exists()  # nothing written when refusing
    ik.io.write_euroc(out, imu, no_bias, truth_bias=ik.ImuBias(gyro=[1e-3, -2e-3, 0.0], accel=[0.1, 0.0, -0.2]))
    _, truth = ik.io.read_euroc(out)
    assert truth is not None and truth.gyro_bias is not None and truth.accel_bias is not None
    np.testing.assert_array_equal(truth.gyro_bias, [[1e-3, -2e-3, 0.0]] * 2)
    np.testing.assert_array_equal(truth.accel_bias, [[0.1, 0.0, -0.2]] * 2)


def test_write_refuses_other_objects(tmp_path: Path, rng: np.random.Generator) -> None:
    with pytest.raises(TypeError, match=r"^imu: expected an imukit ImuData"):
        ik.io.write_euroc(tmp_path, np.zeros((2, 7)))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"^truth: expected an imukit Trajectory or None"):
        ik.io.write_euroc(tmp_path, random_imu(rng), np.zeros((2, 17)))  # type: ignore[arg-type]


def test_sensor_yaml(tmp_path: Path, rng: np.random.Generator) -> None:
    imu = random_imu(rng)
    with pytest.raises(ik.ParameterError, match=r"^noise: give noise and rate_hz together"):
        ik.io.write_euroc(tmp_path, imu, noise=NOISE)
    with pytest.raises(ik.ParameterError, match=r"^rate_hz: expected a positive"):
        ik.io.write_euroc(tmp_path, imu, noise=NOISE, rate_hz=0.0)
    ik.io.write_euroc(tmp_path, imu, noise=NOISE, rate_hz=200.0)
    text = (tmp_path / "imu0" / "sensor.yaml").read_text()
    assert "\nsensor_type: imu\n" in text and "\nrate_hz: 200\n" in text  # an integer, as EuRoC writes it
    assert "\ngyroscope_noise_density: 0.00016968  # [rad/s/sqrt(Hz)] white noise\n" in text
    read = ik.io.read_kalibr_imu(tmp_path / "imu0" / "sensor.yaml")
    assert read.noise == NOISE and read.rate_hz == 200.0
    assert read.extra["T_BS"] == {"cols": 4, "rows": 4, "data": np.eye(4).ravel().tolist()}
    ik.io.write_euroc(tmp_path, imu, noise=NOISE, rate_hz=199.99999999999997)
    assert ik.io.read_kalibr_imu(tmp_path / "imu0" / "sensor.yaml").rate_hz == 199.99999999999997


def test_read_euroc_finds_mav0_and_missing_truth(tmp_path: Path, rng: np.random.Generator) -> None:
    imu = random_imu(rng)
    ik.io.write_euroc(tmp_path / "MH_01_easy" / "mav0", imu)
    back, truth = ik.io.read_euroc(tmp_path / "MH_01_easy")
    assert truth is None and back.t_ns is not None
    np.testing.assert_array_equal(back.t_ns, imu.t_ns)
    with pytest.raises(FileNotFoundError, match=r"^folder: no imu0/data\.csv in .*nowhere \(nor in its mav0/\)"):
        ik.io.read_euroc(tmp_path / "nowhere")


@requires_euroc
def test_real_imu_file_reads_as_the_euroc_loader(tmp_path: Path) -> None:
    imu = ik.io.read_euroc_imu(IMU_CSV)
    ref = load()
    assert imu.t_ns is not None and len(imu) == 7999 and imu.t_ns[0] == 1_403_715_523_912_140_000
    np.testing.assert_array_equal(np.diff(imu.t_ns), 5_000_000)  # exactly 200 Hz; float64 stamps are not
    k = int(np.searchsorted(imu.t_ns, ref.t_ns[0]))
    np.testing.assert_array_equal(imu.t_ns[k : k + len(ref.t_ns)], ref.t_ns)
    np.testing.assert_array_equal(imu.gyro[k : k + len(ref.t_ns)], ref.gyro)
    np.testing.assert_array_equal(imu.accel[k : k + len(ref.t_ns)], ref.accel)
    np.testing.assert_array_equal(imu.gyro[0], [-0.0006981317, 0.0195476876, 0.0767944871])
    # Real data → write → read: the same numbers.
    ik.io.write_euroc(tmp_path, imu)
    back, _ = ik.io.read_euroc(tmp_path)
    np.testing.assert_array_equal(back.gyro, imu.gyro)
    np.testing.assert_array_equal(back.accel, imu.accel)


@requires_euroc
def test_real_groundtruth_reads_as_the_euroc_loader() -> None:
    truth = ik.io.read_euroc_groundtruth(GT_CSV)
    raw = np.loadtxt(GT_CSV, delimiter=",", comments="#")
    assert truth.t_ns is not None and truth.velocity is not None
    assert truth.gyro_bias is not None and truth.accel_bias is not None
    np.testing.assert_array_equal(
        truth.t_ns, np.loadtxt(GT_CSV, delimiter=",", comments="#", usecols=0, dtype=np.int64)
    )
    assert truth.t_ns[0] == 1_403_715_524_907_143_168
    np.testing.assert_array_equal(truth.position, raw[:, 1:4])
    np.testing.assert_array_equal(truth.velocity, raw[:, 8:11])
    np.testing.assert_array_equal(truth.gyro_bias, raw[:, 11:14])
    np.testing.assert_array_equal(truth.accel_bias, raw[:, 14:17])
    q = raw[:, [5, 6, 7, 4]]  # w first in the file
    np.testing.assert_allclose(truth.rotation.as_quat(), q / np.linalg.norm(q, axis=1)[:, None], rtol=0, atol=2e-16)
    # tests/euroc.py interpolates this ground truth to the IMU stamps: the same numbers from ours.
    ref = load()
    first = slice(0, 200)
    gt_s = (truth.t_ns - ref.t_ns[0]) * 1e-9
    position = np.stack([np.interp(ref.seconds[first], gt_s, c) for c in truth.position.T], axis=-1)
    np.testing.assert_array_equal(position, ref.position[first])
    np.testing.assert_array_equal(np.interp(ref.seconds[first], gt_s, truth.gyro_bias[:, 2]), ref.gyro_bias[first, 2])
    rotation = Slerp(gt_s, truth.rotation)(ref.seconds[first])
    assert_quat_close(rotation.as_quat(), ref.rotation[first].as_quat(), atol=1e-15)


@requires_euroc
def test_real_header_and_crlf_lines_are_skipped(tmp_path: Path) -> None:
    lines = IMU_CSV.read_text().splitlines()[:4]
    path = tmp_path / "data.csv"
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode())
    imu = ik.io.read_euroc_imu(path)
    assert len(imu) == 3
    np.testing.assert_array_equal(imu.accel[2], [9.2100787917, 0.2941995, -3.1789890417])


IMU_ROW = "1403715523912140000,-0.0006981317,0.0195476876,0.0767944871,9.218251,0.3023717083,-3.1544724167\n"


STAMP_1 = "1403715523912140000"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "#h\n" + IMU_ROW + "1403715523917140000,1,2,3,4,5\n",
            r", line 3: expected 7 comma-separated fields \(EuRoC imu0",
        ),
        ("1403715523.912,1,2,3,4,5,6\n", r", line 1: timestamp '1403715523\.912' is not an integer number of nanos"),
        ("99999999999999999999,1,2,3,4,5,6\n", r", line 1: timestamp '99999999999999999999' is not an integer"),
        (IMU_ROW + "1403715523917140000,1,2,x,4,5,6\n", r", line 2: not a number in '1403715523917140000,1,2,x,4,5,6'"),
        ("1403715523917140000,1,2,nan,4,5,6\n", r", line 1: non-finite value"),
        (
            IMU_ROW + "\n" + IMU_ROW,
            rf", line 3: time must increase strictly, but {STAMP_1} follows {STAMP_1} \(line 1\)",
        ),
        ("#timestamp [ns],w_RS_S_x [rad s^-1]\n\n", r": no data lines"),
        (
            "0,1,2,3,4,5,6\n1,1,2,3,4,5,6\n",
            r": t: integer timestamps are read as nanoseconds, but the median step is 1",
        ),
    ],
)
def test_malformed_imu_files_name_file_and_line(tmp_path: Path, text: str, message: str) -> None:
    assert_file_error(tmp_path / "data.csv", text, ik.io.read_euroc_imu, message)


def test_malformed_groundtruth_files_name_file_and_line(tmp_path: Path) -> None:
    path, read = tmp_path / "data.csv", ik.io.read_euroc_groundtruth
    row = "1403715524907143168,0.5,2.0,0.9,0.1,0.7,-0.2,0.5,0,0,0,0,0,0,0,0,0\n"
    fields = r", line 2: expected 17 comma-separated fields \(EuRoC state_groundtruth_estimate0/data\.csv\), got 15$"
    assert_file_error(path, row + "1403715524912143104" + ",0.5" * 14 + "\n", read, fields)
    zero = row.replace("168,", "169,").replace("0.1,0.7,-0.2,0.5", "0,0,0,0")
    assert_file_error(path, row + zero, read, r", line 2: zero quaternion$")
