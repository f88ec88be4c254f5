"""``imukit.torch``'s CPU path (``method="native"``: the Rust kernels and their reverse sweep).

- Forward equals the numpy API (``imukit.preintegrate``, ``integrate_attitude``) and the torch scan
  to 1e-12 (float64) over lengths 1 … 1025 and batch shapes (N, 3), (B, N, 3), (B1, B2, N, 3),
  both schemes, with covariance and bias Jacobian.
- ``torch.autograd.gradcheck`` (float64) of the Rust backward for every differentiable input
  (``dt``, ``gyro``, ``accel``, ``bias``, noise densities, per-sample covariances, the initial
  state), covariance, bias Jacobian and per-step outputs included, at zero rates and masked samples;
  densities alone take the kernels' densities path (``σ²`` per window), checked the same way and
  against the same noise given per sample (forward and gradients, ``dt``'s through ``σ²/dt``).
- Its gradients equal autograd through the torch scan (a second, independent derivative) to 1e-10.
- float32 inputs are widened: the result is the float64 result of the same (rounded) inputs.
- ``mask`` (either end padded) equals each window run alone, on both paths.
"""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch", reason="imukit.torch needs torch (pip install imukit[torch])")

import imukit as ik  # noqa: E402
import imukit.torch as it  # noqa: E402
from torch_cases import NOISE, case, gap, numpy_attitude, numpy_preintegrate  # noqa: E402

LENGTHS = [1, 2, 3, 7, 1000, 1023, 1024, 1025]
FIELDS = ("delta_rotation", "delta_velocity", "delta_position", "delta_t", "covariance", "bias_jacobian")
# Covariance and bias Jacobian asked for, per scheme (both: the kernels cover every output).
LINEAR = {"lie_euler": True, "midpoint": True}


def _run(c, scheme, method, **kw):
    linear = LINEAR[scheme]
    return it.preintegrate(
        c.dt, c.gyro, c.accel, bias=c.bias, noise=NOISE if linear else None, scheme=scheme, method=method,
        return_covariance=linear, return_jacobian=linear, **kw,
    )  # fmt: skip


def _fields(scheme):
    return FIELDS if LINEAR[scheme] else FIELDS[:4]


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
@pytest.mark.parametrize("n", LENGTHS)
def test_native_equals_numpy_and_scan(scheme: str, n: int) -> None:
    c = case((2, 2), n, seed=n)
    out = _run(c, scheme, "native")
    scan = _run(c, scheme, "scan")
    for index in [(0, 0), (0, 1), (1, 0), (1, 1)]:
        ref = numpy_preintegrate(c, index, scheme)
        for name in _fields(scheme):
            assert gap(getattr(out, name)[index], ref[name], relative=name == "covariance") < 1e-12, (name, index)
    for name in _fields(scheme):
        assert gap(getattr(out, name), getattr(scan, name), relative=name == "covariance") < 1e-12, name
    single = _run(type(c)(*(x[0, 1] for x in c)), scheme, "native")
    row = _run(type(c)(*(x[1] for x in c)), scheme, "native")
    for name in _fields(scheme):
        assert gap(getattr(single, name), getattr(out, name)[0, 1], relative=True) < 1e-15, name
        assert gap(getattr(row, name), getattr(out, name)[1], relative=True) < 1e-15, name


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_native_per_step_equals_scan(scheme: str) -> None:
    c = case((3,), 1025, seed=2)
    out, scan = _run(c, scheme, "native", per_step=True), _run(c, scheme, "scan", per_step=True)
    for name in _fields(scheme):
        assert gap(getattr(out, name), getattr(scan, name), relative=name == "covariance") < 1e-12, name


@pytest.mark.parametrize("n", [1, 7, 1025])
def test_native_attitude_equals_numpy(n: int) -> None:
    c = case((2, 2), n, seed=n + 2)
    r0 = torch.linalg.matrix_exp(torch.tensor([[0.0, -0.5, -0.2], [0.5, 0.0, -0.3], [0.2, 0.3, 0.0]]).double())
    from scipy.spatial.transform import Rotation

    out = it.integrate_attitude(c.dt, c.gyro, initial=r0, scheme="exp", method="native")
    for index in [(0, 0), (1, 1)]:
        assert gap(out[index], numpy_attitude(c, index, "exp", Rotation.from_matrix(r0.numpy()))) < 1e-12


def _leaves(*xs):
    return tuple(x.detach().clone().requires_grad_(True) for x in xs)


