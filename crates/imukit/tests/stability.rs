//! Long-run numerical stability (issue 9): after `IMUKIT_STABILITY_STEPS` attitude steps (10^8
//! in `make stability`) every attitude scheme's quaternion is still unit to 1e-12; after a tenth
//! of that (10^7 at 1 kHz) the rotation matrix of every scheme in the matrix representation and
//! the preintegrated ΔR are still orthonormal to 1e-12 and the strapdown
//! and preintegration covariances are exactly symmetric and positive semidefinite, and the
//! filters' quaternions are unit to 1e-12. Each run feeds the same 100 s chunk again and again,
//! continuing from the state the previous call returned (`stability_common`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

mod stability_common;

use imukit::attitude::{self, Representation, Scheme};
use imukit::filters::{Filter, Inputs, Law, Madgwick, Mahony, Options, State};
use imukit::imu::{Bias, NavState, Noise};
use imukit::preint::{self, Preintegrator};
use imukit::propagate::{self, Covariance, Outputs};
use imukit::strapdown;
use nalgebra::{UnitQuaternion, Vector3};
use stability_common::{attitude_steps, in_chunks, long_steps, orthonormality_error, psd_report, timed, Chunk, Worst};

/// The bound asserted on |‖q‖ − 1| and ‖RᵀR − I‖_F. The guarantee (issue 9, docs/guarantees.md)
/// is 1e-12 at full length; the projections keep both at rounding level (≤ 1.3e-15 measured at
/// 10^8 / 10^7 steps) whatever the length, so the bound is tightened to 1e-14 so that the short
/// runs of `make test` still catch a missing projection (without one, the preintegrated ΔR was
/// 7.5e-14 off after 10^5 intervals and 4.6e-12 after 10^7).
const UNIT_TOLERANCE: f64 = 1e-14;

/// ADIS16448-like densities (EuRoC's Kalibr values), bias walks included.
const NOISE: Noise = Noise {
    gyro_density: 1.7e-4,
    accel_density: 2e-3,
    gyro_random_walk: 1.9e-5,
    accel_random_walk: 3e-3,
};

fn norm_error(q: &[f64]) -> f64 {
    (q.iter().map(|v| v * v).sum::<f64>().sqrt() - 1.0).abs()
}

/// Runs one attitude scheme for `attitude_steps()` steps; returns the worst |‖q‖ − 1| over every
/// stored attitude (even chunks store all, which takes the parallel two-pass path of the
/// closed-form schemes) and every returned one (odd chunks store none: the sequential path).
fn attitude_norm_drift(scheme: Scheme) -> f64 {
    let chunk = Chunk::new();
    let options = attitude::Options {
        scheme,
        representation: Representation::Quaternion,
        ..attitude::Options::default()
    };
    let mut out = vec![0.0; chunk.t.len() * 4];
    let mut q = UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0);
    let (mut worst, mut calls, mut done) = (0.0_f64, 0usize, 0usize);
    let steps = attitude_steps();
    timed(&format!("attitude {}", scheme.name()), steps, || {
        in_chunks(steps, |m| {
            let s = chunk.samples(m);
            let store = calls.is_multiple_of(2).then(|| &mut out.as_chunks_mut().0[..m + 1]);
            let stored = store.is_some();
            q = attitude::integrate(s.t(), s.gyro(), &q, &options, store).unwrap();
            if stored {
                worst = out[..4 * (m + 1)].chunks_exact(4).map(norm_error).fold(worst, f64::max);
            }
            worst = worst.max(norm_error(q.coords.as_slice()));
            calls += 1;
            done += m;
        })
    });
    assert_eq!(done, steps);
    println!("attitude {}: worst |‖q‖ − 1| = {worst:e}", scheme.name());
    worst
}

/// One test per scheme, so that each is timed and reported on its own.
macro_rules! attitude_test {
    ($($name:ident: $scheme:expr,)*) => {$(
        #[test]
        fn $name() {
            let e = attitude_norm_drift($scheme);
            assert!(e < UNIT_TOLERANCE, "|‖q‖ − 1| reached {e:e}");
        }
    )*};
}

attitude_test! {
    attitude_euler_stays_unit: Scheme::Euler,
    attitude_exp_stays_unit: Scheme::Exp,
    attitude_midpoint_stays_unit: Scheme::Rk2,
    attitude_rk4_stays_unit: Scheme::Rk4,
    attitude_magnus_stays_unit: Scheme::Magnus,
}

#[test]
fn every_quaternion_scheme_is_tested() {
    // The five tests above cover the quaternion representation's whole scheme list.
    assert_eq!(Representation::Quaternion.schemes().len(), 5);
}

