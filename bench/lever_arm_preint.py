"""Preintegration with a lever arm (``body_from_sensor=(R_bs, r)``, r ≠ 0): how far its covariance
is from the Monte Carlo one, and what the conversion costs.

The covariance holds the direct gyro and accelerometer noise and the gyro noise that the lever-arm
correction puts into the corrected accelerometer (centripetal ``D(ω) R n``, tangential
``[r]× R Δn / Δt``; ``crates/imukit/src/preint/lever.rs``, ``docs/navigation.md``; before it: 12.6 /
14.4 and 5.2e3 / 1.0e4). The second case is strong enough for the centripetal term to rectify the
gyro noise (a bias no covariance holds): expect about 10.5 there. This script measures the mean NEES
of the deltas of noisy re-runs against the noise-free one (χ²₉: 9) for a tactical-grade case and a
gyro-dominated one, both schemes, and the time of ``preintegrate_windows`` with a lever arm against
the rotation alone (median of alternated runs: the machine is shared).

Usage: ``python bench/lever_arm_preint.py [--trials 400] [--n 200000]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik

R_BS = Rotation.from_euler("ZYX", [120, -30, 45], degrees=True)
H = 0.005


def window(n: int, seed: int) -> ik.ImuData:
    """Smooth rates of about 1 rad/s, random specific force around gravity, 200 Hz."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)[:, None] * H
    gyro = np.sin(k * rng.uniform(1, 4, 3) + rng.uniform(0, 6, 3)) * rng.uniform(0.5, 2.0, 3)
    return ik.ImuData(np.arange(n) * H, gyro, rng.normal(0.0, 3.0, (n, 3)) + np.array([0.0, 0.0, 9.81]))


def mean_nees(gyro_density: float, accel_density: float, arm: float, scheme: str, trials: int) -> float:
    noise = ik.ImuNoise(
        gyro_density=gyro_density, accel_density=accel_density, gyro_random_walk=0.0, accel_random_walk=0.0
    )
    imu = window(201, 11)
    params = ik.PreintParams(noise, scheme=scheme, body_from_sensor=(R_BS, np.array([arm, -arm / 3, arm / 2])))
    clean = ik.preintegrate(imu, params)
    info = np.linalg.inv(clean.covariance)
    rng = np.random.default_rng(0)
    out = []
    for _ in range(trials):
        gyro = imu.gyro + rng.normal(0.0, gyro_density / np.sqrt(H), imu.gyro.shape)
        accel = imu.accel + rng.normal(0.0, accel_density / np.sqrt(H), imu.accel.shape)
        q = ik.preintegrate(ik.ImuData(imu.t, gyro, accel), params)
        r = np.concatenate(
            [
                (clean.delta_rotation.inv() * q.delta_rotation).as_rotvec(),
                q.delta_velocity - clean.delta_velocity,
                q.delta_position - clean.delta_position,
            ]
        )
        out.append(float(r @ info @ r))
    return float(np.mean(out))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=400)
    parser.add_argument("--n", type=int, default=200_000)
    args = parser.parse_args()
    for densities in ((2e-3, 2e-2, 0.3), (1e-2, 1e-3, 0.5)):
        for scheme in ("midpoint", "lie_euler"):
            nees = mean_nees(*densities, scheme, args.trials)
            print(f"σ_g, σ_a, |r| ~ {densities} {scheme}: mean NEES {nees:.1f} (χ²₉: 9)")
    imu = window(args.n, 1)
    noise = ik.ImuNoise(gyro_density=2e-3, accel_density=2e-2, gyro_random_walk=0.0, accel_random_walk=0.0)
    edges = ik.preint.regular_boundaries(imu, 0.5)
    runs: dict[str, list[float]] = {"rotation only": [], "lever arm": []}
    for _ in range(3):
        for name, arm in (("rotation only", [0.0, 0.0, 0.0]), ("lever arm", [0.3, -0.1, 0.15])):
            params = ik.PreintParams(noise, body_from_sensor=(R_BS, arm))
            start = time.perf_counter()
            ik.preintegrate_windows(imu, edges, params, threads=1)
            runs[name].append(time.perf_counter() - start)
    times = {k: float(np.median(v)) for k, v in runs.items()}
    ratio = times["lever arm"] / times["rotation only"]
    print(f"preintegrate_windows, {args.n} samples, 1 thread: {times} s, ratio {ratio:.2f}")


if __name__ == "__main__":
    main()
