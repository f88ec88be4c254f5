"""imukit.eval.attitude_error: the BROAD heading / inclination split, against analytic cases and qmt."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

N = 500
# ENU -> NED: x_ned = y_enu (north), y_ned = x_enu (east), z_ned = -z_enu.
ENU_TO_NED = Rotation.from_matrix([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def yaw(a: np.ndarray | float) -> Rotation:
    a = np.atleast_1d(np.asarray(a, dtype=float))
    return Rotation.from_rotvec(np.stack([np.zeros_like(a), np.zeros_like(a), a], axis=-1))


def tilt(angle: np.ndarray | float, azimuth: np.ndarray | float) -> Rotation:
    """Rotation by ``angle`` about the horizontal axis (cos azimuth, sin azimuth, 0)."""
    angle, azimuth = np.broadcast_arrays(np.atleast_1d(angle), np.atleast_1d(azimuth))
    axis = np.stack([np.cos(azimuth), np.sin(azimuth), np.zeros_like(azimuth)], axis=-1)
    return Rotation.from_rotvec(axis * angle[:, None])


@pytest.fixture
def estimate(rng: np.random.Generator) -> Rotation:
    return Rotation.random(N, rng=rng)


def test_pure_heading_error(rng: np.random.Generator, estimate: Rotation) -> None:
    a = rng.uniform(-3.0, 3.0, N)
    err = ik.eval.attitude_error(estimate, yaw(a) * estimate)
    np.testing.assert_allclose(err.heading_signed, a, atol=1e-12)
    np.testing.assert_allclose(err.heading, np.abs(a), atol=1e-12)
    np.testing.assert_allclose(err.total, np.abs(a), atol=1e-12)
    np.testing.assert_allclose(err.inclination, 0.0, atol=1e-12)


def test_pure_inclination_error(rng: np.random.Generator, estimate: Rotation) -> None:
    i = rng.uniform(0.0, 3.0, N)
    err = ik.eval.attitude_error(estimate, tilt(i, rng.uniform(-np.pi, np.pi, N)) * estimate)
    np.testing.assert_allclose(err.inclination, i, atol=1e-12)
    np.testing.assert_allclose(err.total, i, atol=1e-12)
    np.testing.assert_allclose(err.heading, 0.0, atol=1e-12)


@pytest.mark.parametrize("heading_first", [True, False])
def test_combined_error_and_cosine_identity(rng: np.random.Generator, estimate: Rotation, heading_first: bool) -> None:
    h, i, az = rng.uniform(-3.0, 3.0, N), rng.uniform(0.0, 3.0, N), rng.uniform(-np.pi, np.pi, N)
    q_err = yaw(h) * tilt(i, az) if heading_first else tilt(i, az) * yaw(h)
    err = ik.eval.attitude_error(estimate, q_err * estimate)
    np.testing.assert_allclose(err.heading_signed, h, atol=1e-11)
    np.testing.assert_allclose(err.inclination, i, atol=1e-11)
    np.testing.assert_allclose(err.total, q_err.magnitude(), atol=1e-11)
    # exact: cos(total/2) = cos(heading/2) cos(inclination/2)
    np.testing.assert_allclose(np.cos(err.total / 2), np.cos(h / 2) * np.cos(i / 2), atol=1e-14)
    # for small errors, total² ≈ heading² + inclination² only to second order
    small = ik.eval.attitude_error(estimate, yaw(1e-3 * h) * tilt(1e-3 * i, az) * estimate)
    rel = np.abs(small.total**2 - small.heading**2 - small.inclination**2) / small.total**2
    assert rel.max() < 1e-5
    assert np.abs(err.total**2 - err.heading**2 - err.inclination**2).max() > 0.1  # large angles: not Pythagorean


def test_error_is_in_world_frame_not_body_frame() -> None:
    # A turn about the *body* z axis of a body rolled 90° is a world-frame tilt, not a heading error.
    base = Rotation.from_rotvec([np.pi / 2, 0.0, 0.0])  # body z points along world -y
    body_yaw = base * Rotation.from_rotvec([0.0, 0.0, 0.4])
    err = ik.eval.attitude_error(base, body_yaw)
    np.testing.assert_allclose([err.inclination[0], err.heading[0]], [0.4, 0.0], atol=1e-12)


def test_q_and_minus_q_give_identical_errors(rng: np.random.Generator, estimate: Rotation) -> None:
    truth = Rotation.random(N, rng=rng)
    q_est, q_true = estimate.as_quat(), truth.as_quat()
    flip_e, flip_t = rng.choice([-1.0, 1.0], (N, 1)), rng.choice([-1.0, 1.0], (N, 1))
    a = ik.eval.attitude_error(q_est, q_true)
    b = ik.eval.attitude_error(q_est * flip_e, q_true * flip_t)
    for name in ("total", "heading", "inclination", "heading_signed"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), atol=1e-12, err_msg=name)


def test_inputs_rotation_xyzw_and_wxyz_agree(rng: np.random.Generator, estimate: Rotation) -> None:
    truth = Rotation.random(N, rng=rng)
    a = ik.eval.attitude_error(estimate, truth)
    b = ik.eval.attitude_error(estimate.as_quat(), truth.as_quat())
    c = ik.eval.attitude_error(estimate.as_quat(scalar_first=True), truth.as_quat(scalar_first=True), scalar_first=True)
    np.testing.assert_allclose(a.total, b.total, atol=1e-14)
    np.testing.assert_allclose(a.heading_signed, c.heading_signed, atol=1e-14)
    # a single quaternion broadcasts against N
    one = ik.eval.attitude_error(estimate[0].as_quat(), truth.as_quat())
    np.testing.assert_allclose(one.total, (truth * estimate[0].inv()).magnitude(), atol=1e-12)


def test_align_heading_removes_constant_offset_exactly(rng: np.random.Generator, estimate: Rotation) -> None:
    offset = 2.5
    i, az = rng.uniform(0.0, 0.2, N), rng.uniform(-np.pi, np.pi, N)
    truth = yaw(offset) * tilt(i, az) * estimate
    raw = ik.eval.attitude_error(estimate, truth)
    np.testing.assert_allclose(raw.heading, offset, atol=1e-11)
    err = ik.eval.attitude_error(estimate, truth, align_heading=True)
    assert err.heading_offset == pytest.approx(offset, abs=1e-12)
    np.testing.assert_allclose(err.heading, 0.0, atol=1e-11)
    np.testing.assert_allclose(err.inclination, i, atol=1e-11)
    np.testing.assert_allclose(err.total, i, atol=1e-11)
    assert raw.rmse().total > 2.0 > 0.2 > err.rmse().total
    # the same quaternions read as NED: the offset is a turn about +z = down, i.e. −offset about up
    ned = ik.eval.attitude_error(estimate, truth, align_heading=True, world="NED")
    assert ned.heading_offset == pytest.approx(-offset, abs=1e-12)
    np.testing.assert_allclose(ned.total, err.total, atol=1e-12)


def test_align_heading_uses_the_circular_mean(rng: np.random.Generator, estimate: Rotation) -> None:
    # Heading errors scattered around ±π: the arithmetic mean (≈ 0) would be wrong by π.
    h = np.pi + rng.uniform(-0.1, 0.1, N)
    truth = yaw(h) * estimate
    err = ik.eval.attitude_error(estimate, truth, align_heading=True)
    expected = np.arctan2(np.sin(h).sum(), np.cos(h).sum())
    assert abs(abs(err.heading_offset) - np.pi) < 0.02
    assert err.heading_offset == pytest.approx(expected, abs=1e-12)
    np.testing.assert_allclose(err.heading_signed, np.angle(np.exp(1j * (h - expected))), atol=1e-11)
    assert err.heading.max() < 0.2


def test_align_heading_offset_comes_from_the_mask(estimate: Rotation) -> None:
    h = np.where(np.arange(N) < N // 2, 0.3, 1.0)
    truth = yaw(h) * estimate
    mask = np.arange(N) >= N // 2
    err = ik.eval.attitude_error(estimate, truth, align_heading=True, mask=mask)
    assert err.heading_offset == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(err.heading[mask], 0.0, atol=1e-12)
    np.testing.assert_allclose(err.heading[~mask], 0.7, atol=1e-12)
    assert err.rmse().n_samples == N - N // 2
    assert err.rmse().heading == pytest.approx(0.0, abs=1e-12)


def test_enu_and_ned_conventions(rng: np.random.Generator, estimate: Rotation) -> None:
    h, i, az = rng.uniform(-3.0, 3.0, N), rng.uniform(0.0, 1.0, N), rng.uniform(-np.pi, np.pi, N)
    truth = yaw(h) * tilt(i, az) * estimate
    enu = ik.eval.attitude_error(estimate, truth, world="ENU")
    # the same physical attitudes expressed in NED: R_nb = T R_eb
    ned = ik.eval.attitude_error(ENU_TO_NED * estimate, ENU_TO_NED * truth, world="NED")
    for name in ("total", "heading", "inclination", "heading_signed"):
        np.testing.assert_allclose(getattr(ned, name), getattr(enu, name), atol=1e-11, err_msg=name)
    # in NED a positive turn about +z (down) is clockwise seen from above: negative about up
    same_quats_ned = ik.eval.attitude_error(estimate, truth, world="NED")
    np.testing.assert_allclose(same_quats_ned.heading_signed, -h, atol=1e-11)
    np.testing.assert_allclose(same_quats_ned.heading, enu.heading, atol=1e-14)
    # mixing frames is caught by the metric: NED truth against an ENU estimate is far off
    mixed = ik.eval.attitude_error(estimate, ENU_TO_NED * estimate)
    np.testing.assert_allclose(mixed.inclination, np.pi, atol=1e-12)


def test_nan_truth_rows_are_counted_and_excluded(rng: np.random.Generator, estimate: Rotation) -> None:
    i = rng.uniform(0.0, 0.5, N)
    q_true = (tilt(i, 0.0) * estimate).as_quat()
    missing = rng.random(N) < 0.1
    q_true[missing] = np.nan
    err = ik.eval.attitude_error(estimate, q_true, align_heading=True)
    assert err.n_missing == int(missing.sum()) > 0
    np.testing.assert_array_equal(err.valid, ~missing)
    assert np.isnan(err.total[missing]).all() and np.isnan(err.inclination[missing]).all()
    assert np.isfinite(err.total[~missing]).all()
    r = err.rmse()
    assert r.n_samples == int((~missing).sum())
    assert r.inclination == pytest.approx(np.sqrt(np.mean(i[~missing] ** 2)), rel=1e-12)
    assert np.isfinite(err.heading_offset)
    # a user mask never resurrects a NaN row
    assert err.rmse(np.ones(N, dtype=bool)).n_samples == r.n_samples
    with pytest.raises(ik.ParameterError, match=r"^mask: no sample"):
        err.rmse(missing)


def test_rmse_degrees_and_extra_mask(estimate: Rotation) -> None:
    truth = yaw(np.full(N, 0.1)) * estimate
    err = ik.eval.attitude_error(estimate, truth)
    assert err.rmse(degrees=True).heading == pytest.approx(np.degrees(0.1), rel=1e-12)
    first = np.arange(N) < 10
    assert err.rmse(first).n_samples == 10
    assert err.rmse(first.astype(np.uint8)).n_samples == 10  # MATLAB logical masks arrive as uint8
    # one rule for both places a mask enters: integer 0/1 counts as booleans, floats and 2s do not
    aligned = ik.eval.attitude_error(estimate, truth, mask=first.astype(np.uint8), align_heading=True)
    assert aligned.rmse().n_samples == 10
    for bad in (first.astype(np.float64), first.astype(np.int64) * 2):
        with pytest.raises(ik.DTypeError, match=r"^mask: expected a boolean array"):
            err.rmse(bad)
        with pytest.raises(ik.DTypeError, match=r"^mask: expected a boolean array"):
            ik.eval.attitude_error(estimate, truth, mask=bad)


def test_agrees_with_qmt_reference(rng: np.random.Generator, estimate: Rotation) -> None:
    qmt = pytest.importorskip("qmt")
    truth = Rotation.from_rotvec(rng.normal(0.0, 0.7, (N, 3))) * estimate
    q_est, q_true = estimate.as_quat(scalar_first=True), truth.as_quat(scalar_first=True)
    err = ik.eval.attitude_error(q_est, q_true, scalar_first=True)
    # qmt / BROAD form the inverse error quaternion, q_est ⊗ q_truth⁻¹ (same magnitudes)
    q_diff = qmt.qmult(q_est, qmt.qinv(q_true))
    heading, inclination = qmt.headingInclinationAngle(q_diff)
    np.testing.assert_allclose(err.heading, np.abs(heading), atol=1e-10)
    np.testing.assert_allclose(err.inclination, inclination, atol=1e-7)  # qmt uses arccos: ~1e-8 near 0
    np.testing.assert_allclose(err.total, np.abs(qmt.quatAngle(q_diff)), atol=1e-7)
    # and our q_err = q_truth ⊗ q_est⁻¹ is its inverse: heading sign flips
    np.testing.assert_allclose(err.heading_signed, -heading, atol=1e-10)


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"estimate": np.zeros((3, 3))}, ik.ShapeError, "^estimate: expected shape"),
        ({"truth": np.zeros((4, 4, 4))}, ik.ShapeError, "^truth: expected shape"),
        ({"truth": np.tile([0.0, 0, 0, 1], (5, 1))}, ik.ShapeError, "^estimate / truth: lengths differ"),
        ({"truth": np.zeros((4, 4))}, ik.InvalidQuaternionError, "^truth: zero-norm quaternion at sample 0"),
        ({"estimate": np.full((4, 4), np.nan)}, ik.NonFiniteError, "^estimate: NaN at sample 0"),
        ({"truth": np.full((4, 4), np.inf)}, ik.NonFiniteError, "^truth: holds"),
        ({"estimate": np.array([["a"] * 4] * 4)}, ik.DTypeError, "^estimate:"),
        ({"world": "NWU"}, ik.ParameterError, "^world: expected one of"),
        ({"align_heading": "yes"}, ik.ParameterError, "^align_heading:"),
        ({"mask": np.ones(3, dtype=bool)}, ik.ShapeError, "^mask: expected shape"),
        ({"mask": np.full(4, 0.5)}, ik.DTypeError, "^mask: expected a boolean"),
        ({"mask": np.zeros(4, dtype=bool), "align_heading": True}, ik.ParameterError, "^mask: no sample"),
    ],
)
def test_bad_arguments_name_the_argument(kwargs: dict[str, object], error: type[Exception], message: str) -> None:
    args: dict[str, object] = {"estimate": np.tile([0.0, 0, 0, 1], (4, 1)), "truth": np.tile([0.0, 0, 0, 1], (4, 1))}
    args.update(kwargs)
    with pytest.raises(error, match=message):
        ik.eval.attitude_error(args.pop("estimate"), args.pop("truth"), **args)  # type: ignore[arg-type]
