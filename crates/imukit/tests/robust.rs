//! `Robust` on simulated motion: accelerations do not tilt it, the bias is estimated (at rest and
//! in motion alone) with a consistent σ, a disturbed field (norm or dip) changes neither inclination nor heading, its
//! rejection is bounded in time, a new homogeneous field is accepted, streaming = batch,
//! save / restore / resume, NED = ENU rotated, the smoother deterministic and finite.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::filters::{Inputs, Robust, RobustParams, RobustState, RobustTrack, World};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

const G: f64 = 9.81;
const RATE: f64 = 100.0;

/// A simulated record: truth `q_wb` (ENU) and the sensor samples.
struct Record {
    t: Vec<f64>,
    truth: Vec<UnitQuaternion<f64>>,
    gyro: Vec<[f64; 3]>,
    accel: Vec<[f64; 3]>,
    mag: Vec<[f64; 3]>,
}

impl Record {
    fn inputs(&self, nine: bool) -> Inputs<'_> {
        Inputs {
            t: &self.t,
            gyro: &self.gyro,
            accel: &self.accel,
            mag: nine.then_some(&self.mag[..]),
        }
    }
}

/// Deterministic standard normal numbers (xorshift64* and Box–Muller), one stream per seed.
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    fn vec(&mut self, sigma: f64) -> Vector3<f64> {
        Vector3::new(self.normal(), self.normal(), self.normal()) * sigma
    }
}

const FIELD: [f64; 3] = [0.0, 20.0, -40.0]; // µT, ENU: north and down (dip about 63°)

/// `seconds` of motion with body rate `omega(t)`, world acceleration `acc(t)` (ENU, m/s²), world
/// field `field(t)`, gyro bias `bias`, white noise `sigma_gyro` / `sigma_acc` from `seed`.
#[allow(clippy::too_many_arguments)]
fn simulate(
    seconds: f64,
    q0: UnitQuaternion<f64>,
    omega: impl Fn(f64) -> Vector3<f64>,
    acc: impl Fn(f64) -> Vector3<f64>,
    field: impl Fn(f64) -> Vector3<f64>,
    bias: Vector3<f64>,
    (sigma_gyro, sigma_acc, seed): (f64, f64, u64),
) -> Record {
    let n = (seconds * RATE) as usize;
    let mut noise = Noise(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut q = q0;
    let mut r = Record {
        t: Vec::new(),
        truth: Vec::new(),
        gyro: Vec::new(),
        accel: Vec::new(),
        mag: Vec::new(),
    };
    for k in 0..n {
        let t = k as f64 / RATE;
        let w = omega(t);
        let f = q.inverse() * (acc(t) + Vector3::new(0.0, 0.0, G)) + noise.vec(sigma_acc);
        r.t.push(t);
        r.truth.push(q);
        r.gyro.push((w + bias + noise.vec(sigma_gyro)).into());
        r.accel.push(f.into());
        r.mag.push((q.inverse() * field(t)).into());
        q *= UnitQuaternion::from_scaled_axis(w / RATE);
    }
    r
}

/// The attitude of row `k`.
fn quat(o: &RobustTrack, k: usize) -> UnitQuaternion<f64> {
    let [x, y, z, w] = o.q[k];
    UnitQuaternion::new_normalize(Quaternion::new(w, x, y, z))
}

fn run(f: &Robust, r: &Record, nine: bool, offline: bool) -> RobustTrack {
    let mut out = RobustTrack::new(r.t.len());
    let mut s = RobustState::default();
    if offline {
        f.smooth(&mut s, &r.inputs(nine), &mut out.outputs()).unwrap();
    } else {
        f.run(&mut s, &r.inputs(nine), false, &mut out.outputs()).unwrap();
    }
    out
}

/// Turning (after 5 s at rest) with noise, no acceleration, the clean field.
fn turning_record(seconds: f64, bias: Vector3<f64>, seed: u64) -> Record {
    simulate(
        seconds,
        tilted(),
        turning,
        |_| Vector3::zeros(),
        |_| FIELD.into(),
        bias,
        (0.003, 0.03, seed),
    )
}

/// Angle between the estimated and the true up direction in the body [°].
fn tilt_deg(est: &UnitQuaternion<f64>, truth: &UnitQuaternion<f64>) -> f64 {
    let (a, b) = (est.inverse() * Vector3::z(), truth.inverse() * Vector3::z());
    a.angle(&b).to_degrees()
}

/// Heading of `q`'s body x axis projected on the horizontal \[rad\] (ENU).
fn heading(q: &UnitQuaternion<f64>) -> f64 {
    let x = q * Vector3::x();
    x.y.atan2(x.x)
}

fn filter() -> Robust {
    Robust::new(RobustParams::default(), World::Enu).unwrap()
}

fn turning(t: f64) -> Vector3<f64> {
    if t < 5.0 {
        Vector3::zeros()
    } else {
        Vector3::new(
            0.4 * (0.7 * t).sin(),
            0.3 * (0.5 * t + 1.0).sin(),
            0.5 * (0.3 * t).cos(),
        )
    }
}

fn tilted() -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0)
}

