"""Issue 15: does a bounded-motion constraint (position and velocity stay small) beat the
velocity-over-τ assumption of ``imukit.filters.Robust`` (and VQF) on BROAD's inclination?

Usage (answer and numbers: docs/filters_robust.md, "a bounded-motion constraint")::

    python bench/robust_bounded.py --diagnose      # Robust's (and VQF's) tilt error: slow / fast split
    python bench/robust_bounded.py                 # per trial: Robust, + bounds, VQF (online, offline)
    python bench/robust_bounded.py --oracle        # the same plus the mocap positions in place of the bounds
    python bench/robust_bounded.py --set sigma_p=1 --set q_theta=0.01   # parameters (q_theta in (°)²/s)
    python bench/robust_bounded.py --cv [--offline]  # GRID: all trials and leave one group out
    python bench/robust_bounded.py --euroc         # the EuRoC excerpt
    python bench/robust_bounded.py --motion        # the mocap's position and velocity spread
    python bench/robust_bounded.py --misalign      # a constant rotation fitted per trial (oracle)

The prototype (:func:`reduce`, :func:`kalman`, :func:`correct`) is an error-state Kalman filter
with an RTS smoother on Robust's attitude, 6D only, NumPy, at 25 Hz.

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
import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import partial

import numpy as np
from scipy.io import loadmat
from scipy.optimize import OptimizeResult, minimize
from scipy.signal import butter, sosfiltfilt
from scipy.spatial.transform import Rotation

import imukit as ik
from broad_accuracy import DATA, GROUPS, Trial, euroc_trial
from robust_tune import Runner, robust_runner, score, table, trials, vqf_runner


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


G = 9.80665  # m/s²: the nominal gravity; the filter estimates the offset
UP = np.array([0.0, 0.0, 1.0])
# The state: c = [δθ_x, δθ_y, b_a (3), δg, s_a (3)] (constants, NC of them), v, p, lever arm.
NC = 9
NX = NC + 9
C, V, P, L = slice(0, NC), slice(NC, NC + 3), slice(NC + 3, NC + 6), slice(NC + 6, NX)


@dataclass(frozen=True)
class Bounded:
    """The bounded-motion filter's parameters (SI, angles in rad). A bias state with zero prior
    and zero random walk stays zero: ``sigma_bias0=0, q_bias=0`` switches it off. The defaults
    are ``--cv``'s online choice on all 12 trials."""

    rate_hz: float = 25.0  # the filter's rate (inputs integrated over ``round(rate / rate_hz)`` samples)
    sigma_p: float = 0.3  # m: spread of each position axis about its mean (the room)
    tau_p: float = 10.0  # s: its correlation time
    sigma_v: float = 1e3  # m/s (1e3: in effect off)
    tau_v: float = 1.0  # s
    q_theta: float = float(np.radians(0.03) ** 2)  # rad²/s: random walk of the tilt error
    q_acc: float = 0.03  # m²/s³: white world-acceleration error (noise and Robust's fast tilt error)
    q_bias: float = 1e-6  # (m/s²)²/s: random walk of the accelerometer bias and the gravity offset
    sigma_zupt: float = 0.01  # m/s: velocity at Robust's rest
    sigma_theta0: float = float(np.radians(1.0))
    sigma_bias0: float = 0.1  # m/s²: accelerometer bias and gravity offset, prior
    sigma_scale0: float = 0.0  # accelerometer scale factors (constant), prior; 0: off
    sigma_v0: float = 0.05  # m/s
    sigma_p0: float = 0.05  # m


@dataclass(frozen=True)
class Steps:
    """Robust's attitude and the accelerometer reduced to the filter's intervals
    ``start[k]:end[k]``: the kinematic sums of ``v_{k+1} = v_k + sv + jv c``,
    ``p_{k+1} = p_k + T v_k + sp + jp c`` (``c`` as in ``NC``) and whether Robust
    flagged every sample of the interval rest."""

    start: np.ndarray
    end: np.ndarray
    dt: np.ndarray  # (K,) s
    sv: np.ndarray  # (K, 3)
    sp: np.ndarray  # (K, 3)
    jv: np.ndarray  # (K, 3, NC)
    jp: np.ndarray  # (K, 3, NC)
    rest: np.ndarray  # (K,) bool
    rot_end: np.ndarray  # (K, 3, 3): R̂ at each interval's last sample


