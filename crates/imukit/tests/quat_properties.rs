//! Property tests of `imukit::quat`: Hamilton and JPL products, product matrices, Ω(ω),
//! quaternion kinematics, conjugate/inverse/normalize, exp/log and rotation of vectors.
//!
//! Layout reminder: nalgebra's `Quaternion::new(w, x, y, z)` stores `coords = [x, y, z, w]`, and
//! every 4×4 matrix of `imukit::quat` acts on that `[x, y, z, w]` column.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![allow(missing_docs)]

use std::f64::consts::{PI, TAU};

use imukit::{quat, so3, Error};
use imukit_testing::{
    any_quaternion, check, check_rotation_vectors, max_abs_diff, numeric_jacobian, random_rotation, unit_vector,
    vector3,
};
use nalgebra::{Matrix4, Quaternion, Rotation3, UnitQuaternion, Vector1, Vector3, Vector4};
use proptest::prelude::*;

const CASES: u32 = 256;

/// Products of quaternions with norms up to ~3.5: a few ulp of |q||p| ≤ 12.
const PRODUCT_TOL: f64 = 1e-14;

fn unit_quaternion() -> BoxedStrategy<UnitQuaternion<f64>> {
    random_rotation()
        .prop_map(|r| UnitQuaternion::from_rotation_matrix(&r))
        .boxed()
}

/// Hamilton product written out component by component (Solà 2017, eq. 12), `i j = k`.
fn hamilton_by_hand(q: &Quaternion<f64>, p: &Quaternion<f64>) -> Quaternion<f64> {
    let (qw, qx, qy, qz) = (q.w, q.i, q.j, q.k);
    let (pw, px, py, pz) = (p.w, p.i, p.j, p.k);
    Quaternion::new(
        qw * pw - qx * px - qy * py - qz * pz,
        qw * px + qx * pw + qy * pz - qz * py,
        qw * py - qx * pz + qy * pw + qz * px,
        qw * pz + qx * py - qy * px + qz * pw,
    )
}

fn diff(a: &Quaternion<f64>, b: &Quaternion<f64>) -> f64 {
    (a.coords - b.coords).abs().max()
}

// ---------------------------------------------------------------------------------------------
// products
// ---------------------------------------------------------------------------------------------

#[test]
fn hamilton_basis_products() {
    let one = Quaternion::new(1.0, 0.0, 0.0, 0.0);
    let i = Quaternion::new(0.0, 1.0, 0.0, 0.0);
    let j = Quaternion::new(0.0, 0.0, 1.0, 0.0);
    let k = Quaternion::new(0.0, 0.0, 0.0, 1.0);
    assert_eq!(quat::multiply(&i, &j), k);
    assert_eq!(quat::multiply(&j, &k), i);
    assert_eq!(quat::multiply(&k, &i), j);
    assert_eq!(quat::multiply(&j, &i), -k);
    assert_eq!(quat::multiply(&i, &i), -one);
    assert_eq!(quat::multiply(&quat::multiply(&i, &j), &k), -one);
    // JPL: i j = −k (Trawny & Roumeliotis 2005, eq. 8).
    assert_eq!(quat::multiply_jpl(&i, &j), -k);
    assert_eq!(quat::multiply_jpl(&j, &k), -i);
    assert_eq!(quat::multiply_jpl(&i, &i), -one);
}

#[test]
fn hamilton_product_matches_the_component_formula() {
    check("q ⊗ p", CASES, (any_quaternion(), any_quaternion()), |(q, p)| {
        let err = diff(&quat::multiply(&q, &p), &hamilton_by_hand(&q, &p));
        prop_assert!(err <= PRODUCT_TOL, "{err:e}");
        // |q ⊗ p| = |q| |p|
        let n = quat::multiply(&q, &p).norm();
        prop_assert!((n - q.norm() * p.norm()).abs() <= PRODUCT_TOL);
        Ok(())
    });
}

