//! Mahony and Madgwick: convergence at the 24 axis-aligned attitudes in ENU and NED (6D in
//! inclination, 9D fully), streaming = batch, save/restore, errors naming the sample, no panics.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::filters::{Filter, GainRamp, Inputs, Law, Madgwick, Mahony, Options, State, World};
use imukit::Error;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

const G: f64 = 9.81;

fn options(world: World) -> Options {
    Options {
        world,
        ..Options::default()
    }
}

/// Runs `$body` with `$f` bound to the Mahony, then the Madgwick filter in `$world`.
macro_rules! for_each_filter {
    ($world:expr, |$f:ident| $body:block) => {{
        {
            let $f = Filter::new(Mahony::default(), options($world)).unwrap();
            $body
        }
        {
            let $f = Filter::new(Madgwick::default(), options($world)).unwrap();
            $body
        }
    }};
}

/// The 24 signed axis permutations with det +1.
fn axis_rotations() -> Vec<Matrix3<f64>> {
    let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let mut out = Vec::new();
    for p in perms {
        for signs in 0..8 {
            let mut m = Matrix3::zeros();
            for (i, &j) in p.iter().enumerate() {
                m[(i, j)] = if signs >> i & 1 == 1 { -1.0 } else { 1.0 };
            }
            if m.determinant() > 0.0 {
                out.push(m);
            }
        }
    }
    out
}

/// Resting readings: specific force points up (ENU `+g z`, NED `−g z`); field 22 µT north, 42 down.
fn readings(world: World, r_wb: &Matrix3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let (up, field) = match world {
        World::Enu => (Vector3::new(0.0, 0.0, G), Vector3::new(0.0, 22.0, -42.0)),
        World::Ned => (Vector3::new(0.0, 0.0, -G), Vector3::new(22.0, 0.0, 42.0)),
    };
    (r_wb.transpose() * up, r_wb.transpose() * field)
}

fn run<L: Law>(
    f: &Filter<L>,
    state: &mut State<L>,
    n: usize,
    accel: Vector3<f64>,
    mag: Option<Vector3<f64>>,
) -> Vec<[f64; 4]> {
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let gyro = vec![[0.0; 3]; n];
    let a = vec![accel.into(); n];
    let m: Option<Vec<[f64; 3]>> = mag.map(|m| vec![m.into(); n]);
    let inputs = Inputs {
        t: &t,
        gyro: &gyro,
        accel: &a,
        mag: m.as_deref(),
    };
    let (mut q, mut b) = (vec![[0.0; 4]; n], vec![[0.0; 3]; n]);
    f.run(state, &inputs, false, &mut q, &mut b).unwrap();
    q
}

fn quaternion(q: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[3], q[0], q[1], q[2]))
}

/// The angle \[rad\] one Madgwick step turns an estimate tilted by `gap` about x, the sensor level
/// and still (gyro zero, 0.01 s from the state's time), every shared stage off so that the law alone acts.
fn madgwick_step(law: Madgwick, gap: f64, nine: bool) -> f64 {
    let options = Options {
        gain_ramp: GainRamp {
            duration_s: 0.0,
            factor: 1.0,
        },
        acc_lowpass: None,
        acc_rejection: None,
        mag_rejection: None,
        rest_detection: None,
        ..options(World::Enu)
    };
    let f = Filter::new(law, options).unwrap();
    let start = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), gap);
    let mut state = State::at(start, Vector3::zeros(), 0.0);
    let (accel, mag) = readings(World::Enu, &Matrix3::identity());
    let q = run(&f, &mut state, 2, accel, nine.then_some(mag));
    assert!(
        quaternion(&q[0]).angle_to(&start) < 1e-15,
        "no step at the state's own time"
    );
    quaternion(&q[1]).angle_to(&start)
}