#[test]
fn figure_eight_accelerations_cancel() {
    // Horizontal figure eight with 3 m/s² peaks on each axis (period 4 s) while turning, faded in
    // over 10 s (a sine switched on at full amplitude has a low-frequency part of its own).
    let w = std::f64::consts::TAU / 4.0;
    let acc = |t: f64| Vector3::new(-3.0 * (w * t).sin(), -3.0 * (2.0 * w * t).sin(), 0.0) * (t / 10.0).min(1.0);
    let r = simulate(
        60.0,
        tilted(),
        turning,
        acc,
        |_| FIELD.into(),
        Vector3::zeros(),
        (0.0, 0.0, 1),
    );
    let out = run(&filter(), &r, false, false);
    let worst = (0..r.t.len())
        .map(|k| tilt_deg(&quat(&out, k), &r.truth[k]))
        .fold(0.0, f64::max);
    // A filter correcting towards the raw accelerometer tilts by up to atan(3√2/g) ≈ 23°; the
    // Butterworth (τ = 2 s) passes 10% at 0.25 Hz: 2.14° measured. The 0.5° needs τ ≈ 4 s,
    // which costs accuracy on BROAD (docs/filters_robust.md, limits); 20% worse fails.
    assert!(worst < 2.55, "worst tilt {worst}°");
}

#[test]
fn offline_filters_the_specific_force_forward_then_backward() {
    // A still sensor accelerated along x, A sin(2π f t), f = 0.25 Hz: the estimated up leans by
    // the filtered specific force, u_x = ā_x/g. Online ā = H a (the Butterworth: |H| = 0.10 at
    // f/f_c = 3.14, f_c = 1/(2π τ), τ = 2 s, phase about −163°); the smoother filters it forward
    // then backward in the inertial frame, ā = |H|² a: amplitude 1.0% of A/g and no phase.
    let (amp, f) = (3.0, 0.25);
    let w = std::f64::consts::TAU * f;
    let r = simulate(
        60.0,
        UnitQuaternion::identity(),
        |_| Vector3::zeros(),
        |t| Vector3::new(amp * (w * t).sin(), 0.0, 0.0),
        |_| FIELD.into(),
        Vector3::zeros(),
        (0.0, 0.0, 1),
    );
    // Least-squares fit of u_x = α sin + β cos over the middle 20 s (away from the ends).
    let fit = |o: &RobustTrack| {
        let (mut ss, mut sc, mut cc, mut ys, mut yc) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for k in (0..r.t.len()).filter(|&k| (20.0..40.0).contains(&r.t[k])) {
            let (s, c) = (w * r.t[k]).sin_cos();
            let u = (quat(o, k).inverse() * Vector3::z()).x;
            (ss, sc, cc, ys, yc) = (ss + s * s, sc + s * c, cc + c * c, ys + u * s, yc + u * c);
        }
        let det = ss * cc - sc * sc;
        ((ys * cc - yc * sc) / det, (yc * ss - ys * sc) / det)
    };
    let gain = 1.0 / (1.0 + (std::f64::consts::TAU * f * 2.0).powi(4)).sqrt();
    let (alpha, beta) = fit(&run(&filter(), &r, false, true));
    let expected = gain * gain * amp / G;
    assert!(
        (alpha / expected - 1.0).abs() < 0.02,
        "α {alpha} vs |H|² A/g {expected}"
    );
    assert!(beta.abs() < 0.01 * expected, "β {beta}: a phase lag");
    let (a_on, b_on) = fit(&run(&filter(), &r, false, false));
    let online = a_on.hypot(b_on);
    assert!(
        (online / (gain * amp / G) - 1.0).abs() < 0.1,
        "online amplitude {online}"
    );
}

