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
    let gyro = [[w; 3]; 3];
    for scheme in [Scheme::Rk4, Scheme::Rk2, Scheme::Euler] {
        let options = attitude::Options {
            scheme,
            representation: Representation::Quaternion,
            ..attitude::Options::default()
        };
        let mut out = [[0.0; 4]; 3];
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
    let mut out = [[0.0; 4]; 3];
    let stored = attitude::integrate(&t, &gyro, &UnitQuaternion::identity(), &options, Some(&mut out));
    assert!(matches!(stored, Err(Error::Overflow { index: 1 })), "{stored:?}");
    let last = attitude::integrate(&t, &gyro, &UnitQuaternion::identity(), &options, None);
    assert!(matches!(last, Err(Error::Overflow { index: 2 })), "{last:?}");
}

/// fuzz/artifacts/preint/crash-8c76f01f…: finite samples with a finite but enormous noise density
/// (its square overflows) left an infinite covariance behind an `Ok`. Now an overflow at the last
/// sample, with nothing added; the windows report the sample ending the first bad window.
#[test]
fn preintegration_overflow_is_an_error_and_adds_nothing() {
    use imukit::imu::Noise;
    use imukit::imu::Samples;
    use imukit::preint::{preintegrate_windows, Preintegrator, Scheme};
    use nalgebra::Vector3;

    let t = [0.0, 0.01, 0.02];
    let gyro = [0.1, -0.2, 0.3, 0.1, -0.2, 0.3, 0.1, -0.2, 0.3];
    let accel = [0.0, 0.0, 9.81, 0.0, 0.0, 9.81, 0.0, 0.0, 9.81];
    let samples = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let huge = 1.6e212;
    for (noise, walk) in [
        (
            Noise {
                accel_random_walk: huge,
                ..Noise::default()
            },
            true,
        ),
        (
            Noise {
                accel_density: huge,
                ..Noise::default()
            },
            false,
        ),
    ] {
        for scheme in [Scheme::Euler, Scheme::Midpoint] {
            let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise).with_scheme(scheme);
            if walk {
                p = p.with_bias_walk();
            }
            let before = p.clone();
            let result = p.integrate_samples(&samples);
            assert!(
                matches!(result, Err(Error::Overflow { index: 2 })),
                "{scheme:?}: {result:?}"
            );
            assert_eq!(p, before, "{scheme:?}: the failed call changed the preintegration");
            let windows = preintegrate_windows(&samples, &[0.0, 0.005, 0.02], &before);
            assert!(
                matches!(windows, Err(Error::Overflow { index: 1 })),
                "{scheme:?}: {windows:?}"
            );
        }
    }
}

/// fuzz/artifacts/preint/crash-7386d8e0… (found on the AVX-512 path; every path agrees): a
/// midpoint window of two samples with an accelerometer bias of −2.0e265 m/s² and zero noise.
/// The deltas (5e263 m/s) and the stored covariance blocks are finite, but the public
/// `covariance()` adds the last sample's pending term, whose Gram products of the 1e262-sized
/// cross blocks overflow and meet the zero noise as `0 · inf`: NaN behind an `Ok`. It is an
/// overflow error now, with nothing added; every `Ok` of the case's neighbours is finite.
#[test]
fn preintegration_pending_term_overflow_is_an_error_not_a_nan_covariance() {
    use imukit::imu::{Noise, Samples};
    use imukit::preint::{Preintegrator, Scheme};
    use nalgebra::Vector3;

    let unit = 2f64.powi(-10);
    let t0 = 1.8813709274036607e-183 - 0.1281;
    let t = [t0, t0 + 0.0255];
    let gyro = [
        [-256.0 * unit, -unit, 0.0],
        [23296.0 * unit, 1024.0 * unit, 10240.0 * unit],
    ];
    let accel = [[-256.0 * unit, -unit, -unit], [255.0 * unit, 0.0, 0.0]];
    let samples = Samples::new(&t, &gyro, &accel).unwrap();
    for (bias, overflows) in [(-2.0152837035555516e265, true), (-2.0e150, false)] {
        for scheme in [Scheme::Midpoint, Scheme::Euler] {
            let mut p = Preintegrator::new(Vector3::zeros(), Vector3::new(bias, 5e-324, 0.0), Noise::default())
                .with_scheme(scheme);
            let before = p.clone();
            match p.integrate_samples(&samples) {
                Err(Error::Overflow { index }) => {
                    assert!(overflows, "{scheme:?}, bias {bias:e}: an overflow error");
                    assert_eq!(index, 1);
                    assert_eq!(p, before, "{scheme:?}: the failed call changed the preintegration");
                }
                Ok(()) => {
                    assert!(
                        !(overflows && scheme == Scheme::Midpoint),
                        "{scheme:?}, bias {bias:e}: Ok"
                    );
                    let (cov, jac) = (p.covariance(), p.bias_jacobian());
                    let values = [cov.as_slice(), jac.as_slice(), p.delta_velocity.as_slice()];
                    assert!(
                        values.iter().all(|v| v.iter().all(|x| x.is_finite())),
                        "{scheme:?}: non-finite Ok"
                    );
                }
                Err(e) => panic!("{scheme:?}: {e}"),
            }
        }
    }
}

/// An overflow at sample 1 blamed on the gyro bias (the rate's term dominates).
fn is_bias_overflow<T>(r: &Result<T, Error>) -> bool {
    matches!(r, Err(e) if e.argument() == Some("bias") && matches!(e.root(), Error::Overflow { index: 1 }))
}

