//! Property tests of `imukit::euler`: intrinsic ZYX angles `χ = [ψ, θ, φ]` (yaw, pitch, roll),
//! `R = Rz(ψ) Ry(θ) Rx(φ)`, the rate map `χ̇ = E(χ) ω_b` and gimbal-lock handling.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![allow(missing_docs)]

use std::f64::consts::{FRAC_PI_2, PI};

use imukit::{euler, so3, Error};
use imukit_testing::{check, identity3, max_abs_diff, numeric_jacobian, random_rotation, vector3};
use nalgebra::{Matrix3, Rotation3, Unit, Vector1, Vector3};
use proptest::prelude::*;

const CASES: u32 = 256;

/// `a − b` wrapped to (−π, π]: yaw and roll near ±π may come back on the other side of the cut.
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI {
        d - 2.0 * PI
    } else {
        d
    }
}

fn rz_ry_rx(chi: &Vector3<f64>) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), chi.x)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), chi.y)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), chi.z)
}

/// χ with yaw and roll in (−π, π) and pitch in (−p, p).
fn angles(max_pitch: f64) -> impl Strategy<Value = Vector3<f64>> {
    (-PI..PI, -max_pitch..max_pitch, -PI..PI).prop_map(|(y, p, r)| Vector3::new(y, p, r))
}

#[test]
fn to_rotation_is_rz_ry_rx() {
    // Intrinsic z–y′–x″ = extrinsic x–y–z = the matrix product Rz Ry Rx; any pitch.
    check("Rz Ry Rx", CASES, angles(PI), |chi| {
        let err = max_abs_diff(euler::to_rotation(&chi).matrix(), rz_ry_rx(&chi).matrix());
        prop_assert!(err <= 2e-15, "{err:e}");
        Ok(())
    });
    // Yaw alone turns x towards y (active, z up).
    let r = euler::to_rotation(&Vector3::new(FRAC_PI_2, 0.0, 0.0));
    assert!((r * Vector3::x() - Vector3::y()).norm() < 1e-15);
}

#[test]
fn rotation_with_body_rate_equals_its_two_parts() {
    let rates = (angles(PI), angles(PI)).prop_map(|(chi, d)| (chi, d));
    check("R and E⁻¹ χ̇", CASES, rates, |(chi, chi_dot)| {
        let (r, w) = euler::to_rotation_with_body_rate(&chi, &chi_dot);
        prop_assert!(r == euler::to_rotation(&chi));
        let err = (w - euler::rate_matrix_inv(&chi) * chi_dot).amax();
        prop_assert!(err <= 1e-14, "{err:e}");
        Ok(())
    });
}

#[test]
fn from_rotation_inverts_to_rotation() {
    // Away from gimbal lock the angles are unique in the stated ranges; their error grows like
    // ε / cos θ (≈ 2e-14 at 0.01 rad from the pole).
    check("χ round trip", CASES, angles(FRAC_PI_2 - 0.01), |chi| {
        let back = euler::from_rotation(&euler::to_rotation(&chi));
        let errs = [angle_diff(back.x, chi.x), back.y - chi.y, angle_diff(back.z, chi.z)];
        let worst = errs.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        prop_assert!(worst <= 1e-13, "{chi} → {back}: {worst:e}");
        Ok(())
    });
}

#[test]
fn from_rotation_reproduces_any_rotation() {
    check("any R", CASES, random_rotation(), |r| {
        let chi = euler::from_rotation(&r);
        prop_assert!(
            chi.x.abs() <= PI && chi.z.abs() <= PI && chi.y.abs() <= FRAC_PI_2,
            "{chi}"
        );
        let err = max_abs_diff(euler::to_rotation(&chi).matrix(), r.matrix());
        prop_assert!(err <= 1e-14, "{err:e}");
        Ok(())
    });
}

