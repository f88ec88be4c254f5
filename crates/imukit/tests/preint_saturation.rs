//! Saturation: a clipped sample's white-noise densities are multiplied by the saturation noise
//! factor (euler: on the interval the sample starts; midpoint: the sample's own noise, shared by
//! the two intervals it bounds). Checked against a closed form for one interval, against dense
//! propagations with per-sample noise variances set by hand, and for bit-identity where nothing
//! changes (deltas always; covariance without flags or with factor 1).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::imu::Samples;
use imukit::preint::{
    preintegrate_windows, preintegrate_windows_clipped, ClipMask, Clipped, Preintegrator, Scheme, CHUNK,
};
use imukit::Error;
use imukit_testing::preint::{samples, H, NOISE};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

const F: f64 = 100.0;

/// `(t, gyro, accel)`, the fixture's samples (flat) with uneven steps, so that each sample's own
/// interval length matters.
fn stream() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let data = samples();
    let mut t = vec![0.3];
    for k in 1..data.len() {
        t.push(t[k - 1] + H * (1.0 + 0.3 * (k as f64).sin()));
    }
    let gyro = data.iter().flat_map(|(_, w)| w.iter().copied()).collect();
    (t, gyro, data.iter().flat_map(|(a, _)| a.iter().copied()).collect())
}

fn view<'a>(t: &'a [f64], gyro: &'a [f64], accel: &'a [f64]) -> Samples<'a> {
    Samples::new(t, gyro.as_chunks().0, accel.as_chunks().0).unwrap()
}

fn template(scheme: Scheme) -> Preintegrator {
    Preintegrator::new(Vector3::new(0.01, 0.0, -0.02), Vector3::new(0.1, -0.1, 0.05), NOISE).with_scheme(scheme)
}

fn batch(s: &Samples<'_>, mask: Option<&ClipMask<'_>>, p: Preintegrator) -> Preintegrator {
    let mut p = p;
    p.integrate_samples_clipped(s, mask).unwrap();
    p
}

/// Gyro flags at 0, 37 and 120..125, accelerometer flags at 37, 80 and the last sample.
fn flags(n: usize) -> (Vec<bool>, Vec<bool>) {
    let gyro: Vec<bool> = (0..n).map(|k| k == 0 || k == 37 || (120..125).contains(&k)).collect();
    let accel: Vec<bool> = (0..n).map(|k| k == 37 || k == 80 || k == n - 1).collect();
    (gyro, accel)
}

fn rel(a: &SMatrix<f64, 9, 9>, b: &SMatrix<f64, 9, 9>) -> f64 {
    (a - b).amax() / b.amax()
}

fn diag6(gyro: f64, accel: f64) -> SMatrix<f64, 6, 6> {
    SMatrix::<f64, 6, 6>::from_diagonal(&SVector::<f64, 6>::from_fn(|i, _| if i < 3 { gyro } else { accel }))
}

#[test]
fn one_clipped_euler_interval_has_the_closed_form_covariance() {
    // From an empty preintegration with ω̂ = 0: Σ_θθ = σ_g² h I (J_r = I), Σ_vv = σ_a² h I,
    // Σ_pp = σ_a² h³/4 I; a clipped gyro multiplies only Σ_θθ by F², a clipped accelerometer only
    // the v and p blocks.
    let h = 0.01;
    let (a, w) = (Vector3::new(0.3, -0.2, 9.8), Vector3::zeros());
    for (clipped, sg, sa) in [
        (
            Clipped {
                gyro: true,
                accel: false,
            },
            F * F,
            1.0,
        ),
        (
            Clipped {
                gyro: false,
                accel: true,
            },
            1.0,
            F * F,
        ),
        (
            Clipped {
                gyro: true,
                accel: true,
            },
            F * F,
            F * F,
        ),
        (Clipped::NONE, 1.0, 1.0),
    ] {
        let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE);
        p.integrate_measurement_clipped(&a, &w, h, clipped);
        let c = p.covariance();
        let block = |i: usize, j: usize| c.fixed_view::<3, 3>(3 * i, 3 * j).into_owned();
        let close = |m: Matrix3<f64>, v: f64| (m - Matrix3::identity() * v).amax() <= 1e-14 * v;
        let (g2, a2) = (NOISE.gyro_density.powi(2), NOISE.accel_density.powi(2));
        assert!(close(block(0, 0), g2 * h * sg), "{clipped:?}: {}", block(0, 0));
        assert!(close(block(1, 1), a2 * h * sa), "{clipped:?}: {}", block(1, 1));
        assert!(
            close(block(2, 2), a2 * h.powi(3) / 4.0 * sa),
            "{clipped:?}: {}",
            block(2, 2)
        );
    }
}

