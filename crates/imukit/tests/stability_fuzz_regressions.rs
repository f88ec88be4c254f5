//! Inputs the fuzzers (`fuzz/`, `make fuzz`) found, kept as regression tests: each was accepted
//! with an invalid `Ok` result before its fix.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::attitude::{self, Representation, Scheme};
use imukit::Error;
use nalgebra::UnitQuaternion;

/// fuzz/artifacts/attitude/crash-9b6040bc…: an RK4 quaternion step with a finite but enormous
/// rate (3.3e38 rad/s over 3.16 s) grew |q|² past f64::MAX, so `q/|q|` was the zero quaternion,
/// finite, and returned as `Ok`. It is an overflow, as a non-finite result is.
#[test]
fn rk4_norm_overflow_is_an_error_not_a_zero_quaternion() {
    let w = 31611.0 * 2f64.powi(113);
    let t = [0.0, 3.1611, 6.3222];
    let gyro = [w; 9];
    for scheme in [Scheme::Rk4, Scheme::Midpoint, Scheme::Euler] {
        let options = attitude::Options {
            scheme,
            representation: Representation::Quaternion,
            ..attitude::Options::default()
        };
        let mut out = [0.0; 12];
        for store in [false, true] {
            let result = attitude::integrate(
                &t,
                &gyro,
                &UnitQuaternion::identity(),
                &options,
                store.then_some(&mut out[..]),
            );
            match result {
                Err(Error::Overflow { index }) => assert!(index >= 1, "{scheme:?}: index {index}"),
                Ok(q) => assert!((q.norm() - 1.0).abs() < 1e-12, "{scheme:?} returned |q| = {}", q.norm()),
                Err(e) => panic!("{scheme:?}: {e}"),
            }
        }
    }
    // The case itself: an error, at the first step, stored or not.
    let options = attitude::Options {
        scheme: Scheme::Rk4,
        ..attitude::Options::default()
    };
    let mut out = [0.0; 12];
    let stored = attitude::integrate(&t, &gyro, &UnitQuaternion::identity(), &options, Some(&mut out));
    assert!(matches!(stored, Err(Error::Overflow { index: 1 })), "{stored:?}");
    let last = attitude::integrate(&t, &gyro, &UnitQuaternion::identity(), &options, None);
    assert!(matches!(last, Err(Error::Overflow { index: 2 })), "{last:?}");
}
