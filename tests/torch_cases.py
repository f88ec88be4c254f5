"""Random inputs for the ``imukit.torch`` tests and the numpy API's answers on them.

The torch functions take ``dt`` as ``PreintegratedImu.integrate_measurement`` does (lie_euler /
exp: sample k held over ``dt[k]``; midpoint / rk2: sample k taken ``dt[k]`` after sample k − 1), so
the numpy reference is given the stamps that convention implies: lie_euler gets one more stamp
(the last sample repeated, never used), midpoint the stamps of ``dt[1:]``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import torch
from scipy.spatial.transform import Rotation

import imukit as ik

NOISE = ik.ImuNoise(gyro_density=1.7e-3, accel_density=2.0e-2, gyro_random_walk=0.0, accel_random_walk=0.0)
HELD = ("lie_euler", "exp")


class Case(NamedTuple):
    dt: torch.Tensor  # (*B, N)
    gyro: torch.Tensor  # (*B, N, 3)
    accel: torch.Tensor
    bias: torch.Tensor  # (*B, 6)


def case(batch: tuple[int, ...], n: int, seed: int = 0, dtype: torch.dtype = torch.float64) -> Case:
    """Rates of about 1 rad/s, specific forces around +g on z, steps of 4 to 6 ms, small biases."""
    g = torch.Generator().manual_seed(seed)
    gyro = torch.randn(*batch, n, 3, generator=g, dtype=torch.float64)
    accel = torch.randn(*batch, n, 3, generator=g, dtype=torch.float64) + torch.tensor([0.0, 0.0, 9.81])
    dt = 0.004 + 0.002 * torch.rand(*batch, n, generator=g, dtype=torch.float64)
    bias = 0.05 * torch.randn(*batch, 6, generator=g, dtype=torch.float64)
    return Case(*(x.to(dtype) for x in (dt, gyro, accel, bias)))


def imu_data(dt: np.ndarray, gyro: np.ndarray, accel: np.ndarray, scheme: str) -> ik.ImuData:
    """One window as the numpy API's ImuData (module docs)."""
    if scheme in HELD:
        t = np.concatenate(([0.0], np.cumsum(dt)))
        return ik.ImuData(t, np.vstack((gyro, gyro[-1:])), np.vstack((accel, accel[-1:])))
    return ik.ImuData(np.concatenate(([0.0], np.cumsum(dt[1:]))), gyro, accel)


def numpy_window(c: Case, index: tuple[int, ...], scheme: str) -> tuple[ik.ImuData, ik.ImuBias]:
    dt, gyro, accel, bias = (x[index].double().numpy() for x in c)
    return imu_data(dt, gyro, accel, scheme), ik.ImuBias(bias[:3], bias[3:])


def numpy_preintegrate(c: Case, index: tuple[int, ...], scheme: str) -> dict[str, np.ndarray]:
    imu, bias = numpy_window(c, index, scheme)
    p = ik.preintegrate(imu, noise=NOISE, bias=bias, scheme=scheme)
    return {
        "delta_rotation": p.delta_rotation.as_matrix(),
        "delta_velocity": p.delta_velocity,
        "delta_position": p.delta_position,
        "delta_t": np.array(p.delta_t),
        "covariance": p.covariance,
        "bias_jacobian": p.bias_jacobian,
    }


def numpy_integrate(c: Case, index: tuple[int, ...], scheme: str, initial: ik.NavState) -> dict[str, np.ndarray]:
    """Per-step states, aligned with the torch output (lie_euler: the states after each sample)."""
    imu, bias = numpy_window(c, index, scheme)
    tr = ik.integrate(imu, initial=initial, bias=bias, scheme=scheme)
    keep = slice(1, None) if scheme in HELD else slice(None)
    return {"rotation": tr.rotation.as_matrix()[keep], "velocity": tr.velocity[keep], "position": tr.position[keep]}


def numpy_attitude(c: Case, index: tuple[int, ...], scheme: str, initial: Rotation) -> np.ndarray:
    imu, _ = numpy_window(c, index, scheme)
    keep = slice(1, None) if scheme in HELD else slice(None)
    return ik.integrate_attitude(imu.t, imu.gyro, initial=initial, scheme=scheme).as_matrix()[keep]


def gap(a: Any, b: Any, *, relative: bool = False) -> float:
    """Largest difference over the larger of 1 and b's largest magnitude (``relative``: over the
    latter alone, for covariances, whose entries are far below 1)."""
    a = a.detach().double().cpu().numpy() if isinstance(a, torch.Tensor) else np.asarray(a)
    b = b.detach().double().cpu().numpy() if isinstance(b, torch.Tensor) else np.asarray(b)
    assert a.shape == b.shape, f"{a.shape} != {b.shape}"
    scale = float(np.abs(b).max(initial=0.0))
    return float(np.abs(a - b).max(initial=0.0) / (scale if relative and scale > 0 else max(1.0, scale)))
