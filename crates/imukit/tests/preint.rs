//! Preintegration (Forster, euler scheme): bias Jacobians against central differences of a full
//! re-integration, first-order bias correction converging quadratically, the deltas against the
//! strapdown integrator, and the covariance against a Monte Carlo.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::imu::Noise;
use imukit::preint::{Preintegrator, Scheme};
use imukit_testing::preint::{chart, corrected, deltas, samples, Normal, H, N};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

fn run(bg: Vector3<f64>, ba: Vector3<f64>, noise: Noise, data: &[(Vector3<f64>, Vector3<f64>)]) -> Preintegrator {
    imukit_testing::preint::run(Scheme::Euler, (bg, ba), noise, data)
}

#[test]
fn bias_jacobian_matches_central_differences_of_full_reintegration() {
    let data = samples();
    let (bg, ba) = (Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.2));
    let base = run(bg, ba, Noise::default(), &data);
    let eps = 1e-6;
    let mut numeric = SMatrix::<f64, 9, 6>::zeros();
    for c in 0..6 {
        let mut d = SVector::<f64, 6>::zeros();
        d[c] = eps;
        let plus = run(
            bg + d.fixed_rows::<3>(0),
            ba + d.fixed_rows::<3>(3),
            Noise::default(),
            &data,
        );
        let minus = run(
            bg - d.fixed_rows::<3>(0),
            ba - d.fixed_rows::<3>(3),
            Noise::default(),
            &data,
        );
        numeric.set_column(
            c,
            &((chart(&base, deltas(&plus)) - chart(&base, deltas(&minus))) / (2.0 * eps)),
        );
    }
    let analytic = base.bias_jacobian();
    let err = (analytic - numeric).amax() / numeric.amax();
    assert!(err < 1e-6, "relative error {err:e}\n{analytic}\n{numeric}");
    // sensitive: dropping the rotation coupling of ∂Δv/∂b_g is caught
    let mut wrong = analytic;
    wrong.fixed_view_mut::<3, 3>(3, 0).fill(0.0);
    assert!((wrong - numeric).amax() / numeric.amax() > 1e-2);
}

#[test]
fn corrected_converges_quadratically_to_reintegration() {
    let data = samples();
    let base = run(Vector3::zeros(), Vector3::zeros(), Noise::default(), &data);
    let direction_g = Vector3::new(0.3, -0.5, 0.2);
    let direction_a = Vector3::new(-0.4, 0.1, 0.6);
    let gap = |s: f64| {
        let (bg, ba) = (direction_g * s, direction_a * s);
        let exact = run(bg, ba, Noise::default(), &data);
        chart(&exact, corrected(&base, &bg, &ba)).norm()
    };
    let (g1, g2) = (gap(1e-2), gap(5e-3));
    let ratio = g1 / g2;
    assert!(
        (ratio - 4.0).abs() < 0.4,
        "halving the bias change should quarter the gap: {g1:e} / {g2:e} = {ratio}"
    );
}

#[test]
fn deltas_equal_strapdown_from_rest_without_gravity() {
    // Δp, Δv are gravity-free and in the frame at i: integrating from identity, zero velocity,
    // with gravity switched off and the euler scheme gives the same numbers.
    use imukit::imu::{Bias, NavState, Samples};
    use imukit::strapdown::{integrate, Options, Scheme};
    use nalgebra::UnitQuaternion;
    let data = samples();
    let p = run(Vector3::zeros(), Vector3::zeros(), Noise::default(), &data);
    let mut t = vec![];
    let (mut gyro, mut accel) = (vec![], vec![]);
    for (k, (a, w)) in data.iter().enumerate() {
        t.push(k as f64 * H);
        gyro.extend_from_slice(w.as_slice());
        accel.extend_from_slice(a.as_slice());
    }
    t.push(N as f64 * H);
    gyro.extend_from_slice(&[0.0; 3]);
    accel.extend_from_slice(&[0.0; 3]);
    let x0 = NavState {
        position: Vector3::zeros(),
        velocity: Vector3::zeros(),
        rotation: UnitQuaternion::identity(),
    };
    let options = Options {
        scheme: Scheme::LieEuler,
        gravity: Vector3::zeros(),
        ..Options::default()
    };
    let samples = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let x = integrate(&samples, &x0, &Bias::default(), &options, None).unwrap();
    assert!((x.position - p.delta_position).amax() < 1e-12);
    assert!((x.velocity - p.delta_velocity).amax() < 1e-12);
    assert!((x.rotation.to_rotation_matrix().matrix() - p.delta_rotation).amax() < 1e-13);
    assert!((p.delta_t - N as f64 * H).abs() < 1e-12);
}