#[test]
fn sustained_acceleration_leaks_in_bounded_and_leaves() {
    // 5 m/s² east for 10 s. An accelerometer sees a tilt θ and a horizontal acceleration g tan θ
    // alike; what tells them apart is the gyro (no rotation) and the norm (√(g² + a²) ≠ g, but
    // an acceleration (R − I) g keeps the norm). A low pass of time constant τ lets a step in
    // through its step response s(t/τ): below 0.5° of atan(5/g) = 27° after 10 s needs
    // s(10/τ) < 0.019, i.e. τ > 52 s for the 2nd-order Butterworth (s ≈ (t/τ)²/2), whose lag
    // √2 τ ε then turns a bias residual ε = 0.02 °/s into 1.5° of tilt; a norm gate reaches 0.4°
    // here but tilts BROAD (6D 0.67° → 1.9°). So the tilt reaches the low pass's own peak,
    // atan(1.043 · 5/g) = 28.0° (4.3% Butterworth overshoot; 28.02° measured: the bias loop adds
    // nothing), and leaves within 15 s (docs/filters_robust.md, limits).
    let acc = |t: f64| {
        if (10.0..20.0).contains(&t) {
            Vector3::new(5.0, 0.0, 0.0)
        } else {
            Vector3::zeros()
        }
    };
    let r = simulate(
        50.0,
        tilted(),
        |_| Vector3::zeros(),
        acc,
        |_| FIELD.into(),
        Vector3::zeros(),
        (0.0, 0.0, 2),
    );
    let out = run(&filter(), &r, false, false);
    let tilt: Vec<f64> = (0..r.t.len()).map(|k| tilt_deg(&quat(&out, k), &r.truth[k])).collect();
    let during = tilt[..(20.0 * RATE) as usize].iter().fold(0.0, |a: f64, &b| a.max(b));
    let after = tilt[(35.0 * RATE) as usize..].iter().fold(0.0, |a: f64, &b| a.max(b));
    assert!(tilt[(10.0 * RATE) as usize - 1] < 1e-6);
    assert!(during < 28.5 && during > 27.0, "{during}");
    assert!(after < 0.07, "{after}"); // 0.057° measured
}

/// Bias errors of 8 seeds × 6D / 9D: rests of `rest_s` seconds then 25 s of turning, five times;
/// the error in the world (x, y horizontal, z vertical) at the end of the fifth rest, per run
/// and axis, and how many of the σ checks (second half, every 5 s) have `|error| ≤ 2σ`.
/// The bias tests' gyro bias, 1 °/s per axis [rad/s].
fn rest_turn_bias() -> Vector3<f64> {
    Vector3::new(1.0, -1.0, 1.0) * 1f64.to_radians()
}

/// The bias tests' record: rests of `rest_s` seconds then 25 s of turning, four times, and a last
/// rest; gyro bias [`rest_turn_bias`], noise 0.003 rad/s and 0.03 m/s² per sample.
fn rest_turn_record(rest_s: f64, seed: u64) -> Record {
    let period = rest_s + 25.0;
    let omega = move |t: f64| {
        if t % period < rest_s {
            Vector3::zeros()
        } else {
            turning(t)
        }
    };
    simulate(
        4.0 * period + rest_s,
        tilted(),
        omega,
        |_| Vector3::zeros(),
        |_| FIELD.into(),
        rest_turn_bias(),
        (0.003, 0.03, seed),
    )
}

fn bias_errors(rest_s: f64) -> (Vec<[f64; 3]>, usize, usize) {
    let deg = 1f64.to_radians();
    let bias = rest_turn_bias();
    let (mut errors, mut covered, mut total) = (Vec::new(), 0, 0);
    for nine in [false, true] {
        for seed in 0..8 {
            let r = rest_turn_record(rest_s, seed);
            let out = run(&filter(), &r, nine, false);
            let k = r.t.len() - 10; // 0.1 s before the end of the fifth rest
            let err = r.truth[k] * (Vector3::from(out.bias[k]) - bias) / deg;
            errors.push([err.x, err.y, err.z]);
            for i in 0..3 {
                assert!(out.bias_sigma[k][i] < 0.06 * deg && out.bias_sigma[k][i] > 0.0);
                for m in (r.t.len() / 2..r.t.len()).step_by(500) {
                    total += 1;
                    if (out.bias[m][i] - bias[i]).abs() <= 2.0 * out.bias_sigma[m][i] {
                        covered += 1;
                    }
                }
            }
        }
    }
    (errors, covered, total)
}

/// Per axis: the worst |error| and the RMS over the runs [°/s].
fn worst_and_rms(errors: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let (mut worst, mut rms) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..3 {
        worst[i] = errors.iter().fold(0.0, |a: f64, e| a.max(e[i].abs()));
        rms[i] = (errors.iter().map(|e| e[i] * e[i]).sum::<f64>() / errors.len() as f64).sqrt();
    }
    (worst, rms)
}

