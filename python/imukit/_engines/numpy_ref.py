"""A pure-numpy reference engine, written from the equations of the core's module docs with dense
matrices (``crates/imukit/src/preint/mod.rs``: lie_euler, Forster et al. 2017 eqs. 62–63, 69;
``preint/midpoint.rs``: VINS-Mono's midpoint with the exact shared-sample correlation;
``preint/windows.rs``: the boundary signal model). Slow (a Python loop per sample): it is the
specification a new engine (torch) is tested against, next to the Rust one.

One interval of length h, with ``Φ = Exp(ω̂h)ᵀ``, ``J = J_r(ω̂h)`` and the scheme's ``M``:

    A = [[Φ, 0, 0], [M h, I, 0], [½ M h², h I, I]]
    lie_euler: M = −ΔR[â]×, B_a = [0; ΔR h; ½ ΔR h²], B_g = [J h; 0; 0], Σ ← A Σ Aᵀ + B Q Bᵀ
    midpoint:  M = −½(R_0[â_0]× + R_1[â_1]× Φ), K = ¼ h R_1[â_1]× J,
               B_s = [[−½hJ, 0], [hK, −½hR_s], [½h²K, −¼h²R_s]],
               Σ ← A Σ Aᵀ + B_0 Q_0 B_0ᵀ + B_1 Q_1 B_1ᵀ + A C B_0ᵀ + B_0 Cᵀ Aᵀ,  C ← B_1 Q_1
    bias Jacobian J_b ← A J_b + G_b (lie_euler G_b = [[−J h, 0], [0, −ΔR h], [0, −½ΔR h²]],
    midpoint G_b = B_0 + B_1); combined: F = [[A, G_b], [0, I]], P ← F P Fᵀ + diag(noise, Q_w h)

Noise variances are ``σ²/h`` per sample (midpoint: h of the interval that ends at the sample, the
window's first sample that of the first interval), × the saturation factor² where clipped.
"""

from __future__ import annotations

import numpy as np

from imukit._arrays import FloatArray
from imukit._engines._windows import Windows, record
from imukit._preint_record import Preintegration, PreintParams
from imukit.imu import ImuData

_I3 = np.eye(3)
_PROJECT_EVERY = 16  # the core's Björck–Bowie projection of ΔR


