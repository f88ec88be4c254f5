"""``imukit simulate``: an IMU recording (EuRoC folder) from a named motion or a TUM trajectory."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, Callable

import numpy as np

from imukit import sim
from imukit.cli._common import CliError, out, positive, read_trajectory, wrote
from imukit.imu import ImuData, ImuNoise
from imukit.io import read_kalibr_imu, write_euroc
from imukit.state import Trajectory

MOTIONS: dict[str, Callable[[], sim.Motion]] = {
    "static": sim.Static,
    "circle": sim.Circle,
    "helix": sim.Helix,
    "figure-eight": sim.FigureEight,
    "vio-ellipse": sim.VioEllipse,
    "constant-twist": sim.ConstantTwist,
}

DESCRIPTION = f"""\
Simulate an IMU moving along TRAJECTORY (docs/simulation.md).

Writes: the readings and the exact truth as an EuRoC / ASL folder: FOLDER/mav0/imu0/data.csv,
FOLDER/mav0/state_groundtruth_estimate0/data.csv (with the true biases) and
FOLDER/mav0/imu0/sensor.yaml (the noise model; zeros without --noise). Read it back with any
imukit command, or with EuRoC tools.

TRAJECTORY is a closed-form motion of imukit.sim with its default parameters
({", ".join(MOTIONS)}; docs/simulation.md), or a TUM trajectory file (`t x y z qx qy qz qw`):
a C2 spline through its poses (imukit.sim.Waypoints, at rest at both ends), simulated from its
first stamp.
Frames and units: world z up, gravity (0, 0, -9.81) m/s^2; stamps t = start + k / rate written
as integer nanoseconds (exact when 1e9 / rate is an integer; a file's start is its first stamp, to the ns).
The noise (--noise, a Kalibr imu.yaml: white noise and bias random walk densities) is drawn from
--seed: the same seed gives the same files.

Example:
  imukit simulate figure-eight --duration 60 --rate 200 --noise imu.yaml --seed 1 --out sim_fig8/"""


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "simulate",
        help="simulate an IMU on a motion or a TUM trajectory, written as an EuRoC folder",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("trajectory", metavar="TRAJECTORY", help=f"one of {', '.join(MOTIONS)}, or a TUM file")
    p.add_argument(
        "--duration", type=positive, metavar="S", help="seconds to simulate (default: 60; a TUM file's span)"
    )
    p.add_argument("--rate", type=positive, default=200.0, metavar="HZ", help="sample rate [Hz] (default: %(default)s)")
    p.add_argument("--noise", metavar="YAML", help="Kalibr imu.yaml: the sensor noise to add (default: none)")
    p.add_argument("--seed", type=int, default=0, help="seed of the noise (default: %(default)s)")
    p.add_argument("--out", required=True, metavar="FOLDER", help="the EuRoC folder to write (created)")
    p.set_defaults(run=run)
    return p


def motion(name: str, *, skip_bad_lines: bool) -> tuple[sim.Motion, int, float | None]:
    """The motion, its start time [ns] and its span [s] (None: unbounded). A file's spline runs in
    seconds from its first stamp: at epoch stamps float seconds resolve only 238 ns."""
    if name in MOTIONS:
        return MOTIONS[name](), 0, None
    if not Path(name).is_file():
        raise CliError(f"TRAJECTORY: {name!r} is neither a motion ({', '.join(MOTIONS)}) nor a file")
    truth: Trajectory = read_trajectory(name, skip_bad_lines=skip_bad_lines)
    if len(truth) < 2:
        raise CliError(f"TRAJECTORY: {name} has {len(truth)} pose; a spline needs at least 2")
    stamps = truth.t_ns if truth.t_ns is not None else np.round(truth.t * 1e9).astype(np.int64)
    seconds = (stamps - stamps[0]) / 1e9
    return sim.Waypoints(seconds, truth.position, truth.rotation), int(stamps[0]), float(seconds[-1])


def simulate(args: argparse.Namespace) -> tuple[ImuData, Trajectory, ImuNoise | None]:
    """What ``imukit simulate`` writes, in memory: stamps ``start + k / rate`` in integer ns."""
    trajectory, start_ns, span = motion(args.trajectory, skip_bad_lines=args.skip_bad_lines)
    duration = args.duration if args.duration is not None else (span if span is not None else 60.0)
    if span is not None and duration > span:
        raise CliError(f"--duration: {duration} s is longer than the trajectory file's {span:.6g} s")
    noise = None if args.noise is None else read_kalibr_imu(args.noise).noise
    if args.seed < 0:
        raise CliError(f"--seed: expected a non-negative integer, got {args.seed}")
    imu, truth = sim.simulate(trajectory, rate=args.rate, duration=duration, noise=noise, seed=args.seed)
    stamps = start_ns + np.round(imu.t * 1e9).astype(np.int64)
    imu = ImuData(stamps, imu.gyro, imu.accel)
    truth = Trajectory(
        stamps,
        truth.position,
        truth.velocity,
        truth.rotation,
        gyro_bias=truth.gyro_bias,
        accel_bias=truth.accel_bias,
    )
    return imu, truth, noise


def run(args: argparse.Namespace) -> int:
    imu, truth, noise = simulate(args)
    folder = Path(args.out) / "mav0"
    write_euroc(folder, imu, truth, noise=noise or ImuNoise(0.0, 0.0, 0.0, 0.0), rate_hz=args.rate)
    out.print(
        f"simulated {args.trajectory}: {len(imu)} samples at {args.rate:g} Hz over {imu.duration:.6g} s"
        + ("" if noise is None else f", noise from {args.noise} (seed {args.seed})"),
        markup=False,
    )
    wrote("EuRoC folder", folder)
    return 0