#[test]
fn covariance_matches_monte_carlo() {
    let data = samples();
    let noise = Noise {
        gyro_density: 2e-3,
        accel_density: 2e-2,
        ..Noise::default()
    };
    let nominal = run(Vector3::zeros(), Vector3::zeros(), noise, &data);
    let runs = 2000;
    let mut rng = Normal(0x1234_5678_9ABC_DEF1);
    let mut sample = SMatrix::<f64, 9, 9>::zeros();
    let mut nees = 0.0;
    let inv = nominal.covariance().try_inverse().unwrap();
    for _ in 0..runs {
        let noisy: Vec<_> = data
            .iter()
            .map(|(a, w)| {
                let na = rng.vector() * (noise.accel_density / H.sqrt());
                let ng = rng.vector() * (noise.gyro_density / H.sqrt());
                (a + na, w + ng)
            })
            .collect();
        let p = run(Vector3::zeros(), Vector3::zeros(), Noise::default(), &noisy);
        // error of the nominal relative to the noisy deltas: [Log(ΔR̂ᵀΔR), Δv − Δv̂, Δp − Δp̂]
        let e = chart(&nominal, deltas(&p));
        sample += e * e.transpose();
        nees += (e.transpose() * inv * e)[0];
    }
    sample /= runs as f64;
    let mean_nees = nees / runs as f64;
    // χ² with 9·2000 dof, 99% interval of the mean: 9 ± 2.576 √(18/2000)
    let half_width = 2.576 * (18.0f64 / runs as f64).sqrt();
    assert!((mean_nees - 9.0).abs() < half_width, "mean NEES {mean_nees}");
    let rel = (sample - nominal.covariance()).norm() / nominal.covariance().norm();
    assert!(rel < 0.1, "relative Frobenius error {rel}");
    assert!((sample - nominal.covariance() * 2.0).norm() / (nominal.covariance().norm() * 2.0) > 0.1);
}

#[test]
fn block_covariance_update_equals_the_dense_reference() {
    let noise = Noise {
        gyro_density: 2e-3,
        accel_density: 2e-2,
        ..Noise::default()
    };
    let bias = (Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.2));
    let mut p = Preintegrator::new(bias.0, bias.1, noise);
    let mut dense = SMatrix::<f64, 9, 9>::zeros();
    for (k, (a, w)) in samples().iter().enumerate() {
        let h = H * (1.0 + 0.3 * (k as f64).sin()); // uneven steps
        let m = p.step_matrices(a, w, h);
        let var_a = noise.accel_density * noise.accel_density / h;
        let var_g = noise.gyro_density * noise.gyro_density / h;
        dense = m.a * dense * m.a.transpose() + m.b * m.b.transpose() * var_a + m.c * m.c.transpose() * var_g;
        p.integrate_measurement(a, w, h);
    }
    let err = (p.covariance() - dense).amax() / dense.amax();
    assert!(err < 1e-12, "relative error {err:e}");
    assert_eq!(p.covariance(), p.covariance().transpose());
}

/// The combined 15×15 covariance: dense `F Σ Fᵀ + G Q Gᵀ` with `F = [[A, G_b], [0, I]]`.
#[test]
fn combined_covariance_equals_the_dense_reference() {
    let noise = Noise {
        gyro_density: 2e-3,
        accel_density: 2e-2,
        gyro_random_walk: 1e-3,
        accel_random_walk: 1e-2,
    };
    let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise).with_bias_walk();
    let mut dense = SMatrix::<f64, 15, 15>::zeros();
    for (k, (a, w)) in samples().iter().enumerate() {
        let h = H * (1.0 + 0.3 * (k as f64).sin());
        let m = p.step_matrices(a, w, h);
        let mut f = SMatrix::<f64, 15, 15>::identity();
        f.fixed_view_mut::<9, 9>(0, 0).copy_from(&m.a);
        // G_b: θ ← −J_r h δb_g (= −C), v ← −ΔR h δb_a, p ← −½ ΔR h² δb_a (= −B)
        f.fixed_view_mut::<9, 3>(0, 9).copy_from(&(-m.c));
        f.fixed_view_mut::<9, 3>(0, 12).copy_from(&(-m.b));
        let mut g = SMatrix::<f64, 15, 12>::zeros();
        g.fixed_view_mut::<9, 3>(0, 0).copy_from(&m.c);
        g.fixed_view_mut::<9, 3>(0, 3).copy_from(&m.b);
        g.fixed_view_mut::<3, 3>(9, 6).copy_from(&Matrix3::identity());
        g.fixed_view_mut::<3, 3>(12, 9).copy_from(&Matrix3::identity());
        let q = [
            noise.gyro_density.powi(2) / h,
            noise.accel_density.powi(2) / h,
            noise.gyro_random_walk.powi(2) * h,
            noise.accel_random_walk.powi(2) * h,
        ];
        let q = SMatrix::<f64, 12, 12>::from_diagonal(&SVector::<f64, 12>::from_fn(|i, _| q[i / 3]));
        dense = f * dense * f.transpose() + g * q * g.transpose();
        p.integrate_measurement(a, w, h);
    }
    let combined = p.covariance_combined().unwrap();
    let err = (combined - dense).amax() / dense.amax();
    assert!(err < 1e-12, "relative error {err:e}");
    assert_eq!(combined, combined.transpose());
    assert_eq!(combined.fixed_view::<9, 9>(0, 0), p.covariance());
    // and the bias terms matter: the 9×9 part differs from the walk-free covariance
    let plain = run(Vector3::zeros(), Vector3::zeros(), noise, &[]).covariance();
    assert_eq!(plain, SMatrix::<f64, 9, 9>::zeros());
    assert!(Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise)
        .covariance_combined()
        .is_none());
}