/// Runs one scheme in the rotation-matrix representation for `long_steps()` steps, each chunk
/// continuing from the matrix the previous one returned (never through a quaternion); returns the
/// worst ‖RᵀR − I‖_F after any chunk.
fn attitude_matrix_drift(scheme: Scheme) -> f64 {
    let chunk = Chunk::new();
    let options = attitude::Options {
        scheme,
        representation: Representation::Matrix,
        ..attitude::Options::default()
    };
    let mut r = *UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0)
        .to_rotation_matrix()
        .matrix();
    let (mut worst, mut done) = (0.0_f64, 0usize);
    let steps = long_steps();
    timed(&format!("attitude matrix {}", scheme.name()), steps, || {
        in_chunks(steps, |m| {
            let s = chunk.samples(m);
            r = attitude::integrate_rotation_matrix(s.t(), s.gyro(), &r, &options).unwrap();
            worst = worst.max(orthonormality_error(&r));
            done += m;
        })
    });
    assert_eq!(done, steps);
    println!("attitude matrix {}: worst ‖RᵀR − I‖ = {worst:e}", scheme.name());
    worst
}

macro_rules! matrix_test {
    ($($name:ident: $scheme:expr,)*) => {$(
        #[test]
        fn $name() {
            let e = attitude_matrix_drift($scheme);
            assert!(e < UNIT_TOLERANCE, "‖RᵀR − I‖ reached {e:e}");
        }
    )*};
}

matrix_test! {
    attitude_matrix_euler_stays_orthonormal: Scheme::Euler,
    attitude_matrix_exp_stays_orthonormal: Scheme::Exp,
    attitude_matrix_midpoint_stays_orthonormal: Scheme::Rk2,
    attitude_matrix_rk4_stays_orthonormal: Scheme::Rk4,
    attitude_matrix_magnus_stays_orthonormal: Scheme::Magnus,
}

#[test]
fn every_matrix_scheme_is_tested() {
    assert_eq!(Representation::Matrix.schemes().len(), 5);
}

/// Streams `long_steps()` intervals through a preintegrator; checks ΔR and the covariances after
/// every chunk. Returns the worst orthonormality error.
fn preintegration_run(label: &str, mut p: Preintegrator) -> f64 {
    let chunk = Chunk::new();
    let steps = long_steps();
    let (mut ortho, mut cov9, mut cov15) = (0.0_f64, Worst::default(), Worst::default());
    let combined = p.covariance_combined().is_some();
    // The chunk's stamps restart at 0; its own last sample equals its first, and the run's clock
    // goes on: each batch continues the last on that clock (`integrate_samples_at`), as the
    // continuity rule asks (`preint/continuity.rs`; fed with chunk-local stamps, the second chunk
    // was refused as starting at t = 0 after an end at t = 100).
    let mut done = 0;
    timed(label, steps, || {
        in_chunks(steps, |m| {
            let clock = [
                done as f64 * stability_common::H,
                (done + m) as f64 * stability_common::H,
            ];
            p.integrate_samples_at(&chunk.samples(m), None, clock).unwrap();
            done += m;
            ortho = ortho.max(orthonormality_error(&p.delta_rotation));
            cov9.add(psd_report(&p.covariance()));
            if let Some(c) = p.covariance_combined() {
                cov15.add(psd_report(&c));
            }
        })
    });
    assert!((p.delta_t - steps as f64 * stability_common::H).abs() < 1e-6 * p.delta_t);
    println!("{label}: worst ‖ΔRᵀΔR − I‖ = {ortho:e}");
    cov9.assert_psd(&format!("{label} 9×9"));
    if combined {
        cov15.assert_psd(&format!("{label} 15×15"));
    }
    ortho
}

fn preintegrator(scheme: preint::Scheme) -> Preintegrator {
    Preintegrator::new(Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.05, 0.02, -0.1), NOISE).with_scheme(scheme)
}

#[test]
fn preintegration_euler_sequential_with_bias_walk() {
    // The bias walk keeps the euler batch sequential.
    let e = preintegration_run(
        "preint euler+walk",
        preintegrator(preint::Scheme::Euler).with_bias_walk(),
    );
    assert!(e < UNIT_TOLERANCE, "‖ΔRᵀΔR − I‖ reached {e:e}");
}

#[test]
fn preintegration_euler_parallel_chunks() {
    // 100 000 intervals per call > 2 CHUNK: the parallel path, merged chunk by chunk.
    const _: () = assert!(stability_common::CHUNK_STEPS > 2 * preint::CHUNK);
    let e = preintegration_run("preint euler batch", preintegrator(preint::Scheme::Euler));
    assert!(e < UNIT_TOLERANCE, "‖ΔRᵀΔR − I‖ reached {e:e}");
}