#[test]
fn bias_estimated_and_sigma_consistent_over_seeds() {
    // At rest the estimate is the mean gyro since the sensor went still, whose error has σ =
    // 0.17 °/s / √(100 T) per axis for T seconds of still data (gyro noise 0.003 rad/s per sample
    // at 100 Hz): the floor of any estimator. Stillness is found about 1.3 s after a stop (after
    // 24 °/s of turning; 2.1 s before the bias came off the low-passed gyro, filters_robust.md),
    // so 5 s rests leave T ≈ 3.7 s, σ ≈ 0.009 °/s, and the worst of 16 runs × 2 horizontal axes
    // lands near 2.5σ ≈ 0.022 °/s: the 0.02 °/s is then luck, not a property. With 10 s
    // rests, T ≈ 8.7 s, σ ≈ 0.006 °/s and 0.02 °/s is 3.4σ, which an estimator near the floor
    // meets: that is the test.
    let (errors, covered, total) = bias_errors(10.0);
    let (worst, rms) = worst_and_rms(&errors);
    // 2σ covers 95% of a Gaussian error; a σ too small by half would cover about 68%.
    assert!(covered as f64 >= 0.9 * total as f64, "{covered} of {total}");
    // Measured: worst 0.0159 / 0.0109 / 0.0111 °/s (x, y, z), RMS 0.0091 / 0.0064 / 0.0058;
    // coverage 720 of 720 (since the rest test under vibration, 2026-12-01; before 0.0159 / 0.0105
    // / 0.0101, RMS 0.0089 / 0.0064 / 0.0056) (σ is conservative). The x RMS is 1.5 times the floor: the rest noise
    // of the filter (0.06 °/s per second, set for real sensors) is 3.5 times this simulation's
    // 0.017, so the estimate from motion before the rest keeps some weight. RMS 20% worse fails.
    assert!(worst.iter().all(|&w| w < 0.02), "worst {worst:?} RMS {rms:?}");
    assert!(rms.iter().all(|&r| r < 0.0107), "RMS {rms:?}");
    // 5 s rests (the earlier version of this test), at their measured bounds (20% margin):
    // worst 0.0236 / 0.0135 / 0.0160 °/s, RMS 0.0112 / 0.0082 / 0.0098, coverage 624 of 624
    // (2026-12-01; before 0.0236 / 0.0148 / 0.0154, RMS 0.0111 / 0.0084 / 0.0095).
    let (errors, covered, total) = bias_errors(5.0);
    let (worst, rms) = worst_and_rms(&errors);
    assert!(covered as f64 >= 0.9 * total as f64, "{covered} of {total}");
    assert!(worst[0].max(worst[1]) < 0.0283, "worst {worst:?} RMS {rms:?}");
    assert!(worst[2] < 0.0185, "worst {worst:?} RMS {rms:?}");
    assert!(rms.iter().all(|&r| r < 0.0133), "RMS {rms:?}");
}

#[test]
fn rest_is_detected_and_motion_is_not() {
    let r = turning_record(40.0, Vector3::zeros(), 3);
    let out = run(&filter(), &r, false, false);
    assert!(out.rest[(4.5 * RATE) as usize]);
    assert!(
        !out.rest[(2.0 * RATE) as usize..(5.0 * RATE) as usize]
            .iter()
            .all(|&x| x)
            || out.rest[(4.9 * RATE) as usize]
    );
    assert!(out.rest[(7.0 * RATE) as usize..].iter().all(|&x| !x));
}

/// A drone idling on the ground, as EuRoC V1_02's first 3 s: rotor vibration as white noise of
/// 1.4 °/s per gyro sample and 0.35 m/s² per accelerometer sample on every axis (at 100 Hz the
/// noise density of EuRoC's worst axes, 2 °/s and 0.48 m/s² per sample at 200 Hz), a bias of
/// 4.45 °/s about body z (above VQF's 2 °/s clip and the 2 °/s rest threshold), then turning.
fn idling_drone(seed: u64) -> (Record, Vector3<f64>) {
    let deg = 1f64.to_radians();
    let bias = Vector3::new(-0.12, 1.12, 4.45) * deg;
    let omega = |t: f64| if t < 3.0 { Vector3::zeros() } else { turning(t + 2.0) };
    let r = simulate(
        20.0,
        tilted(),
        omega,
        |_| Vector3::zeros(),
        |_| FIELD.into(),
        bias,
        (1.4 * deg, 0.35, seed),
    );
    (r, bias)
}

#[test]
fn rest_is_detected_under_vibration_and_measures_a_large_bias() {
    let deg = 1f64.to_radians();
    for seed in 0..4 {
        let (r, bias) = idling_drone(seed);
        let out = run(&filter(), &r, false, false);
        // Rest holds from 1.5 s (rest_duration_s) plus the low passes' settling until the motion
        // (measured: from 1.57–1.95 s).
        let first = out.rest.iter().position(|&x| x).expect("rest detected");
        assert!(first < (2.2 * RATE) as usize, "seed {seed}: rest from sample {first}");
        assert!(out.rest[first..(2.9 * RATE) as usize].iter().all(|&x| x), "seed {seed}");
        assert!(out.rest[(4.0 * RATE) as usize..].iter().all(|&x| !x), "seed {seed}");
        // The rest updates (at 1.5 s and 2.5 s) average the first 2.5 s of still data: σ =
        // 1.4 °/s / √250 = 0.09 °/s per axis; 0.3 °/s is 3.4σ, against 4.45 °/s for a bias that
        // stayed at the prior and 2.45 °/s at VQF's clip (measured: at most 0.16 °/s).
        let k = (2.9 * RATE) as usize;
        let err = (Vector3::from(out.bias[k]) - bias) / deg;
        assert!(err.amax() < 0.3, "seed {seed}: bias error {err:?} °/s");
    }
}

