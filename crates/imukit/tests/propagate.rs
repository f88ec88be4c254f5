//! Error-state propagation: F_x and F_i against central differences of the discrete step, the
//! block-structured covariance update against the dense product, and the closed-form Γ₂.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::imu::{Bias, NavState, Noise, Samples};
use imukit::propagate::{impulse_covariance, propagate, step_jacobians, Covariance, Outputs};
use imukit::so3;
use imukit::strapdown::{Options, Scheme};
use imukit_testing::numeric_jacobian;
use nalgebra::{Matrix3, SVector, UnitQuaternion, Vector3};

const G: Vector3<f64> = Vector3::new(0.0, 0.0, -9.81);

/// Full state with biases, for perturbation.
#[derive(Clone, Copy)]
struct Full {
    p: Vector3<f64>,
    v: Vector3<f64>,
    r: UnitQuaternion<f64>,
    ba: Vector3<f64>,
    bg: Vector3<f64>,
}

/// The discrete first-order step with impulses i = [v_i, θ_i, a_i, ω_i], written here from its
/// definition (module docs of `propagate`), independently of the library's stepper.
fn step(x: &Full, wm: &Vector3<f64>, am: &Vector3<f64>, h: f64, i: &SVector<f64, 12>) -> Full {
    let a_hat = am - x.ba;
    let w_hat = wm - x.bg;
    let acc = x.r * a_hat + G;
    let vi = i.fixed_rows::<3>(0).into_owned();
    let thi = i.fixed_rows::<3>(3).into_owned();
    Full {
        p: x.p + x.v * h + acc * (0.5 * h * h),
        v: x.v + acc * h + vi,
        r: x.r * UnitQuaternion::from_rotation_matrix(&so3::exp(&(w_hat * h + thi))),
        ba: x.ba + i.fixed_rows::<3>(6).into_owned(),
        bg: x.bg + i.fixed_rows::<3>(9).into_owned(),
    }
}

/// `x ⊕ δx` with the right (local) rotation perturbation.
fn plus(x: &Full, d: &SVector<f64, 15>) -> Full {
    let v3 = |k: usize| d.fixed_rows::<3>(3 * k).into_owned();
    Full {
        p: x.p + v3(0),
        v: x.v + v3(1),
        r: x.r * UnitQuaternion::from_rotation_matrix(&so3::exp(&v3(2))),
        ba: x.ba + v3(3),
        bg: x.bg + v3(4),
    }
}

/// `y ⊖ x`.
fn minus(y: &Full, x: &Full) -> SVector<f64, 15> {
    let mut d = SVector::<f64, 15>::zeros();
    d.fixed_rows_mut::<3>(0).copy_from(&(y.p - x.p));
    d.fixed_rows_mut::<3>(3).copy_from(&(y.v - x.v));
    d.fixed_rows_mut::<3>(6)
        .copy_from(&so3::log(&(x.r.inverse() * y.r).to_rotation_matrix()));
    d.fixed_rows_mut::<3>(9).copy_from(&(y.ba - x.ba));
    d.fixed_rows_mut::<3>(12).copy_from(&(y.bg - x.bg));
    d
}

fn cases() -> Vec<(Full, Vector3<f64>, Vector3<f64>, f64)> {
    let mk = |rv: [f64; 3], w: [f64; 3], a: [f64; 3], h: f64| {
        (
            Full {
                p: Vector3::new(1.0, -2.0, 0.5),
                v: Vector3::new(0.3, 0.1, -0.2),
                r: UnitQuaternion::from_scaled_axis(Vector3::from(rv)),
                ba: Vector3::new(0.02, -0.01, 0.03),
                bg: Vector3::new(0.001, 0.002, -0.003),
            },
            Vector3::from(w),
            Vector3::from(a),
            h,
        )
    };
    vec![
        mk([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 9.81], 0.005),
        mk([0.3, -0.4, 1.2], [0.5, -1.1, 2.0], [1.0, -0.5, 9.5], 0.005),
        mk([3.0, 0.5, -0.2], [3.0, 2.0, -4.0], [-3.0, 4.0, 7.0], 0.05),
    ]
}

