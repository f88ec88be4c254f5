"""BROAD's inclination error against the time at which the motion capture is read: each filter's
estimate at IMU sample k scored against the reference slerped at sample ``k + s`` (``s`` in
samples, 1/286 s each), for imukit ``Robust`` (online, offline) and vqf ``VQF`` / ``offlineVQF`` at
their defaults on the 12 trials in ``../shared/data/broad`` (the metric of
``bench/broad_accuracy.py``: 6D inclination RMSE over the ``movement`` samples, heading offset
removed). A diagnostic of the reference, not a tuning: the filters are not changed.

Usage: ``python bench/broad_time_offset.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik
import robust_tune as rt
from broad_accuracy import Trial

GRID = [-1.5, -1.0, -0.75, -0.6, -0.5, -0.4, -0.25, 0.0, 0.5]


def truth_at(tr: Trial, s: float) -> np.ndarray:
    """The reference quaternions (w first, NaN where missing) slerped at fractional sample k + s:
    ``ik.eval.associate`` with the offset ``s`` samples, interpolating only between neighbouring
    mocap samples (a dropout is not bridged). At a whole ``s`` a stamp that lands on a mocap
    sample is kept even when the next one is missing, and rounding of ``(k + s) / rate`` may move
    a stamp off it: up to 13 movement samples a trial differ from a slerp by index, which moves
    the table's means by 1–2e-5° (the printed three decimals are unchanged)."""
    q = tr.truth
    t = np.arange(len(q)) / tr.rate
    ok = np.all(np.isfinite(q), axis=1)
    reference = ik.Trajectory(t[ok], np.zeros((ok.sum(), 3)), None, Rotation.from_quat(q[ok], scalar_first=True))
    samples = ik.Trajectory(t, np.zeros((len(q), 3)), None, Rotation.identity(len(q)))
    pairs = ik.eval.associate(samples, reference, offset=s / tr.rate, max_dt=1.5 / tr.rate)
    out = np.full_like(q, np.nan)
    out[pairs.mask] = pairs.reference.rotation.as_quat(scalar_first=True)
    return out


def main() -> None:
    trs = rt.trials()
    runners = {
        "Robust online": rt.robust_runner(False),
        "Robust offline": rt.robust_runner(True),
        "VQF": rt.vqf_runner(False),
        "offlineVQF": rt.vqf_runner(True),
    }
    est = {name: [r(tr, False) for tr in trs] for name, r in runners.items()}
    print("| reference at sample k + s | " + " | ".join(runners) + " |")
    print("|---" * (len(runners) + 1) + "|")
    scores: dict[str, list[list[float]]] = {name: [] for name in runners}
    for s in GRID:
        refs = [truth_at(tr, s) for tr in trs]
        cells = []
        for name in runners:
            vals = []
            for tr, q, ref in zip(trs, est[name], refs):
                mask = tr.movement & np.all(np.isfinite(ref), axis=1)
                err = ik.eval.attitude_error(q, ref, scalar_first=True, align_heading=True, mask=mask, world="ENU")
                vals.append(float(err.rmse(degrees=True).inclination))
            scores[name].append(vals)
            cells.append(f"{np.mean(vals):.3f}")
        print(f"| {s:+.2f} | " + " | ".join(cells) + " |")
    best = np.array(scores["Robust offline"]).argmin(axis=0)
    print(
        "best s per trial (Robust offline): " + ", ".join(f"{tr.name[:2]} {GRID[i]:+.2f}" for tr, i in zip(trs, best))
    )


if __name__ == "__main__":
    main()