#[test]
fn hamilton_product_composes_rotations() {
    // rotation(q ⊗ p) = rotation(q) rotation(p): Hamilton with active rotations composes in the
    // same order as matrices. The rotations come from nalgebra's matrices, not from quaternions.
    check(
        "composition",
        CASES,
        (random_rotation(), random_rotation()),
        |(rq, rp)| {
            let q = UnitQuaternion::from_rotation_matrix(&rq);
            let p = UnitQuaternion::from_rotation_matrix(&rp);
            let product = UnitQuaternion::new_normalize(quat::multiply(q.quaternion(), p.quaternion()));
            let err = max_abs_diff(product.to_rotation_matrix().matrix(), &(rq.matrix() * rp.matrix()));
            prop_assert!(err <= 1e-14, "{err:e}");
            // The JPL product composes the other way round.
            let jpl = UnitQuaternion::new_normalize(quat::multiply_jpl(q.quaternion(), p.quaternion()));
            let err = max_abs_diff(jpl.to_rotation_matrix().matrix(), &(rp.matrix() * rq.matrix()));
            prop_assert!(err <= 1e-14, "{err:e}");
            Ok(())
        },
    );
}

#[test]
fn product_matrices() {
    check(
        "L, R",
        CASES,
        (any_quaternion(), any_quaternion(), any_quaternion()),
        |(q, p, r)| {
            let qp = quat::multiply(&q, &p).coords;
            let err_l = (quat::left_matrix(&q) * p.coords - qp).abs().max();
            let err_r = (quat::right_matrix(&p) * q.coords - qp).abs().max();
            prop_assert!(
                err_l <= PRODUCT_TOL && err_r <= PRODUCT_TOL,
                "L: {err_l:e}, R: {err_r:e}"
            );
            // L(q ⊗ p) = L(q) L(p), R(q ⊗ p) = R(p) R(q), and L(q) R(r) = R(r) L(q) (associativity).
            let qp = quat::multiply(&q, &p);
            let tol = 1e-13;
            prop_assert!(
                max_abs_diff(
                    &quat::left_matrix(&qp),
                    &(quat::left_matrix(&q) * quat::left_matrix(&p))
                ) <= tol
            );
            prop_assert!(
                max_abs_diff(
                    &quat::right_matrix(&qp),
                    &(quat::right_matrix(&p) * quat::right_matrix(&q))
                ) <= tol
            );
            let lr = quat::left_matrix(&q) * quat::right_matrix(&r);
            prop_assert!(max_abs_diff(&lr, &(quat::right_matrix(&r) * quat::left_matrix(&q))) <= tol);
            // L(q*) = L(q)ᵀ, R(q*) = R(q)ᵀ
            let qc = quat::conjugate(&q);
            prop_assert_eq!(quat::left_matrix(&qc), quat::left_matrix(&q).transpose());
            prop_assert_eq!(quat::right_matrix(&qc), quat::right_matrix(&q).transpose());
            Ok(())
        },
    );
}

