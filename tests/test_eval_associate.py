"""imukit.eval.associate: interpolation checked by hand, drops counted exactly, nanosecond exactness."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

MS = 1_000_000  # ns


def still(t_ns: np.ndarray) -> ik.Trajectory:
    """A trajectory at rest at the origin with the given nanosecond stamps."""
    n = len(t_ns)
    return ik.Trajectory(None, np.zeros((n, 3)), None, Rotation.identity(n), t_ns=t_ns)


def test_interpolation_at_hand_computed_points() -> None:
    rz90 = Rotation.from_rotvec([0.0, 0.0, np.pi / 2])
    ref = ik.Trajectory(
        np.array([0.0, 1.0, 2.0]),
        [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 4.0, 0.0]],
        [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 4.0, 0.0]],
        Rotation.concatenate([Rotation.identity(), rz90, rz90 * Rotation.from_rotvec([np.pi / 2, 0.0, 0.0])]),
        gyro_bias=[[0.0, 0.0, 0.0], [0.04, 0.0, 0.0], [0.04, 0.0, 0.08]],
        accel_bias=np.zeros((3, 3)),
    )
    est = ik.Trajectory(np.array([0.5, 1.25, 2.0]), np.ones((3, 3)), None, Rotation.identity(3))
    pair = ik.eval.associate(est, ref, max_dt=1.0)
    assert pair.n_dropped == 0 and pair.mask.all()
    np.testing.assert_allclose(pair.reference.t, [0.5, 1.25, 2.0], atol=0)
    np.testing.assert_allclose(pair.reference.position, [[1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [2.0, 4.0, 0.0]], atol=1e-15)
    assert pair.reference.velocity is not None
    np.testing.assert_allclose(pair.reference.velocity, [[1.0, 0.0, 0.0], [1.5, 1.0, 0.0], [0.0, 4.0, 0.0]], atol=1e-15)
    assert pair.reference.gyro_bias is not None
    np.testing.assert_allclose(pair.reference.gyro_bias, [[0.02, 0.0, 0.0], [0.04, 0.0, 0.02], [0.04, 0.0, 0.08]])
    # slerp: halfway from I to Rz(90°) is Rz(45°) = (0, 0, sin 22.5°, cos 22.5°); a quarter of the way
    # from Rz(90°) to Rz(90°) Rx(90°) is Rz(90°) Rx(22.5°) = (cos 45° sin 11.25°)(1, 1, 0) + ...
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    a, b = np.cos(np.pi / 16), np.sin(np.pi / 16)
    expected = np.array(
        [
            [0.0, 0.0, np.sin(np.pi / 8), np.cos(np.pi / 8)],
            [c * b, s * b, s * a, c * a],  # (0, 0, s, c) ⊗ (b, 0, 0, a)
            (rz90 * Rotation.from_rotvec([np.pi / 2, 0.0, 0.0])).as_quat(),
        ]
    )
    got = pair.reference.rotation.as_quat()
    np.testing.assert_allclose(got * np.sign(got[:, 3:]), expected * np.sign(expected[:, 3:]), atol=1e-15)
    # the estimate is kept as it was, at the same instants
    np.testing.assert_array_equal(pair.estimate.position, est.position)
    np.testing.assert_array_equal(pair.estimate.t, pair.reference.t)


def test_gap_and_span_drops_are_counted_exactly() -> None:
    # reference: 0 … 1000 ms and 1500 … 2000 ms every 10 ms (a 500 ms dropout); estimate every 5 ms
    ref_ns = np.concatenate([np.arange(0, 1000 * MS + 1, 10 * MS), np.arange(1500 * MS, 2000 * MS + 1, 10 * MS)])
    est_ns = np.arange(-200 * MS, 2300 * MS + 1, 5 * MS)
    pair = ik.eval.associate(still(est_ns), still(ref_ns), max_dt=0.02)
    # outside: −200 … −5 ms (40 samples) and 2005 … 2300 ms (60); gap: 1005 … 1495 ms (99)
    assert (pair.n_outside_span, pair.n_in_gaps, pair.n_dropped) == (100, 99, 199)
    expected = ((est_ns >= 0) & (est_ns <= 1000 * MS)) | ((est_ns >= 1500 * MS) & (est_ns <= 2000 * MS))
    np.testing.assert_array_equal(pair.mask, expected)
    assert len(pair.estimate) == len(est_ns) - 199 == 302
    assert pair.reference.t_ns is not None
    np.testing.assert_array_equal(pair.reference.t_ns, est_ns[expected])
    # a max_dt just under the 10 ms spacing refuses every interpolation: only exact hits stay (every other)
    strict = ik.eval.associate(still(est_ns), still(ref_ns), max_dt=0.0099)
    assert len(strict.estimate) == len(ref_ns) == 152
    assert strict.n_in_gaps == 302 - 152 + 99


def test_offset_is_added_to_the_estimate_stamps() -> None:
    # reference moving along p(t) = (t, 2t, −t) every 0.1 s: linear interpolation is exact
    t = np.round(np.arange(0.0, 5.0001, 0.1), 12)
    ref = ik.Trajectory(t, np.outer(t, [1.0, 2.0, -1.0]), None, Rotation.identity(len(t)))
    est_t = np.array([0.0, 1.01, 2.37, 4.9])
    pair = ik.eval.associate(
        ik.Trajectory(est_t, np.zeros((4, 3)), None, Rotation.identity(4)), ref, max_dt=0.2, offset=0.05
    )
    s = est_t + 0.05
    np.testing.assert_allclose(pair.reference.t, s, atol=0)
    np.testing.assert_allclose(pair.reference.position, np.outer(s, [1.0, 2.0, -1.0]), atol=1e-12)
    # 4.9 + 0.05 is inside, 4.9 + 0.15 is not
    late = ik.eval.associate(
        ik.Trajectory(est_t, np.zeros((4, 3)), None, Rotation.identity(4)), ref, max_dt=0.2, offset=0.15
    )
    assert late.n_outside_span == 1 and not late.mask[-1]


def test_nanosecond_stamps_interpolate_exactly_where_float_seconds_cannot() -> None:
    # epoch stamps (2014): float seconds there resolve only 0.24 µs
    ref_ns = 1_403_715_524_907_143_168 + np.arange(0, 201) * 5_000_192
    est_ns = ref_ns[:-1] + 2_500_096  # exact midpoints, in integer nanoseconds
    p = np.outer(np.arange(201.0), [1.0, 0.0, 0.0])  # 1 m per reference step
    ref = ik.Trajectory(None, p, None, Rotation.identity(201), t_ns=ref_ns)
    est = ik.Trajectory(None, np.zeros((200, 3)), None, Rotation.identity(200), t_ns=est_ns)
    exact = ik.eval.associate(est, ref).reference.position[:, 0]
    np.testing.assert_array_equal(exact, np.arange(200) + 0.5)
    as_float = ik.eval.associate(
        ik.Trajectory(est_ns * 1e-9, np.zeros((200, 3)), None, Rotation.identity(200)),
        ik.Trajectory(ref_ns * 1e-9, p, None, Rotation.identity(201)),
    ).reference.position[:, 0]
    # one ulp of an epoch stamp (2.4e-7 s) is 4.8e-5 of a 5 ms step: 2.4e-5 m at 1 m per step here
    assert np.abs(as_float - (np.arange(200) + 0.5)).max() > 1e-5


def test_single_sample_reference_pairs_only_an_exact_stamp() -> None:
    pair = ik.eval.associate(still(np.array([0, 10, 20]) * MS), still(np.array([10 * MS])))
    np.testing.assert_array_equal(pair.mask, [False, True, False])
    assert pair.n_outside_span == 2


def test_no_survivor_names_both_spans() -> None:
    est = ik.Trajectory(np.array([10.0, 11.0]), np.zeros((2, 3)), None, Rotation.identity(2))
    ref = ik.Trajectory(np.array([0.0, 1.0]), np.zeros((2, 3)), None, Rotation.identity(2))
    with pytest.raises(ik.ParameterError, match=r"^estimate: no estimate sample .* \[10, 11\] s .* \[0, 1\] s; 2 "):
        ik.eval.associate(est, ref)
    # a clock offset brings them together; a wrong one is named first
    assert ik.eval.associate(est, ref, offset=-10.0).n_dropped == 0
    with pytest.raises(ik.ParameterError, match=r"^offset: no estimate sample .* \[15, 16\] s \(offset 5 s applied\)"):
        ik.eval.associate(est, ref, offset=5.0)
    # every sample inside the span but in gaps: max_dt is what refused them
    inside = ik.Trajectory(np.array([0.25, 0.5]), np.zeros((2, 3)), None, Rotation.identity(2))
    with pytest.raises(ik.ParameterError, match=r"^max_dt: no estimate sample .* 0 samples outside .* 2 inside"):
        ik.eval.associate(inside, ref, max_dt=0.5)


def test_offset_beyond_the_int64_nanosecond_range_is_refused() -> None:
    t_ns = np.array([1_403_715_524_907_143_168, 1_403_715_524_912_143_104])
    with pytest.raises(ik.ParameterError, match=r"^offset: 1e\+10 s moves the estimate's nanosecond stamps out"):
        ik.eval.associate(still(t_ns), still(t_ns), offset=1e10)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_dt": 0.0}, "^max_dt: expected a finite positive number"),
        ({"max_dt": float("inf")}, "^max_dt: expected a finite positive"),
        ({"offset": float("nan")}, "^offset: expected a finite number"),
        ({"offset": "1"}, "^offset: expected a number"),
        ({"reference": np.zeros((3, 3))}, "^reference: expected an imukit Trajectory"),
    ],
)
def test_bad_arguments(kwargs: dict[str, object], message: str) -> None:
    args: dict[str, object] = {"estimate": still(np.array([0, MS])), "reference": still(np.array([0, MS]))}
    args.update(kwargs)
    with pytest.raises(ik.ParameterError, match=message):
        ik.eval.associate(args.pop("estimate"), args.pop("reference"), **args)  # type: ignore[arg-type]