def reduce(rot: Rotation, acc: np.ndarray, rest: np.ndarray, rate: float, out_rate: float) -> Steps:
    """With the true attitude ``R = Exp(δθ) R̂``, ``δθ = (δθ_x, δθ_y, 0)`` in the world frame, and
    ``f = f_m − b_a − diag(f_m) s_a``, the world acceleration to first order is
    ``ẍ = R̂ f_m − (g + δg) e_z + δθ × (R̂ f_m) − R̂ b_a − R̂ diag(f_m) s_a`` (Groves 2013, §14.2's attitude-error
    coupling ``−[R̂ f]× δθ``). Integrated sample by sample (``v_j = v_{j−1} + ẍ_j dt``,
    ``p_j = p_{j−1} + v_j dt``) over an interval of ``M`` samples with ``c`` constant, sample
    ``i`` enters ``v`` with weight ``dt`` and ``p`` with ``(end − i) dt²``."""
    n = len(acc)
    m = max(1, round(rate / out_rate))
    dt = 1.0 / rate
    start = np.arange(0, n, m)
    end = np.minimum(start + m, n)
    a = rot.apply(acc)
    b = np.zeros((n, 3, NC))
    b[:, 0, 1], b[:, 1, 0] = (a[:, 2], -a[:, 2])  # −[a]× e_x, −[a]× e_y: the first two columns
    b[:, 2, 0], b[:, 2, 1] = a[:, 1], -a[:, 0]
    b[:, :, 2:5] = -rot.as_matrix()
    b[:, 2, 5] = -1.0
    b[:, :, 6:9] = -rot.as_matrix() * acc[:, None, :]  # −R̂ diag(f_m)
    u = np.concatenate([a - G * UP, b.reshape(n, 3 * NC)], axis=1)
    w = (np.repeat(end, end - start) - np.arange(n)) * dt**2
    sv = np.add.reduceat(u * dt, start, axis=0)
    sp = np.add.reduceat(u * w[:, None], start, axis=0)
    return Steps(
        start,
        end,
        (end - start) * dt,
        sv[:, :3],
        sp[:, :3],
        sv[:, 3:].reshape(-1, 3, NC),
        sp[:, 3:].reshape(-1, 3, NC),
        np.logical_and.reduceat(rest, start),
        rot[end - 1].as_matrix(),
    )