#[test]
fn madgwick_step_is_proportional_below_the_floor_normalised_above_and_never_past_the_gap() {
    let (beta, dt) = (0.5, 0.01);
    let floored = Madgwick {
        beta,
        full_rate_angle_rad: 0.1,
    };
    for gap in [1e-3_f64, 0.02, 0.05, 0.099, 0.101, 0.3, 1.0] {
        // the step's rate 2β ‖s × v̂‖ / max(‖s × v̂‖, θ₀), ‖s × v̂‖ = sin(gap)
        let expected = 2.0 * beta * dt * (gap.sin() / 0.1).min(1.0);
        let got = madgwick_step(floored, gap, false);
        assert!((got / expected - 1.0).abs() < 1e-6, "gap {gap}: {got} vs {expected}");
        // Madgwick's own normalised step at every gap, and in 9D (the field's heading term is
        // weighted by cos(dip): a shared floor would slow the heading correction); but never past
        // the measurement: at most `d/n` for n measurements, here the gap's sine in 6D and half
        // of it in 9D (about east the field's reference, rebuilt from the estimate, sees no gap)
        let textbook = Madgwick {
            full_rate_angle_rad: 0.0,
            ..floored
        };
        for (law, nine) in [(textbook, false), (floored, true)] {
            let got = madgwick_step(law, gap, nine);
            let expected = (2.0 * beta * dt).min(gap.sin() / if nine { 2.0 } else { 1.0 });
            assert!(
                (got / expected - 1.0).abs() < 1e-6,
                "gap {gap}, 9D {nine}: {got} vs {expected}"
            );
        }
    }
}

#[test]
fn converges_at_24_attitudes_enu_and_ned() {
    let rots = axis_rotations();
    assert_eq!(rots.len(), 24);
    let offset = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.25, 0.35));
    for world in [World::Enu, World::Ned] {
        let up_w = world.up();
        for_each_filter!(world, |f| {
            for m in &rots {
                let truth = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*m));
                let (a, mag) = readings(world, m);
                // 6D from a wrong start: inclination only.
                let mut s = State::at(offset * truth, Vector3::zeros(), 0.0);
                let q = run(&f, &mut s, 2000, a, None);
                let est = quaternion(&q[1999]);
                let inclination = (est.inverse() * up_w).angle(&(truth.inverse() * up_w));
                assert!(
                    inclination < 1e-3,
                    "{world:?} {:?} 6D inclination {inclination}",
                    f.law()
                );
                // 9D: fully, in 30 s: rest detection holds Mahony's integral at the true (zero)
                // bias, so the heading converges at k_P alone (0.13° left after 20 s).
                let mut s = State::at(offset * truth, Vector3::zeros(), 0.0);
                let q = run(&f, &mut s, 3000, a, Some(mag));
                let est = quaternion(&q[2999]);
                assert!(
                    est.angle_to(&truth) < 2e-3,
                    "{world:?} 9D error {}",
                    est.angle_to(&truth)
                );
                // Initialised from the sensors: exact at the first sample.
                let mut s = State::default();
                let q = run(&f, &mut s, 1, a, Some(mag));
                assert!(quaternion(&q[0]).angle_to(&truth) < 1e-12);
            }
        });
    }
}

type Rows = Vec<[f64; 3]>;

fn moving(n: usize) -> (Vec<f64>, Rows, Rows, Rows) {
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.005).collect();
    let gyro = t
        .iter()
        .map(|tk| [0.3 * (1.1 * tk).sin(), 0.2 * (0.7 * tk).cos(), 0.5 * (1.3 * tk).sin()])
        .collect();
    let accel = t
        .iter()
        .map(|tk| {
            [
                0.5 * (0.9 * tk).sin(),
                0.4 * (0.3 * tk).cos(),
                9.81 + 0.2 * (1.7 * tk).sin(),
            ]
        })
        .collect();
    let mag = t
        .iter()
        .map(|tk| [20.0 * (0.2 * tk).cos(), 20.0 * (0.2 * tk).sin(), -40.0])
        .collect();
    (t, gyro, accel, mag)
}

