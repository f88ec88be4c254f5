//! Preintegration, midpoint scheme: the block update against a dense augmented-state propagation
//! that carries the shared sample's noise explicitly, bias Jacobians against central differences of
//! a full re-integration, the deltas against the strapdown midpoint integrator, the covariance
//! against Monte Carlo runs with per-sample noise, and merging.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::imu::Noise;
use imukit::preint::{Preintegrator, Scheme};
use imukit_testing::preint::{chart, corrected, deltas, samples, Normal, H, N, NOISE};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

fn run(bias: (Vector3<f64>, Vector3<f64>), noise: Noise, data: &[(Vector3<f64>, Vector3<f64>)]) -> Preintegrator {
    imukit_testing::preint::run(Scheme::Midpoint, bias, noise, data)
}

fn zero_bias() -> (Vector3<f64>, Vector3<f64>) {
    (Vector3::zeros(), Vector3::zeros())
}

/// `[σ_g², σ_g², σ_g², σ_a², σ_a², σ_a²] / h` or `· h`, as a diagonal.
fn diag6(gyro: f64, accel: f64) -> SMatrix<f64, 6, 6> {
    SMatrix::<f64, 6, 6>::from_diagonal(&SVector::<f64, 6>::from_fn(|i, _| if i < 3 { gyro } else { accel }))
}

/// State `z = [δx (9), δb (6), n_last (6)]`: `δx' = A δx + G_b δb + B_0 n_last + B_1 n_new`,
/// `δb' = δb + w`, `n_last' = n_new`, with `G_b = B_0 + B_1` (a bias enters both samples).
#[test]
fn block_update_equals_a_dense_augmented_state_propagation() {
    let noise = Noise {
        gyro_random_walk: 1e-3,
        accel_random_walk: 1e-2,
        ..NOISE
    };
    let bias = (Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.2));
    let mut p = Preintegrator::new(bias.0, bias.1, noise)
        .with_scheme(Scheme::Midpoint)
        .with_bias_walk();
    let data = samples();
    let step = |k: usize| H * (1.0 + 0.3 * (k as f64).sin()); // uneven steps
    p.integrate_measurement(&data[0].0, &data[0].1, 0.0);
    let mut z = SMatrix::<f64, 21, 21>::zeros();
    let h0 = step(1);
    z.fixed_view_mut::<6, 6>(15, 15).copy_from(&diag6(
        noise.gyro_density.powi(2) / h0,
        noise.accel_density.powi(2) / h0,
    ));
    for (k, (a, w)) in data.iter().enumerate().skip(1) {
        let h = step(k);
        let m = p.midpoint_step_matrices(a, w, h).unwrap();
        let mut f = SMatrix::<f64, 21, 21>::zeros();
        f.fixed_view_mut::<9, 9>(0, 0).copy_from(&m.a);
        f.fixed_view_mut::<9, 6>(0, 9).copy_from(&(m.b0 + m.b1));
        f.fixed_view_mut::<9, 6>(0, 15).copy_from(&m.b0);
        f.fixed_view_mut::<6, 6>(9, 9)
            .copy_from(&SMatrix::<f64, 6, 6>::identity());
        let mut g = SMatrix::<f64, 21, 12>::zeros();
        g.fixed_view_mut::<9, 6>(0, 0).copy_from(&m.b1);
        g.fixed_view_mut::<6, 6>(9, 6)
            .copy_from(&SMatrix::<f64, 6, 6>::identity());
        g.fixed_view_mut::<6, 6>(15, 0)
            .copy_from(&SMatrix::<f64, 6, 6>::identity());
        let mut q = SMatrix::<f64, 12, 12>::zeros();
        q.fixed_view_mut::<6, 6>(0, 0)
            .copy_from(&diag6(noise.gyro_density.powi(2) / h, noise.accel_density.powi(2) / h));
        q.fixed_view_mut::<6, 6>(6, 6).copy_from(&diag6(
            noise.gyro_random_walk.powi(2) * h,
            noise.accel_random_walk.powi(2) * h,
        ));
        z = f * z * f.transpose() + g * q * g.transpose();
        p.integrate_measurement(a, w, h);
    }
    let dense = z.fixed_view::<15, 15>(0, 0).into_owned();
    let combined = p.covariance_combined().unwrap();
    let err = (combined - dense).amax() / dense.amax();
    assert!(err < 1e-12, "relative error {err:e}");
    assert_eq!(combined, combined.transpose());
    assert_eq!(combined.fixed_view::<9, 9>(0, 0), p.covariance());
    assert!(p.midpoint_step_matrices(&data[0].0, &data[0].1, H).is_some());
    let empty = Preintegrator::new(bias.0, bias.1, noise).with_scheme(Scheme::Midpoint);
    assert!(empty.midpoint_step_matrices(&data[0].0, &data[0].1, H).is_none());
}