#[test]
fn preintegration_midpoint_with_bias_walk() {
    let e = preintegration_run(
        "preint midpoint+walk",
        preintegrator(preint::Scheme::Midpoint).with_bias_walk(),
    );
    assert!(e < UNIT_TOLERANCE, "‖ΔRᵀΔR − I‖ reached {e:e}");
}

/// Propagates the strapdown state and the 15×15 covariance for `long_steps()` steps with the
/// mean integrated by `scheme`; checks the covariance and |q| after every chunk.
fn strapdown_run(scheme: strapdown::Scheme) {
    let chunk = Chunk::new();
    let steps = long_steps();
    let options = strapdown::Options {
        scheme,
        ..strapdown::Options::default()
    };
    let bias = Bias {
        gyro: Vector3::new(0.002, -0.001, 0.003),
        accel: Vector3::new(0.02, 0.01, -0.03),
    };
    let mut x = NavState {
        position: Vector3::zeros(),
        velocity: Vector3::zeros(),
        rotation: UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3),
    };
    let mut p = Covariance::identity() * 1e-4;
    let mut covariances = vec![[0.0; 225]; 2];
    let (mut worst, mut norm) = (Worst::default(), 0.0_f64);
    let label = format!("strapdown {}", scheme.name());
    timed(&label, steps, || {
        in_chunks(steps, |m| {
            let outputs = Outputs {
                states: None,
                covariances: &mut covariances,
                every: m,
            };
            (x, p) = propagate::propagate(&chunk.samples(m), &x, &p, &bias, &NOISE, &options, outputs).unwrap();
            worst.add(psd_report(&p));
            norm = norm.max((x.rotation.norm() - 1.0).abs());
        })
    });
    println!("{label}: worst |‖q‖ − 1| = {norm:e}");
    worst.assert_psd(&label);
    assert!(norm < UNIT_TOLERANCE, "|‖q‖ − 1| reached {norm:e}");
    // The covariance did grow over the run (the checks saw a live matrix, not the start).
    assert!(p[(0, 0)] > 1e3, "position variance {:e}", p[(0, 0)]);
}

macro_rules! strapdown_test {
    ($($name:ident: $scheme:expr,)*) => {$(
        #[test]
        fn $name() {
            strapdown_run($scheme);
        }
    )*};
}

strapdown_test! {
    strapdown_euler_covariance_stays_psd: strapdown::Scheme::LieEuler,
    strapdown_midpoint_covariance_stays_psd: strapdown::Scheme::Midpoint,
    strapdown_rk4_covariance_stays_psd: strapdown::Scheme::Rk4,
    strapdown_exp_covariance_stays_psd: strapdown::Scheme::Exp,
}

/// Runs a filter over `long_steps()` samples in batches continuing one another; returns the
/// worst |‖q‖ − 1| over every output attitude.
fn filter_norm_drift<L: Law>(label: &str, law: L, nine: bool) -> f64 {
    let chunk = Chunk::new();
    let steps = long_steps();
    let filter = Filter::new(law, Options::default()).unwrap();
    let mag: Vec<[f64; 3]> = chunk
        .t
        .iter()
        .map(|&s| [0.2, 0.4 + 0.05 * (0.3 * s).sin(), -0.3])
        .collect();
    let (gyro, accel) = (chunk.gyro.as_chunks::<3>().0, chunk.accel.as_chunks::<3>().0);
    let mut state = State::default();
    let (mut out_q, mut out_bias) = (vec![[0.0; 4]; chunk.t.len()], vec![[0.0; 3]; chunk.t.len()]);
    let (mut worst, mut offset) = (0.0_f64, 0.0);
    timed(label, steps, || {
        in_chunks(steps, |m| {
            // Batches continue one another: the stamps go on from the previous batch's last one.
            let t: Vec<f64> = chunk.t[1..=m].iter().map(|s| s + offset).collect();
            let inputs = Inputs {
                t: &t,
                gyro: &gyro[1..=m],
                accel: &accel[1..=m],
                mag: nine.then(|| &mag[1..=m]),
            };
            let continued = state.common.initialized;
            filter
                .run(&mut state, &inputs, continued, &mut out_q[..m], &mut out_bias[..m])
                .unwrap();
            worst = out_q[..m].iter().map(|q| norm_error(q)).fold(worst, f64::max);
            offset = t[m - 1];
        })
    });
    println!("{label}: worst |‖q‖ − 1| = {worst:e}");
    worst
}

#[test]
fn mahony_9d_stays_unit() {
    let e = filter_norm_drift("mahony 9D", Mahony::default(), true);
    assert!(e < UNIT_TOLERANCE, "|‖q‖ − 1| reached {e:e}");
}

#[test]
fn madgwick_6d_stays_unit() {
    let e = filter_norm_drift("madgwick 6D", Madgwick::default(), false);
    assert!(e < UNIT_TOLERANCE, "|‖q‖ − 1| reached {e:e}");
}