def kalman(st: Steps, par: Bounded, smooth: bool, oracle: np.ndarray | None = None) -> np.ndarray:
    """The tilt error ``(K, 2)`` at each interval's end: the forward filter's, or RTS-smoothed
    (Rauch, Tung & Striebel, AIAA J. 3 (1965)). States ``[c (NC), v (3), p (3), r (3)]``; ``c``
    random walks, ``v, p`` driven by a white acceleration error. The bounded motion enters as
    pseudo-measurements ``0 = v + n_v``, ``0 = p + n_p`` at every step: an Ornstein–Uhlenbeck
    process of variance σ² and time constant τ has the low-frequency power density ``2σ²τ``, so
    it is taken as white noise of that density (variance ``2σ²τ/T`` per step of ``T`` s): a
    repeated pseudo-measurement then weighs as much per second at any filter rate, and only
    ``σ²τ`` matters. At Robust's rest ``v = 0`` with ``σ_zupt`` (a ZUPT, Foxlin 2005).

    ``oracle`` (``(K, 3)``, NaN where missing): the motion capture's positions at the interval
    ends replace the bounds, ``z = p − R̂ r`` with 1 cm noise and ``r`` the lever arm from the IMU
    to the markers' origin (body frame, constant, estimated): what the best position aid reaches.
    """
    n_k = len(st.dt)
    eye = np.eye(NX)
    x = np.zeros(NX)
    lever0 = 0.0 if oracle is None else 0.1
    p = np.diag(
        np.array(
            [par.sigma_theta0] * 2
            + [par.sigma_bias0] * 4
            + [par.sigma_scale0] * 3
            + [par.sigma_v0] * 3
            + [par.sigma_p0] * 3
            + [lever0] * 3
        )
        ** 2
    )
    if oracle is not None:
        x[P] = oracle[np.isfinite(oracle).all(1)][0]  # the first fix: the start is at rest
    q_c = np.diag([par.q_theta] * 2 + [par.q_bias] * 4 + [0.0] * 3)
    xs_f, ps_f, xs_p, ps_p, fs = (np.zeros((n_k, NX)), np.zeros((n_k, NX, NX)), [], [], [])
    for k in range(n_k):
        t = st.dt[k]
        f = eye.copy()
        f[V, C] = st.jv[k]
        f[P, C] = st.jp[k]
        f[P, V] = t * np.eye(3)
        q = np.zeros((NX, NX))
        q[C, C] = q_c * t
        q[V, V] = par.q_acc * t * np.eye(3)
        q[V, P] = q[P, V] = par.q_acc * t**2 / 2 * np.eye(3)
        q[P, P] = par.q_acc * t**3 / 3 * np.eye(3)
        x = f @ x
        x[V] += st.sv[k]
        x[P] += st.sp[k]
        p = f @ p @ f.T + q
        if smooth:
            xs_p.append(x.copy())
            ps_p.append(p.copy())
            fs.append(f)
        h, z, r = measurement(st, par, k, oracle)
        if len(z):
            s = h @ p @ h.T + np.diag(r)
            gain = np.linalg.solve(s, h @ p).T
            x = x + gain @ (z - h @ x)
            p = p - gain @ s @ gain.T
            p = (p + p.T) / 2
        xs_f[k], ps_f[k] = x, p
    if not smooth:
        return xs_f[:, :2]
    xs = xs_f.copy()
    for k in range(n_k - 2, -1, -1):
        # pinv: a state switched off (zero prior, zero noise) makes P⁻ singular
        c = ps_f[k] @ fs[k + 1].T @ np.linalg.pinv(ps_p[k + 1], hermitian=True)
        xs[k] = xs_f[k] + c @ (xs[k + 1] - xs_p[k + 1])
    return xs[:, :2]