fn streaming_equals_batch<L: Law>(f: &Filter<L>, nine: bool) {
    let n = 3000;
    let (t, gyro, accel, mag) = moving(n);
    let inputs = Inputs {
        t: &t,
        gyro: &gyro,
        accel: &accel,
        mag: nine.then_some(&mag[..]),
    };
    let (mut q, mut b) = (vec![[0.0; 4]; n], vec![[0.0; 3]; n]);
    let mut batch_state = State::default();
    f.run(&mut batch_state, &inputs, false, &mut q, &mut b).unwrap();

    let v = |x: &Rows, k: usize| Vector3::from(x[k]);
    let mut s = State::default();
    let mut saved = None;
    for k in 0..n {
        let dt = if k == 0 { 0.0 } else { t[k] - t[k - 1] };
        let m = nine.then(|| v(&mag, k));
        f.update(&mut s, &v(&gyro, k), &v(&accel, k), m.as_ref(), dt).unwrap();
        assert_eq!(s.common.q.coords.as_slice(), &q[k], "sample {k}");
        if k == 1000 {
            saved = Some(s);
        }
    }
    // Restore at 1000 and resume: the same numbers.
    let mut r = saved.unwrap();
    for k in 1001..n {
        let m = nine.then(|| v(&mag, k));
        f.update(&mut r, &v(&gyro, k), &v(&accel, k), m.as_ref(), t[k] - t[k - 1])
            .unwrap();
    }
    assert_eq!(r, s);
    // A state rebuilt from its stored numbers is the same state, bit for bit.
    assert_eq!(s.common.restored(s.common.q.coords.into()).unwrap(), s.common);
    // Batch split in two, the second part continuing the first: the same numbers.
    let cut = 1234;
    let mut st = State::default();
    let (mut q1, mut b1) = (vec![[0.0; 4]; cut], vec![[0.0; 3]; cut]);
    let first = Inputs {
        t: &t[..cut],
        gyro: &gyro[..cut],
        accel: &accel[..cut],
        mag: nine.then_some(&mag[..cut]),
    };
    f.run(&mut st, &first, false, &mut q1, &mut b1).unwrap();
    let rest = Inputs {
        t: &t[cut..],
        gyro: &gyro[cut..],
        accel: &accel[cut..],
        mag: nine.then_some(&mag[cut..]),
    };
    let (mut q2, mut b2) = (vec![[0.0; 4]; n - cut], vec![[0.0; 3]; n - cut]);
    f.run(&mut st, &rest, true, &mut q2, &mut b2).unwrap();
    q1.extend(q2);
    assert_eq!(q1, q);
}

#[test]
fn streaming_equals_batch_and_restore_resumes_identically() {
    for nine in [false, true] {
        for_each_filter!(World::Ned, |f| { streaming_equals_batch(&f, nine) });
    }
}

/// A state saved by the filter of one world and continued by the filter of the other: the
/// attitude turned into the new world, not read as if it were already in it (180° off before).
fn continued_in_the_other_world<L: Law>(ned: &Filter<L>, enu: &Filter<L>) {
    let n = 2000;
    let cut = 700;
    let (t, gyro, accel, mag) = moving(n);
    let part = |r: std::ops::Range<usize>| Inputs {
        t: &t[r.clone()],
        gyro: &gyro[r.clone()],
        accel: &accel[r.clone()],
        mag: Some(&mag[r]),
    };
    let out = |m: usize| (vec![[0.0; 4]; m], vec![[0.0; 3]; m]);
    let mut s = State::default();
    let (mut q, mut b) = out(cut);
    ned.run(&mut s, &part(0..cut), false, &mut q, &mut b).unwrap();
    let saved = s;
    let (mut q_enu, mut b_enu) = out(n - cut);
    enu.run(&mut s, &part(cut..n), true, &mut q_enu, &mut b_enu).unwrap();
    assert_eq!(s.common.world, Some(World::Enu));

    // The reference: the NED filter carries on, and its attitudes are turned into ENU.
    let mut r = saved;
    let (mut q_ned, mut b_ned) = out(n - cut);
    ned.run(&mut r, &part(cut..n), true, &mut q_ned, &mut b_ned).unwrap();
    // ENU from NED: x ↔ y, z flipped.
    let turn = Rotation3::from_matrix_unchecked(Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0));
    let turn = UnitQuaternion::from_rotation_matrix(&turn);
    for k in [0, 1, 500, n - cut - 1] {
        let want = turn * quaternion(&q_ned[k]);
        let angle = quaternion(&q_enu[k]).angle_to(&want);
        assert!(angle < 1e-6, "sample {k}: {angle} rad from the NED run turned into ENU");
    }
    // Streaming takes a state of the other world the same way.
    let mut u = saved;
    let k = cut;
    let dt = t[k] - t[k - 1];
    enu.update(
        &mut u,
        &Vector3::from(gyro[k]),
        &Vector3::from(accel[k]),
        Some(&Vector3::from(mag[k])),
        dt,
    )
    .unwrap();
    assert_eq!(u.common.q.coords.as_slice(), &q_enu[0]);
}

