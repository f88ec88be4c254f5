"""Score and tune ``imukit.filters.Robust`` on the BROAD trials in ``../shared/data/broad``, next to
vqf in the same run, with leave-one-group-out cross-validation, and time it against vqf.

Usage::

    python bench/robust_tune.py                       # per-trial and per-group table, online + offline, vs vqf
    python bench/robust_tune.py --set tau_acc_s=2.5   # the same with parameters changed
    python bench/robust_tune.py --cv                  # grid search: all-trials and leave-one-group-out scores
    python bench/robust_tune.py --cv --grid field     # the same over the magnetic thresholds
    python bench/robust_tune.py --cv --grid filter --grid bias_motion  # two grids' product
    python bench/robust_tune.py --speed               # 10^6 samples: Robust vs vqf.VQF.updateBatch / offlineVQF
    python bench/robust_tune.py --field               # the field seen through the true attitude, per trial

Metric as ``bench/broad_accuracy.py``: :func:`imukit.eval.attitude_error` over the ``movement``
samples with mocap; 6D inclination RMSE with the heading offset removed, 9D total RMSE as estimated.
"""

from __future__ import annotations

import argparse
import itertools
import time
from collections.abc import Callable, Sequence

import numpy as np

import imukit as ik
from broad_accuracy import DATA, Trial, load

GROUPS: dict[str, tuple[str, ...]] = {
    "rotation": ("01", "03", "06", "08"),
    "translation": ("10", "12", "18"),
    "tapping+vibration": ("24", "27"),
    "magnets": ("28", "32", "34"),
}
# The grids of --cv (--grid NAME): each parameter's candidates (the default among them).
GRIDS: dict[str, dict[str, tuple[float, ...]]] = {
    "filter": {
        "tau_acc_s": (2.0, 3.0),
        "tau_mag_s": (9.0, 20.0),
        "bias_window_s": (1.0, 2.0, 4.0),
        "bias_forgetting_s": (1600.0, 16000.0),  # the random walks of 100 s (VQF's) and 1000 s at σ_init 0.5 °/s
    },
    # The magnetic thresholds (9D only: 6D does not change).
    "field": {
        "tau_mag_s": (9.0, 14.0, 20.0),
        "mag_dip_rad": tuple(np.radians([10.0, 15.0, 25.0])),
        "mag_norm_fraction": (0.1, 0.15),
    },
    # Rest detection (issue 15: rest under vibration).
    "rest": {
        "rest_noise_tau_s": (0.02, 0.05, 0.1),
        "rest_gyro_rad_s": tuple(float(x) for x in np.radians([1.0, 2.0, 3.0])),
        "rest_accel": (0.25, 0.5),
    },
    # Bias updates in motion (issue 15: offline 9D); 100 °/s switches them off in effect.
    "bias_motion": {
        "bias_sigma_motion_rad_s": tuple(float(x) for x in np.radians([0.2, 0.5, 2.0, 100.0])),
    },
    "dip": {
        "tau_mag_s": (14.0, 20.0),
        "mag_dip_rad": tuple(np.radians([20.0, 25.0, 35.0, 45.0])),
        "mag_norm_fraction": (0.1, 0.15),
    },
}
Runner = Callable[[Trial, bool], np.ndarray]


def trials() -> list[Trial]:
    return [load(p) for p in sorted(DATA.glob("*.mat"))]


def group(tr: Trial) -> str:
    return next(g for g, ids in GROUPS.items() if tr.name[:2] in ids)


def robust_runner(offline: bool, **params: float) -> Runner:
    f = ik.filters.Robust(**params)

    def run(tr: Trial, nine: bool) -> np.ndarray:
        imu = ik.ImuData(np.arange(len(tr.gyr)) / tr.rate, tr.gyr, tr.acc)
        res = f.run(imu, mag=tr.mag if nine else None, offline=offline)
        return np.asarray(res.rotation.as_quat(scalar_first=True))

    return run


def vqf_runner(offline: bool) -> Runner:
    import vqf  # type: ignore[import-untyped]

    def run(tr: Trial, nine: bool) -> np.ndarray:
        if offline:
            out = vqf.offlineVQF(tr.gyr, tr.acc, tr.mag if nine else None, 1.0 / tr.rate)
        else:
            f = vqf.VQF(1.0 / tr.rate)
            out = f.updateBatch(tr.gyr, tr.acc, tr.mag) if nine else f.updateBatch(tr.gyr, tr.acc)
        return np.asarray(out["quat9D" if nine else "quat6D"])

    return run


def score(run: Runner, trs: Sequence[Trial], nine: bool) -> dict[str, float]:
    """Per trial: 6D inclination RMSE (heading offset removed) or 9D total RMSE [°]."""
    out = {}
    for tr in trs:
        q = run(tr, nine)
        err = ik.eval.attitude_error(
            q, tr.truth, scalar_first=True, align_heading=not nine, mask=tr.movement, world="ENU"
        )
        rmse = err.rmse(degrees=True)
        out[tr.name] = float(rmse.total if nine else rmse.inclination)
    return out


