//! SO(3): rotation matrices, the Lie algebra so(3), exp/log and the Jacobians of `Exp`.
//!
//! | item | convention |
//! |---|---|
//! | group element | [`Rotation3`] `R_wb`, active: `v_w = R_wb v_b` |
//! | tangent | rotation vector `φ = θ u` in radians, `θ = |φ|`; [`log`] returns `θ ∈ [0, π]` |
//! | hat | `[φ]× v = φ × v`; [`vee`] inverts it (on the skew part of any matrix) |
//! | plus / minus | right (local): `R ⊕ δ = R Exp(δ)`, `R₁ ⊖ R₂ = Log(R₂ᵀ R₁)` |
//! | body rate | `Ṙ = R [ω]×`, so `R(t) = R(t₀) Exp(ω (t − t₀))` for constant ω |
//!
//! Jacobians of `Exp` (Chirikjian 2011, vol. 2, §10.6; Solà, Deray & Atchuthan 2018, eqs. 143–146),
//! named by what they differentiate:
//!
//! | function | defining first-order identity |
//! |---|---|
//! | [`right_jacobian`] `J_r(φ)` | `Exp(φ + δ) ≈ Exp(φ) Exp(J_r(φ) δ)` |
//! | [`right_jacobian_inv`] `J_r⁻¹(φ)` | `Log(Exp(φ) Exp(δ)) ≈ φ + J_r⁻¹(φ) δ` |
//! | [`left_jacobian`] `J_l(φ) = J_r(−φ)` | `Exp(φ + δ) ≈ Exp(J_l(φ) δ) Exp(φ)` |
//! | [`left_jacobian_inv`] `J_l⁻¹(φ)` | `Log(Exp(δ) Exp(φ)) ≈ φ + J_l⁻¹(φ) δ` |
//!
//! `J_l(φ) = Exp(φ) J_r(φ)` and the adjoint is `Ad(R) = R`: `R [a]× Rᵀ = [R a]×`, so a right
//! increment δ equals the left increment `R δ` (hence `ω_world = R ω_body`). The inverses are
//! singular at `θ = 2π k`, k ≠ 0; on the output range of [`log`] they are finite.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

use crate::lie::series::{
    self, cos_remainder, inv_jacobian_coefficient, one_minus_cos_over_sq, theta_minus_sin_over_cube,
};
pub use crate::lie::skew::{hat, vee};
use crate::quat;

/// `Exp(φ) = I + (sin θ/θ) [φ]× + ((1 − cos θ)/θ²) [φ]×²` (Rodrigues), series-safe at θ → 0.
#[inline]
pub fn exp(phi: &Vector3<f64>) -> Rotation3<f64> {
    let (a, b) = series::rodrigues(phi.norm());
    // [φ]×² = φ φᵀ − θ² I, written out to skip the matrix product.
    let (x, y, z) = (phi.x, phi.y, phi.z);
    let (bxy, bxz, byz) = (b * x * y, b * x * z, b * y * z);
    let (ax, ay, az) = (a * x, a * y, a * z);
    Rotation3::from_matrix_unchecked(Matrix3::new(
        1.0 - b * (y * y + z * z),
        bxy - az,
        bxz + ay,
        bxy + az,
        1.0 - b * (x * x + z * z),
        byz - ax,
        bxz - ay,
        byz + ax,
        1.0 - b * (x * x + y * y),
    ))
}

/// `Log(R)` with angle in `[0, π]`, accurate at identity and at π (via the quaternion of R and
/// `atan2`, see [`quat::log`]). At exactly π, `φ` and `−φ` are the same rotation; either may return.
pub fn log(r: &Rotation3<f64>) -> Vector3<f64> {
    quat::log(&UnitQuaternion::from_rotation_matrix(r))
}

/// `R ⊕ δ = R Exp(δ)`.
pub fn plus(r: &Rotation3<f64>, delta: &Vector3<f64>) -> Rotation3<f64> {
    r * exp(delta)
}

/// `R₁ ⊖ R₂ = Log(R₂ᵀ R₁)`, the right increment that takes `R₂` to `R₁`.
pub fn minus(r1: &Rotation3<f64>, r2: &Rotation3<f64>) -> Vector3<f64> {
    log(&(r2.inverse() * r1))
}

/// Adjoint of SO(3), `Ad(R) = R`: `R Exp(δ) = Exp(Ad(R) δ) R`.
pub fn adjoint(r: &Rotation3<f64>) -> Matrix3<f64> {
    *r.matrix()
}

