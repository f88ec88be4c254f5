//! The `Law` seam from outside the crate: a third, trivial law (gyro only, no correction) plugs
//! into `Filter<L>` without touching Mahony or Madgwick. Its output is pure gyro integration
//! (`attitude::integrate`, scheme `exp`) to rounding, and the shared machinery (gain ramp,
//! accelerometer and magnetometer gates) leaves it bit for bit unchanged.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::attitude::{self, Representation, Scheme};
use imukit::filters::{Filter, GainRamp, Inputs, Law, Options, State, Step};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// No correction at all: the estimate is the integrated gyro.
#[derive(Debug, Clone, Copy, PartialEq)]
struct GyroOnly;

impl Law for GyroOnly {
    type Extra = ();

    fn validate(&self) -> imukit::Result<()> {
        Ok(())
    }

    fn correct(&self, _: &Step<'_>, _: &mut Vector3<f64>, _: &mut ()) -> Vector3<f64> {
        Vector3::zeros()
    }
}

const N: usize = 5000;

type Rows = Vec<[f64; 3]>;

/// A tumbling body at 200 Hz, with an accelerometer and a magnetometer that the gates would
/// reject (norm far from g, field jumping) half of the time.
fn samples() -> (Vec<f64>, Rows, Rows, Rows) {
    let t: Vec<f64> = (0..N).map(|k| k as f64 * 0.005).collect();
    let gyro = t
        .iter()
        .map(|s| [1.3 * (0.7 * s).sin(), -0.8 * (1.1 * s).cos(), 2.1 * (0.3 * s).sin()])
        .collect();
    let accel = t
        .iter()
        .map(|s| [3.0 * (5.0 * s).sin(), 0.5, 9.81 + 12.0 * (2.0 * s).cos()])
        .collect();
    let mag = t
        .iter()
        .enumerate()
        .map(|(k, s)| [20.0 * s.cos(), if k % 400 < 200 { 20.0 } else { -60.0 }, -40.0])
        .collect();
    (t, gyro, accel, mag)
}

fn run(options: Options, nine: bool, initial: UnitQuaternion<f64>) -> Vec<[f64; 4]> {
    let (t, gyro, accel, mag) = samples();
    let filter = Filter::new(GyroOnly, options).unwrap();
    let mut state = State::<GyroOnly>::at(initial, Vector3::zeros(), 0.0);
    let inputs = Inputs {
        t: &t,
        gyro: &gyro,
        accel: &accel,
        mag: nine.then_some(&mag[..]),
    };
    let (mut q, mut b) = (vec![[0.0; 4]; N], vec![[0.0; 3]; N]);
    filter.run(&mut state, &inputs, false, &mut q, &mut b).unwrap();
    assert!(b.iter().all(|b| *b == [0.0; 3]), "no law, no bias");
    q
}

#[test]
fn gyro_only_law_is_pure_gyro_integration() {
    let initial = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.2, 1.0));
    let q = run(Options::default(), true, initial);
    // The filter's step to sample k uses ω_k; attitude's zero-order hold from sample k uses ω_k:
    // shift the rates by one sample.
    let (t, gyro, _, _) = samples();
    let held: Vec<[f64; 3]> = gyro[1..].iter().copied().chain([[0.0; 3]]).collect();
    let options = attitude::Options {
        scheme: Scheme::Exp,
        representation: Representation::Quaternion,
        ..attitude::Options::default()
    };
    let mut reference = vec![[0.0; 4]; N];
    attitude::integrate(&t, &held, &initial, &options, Some(&mut reference)).unwrap();
    let mut worst = 0.0_f64;
    for (k, (ours, theirs)) in q.iter().zip(&reference).enumerate() {
        let a = UnitQuaternion::from_quaternion(Quaternion::new(ours[3], ours[0], ours[1], ours[2]));
        let b = UnitQuaternion::from_quaternion(Quaternion::new(theirs[3], theirs[0], theirs[1], theirs[2]));
        let angle = a.angle_to(&b);
        assert!(angle < 1e-11, "sample {k}: {angle:e} rad from gyro integration");
        worst = worst.max(angle);
    }
    println!("gyro-only vs attitude exp over {N} samples: worst {worst:e} rad");
}

#[test]
fn gates_and_ramp_do_not_alter_a_law_without_correction() {
    let initial = UnitQuaternion::from_scaled_axis(Vector3::new(-0.4, 0.1, 0.2));
    let off = Options {
        gain_ramp: GainRamp {
            duration_s: 0.0,
            factor: 1.0,
        },
        acc_rejection: None,
        mag_rejection: None,
        ..Options::default()
    };
    let strong_ramp = Options {
        gain_ramp: GainRamp {
            duration_s: 20.0,
            factor: 50.0,
        },
        ..Options::default()
    };
    for nine in [false, true] {
        let reference = run(off, nine, initial);
        assert_eq!(run(Options::default(), nine, initial), reference, "9D: {nine}");
        assert_eq!(run(strong_ramp, nine, initial), reference, "9D: {nine}");
    }
}