def table(rows: dict[str, dict[str, float]], trs: Sequence[Trial]) -> None:
    cols = list(rows)
    print("| trial | " + " | ".join(cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    for tr in trs:
        print(f"| {tr.name} | " + " | ".join(f"{rows[c][tr.name]:.2f}" for c in cols) + " |")
    for g in GROUPS:
        names = [tr.name for tr in trs if group(tr) == g]
        print(f"| **{g}** | " + " | ".join(f"{np.mean([rows[c][n] for n in names]):.2f}" for c in cols) + " |")
    print("| **mean** | " + " | ".join(f"{np.mean(list(rows[c].values())):.2f}" for c in cols) + " |")


def report(trs: list[Trial], params: dict[str, float], with_vqf: bool) -> None:
    for nine in (False, True):
        rows = {}
        for offline in (False, True):
            rows[f"Robust {'offline' if offline else 'online'}"] = score(robust_runner(offline, **params), trs, nine)
            if with_vqf:
                rows["offlineVQF" if offline else "VQF"] = score(vqf_runner(offline), trs, nine)
        print(f"\n### {'9D total' if nine else '6D inclination'} RMSE [°]\n")
        table(rows, trs)


def objective(s6: dict[str, float], s9: dict[str, float]) -> float:
    """One number to minimise: mean 6D inclination + mean 9D total / 4 (the 9D errors are about
    four times larger, so each counts about equally)."""
    return float(np.mean(list(s6.values())) + np.mean(list(s9.values())) / 4.0)


def cross_validate(trs: list[Trial], offline: bool, grid: dict[str, tuple[float, ...]]) -> None:
    """Grid search over ``grid``; the best on all trials, and for each group the best on the other
    three scored on the held-out group."""
    keys = list(grid)
    results = []
    for values in itertools.product(*(grid[k] for k in keys)):
        params = dict(zip(keys, values, strict=True))
        run = robust_runner(offline, **params)
        results.append((params, score(run, trs, False), score(run, trs, True)))
        m6, m9 = np.mean(list(results[-1][1].values())), np.mean(list(results[-1][2].values()))
        print(f"  {params}: 6D {m6:.3f}, 9D {m9:.3f}", flush=True)

    def best(names: set[str]) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
        def sub(d: dict[str, float]) -> dict[str, float]:
            return {k: v for k, v in d.items() if k in names}

        return min(results, key=lambda r: objective(sub(r[1]), sub(r[2])))

    mode = "offline" if offline else "online"
    p, s6, s9 = best({tr.name for tr in trs})
    print(f"\n### {mode}: tuned on all 12: {p}")
    print(f"all trials: 6D {np.mean(list(s6.values())):.3f}°, 9D {np.mean(list(s9.values())):.3f}°")
    print(
        "\n| held-out group | chosen on the other three | 6D incl. held out | 9D total held out "
        "| 6D (all-trials choice) | 9D (all-trials choice) |"
    )
    print("|---|---|---|---|---|---|")
    cv6, cv9 = {}, {}
    for g in GROUPS:
        held = {tr.name for tr in trs if group(tr) == g}
        pg, g6, g9 = best({tr.name for tr in trs} - held)
        cv6.update({k: g6[k] for k in held})
        cv9.update({k: g9[k] for k in held})
        short = ", ".join(f"{k}={v:.4g}" for k, v in pg.items())
        print(
            f"| {g} | {short} | {np.mean([g6[k] for k in held]):.3f} | {np.mean([g9[k] for k in held]):.3f} "
            f"| {np.mean([s6[k] for k in held]):.3f} | {np.mean([s9[k] for k in held]):.3f} |"
        )
    means = [np.mean(list(d.values())) for d in (cv6, cv9, s6, s9)]
    print("| **all, leave-one-group-out** | | " + " | ".join(f"{m:.3f}" for m in means) + " |")


def speed(n: int = 1_000_000, repeat: int = 3) -> None:
    """Median wall time of 10^6 samples (BROAD trials tiled), Robust vs vqf, same run."""
    import vqf

    if DATA.is_dir():
        tr = trials()[0]
        reps = -(-n // len(tr.gyr))
        gyr, acc, mag = (np.ascontiguousarray(np.tile(x, (reps, 1))[:n]) for x in (tr.gyr, tr.acc, tr.mag))
        rate = tr.rate
    else:  # a machine without the shared data: a turning sensor at rest, simulated
        rate = 285.714
        t = np.arange(n) / rate
        gyr = np.stack([0.4 * np.sin(0.7 * t), 0.3 * np.sin(0.5 * t), 0.5 * np.cos(0.3 * t)], 1)
        acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + 0.01 * np.sin(t)[:, None]
        mag = np.tile([0.0, 20.0, -40.0], (n, 1)) + 0.1 * np.cos(t)[:, None]
    print(f"data: {'BROAD trial 01 tiled' if DATA.is_dir() else 'simulated'}, {rate} Hz")
    imu = ik.ImuData(np.arange(n) / rate, gyr, acc)
    f = ik.filters.Robust()
    cases: dict[str, Callable[[], object]] = {
        "Robust online 6D": lambda: f.run(imu),
        "Robust online 9D": lambda: f.run(imu, mag=mag),
        "Robust offline 6D": lambda: f.run(imu, offline=True),
        "Robust offline 9D": lambda: f.run(imu, mag=mag, offline=True),
        "vqf.VQF.updateBatch 6D": lambda: vqf.VQF(1 / rate).updateBatch(gyr, acc),
        "vqf.VQF.updateBatch 9D": lambda: vqf.VQF(1 / rate).updateBatch(gyr, acc, mag),
        "vqf.offlineVQF 6D": lambda: vqf.offlineVQF(gyr, acc, None, 1 / rate),
        "vqf.offlineVQF 9D": lambda: vqf.offlineVQF(gyr, acc, mag, 1 / rate),
    }
    times = {}
    for name, call in cases.items():
        ts = []
        for _ in range(repeat):
            start = time.perf_counter()
            call()
            ts.append(time.perf_counter() - start)
        times[name] = float(np.median(ts))
    print(f"\n### Speed, {n} samples, median of {repeat} [s]\n")
    print("| case | time [s] | ns/sample | vqf / Robust |\n|---|---|---|---|")
    for name, t in times.items():
        ref = ""
        if name.startswith("Robust"):
            peer = ("vqf.offlineVQF " if "offline" in name else "vqf.VQF.updateBatch ") + name[-2:]
            ref = f"{times[peer] / t:.1f}×"
        print(f"| {name} | {t:.3f} | {1e9 * t / n:.0f} | {ref} |")


def field_report(trs: list[Trial]) -> None:
    """Per trial, the field seen through the motion capture's attitude, ``m_w = R_truth m``: the
    heading of its horizontal part from mocap north (what a filter following the magnetometer
    cannot avoid), per sixth of the trial, and a hard-iron fit ``m = Rᵀ m_w + h`` (least squares
    for ``m_w`` and ``h``; its condition number says whether the record turns enough to tell them
    apart)."""
    from scipy.spatial.transform import Rotation

    def heading(m: np.ndarray) -> np.ndarray:
        return np.degrees(np.arctan2(m[:, 0], m[:, 1]))

    print(
        "| trial | heading of m_w [°] mean ± std | per sixth [°] | attitude spread, median [°] "
        "| h [µT] | residual without / with h [µT] | condition | heading with h removed [°] |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for tr in trs:
        ok = np.isfinite(tr.truth).all(1) & tr.movement
        rot = Rotation.from_quat(tr.truth[ok], scalar_first=True)
        m = tr.mag[ok]
        head = heading(rot.apply(m))
        n = len(m)
        a = np.zeros((3 * n, 6))
        a[:, :3] = rot.inv().as_matrix().reshape(3 * n, 3)
        a[:, 3:] = np.tile(np.eye(3), (n, 1))
        x, *_ = np.linalg.lstsq(a, m.ravel(), rcond=None)
        x0, *_ = np.linalg.lstsq(a[:, :3], m.ravel(), rcond=None)
        res = [float(np.sqrt(np.mean((m.ravel() - a[:, : k.size] @ k) ** 2))) for k in (x0, x)]
        sv = np.linalg.svd(a, compute_uv=False)
        spread = np.degrees((rot.mean().inv() * rot).magnitude())
        sixths = ", ".join(f"{np.mean(c):.1f}" for c in np.array_split(head, 6))
        print(
            f"| {tr.name} | {head.mean():.2f} ± {head.std():.2f} | {sixths} | {np.median(spread):.0f} "
            f"| {np.array2string(x[3:], precision=2)} | {res[0]:.2f} / {res[1]:.2f} | {sv[0] / sv[-1]:.1f} "
            f"| {heading(rot.apply(m - x[3:])).mean():.2f} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--set", action="append", default=[], help="parameter=value (repeatable)")
    parser.add_argument("--no-vqf", action="store_true", help="leave vqf out of the table")
    parser.add_argument("--cv", action="store_true", help="grid search with leave-one-group-out scores")
    parser.add_argument("--offline", action="store_true", help="with --cv: tune the smoother")
    parser.add_argument(
        "--grid", choices=sorted(GRIDS), action="append", help="with --cv: which grid (repeat: their product)"
    )
    parser.add_argument("--speed", action="store_true", help="timing, 10^6 samples")
    parser.add_argument("--field", action="store_true", help="the field through the true attitude, per trial")
    args = parser.parse_args()
    params = {k: float(v) for k, v in (s.split("=", 1) for s in args.set)}
    if args.speed:
        speed()
        return
    trs = trials()
    if args.field:
        field_report(trs)
    elif args.cv:
        cross_validate(trs, args.offline, {k: v for g in args.grid or ["filter"] for k, v in GRIDS[g].items()})
    else:
        report(trs, params, not args.no_vqf)


if __name__ == "__main__":
    main()