#[test]
fn magnetic_disturbance_changes_neither_inclination_nor_heading() {
    // From 20 s to 40 s the field is 1.5 times as strong and turned by 46° about the vertical.
    let disturbed = |t: f64| {
        let f = Vector3::from(FIELD);
        if (20.0..40.0).contains(&t) {
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.8) * f * 1.5
        } else {
            f
        }
    };
    for offline in [false, true] {
        let clean = turning_record(60.0, Vector3::zeros(), 4);
        let dist = turning_in_field(60.0, disturbed, 4);
        let (a, b) = (
            run(&filter(), &clean, true, offline),
            run(&filter(), &dist, true, offline),
        );
        let incl = (0..clean.t.len())
            .map(|k| tilt_deg(&quat(&a, k), &quat(&b, k)))
            .fold(0.0, f64::max);
        let head = largest_heading_difference(&a, &b);
        // The smoother fuses two bias estimates, each of which saw the disturbance differently.
        let bound = if offline { 0.2 } else { 0.1 };
        assert!(incl < bound, "offline {offline}: inclination {incl}°");
        assert!(head < 2.0, "offline {offline}: heading {head}°");
        assert!(b.mag_disturbed[(25.0 * RATE) as usize] && !b.mag_disturbed[(15.0 * RATE) as usize]);
        // The clean run's heading is right.
        let k = clean.t.len() - 1;
        let e = (heading(&quat(&a, k)) - heading(&clean.truth[k])).to_degrees();
        assert!(e.abs() < 1.0, "{e}");
    }
}

/// Heading error of row `k` against the truth, wrapped to [−180°, 180°) [°].
fn heading_error(out: &RobustTrack, r: &Record, k: usize) -> f64 {
    wrap_pi(heading(&quat(out, k)) - heading(&r.truth[k])).to_degrees()
}

/// The largest heading difference between two runs' rows, wrapped [°].
fn largest_heading_difference(a: &RobustTrack, b: &RobustTrack) -> f64 {
    (0..a.q.len())
        .map(|k| wrap_pi(heading(&quat(a, k)) - heading(&quat(b, k))).to_degrees().abs())
        .fold(0.0, f64::max)
}

/// Turning as [`turning_record`] (no bias) in the world field `field(t)`.
fn turning_in_field(seconds: f64, field: impl Fn(f64) -> Vector3<f64>, seed: u64) -> Record {
    simulate(
        seconds,
        tilted(),
        turning,
        |_| Vector3::zeros(),
        field,
        Vector3::zeros(),
        (0.003, 0.03, seed),
    )
}

#[test]
fn a_dip_disturbance_is_rejected() {
    // From 20 s to 40 s the field keeps its norm but its dip falls from 63° to 29° (turned 0.6 rad
    // about east) and its horizontal part turns 46°: only the dip test can reject it.
    let disturbed = |t: f64| {
        let f = Vector3::from(FIELD);
        if (20.0..40.0).contains(&t) {
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.8) * (UnitQuaternion::from_euler_angles(0.6, 0.0, 0.0) * f)
        } else {
            f
        }
    };
    let clean = turning_record(60.0, Vector3::zeros(), 6);
    let dist = turning_in_field(60.0, disturbed, 6);
    let (a, b) = (run(&filter(), &clean, true, false), run(&filter(), &dist, true, false));
    let at = |s: f64| (s * RATE) as usize;
    assert!(!b.mag_disturbed[at(15.0)] && b.mag_disturbed[at(25.0)] && b.mag_disturbed[at(39.0)]);
    assert!(!b.mag_disturbed[at(50.0)], "the clean field is accepted again");
    let head = largest_heading_difference(&a, &b);
    // Accepted, the turned field would pull the heading 46° (1 − e^−1 of it in 20 s: 29°).
    assert!(head < 2.0, "heading {head}°");
}

#[test]
fn rejection_is_bounded_in_time() {
    // A still sensor; from 10 s on a disturbed field (1.5× the norm, turned 46°) for 100 s. It is
    // rejected for `mag_max_rejection_s` (60 s), then used at `mag_slow_factor × tau_mag_s` (40 s).
    let field = |t: f64| {
        let f = Vector3::from(FIELD);
        if t >= 10.0 {
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.8) * f * 1.5
        } else {
            f
        }
    };
    let r = simulate(
        110.0,
        tilted(),
        |_| Vector3::zeros(),
        |_| Vector3::zeros(),
        field,
        Vector3::zeros(),
        (0.003, 0.03, 7),
    );
    let out = run(&filter(), &r, true, false);
    let at = |s: f64| (s * RATE) as usize;
    assert!(
        out.mag_disturbed[at(20.0)] && out.mag_disturbed[at(109.0)],
        "flagged while it lasts"
    );
    let held = heading_error(&out, &r, at(69.0));
    assert!(held.abs() < 1.0, "rejected for 60 s: heading error {held}° at 69 s");
    // Used from 70 s at τ = 40 s: 1 − e^(−40/40) = 63% of the 46° turn by 110 s, i.e. 29°.
    let end = heading_error(&out, &r, r.t.len() - 1);
    assert!(
        (end.abs() - 29.0).abs() < 3.0,
        "then followed slowly: heading error {end}° at 110 s"
    );
}

