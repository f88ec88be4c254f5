"""``imukit demo``: the conventions in numbers, checked against scipy, and a quick timing."""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

from imukit import euler, quat, so3


def _median_seconds(f: object, repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()  # type: ignore[operator]
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def run() -> None:
    """Print the demo."""
    np.set_printoptions(precision=6, suppress=True)
    quarter_z = np.array([0.0, 0.0, np.pi / 2])
    print("1. Exp([0, 0, π/2]) is a quarter turn about z; it maps body x onto world y:")
    print(f"   R @ x_b = {so3.exp(quarter_z) @ [1.0, 0.0, 0.0]}")

    print("2. A body rate turns the body about its own axes: q_{k+1} = q_k ⊗ Exp(ω dt).")
    q = quat.exp([np.pi / 2, 0.0, 0.0])  # rolled 90°: body y points to world z
    step = quat.multiply(q, quat.exp([0.0, 0.0, 0.1]))  # yaw rate about the *body* z
    print(f"   rolled 90° then 0.1 rad about body z: body x now points to {quat.rotate(step, [1, 0, 0])}")

    print("3. Ω(ω) is the right-product matrix of [ω, 0] (xyzw), as written in VINS-Mono:")
    print(quat.omega_matrix([0.1, -0.2, 0.3]))

    print("4. ZYX Euler rate map: χ̇ = E(χ) ω_b; at yaw 0, pitch 30°, roll 0, a body z rate of")
    e = euler.rate_matrix([0.0, np.radians(30.0), 0.0])
    print(f"   1 rad/s gives [ψ̇, θ̇, φ̇] = {e @ [0.0, 0.0, 1.0]}  (ψ̇ = 1/cos 30°)")

    rng = np.random.default_rng(0)
    phi = rng.normal(size=(1_000_000, 3))
    ours = so3.exp(phi)
    ref = Rotation.from_rotvec(phi).as_matrix()
    print(f"5. so3.exp on 10^6 vectors agrees with scipy to {np.abs(ours - ref).max():.1e}.")
    t_ours = _median_seconds(lambda: so3.exp(phi))
    t_scipy = _median_seconds(lambda: Rotation.from_rotvec(phi).as_matrix())
    print(f"   imukit {t_ours * 1e3:.1f} ms, scipy {t_scipy * 1e3:.1f} ms: {t_scipy / t_ours:.1f}x (bench/ has more)")