#[test]
fn bias_jacobian_matches_central_differences_of_full_reintegration() {
    let data = samples();
    let bias = (Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.2));
    let base = run(bias, Noise::default(), &data);
    let eps = 1e-6;
    let mut numeric = SMatrix::<f64, 9, 6>::zeros();
    for c in 0..6 {
        let mut d = SVector::<f64, 6>::zeros();
        d[c] = eps;
        let (dg, da) = (d.fixed_rows::<3>(0).into_owned(), d.fixed_rows::<3>(3).into_owned());
        let plus = run((bias.0 + dg, bias.1 + da), Noise::default(), &data);
        let minus = run((bias.0 - dg, bias.1 - da), Noise::default(), &data);
        numeric.set_column(
            c,
            &((chart(&base, deltas(&plus)) - chart(&base, deltas(&minus))) / (2.0 * eps)),
        );
    }
    let analytic = base.bias_jacobian();
    let err = (analytic - numeric).amax() / numeric.amax();
    assert!(err < 1e-6, "relative error {err:e}\n{analytic}\n{numeric}");
    // sensitive: the euler scheme's Jacobian of the same samples is visibly different
    let euler = imukit_testing::preint::run(Scheme::Euler, bias, Noise::default(), &data).bias_jacobian();
    assert!((euler - numeric).amax() / numeric.amax() > 1e-3);
}

#[test]
fn corrected_converges_quadratically_to_reintegration() {
    let data = samples();
    let base = run(zero_bias(), Noise::default(), &data);
    let gap = |s: f64| {
        let bias = (Vector3::new(0.3, -0.5, 0.2) * s, Vector3::new(-0.4, 0.1, 0.6) * s);
        let exact = run(bias, Noise::default(), &data);
        chart(&exact, corrected(&base, &bias.0, &bias.1)).norm()
    };
    let ratio = gap(1e-2) / gap(5e-3);
    assert!((ratio - 4.0).abs() < 0.4, "ratio {ratio}");
}

#[test]
fn deltas_equal_strapdown_midpoint_without_gravity() {
    use imukit::imu::{Bias, NavState, Samples};
    use imukit::strapdown::{integrate, Options};
    use nalgebra::UnitQuaternion;
    let data = samples();
    let bias = (Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.2));
    let p = run(bias, Noise::default(), &data);
    let t: Vec<f64> = (0..N).map(|k| k as f64 * H).collect();
    let gyro: Vec<f64> = data.iter().flat_map(|(_, w)| w.iter().copied()).collect();
    let accel: Vec<f64> = data.iter().flat_map(|(a, _)| a.iter().copied()).collect();
    let x0 = NavState {
        position: Vector3::zeros(),
        velocity: Vector3::zeros(),
        rotation: UnitQuaternion::identity(),
    };
    let options = Options {
        scheme: imukit::strapdown::Scheme::Midpoint,
        gravity: Vector3::zeros(),
        ..Options::default()
    };
    let samples = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let b = Bias {
        gyro: bias.0,
        accel: bias.1,
    };
    let x = integrate(&samples, &x0, &b, &options, None).unwrap();
    assert!((x.position - p.delta_position).amax() < 1e-12);
    assert!((x.velocity - p.delta_velocity).amax() < 1e-12);
    assert!((x.rotation.to_rotation_matrix().matrix() - p.delta_rotation).amax() < 1e-13);
    assert!((p.delta_t - (N - 1) as f64 * H).abs() < 1e-12);
}