/// fuzz/artifacts/strapdown/crash-61955b01…: an RK4 strapdown step with a finite but enormous
/// bias-corrected rate (1.3e66 rad/s over 2 s) overflowed |q|² inside `new_normalize`, which
/// returned the zero quaternion; `integrate` and `propagate` returned it as `Ok`.
#[test]
fn strapdown_rk4_norm_overflow_is_an_error_not_a_zero_quaternion() {
    use imukit::imu::{Bias, NavState, Noise, Samples};
    use imukit::propagate::{self, Covariance, Outputs};
    use imukit::strapdown::{self, StatesOut};
    use nalgebra::Vector3;

    let t = [0.0, 1.9789];
    let gyro = [0.0; 6];
    let accel = [0.0, 0.0, 9.81, 0.0, 0.0, 9.81];
    let samples = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let initial = NavState {
        position: Vector3::zeros(),
        velocity: Vector3::zeros(),
        rotation: UnitQuaternion::identity(),
    };
    let bias = Bias {
        gyro: Vector3::new(0.0, 0.0, 1.3e66),
        accel: Vector3::zeros(),
    };
    let options = strapdown::Options {
        scheme: strapdown::Scheme::Rk4,
        ..strapdown::Options::default()
    };
    let last = strapdown::integrate(&samples, &initial, &bias, &options, None);
    assert!(is_bias_overflow(&last), "{last:?}");
    let (mut pv, mut rot) = ([[0.0; 6]; 2], [[0.0; 4]; 2]);
    let states = StatesOut {
        position_velocity: &mut pv,
        rotation: &mut rot,
    };
    let stored = strapdown::integrate(&samples, &initial, &bias, &options, Some(states));
    assert!(is_bias_overflow(&stored), "{stored:?}");
    let mut covariances = [[0.0; 225]; 2];
    let outputs = Outputs {
        states: None,
        covariances: &mut covariances,
        every: 1,
    };
    let noise = Noise::default();
    let propagated = propagate::propagate(
        &samples,
        &initial,
        &Covariance::zeros(),
        &bias,
        &noise,
        &options,
        outputs,
    );
    assert!(is_bias_overflow(&propagated), "{propagated:?}");
    // Every other scheme composes exact rotations: still unit, still Ok.
    for scheme in [
        strapdown::Scheme::LieEuler,
        strapdown::Scheme::Midpoint,
        strapdown::Scheme::Exp,
    ] {
        let options = strapdown::Options { scheme, ..options };
        let x = strapdown::integrate(&samples, &initial, &bias, &options, None).unwrap();
        assert!((x.rotation.norm() - 1.0).abs() < 1e-12, "{scheme:?}");
    }
}

/// fuzz/artifacts/preint/crash-e55713a2…: two finite preintegrations with an enormous accelerometer
/// bias (2.3e197 m/s²) merged into an infinite covariance and Jacobian behind an `Ok`.
#[test]
fn preintegration_merge_overflow_is_an_error() {
    use imukit::imu::Noise;
    use imukit::imu::Samples;
    use imukit::preint::Preintegrator;
    use nalgebra::Vector3;

    let t = [0.0, 0.5];
    let gyro = [0.1, -0.2, 0.3, 0.1, -0.2, 0.3];
    let accel = [0.0; 6];
    let samples = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let noise = Noise {
        gyro_density: 1e-3,
        accel_density: 1e-2,
        ..Noise::default()
    };
    // The window after it: the same readings from its last stamp (the continuity rule).
    let later = [0.5, 1.0];
    let next = Samples::new(&later, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let run = |bias: f64, samples: &Samples<'_>| {
        let mut p = Preintegrator::new(Vector3::zeros(), Vector3::new(bias, 0.0, 0.0), noise);
        p.integrate_samples(samples).unwrap();
        p
    };
    let result = run(-2.3e197, &samples).merge(&run(-2.3e197, &next));
    match result {
        Err(Error::Argument { name, source }) => {
            assert_eq!(name, "next");
            assert!(matches!(*source, Error::Overflow { .. }), "{source:?}");
        }
        other => panic!("{other:?}"),
    }
    // A modest bias merges.
    let merged = run(0.1, &samples).merge(&run(0.1, &next)).unwrap();
    assert!((merged.delta_t - 1.0).abs() < 1e-15);
}

/// fuzz/artifacts/filters/crash-1c7ef27b…: a magnetometer reading 5e-8 rad off the measured
/// gravity direction left the initial north off perpendicular by cancellation, and the first
/// attitude (`initial_attitude`) was 1.07e-9 off unit norm.
#[test]
fn initial_attitude_is_unit_for_a_field_nearly_along_gravity() {
    use imukit::filters::{initial_attitude, World};
    use nalgebra::Vector3;

    let accel = Vector3::new(-128.0, -128.0, -128.0);
    let mag = Vector3::new(1.1278054389845096e45, 1.1278055297264741e45, 1.1278055297264741e45);
    for world in [World::Enu, World::Ned] {
        let q = initial_attitude(world, &accel, Some(&mag));
        assert!(
            (q.norm() - 1.0).abs() < 1e-15,
            "{world:?}: |q| − 1 = {:e}",
            q.norm() - 1.0
        );
        // Still the attitude the accelerometer asks for: body "up" is the measured direction.
        let up_world = if world == World::Enu {
            Vector3::z()
        } else {
            -Vector3::z()
        };
        let up_body = q.inverse() * up_world;
        assert!((up_body - accel.normalize()).norm() < 1e-12, "{world:?}: {up_body:?}");
    }
}