/// Right Jacobian `J_r(φ) = I − ((1 − cos θ)/θ²) [φ]× + ((θ − sin θ)/θ³) [φ]×²`.
#[inline]
pub fn right_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    jacobian(&-phi)
}

/// `(Exp(φ), J_r(φ))` at once, the pair every preintegration step needs: with `K = [φ]×`,
/// `Exp = I + a K + b K²` and `J_r = I − b K + c K²` share θ, `b = (1 − cos θ)/θ²` and
/// `K² = φ φᵀ − θ² I` (one norm and one set of coefficients for the two). The coefficients come
/// from θ² ([`series::exp_jacobian_small`]): most steps have θ < 0.01, where no square root sits on
/// the step's chain.
#[inline(always)]
pub fn exp_and_right_jacobian(phi: &Vector3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let (a, b, c) = series::exp_jacobian_small(phi.norm_squared());
    let (x, y, z) = (phi.x, phi.y, phi.z);
    let (xy, xz, yz) = (x * y, x * z, y * z);
    let (d0, d1, d2) = (y * y + z * z, x * x + z * z, x * x + y * y);
    let exp = Matrix3::new(
        1.0 - b * d0,
        b * xy - a * z,
        b * xz + a * y,
        b * xy + a * z,
        1.0 - b * d1,
        b * yz - a * x,
        b * xz - a * y,
        b * yz + a * x,
        1.0 - b * d2,
    );
    let jr = Matrix3::new(
        1.0 - c * d0,
        c * xy + b * z,
        c * xz - b * y,
        c * xy - b * z,
        1.0 - c * d1,
        c * yz + b * x,
        c * xz + b * y,
        c * yz - b * x,
        1.0 - c * d2,
    );
    (exp, jr)
}

/// Left Jacobian `J_l(φ) = I + ((1 − cos θ)/θ²) [φ]× + ((θ − sin θ)/θ³) [φ]×² = J_r(−φ)`.
pub fn left_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    jacobian(phi)
}

/// Inverse right Jacobian `J_r⁻¹(φ) = I + ½ [φ]× + ((1 − (θ/2) cot(θ/2))/θ²) [φ]×²`.
pub fn right_jacobian_inv(phi: &Vector3<f64>) -> Matrix3<f64> {
    jacobian_inv(&-phi)
}

/// Inverse left Jacobian `J_l⁻¹(φ) = I − ½ [φ]× + ((1 − (θ/2) cot(θ/2))/θ²) [φ]×² = J_r⁻¹(−φ)`.
pub fn left_jacobian_inv(phi: &Vector3<f64>) -> Matrix3<f64> {
    jacobian_inv(phi)
}

/// `Γ₂(φ) = ∫₀¹ (1 − s) Exp(s φ) ds = ½ I + ((θ − sin θ)/θ³) [φ]× + ((θ²/2 + cos θ − 1)/θ⁴) [φ]×²`.
///
/// With [`left_jacobian`] `J_l(φ) = Γ₁(φ) = ∫₀¹ Exp(s φ) ds` it integrates a body-frame specific
/// force held constant while the body turns at a constant rate: over a step h with `φ = ω h`,
/// `Δv = R Γ₁(φ) a h` and `Δp = R Γ₂(φ) a h²` (Eckenhoff, Geneva & Huang, IJRR 2019, eqs. 16–17).
pub fn exp_double_integral(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let k = hat(phi);
    Matrix3::identity() * 0.5 + k * theta_minus_sin_over_cube(theta) + k * k * cos_remainder(theta)
}

/// `J_l(φ)`; `J_r` is this at `−φ`.
fn jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let (b, c) = (one_minus_cos_over_sq(theta), theta_minus_sin_over_cube(theta));
    // I + b K + c K², with K² = φ φᵀ − θ² I written out.
    let (x, y, z) = (phi.x, phi.y, phi.z);
    let (cxy, cxz, cyz) = (c * x * y, c * x * z, c * y * z);
    let (bx, by, bz) = (b * x, b * y, b * z);
    Matrix3::new(
        1.0 - c * (y * y + z * z),
        cxy - bz,
        cxz + by,
        cxy + bz,
        1.0 - c * (x * x + z * z),
        cyz - bx,
        cxz - by,
        cyz + bx,
        1.0 - c * (x * x + y * y),
    )
}

/// `J_l⁻¹(φ)`; `J_r⁻¹` is this at `−φ`.
fn jacobian_inv(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let k = hat(phi);
    Matrix3::identity() - k * 0.5 + k * k * inv_jacobian_coefficient(theta)
}