/// Mean NEES and relative Frobenius error of `cov` against errors sampled by `draw`.
fn monte_carlo<const D: usize>(
    cov: &SMatrix<f64, D, D>,
    runs: usize,
    mut draw: impl FnMut() -> SVector<f64, D>,
) -> (f64, f64, SMatrix<f64, D, D>) {
    let inv = cov.try_inverse().unwrap();
    let (mut sample, mut nees) = (SMatrix::<f64, D, D>::zeros(), 0.0);
    for _ in 0..runs {
        let e = draw();
        sample += e * e.transpose();
        nees += (e.transpose() * inv * e)[0];
    }
    sample /= runs as f64;
    (nees / runs as f64, (sample - cov).norm() / cov.norm(), sample)
}

#[test]
fn covariance_matches_monte_carlo_with_per_sample_noise() {
    let data = samples();
    let nominal = run(zero_bias(), NOISE, &data);
    let mut rng = Normal(0x005E_ED0F_F1CE_u64);
    let runs = 2000;
    let (mean_nees, rel, sample) = monte_carlo(&nominal.covariance(), runs, || {
        let noisy: Vec<_> = data
            .iter()
            .map(|(a, w)| {
                (
                    a + rng.vector() * (NOISE.accel_density / H.sqrt()),
                    w + rng.vector() * (NOISE.gyro_density / H.sqrt()),
                )
            })
            .collect();
        chart(&nominal, deltas(&run(zero_bias(), Noise::default(), &noisy)))
    });
    let half_width = 2.576 * (18.0f64 / runs as f64).sqrt(); // mean of χ²₉ over 2000 runs, 99%
    assert!((mean_nees - 9.0).abs() < half_width, "mean NEES {mean_nees}");
    assert!(rel < 0.1, "relative Frobenius error {rel}");
    let doubled = nominal.covariance() * 2.0;
    assert!((sample - doubled).norm() / doubled.norm() > 0.1);
    // VINS-Mono's model (every interval's two samples fresh) misses the shared-sample correlation:
    // the same dense propagation without it is clearly rejected.
    let mut vins = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE).with_scheme(Scheme::Midpoint);
    vins.integrate_measurement(&data[0].0, &data[0].1, H);
    let mut independent = SMatrix::<f64, 9, 9>::zeros();
    let q = diag6(NOISE.gyro_density.powi(2) / H, NOISE.accel_density.powi(2) / H);
    for (a, w) in &data[1..] {
        let m = vins.midpoint_step_matrices(a, w, H).unwrap();
        independent = m.a * independent * m.a.transpose() + m.b0 * q * m.b0.transpose() + m.b1 * q * m.b1.transpose();
        vins.integrate_measurement(a, w, H);
    }
    let vins_rel = (sample - independent).norm() / independent.norm();
    assert!(vins_rel > 0.3, "the independent-noise model fits too: {vins_rel}");
}