#[test]
fn jpl_products_and_matrices() {
    check("JPL", CASES, (any_quaternion(), any_quaternion()), |(q, p)| {
        // q ⊗_J p = p ⊗_H q, component-wise.
        let jpl = quat::multiply_jpl(&q, &p);
        prop_assert_eq!(jpl, quat::multiply(&p, &q));
        // L_J = R_H, R_J = L_H, and they do what their names say.
        prop_assert_eq!(quat::left_matrix_jpl(&q), quat::right_matrix(&q));
        prop_assert_eq!(quat::right_matrix_jpl(&q), quat::left_matrix(&q));
        let err_l = (quat::left_matrix_jpl(&q) * p.coords - jpl.coords).abs().max();
        let err_r = (quat::right_matrix_jpl(&p) * q.coords - jpl.coords).abs().max();
        prop_assert!(err_l <= PRODUCT_TOL && err_r <= PRODUCT_TOL, "{err_l:e} {err_r:e}");
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// Ω(ω) and kinematics
// ---------------------------------------------------------------------------------------------

#[test]
fn omega_matrix_element_by_element() {
    check("Ω", CASES, vector3(10.0), |w| {
        let (x, y, z) = (w.x, w.y, w.z);
        // [[−[ω]×, ω], [−ωᵀ, 0]] on [x, y, z, w], written out (no hat):
        #[rustfmt::skip]
        let expected = Matrix4::new(
             0.0,   z,  -y,   x,
              -z, 0.0,   x,   y,
               y,  -x, 0.0,   z,
              -x,  -y,  -z, 0.0,
        );
        prop_assert_eq!(quat::omega_matrix(&w), expected);
        prop_assert_eq!(quat::omega_matrix_jpl(&w), expected);
        // Ω is skew and squares to −|ω|² I.
        let err = max_abs_diff(&(expected * expected), &(-Matrix4::identity() * w.norm_squared()));
        prop_assert!(err <= 1e-13, "{err:e}");
        Ok(())
    });
}

#[test]
fn quaternion_derivative_is_half_omega_q() {
    // q(t) = q ⊗ Exp(ω t) (body rate, right-multiplied): dq/dt at 0 = ½ Ω(ω) q = ½ q ⊗ [ω, 0].
    // Central differences in t: truncation h² |ω|³/48, rounding ε/h ≈ 2e-11.
    check("q̇", CASES, (unit_quaternion(), vector3(5.0)), |(q, w)| {
        let q = *q.quaternion();
        let numeric = numeric_jacobian(
            |t: &Vector1<f64>| quat::multiply(&q, quat::exp(&(w * t.x)).quaternion()).coords,
            &Vector1::zeros(),
        );
        let analytic = quat::omega_matrix(&w) * q.coords * 0.5;
        let err = (numeric.column(0) - analytic).abs().max();
        prop_assert!(err <= 1e-9, "{err:e}");
        let half_product = quat::multiply(&q, &quat::pure(&w)).coords * 0.5;
        prop_assert!((half_product - analytic).abs().max() <= 1e-14);
        Ok(())
    });
}

#[test]
fn integrating_half_omega_q_gives_right_multiplied_exp() {
    // RK4 on q̇ = ½ Ω(ω) q from q0 reaches q0 ⊗ Exp(ω t) (not Exp(ω t) ⊗ q0).
    check(
        "∫ q̇",
        32,
        (unit_quaternion(), vector3(3.0), 0.2..2.0f64),
        |(q0, w, t)| {
            let omega = quat::omega_matrix(&w) * 0.5;
            let steps = 2000;
            let h = t / f64::from(steps);
            let mut q: Vector4<f64> = q0.coords;
            for _ in 0..steps {
                let k1 = omega * q;
                let k2 = omega * (q + k1 * (h / 2.0));
                let k3 = omega * (q + k2 * (h / 2.0));
                let k4 = omega * (q + k3 * h);
                q += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
            }
            let expected = quat::multiply(q0.quaternion(), quat::exp(&(w * t)).quaternion()).coords;
            let err = (q - expected).abs().max();
            prop_assert!(err <= 1e-10, "{err:e}");
            Ok(())
        },
    );
}

// ---------------------------------------------------------------------------------------------
// conjugate, inverse, normalize
// ---------------------------------------------------------------------------------------------

#[test]
fn conjugate_inverse_normalize() {
    let one = Quaternion::new(1.0, 0.0, 0.0, 0.0);
    check(
        "q*, q⁻¹, q/|q|",
        CASES,
        (any_quaternion(), any_quaternion()),
        |(q, p)| {
            let qc = quat::conjugate(&q);
            prop_assert_eq!(qc, Quaternion::new(q.w, -q.i, -q.j, -q.k));
            prop_assert_eq!(quat::conjugate(&qc), q);
            // q ⊗ q* = |q|² (a real number)
            let n2 = quat::multiply(&q, &qc);
            prop_assert!(diff(&n2, &Quaternion::new(q.norm_squared(), 0.0, 0.0, 0.0)) <= PRODUCT_TOL);
            // (q ⊗ p)* = p* ⊗ q*
            let lhs = quat::conjugate(&quat::multiply(&q, &p));
            let rhs = quat::multiply(&quat::conjugate(&p), &qc);
            prop_assert!(diff(&lhs, &rhs) <= PRODUCT_TOL);
            // q ⊗ q⁻¹ = q⁻¹ ⊗ q = 1 (norms from 0.1: |q⁻¹| ≤ 10)
            let inv = quat::inverse(&q).unwrap();
            prop_assert!(diff(&quat::multiply(&q, &inv), &one) <= 1e-14);
            prop_assert!(diff(&quat::multiply(&inv, &q), &one) <= 1e-14);
            // normalize: unit norm, same direction, same rotation for q and −q.
            let u = quat::normalize(&q).unwrap();
            prop_assert!((u.norm() - 1.0).abs() <= 2e-16 * 4.0);
            prop_assert!(diff(u.quaternion(), &(q / q.norm())) <= 1e-15);
            let un = quat::normalize(&-q).unwrap();
            let err = max_abs_diff(u.to_rotation_matrix().matrix(), un.to_rotation_matrix().matrix());
            prop_assert!(err <= 1e-15);
            // For a unit quaternion the inverse is the conjugate.
            let inv_u = quat::inverse(u.quaternion()).unwrap();
            prop_assert!(diff(&inv_u, &quat::conjugate(u.quaternion())) <= 1e-15);
            Ok(())
        },
    );
}

#[test]
fn zero_quaternion_is_refused() {
    let zero = Quaternion::new(0.0, 0.0, 0.0, 0.0);
    let expected = Error::ZeroQuaternion { index: 0, norm: 0.0 };
    assert_eq!(quat::inverse(&zero), Err(expected.clone()));
    assert_eq!(quat::normalize(&zero).map(|q| q.into_inner()), Err(expected.clone()));
    assert_eq!(quat::rotate(&zero, &Vector3::x()), Err(expected));
    // Below the threshold it is zero as well; the error reports the norm.
    let tiny = Quaternion::new(0.0, 0.0, 5e-13, 0.0);
    assert_eq!(
        quat::inverse(&tiny),
        Err(Error::ZeroQuaternion { index: 0, norm: 5e-13 })
    );
    assert!(matches!(quat::normalize(&tiny), Err(Error::ZeroQuaternion { .. })));
    // Just above it, the result is valid.
    const { assert!(quat::ZERO_NORM <= 1e-11) };
    let small = Quaternion::new(0.0, 0.0, 1e-11, 0.0);
    let n = quat::normalize(&small).unwrap();
    assert_eq!(n.into_inner(), Quaternion::new(0.0, 0.0, 1.0, 0.0));
    assert!(diff(&quat::inverse(&small).unwrap(), &Quaternion::new(0.0, 0.0, -1e11, 0.0)) <= 1e-4);
}

#[test]
fn huge_quaternions_are_normalised_or_refused() {
    // A finite quaternion of norm 1e200 is a valid rotation (π about x). Either the unit
    // quaternion comes back, or an error; a zero "unit" quaternion or an unrotated vector is wrong.
    let q = Quaternion::new(0.0, 1e200, 0.0, 0.0);
    if let Ok(u) = quat::normalize(&q) {
        assert!(
            (u.norm() - 1.0).abs() < 1e-15,
            "normalize(1e200 i) = {:?}",
            u.into_inner()
        );
    }
    if let Ok(v) = quat::rotate(&q, &Vector3::new(1.0, 2.0, 3.0)) {
        assert!(
            (v - Vector3::new(1.0, -2.0, -3.0)).norm() < 1e-14,
            "rotate(1e200 i, v) = {v}"
        );
    }
    if let Ok(inv) = quat::inverse(&q) {
        assert!((inv.i + 1e-200).abs() < 1e-214, "inverse(1e200 i) = {inv:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// exp, log, rotate
// ---------------------------------------------------------------------------------------------

#[test]
fn exp_matches_so3_exp() {
    check_rotation_vectors(CASES, |phi| {
        let q = quat::exp(&phi);
        prop_assert!((q.quaternion().norm() - 1.0).abs() <= 4.0 * f64::EPSILON);
        let err = max_abs_diff(q.to_rotation_matrix().matrix(), so3::exp(&phi).matrix());
        prop_assert!(err <= 1e-14, "θ = {:e}: {err:e}", phi.norm());
        // The scalar part is cos(θ/2) ≥ 0 on [0, π]: exp returns the w ≥ 0 representative.
        prop_assert!(q.w >= 0.0);
        Ok(())
    });
    check("θ in (π, 2π)", CASES, (unit_vector(), PI..TAU), |(u, t)| {
        let err = max_abs_diff(
            quat::exp(&(u * t)).to_rotation_matrix().matrix(),
            so3::exp(&(u * t)).matrix(),
        );
        prop_assert!(err <= 1e-14, "{err:e}");
        Ok(())
    });
}

/// The step exponential's shorter series (θ < 0.01 rad) against `sin`, `cos` of the half angle on
/// both sides of the switch: within a last bit of each component; above it, `quat::exp` itself.
#[test]
fn exp_step_is_exp_to_the_last_bit() {
    check(
        "θ in [1e-9, 0.02]",
        CASES,
        (unit_vector(), -9.0..-1.7_f64),
        |(u, log_t)| {
            let t = 10f64.powf(log_t);
            let q = quat::exp_step(&(u * t));
            let (s, c) = (0.5 * t).sin_cos();
            let expected = Vector4::new(u.x * s, u.y * s, u.z * s, c);
            let err = (q.coords - expected).amax();
            prop_assert!(err <= 2.0 * f64::EPSILON * expected.amax(), "θ = {t:e}: {err:e}");
            if t >= 0.01 {
                prop_assert_eq!(q, quat::exp(&(u * t)));
            }
            Ok(())
        },
    );
}

#[test]
fn log_inverts_exp() {
    check_rotation_vectors(CASES, |phi| {
        let q = quat::exp(&phi);
        let back = quat::log(&q);
        let theta = phi.norm();
        // Relative error, so θ ≈ 1e-8 is checked to full precision (measured ≤ 4.2e-16).
        prop_assert!(
            (back - phi).norm() <= 1e-14 * theta,
            "θ = {theta:e}: {:e}",
            (back - phi).norm()
        );
        // q and −q are the same rotation and have the same log (bit for bit: log flips to w ≥ 0).
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        prop_assert_eq!(quat::log(&neg), back);
        // The matrix route agrees.
        let err = (so3::log(&so3::exp(&phi)) - back).norm();
        prop_assert!(err <= 1e-14 * theta.max(1e-300), "so3::log differs by {err:e}");
        Ok(())
    });
    // Past π: log returns the equivalent vector of angle 2π − θ about the opposite axis.
    check(
        "θ in (π, 2π)",
        CASES,
        (unit_vector(), PI + 1e-6..TAU - 1e-6),
        |(u, t)| {
            let back = quat::log(&quat::exp(&(u * t)));
            let expected = u * (t - TAU);
            prop_assert!((back - expected).norm() <= 1e-14 * TAU, "{back} vs {expected}");
            Ok(())
        },
    );
    assert_eq!(quat::log(&UnitQuaternion::identity()), Vector3::zeros());
}

#[test]
fn rotate_matches_the_matrix_and_the_sandwich_product() {
    let strategy = (any_quaternion(), vector3(10.0), -3.0..3.0f64);
    check("rotate", CASES, strategy, |(q, v, scale)| {
        let rotated = quat::rotate(&q, &v).unwrap();
        // q ⊗ [v, 0] ⊗ q⁻¹ by hand (non-unit q: q⁻¹, not q*)
        let sandwich = quat::multiply(&quat::multiply(&q, &quat::pure(&v)), &quat::inverse(&q).unwrap());
        prop_assert!(sandwich.w.abs() <= 1e-13);
        prop_assert!(
            (rotated - sandwich.imag()).norm() <= 1e-13,
            "{rotated} vs {}",
            sandwich.imag()
        );
        // The same as the rotation matrix of Log(q/|q|).
        let r: Rotation3<f64> = so3::exp(&quat::log(&quat::normalize(&q).unwrap()));
        prop_assert!((rotated - r * v).norm() <= 1e-13);
        // Scale (including sign) of q does not matter.
        if scale.abs() > 0.1 {
            prop_assert!((quat::rotate(&(q * scale), &v).unwrap() - rotated).norm() <= 1e-13);
        }
        Ok(())
    });
    // Active convention: a quarter turn about z maps x to y.
    let q = quat::exp(&Vector3::new(0.0, 0.0, PI / 2.0));
    let v = quat::rotate(q.quaternion(), &Vector3::x()).unwrap();
    assert!((v - Vector3::y()).norm() < 1e-15, "{v}");
}