#[test]
fn a_new_homogeneous_field_is_accepted_while_turning() {
    // At 20 s the sensor enters a new homogeneous field (1.3× the norm, turned 30° about the
    // vertical) and keeps turning at 0.58 rad/s (> 20 °/s): the candidate stays within the thresholds
    // of itself for `mag_new_field_s` (20 s) and becomes the reference; the heading then follows it.
    let omega = |t: f64| Vector3::new(0.3 * (0.5 * t).sin(), 0.3 * (0.5 * t).cos(), 0.5);
    let turned = 30.0f64.to_radians();
    let field = |t: f64| {
        let f = Vector3::from(FIELD);
        if t >= 20.0 {
            UnitQuaternion::from_euler_angles(0.0, 0.0, turned) * f * 1.3
        } else {
            f
        }
    };
    let r = simulate(
        140.0,
        tilted(),
        omega,
        |_| Vector3::zeros(),
        field,
        Vector3::zeros(),
        (0.003, 0.03, 8),
    );
    let out = run(&filter(), &r, true, false);
    let at = |s: f64| (s * RATE) as usize;
    assert!(
        !out.mag_disturbed[at(19.0)] && out.mag_disturbed[at(25.0)],
        "first rejected"
    );
    assert!(
        !out.mag_disturbed[at(45.0)..].iter().any(|&d| d),
        "accepted within 25 s, and kept"
    );
    // North is now the new field's: 30° from the truth's, reached with τ = 20 s (98% after 80 s).
    let end = heading_error(&out, &r, r.t.len() - 1);
    assert!((end.abs() - 30.0).abs() < 2.0, "heading error {end}° at the end");
    // The field never tilts the estimate.
    let tilt = (0..r.t.len())
        .map(|k| tilt_deg(&quat(&out, k), &r.truth[k]))
        .fold(0.0, f64::max);
    assert!(tilt < 1.0, "tilt {tilt}°");
}

#[test]
fn streaming_equals_batch_and_resume_equals_uninterrupted() {
    let r = turning_record(20.0, Vector3::zeros(), 5);
    let f = filter();
    for nine in [false, true] {
        let batch = run(&f, &r, nine, false);
        let mut s = RobustState::default();
        for k in 0..r.t.len() {
            let dt = if k == 0 { 0.0 } else { r.t[k] - r.t[k - 1] };
            let m = Vector3::from(r.mag[k]);
            f.update(&mut s, &r.gyro[k].into(), &r.accel[k].into(), nine.then_some(&m), dt)
                .unwrap();
            assert_eq!(<[f64; 4]>::from(s.q.coords), batch.q[k]);
            assert_eq!(<[f64; 3]>::from(s.bias), batch.bias[k]);
        }
        // Resume: the first half, then the second continued from the saved state.
        let h = r.t.len() / 2;
        let mut s = RobustState::default();
        let mut first = RobustTrack::new(h);
        let cut = |a: usize, b: usize| Inputs {
            t: &r.t[a..b],
            gyro: &r.gyro[a..b],
            accel: &r.accel[a..b],
            mag: nine.then_some(&r.mag[a..b]),
        };
        f.run(&mut s, &cut(0, h), false, &mut first.outputs()).unwrap();
        let saved = s;
        let mut second = RobustTrack::new(r.t.len() - h);
        f.run(&mut s, &cut(h, r.t.len()), true, &mut second.outputs()).unwrap();
        assert_eq!(second.q, batch.q[h..]);
        let mut again = RobustTrack::new(r.t.len() - h);
        let mut restored = RobustState::restored(&imukit::filters::Fields::values(&saved)).unwrap();
        f.run(&mut restored, &cut(h, r.t.len()), true, &mut again.outputs())
            .unwrap();
        assert_eq!(again.q, second.q);
    }
}

/// The heading is kept twice (`step::turn_heading`): as the pair `(cos ψ/2, sin ψ/2)` the output
/// uses and as the angle ψ the heading error is taken from. After a 9D run of 60 s (6,000 turns
/// of both by the field's correction) the two agree to rounding; a state whose angle is outside
/// [−π, π], or away from the pair's, is refused on restore.
#[test]
fn heading_angle_and_pair_agree_and_the_angle_is_checked_on_restore() {
    let r = turning_record(60.0, Vector3::zeros(), 7);
    let mut s = RobustState::default();
    let mut track = RobustTrack::new(r.t.len());
    filter()
        .run(&mut s, &r.inputs(true), false, &mut track.outputs())
        .unwrap();
    let from_pair = 2.0 * s.heading.y.atan2(s.heading.x);
    let diff = wrap_pi(s.heading_angle - from_pair);
    assert!(diff.abs() < 1e-12, "angle {} vs pair {from_pair}", s.heading_angle);
    assert!(s.heading_angle.abs() <= std::f64::consts::PI);
    let mut values = imukit::filters::Fields::values(&s);
    assert!(RobustState::restored(&values).is_ok());
    let at = <RobustState as imukit::filters::Fields>::NAMES
        .iter()
        .position(|&n| n == "heading_angle")
        .unwrap();
    values[at] = 4.0;
    assert!(RobustState::restored(&values).is_err());
    // In range but not the pair's heading: two headings in one state.
    values[at] = wrap_pi(from_pair + 1e-3);
    assert!(RobustState::restored(&values).is_err());
    // A difference at rounding is the same heading.
    values[at] = wrap_pi(from_pair + 1e-9);
    assert!(RobustState::restored(&values).is_ok());
}

