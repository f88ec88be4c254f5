//! Property tests of `imukit::so3`: exp/log, the four Jacobians of Exp, the adjoint, hat/vee.
//!
//! Every property runs in the four regimes of `imukit_testing::REGIMES` (identity, θ ≈ 1e-8,
//! θ ≈ π − 1e-6, random) and, where a closed form switches to a Taylor series, at angles next to
//! the switch points (`series_switch_vector`), where a wrong or missing series term is largest.
//!
//! Tolerances. Measured worst cases over 20 000 draws per regime (debug build, this code):
//! log∘exp relative error 7e-16, RᵀR − I 2.3e-15, det − 1 2.2e-15, analytic Jacobians against
//! their defining series 2e-15, central differences against analytic Jacobians 2.2e-10. The
//! tolerances below sit 5–20× above those: tight enough that a wrong sign, a 1/6 for a 1/12, a
//! relative error of 1e-9 in a closed-form coefficient or a dropped series term up to θ⁶ fails
//! (each checked by mutating the source). The last term of each long series (≈ 1e-13 at its
//! switch point, ≈ 3e-15 in the Jacobian) is below these tolerances; the unit test in so3.rs
//! checks the coefficients themselves against 50-digit values.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![allow(missing_docs)]

use std::f64::consts::{PI, TAU};

use imukit::so3;
use imukit_testing::{
    check, check_rotation_vectors, identity3, log_near, max_abs_diff, numeric_jacobian, perpendicular, random_rotation,
    rotation_distance, rotation_vector, series_left_jacobian, small_vector, unit_vector, vector3, Regime,
};
use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;

const CASES: u32 = 256;

/// Relative accuracy of exp/log round trips (measured 7e-16).
const ROUND_TRIP_REL: f64 = 1e-14;
/// Absolute accuracy of rotation matrices and O(1) Jacobians (measured 2–3e-15).
const MATRIX_ABS: f64 = 1e-14;
/// Central differences with step 6e-6: truncation ~h²‖f‴‖/6 ≈ 1e-11, rounding ~ε/h ≈ 4e-11
/// (measured 2.2e-10 worst case). A coefficient error that moves a Jacobian entry by 1e-8 fails.
const CENTRAL_DIFF: f64 = 5e-9;

fn jl_inv_reference(phi: &Vector3<f64>) -> Matrix3<f64> {
    // J_l is well conditioned for θ ≤ π (singular values 1 and sin(θ/2)/(θ/2) ≥ 2/π).
    series_left_jacobian(phi)
        .try_inverse()
        .expect("J_l is invertible for θ ≤ π")
}

// ---------------------------------------------------------------------------------------------
// exp / log
// ---------------------------------------------------------------------------------------------

#[test]
fn log_inverts_exp() {
    check_rotation_vectors(CASES, |phi| {
        let back = so3::log(&so3::exp(&phi));
        let theta = phi.norm();
        if theta == 0.0 {
            prop_assert_eq!(back, Vector3::zeros());
        } else {
            // Relative, so that θ ≈ 1e-8 is checked to full precision too (an absolute 1e-14
            // would accept a log that returned 0 there). All regimes stay below π, so no sign flip.
            let err = (back - phi).norm();
            prop_assert!(
                err <= ROUND_TRIP_REL * theta,
                "θ = {theta:e}: log(exp(φ)) − φ = {err:e}"
            );
        }
        Ok(())
    });
}

#[test]
fn log_at_and_beyond_pi() {
    // At θ = π exactly, φ and −φ are the same rotation: either is a correct log. Beyond π, log
    // returns the equivalent vector with angle 2π − θ about −u. Within 1e-9 of π both signs are
    // accepted (the sign of the axis is then decided by rounding of entries ≈ 1e-9).
    let strategy = (unit_vector(), -1e-3..1e-3f64);
    check("around π", CASES, strategy, |(u, offset)| {
        let theta = PI + offset;
        let phi = u * theta;
        let back = so3::log(&so3::exp(&phi));
        prop_assert!(back.norm() <= PI + 1e-15, "|log| = {} > π", back.norm());
        let expected = if theta <= PI { phi } else { phi - u * TAU };
        let err = if (theta - PI).abs() <= 1e-9 {
            (back - expected).norm().min((back + expected).norm())
        } else {
            (back - expected).norm()
        };
        prop_assert!(
            err <= 1e-12,
            "θ = π + {offset:e}: log = {back}, expected ±{expected}, error {err:e}"
        );
        Ok(())
    });
    for axis in [
        Vector3::x(),
        Vector3::y(),
        Vector3::z(),
        Vector3::new(1.0, -2.0, 3.0).normalize(),
    ] {
        let back = so3::log(&so3::exp(&(axis * PI)));
        let err = (back - axis * PI).norm().min((back + axis * PI).norm());
        assert!(err <= 1e-14, "log(exp(π {axis})) = {back}");
    }
}