#[test]
fn combined_covariance_matches_monte_carlo_with_bias_random_walk() {
    let data = samples();
    let noise = Noise {
        gyro_density: 2e-3,
        accel_density: 2e-2,
        gyro_random_walk: 2e-2,
        accel_random_walk: 2e-1,
    };
    let truth = run(Vector3::zeros(), Vector3::zeros(), Noise::default(), &data);
    let mut nominal = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise).with_bias_walk();
    for (a, w) in &data {
        nominal.integrate_measurement(a, w, H);
    }
    let p15 = nominal.covariance_combined().unwrap();
    let inv = p15.try_inverse().unwrap();
    let runs = 2000;
    let mut rng = Normal(0x0DDB_1A5E_5BAD_5EED);
    let (mut sample, mut nees) = (SMatrix::<f64, 15, 15>::zeros(), 0.0);
    for _ in 0..runs {
        let (mut bg, mut ba) = (Vector3::zeros(), Vector3::zeros());
        let mut noisy = Vec::with_capacity(N);
        for (a, w) in &data {
            noisy.push((
                a + ba + rng.vector() * (noise.accel_density / H.sqrt()),
                w + bg + rng.vector() * (noise.gyro_density / H.sqrt()),
            ));
            bg += rng.vector() * (noise.gyro_random_walk * H.sqrt());
            ba += rng.vector() * (noise.accel_random_walk * H.sqrt());
        }
        let est = run(Vector3::zeros(), Vector3::zeros(), Noise::default(), &noisy);
        // δx = truth ⊖ estimate, the bias errors being the true biases at j (estimate: 0)
        let mut e = SVector::<f64, 15>::zeros();
        e.fixed_rows_mut::<9>(0).copy_from(&chart(&est, deltas(&truth)));
        e.fixed_rows_mut::<3>(9).copy_from(&bg);
        e.fixed_rows_mut::<3>(12).copy_from(&ba);
        sample += e * e.transpose();
        nees += (e.transpose() * inv * e)[0];
    }
    sample /= runs as f64;
    let mean_nees = nees / runs as f64;
    let half_width = 2.576 * (30.0f64 / runs as f64).sqrt(); // χ² with 15·2000 dof, 99%
    assert!((mean_nees - 15.0).abs() < half_width, "mean NEES {mean_nees}");
    let rel = (sample - p15).norm() / p15.norm();
    assert!(rel < 0.1, "relative Frobenius error {rel}");
    // the walk matters: the 9×9 block without it is clearly too small
    let without = run(
        Vector3::zeros(),
        Vector3::zeros(),
        Noise {
            gyro_random_walk: 0.0,
            accel_random_walk: 0.0,
            ..noise
        },
        &data,
    );
    let gap = (sample.fixed_view::<9, 9>(0, 0) - without.covariance()).norm() / without.covariance().norm();
    assert!(gap > 0.1, "bias walk changed the 9×9 block by only {gap}");
}

#[test]
fn merge_equals_one_preintegration_over_both_segments() {
    let data = samples();
    let noise = Noise {
        gyro_density: 2e-3,
        accel_density: 2e-2,
        ..Noise::default()
    };
    let (bg, ba) = (Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.2));
    let whole = run(bg, ba, noise, &data);
    let (first, second) = data.split_at(73);
    let merged = run(bg, ba, noise, first).merge(&run(bg, ba, noise, second)).unwrap();
    assert!((merged.delta_rotation - whole.delta_rotation).amax() < 1e-14);
    assert!((merged.delta_velocity - whole.delta_velocity).amax() < 1e-13);
    assert!((merged.delta_position - whole.delta_position).amax() < 1e-13);
    assert!((merged.delta_t - whole.delta_t).abs() < 1e-15);
    let cov_err = (merged.covariance() - whole.covariance()).amax() / whole.covariance().amax();
    assert!(cov_err < 1e-12, "covariance off by {cov_err:e}");
    let jac_err = (merged.bias_jacobian() - whole.bias_jacobian()).amax() / whole.bias_jacobian().amax();
    assert!(jac_err < 1e-12, "bias Jacobian off by {jac_err:e}");
    // different biases do not merge
    assert!(run(bg, ba, noise, first).merge(&run(ba, bg, noise, second)).is_err());
}