/// Euler: `Σ ← A Σ Aᵀ + B (s_a σ_a²/h) Bᵀ + C (s_g σ_g²/h) Cᵀ` with dense step matrices, the
/// multipliers `s` set by hand from the flags of the interval's starting sample.
#[test]
fn euler_covariance_equals_a_dense_propagation_with_hand_inflated_noise() {
    let (t, gyro, accel) = stream();
    let s = view(&t, &gyro, &accel);
    let n = t.len();
    let (g, a) = flags(n);
    let mask = ClipMask { gyro: &g, accel: &a };
    let flagged = batch(&s, Some(&mask), template(Scheme::Euler));
    let mut p = template(Scheme::Euler);
    let mut cov = SMatrix::<f64, 9, 9>::zeros();
    for k in 0..n - 1 {
        let h = t[k + 1] - t[k];
        let m = p.step_matrices(&s.accel_at(k), &s.gyro_at(k), h);
        let sg = if g[k] { F * F } else { 1.0 };
        let sa = if a[k] { F * F } else { 1.0 };
        cov = m.a * cov * m.a.transpose()
            + m.b * m.b.transpose() * (sa * NOISE.accel_density.powi(2) / h)
            + m.c * m.c.transpose() * (sg * NOISE.gyro_density.powi(2) / h);
        p.integrate_measurement(&s.accel_at(k), &s.gyro_at(k), h);
    }
    let err = rel(&flagged.covariance(), &cov);
    assert!(err < 1e-12, "relative error {err:e}");
    // Sensitive: the covariance without flags is far from it.
    assert!(rel(&p.covariance(), &cov) > 0.1);
}

/// Midpoint: the augmented state `[δx, n_last]`, `δx' = A δx + B_0 n_last + B_1 n_new`, each
/// sample's noise with variance `s σ²/h` (h: its first interval, s from its own flags).
#[test]
fn midpoint_covariance_equals_a_dense_propagation_with_hand_inflated_sample_noise() {
    let (t, gyro, accel) = stream();
    let s = view(&t, &gyro, &accel);
    let n = t.len();
    let (g, a) = flags(n);
    let mask = ClipMask { gyro: &g, accel: &a };
    let flagged = batch(&s, Some(&mask), template(Scheme::Midpoint));
    let var = |k: usize, h: f64| {
        let sg = if g[k] { F * F } else { 1.0 };
        let sa = if a[k] { F * F } else { 1.0 };
        diag6(
            sg * NOISE.gyro_density.powi(2) / h,
            sa * NOISE.accel_density.powi(2) / h,
        )
    };
    let mut p = template(Scheme::Midpoint);
    p.integrate_measurement(&s.accel_at(0), &s.gyro_at(0), 0.0);
    let mut z = SMatrix::<f64, 15, 15>::zeros();
    z.fixed_view_mut::<6, 6>(9, 9).copy_from(&var(0, t[1] - t[0]));
    for k in 1..n {
        let h = t[k] - t[k - 1];
        let m = p.midpoint_step_matrices(&s.accel_at(k), &s.gyro_at(k), h).unwrap();
        let mut f = SMatrix::<f64, 15, 15>::zeros();
        f.fixed_view_mut::<9, 9>(0, 0).copy_from(&m.a);
        f.fixed_view_mut::<9, 6>(0, 9).copy_from(&m.b0);
        let mut gm = SMatrix::<f64, 15, 6>::zeros();
        gm.fixed_view_mut::<9, 6>(0, 0).copy_from(&m.b1);
        gm.fixed_view_mut::<6, 6>(9, 0)
            .copy_from(&SMatrix::<f64, 6, 6>::identity());
        z = f * z * f.transpose() + gm * var(k, h) * gm.transpose();
        p.integrate_measurement(&s.accel_at(k), &s.gyro_at(k), h);
    }
    let dense = z.fixed_view::<9, 9>(0, 0).into_owned();
    let err = rel(&flagged.covariance(), &dense);
    assert!(err < 1e-12, "relative error {err:e}");
    assert!(rel(&p.covariance(), &dense) > 0.1);
}