fn wrap_pi(x: f64) -> f64 {
    (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

#[test]
fn ned_is_enu_turned() {
    let r = turning_record(20.0, Vector3::zeros(), 6);
    let enu = run(&filter(), &r, true, false);
    let ned = run(
        &Robust::new(RobustParams::default(), World::Ned).unwrap(),
        &r,
        true,
        false,
    );
    // R_ned_enu: x ↔ y, z → −z.
    let c = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
        0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0,
    )));
    for k in (0..r.t.len()).step_by(97) {
        assert!((c * quat(&enu, k)).angle_to(&quat(&ned, k)) < 1e-9);
    }
}

#[test]
fn offline_is_deterministic_finite_and_better_at_the_start() {
    let deg = 1f64.to_radians();
    let bias = Vector3::new(0.5, -0.3, 0.2) * deg;
    let r = turning_record(60.0, bias, 7);
    let f = filter();
    for nine in [false, true] {
        let (a, b) = (run(&f, &r, nine, true), run(&f, &r, nine, true));
        assert_eq!(a.q, b.q);
        assert_eq!(a.bias, b.bias);
        let n = r.t.len();
        assert!(a.q[0]
            .iter()
            .chain(&a.q[n - 1])
            .chain(&a.bias[0])
            .all(|x| x.is_finite()));
        // The smoothed bias at the start knows what the forward pass learns later.
        let online = run(&f, &r, nine, false);
        let err = |o: &RobustTrack, k: usize| (Vector3::from(o.bias[k]) - bias).norm();
        assert!(
            err(&a, 10) < 0.5 * err(&online, 10),
            "{} {}",
            err(&a, 10),
            err(&online, 10)
        );
        let worst = |o: &RobustTrack| (0..n).map(|k| tilt_deg(&quat(o, k), &r.truth[k])).fold(0.0, f64::max);
        assert!(worst(&a) < worst(&online), "{} {}", worst(&a), worst(&online));
    }
}

#[test]
fn errors_name_the_input() {
    let f = filter();
    let mut s = RobustState::default();
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    let e = f.update(&mut s, &nan, &Vector3::z(), None, 0.01).unwrap_err();
    assert_eq!(e.argument(), Some("gyro"));
    let bad = RobustParams {
        tau_acc_s: -1.0,
        ..RobustParams::default()
    };
    assert!(Robust::new(bad, World::Enu).is_err());
    let r = simulate(
        1.0,
        tilted(),
        turning,
        |_| Vector3::zeros(),
        |_| FIELD.into(),
        Vector3::zeros(),
        (0.0, 0.0, 8),
    );
    let mut t = r.t.clone();
    t[5] = t[4];
    let inputs = Inputs {
        t: &t,
        ..r.inputs(false)
    };
    let mut out = RobustTrack::new(t.len());
    let e = f
        .run(&mut RobustState::default(), &inputs, false, &mut out.outputs())
        .unwrap_err();
    assert_eq!((e.argument(), e.index()), (Some("t"), Some(5)));
    // A part of a longer record: the row in the whole record.
    let e = f
        .run_part(&mut RobustState::default(), &inputs, 100, false, &mut out.outputs())
        .unwrap_err();
    assert_eq!((e.argument(), e.index()), (Some("t"), Some(105)));
}

/// A stamp refused at row 700 (inside the third block of a loop that would prepare blocks of 256
/// rows ahead of the step, docs/filters_robust.md "Speed, seventh round") ends the run there,
/// naming it, after the rows before it were filtered as in a run that stops before it.
#[test]
fn a_refused_row_inside_a_block_ends_the_run_after_the_rows_before() {
    let f = filter();
    let r = turning_record(10.0, Vector3::new(0.004, -0.002, 0.003), 21);
    let bad = 700;
    let mut t = r.t.clone();
    t[bad] = t[bad - 1];
    let mut out = RobustTrack::new(t.len());
    let e = f
        .run(
            &mut RobustState::default(),
            &Inputs {
                t: &t,
                ..r.inputs(true)
            },
            false,
            &mut out.outputs(),
        )
        .unwrap_err();
    assert_eq!((e.argument(), e.index()), (Some("t"), Some(bad)));
    let before = Inputs {
        t: &r.t[..bad],
        gyro: &r.gyro[..bad],
        accel: &r.accel[..bad],
        mag: Some(&r.mag[..bad]),
    };
    let mut prefix = RobustTrack::new(bad);
    f.run(&mut RobustState::default(), &before, false, &mut prefix.outputs())
        .unwrap();
    assert_eq!(&out.q[..bad], &prefix.q[..]);
    assert_eq!(&out.bias[..bad], &prefix.bias[..]);
    assert!(out.q[bad..].iter().all(|q| *q == [0.0; 4]));
}

