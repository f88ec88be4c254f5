"""Issue 15: does a bounded-motion constraint (position and velocity stay small) beat the
velocity-over-τ assumption of ``imukit.filters.Robust`` (and VQF) on BROAD's inclination?

Usage::

    python bench/robust_bounded.py --diagnose      # Robust's (and VQF's) tilt error: slow / fast split

The diagnosis answers whether the idea *can* reach issue 15's targets before anything is built: a
constraint on position observes a tilt error δθ only through ½ g δθ t², so only the part of the
error that is slow against a few seconds can be removed. The tilt error is taken as a vector in the
world frame, ``δθ = axis · angle`` of the inclination part of ``q_err = q_truth ⊗ q_est⁻¹`` (after
the 6D heading offset is removed, as ``imukit.eval.attitude_error`` does), filled linearly over
mocap dropouts, and split by a zero-phase 2nd-order Butterworth low pass (``--split-s``, default
5 s period) into slow and fast parts. Their RMS over the ``movement`` samples with mocap add in
squares to the inclination RMSE up to the small-angle approximation and the cross term, which is
printed as the check ``√(slow² + fast²)`` next to the RMSE. The "fast" column is what would be left
if an oracle removed every slow error: the best such a constraint could do.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np
from scipy.signal import butter, sosfiltfilt
from scipy.spatial.transform import Rotation

import imukit as ik
from broad_accuracy import GROUPS, Trial
from robust_tune import Runner, robust_runner, trials, vqf_runner


def tilt_vector(q_est: np.ndarray, tr: Trial) -> tuple[np.ndarray, np.ndarray]:
    """World-frame tilt error ``(N, 2)`` [rad] (NaN-free: dropouts filled) and the scored mask."""
    err = ik.eval.attitude_error(q_est, tr.truth, scalar_first=True, align_heading=True, mask=tr.movement)
    valid = np.isfinite(tr.truth).all(1)
    est = Rotation.from_euler("z", err.heading_offset) * Rotation.from_quat(q_est, scalar_first=True)
    truth = Rotation.from_quat(np.where(valid[:, None], tr.truth, [1.0, 0.0, 0.0, 0.0]), scalar_first=True)
    up = (truth * est.inv()).apply([0.0, 0.0, 1.0])
    # The rotation taking up to R_err up: axis up × u (horizontal), angle between them.
    axis = np.stack([-up[:, 1], up[:, 0]], 1)
    s = np.linalg.norm(axis, axis=1)
    angle = np.arctan2(s, up[:, 2])
    vec = axis * np.where(s > 0, angle / np.maximum(s, 1e-300), 1.0)[:, None]
    idx = np.arange(len(vec))
    for k in range(2):
        vec[:, k] = np.interp(idx, idx[valid], vec[valid, k])
    return vec, err.mask


def split(vec: np.ndarray, rate: float, period_s: float) -> tuple[np.ndarray, np.ndarray]:
    sos = butter(2, 1.0 / period_s, fs=rate, output="sos")
    slow = sosfiltfilt(sos, vec, axis=0)
    return slow, vec - slow


def rms(x: np.ndarray, mask: np.ndarray) -> float:
    return float(np.degrees(np.sqrt(np.mean(np.sum(x[mask] ** 2, axis=-1)))))


def diagnose(trs: Sequence[Trial], period_s: float) -> None:
    runners: dict[str, Runner] = {
        "Robust online": robust_runner(False),
        "VQF": vqf_runner(False),
        "Robust offline": robust_runner(True),
        "offlineVQF": vqf_runner(True),
    }
    print(
        f"\n### Tilt error split at a {period_s:g} s period (RMS over movement samples with mocap) [°]\n\n"
        "| filter | trial | incl. RMSE | slow | fast | √(slow²+fast²) | corr(‖δθ‖, ‖ω‖) | corr(‖δθ_fast‖, ‖ω‖) |\n"
        "|---|---|---|---|---|---|---|---|"
    )
    summary: dict[str, dict[str, tuple[float, float, float]]] = {}
    for name, run in runners.items():
        summary[name] = {}
        for tr in trs:
            q = run(tr, False)
            vec, mask = tilt_vector(q, tr)
            slow, fast = split(vec, tr.rate, period_s)
            incl = ik.eval.attitude_error(q, tr.truth, scalar_first=True, align_heading=True, mask=tr.movement).rmse(
                degrees=True
            )
            w = np.linalg.norm(tr.gyr, axis=1)[mask]
            c_all = float(np.corrcoef(np.linalg.norm(vec[mask], axis=1), w)[0, 1])
            c_fast = float(np.corrcoef(np.linalg.norm(fast[mask], axis=1), w)[0, 1])
            s, f = rms(slow, mask), rms(fast, mask)
            summary[name][tr.name] = (incl.inclination, s, f)
            print(
                f"| {name} | {tr.name[:2]} | {incl.inclination:.3f} | {s:.3f} | {f:.3f} | {np.hypot(s, f):.3f} "
                f"| {c_all:+.2f} | {c_fast:+.2f} |",
                flush=True,
            )
    print("\n### Means (per group and over the 12): incl. RMSE / slow / fast [°]\n")
    print("| filter | " + " | ".join(GROUPS) + " | mean |\n" + "|---" * (len(GROUPS) + 2) + "|")
    for name, per in summary.items():
        cells = []
        for g in [*GROUPS, None]:
            vals = np.array([v for n, v in per.items() if g is None or group_of(n) == g])
            cells.append(" / ".join(f"{m:.3f}" for m in vals.mean(0)))
        print(f"| {name} | " + " | ".join(cells) + " |")


def group_of(name: str) -> str:
    return next(g for g, names in GROUPS.items() if name in names)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--diagnose", action="store_true", help="slow / fast split of the tilt error")
    parser.add_argument("--split-s", type=float, default=5.0, help="period splitting slow from fast [s]")
    args = parser.parse_args()
    trs = trials()
    if args.diagnose:
        diagnose(trs, args.split_s)


if __name__ == "__main__":
    main()
