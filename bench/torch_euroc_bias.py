"""Recover the IMU biases of EuRoC V1_02_medium by gradient descent through
``imukit.torch.preintegrate`` (docs/torch.md, "Example").

The excerpt in ``../shared/data`` (40 s at 200 Hz) is cut into windows of ``WINDOW`` s; for each
window the ground truth gives the relative motion that the preintegrated deltas must explain
(docs/preintegration.md, "residual"):
``[Log(ΔR(b)ᵀ R_iᵀ R_j), R_iᵀ(v_j − v_i − g Δt) − Δv(b), R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp(b)]``.
One constant bias b = (b_g, b_a) for the whole excerpt minimises the sum of squared residuals,
each block divided by its typical size on this recording (``SCALE``: the rms residuals with the
ground-truth bias, docs/preintegration.md), by L-BFGS on autograd gradients from zero. The answer is
compared with the mean of EuRoC's own bias estimate over the excerpt.

Run: ``python bench/torch_euroc_bias.py`` (about 10 s on one core).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import NamedTuple

import numpy as np
import torch

import imukit as ik
import imukit.torch as it

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "euroc_v1_02_medium"
WINDOW = 0.5  # s; 100 intervals at 200 Hz
SCALE = (1.3e-3, 3.3e-2, 8.7e-3)  # rad, m/s, m: rms residuals θ, v, p with the ground-truth bias


class Windows(NamedTuple):
    """M windows of n samples (batch first) and the ground-truth motion between their ends."""

    dt: torch.Tensor  # (M, n) midpoint convention: dt[k] = t_k − t_{k−1}, dt[0] unused
    gyro: torch.Tensor  # (M, n, 3)
    accel: torch.Tensor
    r_i: torch.Tensor  # (M, 3, 3)
    r_j: torch.Tensor
    dv: torch.Tensor  # (M, 3): R_iᵀ(v_j − v_i − g Δt)
    dp: torch.Tensor  # (M, 3): R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²)
    truth_bias: np.ndarray  # (6,) EuRoC's [b_g, b_a], mean over the windows' samples


def load(folder: Path = DATA, window: float = WINDOW) -> Windows:
    imu = ik.io.read_euroc_imu(folder / "imu0_data_first40s.csv")
    at = ik.eval.truth_at_imu(ik.io.read_euroc_groundtruth(folder / "state_groundtruth_estimate0_data.csv"), imu)
    first = int(np.flatnonzero(at.mask)[0])  # the truth covers the samples from here on
    gt = at.reference
    n = round(window / float(np.median(np.diff(imu.seconds)))) + 1
    m = (len(gt) - 1) // (n - 1)
    rows = (n - 1) * np.arange(m)[:, None] + np.arange(n)  # consecutive windows share an end sample
    t = imu.seconds[first + rows]
    i, j, span = rows[:, 0], rows[:, -1], (t[:, -1] - t[:, 0])[:, None]
    r, g = gt.rotation.as_matrix(), np.asarray(ik.GRAVITY)
    r_it = np.transpose(r[i], (0, 2, 1))
    dv = np.einsum("mab,mb->ma", r_it, gt.velocity[j] - gt.velocity[i] - g * span)
    dp = np.einsum("mab,mb->ma", r_it, gt.position[j] - gt.position[i] - gt.velocity[i] * span - 0.5 * g * span**2)
    covered = slice(0, int(rows[-1, -1]) + 1)
    truth_bias = np.concatenate((gt.gyro_bias[covered].mean(0), gt.accel_bias[covered].mean(0)))

    def tensor(x: np.ndarray) -> torch.Tensor:
        return torch.from_numpy(np.ascontiguousarray(x))

    dt = np.diff(t, axis=1, prepend=t[:, :1])
    gyro, accel = imu.gyro[first + rows], imu.accel[first + rows]
    return Windows(*map(tensor, (dt, gyro, accel, r[i], r[j], dv, dp)), truth_bias)


def _log(r: torch.Tensor) -> torch.Tensor:
    """``Log`` of rotations near the identity (residuals): ``θ/sin θ · vee((R − Rᵀ)/2)``."""
    s = 0.5 * (r - r.transpose(-1, -2))
    v = torch.stack((s[..., 2, 1], s[..., 0, 2], s[..., 1, 0]), -1)
    sin = v.norm(dim=-1, keepdim=True)
    cos = 0.5 * (r.diagonal(dim1=-2, dim2=-1).sum(-1, keepdim=True) - 1)
    # θ/sin θ → 1 + sin²/6 as sin → 0 (no 0/0 in value or gradient).
    safe = torch.where(sin > 1e-6, sin, torch.ones_like(sin))
    ratio = torch.where(sin > 1e-6, torch.atan2(safe, cos) / safe, 1 + sin * sin / 6)
    return ratio * v


def residuals(w: Windows, bias: torch.Tensor, scheme: str = "midpoint") -> torch.Tensor:
    """(M, 9) residuals ``[θ, v, p]``, each block over its ``SCALE``."""
    d = it.preintegrate(w.dt, w.gyro, w.accel, bias=bias, scheme=scheme)
    theta = _log(d.delta_rotation.transpose(-1, -2) @ w.r_i.transpose(-1, -2) @ w.r_j)
    blocks = (theta, w.dv - d.delta_velocity, w.dp - d.delta_position)
    return torch.cat([b / s for b, s in zip(blocks, SCALE)], dim=-1)


def recover(w: Windows, iterations: int = 30) -> torch.Tensor:
    """The bias (6,) ``[b_g, b_a]`` minimising the squared residuals, by L-BFGS from zero."""
    bias = torch.zeros(6, dtype=torch.float64, requires_grad=True)
    opt = torch.optim.LBFGS([bias], max_iter=iterations, line_search_fn="strong_wolfe", tolerance_change=1e-15)

    def closure() -> torch.Tensor:
        opt.zero_grad()
        loss = residuals(w, bias).square().mean()
        loss.backward()  # type: ignore[no-untyped-call]
        return loss

    opt.step(closure)  # type: ignore[no-untyped-call]
    return bias.detach()


def main() -> None:
    torch.set_num_threads(1)
    w = load()
    start = time.perf_counter()
    b = recover(w).numpy()
    elapsed = time.perf_counter() - start
    truth = w.truth_bias
    print(f"EuRoC V1_02_medium, {len(w.dt)} windows of {WINDOW} s, midpoint, L-BFGS from zero: {elapsed:.1f} s")
    print(f"{'':>14} {'recovered':>30} {'EuRoC ground truth':>30} {'|difference|':>10}")
    for name, sl in (("gyro [rad/s]", slice(0, 3)), ("accel [m/s²]", slice(3, 6))):
        diff = np.abs(b[sl] - truth[sl]).max()
        got, want = (np.array2string(x[sl], precision=5) for x in (b, truth))
        print(f"{name:>14} {got:>30} {want:>30} {diff:10.2e}")
    for label, bias in (("zero bias", np.zeros(6)), ("ground-truth bias", truth), ("recovered bias", b)):
        rms = residuals(w, torch.from_numpy(bias)).square().mean().sqrt()
        print(f"rms scaled residual with the {label}: {float(rms):.3f}")


if __name__ == "__main__":
    main()
