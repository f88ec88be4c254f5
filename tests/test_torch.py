"""``imukit.torch`` forward: equal to the numpy API, the scan equal to the sequential recursion.

- Every output of ``preintegrate`` (deltas, covariance, bias Jacobian), ``integrate`` and
  ``integrate_attitude`` equals the numpy API on the same windows (``tests/torch_cases.py``) to
  1e-12 in float64 (deltas relative to max(1, |value|), covariances relative to their largest
  entry), for lengths 1 … 1025 (around the scan's powers of two) and batch shapes (N, 3),
  (B, N, 3), (B1, B2, N, 3).
- The associative scan equals the sequential recursion to 1e-10 (float64); float32 stays within
  the stated bounds of the float64 result.
- Ragged windows (``lengths``) equal the windows cut to their lengths.
- ``import imukit`` does not import torch.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

torch = pytest.importorskip("torch", reason="imukit.torch needs torch (pip install imukit[torch])")

import imukit as ik  # noqa: E402
import imukit.torch as it  # noqa: E402
from torch_cases import NOISE, case, gap, numpy_attitude, numpy_integrate, numpy_preintegrate  # noqa: E402

LENGTHS = [1, 2, 3, 7, 1000, 1023, 1024, 1025]
BATCH = (2, 2)
INDICES = [(0, 0), (0, 1), (1, 0), (1, 1)]
FIELDS = ("delta_rotation", "delta_velocity", "delta_position", "delta_t", "covariance", "bias_jacobian")


def _preintegrate(c, scheme, **kw):
    return it.preintegrate(
        c.dt,
        c.gyro,
        c.accel,
        bias=c.bias,
        noise=NOISE,
        scheme=scheme,
        return_covariance=True,
        return_jacobian=True,
        **kw,
    )


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
@pytest.mark.parametrize("n", LENGTHS)
def test_preintegrate_equals_numpy(scheme: str, n: int) -> None:
    c = case(BATCH, n, seed=n)
    out = _preintegrate(c, scheme)
    for index in INDICES:
        ref = numpy_preintegrate(c, index, scheme)
        for name in FIELDS:
            got = getattr(out, name)[index]
            assert gap(got, ref[name], relative=name == "covariance") < 1e-12, (name, index)
    # The same windows as (N, 3) and (B, N, 3) batches give the same numbers.
    single = _preintegrate(type(c)(*(x[0, 1] for x in c)), scheme)
    row = _preintegrate(type(c)(*(x[1] for x in c)), scheme)
    for name in FIELDS:
        assert gap(getattr(single, name), getattr(out, name)[0, 1], relative=True) < 1e-14, name
        assert gap(getattr(row, name), getattr(out, name)[1], relative=True) < 1e-14, name


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
@pytest.mark.parametrize("n", [1, 2, 7, 1025])
def test_integrate_equals_numpy(scheme: str, n: int) -> None:
    c = case(BATCH, n, seed=n + 1)
    r0 = Rotation.from_rotvec([0.3, -0.2, 0.5])
    v0, p0 = np.array([1.0, 2.0, -0.5]), np.array([-1.0, 0.5, 2.0])
    initial = it.State(torch.tensor(r0.as_matrix()), torch.tensor(v0), torch.tensor(p0))
    out = it.integrate(c.dt, c.gyro, c.accel, initial_state=initial, bias=c.bias, scheme=scheme)
    for index in INDICES:
        ref = numpy_integrate(c, index, scheme, ik.NavState(p0, v0, r0))
        for name in ("rotation", "velocity", "position"):
            assert gap(getattr(out, name)[index], ref[name]) < 1e-12, (name, index)


@pytest.mark.parametrize("scheme", ["rk2", "exp"])
@pytest.mark.parametrize("n", [1, 2, 7, 1000, 1025])
def test_integrate_attitude_equals_numpy(scheme: str, n: int) -> None:
    c = case(BATCH, n, seed=n + 2)
    r0 = Rotation.from_rotvec([0.3, -0.2, 0.5])
    out = it.integrate_attitude(c.dt, c.gyro, initial=torch.tensor(r0.as_matrix()), scheme=scheme)
    assert out.shape == (*BATCH, n, 3, 3)
    for index in INDICES:
        assert gap(out[index], numpy_attitude(c, index, scheme, r0)) < 1e-12, index


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
@pytest.mark.parametrize("n", [1025])
def test_scan_equals_sequential(scheme: str, n: int) -> None:
    c = case((2,), n, seed=3)
    scan = _preintegrate(c, scheme, per_step=True)
    seq = _preintegrate(c, scheme, per_step=True, method="sequential")
    for name in FIELDS:
        assert gap(getattr(scan, name), getattr(seq, name), relative=name == "covariance") < 1e-10, name
    # The final-only reduction is the last step of the scan.
    final = _preintegrate(c, scheme)
    for name in FIELDS:
        assert gap(getattr(final, name), getattr(scan, name)[:, -1], relative=True) < 1e-12, name


# float32 against float64, 1000 steps of 4-6 ms, relative to the largest entry: measured (midpoint /
# lie_euler) rotation 1.7e-6 / 2.2e-6, velocity 1.1e-6 / 9.7e-7, position 7.5e-7 / 6.4e-7, Δt 1.2e-7,
# covariance 1.6e-6 / 2.7e-6, bias Jacobian 9.7e-7 / 1.7e-6. Bounds about 10x that.
FLOAT32 = {"delta_rotation": 2e-5, "delta_velocity": 1e-5, "delta_position": 1e-5, "delta_t": 1e-6}
FLOAT32 |= {"covariance": 3e-5, "bias_jacobian": 2e-5}


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_float32_within_stated_tolerance(scheme: str) -> None:
    c64 = case((2,), 1000, seed=4)
    c32 = type(c64)(*(x.float() for x in c64))
    ref, out = _preintegrate(c64, scheme), _preintegrate(c32, scheme)
    for name, bound in FLOAT32.items():
        assert getattr(out, name).dtype == torch.float32
        assert gap(getattr(out, name), getattr(ref, name), relative=True) < bound, name


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_lengths_cut_ragged_windows(scheme: str) -> None:
    c = case((3,), 40, seed=5)
    lengths = torch.tensor([1, 17, 40])
    out = _preintegrate(c, scheme, lengths=lengths, per_step=True)
    for b, m in enumerate(lengths.tolist()):
        cut = _preintegrate(type(c)(c.dt[b, :m], c.gyro[b, :m], c.accel[b, :m], c.bias[b]), scheme, per_step=True)
        for name in FIELDS:
            steps = getattr(out, name)[b]
            assert gap(steps[:m], getattr(cut, name), relative=True) < 1e-14, (name, m)
            # Past its length a window stays where it ended (to rounding: the scan groups differently).
            assert gap(steps[m:], steps[m - 1 : m].expand_as(steps[m:]), relative=True) < 1e-14, (name, m)


def test_import_imukit_does_not_import_torch() -> None:
    code = "import sys, imukit, imukit.preint, imukit.strapdown; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_inputs_are_checked() -> None:
    c = case((), 5)
    with pytest.raises(ik.ShapeError, match="gyro: expected shape"):
        it.preintegrate(c.dt, c.gyro[:, :2], c.accel)
    with pytest.raises(ik.ShapeError, match="dt: expected a scalar or shape"):
        it.preintegrate(c.dt[:4], c.gyro, c.accel)
    with pytest.raises(ik.DTypeError, match="gyro: expected float32 or float64"):
        it.preintegrate(c.dt, c.gyro.int(), c.accel)
    with pytest.raises(ik.ParameterError, match="return_covariance: needs noise"):
        it.preintegrate(c.dt, c.gyro, c.accel, return_covariance=True)
    with pytest.raises(ik.ParameterError, match="scheme: expected one of"):
        it.preintegrate(c.dt, c.gyro, c.accel, scheme="rk4")
    with pytest.raises(ik.ParameterError, match="scheme: expected one of"):
        it.integrate_attitude(c.dt, c.gyro, scheme="magnus")


@pytest.mark.skipif(not torch.cuda.is_available(), reason="no CUDA GPU here (CI has none); bench/bench_torch.py")
@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_cuda_equals_cpu(scheme: str) -> None:
    c = case((4,), 1025, seed=6)
    cpu = _preintegrate(c, scheme)
    gpu = _preintegrate(type(c)(*(x.cuda() for x in c)), scheme)
    for name in FIELDS:
        assert gap(getattr(gpu, name), getattr(cpu, name), relative=name == "covariance") < 1e-12, name