@pytest.mark.parametrize("per_step", [False, True])
@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_gradcheck_native_preintegrate(scheme: str, per_step: bool) -> None:
    c = case((2,), 5, seed=10)
    g = torch.Generator().manual_seed(3)
    gyro_cov = 1e-4 * torch.rand(2, 5, 3, 3, generator=g, dtype=torch.float64)  # full, not symmetric
    densities = torch.tensor([[1.7e-2, 2.0e-1], [3e-2, 1e-1]], dtype=torch.float64)
    inputs = _leaves(c.dt, c.gyro, c.accel, c.bias, densities, gyro_cov)

    def f(dt, gyro, accel, bias, noise, gcov):
        out = it.preintegrate(
            dt, gyro, accel, bias=bias, noise=noise, gyro_cov=gcov, scheme=scheme, method="native",
            return_covariance=True, return_jacobian=True, per_step=per_step,
        )  # fmt: skip
        return tuple(out)

    assert torch.autograd.gradcheck(f, inputs)


# Windows padded at either end: a midpoint window's first sample owns the next interval's step.
PADDED = torch.tensor([[True] * 6, [False, True, True, True, True, False], [False, False, True, True, True, True]])


@pytest.mark.parametrize("jacobian", [True, False])
@pytest.mark.parametrize("per_step", [False, True])
@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_gradcheck_native_noise_densities(scheme: str, per_step: bool, jacobian: bool) -> None:
    """Without the bias Jacobian, lie_euler's final covariance runs ``adjoint/euler.rs`` (the
    rotation error in the start frame), the others ``step.rs``."""
    c = case((3,), 6, seed=16)
    densities = torch.tensor([[1.7e-2, 2.0e-1], [3e-2, 1e-1], [2e-2, 5e-2]], dtype=torch.float64)

    def f(dt, gyro, accel, bias, noise):
        out = it.preintegrate(
            dt, gyro, accel, bias=bias, noise=noise, mask=PADDED, scheme=scheme, method="native",
            return_covariance=True, return_jacobian=jacobian, per_step=per_step,
        )  # fmt: skip
        return tuple(x for x in out if x is not None)

    assert torch.autograd.gradcheck(f, _leaves(c.dt, c.gyro, c.accel, c.bias, densities))


@pytest.mark.parametrize("per_step", [True, False])
@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_native_densities_equal_the_same_noise_per_sample(scheme: str, per_step: bool) -> None:
    c = case((3,), 50, seed=17)
    sigma = torch.tensor([1.7e-2, 2.0e-1], dtype=torch.float64)
    results = []
    for per_sample in (False, True):
        dt, gyro, accel, noise = _leaves(c.dt, c.gyro, c.accel, sigma)
        # Each sample's own step (midpoint: the one it ends; the first sample the one it starts).
        own = torch.cat((dt[:, 1:2], dt[:, 1:]), 1) if scheme == "midpoint" else dt
        given = {"gyro_cov": (noise[0] ** 2 / own)[..., None].expand(3, 50, 3)}
        given["accel_cov"] = (noise[1] ** 2 / own)[..., None].expand(3, 50, 3)
        out = it.preintegrate(
            dt, gyro, accel, scheme=scheme, method="native", return_covariance=True, per_step=per_step,
            **(given if per_sample else {"noise": noise}),
        )  # fmt: skip
        loss = sum((torch.sin(3.0 * x) * (1 + k)).sum() for k, x in enumerate(out) if x is not None)
        results.append((out.covariance, torch.autograd.grad(loss, (dt, gyro, accel, noise))))
    (cov, grads), (cov_ref, grads_ref) = results
    assert gap(cov, cov_ref, relative=True) < 1e-13
    for a, b in zip(grads, grads_ref):
        assert gap(a, b, relative=True) < 1e-12


@pytest.mark.parametrize("scheme", ["lie_euler", "midpoint"])
def test_zero_length_interval_gets_no_noise(scheme: str) -> None:
    """dt = 0 on a valid sample, one rule on every path (docs/torch.md, "dt = 0"): σ²/0 is never
    formed. The kernels' densities, the per-sample blocks built in torch (accelerometer density
    beside a zero gyro covariance, refused as σ²/0 before) and the scan agree and are finite, with
    finite gradients; lie_euler's covariance is the limit of a vanishing step."""
    c = case((2,), 12, seed=5)
    dt = c.dt.clone()
    dt[:, 4] = 0.0
    sigma = torch.tensor([1.7e-2, 2.0e-1], dtype=torch.float64)
    accel_only = torch.tensor([0.0, 2.0e-1], dtype=torch.float64)
    zero_gyro = torch.zeros(2, 12, 3, dtype=torch.float64)

    def cov(step, method, **noise):
        gyro = c.gyro.clone().requires_grad_()
        out = it.preintegrate(step, gyro, c.accel, scheme=scheme, method=method, return_covariance=True, **noise)
        (grad,) = torch.autograd.grad(out.covariance.sum(), gyro)
        assert torch.isfinite(grad).all()
        return out.covariance

    native = cov(dt, "native", noise=sigma)
    assert torch.isfinite(native).all()
    assert gap(native, cov(dt, "scan", noise=sigma), relative=True) < 1e-12
    blocks = cov(dt, "native", noise=sigma, gyro_cov=zero_gyro)
    assert gap(blocks, cov(dt, "native", noise=accel_only), relative=True) < 1e-13
    if scheme == "lie_euler":
        near = dt.clone()
        near[:, 4] = 1e-10
        assert gap(native, cov(near, "native", noise=sigma), relative=True) < 1e-8