#[test]
fn deltas_and_bias_jacobian_do_not_change_and_no_flags_or_factor_one_change_nothing() {
    let (t, gyro, accel) = stream();
    let s = view(&t, &gyro, &accel);
    let n = t.len();
    let (g, a) = flags(n);
    let (none, all) = (vec![false; n], vec![true; n]);
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        let plain = batch(&s, None, template(scheme));
        let flagged = batch(&s, Some(&ClipMask { gyro: &g, accel: &a }), template(scheme));
        assert_eq!(flagged.delta_rotation, plain.delta_rotation);
        assert_eq!(flagged.delta_velocity, plain.delta_velocity);
        assert_eq!(flagged.delta_position, plain.delta_position);
        assert_eq!(flagged.delta_t, plain.delta_t);
        assert_eq!(flagged.bias_jacobian(), plain.bias_jacobian());
        assert_ne!(flagged.covariance(), plain.covariance());
        // An all-false mask, and every sample flagged with factor 1: bit for bit the plain run.
        let unflagged = batch(
            &s,
            Some(&ClipMask {
                gyro: &none,
                accel: &none,
            }),
            template(scheme),
        );
        assert_eq!(unflagged, plain);
        let one = template(scheme).with_saturation_noise_factor(1.0).unwrap();
        let all_one = batch(
            &s,
            Some(&ClipMask {
                gyro: &all,
                accel: &all,
            }),
            one,
        );
        assert_eq!(all_one.covariance(), plain.covariance());
        // Streaming with Clipped::NONE is integrate_measurement.
        let mut streamed = template(scheme);
        if scheme == Scheme::Midpoint {
            streamed.integrate_measurement_clipped(&s.accel_at(0), &s.gyro_at(0), 0.0, Clipped::NONE);
        }
        for k in 1..n {
            let held = if scheme == Scheme::Euler { k - 1 } else { k };
            let h = t[k] - t[k - 1];
            streamed.integrate_measurement_clipped(&s.accel_at(held), &s.gyro_at(held), h, Clipped::NONE);
        }
        // All but the batch's ends (continuity.rs), which unchecked steps do not record.
        let (a, b) = (streamed.state_words(), plain.state_words());
        assert_eq!(a[..a.len() - 18], b[..b.len() - 18]);
    }
}

#[test]
fn euler_ignores_the_last_sample_flag_midpoint_uses_it() {
    let (t, gyro, accel) = stream();
    let s = view(&t, &gyro, &accel);
    let n = t.len();
    let none = vec![false; n];
    let last: Vec<bool> = (0..n).map(|k| k == n - 1).collect();
    let first: Vec<bool> = (0..n).map(|k| k == 0).collect();
    for (scheme, last_counts) in [(Scheme::Euler, false), (Scheme::Midpoint, true)] {
        let plain = batch(&s, None, template(scheme));
        let at_last = batch(
            &s,
            Some(&ClipMask {
                gyro: &last,
                accel: &none,
            }),
            template(scheme),
        );
        let at_first = batch(
            &s,
            Some(&ClipMask {
                gyro: &first,
                accel: &none,
            }),
            template(scheme),
        );
        // The last sample starts no euler interval; the midpoint's last interval ends with it.
        assert_eq!(at_last.covariance() != plain.covariance(), last_counts, "{scheme:?}");
        // The first sample is used by both.
        assert!(
            at_first.covariance()[(0, 0)] > 1.5 * plain.covariance()[(0, 0)],
            "{scheme:?}"
        );
    }
}

#[test]
fn windows_with_a_clipped_sample_grow_and_the_others_are_unchanged() {
    let (t, gyro, accel) = stream();
    let s = view(&t, &gyro, &accel);
    let n = t.len();
    // Accelerometer clipped at samples 60..=62 only; boundaries on samples and between them.
    let a: Vec<bool> = (0..n).map(|k| (60..=62).contains(&k)).collect();
    let g = vec![false; n];
    let mask = ClipMask { gyro: &g, accel: &a };
    let b = [
        t[0],
        t[30],
        0.5 * (t[50] + t[51]),
        t[70],
        0.5 * (t[100] + t[101]),
        t[n - 1],
    ];
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        let plain = preintegrate_windows(&s, &b, &template(scheme)).unwrap();
        let flagged = preintegrate_windows_clipped(&s, Some(&mask), &b, &template(scheme)).unwrap();
        for (m, (f, p)) in flagged.iter().zip(&plain).enumerate() {
            assert_eq!(
                (f.delta_velocity, f.delta_position),
                (p.delta_velocity, p.delta_position)
            );
            if m == 2 {
                // [t50.5, t70] holds the clipped samples: its velocity variance grows by far more
                // than the ×1.5 a window's own growth would explain.
                assert!(f.covariance()[(3, 3)] > 10.0 * p.covariance()[(3, 3)], "{scheme:?}");
            } else {
                assert_eq!(f, p, "{scheme:?} window {m}");
            }
        }
    }
}

