"""``imukit allan``: Allan deviation of a static recording, the fitted noise model and its plots."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

from imukit.cli._common import add_input_options, err, note, out, output_path, positive, read_imu, wrote
from imukit.imu import ImuData
from imukit.io import write_kalibr_imu
from imukit.noise import (
    UNRESOLVED,
    AllanDeviation,
    AllanFit,
    allan_deviation,
    fit_allan,
    mean_rate_hz,
    moving_seconds,
    plot_allan,
    to_imu_noise,
)

DESCRIPTION = """\
Allan deviation of the gyro and accelerometer of PATH (all three axes), and the white noise N,
bias instability B and random walk K fitted to it (docs/noise.md). The recording must be static
(hours at rest for a good K); the sample rate is the mean rate of the stamps.

Reads: PATH in any format imukit detects.
Units: gyro rad/s (N in rad/s/sqrt(Hz), K in rad/s^2/sqrt(Hz)), accelerometer m/s^2 (N in
m/s^2/sqrt(Hz), K in m/s^3/sqrt(Hz)).
Writes, from --out NAME.png: NAME_gyro.png and NAME_accel.png (log-log sigma(tau) with 95%
intervals and the fitted terms), and NAME.yaml, a Kalibr imu.yaml with the fitted densities
(or the file given by --yaml): densities to 4 significant digits, update_rate to 6. Prints both fits.
A random walk K whose 95% interval reaches 0 (a recording too short to tell it from none; hours
are needed) would tell a VIO system that the bias is constant: it is written as the interval's
upper end (--unresolved-walk fitted: as fitted), or as --gyro-random-walk / --accel-random-walk,
with a comment in the yaml and a warning on stderr.

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
    p.add_argument(
        "--unresolved-walk",
        choices=UNRESOLVED,
        default="upper",
        help="random walk written when its interval reaches 0: the interval's upper end or the fitted value "
        "(default: %(default)s)",
    )
    for sensor, unit in (("gyro", "rad/s^2/sqrt(Hz)"), ("accel", "m/s^3/sqrt(Hz)")):
        p.add_argument(
            f"--{sensor}-random-walk",
            type=positive,
            metavar="K",
            help=f"write this {sensor} random walk [{unit}] (e.g. a datasheet's) in place of the fitted one",
        )
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


# Digits written: the 95% intervals of N are a few %, of K tens of %; a rate is nominal.
DENSITY_DIGITS, RATE_DIGITS = 4, 6


def digits(x: float, significant: int) -> float:
    """``x`` rounded to ``significant`` digits, so that ``repr`` writes no more."""
    return float(f"{x:.{significant}g}")


def walk_choices(fits: dict[str, AllanFit], args: argparse.Namespace) -> tuple[dict[str, float], dict[str, str]]:
    """The random walks to write in place of the fitted ones (by ImuNoise field) and a comment per
    Kalibr key: the user's value, or the upper end of an unresolved interval (each also a warning)."""
    values: dict[str, float] = {}
    comments: dict[str, str] = {}
    for sensor, key in (("gyro", "gyroscope_random_walk"), ("accel", "accelerometer_random_walk")):
        fit, given = fits[sensor], getattr(args, f"{sensor}_random_walk")
        lo, hi = fit.random_walk_interval
        if given is not None:
            values[f"{sensor}_random_walk"] = given
            comments[key] = f"given (--{sensor}-random-walk); fitted {fit.random_walk:.4g}, 95%: [{lo:.4g}, {hi:.4g}]"
        elif not fit.random_walk_resolved:
            upper = args.unresolved_walk == "upper"
            written = f"its upper end {hi:.4g}" if upper else f"the fitted {fit.random_walk:.4g}"
            comments[key] = f"NOT RESOLVED: 95% interval [0, {hi:.4g}] reaches 0; written: {written}"
            note(
                f"warning: the {sensor} random walk is not resolved by this recording (95% interval "
                f"[0, {hi:.4g}], fitted {fit.random_walk:.4g}): written as {written} (--unresolved-walk); "
                "a longer static recording, or the datasheet's value, is better"
            )
    return values, comments


def run(args: argparse.Namespace) -> int:
    png = output_path(args.out, (".png",), "--out", args)
    yaml_path = output_path(args.yaml, (".yaml", ".yml"), "--yaml", args) if args.yaml else png.with_suffix(".yaml")
    imu, _ = read_imu(args)
    moving = moving_seconds(imu)
    if moving > 0.01 * imu.duration:
        note(
            f"warning: {args.path} is not still for {moving:.1f} s of its {imu.duration:.1f} s (1 s means of the "
            "gyro 0.05 rad/s or of the accelerometer 0.5 m/s² away from their medians: imukit.noise.moving_seconds); "
            "its Allan deviation measures that motion too, not only the noise"
        )
    with err.status(f"Allan deviation of {len(imu)} samples"):
        rate = mean_rate_hz(imu)
        fits = allan_fits(imu, rate)
    for sensor, (allan, fit) in fits.items():
        out.print(f"{sensor}: {fit}".replace("\n", "\n  "), markup=False)
        path = png.with_name(f"{png.stem}_{sensor}.png")
        plot_allan(allan, path, fit=fit, title=f"Allan deviation, {sensor} (3 axes): {Path(args.path).name}")
        wrote(f"{sensor} Allan plot", path)
    fitted = {sensor: fit for sensor, (_, fit) in fits.items()}
    noise = to_imu_noise(gyro=fitted["gyro"], accel=fitted["accel"], unresolved=args.unresolved_walk)
    rounded = {f.name: digits(getattr(noise, f.name), DENSITY_DIGITS) for f in dataclasses.fields(noise)}
    walks, comments = walk_choices(fitted, args)
    write_kalibr_imu(
        yaml_path,
        dataclasses.replace(noise, **{**rounded, **walks}),
        rate_hz=digits(rate, RATE_DIGITS),
        comments=comments,
        header=f"from imukit allan of {Path(args.path).name}: {len(imu)} samples, {imu.duration:.1f} s",
    )
    wrote("Kalibr imu.yaml", yaml_path)
    return 0