#[test]
fn a_state_of_the_other_world_is_turned_into_the_filters() {
    let ned = Filter::new(Mahony::default(), options(World::Ned)).unwrap();
    let enu = Filter::new(Mahony::default(), options(World::Enu)).unwrap();
    continued_in_the_other_world(&ned, &enu);
    let ned = Filter::new(Madgwick::default(), options(World::Ned)).unwrap();
    let enu = Filter::new(Madgwick::default(), options(World::Enu)).unwrap();
    continued_in_the_other_world(&ned, &enu);
}

/// Heading error [rad] after 10 s of a level sensor turning at 0.5 rad/s about up, started 30° off
/// in heading, streamed with the field on every `every`-th sample (`mag = None` between).
fn heading_error_with_field_every<L: Law>(f: &Filter<L>, every: usize) -> f64 {
    let (rate, dt, n) = (0.5, 0.01, 1001);
    let truth = |k: usize| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.3 + rate * k as f64 * dt);
    let field = Vector3::new(0.0, 22.0, -42.0);
    let start = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 30f64.to_radians()) * truth(0);
    let mut s = State::at(start, Vector3::zeros(), 0.0);
    for k in 1..n {
        let m = (k % every == 0).then(|| truth(k).inverse_transform_vector(&field));
        let (gyro, accel) = (Vector3::new(0.0, 0.0, rate), Vector3::new(0.0, 0.0, G));
        f.update(&mut s, &gyro, &accel, m.as_ref(), dt).unwrap();
    }
    s.common.q.angle_to(&truth(n - 1))
}

/// A field slower than the gyro (`mag = None` between its samples) corrects the heading at the
/// rate a field on every sample does: the last field sample, turned by the gyro, stands in
/// between. On the field's samples alone, a 10 Hz field had a tenth of the gain (30° → 15.3° in
/// 10 s for Mahony, 25.7° for Madgwick, where a field on every sample leaves 0.30° / 0.28°).
#[test]
fn a_field_slower_than_the_gyro_keeps_the_heading_gain() {
    let laws: [&dyn Fn(usize) -> f64; 2] = [
        &|every| heading_error_with_field_every(&Filter::new(Mahony::default(), options(World::Enu)).unwrap(), every),
        &|every| heading_error_with_field_every(&Filter::new(Madgwick::default(), options(World::Enu)).unwrap(), every),
    ];
    for (law, heading) in ["Mahony", "Madgwick"].iter().zip(laws) {
        let full = heading(1);
        for every in [4, 10, 50] {
            let slow = heading(every);
            assert!(
                (slow - full).abs() < 0.25 * full + 1e-3,
                "{law}, field every {every}th sample: {:.2}° after 10 s, {:.2}° with the field on every sample",
                slow.to_degrees(),
                full.to_degrees()
            );
        }
    }
}

#[test]
fn errors_name_input_and_sample() {
    let n = 10;
    let (t, gyro, mut accel, mut mag) = moving(n);
    let f = Filter::new(Mahony::default(), options(World::Enu)).unwrap();
    let mut out = (vec![[0.0; 4]; n], vec![[0.0; 3]; n]);
    accel[6][2] = f64::NAN;
    let inputs = Inputs {
        t: &t,
        gyro: &gyro,
        accel: &accel,
        mag: None,
    };
    let e = f
        .run(&mut State::default(), &inputs, false, &mut out.0, &mut out.1)
        .unwrap_err();
    assert_eq!(e, Error::NonFinite { index: 6 }.in_argument("accel"));
    let good = moving(n).2;
    mag[9][0] = f64::INFINITY;
    let inputs = Inputs {
        t: &t,
        gyro: &gyro,
        accel: &good,
        mag: Some(&mag),
    };
    let e = f
        .run(&mut State::default(), &inputs, false, &mut out.0, &mut out.1)
        .unwrap_err();
    assert_eq!(e, Error::NonFinite { index: 9 }.in_argument("mag"));
    let short = Inputs {
        gyro: &gyro[..2],
        ..inputs
    };
    let e = f
        .run(&mut State::default(), &short, false, &mut out.0, &mut out.1)
        .unwrap_err();
    assert!(matches!(e, Error::Argument { name: "gyro", .. }));
    let bad = Options {
        gravity: -1.0,
        ..Options::default()
    };
    assert!(matches!(
        Filter::new(Mahony::default(), bad),
        Err(Error::Parameter { name: "gravity", .. })
    ));
}

