//! Gyro integration from Rust: exactness for constant rate, the two-pass (parallel increments)
//! path against the one-pass loop, and input errors naming the first bad sample.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::attitude::{self, integrate, Options, Representation, Scheme};
use imukit::{so3, Error};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

fn options(scheme: Scheme, representation: Representation) -> Options {
    Options {
        scheme,
        representation,
        ..Options::default()
    }
}

fn smooth_rates(n: usize, h: f64) -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..n).map(|k| k as f64 * h).collect();
    let gyro = t
        .iter()
        .flat_map(|&s| {
            [
                0.3 * (1.1 * s).sin(),
                0.2 * (0.7 * s).cos() + 0.1,
                0.5 * (1.3 * s).sin(),
            ]
        })
        .collect();
    (t, gyro)
}

#[test]
fn constant_rate_is_exact_for_the_closed_forms() {
    let n = 100_000;
    let w = Vector3::new(0.31, -0.52, 0.77);
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.001).collect();
    let gyro: Vec<f64> = (0..n).flat_map(|_| [w.x, w.y, w.z]).collect();
    let q0 = UnitQuaternion::from_scaled_axis(Vector3::new(0.1, 0.2, -0.3));
    let truth = q0 * UnitQuaternion::from_rotation_matrix(&so3::exp(&(w * t[n - 1])));
    for scheme in [Scheme::Exp, Scheme::Magnus] {
        for representation in [Representation::Quaternion, Representation::Matrix] {
            let mut out = vec![0.0; 4 * n];
            let last = integrate(
                &t,
                gyro.as_chunks().0,
                &q0,
                &options(scheme, representation),
                Some(out.as_chunks_mut().0),
            )
            .unwrap();
            assert!(
                last.angle_to(&truth) < 1e-10,
                "{scheme:?}/{representation:?}: {}",
                last.angle_to(&truth)
            );
            // every stored attitude is unit to rounding
            for q in out.chunks_exact(4) {
                let norm2: f64 = q.iter().map(|v| v * v).sum();
                assert!((norm2 - 1.0).abs() < 1e-14);
            }
        }
    }
}

#[test]
fn stored_path_equals_final_only_path_bit_for_bit() {
    // With `out` the quaternion closed forms take the parallel two-pass path; without, the loop.
    let (t, gyro) = smooth_rates(50_000, 0.005);
    for scheme in [Scheme::Exp, Scheme::Magnus] {
        let o = options(scheme, Representation::Quaternion);
        let q0 = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.1, 0.2));
        let mut out = vec![0.0; 4 * t.len()];
        let stored = integrate(&t, gyro.as_chunks().0, &q0, &o, Some(out.as_chunks_mut().0)).unwrap();
        let last = integrate(&t, gyro.as_chunks().0, &q0, &o, None).unwrap();
        assert_eq!(stored.coords, last.coords, "{scheme:?}");
        assert_eq!(&out[out.len() - 4..], stored.coords.as_slice());
        assert_eq!(&out[..4], q0.coords.as_slice());
    }
}

#[test]
fn errors_name_the_first_bad_sample_on_both_paths() {
    let (mut t, mut gyro) = smooth_rates(20_000, 0.005);
    gyro[3 * 9_000 + 1] = f64::NAN;
    gyro[3 * 15_000] = f64::INFINITY;
    for scheme in [Scheme::Exp, Scheme::Rk2, Scheme::Magnus] {
        for store in [true, false] {
            let mut out = vec![0.0; 4 * t.len()];
            let out = store.then_some(out.as_chunks_mut().0);
            let err = integrate(
                &t,
                gyro.as_chunks().0,
                &UnitQuaternion::identity(),
                &options(scheme, Representation::Quaternion),
                out,
            )
            .unwrap_err();
            assert_eq!(
                err,
                Error::NonFinite { index: 9_000 }.in_argument("gyro"),
                "{scheme:?} store={store}"
            );
        }
    }
    gyro[3 * 9_000 + 1] = 0.0;
    gyro[3 * 15_000] = 0.0;
    t[12_345] = t[12_344];
    t[17_000] = 0.0;
    let mut out = vec![0.0; 4 * t.len()];
    let err = integrate(
        &t,
        gyro.as_chunks().0,
        &UnitQuaternion::identity(),
        &options(Scheme::Magnus, Representation::Quaternion),
        Some(out.as_chunks_mut().0),
    )
    .unwrap_err();
    assert_eq!(
        err,
        Error::NonIncreasingTime { index: 12_345, dt: 0.0 }.in_argument("t")
    );
}

#[test]
fn euler_angles_refuse_group_schemes_and_stop_at_gimbal_lock() {
    let (t, _) = smooth_rates(2_001, 0.001);
    let pitch_up: Vec<f64> = t.iter().flat_map(|_| [0.0, 1.0, 0.0]).collect();
    let err = integrate(
        &t,
        pitch_up.as_chunks().0,
        &UnitQuaternion::identity(),
        &options(Scheme::Exp, Representation::Euler),
        None,
    )
    .unwrap_err();
    assert_eq!(err.argument(), Some("scheme"));
    let Error::Argument { source, .. } = err else {
        panic!("not named: {err}")
    };
    assert!(matches!(*source, Error::Unsupported { supported, .. } if supported == ["euler", "rk2", "rk4"]));
    let o = Options {
        gimbal_tolerance: 1e-3,
        ..options(Scheme::Rk4, Representation::Euler)
    };
    match integrate(&t, pitch_up.as_chunks().0, &UnitQuaternion::identity(), &o, None).unwrap_err() {
        // pitch = k·1e-3 reaches π/2 − 1e-3 at k ≈ 1569.8: the last RK4 stage of the step that
        // starts at sample 1569 evaluates E at pitch 1.570 and is refused, naming that step.
        Error::GimbalLock { index, .. } => assert_eq!(index, 1569),
        other => panic!("{other:?}"),
    }
}

#[test]
fn rotation_matrix_form_is_the_matrix_representation_and_refuses_a_non_rotation() {
    let (t, gyro) = smooth_rates(400, 0.005);
    let initial = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
    let r0 = *initial.to_rotation_matrix().matrix();
    for scheme in Representation::Matrix.schemes() {
        // Same state as integrate(), which converts it to a quaternion only at the end.
        let opts = options(*scheme, Representation::Matrix);
        let r = attitude::integrate_rotation_matrix(&t, gyro.as_chunks().0, &r0, &opts).unwrap();
        let q = attitude::integrate(&t, gyro.as_chunks().0, &initial, &opts, None).unwrap();
        assert!((r - q.to_rotation_matrix().matrix()).abs().max() < 1e-14, "{scheme:?}");
        // The representation field is ignored: quaternion options give the matrix result too.
        let quaternion_opts = options(*scheme, Representation::Quaternion);
        assert_eq!(
            attitude::integrate_rotation_matrix(&t, gyro.as_chunks().0, &r0, &quaternion_opts).unwrap(),
            r
        );
    }
    let opts = options(Scheme::Rk4, Representation::Matrix);
    let reflection = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
    for bad in [r0 * 1.001, reflection, Matrix3::from_element(f64::NAN)] {
        let e = attitude::integrate_rotation_matrix(&t, gyro.as_chunks().0, &bad, &opts).unwrap_err();
        assert!(e.to_string().contains("initial"), "{e}");
    }
}