#[test]
fn exp_inverts_log_on_any_rotation() {
    // R from nalgebra (not from so3::exp), so that a shared mistake in exp and log cannot cancel.
    check("random rotation", CASES, random_rotation(), |r| {
        let phi = so3::log(&r);
        prop_assert!(phi.norm() <= PI);
        let err = max_abs_diff(so3::exp(&phi).matrix(), r.matrix());
        prop_assert!(err <= MATRIX_ABS, "exp(log R) − R = {err:e}");
        Ok(())
    });
    check_rotation_vectors(CASES, |phi| {
        let r = so3::exp(&phi);
        let err = max_abs_diff(so3::exp(&so3::log(&r)).matrix(), r.matrix());
        prop_assert!(err <= MATRIX_ABS, "exp(log R) − R = {err:e}");
        Ok(())
    });
}

#[test]
fn exp_is_orthonormal_with_unit_determinant() {
    let check_rot = |phi: Vector3<f64>| {
        let m = *so3::exp(&phi).matrix();
        let orth = max_abs_diff(&(m.transpose() * m), &identity3());
        let det = (m.determinant() - 1.0).abs();
        prop_assert!(
            orth <= MATRIX_ABS && det <= MATRIX_ABS,
            "θ = {}: |RᵀR − I| = {orth:e}, |det − 1| = {det:e}",
            phi.norm()
        );
        Ok(())
    };
    check_rotation_vectors(CASES, check_rot);
    // exp takes any rotation vector, not only the output range of log.
    check("large angles", CASES, (unit_vector(), PI..40.0), |(u, a)| {
        check_rot(u * a)
    });
}

#[test]
fn exp_of_large_angle_wraps() {
    // Exp(θu) = Exp((θ − 2π)u): Rodrigues is periodic in θ.
    check("wrap", CASES, (unit_vector(), PI..30.0), |(u, a)| {
        let d = rotation_distance(&so3::exp(&(u * a)), &so3::exp(&(u * (a - TAU))));
        prop_assert!(d <= 1e-13, "θ = {a}: {d:e}");
        Ok(())
    });
}

