"""``imukit.torch`` against pypose's ``IMUPreintegrator`` (pypose 0.9.5), the one other
differentiable IMU integrator, after converting conventions (docs/torch.md, "pypose").

- pypose removes gravity from each sample with the rotation at the end of its interval; given the
  rotations at the interval starts (its ``rot=``), its world-frame states equal
  ``it.integrate(..., scheme="lie_euler")``: rotations to 1e-14, velocities and positions to 1e-7
  (measured 2e-15, 6e-9, 1e-9); without them, velocities differ at O(h) (measured 2e-3 relative).
- With zero gravity its deltas equal ``it.preintegrate(..., scheme="lie_euler")`` to 1e-14, and its
  covariance (densities, divided by ``dt``) equals ours with per-sample covariances ``σ²/dt`` to
  first order: 9e-5 relative after 63 samples (it builds ``A``, ``B`` with ``ΔR`` after each step),
  bound 1e-3.

pypose 0.9.5 on torch 2.15 needs ``samples + 1`` to be a power of two (its ``cumops``): 63 here.
"""

from __future__ import annotations

import warnings

import pytest

torch = pytest.importorskip("torch", reason="imukit.torch needs torch (pip install imukit[torch])")
with warnings.catch_warnings():
    warnings.simplefilter("ignore", FutureWarning)  # pypose uses torch.jit.script at import
    pp = pytest.importorskip("pypose", reason="pypose is the comparison peer (requirements/dev.txt)")

import imukit.torch as it  # noqa: E402
from torch_cases import case, gap  # noqa: E402

N = 63


def test_world_frame_states_equal_pypose_given_its_rotations() -> None:
    c = case((3,), N, seed=20)
    r0 = pp.so3(torch.tensor([[0.3, -0.2, 0.5]] * 3, dtype=torch.float64)).Exp()
    v0 = torch.tensor([[1.0, 2.0, -0.5]] * 3, dtype=torch.float64)
    p0 = torch.tensor([[-1.0, 0.5, 2.0]] * 3, dtype=torch.float64)
    g = 9.81007  # pypose's default magnitude
    ours = it.integrate(
        c.dt, c.gyro, c.accel, initial_state=it.State(r0.matrix(), v0, p0), gravity=(0, 0, -g), scheme="lie_euler"
    )
    start = torch.cat((r0.matrix()[:, None], ours.rotation[:, :-1]), 1)
    init = {"pos": p0[:, None], "rot": r0[:, None], "vel": v0[:, None]}
    integ = pp.module.IMUPreintegrator(reset=True, prop_cov=False, gravity=g).double()
    given = integ(c.dt[..., None], c.gyro, c.accel, rot=pp.mat2SO3(start), init_state=init)
    assert gap(given["rot"].matrix(), ours.rotation) < 1e-14
    assert gap(given["vel"], ours.velocity) < 1e-7
    assert gap(given["pos"], ours.position) < 1e-7
    own = integ(c.dt[..., None], c.gyro, c.accel, init_state=init)
    assert 1e-4 < gap(own["vel"], ours.velocity) < 1e-2  # its end-of-interval gravity rotation


def test_deltas_and_covariance_equal_pypose_without_gravity() -> None:
    c = case((3,), N, seed=21)
    sg, sa = 3.2e-3**2, 8e-2**2
    integ = pp.module.IMUPreintegrator(reset=True, prop_cov=True, gravity=0.0, gyro_cov=sg, acc_cov=sa).double()
    theirs = integ(c.dt[..., None], c.gyro, c.accel)

    def per_sample(var: float) -> torch.Tensor:
        return (var / c.dt)[..., None].expand(3, N, 3)

    ours = it.preintegrate(
        c.dt, c.gyro, c.accel, scheme="lie_euler", gyro_cov=per_sample(sg), accel_cov=per_sample(sa),
        return_covariance=True,
    )  # fmt: skip
    assert gap(theirs["rot"].matrix()[:, -1], ours.delta_rotation) < 1e-14
    assert gap(theirs["vel"][:, -1], ours.delta_velocity) < 1e-14
    assert gap(theirs["pos"][:, -1], ours.delta_position) < 1e-14
    assert gap(theirs["cov"], ours.covariance, relative=True) < 1e-3