#[test]
fn combined_covariance_matches_monte_carlo_with_bias_random_walk() {
    let data = samples();
    let noise = Noise {
        gyro_random_walk: 2e-2,
        accel_random_walk: 2e-1,
        ..NOISE
    };
    let truth = run(zero_bias(), Noise::default(), &data);
    let mut nominal = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise)
        .with_scheme(Scheme::Midpoint)
        .with_bias_walk();
    for (a, w) in &data {
        nominal.integrate_measurement(a, w, H);
    }
    let mut rng = Normal(0x0B1A_5000_0007_u64);
    // Measurements as a sensor makes them: sample k carries the bias b_k of its own instant.
    let (mean_nees, rel, _) = monte_carlo(&nominal.covariance_combined().unwrap(), 2000, || {
        let (mut bg, mut ba) = (Vector3::zeros(), Vector3::zeros());
        let mut noisy = Vec::with_capacity(N);
        for (k, (a, w)) in data.iter().enumerate() {
            if k > 0 {
                bg += rng.vector() * (noise.gyro_random_walk * H.sqrt());
                ba += rng.vector() * (noise.accel_random_walk * H.sqrt());
            }
            noisy.push((
                a + ba + rng.vector() * (noise.accel_density / H.sqrt()),
                w + bg + rng.vector() * (noise.gyro_density / H.sqrt()),
            ));
        }
        let est = run(zero_bias(), Noise::default(), &noisy);
        let mut e = SVector::<f64, 15>::zeros();
        e.fixed_rows_mut::<9>(0).copy_from(&chart(&est, deltas(&truth)));
        e.fixed_rows_mut::<3>(9).copy_from(&bg);
        e.fixed_rows_mut::<3>(12).copy_from(&ba);
        e
    });
    let half_width = 2.576 * (30.0f64 / 2000.0).sqrt();
    assert!((mean_nees - 15.0).abs() < half_width, "mean NEES {mean_nees}");
    assert!(rel < 0.1, "relative Frobenius error {rel}");
}

#[test]
fn merge_equals_one_preintegration_over_both_segments() {
    let data = samples();
    let bias = (Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.2));
    let whole = run(bias, NOISE, &data);
    // the segments share sample 73, whose noise enters both
    let (first, second) = (&data[..74], &data[73..]);
    let merged = run(bias, NOISE, first).merge(&run(bias, NOISE, second)).unwrap();
    assert!((merged.delta_rotation - whole.delta_rotation).amax() < 1e-14);
    assert!((merged.delta_velocity - whole.delta_velocity).amax() < 1e-13);
    assert!((merged.delta_position - whole.delta_position).amax() < 1e-13);
    let cov_err = (merged.covariance() - whole.covariance()).amax() / whole.covariance().amax();
    assert!(cov_err < 1e-12, "covariance off by {cov_err:e}");
    let jac_err = (merged.bias_jacobian() - whole.bias_jacobian()).amax() / whole.bias_jacobian().amax();
    assert!(jac_err < 1e-12, "bias Jacobian off by {jac_err:e}");
    // merged three ways, the result continues like the whole
    let (a, b, c) = (&data[..40], &data[39..120], &data[119..]);
    let three = run(bias, NOISE, a)
        .merge(&run(bias, NOISE, b))
        .unwrap()
        .merge(&run(bias, NOISE, c))
        .unwrap();
    let err3 = (three.covariance() - whole.covariance()).amax() / whole.covariance().amax();
    assert!(err3 < 1e-12, "three-way covariance off by {err3:e}");
    // segments that do not share their boundary sample, or differ in scheme, do not merge
    assert!(run(bias, NOISE, first).merge(&run(bias, NOISE, &data[75..])).is_err());
    let euler = imukit_testing::preint::run(Scheme::Euler, bias, NOISE, second);
    assert!(run(bias, NOISE, first).merge(&euler).is_err());
}

#[test]
fn the_first_sample_only_starts_the_window() {
    let data = samples();
    let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE).with_scheme(Scheme::Midpoint);
    p.integrate_measurement(&data[0].0, &data[0].1, 123.0);
    assert_eq!(p.delta_t, 0.0);
    assert_eq!(p.covariance(), SMatrix::<f64, 9, 9>::zeros());
    assert_eq!(p.delta_rotation, Matrix3::identity());
}