def test_gradcheck_native_integrate_and_attitude() -> None:
    c = case((2,), 6, seed=12)
    r0 = torch.linalg.matrix_exp(torch.tensor([[0.0, -0.5, -0.2], [0.5, 0.0, -0.3], [0.2, 0.3, 0.0]]).double())
    v0, p0 = torch.tensor([1.0, 2.0, -0.5]).double(), torch.tensor([-1.0, 0.5, 2.0]).double()
    inputs = _leaves(c.dt, c.gyro, c.accel, c.bias, r0, v0, p0)

    def f(dt, gyro, accel, bias, r, v, p):
        d = it.preintegrate(dt, gyro, accel, bias=bias, scheme="midpoint", method="native", per_step=True)
        start = it.State(r, v, p)
        s = it.integrate(dt, gyro, accel, initial_state=start, bias=bias, scheme="lie_euler", method="native")
        att = it.integrate_attitude(dt, gyro, initial=r, scheme="exp", method="native")
        return (*d[:4], *s, att)

    assert torch.autograd.gradcheck(f, inputs)


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_gradcheck_native_at_zero_rates_and_masked_samples(scheme: str) -> None:
    c = case((2,), 5, seed=14)
    gyro = c.gyro.clone()
    gyro[0, 1] = 0.0
    mask = torch.tensor([[True, True, True, True, True], [False, True, True, True, False]])

    def f(dt, w, a, b):
        out = it.preintegrate(
            dt, w, a, bias=b, noise=torch.tensor([1e-2, 1e-1]).double(), mask=mask, scheme=scheme,
            method="native", return_covariance=True, return_jacobian=True,
        )  # fmt: skip
        return tuple(out)

    assert torch.autograd.gradcheck(f, _leaves(c.dt, gyro, c.accel, c.bias))


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_native_gradients_equal_autograd_through_scan(scheme: str) -> None:
    c = case((3,), 60, seed=21)
    g = torch.Generator().manual_seed(5)
    cov = 1e-3 * torch.rand(3, 60, 3, generator=g, dtype=torch.float64)
    grads = {}
    for method in ("native", "scan"):
        inputs = _leaves(c.dt, c.gyro, c.accel, c.bias, cov)
        dt, gyro, accel, bias, acov = inputs
        linear = LINEAR[scheme]
        out = it.preintegrate(
            dt, gyro, accel, bias=bias, accel_cov=acov if linear else None, scheme=scheme, method=method,
            return_covariance=linear, return_jacobian=linear, per_step=True,
        )  # fmt: skip
        loss = sum((torch.sin(3.0 * x) * (1 + k)).sum() for k, x in enumerate(out) if x is not None)
        grads[method] = torch.autograd.grad(loss, inputs[:4] + (inputs[4:] if linear else ()))
    for a, b in zip(grads["native"], grads["scan"]):
        assert gap(a, b, relative=True) < 1e-10


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_float32_is_widened(scheme: str) -> None:
    c32 = case((2,), 300, seed=4, dtype=torch.float32)
    out = _run(c32, scheme, "native")
    ref = _run(type(c32)(*(x.double() for x in c32)), scheme, "native")
    for name in _fields(scheme):
        got = getattr(out, name)
        assert got.dtype == torch.float32
        assert gap(got, getattr(ref, name), relative=True) < 1.2e-7, name  # float32 rounding only


@pytest.mark.parametrize("method", ["native", "scan"])
@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_mask_equals_windows_alone(scheme: str, method: str) -> None:
    c = case((3,), 40, seed=5)
    spans = [(0, 40), (3, 40), (5, 21)]
    mask = torch.zeros(3, 40, dtype=torch.bool)
    for b, (lo, hi) in enumerate(spans):
        mask[b, lo:hi] = True
    out = _run(c, scheme, method, mask=mask)
    for b, (lo, hi) in enumerate(spans):
        alone = _run(type(c)(c.dt[b, lo:hi], c.gyro[b, lo:hi], c.accel[b, lo:hi], c.bias[b]), scheme, method)
        for name in _fields(scheme):
            got = getattr(out, name)[b]
            assert gap(got, getattr(alone, name), relative=name == "covariance") < 1e-13, (name, b)


def test_native_where_it_does_not_apply_is_refused() -> None:
    c = case((), 5)
    with pytest.raises(ik.ParameterError, match="method: the native kernels need"):
        it.integrate_attitude(c.dt, c.gyro, scheme="rk2", method="native")
    with pytest.raises(ik.ParameterError, match="mask: expected a boolean"):
        it.preintegrate(c.dt, c.gyro, c.accel, mask=torch.ones(5))
    with pytest.raises(ik.ParameterError, match="dt: dt must be steps ≥ 0"):
        it.preintegrate(-c.dt, c.gyro, c.accel, scheme="lie_euler", method="native")