def _hat(v: FloatArray) -> FloatArray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _exp_jr(phi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``Exp(φ)`` (Rodrigues) and ``J_r(φ)``, with Taylor series below θ = 1e-4."""
    theta2 = float(phi @ phi)
    theta = np.sqrt(theta2)
    if theta < 1e-4:
        a, b, c = 1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0, 1.0 / 6.0 - theta2 / 120.0
    else:
        a, b, c = np.sin(theta) / theta, (1.0 - np.cos(theta)) / theta2, (theta - np.sin(theta)) / (theta2 * theta)
    k = _hat(phi)
    k2 = k @ k
    return _I3 + a * k + b * k2, _I3 - b * k + c * k2


class _State:
    """One window's state: deltas, dense covariance (15×15 when combined), bias Jacobian."""

    def __init__(self, params: PreintParams) -> None:
        self.p = params
        self.r, self.v, self.pos, self.t = np.eye(3), np.zeros(3), np.zeros(3), 0.0
        n = 15 if params.combined else 9
        self.cov = np.zeros((n, n))
        self.jac = np.zeros((9, 6))
        self.cross = np.zeros((9, 6))  # midpoint: Cov(δx, n_last)
        self.last: tuple[FloatArray, FloatArray, FloatArray, FloatArray | None] | None = None
        self.intervals = 0

    def scale(self, clipped: FloatArray) -> FloatArray:
        f2 = self.p.saturation_noise_factor**2
        return np.where(clipped, f2, 1.0)

    def q(self, h: float, scale: FloatArray) -> FloatArray:
        """Per-axis white-noise variances ``[gyro×3, accel×3]`` of one sample."""
        n = self.p.noise
        return np.repeat([n.gyro_density**2 / h * scale[0], n.accel_density**2 / h * scale[1]], 3)

    def transition(self, phi: FloatArray, m: FloatArray, h: float) -> FloatArray:
        a = np.eye(9)
        a[0:3, 0:3], a[3:6, 0:3], a[6:9, 0:3], a[6:9, 3:6] = phi, m * h, 0.5 * m * h * h, _I3 * h
        return a

    def propagate(self, a: FloatArray, white: FloatArray, g_b: FloatArray) -> None:
        """``P ← F P Fᵀ + diag(white, Q_w h)`` (9×9 ``white`` already summed), ``J_b ← A J_b + G_b``."""
        h = self.h
        if self.p.combined:
            f = np.eye(15)
            f[0:9, 0:9], f[0:9, 9:15] = a, g_b
            n = self.p.noise
            walk = np.repeat([n.gyro_random_walk**2 * h, n.accel_random_walk**2 * h], 3)
            q = np.zeros((15, 15))
            q[0:9, 0:9], q[9:15, 9:15] = white, np.diag(walk)
            self.cov = f @ self.cov @ f.T + q
        else:
            self.cov = a @ self.cov @ a.T + white
        self.jac = a @ self.jac + g_b

    def count(self) -> None:
        self.intervals += 1
        if self.intervals % _PROJECT_EVERY == 0:
            self.r = 0.5 * self.r @ (3.0 * _I3 - self.r.T @ self.r)

    def euler(self, acc: FloatArray, gyro: FloatArray, h: float, clipped: FloatArray) -> None:
        b = self.p.bias
        a_hat, w_hat = acc - b.accel, gyro - b.gyro
        r = self.r
        step, jr = _exp_jr(w_hat * h)
        a = self.transition(step.T, -r @ _hat(a_hat), h)
        g_b = np.zeros((9, 6))
        g_b[0:3, 0:3], g_b[3:6, 3:6], g_b[6:9, 3:6] = -jr * h, -r * h, -0.5 * r * h * h
        bn = np.zeros((9, 6))  # the noise input: columns [gyro, accel]
        bn[0:3, 0:3], bn[3:6, 3:6], bn[6:9, 3:6] = jr * h, r * h, 0.5 * r * h * h
        self.h = h
        self.propagate(a, bn @ np.diag(self.q(h, self.scale(clipped))) @ bn.T, g_b)
        ra = r @ a_hat
        self.pos = self.pos + self.v * h + 0.5 * ra * h * h
        self.v = self.v + ra * h
        self.r = r @ step
        self.t += h
        self.count()

    def midpoint(self, acc: FloatArray, gyro: FloatArray, h: float, clipped: FloatArray) -> None:
        scale = self.scale(clipped)
        if self.last is None:
            self.last = (acc, gyro, scale, None)
            return
        a0_m, w0_m, scale0, q0 = self.last
        b = self.p.bias
        a0, a1 = a0_m - b.accel, acc - b.accel
        w_hat = 0.5 * (w0_m + gyro) - b.gyro
        r0 = self.r
        step, jr = _exp_jr(w_hat * h)
        phi, r1 = step.T, r0 @ step
        r1a = r1 @ _hat(a1)
        m = -0.5 * (r0 @ _hat(a0) + r1a @ phi)
        k = 0.25 * h * r1a @ jr
        a = self.transition(phi, m, h)

        def b_s(r_s: FloatArray) -> FloatArray:
            out = np.zeros((9, 6))
            out[0:3, 0:3], out[3:6, 0:3], out[6:9, 0:3] = -0.5 * h * jr, h * k, 0.5 * h * h * k
            out[3:6, 3:6], out[6:9, 3:6] = -0.5 * h * r_s, -0.25 * h * h * r_s
            return out

        b0, b1 = b_s(r0), b_s(r1)
        q1 = self.q(h, scale)
        q0 = self.q(h, scale0) if q0 is None else q0
        ac = a @ self.cross
        white = b0 @ np.diag(q0) @ b0.T + b1 @ np.diag(q1) @ b1.T + ac @ b0.T + b0 @ ac.T
        self.h = h
        self.propagate(a, white, b0 + b1)
        self.cross = b1 @ np.diag(q1)
        acc_mean = 0.5 * (r0 @ a0 + r1 @ a1)
        self.pos = self.pos + self.v * h + 0.5 * acc_mean * h * h
        self.v = self.v + acc_mean * h
        self.r = r1
        self.t += h
        self.count()
        self.last = (acc, gyro, scale, q1)


def _window(imu: ImuData, lo: float, hi: float, params: PreintParams) -> _State:
    """One window under the boundary signal model of ``preint/windows.rs``: euler holds the sample
    before a boundary, midpoint interpolates its neighbours (flags: either one's)."""
    t, acc, gyro = imu.seconds, imu.accel, imu.gyro
    flags = np.stack([imu.gyro_saturated, imu.accel_saturated], axis=1)
    euler = params.scheme == "lie_euler"

    def at(k: int, x: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        if euler or x == t[k]:
            return acc[k], gyro[k], flags[k]
        if x == t[k + 1]:
            return acc[k + 1], gyro[k + 1], flags[k + 1]
        s = (x - t[k]) / (t[k + 1] - t[k])
        return acc[k] + (acc[k + 1] - acc[k]) * s, gyro[k] + (gyro[k + 1] - gyro[k]) * s, flags[k] | flags[k + 1]

    state = _State(params)
    step = state.euler if euler else state.midpoint
    start, end = int(np.searchsorted(t, lo, "right")), int(np.searchsorted(t, hi, "left"))
    current, time = at(start - 1, lo), lo
    if not euler:
        step(*current[0:2], 0.0, current[2])
    points = [(t[k], (acc[k], gyro[k], flags[k])) for k in range(start, end)] + [(hi, at(end - 1, hi))]
    for next_time, nxt in points:
        a, w, c = current if euler else nxt
        step(a, w, next_time - time, c)
        time, current = next_time, nxt
    return state


def preintegrate_windows(imu: ImuData, windows: Windows, params: PreintParams, threads: int | None) -> Preintegration:
    """Every window, one after another (``threads`` is ignored)."""
    edges = windows.offsets
    states = [_window(imu, float(lo), float(hi), params) for lo, hi in zip(edges[:-1], edges[1:], strict=True)]
    combined = np.array([s.cov for s in states]) if params.combined else None
    arrays = (
        np.array([s.r for s in states]),
        np.array([s.v for s in states]),
        np.array([s.pos for s in states]),
        np.array([s.t for s in states]),
        np.array([s.cov[0:9, 0:9] for s in states]),
        np.array([s.jac for s in states]),
        combined,
    )
    return record(arrays, windows, params)
