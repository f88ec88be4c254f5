"""Noise files a VIO system can trust: an unresolved random walk is never written as 0, and numbers are
written with the digits they have (``imukit allan``, ``to_imu_noise``, ``write_kalibr_imu``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import imukit as ik
from imukit.cli import main

RATE = 100.0
# A gyro random walk far too small for 3 minutes to resolve (the fit gives K = 0 exactly, seed 0),
# an accelerometer one that 3 minutes resolve (EuRoC's datasheet value).
NOISE = ik.ImuNoise(gyro_density=1.6968e-4, accel_density=2.0e-3, gyro_random_walk=2e-6, accel_random_walk=3.0e-3)


@pytest.fixture(scope="module")
def static_csv(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, ik.ImuData]:
    imu, _ = ik.sim.simulate(ik.sim.Static(), rate=RATE, duration=180.0, noise=NOISE, seed=0)
    path = tmp_path_factory.mktemp("static") / "static.csv"
    rows = np.column_stack([imu.t, imu.gyro, imu.accel])
    np.savetxt(path, rows, delimiter=",", header="t,gx,gy,gz,ax,ay,az", comments="", fmt="%.17g")
    return path, imu


def _fits(imu: ik.ImuData) -> dict[str, ik.noise.AllanFit]:
    # The CLI's fits: float-second stamps, rate = median 1/dt (100.00000000000213 here).
    return {
        s: ik.noise.fit_allan(ik.noise.allan_deviation(x, imu.rate_hz), sensor=s)
        for s, x in (("gyro", imu.gyro), ("accel", imu.accel))
    }


def test_allan_writes_an_unresolved_random_walk_as_its_upper_bound(
    static_csv: tuple[Path, ik.ImuData], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, imu = static_csv
    fits = _fits(imu)
    assert imu.rate_hz != 100.0  # the rate that was written as 100.00000000000213
    assert fits["gyro"].random_walk == 0.0 and not fits["gyro"].random_walk_resolved  # the case of the issue
    assert fits["accel"].random_walk_resolved

    columns = ["--csv-time-column", "t", "--csv-gyro-columns", "gx,gy,gz", "--csv-accel-columns", "ax,ay,az"]
    assert main(["allan", str(path), *columns, "--out", str(tmp_path / "a.png")]) == 0
    err = capsys.readouterr().err
    text = (tmp_path / "a.yaml").read_text()
    doc = yaml.safe_load(text)

    assert "update_rate: 100.0  #" in text
    assert doc["update_rate"] == 100.0
    gyro_walk, accel_walk = doc["gyroscope_random_walk"], doc["accelerometer_random_walk"]
    assert gyro_walk > 0.0 and gyro_walk >= fits["gyro"].random_walk
    assert gyro_walk == float(f"{fits['gyro'].random_walk_interval[1]:.4g}")  # the upper end, 4 digits
    assert accel_walk == float(f"{fits['accel'].random_walk:.4g}") > 0.0  # resolved: the fitted value
    gyro_line = next(line for line in text.splitlines() if line.startswith("gyroscope_random_walk:"))
    assert "NOT RESOLVED" in gyro_line and "reaches 0" in gyro_line
    assert "warning: the gyro random walk is not resolved" in err and "accel random walk" not in err
    # Densities: 4 significant digits, within 10% of the truth (N is resolved in 3 minutes).
    assert doc["gyroscope_noise_density"] == float(f"{fits['gyro'].noise_density:.4g}")
    assert doc["gyroscope_noise_density"] == pytest.approx(NOISE.gyro_density, rel=0.1)
    assert ik.io.read_kalibr_imu(tmp_path / "a.yaml").noise.gyro_random_walk == gyro_walk

    # The user's choices: the fitted value (a warning still), or a value of their own.
    assert main(["allan", str(path), *columns, "--out", str(tmp_path / "b.png"), "--unresolved-walk", "fitted"]) == 0
    assert yaml.safe_load((tmp_path / "b.yaml").read_text())["gyroscope_random_walk"] == 0.0
    assert "not resolved" in capsys.readouterr().err
    given = ["--gyro-random-walk", "1.9393e-05", "--out", str(tmp_path / "c.png")]
    assert main(["allan", str(path), *columns, *given]) == 0
    c_text = (tmp_path / "c.yaml").read_text()
    assert yaml.safe_load(c_text)["gyroscope_random_walk"] == 1.9393e-05
    assert "given (--gyro-random-walk)" in c_text


def test_to_imu_noise_policies(static_csv: tuple[Path, ik.ImuData]) -> None:
    fits = _fits(static_csv[1])
    upper = ik.noise.to_imu_noise(gyro=fits["gyro"], accel=fits["accel"])
    fitted = ik.noise.to_imu_noise(gyro=fits["gyro"], accel=fits["accel"], unresolved="fitted")
    assert upper.gyro_random_walk == fits["gyro"].random_walk_interval[1] > 0.0
    assert fitted.gyro_random_walk == fits["gyro"].random_walk == 0.0
    assert upper.accel_random_walk == fitted.accel_random_walk == fits["accel"].random_walk  # resolved: as fitted
    with pytest.raises(ik.ParameterError, match="unresolved: expected one of"):
        ik.noise.to_imu_noise(gyro=fits["gyro"], accel=fits["accel"], unresolved="zero")


def test_write_kalibr_imu_comments_and_header(tmp_path: Path) -> None:
    noise = ik.ImuNoise(1.696812345e-4, 2.0e-3, 1.93931e-5, 3.0e-3)
    path = tmp_path / "imu.yaml"
    ik.io.write_kalibr_imu(
        path, noise, rate_hz=200.0, comments={"gyroscope_random_walk": "a note"}, header="two\nlines"
    )
    text = path.read_text()
    assert text.splitlines()[1:3] == ["# two", "# lines"]
    assert "gyroscope_random_walk: 1.93931e-05  # [rad/s^2/sqrt(Hz)] bias random walk; a note" in text
    assert ik.io.read_kalibr_imu(path).noise == noise  # still bit for bit
    with pytest.raises(ik.ParameterError, match="comments: keys \\['rate'\\] are not Kalibr noise keys"):
        ik.io.write_kalibr_imu(path, noise, rate_hz=200.0, comments={"rate": "x"})
