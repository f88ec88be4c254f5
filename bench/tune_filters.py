"""Coarse grid search of imukit's default filter parameters on the shared BROAD trials.

Usage: ``python bench/tune_filters.py [--data ../shared/data/broad]`` (a few minutes).

Metric: that of ``bench/broad_accuracy.py`` (RMSE during movement; 6D with the constant heading
offset removed, 9D as estimated), mean over the 3 trials. Objective (lower is better), one parameter
set per filter for 6D and 9D together::

    J = mean 6D inclination RMSE + mean 9D total RMSE

(the two accuracy criteria of issue 7). A full coarse grid over the gains and the
acceleration-rejection thresholds (``norm`` [m/s²], ``angle``; None: no rejection), every point
printed so that the sensitivity is visible, then the best points and the rank of the current
defaults. The defaults are not simply the argmin: see docs/filters.md (physically sensible values,
a rejection that still rejects, an integral gain that still estimates the bias).
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

import imukit as ik
from imukit import filters

sys.path.insert(0, str(Path(__file__).resolve().parent))
from broad_accuracy import DATA, TRIALS, Trial, load

KP = [0.3, 0.5, 1.0, 2.0]  # Mahony k_P [1/s]
KI = [0.0, 0.003, 0.01, 0.03, 0.1]  # Mahony k_I [1/s²]
BETA = [0.02, 0.041, 0.05, 0.07, 0.1, 0.2]  # Madgwick β [1/s]
NORMS = [1.0, 2.0, 4.0]  # rejection |‖a‖ − g| threshold [m/s²]
ANGLES = [10.0, 20.0, 30.0, 45.0]  # rejection angle threshold [°]


def evaluate(cls: Any, trials: list[Trial], **kw: Any) -> tuple[float, float, float]:
    """(J, mean 6D inclination, mean 9D total) for filter ``cls(**kw)``."""
    inc6, tot9 = [], []
    for tr in trials:
        imu = ik.ImuData(np.arange(len(tr.gyr)) / tr.rate, tr.gyr, tr.acc)
        for nine in (False, True):
            q = cls(**kw).run(imu, mag=tr.mag if nine else None).rotation.as_quat(scalar_first=True)
            e = ik.eval.attitude_error(
                q, tr.truth, scalar_first=True, align_heading=not nine, mask=tr.movement, world="ENU"
            ).rmse(degrees=True)
            (tot9 if nine else inc6).append(e.total if nine else e.inclination)
    a, b = float(np.mean(inc6)), float(np.mean(tot9))
    return a + b, a, b


def grid(cls: Any, trials: list[Trial], axes: dict[str, list[Any]]) -> list[tuple[float, float, float, str]]:
    """Evaluates every point of the product of ``axes``; prints and returns ``(J, 6D incl, 9D total, point)``."""
    out = []
    for values in itertools.product(*axes.values()):
        kw = dict(zip(axes, values, strict=True))
        j, a, b = evaluate(cls, trials, **kw)
        shown = ", ".join(f"{k}={_fmt(v)}" for k, v in kw.items())
        print(f"  {cls.__name__:8s} {shown:50s} J={j:6.2f}  6D incl={a:5.2f}  9D total={b:5.2f}", flush=True)
        out.append((j, a, b, shown))
    return out


def _fmt(v: Any) -> str:
    if v is None:
        return "None"
    if isinstance(v, filters.AccelRejection):
        return f"({v.norm:g} m/s², {math.degrees(v.angle_rad):g}°)"
    return f"{v:g}" if isinstance(v, float) else str(v)


def summary(name: str, results: list[tuple[float, float, float, str]], chosen: str) -> None:
    ranked = sorted(results)
    print(f"\n{name}: best 8 of {len(ranked)}")
    for j, a, b, shown in ranked[:8]:
        print(f"  J={j:5.2f}  6D incl={a:5.2f}  9D total={b:5.2f}  {shown}")
    rank = next(i for i, r in enumerate(ranked) if r[3] == chosen)
    j, a, b, _ = ranked[rank]
    print(f"  default ({chosen}): J={j:.2f} (6D incl {a:.2f}, 9D total {b:.2f}), rank {rank + 1}\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA, help="folder of the BROAD .mat files (default: %(default)s)")
    args = parser.parse_args()
    trials = [load(args.data / f"{name}.mat") for name in TRIALS]
    rej = [None, *(filters.AccelRejection(norm=n, angle_rad=math.radians(a)) for n in NORMS for a in ANGLES)]
    default_rej = f"acc_rejection={_fmt(filters.AccelRejection())}"
    print("Mahony")
    m = grid(filters.Mahony, trials, {"kp": KP, "ki": KI, "acc_rejection": rej})
    print("Madgwick")
    g = grid(filters.Madgwick, trials, {"beta": BETA, "acc_rejection": rej})
    d_m, d_g = filters.Mahony(), filters.Madgwick()
    summary("Mahony", m, f"kp={_fmt(d_m.kp)}, ki={_fmt(d_m.ki)}, {default_rej}")
    summary("Madgwick", g, f"beta={_fmt(d_g.beta)}, {default_rej}")


if __name__ == "__main__":
    main()
