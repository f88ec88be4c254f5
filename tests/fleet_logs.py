"""Simulated fleets for the imukit.fleet tests: EuRoC folders and EuRoC-layout CSV files, plus a
corrupt and an empty file; estimates in another world frame for the evaluate job."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit import sim

NOISE = ik.ImuNoise(1.7e-4, 2.0e-3, 0.0, 0.0)
RATE_HZ = 200.0
DURATION_S = 5.0


def write_logs(folder: Path, count: int, *, first: int = 0) -> list[Path]:
    """``count`` static logs of DURATION_S s, each its own seed and bias: even numbers as EuRoC
    folders ``log<k>``, odd ones as the IMU CSV alone, ``log<k>.csv``."""
    paths = []
    for k in range(first, first + count):
        bias = ik.ImuBias([1e-3 * k, -2e-3, 5e-4], [0.01 * (k % 7), 0.0, -0.02])
        imu, truth = sim.simulate(sim.Static(), rate=RATE_HZ, duration=DURATION_S, noise=NOISE, bias=bias, seed=k)
        target = folder / f"log{k:03d}"
        ik.io.write_euroc(target, imu, truth, noise=NOISE, rate_hz=RATE_HZ)
        if k % 2:
            csv = next(target.rglob("imu0/data.csv"))
            shutil.copy(csv, target.with_suffix(".csv"))
            shutil.rmtree(target)
            target = target.with_suffix(".csv")
        paths.append(target)
    return paths


def write_broken(folder: Path) -> dict[Path, str]:
    """A corrupt and an empty file, each with a word its failure's error names."""
    corrupt, empty = folder / "corrupt.csv", folder / "empty.csv"
    corrupt.write_bytes(b"#timestamp,w_x\n\x00\x9f garbage \xff\n")
    empty.write_bytes(b"")
    return {corrupt: "not a text file", empty: "empty file"}


def rigidly_moved(reference: ik.Trajectory, every: int, angle_deg: float, offset: list[float]) -> ik.Trajectory:
    """Every ``every``-th pose of ``reference`` (an estimator's slower output) in a world frame turned
    by ``angle_deg`` about z and shifted by ``offset``: the poses relative to each other unchanged."""
    turn = Rotation.from_euler("z", angle_deg, degrees=True)
    stamps = reference.t_ns
    return ik.Trajectory(
        None if stamps is not None else reference.t[::every],
        turn.apply(np.array(reference.position[::every])) + offset,
        None,
        turn * reference.rotation[::every],
        t_ns=None if stamps is None else stamps[::every],
    )