#[test]
fn an_interpolated_midpoint_boundary_takes_either_neighbours_flag() {
    let (t, gyro, accel) = stream();
    let s = view(&t, &gyro, &accel);
    let n = t.len();
    let g = vec![false; n];
    // Sample 51 clipped: the point between 50 and 51 inherits it, so the window ending there grows.
    let a: Vec<bool> = (0..n).map(|k| k == 51).collect();
    let b = [t[0], 0.5 * (t[50] + t[51]), t[n - 1]];
    let plain = preintegrate_windows(&s, &b, &template(Scheme::Midpoint)).unwrap();
    let mask = ClipMask { gyro: &g, accel: &a };
    let flagged = preintegrate_windows_clipped(&s, Some(&mask), &b, &template(Scheme::Midpoint)).unwrap();
    assert!(flagged[0].covariance()[(3, 3)] > plain[0].covariance()[(3, 3)]);
    assert!(flagged[1].covariance()[(3, 3)] > plain[1].covariance()[(3, 3)]);
    // Euler holds sample 50 up to the boundary: the first window does not see sample 51.
    let plain = preintegrate_windows(&s, &b, &template(Scheme::Euler)).unwrap();
    let flagged = preintegrate_windows_clipped(&s, Some(&mask), &b, &template(Scheme::Euler)).unwrap();
    assert_eq!(flagged[0], plain[0]);
    assert!(flagged[1].covariance()[(3, 3)] > plain[1].covariance()[(3, 3)]);
}

#[test]
fn the_parallel_paths_inflate_as_streaming_does() {
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        parallel_path_inflates_as_streaming_does(scheme);
    }
}

fn parallel_path_inflates_as_streaming_does(scheme: Scheme) {
    let n = 2 * CHUNK + 1000;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let gyro: Vec<f64> = (0..3 * n).map(|i| 0.1 * ((i as f64) * 0.37).sin()).collect();
    let accel: Vec<f64> = (0..3 * n)
        .map(|i| 9.81 * (i % 3 == 2) as u8 as f64 + 0.2 * ((i as f64) * 0.11).cos())
        .collect();
    let samples = view(&t, &gyro, &accel);
    // Four equal chunks: flags on both sides of the boundary at the middle sample (shared by two
    // midpoint chunks), inside chunks, and on the first sample.
    let edge = (n - 1) / 2;
    let a: Vec<bool> = (0..n)
        .map(|k| (edge - 3..edge + 3).contains(&k) || k == 17 || k == 0)
        .collect();
    let g: Vec<bool> = (0..n)
        .map(|k| k == edge || k == CHUNK + 500 || k == 2 * CHUNK + 10)
        .collect();
    let mut par = template(scheme);
    par.integrate_samples_clipped(&samples, Some(&ClipMask { gyro: &g, accel: &a }))
        .unwrap();
    let mut seq = template(scheme);
    let clipped = |k: usize| Clipped {
        gyro: g[k],
        accel: a[k],
    };
    for k in 0..n - 1 {
        let h = t[k + 1] - t[k];
        match scheme {
            Scheme::Euler => {
                seq.integrate_measurement_clipped(&samples.accel_at(k), &samples.gyro_at(k), h, clipped(k))
            }
            Scheme::Midpoint => {
                if k == 0 {
                    seq.integrate_measurement_clipped(&samples.accel_at(0), &samples.gyro_at(0), 0.0, clipped(0));
                }
                seq.integrate_measurement_clipped(&samples.accel_at(k + 1), &samples.gyro_at(k + 1), h, clipped(k + 1));
            }
        }
    }
    let err = rel(&par.covariance(), &seq.covariance());
    assert!(err < 1e-10, "{scheme:?}: relative error {err:e}");
    let mut plain = template(scheme);
    plain.integrate_samples(&samples).unwrap();
    assert!(rel(&plain.covariance(), &seq.covariance()) > 1e-3, "{scheme:?}");
}

#[test]
fn bad_masks_and_factors_are_refused_with_their_name() {
    let (t, gyro, accel) = stream();
    let s = view(&t, &gyro, &accel);
    let n = t.len();
    let (short, ok) = (vec![false; n - 1], vec![false; n]);
    let mut p = template(Scheme::Euler);
    let err = p
        .integrate_samples_clipped(
            &s,
            Some(&ClipMask {
                gyro: &ok,
                accel: &short,
            }),
        )
        .unwrap_err();
    assert!(
        matches!(
            err,
            Error::Parameter {
                name: "accel_saturated",
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(p, template(Scheme::Euler));
    let b = [t[0], t[n - 1]];
    let err = preintegrate_windows_clipped(
        &s,
        Some(&ClipMask {
            gyro: &short,
            accel: &ok,
        }),
        &b,
        &p,
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            Error::Parameter {
                name: "gyro_saturated",
                ..
            }
        ),
        "{err:?}"
    );
    for bad in [0.5, f64::NAN, f64::INFINITY, -3.0] {
        let err = template(Scheme::Euler).with_saturation_noise_factor(bad).unwrap_err();
        assert!(
            matches!(
                err,
                Error::Parameter {
                    name: "saturation_noise_factor",
                    ..
                }
            ),
            "{bad}"
        );
    }
    // Merging needs the same factor.
    let (mut x, mut y) = (
        template(Scheme::Euler),
        template(Scheme::Euler).with_saturation_noise_factor(10.0).unwrap(),
    );
    x.integrate_samples(&s).unwrap();
    y.integrate_samples(&s).unwrap();
    assert!(x.merge(&y).is_err());
}