#[test]
fn bias_sigma_is_consistent_when_the_rest_noise_matches_the_sensor() {
    // The default `bias_sigma_rest_rad_s` (0.06 °/s for one second of rest) is set for real
    // sensors and is 3.5 times this simulation's 0.017 °/s (0.003 rad/s per sample at 100 Hz):
    // σ is then conservative by design (the coverage test above). Matched to the simulation, the
    // bias Kalman filter's σ must be its error's: the normalised errors z = (b̂ − b)/σ at the ends
    // of rests 2–5 (16 seeds × 6D/9D × 3 axes) have an RMS near 1. Measured 0.84; with σ_rest
    // halved 1.80, doubled 0.40, so a covariance doubled (RMS / √2 = 0.59) or halved fails, and a
    // zero σ (z infinite) too.
    let bias = rest_turn_bias();
    let params = RobustParams {
        bias_sigma_rest_rad_s: 0.003 / RATE.sqrt(),
        ..RobustParams::default()
    };
    let f = Robust::new(params, World::Enu).unwrap();
    let (rest_s, period) = (10.0, 35.0);
    let mut z2 = Vec::new();
    for nine in [false, true] {
        for seed in 0..16 {
            let r = rest_turn_record(rest_s, seed);
            let out = run(&f, &r, nine, false);
            for cycle in 1..5 {
                let k = ((f64::from(cycle) * period + rest_s - 0.1) * RATE) as usize;
                for i in 0..3 {
                    let z = (out.bias[k][i] - bias[i]) / out.bias_sigma[k][i];
                    z2.push(z * z);
                }
            }
        }
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    assert!(
        rms > 0.65 && rms < 1.25,
        "RMS of (b̂ − b)/σ over {} checks: {rms}",
        z2.len()
    );
}

#[test]
fn bias_is_estimated_in_motion_without_rest() {
    // 300 s of turning, never still (no rest update): the motion updates alone (the loops' lag
    // modelled, docs/filters_robust.md item 6) estimate a 1 °/s bias on every body axis, in 6D too
    // (the turning carries each body axis through the horizontal). Measured: worst 0.019 °/s over
    // 4 seeds × 6D/9D; with the motion updates off (`bias_sigma_motion_rad_s` = 1000 °/s) 1.0 °/s.
    let deg = 1f64.to_radians();
    let bias = Vector3::new(1.0, -1.0, 1.0) * deg;
    let omega = |t: f64| {
        Vector3::new(
            0.4 * (0.7 * t).sin(),
            0.3 * (0.5 * t + 1.0).sin(),
            0.5 * (0.3 * t).cos(),
        )
    };
    for nine in [false, true] {
        for seed in 0..4 {
            let r = simulate(
                300.0,
                tilted(),
                omega,
                |_| Vector3::zeros(),
                |_| FIELD.into(),
                bias,
                (0.003, 0.03, seed),
            );
            let out = run(&filter(), &r, nine, false);
            assert!(!out.rest.iter().any(|&x| x), "rest detected while turning");
            let k = r.t.len() - 1;
            for i in 0..3 {
                let err = (out.bias[k][i] - bias[i]) / deg;
                let sigma = out.bias_sigma[k][i] / deg;
                assert!(err.abs() < 0.03, "9D {nine}, seed {seed}, axis {i}: error {err} °/s");
                assert!(
                    err.abs() < 3.0 * sigma,
                    "9D {nine}, seed {seed}, axis {i}: error {err}, σ {sigma} °/s"
                );
            }
        }
    }
}

/// A streamed field whose squared norm overflows is refused (as Mahony's and Madgwick's `update`
/// refuse it): held as it was, it made a state that `RobustState::restored` refuses.
#[test]
fn update_refuses_a_field_whose_norm_overflows() {
    let f = filter();
    let mut s = RobustState::default();
    let (gyro, accel) = (Vector3::zeros(), Vector3::new(0.0, 0.0, 9.81));
    f.update(&mut s, &gyro, &accel, Some(&Vector3::new(0.0, 20.0, -40.0)), 0.0)
        .unwrap();
    let before = s;
    let huge = Vector3::new(1e200, 0.0, 0.0);
    let e = f.update(&mut s, &gyro, &accel, Some(&huge), 0.01).unwrap_err();
    assert_eq!(e, imukit::Error::Overflow { index: 0 }.in_argument("mag"));
    assert_eq!(s, before);
}