fn state(x: &Full) -> NavState {
    NavState {
        position: x.p,
        velocity: x.v,
        rotation: x.r,
    }
}

#[test]
fn f_x_and_f_i_match_central_differences() {
    for (x, wm, am, h) in cases() {
        let zero_i = SVector::<f64, 12>::zeros();
        let nominal = step(&x, &wm, &am, h, &zero_i);
        let num_fx = numeric_jacobian(
            |d: &SVector<f64, 15>| minus(&step(&plus(&x, d), &wm, &am, h, &zero_i), &nominal),
            &SVector::zeros(),
        );
        let num_fi = numeric_jacobian(
            |i: &SVector<f64, 12>| minus(&step(&x, &wm, &am, h, i), &nominal),
            &SVector::zeros(),
        );
        let j = step_jacobians(&state(&x), &(wm - x.bg), &(am - x.ba), h);
        let err_x = (j.f_x - num_fx).amax();
        let err_i = (j.f_i - num_fi).amax();
        assert!(err_x < 1e-8, "F_x off by {err_x:e} at h = {h}\n{}\n{}", j.f_x, num_fx);
        assert!(err_i < 1e-8, "F_i off by {err_i:e}");
        // and the comparison is sensitive: Solà's approximation (I instead of J_r, no h² terms)
        // differs by more than the tolerance at the larger steps
        if h > 0.01 {
            let mut approx = j.f_x;
            approx.fixed_view_mut::<3, 3>(0, 6).fill(0.0);
            assert!((approx - num_fx).amax() > 1e-4);
        }
    }
}

#[test]
fn block_propagation_equals_the_dense_product() {
    let noise = Noise {
        gyro_density: 1.7e-4,
        accel_density: 2e-3,
        gyro_random_walk: 1.9e-5,
        accel_random_walk: 3e-3,
    };
    // A random symmetric positive-definite start.
    let l = Covariance::from_fn(|i, j| ((i * 7 + j * 13) % 11) as f64 * 0.01 + if i == j { 0.5 } else { 0.0 });
    let p0 = l * l.transpose();
    let (x, wm, am, h) = cases()[1];
    let t = [0.0, h];
    let gyro = [wm.x, wm.y, wm.z, wm.x, wm.y, wm.z];
    let accel = [am.x, am.y, am.z, am.x, am.y, am.z];
    let samples = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let bias = Bias {
        gyro: x.bg,
        accel: x.ba,
    };
    let options = Options {
        scheme: Scheme::LieEuler,
        gravity: G,
        ..Options::default()
    };
    let mut covs = vec![[0.0; 225]; 2];
    let outputs = Outputs {
        states: None,
        covariances: &mut covs,
        every: 1,
    };
    let (_, p1) = propagate(&samples, &state(&x), &p0, &bias, &noise, &options, outputs).unwrap();
    let j = step_jacobians(&state(&x), &(wm - x.bg), &(am - x.ba), h);
    let dense = j.f_x * p0 * j.f_x.transpose() + j.f_i * impulse_covariance(&noise, h) * j.f_i.transpose();
    assert!((p1 - dense).amax() < 1e-14 * dense.amax(), "{:e}", (p1 - dense).amax());
    assert_eq!(p1, p1.transpose());
    assert_eq!(
        covs[1].as_slice(),
        Covariance::from_row_slice(&covs[1]).transpose().as_slice()
    );
}

#[test]
fn exp_double_integral_matches_quadrature() {
    for phi in [
        Vector3::new(1e-7, 0.0, 0.0),
        Vector3::new(0.1, -0.05, 0.02),
        Vector3::new(1.0, 2.0, -0.5),
    ] {
        // Simpson's rule on ∫₀¹ (1 − s) Exp(s φ) ds with 2000 intervals.
        let n = 2000;
        let mut acc = Matrix3::zeros();
        for k in 0..=n {
            let s = k as f64 / n as f64;
            let w = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            acc += so3::exp(&(phi * s)).matrix() * ((1.0 - s) * w);
        }
        acc /= 3.0 * n as f64;
        let err = (so3::exp_double_integral(&phi) - acc).amax();
        assert!(err < 1e-12, "{phi}: {err:e}");
    }
}
