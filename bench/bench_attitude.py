"""Gyro integration, 10^6 samples, every attitude kept: imukit against numpy-quaternion and a
scipy ``Rotation`` loop, measured side by side in one run.

Usage: ``python bench/bench_attitude.py [--n 1000000] [--repeats 9]``. Prints the median time per
sample (including array conversion and building the returned ``Rotation``) and the ratio
peer / imukit (> 1: imukit faster). The scipy loop is timed on ``--loop-n`` samples and reported
per sample. All three compute the same zero-order-hold product ``q_k = q_{k-1} ⊗ Exp(ω_{k-1} h)``;
the script checks that they agree before timing.
"""

from __future__ import annotations

import argparse

import numpy as np
import quaternion  # numpy-quaternion
from scipy.spatial.transform import Rotation

import imukit as ik
from _timing import median_s


def numpy_quaternion(dt: float, gyro: np.ndarray) -> np.ndarray:
    steps = quaternion.from_rotation_vector(gyro[:-1] * dt)
    out = np.empty(len(gyro), dtype=np.quaternion)
    out[0] = quaternion.one
    np.multiply.accumulate(steps, out=out[1:])
    return out


def scipy_loop(dt: float, gyro: np.ndarray) -> Rotation:
    r = Rotation.identity()
    out = [r]
    for w in gyro[:-1]:
        r = r * Rotation.from_rotvec(w * dt)
        out.append(r)
    return Rotation.concatenate(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--loop-n", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=9)
    args = parser.parse_args()

    dt = 0.005
    t = np.arange(args.n) * dt
    gyro = np.stack([0.3 * np.sin(1.1 * t), 0.2 * np.cos(0.7 * t), 0.5 * np.sin(1.3 * t)], axis=-1)

    ours = ik.integrate_attitude(t, gyro, scheme="exp").as_quat()
    peer = quaternion.as_float_array(numpy_quaternion(dt, gyro))[:, [1, 2, 3, 0]]
    gap = np.minimum(np.abs(ours - peer).max(axis=1), np.abs(ours + peer).max(axis=1)).max()
    m = args.loop_n
    loop_gap = np.abs(scipy_loop(dt, gyro[:m]).as_quat() - ours[:m]).max()
    print(f"agreement over {args.n:,} steps: numpy-quaternion {gap:.1e}, scipy loop ({m:,}) {loop_gap:.1e}")

    per = {
        "imukit exp": median_s(lambda: ik.integrate_attitude(t, gyro, scheme="exp"), args.repeats) / args.n,
        "imukit magnus": median_s(lambda: ik.integrate_attitude(t, gyro, scheme="magnus"), args.repeats) / args.n,
        "imukit midpoint": median_s(lambda: ik.integrate_attitude(t, gyro, scheme="midpoint"), args.repeats) / args.n,
        "numpy-quaternion": median_s(lambda: numpy_quaternion(dt, gyro), args.repeats) / args.n,
        "scipy Rotation loop": median_s(lambda: scipy_loop(dt, gyro[:m]), 3) / m,
    }
    base = per["imukit exp"]
    print(f"{'method':22s} {'ns/sample':>10s} {'÷ imukit exp':>13s}")
    for name, seconds in per.items():
        print(f"{name:22s} {seconds * 1e9:10.1f} {seconds / base:12.1f}x")


if __name__ == "__main__":
    main()
