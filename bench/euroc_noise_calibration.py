"""Noise calibration on real data: EuRoC V1_02_medium (the 40 s excerpt), windows of ``--window`` s
(10 Hz keyframes by default) inside the ground-truth span, each at the ground-truth bias at its start,
datasheet densities; :func:`imukit.noise.calibrate_from_residuals` on all windows, then fitted on one
half of the recording and scored on the other (both ways), the scored half re-preintegrated with the
fitted densities.

Usage: ``python bench/euroc_noise_calibration.py [--data DIR] [--window 0.1]``. Prints markdown; the
numbers of ``docs/noise.md`` § On EuRoC.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import imukit as ik
from euroc_preint_residuals import DATA, NOISE, load, truth
from imukit.preint import PreintParams, States, preintegrate_windows


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA, help=f"EuRoC excerpt folder (default {DATA})")
    parser.add_argument("--window", type=float, default=0.1, help="window length [s] (default 0.1)")
    args = parser.parse_args()
    rec = load(args.data)
    gt = truth(rec)
    imu = ik.ImuData(rec.t_ns, rec.gyro, rec.accel)
    step = round(args.window / float(np.median(np.diff(rec.seconds))))
    idx = np.arange(0, len(imu), step)
    i, j = idx[:-1], idx[1:]
    rot = gt.rotation.as_matrix()
    state_i = States(gt.position[i], gt.velocity[i], rot[i])
    state_j = States(gt.position[j], gt.velocity[j], rot[j])
    biases = [ik.ImuBias(g, a) for g, a in zip(gt.gyro_bias[i], gt.accel_bias[i])]
    mean_bias = ik.ImuBias(gt.gyro_bias.mean(axis=0), gt.accel_bias.mean(axis=0))

    def part(states: States, s: slice) -> States:
        return States(*(a[s] for a in states))

    print(f"| scheme | windows | χ² mean before | f_θ | f_v | f_p | gyro × | accel × | over {21.67} after |")
    print("|---|---|---|---|---|---|---|---|---|")
    held = []
    for scheme in ("lie_euler", "midpoint"):
        windows = preintegrate_windows(imu, imu.t_ns[idx], PreintParams(NOISE, bias=mean_bias, scheme=scheme))
        cal = ik.noise.calibrate_from_residuals(windows, state_i, state_j, bias=biases)
        f = cal.block_factors
        print(
            f"| {scheme} | {len(windows)} | {cal.chi2_before.mean():.4g} | {f[0]:.3g} | {f[1]:.3g} | {f[2]:.3g} | "
            f"{cal.gyro_factor:.3g} | {cal.accel_factor:.3g} | {np.mean(cal.chi2_after > cal.chi2_bound):.3f} |"
        )
        m = len(windows)
        halves = (slice(0, m // 2), slice(m // 2, m))
        for name, fit, test in (("first → second", *halves), ("second → first", *halves[::-1])):
            c = ik.noise.calibrate_from_residuals(
                windows[fit], part(state_i, fit), part(state_j, fit), bias=biases[fit]
            )
            again = preintegrate_windows(imu, imu.t_ns[idx], PreintParams(c.noise, bias=mean_bias, scheme=scheme))
            t = ik.noise.calibrate_from_residuals(
                again[test], part(state_i, test), part(state_j, test), bias=biases[test]
            )
            held.append(
                f"| {scheme} | {name} | {c.gyro_factor:.3g} | {c.accel_factor:.3g} | {t.chi2_before.mean():.3g} | "
                f"{np.mean(t.chi2_before > t.chi2_bound):.3f} | {t.gyro_factor:.3g} | {t.accel_factor:.3g} |"
            )
    print()
    print(
        "| scheme | fit → scored | gyro × | accel × | held-out χ² mean | over 21.67 | held-out own gyro | own accel |"
    )
    print("|---|---|---|---|---|---|---|---|")
    print("\n".join(held))


if __name__ == "__main__":
    main()