#[test]
fn from_rotation_near_gimbal_lock_reproduces_the_rotation() {
    // R built by a different route (nalgebra products, then an exp/log round trip) has rounding
    // noise in the entries that vanish at lock. Yaw and roll are then not separately
    // determined, but to_rotation(from_rotation(R)) must still be R.
    let offsets = prop_oneof![0.0..2e-12f64, 0.0..1e-6f64];
    let strategy = (-PI..PI, prop_oneof![Just(1.0), Just(-1.0)], offsets, -PI..PI);
    check("near lock", CASES, strategy, |(yaw, sign, offset, roll)| {
        let pitch = sign * (FRAC_PI_2 - offset);
        let r0 = rz_ry_rx(&Vector3::new(yaw, pitch, roll));
        let r = so3::exp(&so3::log(&r0));
        let chi = euler::from_rotation(&r);
        let err = max_abs_diff(euler::to_rotation(&chi).matrix(), r.matrix());
        let cos_pitch = r[(0, 0)].hypot(r[(1, 0)]);
        // Within GIMBAL_LOCK_COS of the pole, reporting roll 0 moves the first column by up to
        // 2 cos θ (its entries are cos ψ cos θ, sin ψ cos θ with ψ then replaced by ψ ∓ φ): an
        // error ≤ 2e-12, above rounding. Elsewhere the reconstruction is exact to rounding.
        let tol = if cos_pitch < euler::GIMBAL_LOCK_COS {
            1e-14 + 2.5 * cos_pitch
        } else {
            1e-14
        };
        prop_assert!(err <= tol, "pitch π/2 − {offset:e}: χ = {chi}, error {err:e}");
        // Within GIMBAL_LOCK_COS of the pole yaw takes the whole vertical rotation: roll is 0.
        if cos_pitch < euler::GIMBAL_LOCK_COS {
            prop_assert!(chi.z.abs() <= 1e-14, "roll {} at cos θ < GIMBAL_LOCK_COS", chi.z);
            let observable = yaw - sign * roll;
            prop_assert!(
                angle_diff(chi.x, observable).abs() <= 1e-12,
                "yaw {} vs {observable}",
                chi.x
            );
        }
        Ok(())
    });
}