fn extreme_finite_input<L: Law>(filter: &Filter<L>) {
    let values = [0.0, 1e-300, -1e-300, 1e300, -1e300, f64::MAX, f64::MIN_POSITIVE, 3.0];
    let mut s = State::default();
    for (i, &x) in values.iter().enumerate() {
        for &y in &values {
            let v = Vector3::new(x, y, values[(i + 3) % values.len()]);
            for r in [
                filter.update(&mut s, &v, &Vector3::new(y, x, 9.81), Some(&v), 0.01),
                filter.update(&mut s, &v, &v, None, 1e-3),
            ] {
                if let Err(e) = r {
                    // The state overflowed, or the field's squared norm did (refused up front,
                    // naming `mag`: it would become the gate's reference).
                    let named = e.argument().is_none_or(|name| name == "mag");
                    assert!(named && matches!(e.root(), Error::Overflow { .. }), "{e}");
                    s = State::default(); // an overflowed state is reported, then discarded
                }
            }
        }
    }
}

#[test]
fn extreme_finite_input_does_not_panic() {
    for_each_filter!(World::Enu, |f| { extreme_finite_input(&f) });
}

/// An error part-way through a batch run (row 700, then 900: inside a block of a loop that
/// computes its input-only values ahead, `docs/performance.md`) is the row's, and leaves the state
/// of the last good row: streaming's over the rows before it, bit for bit (rest detection's means
/// included), with the clock at its stamp.
fn error_part_way<L: Law>(f: &Filter<L>) {
    let n = 1000;
    let (t, gyro, accel, mag) = moving(n);
    let v = |x: &Rows, k: usize| Vector3::from(x[k]);
    let streamed = |rows: usize| {
        let mut s = State::default();
        for k in 0..rows {
            let dt = if k == 0 { 0.0 } else { t[k] - t[k - 1] };
            f.update(&mut s, &v(&gyro, k), &v(&accel, k), Some(&v(&mag, k)), dt)
                .unwrap();
        }
        s.common.time = t[rows - 1];
        s
    };
    let mut bad_accel = accel.clone();
    bad_accel[700][1] = f64::INFINITY;
    let mut bad_t = t.clone();
    bad_t[900] = bad_t[899];
    let cases = [
        (
            &t,
            &bad_accel,
            Error::NonFinite { index: 700 }.in_argument("accel"),
            700,
        ),
        (
            &bad_t,
            &accel,
            Error::NonIncreasingTime { index: 900, dt: 0.0 }.in_argument("t"),
            900,
        ),
    ];
    for (t, accel, expected, good) in cases {
        let inputs = Inputs {
            t,
            gyro: &gyro,
            accel,
            mag: Some(&mag),
        };
        let (mut q, mut b) = (vec![[0.0; 4]; n], vec![[0.0; 3]; n]);
        let mut s = State::default();
        let e = f.run(&mut s, &inputs, false, &mut q, &mut b).unwrap_err();
        assert_eq!(e, expected);
        assert_eq!(s, streamed(good));
    }
}

#[test]
fn an_error_part_way_leaves_the_last_good_rows_state() {
    for_each_filter!(World::Enu, |f| { error_part_way(&f) });
}