def measurement(
    st: Steps, par: Bounded, k: int, oracle: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step ``k``'s ``H``, ``z`` and noise variances (see :func:`kalman`)."""
    rows, z, r = [], [], []
    v_var = par.sigma_zupt**2 if st.rest[k] else 2 * par.sigma_v**2 * par.tau_v / st.dt[k]
    if oracle is None or st.rest[k]:
        rows.append(np.eye(3, NX, V.start))
        z.append(np.zeros(3))
        r += [v_var] * 3
    if oracle is None:
        rows.append(np.eye(3, NX, P.start))
        z.append(np.zeros(3))
        r += [2 * par.sigma_p**2 * par.tau_p / st.dt[k]] * 3
    elif np.isfinite(oracle[k]).all():
        h = np.eye(3, NX, P.start)
        h[:, L] = -st.rot_end[k]
        rows.append(h)
        z.append(oracle[k])
        r += [1e-4] * 3
    if not rows:
        return np.zeros((0, NX)), np.zeros(0), np.zeros(0)
    return np.vstack(rows), np.concatenate(z), np.array(r)


def correct(rot: Rotation, st: Steps, dtheta: np.ndarray, causal: bool) -> Rotation:
    """``Exp(δθ) R̂`` at full rate: causal, each interval uses the estimate after the one before
    (zero in the first); otherwise ``δθ`` interpolated linearly between the interval ends."""
    n = len(rot)
    if causal:
        held = np.vstack([np.zeros((1, 2)), dtheta[:-1]])
        d = np.repeat(held, st.end - st.start, axis=0)
    else:
        d = np.stack([np.interp(np.arange(n), st.end - 1, dtheta[:, i]) for i in range(2)], axis=1)
    return Rotation.from_rotvec(np.column_stack([d, np.zeros(n)])) * rot


_BASE: dict[tuple[str, bool], tuple[Rotation, np.ndarray]] = {}


def robust_base(tr: Trial, offline: bool) -> tuple[Rotation, np.ndarray]:
    """Robust's 6D attitude and rest flags (cached: the bounded filter's grid reruns only itself)."""
    key = (tr.name, offline)
    if key not in _BASE:
        imu = ik.ImuData(np.arange(len(tr.gyr)) / tr.rate, tr.gyr, tr.acc)
        res = ik.filters.Robust().run(imu, offline=offline)
        _BASE[key] = (res.rotation, np.asarray(res.rest, bool))
    return _BASE[key]


def bounded_runner(offline: bool, par: Bounded, oracle: bool = False) -> Runner:
    """Robust (online: forward filter on the online attitude; offline: forward filter and RTS on
    the smoothed attitude), corrected by the bounded-motion filter; ``oracle``: by the motion
    capture's positions instead of the bounds."""

    def run(tr: Trial, nine: bool) -> np.ndarray:
        if nine:
            raise ValueError("the bounded-motion prototype is 6D only")
        rot, rest = robust_base(tr, offline)
        st = reduce(rot, tr.acc, rest, tr.rate, par.rate_hz)
        pos = mocap_positions(tr, rot)[st.end - 1] if oracle else None
        out = correct(rot, st, kalman(st, par, smooth=offline, oracle=pos), causal=not offline)
        return np.asarray(out.as_quat(scalar_first=True))

    return run


def mocap_positions(tr: Trial, rot: Rotation) -> np.ndarray:
    """BROAD's ``opt_pos`` [m] turned into the estimate's world, NaN where the mocap dropped out.
    The 6D heading drifts (trial 08: 7.9° std), so the turn is per sample: the heading offset
    ``δ`` and the remaining signed heading error ``ψ`` (``R_truth ≈ Rz(δ + ψ) R̂``) removed."""
    pos = np.asarray(loadmat(DATA / f"{tr.name}.mat")["opt_pos"], float)
    err = ik.eval.attitude_error(
        rot.as_quat(scalar_first=True), tr.truth, scalar_first=True, align_heading=True, mask=tr.movement
    )
    turn = -(err.heading_offset + np.nan_to_num(err.heading_signed))
    ok = np.isfinite(pos).all(1) & err.valid
    return np.where(ok[:, None], Rotation.from_euler("z", turn[:, None]).apply(np.nan_to_num(pos)), np.nan)


# --cv's grid; 1e3 stands for "off" (a bound of 1 km, a ZUPT of 1 km/s).
GRID: dict[str, tuple[float, ...]] = {
    "sigma_p": (0.3, 1.0, 1e3),
    "sigma_v": (1.0, 1e3),
    "q_acc": (0.01, 0.03, 0.1),
    "sigma_zupt": (0.01, 1e3),
}


def parse_set(items: Sequence[str]) -> Bounded:
    """``--set name=value`` (``q_theta`` in (°)²/s, the rest in SI)."""
    kw = {k: float(v) for k, v in (item.split("=", 1) for item in items)}
    if "q_theta" in kw:
        kw["q_theta"] = float(np.radians(1.0) ** 2 * kw["q_theta"])
    return replace(Bounded(), **kw)


def report(trs: Sequence[Trial], par: Bounded, with_oracle: bool) -> None:
    """Per trial, per group and mean: Robust, Robust + bounds (and the mocap-position oracle), VQF."""
    rows = {}
    for offline in (False, True):
        mode = "offline" if offline else "online"
        rows[f"Robust {mode}"] = score(robust_runner(offline), trs, False)
        rows[f"+ bounds {mode}"] = score(bounded_runner(offline, par), trs, False)
        if with_oracle:
            rows[f"+ mocap position {mode}"] = score(bounded_runner(offline, par, oracle=True), trs, False)
        rows["offlineVQF" if offline else "VQF"] = score(vqf_runner(offline), trs, False)
    print(f"\n### 6D inclination RMSE [°], {par}\n")
    table(rows, trs)


def cross_validate(trs: Sequence[Trial], offline: bool) -> None:
    """``GRID`` on all trials and leave one group out (tuned on three groups, scored on the fourth)."""
    keys = list(GRID)
    results = []
    for values in itertools.product(*(GRID[k] for k in keys)):
        kw = dict(zip(keys, values, strict=True))
        results.append((kw, score(bounded_runner(offline, replace(Bounded(), **kw)), trs, False)))
        print(f"  {kw}: {np.mean(list(results[-1][1].values())):.4f}", flush=True)

    def best(names: set[str]) -> tuple[dict[str, float], dict[str, float]]:
        return min(results, key=lambda r: float(np.mean([r[1][n] for n in names])))

    base = score(robust_runner(offline), trs, False)
    mode = "offline" if offline else "online"
    kw_all, s_all = best({tr.name for tr in trs})
    m_all, m_base = np.mean(list(s_all.values())), np.mean(list(base.values()))
    print(f"\n### {mode}: chosen on all 12: {kw_all}: {m_all:.4f}° (Robust {m_base:.4f}°)\n")
    print(
        "| held-out group | chosen on the other three | held out | all-trials choice | Robust |\n|---|---|---|---|---|"
    )
    held_scores: dict[str, float] = {}
    for g, names in GROUPS.items():
        kw, s = best({tr.name for tr in trs} - set(names))
        held_scores.update({n: s[n] for n in names})
        short = ", ".join(f"{k}={v:g}" for k, v in kw.items())
        cells = " | ".join(f"{np.mean([d[n] for n in names]):.3f}" for d in (s, s_all, base))
        print(f"| {g} | {short} | {cells} |")
    print(f"| **mean** | | {np.mean(list(held_scores.values())):.3f} | {m_all:.3f} | {m_base:.3f} |")


def euroc(par: Bounded) -> None:
    """The EuRoC excerpt (a drone flying meters; every sample scored)."""
    tr = euroc_trial()
    if tr is None:
        print("EuRoC excerpt not found")
        return
    print("\n### EuRoC V1_02_medium, 6D inclination RMSE [°]\n\n| | online | offline |\n|---|---|---|")
    for name, make in (
        ("Robust", lambda off: robust_runner(off)),
        ("+ bounds", lambda off: bounded_runner(off, par)),
        ("VQF / offlineVQF", vqf_runner),
    ):
        cells = [f"{score(make(off), [tr], False)[tr.name]:.3f}" for off in (False, True)]
        print(f"| {name} | " + " | ".join(cells) + " |")


def motion(trs: Sequence[Trial]) -> None:
    """What the bounds assume, measured: the motion capture's position spread and velocity."""
    print("| trial | p std x/y/z [m] | max ‖p − mean‖ [m] | v RMS x/y/z [m/s] | max ‖v‖ [m/s] |\n|---|---|---|---|---|")
    for tr in trs:
        pos = np.asarray(loadmat(DATA / f"{tr.name}.mat")["opt_pos"], float)
        ok = np.isfinite(pos).all(1)
        idx = np.arange(len(pos))
        pos = np.stack([np.interp(idx, idx[ok], pos[ok, i]) for i in range(3)], 1)
        v = np.gradient(sosfiltfilt(butter(2, 5.0, fs=tr.rate, output="sos"), pos, axis=0), 1 / tr.rate, axis=0)
        dev = pos[ok] - pos[ok].mean(0)
        p_std = " / ".join(f"{x:.2f}" for x in dev.std(0))
        v_rms = " / ".join(f"{x:.2f}" for x in np.sqrt(np.mean(v[ok] ** 2, 0)))
        p_max, v_max = (np.linalg.norm(dev, axis=1).max(), np.linalg.norm(v[ok], axis=1).max())
        print(f"| {tr.name[:2]} | {p_std} | {p_max:.2f} | {v_rms} | {v_max:.2f} |")


def group_of(name: str) -> str:
    return next(g for g, names in GROUPS.items() if name in names)


def inclination(rot: Rotation, tr: Trial) -> float:
    err = ik.eval.attitude_error(
        rot.as_quat(scalar_first=True), tr.truth, scalar_first=True, align_heading=True, mask=tr.movement
    )
    return err.rmse(degrees=True).inclination


def in_body(rot: Rotation, m: np.ndarray) -> Rotation:
    return rot * Rotation.from_rotvec(m)


def in_world(rot: Rotation, w: np.ndarray) -> Rotation:
    return Rotation.from_rotvec([w[0], w[1], 0.0]) * rot


def fit(tr: Trial, turn: Callable[[np.ndarray], Rotation], n: int) -> OptimizeResult:
    """The ``n`` parameters of ``turn`` that minimise the inclination RMSE (Powell: no gradient)."""
    return minimize(lambda x: inclination(turn(x), tr), np.zeros(n), method="Powell")


def misalignment(trs: Sequence[Trial]) -> None:
    """How much of the error a constant rotation explains, fitted per trial (an oracle with the
    truth): in the body frame, ``R̂ Exp(m)`` (the IMU-to-markers misalignment, which no filter can
    see: it is a tilt against the reference, not against gravity), or in the world frame,
    ``Exp(w) R̂`` with ``w`` horizontal (a constant tilt, the slowest error the bounds can see)."""
    print("| filter | trial | incl. RMSE | body fit: RMSE, ‖m‖ | world fit: RMSE, ‖w‖ |\n|---|---|---|---|---|")
    means = []
    for offline in (False, True):
        for tr in trs:
            rot, _ = robust_base(tr, offline)

            body = fit(tr, partial(in_body, rot), 3)
            world = fit(tr, partial(in_world, rot), 2)
            means.append((inclination(rot, tr), body.fun, world.fun))
            print(
                f"| Robust {'offline' if offline else 'online'} | {tr.name[:2]} | {means[-1][0]:.3f} "
                f"| {body.fun:.3f}, {np.degrees(np.linalg.norm(body.x)):.2f}° "
                f"| {world.fun:.3f}, {np.degrees(np.linalg.norm(world.x)):.2f}° |",
                flush=True,
            )
    for offline, block in ((False, means[: len(trs)]), (True, means[len(trs) :])):
        m = np.mean(block, axis=0)
        print(f"| Robust {'offline' if offline else 'online'} | **mean** | {m[0]:.3f} | {m[1]:.3f} | {m[2]:.3f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--diagnose", action="store_true", help="slow / fast split of the tilt error")
    parser.add_argument("--split-s", type=float, default=5.0, help="period splitting slow from fast [s]")
    parser.add_argument("--set", action="append", default=[], help="Bounded parameter=value (repeatable)")
    parser.add_argument("--oracle", action="store_true", help="also the motion capture's positions as the aid")
    parser.add_argument("--cv", action="store_true", help="GRID: all trials and leave one group out")
    parser.add_argument("--offline", action="store_true", help="with --cv: the smoother")
    parser.add_argument("--euroc", action="store_true", help="the EuRoC excerpt")
    parser.add_argument("--motion", action="store_true", help="the motion capture's position and velocity spread")
    parser.add_argument("--misalign", action="store_true", help="a constant rotation fitted per trial (oracle)")
    args = parser.parse_args()
    par = parse_set(args.set)
    if args.euroc:
        euroc(par)
        return
    trs = trials()
    if args.diagnose:
        diagnose(trs, args.split_s)
    elif args.motion:
        motion(trs)
    elif args.misalign:
        misalignment(trs)
    elif args.cv:
        cross_validate(trs, args.offline)
    else:
        report(trs, par, args.oracle)


if __name__ == "__main__":
    main()