#[test]
fn from_rotation_at_exact_gimbal_lock() {
    // R = Rz(ψ) Ry(±π/2) Rx(φ) with the entries that are exactly zero at lock set to zero.
    // Only ψ − φ (pitch +π/2) or ψ + φ (pitch −π/2) is observable; roll is reported as 0.
    let strategy = (-PI..PI, prop_oneof![Just(1.0), Just(-1.0)], -PI..PI);
    check("exact lock", CASES, strategy, |(yaw, sign, roll)| {
        let mut m = *euler::to_rotation(&Vector3::new(yaw, sign * FRAC_PI_2, roll)).matrix();
        m[(0, 0)] = 0.0;
        m[(1, 0)] = 0.0;
        m[(2, 1)] = 0.0;
        m[(2, 2)] = 0.0;
        m[(2, 0)] = -sign;
        let r = Rotation3::from_matrix_unchecked(m);
        let chi = euler::from_rotation(&r);
        prop_assert_eq!(chi.y, sign * FRAC_PI_2);
        prop_assert!(chi.z.abs() <= 1e-15, "roll {}", chi.z);
        let observable = yaw - sign * roll;
        prop_assert!(
            angle_diff(chi.x, observable).abs() <= 1e-14,
            "yaw {} vs {observable}",
            chi.x
        );
        let err = max_abs_diff(euler::to_rotation(&chi).matrix(), &m);
        prop_assert!(err <= 1e-15 * 4.0, "{err:e}");
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// rate map
// ---------------------------------------------------------------------------------------------

#[test]
fn rate_matrix_matches_finite_differences() {
    // R(t) = R0 Exp(ω t) (body rate), χ(t) = from_rotation(R(t)): χ̇(0) = E(χ0) ω. Yaw and roll
    // stay 0.1 away from the ±π cut, so χ(t) is smooth over the difference stencil. With
    // |pitch| ≤ 1.3 (cos ≥ 0.27), |χ‴| ≲ |ω|³/cos³ ≈ 500 gives truncation ≲ 3e-9.
    let strategy = (-PI + 0.1..PI - 0.1, -1.3..1.3f64, -PI + 0.1..PI - 0.1, vector3(2.0));
    check("E(χ) ω", CASES, strategy, |(yaw, pitch, roll, w)| {
        let chi0 = Vector3::new(yaw, pitch, roll);
        let r0 = euler::to_rotation(&chi0);
        let numeric = numeric_jacobian(
            |t: &Vector1<f64>| euler::from_rotation(&(r0 * so3::exp(&(w * t.x)))),
            &Vector1::zeros(),
        );
        let numeric = numeric.column(0).into_owned();
        let e = euler::rate_matrix(&chi0, euler::GIMBAL_TOLERANCE).unwrap();
        let err = (numeric - e * w).norm();
        prop_assert!(
            err <= 1e-7 * (e * w).norm().max(1.0),
            "χ̇ numeric {numeric} vs E ω {}: {err:e}",
            e * w
        );
        // And back: ω = E⁻¹(χ) χ̇.
        let err = (euler::rate_matrix_inv(&chi0) * numeric - w).norm();
        prop_assert!(err <= 1e-7 * w.norm().max(1.0), "{err:e}");
        Ok(())
    });
}

#[test]
fn inverse_rate_matrix_matches_finite_differences_everywhere() {
    // E⁻¹ is defined at any pitch, gimbal lock included: ω = vee(R0ᵀ Ṙ) for R(t) =
    // to_rotation(χ0 + χ̇ t), i.e. the derivative of Log(R0ᵀ R(t)) at t = 0.
    check(
        "E⁻¹(χ) χ̇",
        CASES,
        (angles(PI), vector3(2.0)),
        |(chi0, chi_dot)| {
            let r0 = euler::to_rotation(&chi0);
            let numeric = numeric_jacobian(
                |t: &Vector1<f64>| so3::log(&(r0.inverse() * euler::to_rotation(&(chi0 + chi_dot * t.x)))),
                &Vector1::zeros(),
            );
            let err = (numeric.column(0) - euler::rate_matrix_inv(&chi0) * chi_dot).norm();
            prop_assert!(err <= 1e-8 * chi_dot.norm().max(1.0), "{err:e}");
            Ok(())
        },
    );
}

#[test]
fn rate_matrix_times_its_inverse_is_identity() {
    // E has entries up to 1/cos θ ≤ 100 here; products then carry ~100 ε.
    check("E E⁻¹", CASES, angles(FRAC_PI_2 - 0.01), |chi| {
        let e = euler::rate_matrix(&chi, euler::GIMBAL_TOLERANCE).unwrap();
        let e_inv = euler::rate_matrix_inv(&chi);
        let err1 = max_abs_diff(&(e * e_inv), &identity3());
        let err2 = max_abs_diff(&(e_inv * e), &identity3());
        prop_assert!(err1 <= 1e-13 && err2 <= 1e-13, "{err1:e} {err2:e}");
        Ok(())
    });
}

#[test]
fn rate_matrix_refuses_gimbal_lock_within_the_tolerance() {
    let chi = |pitch: f64| Vector3::new(0.3, pitch, -0.7);
    for tol in [euler::GIMBAL_TOLERANCE, 1e-3, 0.1] {
        // Every pole, including pitch values outside [−π/2, π/2] (integrated angles).
        for pole in [-3.0 * FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2, 3.0 * FRAC_PI_2] {
            for side in [-1.0, 1.0] {
                let inside = pole + side * 0.5 * tol;
                match euler::rate_matrix(&chi(inside), tol) {
                    Err(Error::GimbalLock {
                        index,
                        pitch_deg,
                        tolerance_deg,
                    }) => {
                        assert_eq!(index, 0);
                        assert_eq!(pitch_deg, inside.to_degrees());
                        assert_eq!(tolerance_deg, tol.to_degrees());
                    }
                    other => panic!("pitch {inside} (tol {tol}) must be refused, got {other:?}"),
                }
                assert!(euler::check_pitch(inside, tol).is_err());
                let outside = pole + side * 2.0 * tol;
                let e = euler::rate_matrix(&chi(outside), tol);
                assert!(e.is_ok(), "pitch {outside} (tol {tol}): {e:?}");
                assert!(euler::check_pitch(outside, tol).is_ok());
            }
        }
        assert!(euler::rate_matrix(&chi(FRAC_PI_2), tol).is_err());
    }
    // The error message names the pitch in degrees.
    let message = euler::rate_matrix(&chi(FRAC_PI_2), 1e-6).unwrap_err().to_string();
    assert!(message.contains("gimbal lock") && message.contains("90"), "{message}");
}

#[test]
fn check_pitch_rejects_invalid_tolerances() {
    for tol in [-1e-6, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let result = euler::check_pitch(0.0, tol);
        assert!(
            matches!(result, Err(Error::Parameter { name: "tolerance", .. })),
            "tolerance {tol}: {result:?}"
        );
        let result = euler::rate_matrix(&Vector3::zeros(), tol);
        assert!(
            matches!(result, Err(Error::Parameter { .. })),
            "tolerance {tol}: {result:?}"
        );
    }
    assert_eq!(euler::check_pitch(0.0, 0.0), Ok(()));
    assert_eq!(euler::check_pitch(1.0, 0.5), Ok(()));
}

#[test]
fn rate_matrix_closed_form() {
    // Spot values: at χ = 0, E maps body x → roll rate, y → pitch rate, z → yaw rate.
    let e = euler::rate_matrix(&Vector3::zeros(), 1e-6).unwrap();
    assert_eq!(e, Matrix3::new(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0));
    // Pure yaw rate with the body pitched: ω_b = ψ̇ Ry(θ)ᵀ z.
    let theta = 0.4;
    let chi = Vector3::new(0.0, theta, 0.0);
    let w = Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::y()), theta).inverse() * Vector3::z();
    let rates = euler::rate_matrix(&chi, 1e-6).unwrap() * w;
    assert!((rates - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-15, "{rates}");
}