/// One step of `dt` from an estimate `gap` rad off the truth (about a world axis: horizontal in
/// 6D, where the heading is not observed), the sensor turning at `rate` (body axes, rad/s); the
/// error vector (world frame) before and after.
fn error_after_one_step<L: Law>(
    f: &Filter<L>,
    world: World,
    nine: bool,
    (gap, dt, rate): (f64, f64, Vector3<f64>),
    ramped: bool,
) -> (Vector3<f64>, Vector3<f64>) {
    let truth = UnitQuaternion::from_scaled_axis(Vector3::new(0.2, -0.4, 1.0));
    let axis = if nine {
        Vector3::new(1.0, 2.0, 3.0).normalize()
    } else {
        Vector3::new(3.0, -1.0, 0.0).normalize()
    };
    let start = UnitQuaternion::from_scaled_axis(axis * gap) * truth;
    let mut s = State::at(start, Vector3::zeros(), 0.0);
    if ramped {
        s.common.ramp_elapsed = f.options().gain_ramp.duration_s;
    }
    let end = truth * UnitQuaternion::from_scaled_axis(rate * dt);
    let (accel, mag) = readings(world, end.to_rotation_matrix().matrix());
    let m = nine.then_some(mag);
    f.update(&mut s, &rate, &accel, m.as_ref(), dt).unwrap();
    (
        (start * truth.inverse()).scaled_axis(),
        (s.common.q * end.inverse()).scaled_axis(),
    )
}

/// A long step (a gap in the stamps) turns the estimate towards the measurement but never past
/// it, whatever the gap, in the gain ramp (gates open, gain ×10) and after it, still and turning
/// (the measurement then compared with the estimate turned by the gyro). The correction
/// `k_P ρ ω_mes dt` (Mahony) and `2βρ dt` (Madgwick) grew with `dt` unbounded: a 5 s gap at rest
/// on BROAD 01 (9D) left Madgwick 141° and Mahony 13.6° off the uninterrupted run in the gain
/// ramp, 20.8° and 7.8° after it; compared with the estimate before the gyro's turn, Madgwick
/// after the ramp went 20° off in a 5 s step at 0.19 rad/s.
#[test]
fn a_long_step_never_overshoots_the_measurement() {
    for world in [World::Enu, World::Ned] {
        for_each_filter!(world, |f| {
            for (nine, ramped) in [(false, false), (true, false), (false, true), (true, true)] {
                for gap in [1e-4, 0.02, 0.3, 1.0] {
                    for dt in [0.01, 1.0, 2.0, 5.0, 10.0, 100.0, 1e6] {
                        // A step at a normal rate compares with the estimate before the gyro's
                        // turn (a lag of one sample, docs/filters.md), which a gap of 1e-4 rad
                        // does not dominate: turning only from 1 s (a turn of 0.06 rad or more,
                        // past LONG_TURN_RAD from 2 s at the slower rate). 1e-9 rad: the rounding
                        // of a 1e6 s turn.
                        let turning = if dt >= 1.0 { &[0.0, 0.05, 0.3][..] } else { &[0.0][..] };
                        for &w in turning {
                            let rate = Vector3::new(1.0, -2.0, 3.0) * w;
                            if dt * rate.norm() > 0.0 && dt * rate.norm() <= imukit::filters::LONG_TURN_RAD {
                                continue;
                            }
                            // After the ramp the gate rejects a tilt beyond its 3°, and a 9D
                            // heading correction with nothing to level it lands on the field's
                            // heading seen from the tilted estimate (tan(dip) per radian of tilt
                            // off the truth: where Mahony converges at any rate).
                            if ramped && nine && gap > 0.05 {
                                continue;
                            }
                            let (before, after) = error_after_one_step(&f, world, nine, (gap, dt, rate), ramped);
                            assert!(
                                after.norm() <= before.norm() + 1e-9 && after.dot(&before) >= -1e-9 * before.norm(),
                                "{world:?} {:?} 9D {nine} ramped {ramped}, gap {gap} rad, dt {dt} s, rate {rate:?}: \
                                 error {before:?} → {after:?}",
                                f.law()
                            );
                            // after the ramp the gates reject a gap beyond their 3° (an
                            // acceleration, until the recovery), so only 0.02 rad must shrink
                            if dt >= 2.0 && gap >= 0.02 && (!ramped || gap < 0.05) {
                                assert!(
                                    after.norm() < 0.9 * before.norm(),
                                    "{world:?} {:?} 9D {nine} ramped {ramped}, gap {gap}, dt {dt}, rate {rate:?}: \
                                     no correction, {after:?}",
                                    f.law()
                                );
                            }
                        }
                    }
                }
            }
        });
    }
}
