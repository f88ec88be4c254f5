//! `Preintegrator::try_integrate_measurement`: the streaming step checks its values in the core
//! (finite readings, the midpoint first-sample `dt == 0` rule, a positive finite `dt`) and is
//! transactional: a refused step, an overflowing one included, leaves the state exactly as it was.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::imu::Noise;
use imukit::preint::{Clipped, Preintegrator, Scheme};
use imukit::Error;
use nalgebra::Vector3;

fn noise() -> Noise {
    Noise {
        gyro_density: 1.7e-4,
        accel_density: 2e-3,
        gyro_random_walk: 1.9e-5,
        accel_random_walk: 3e-3,
    }
}

/// A preintegrator with a few accepted steps behind it.
fn started(scheme: Scheme) -> Preintegrator {
    let mut p = Preintegrator::new(Vector3::new(0.01, 0.0, -0.02), Vector3::zeros(), noise())
        .with_scheme(scheme)
        .with_bias_walk();
    let a = Vector3::new(0.1, -0.2, 9.81);
    let w = Vector3::new(0.3, 0.1, -0.2);
    if scheme == Scheme::Midpoint {
        p.try_integrate_measurement(&a, &w, 0.0, Clipped::NONE).unwrap();
    }
    for _ in 0..5 {
        p.try_integrate_measurement(&a, &w, 0.005, Clipped::NONE).unwrap();
    }
    p
}

fn refused(p: &Preintegrator, accel: [f64; 3], gyro: [f64; 3], dt: f64) -> Error {
    let mut q = p.clone();
    let err = q
        .try_integrate_measurement(&Vector3::from(accel), &Vector3::from(gyro), dt, Clipped::NONE)
        .unwrap_err();
    assert_eq!(&q, p, "a refused step changed the state ({err})");
    err
}

#[test]
fn refused_steps_leave_the_state_unchanged_and_name_their_argument() {
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        let p = started(scheme);
        let ok = [0.0, 0.0, 9.81];
        let e = refused(&p, [0.0, f64::NAN, 9.81], ok, 0.005);
        assert_eq!(
            (e.to_string().starts_with("accel:"), e.root()),
            (true, &Error::NonFinite { index: 1 })
        );
        let e = refused(&p, ok, [f64::INFINITY, 0.0, 0.0], 0.005);
        assert!(e.to_string().starts_with("gyro:"), "{e}");
        for dt in [0.0, -0.005, f64::NAN, f64::INFINITY] {
            let e = refused(&p, ok, ok, dt);
            assert!(matches!(e, Error::Parameter { name: "dt", .. }), "{e}");
        }
        // Finite readings that overflow the covariance: refused whole, nothing half-applied.
        let e = refused(&p, [1e300, -1e300, 1e300], [1e300, 1e300, 0.0], 1e10);
        assert!(matches!(e.root(), Error::Overflow { .. }), "{e}");
        assert!(e.to_string().starts_with("accel / gyro / dt:"), "{e}");
    }
}

#[test]
fn a_midpoint_window_starts_with_dt_zero() {
    let empty = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise()).with_scheme(Scheme::Midpoint);
    let e = refused(&empty, [0.0, 0.0, 9.81], [0.0; 3], 0.005);
    assert!(
        e.to_string()
            .starts_with("dt: the first sample of a midpoint window must be"),
        "{e}"
    );
    let mut p = empty.clone();
    p.try_integrate_measurement(&Vector3::new(0.0, 0.0, 9.81), &Vector3::zeros(), 0.0, Clipped::NONE)
        .unwrap();
    assert_eq!(p.last_sample(), Some((Vector3::new(0.0, 0.0, 9.81), Vector3::zeros())));
}

#[test]
fn accepted_steps_equal_the_unchecked_ones_bit_for_bit() {
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        let checked = started(scheme);
        let mut unchecked = Preintegrator::new(Vector3::new(0.01, 0.0, -0.02), Vector3::zeros(), noise())
            .with_scheme(scheme)
            .with_bias_walk();
        let (a, w) = (Vector3::new(0.1, -0.2, 9.81), Vector3::new(0.3, 0.1, -0.2));
        if scheme == Scheme::Midpoint {
            unchecked.integrate_measurement(&a, &w, 0.0);
        }
        for _ in 0..5 {
            unchecked.integrate_measurement(&a, &w, 0.005);
        }
        // The checked steps also record the window's ends for the continuity rule.
        let ends = checked.ends();
        assert!(ends.first.is_some_and(|e| e.t.is_none() && e.accel == a && e.gyro == w));
        assert_eq!(ends.last.is_some(), scheme == Scheme::Midpoint);
        let (c, u) = (checked.state_words(), unchecked.state_words());
        assert_eq!(c[..c.len() - 18], u[..u.len() - 18]);
    }
}