#[test]
fn plus_and_minus_are_inverse() {
    let strategy = (random_rotation(), rotation_vector(Regime::Random));
    check("plus/minus", CASES, strategy, |(r, delta)| {
        let back = so3::minus(&so3::plus(&r, &delta), &r);
        prop_assert!((back - delta).norm() <= ROUND_TRIP_REL * delta.norm().max(1.0));
        // Right (local) perturbation: R ⊕ δ = R Exp(δ), not Exp(δ) R.
        let right = r * so3::exp(&delta);
        prop_assert!(rotation_distance(&so3::plus(&r, &delta), &right) <= 1e-15);
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Jacobians of Exp: algebraic identities and their defining series
// ---------------------------------------------------------------------------------------------

#[test]
fn jacobians_match_their_defining_series() {
    // J_l(φ) = Σ [φ]×ᵏ/(k+1)!, J_r(φ) = J_l(−φ), and the inverses are the matrix inverses.
    check_rotation_vectors(CASES, |phi| {
        let cases = [
            ("J_l", so3::left_jacobian(&phi), series_left_jacobian(&phi)),
            ("J_r", so3::right_jacobian(&phi), series_left_jacobian(&-phi)),
            ("J_l⁻¹", so3::left_jacobian_inv(&phi), jl_inv_reference(&phi)),
            ("J_r⁻¹", so3::right_jacobian_inv(&phi), jl_inv_reference(&-phi)),
            (
                "fused J_r",
                so3::exp_and_right_jacobian(&phi).1,
                series_left_jacobian(&-phi),
            ),
            (
                "fused Exp",
                so3::exp_and_right_jacobian(&phi).0,
                *so3::exp(&phi).matrix(),
            ),
        ];
        for (name, analytic, reference) in cases {
            let err = max_abs_diff(&analytic, &reference);
            prop_assert!(
                err <= MATRIX_ABS,
                "{name} at θ = {:e}: error {err:e}\n{analytic}{reference}",
                phi.norm()
            );
        }
        Ok(())
    });
}

#[test]
fn jacobian_identities() {
    check_rotation_vectors(CASES, |phi| {
        let jr = so3::right_jacobian(&phi);
        let jl = so3::left_jacobian(&phi);
        let jr_inv = so3::right_jacobian_inv(&phi);
        let jl_inv = so3::left_jacobian_inv(&phi);
        let r = *so3::exp(&phi).matrix();
        let i = identity3();
        let cases = [
            ("J_r(φ) = J_l(−φ)", jr, so3::left_jacobian(&-phi)),
            ("J_r = J_lᵀ", jr, jl.transpose()),
            ("J_r⁻¹(φ) = J_l⁻¹(−φ)", jr_inv, so3::left_jacobian_inv(&-phi)),
            ("J_r J_r⁻¹ = I", jr * jr_inv, i),
            ("J_r⁻¹ J_r = I", jr_inv * jr, i),
            ("J_l J_l⁻¹ = I", jl * jl_inv, i),
            ("J_l⁻¹ J_l = I", jl_inv * jl, i),
            ("J_l = Exp(φ) J_r", jl, r * jr),
            (
                "J_r φ = φ",
                Matrix3::from_columns(&[jr * phi, phi, phi]),
                Matrix3::from_columns(&[phi, phi, phi]),
            ),
        ];
        for (name, lhs, rhs) in cases {
            let err = max_abs_diff(&lhs, &rhs);
            prop_assert!(err <= MATRIX_ABS, "{name} at θ = {:e}: error {err:e}", phi.norm());
        }
        Ok(())
    });
}

/// Bound on the second-order remainder of the first-order expansions of Exp. Measured over 20 000
/// draws per regime: ≤ 0.16 |δ|² (forward, Exp(φ + δ) vs Exp(φ) Exp(J_r δ)) and ≤ 0.39 |δ|²
/// (inverse, Log(Exp(φ) Exp(δ)) vs φ + J_r⁻¹ δ); 0.5 |δ|² and |δ|² leave ~3× margin and stay
/// ~1e-10, far below the error |ΔJ| |δ| of any wrong Jacobian (e.g. θ/2 · 1e-5 for J = I).
fn second_order(delta: &Vector3<f64>) -> f64 {
    0.5 * delta.norm_squared() + 1e-15
}

#[test]
fn first_order_expansions_of_exp() {
    let strategy = |regime| (rotation_vector(regime), small_vector());
    imukit_testing::check_regimes(CASES, strategy, |regime, (phi, delta)| {
        let exact = so3::exp(&(phi + delta));
        let exp_phi = so3::exp(&phi);
        let right = exp_phi * so3::exp(&(so3::right_jacobian(&phi) * delta));
        let left = so3::exp(&(so3::left_jacobian(&phi) * delta)) * exp_phi;
        let (er, el) = (rotation_distance(&exact, &right), rotation_distance(&exact, &left));
        prop_assert!(er <= second_order(&delta), "{regime:?} right: {er:e}");
        prop_assert!(el <= second_order(&delta), "{regime:?} left: {el:e}");

        let log_right = log_near(&(exp_phi * so3::exp(&delta)), &phi);
        let log_left = log_near(&(so3::exp(&delta) * exp_phi), &phi);
        let eri = (log_right - (phi + so3::right_jacobian_inv(&phi) * delta)).norm();
        let eli = (log_left - (phi + so3::left_jacobian_inv(&phi) * delta)).norm();
        prop_assert!(eri <= 2.0 * second_order(&delta), "{regime:?} right inverse: {eri:e}");
        prop_assert!(eli <= 2.0 * second_order(&delta), "{regime:?} left inverse: {eli:e}");
        Ok(())
    });
}

#[test]
fn first_order_expansion_fails_without_the_jacobian() {
    // The same check with J = I (or with the other side's Jacobian) must fail by orders of
    // magnitude once θ is not small; δ ⊥ φ because J_r φ = φ hides any error along φ.
    let strategy = (unit_vector(), 0.1..PI - 1e-3, 1e-6..1e-5f64);
    check("J = I fails", CASES, strategy, |(u, theta, eps)| {
        let phi = u * theta;
        let delta = perpendicular(&u) * eps;
        let exact = so3::exp(&(phi + delta));
        let exp_phi = so3::exp(&phi);
        let with_jr = rotation_distance(&exact, &(exp_phi * so3::exp(&(so3::right_jacobian(&phi) * delta))));
        let with_i = rotation_distance(&exact, &(exp_phi * so3::exp(&delta)));
        let with_jl = rotation_distance(&exact, &(exp_phi * so3::exp(&(so3::left_jacobian(&phi) * delta))));
        prop_assert!(with_jr <= second_order(&delta));
        // For δ ⊥ φ, |(J_r − I) δ| ≥ |δ| (1 − cos θ)/θ and |(J_l − J_r) δ| = 2 |δ| (1 − cos θ)/θ,
        // both ≥ 0.04 |δ| for θ ≥ 0.1.
        prop_assert!(
            with_i >= 0.04 * eps && with_i >= 100.0 * with_jr,
            "J = I: {with_i:e} vs J_r: {with_jr:e}"
        );
        prop_assert!(
            with_jl >= 0.04 * eps && with_jl >= 100.0 * with_jr,
            "J_l: {with_jl:e} vs J_r: {with_jr:e}"
        );
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Jacobians of Exp against central differences
// ---------------------------------------------------------------------------------------------

#[test]
fn jacobians_match_central_differences() {
    // Near π, Exp(φ) Exp(±h e_k) may have angle > π, where Log jumps to the other branch;
    // log_near unwraps it (Log + 2πk u nearest φ), which is smooth through π.
    check_rotation_vectors(CASES, |phi| {
        let r = so3::exp(&phi);
        let zero = Vector3::zeros();
        let jr = numeric_jacobian(|d| so3::log(&(r.inverse() * so3::exp(&(phi + d)))), &zero);
        let jr_inv = numeric_jacobian(|d| log_near(&(r * so3::exp(d)), &phi), &zero);
        let jl = numeric_jacobian(|d| so3::log(&(so3::exp(&(phi + d)) * r.inverse())), &zero);
        let jl_inv = numeric_jacobian(|d| log_near(&(so3::exp(d) * r), &phi), &zero);
        let cases = [
            ("J_r", jr, so3::right_jacobian(&phi)),
            ("J_r⁻¹", jr_inv, so3::right_jacobian_inv(&phi)),
            ("J_l", jl, so3::left_jacobian(&phi)),
            ("J_l⁻¹", jl_inv, so3::left_jacobian_inv(&phi)),
        ];
        for (name, numeric, analytic) in cases {
            let err = max_abs_diff(&numeric, &analytic);
            prop_assert!(
                err <= CENTRAL_DIFF,
                "{name} at θ = {:e}: error {err:e}\nnumeric{numeric}analytic{analytic}",
                phi.norm()
            );
        }
        Ok(())
    });
}

#[test]
fn jacobians_of_the_group_operations() {
    // Solà, Deray & Atchuthan 2018 (the "manif" paper), eqs. 68, 72, 76-77 and 138: right
    // Jacobians of R v, R⁻¹ and R S, checked by central differences on the right perturbation.
    let strategy = |regime| (rotation_vector(regime), random_rotation(), vector3(10.0));
    imukit_testing::check_regimes(CASES, strategy, |regime, (phi, s, v)| {
        let r = so3::exp(&phi);
        let zero = Vector3::zeros();
        // d(R ⊕ δ) v / dδ = −R [v]×
        let action = numeric_jacobian(|d| so3::plus(&r, d) * v, &zero);
        let err = max_abs_diff(&action, &(-r.matrix() * so3::hat(&v)));
        prop_assert!(err <= CENTRAL_DIFF * v.norm().max(1.0), "{regime:?} action: {err:e}");
        // d(R ⊕ δ)⁻¹ ⊖ R⁻¹ / dδ = −Ad(R) = −R
        let inverse = numeric_jacobian(|d| so3::minus(&so3::plus(&r, d).inverse(), &r.inverse()), &zero);
        let err = max_abs_diff(&inverse, &-so3::adjoint(&r));
        prop_assert!(err <= CENTRAL_DIFF, "{regime:?} inverse: {err:e}");
        // d((R ⊕ δ) S ⊖ R S)/dδ = Sᵀ and d(R (S ⊕ δ) ⊖ R S)/dδ = I
        let rs = r * s;
        let first = numeric_jacobian(|d| so3::minus(&(so3::plus(&r, d) * s), &rs), &zero);
        let second = numeric_jacobian(|d| so3::minus(&(r * so3::plus(&s, d)), &rs), &zero);
        let err1 = max_abs_diff(&first, &s.matrix().transpose());
        let err2 = max_abs_diff(&second, &identity3());
        prop_assert!(
            err1 <= CENTRAL_DIFF && err2 <= CENTRAL_DIFF,
            "{regime:?} compose: {err1:e} {err2:e}"
        );
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Adjoint
// ---------------------------------------------------------------------------------------------

#[test]
fn adjoint_identities() {
    let strategy = |regime| (rotation_vector(regime), random_rotation(), vector3(5.0));
    imukit_testing::check_regimes(CASES, strategy, |regime, (delta, r, a)| {
        let m = *r.matrix();
        prop_assert_eq!(so3::adjoint(&r), m);
        // R [a]× Rᵀ = [R a]×
        let err = max_abs_diff(&(m * so3::hat(&a) * m.transpose()), &so3::hat(&(m * a)));
        prop_assert!(err <= MATRIX_ABS * a.norm().max(1.0), "{regime:?} hat: {err:e}");
        // R Exp(δ) = Exp(R δ) R: a body (right) increment δ is the world (left) increment R δ.
        let lhs = r * so3::exp(&delta);
        let rhs = so3::exp(&(so3::adjoint(&r) * delta)) * r;
        let err = max_abs_diff(lhs.matrix(), rhs.matrix());
        prop_assert!(err <= MATRIX_ABS, "{regime:?} Exp(Rδ) R: {err:e}");
        // And not Exp(Rᵀ δ) R (a transposed adjoint): the two differ by about |R δ − Rᵀ δ| while
        // |δ| < 2 keeps Exp one-to-one with bounded distortion (skipped when δ ∥ axis or tiny).
        let wrong = so3::exp(&(m.transpose() * delta)) * r;
        let gap = ((m - m.transpose()) * delta).norm();
        if gap > 1e-3 && delta.norm() < 2.0 {
            let d = rotation_distance(&lhs, &wrong);
            prop_assert!(
                d > 0.1 * gap,
                "{regime:?} transposed adjoint undetected: {d:e} vs {gap:e}"
            );
        }
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// hat / vee
// ---------------------------------------------------------------------------------------------

#[test]
fn hat_and_vee() {
    check("hat/vee", CASES, (vector3(100.0), vector3(100.0)), |(a, v)| {
        let k = so3::hat(&a);
        prop_assert_eq!(so3::vee(&k), a);
        prop_assert_eq!(k.transpose(), -k);
        // [a]× v = a × v (a sign or index error in hat fails by O(|a||v|)).
        let err = (k * v - a.cross(&v)).norm();
        prop_assert!(err <= 1e-15 * a.norm() * v.norm() * 4.0, "{err:e}");
        Ok(())
    });
    assert_eq!(
        so3::hat(&Vector3::new(1.0, 2.0, 3.0)),
        Matrix3::new(0.0, -3.0, 2.0, 3.0, 0.0, -1.0, -2.0, 1.0, 0.0)
    );
}

#[test]
fn vee_of_a_general_matrix_is_the_vector_of_its_skew_part() {
    let entries = proptest::array::uniform9(-10.0..10.0f64);
    check("vee of any matrix", CASES, (entries, vector3(10.0)), |(e, a)| {
        let m = Matrix3::from_row_slice(&e);
        let skew = (m - m.transpose()) * 0.5;
        let err = (so3::vee(&m) - so3::vee(&skew)).norm();
        prop_assert!(err <= 1e-14, "{err:e}");
        // Adding a symmetric matrix changes nothing.
        let symmetric = m + m.transpose();
        let err = (so3::vee(&(symmetric + so3::hat(&a))) - a).norm();
        prop_assert!(err <= 1e-13, "{err:e}");
        Ok(())
    });
    let m = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
    // skew part [[0, -1, -2], [1, 0, -1], [2, 1, 0]] = hat([1, -2, 1])
    assert_eq!(so3::vee(&m), Vector3::new(1.0, -2.0, 1.0));
}

#[test]
fn exp_matches_rotation_about_the_axis() {
    // Independent of every other test: nalgebra's axis-angle constructor, active convention.
    check("axis-angle", CASES, (unit_vector(), 0.0..PI), |(u, a)| {
        let reference = Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(u), a);
        let err = max_abs_diff(so3::exp(&(u * a)).matrix(), reference.matrix());
        prop_assert!(err <= MATRIX_ABS, "{err:e}");
        Ok(())
    });
    // Quarter turn about z: x ↦ y (active).
    let r = so3::exp(&Vector3::new(0.0, 0.0, PI / 2.0));
    assert!((r * Vector3::x() - Vector3::y()).norm() < 1e-15);
}
