"""``imukit allan``: Allan deviation of a static recording, the fitted noise model and its plots."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from imukit.cli._common import add_input_options, err, out, output_path, read_imu, wrote
from imukit.imu import ImuData
from imukit.io import write_kalibr_imu
from imukit.noise import AllanDeviation, AllanFit, allan_deviation, fit_allan, mean_rate_hz, plot_allan, to_imu_noise

DESCRIPTION = """\
Allan deviation of the gyro and accelerometer of PATH (all three axes), and the white noise N,
bias instability B and random walk K fitted to it (docs/noise.md). The recording must be static
(hours at rest for a good K); the sample rate is the mean rate of the stamps.

Reads: PATH in any format imukit detects.
Units: gyro rad/s (N in rad/s/sqrt(Hz), K in rad/s^2/sqrt(Hz)), accelerometer m/s^2 (N in
m/s^2/sqrt(Hz), K in m/s^3/sqrt(Hz)).
Writes, from --out NAME.png: NAME_gyro.png and NAME_accel.png (log-log sigma(tau) with 95%
intervals and the fitted terms), and NAME.yaml, a Kalibr imu.yaml with the fitted densities
(or the file given by --yaml). Prints both fits.

Example:
  imukit allan static_imu/ --out allan.png"""


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "allan",
        help="Allan deviation of a static recording: plots and a fitted Kalibr imu.yaml",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("path", metavar="PATH", help="a static recording (EuRoC folder, CSV, bag, ...)")
    p.add_argument("--out", required=True, metavar="PNG", help="NAME.png: writes NAME_gyro.png and NAME_accel.png")
    p.add_argument("--yaml", metavar="YAML", help="where to write the fitted Kalibr imu.yaml (default: NAME.yaml)")
    add_input_options(p)
    p.set_defaults(run=run)
    return p


def allan_fits(imu: ImuData, rate_hz: float) -> dict[str, tuple[AllanDeviation, AllanFit]]:
    """The Allan deviation of both sensors at ``rate_hz``, and their joint 3-axis fits."""
    result = {}
    for sensor, samples in (("gyro", imu.gyro), ("accel", imu.accel)):
        allan = allan_deviation(samples, rate_hz)
        result[sensor] = allan, fit_allan(allan, sensor=sensor)
    return result


def run(args: argparse.Namespace) -> int:
    png = output_path(args.out, (".png",), "--out")
    yaml_path = output_path(args.yaml, (".yaml", ".yml"), "--yaml") if args.yaml else png.with_suffix(".yaml")
    imu, _ = read_imu(args)
    with err.status(f"Allan deviation of {len(imu)} samples"):
        rate = mean_rate_hz(imu)
        fits = allan_fits(imu, rate)
    for sensor, (allan, fit) in fits.items():
        out.print(f"{sensor}: {fit}".replace("\n", "\n  "), markup=False)
        path = png.with_name(f"{png.stem}_{sensor}.png")
        plot_allan(allan, path, fit=fit, title=f"Allan deviation, {sensor} (3 axes): {Path(args.path).name}")
        wrote(f"{sensor} Allan plot", path)
    write_kalibr_imu(yaml_path, to_imu_noise(gyro=fits["gyro"][1], accel=fits["accel"][1]), rate_hz=rate)
    wrote("Kalibr imu.yaml", yaml_path)
    return 0
