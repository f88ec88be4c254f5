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

use crate::quat;

/// `[φ]×`, the skew-symmetric matrix with `[φ]× v = φ × v`.
pub fn hat(phi: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(
        0.0, -phi.z, phi.y, //
        phi.z, 0.0, -phi.x, //
        -phi.y, phi.x, 0.0,
    )
}

/// Inverse of [`hat`]. For a matrix that is not exactly skew it returns the vector of its skew
/// part `(M − Mᵀ)/2`, the nearest element of so(3) in the Frobenius norm.
pub fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    // Halve before subtracting: entries near f64::MAX must not overflow.
    Vector3::new(
        0.5 * m[(2, 1)] - 0.5 * m[(1, 2)],
        0.5 * m[(0, 2)] - 0.5 * m[(2, 0)],
        0.5 * m[(1, 0)] - 0.5 * m[(0, 1)],
    )
}

/// `Exp(φ) = I + (sin θ/θ) [φ]× + ((1 − cos θ)/θ²) [φ]×²` (Rodrigues), series-safe at θ → 0.
#[inline]
pub fn exp(phi: &Vector3<f64>) -> Rotation3<f64> {
    let theta = phi.norm();
    // Series below θ = 0.5; above, one sin_cos of θ/2 gives both: sin θ = 2 s c, 1 − cos θ = 2 s².
    let (a, b) = if theta < 0.5 {
        // sin θ/θ = Σ (−1)ᵏ θ²ᵏ/(2k+1)! and (1 − cos θ)/θ² = Σ (−1)ᵏ θ²ᵏ/(2k+2)! through θ¹²;
        // the first omitted terms are below 5e-17 at θ = 0.5.
        let t = theta * theta;
        let a = horner(
            t,
            &[
                1.0,
                -1.0 / 6.0,
                1.0 / 120.0,
                -1.0 / 5_040.0,
                1.0 / 362_880.0,
                -1.0 / 39_916_800.0,
                1.0 / 6_227_020_800.0,
            ],
        );
        let b = horner(
            t,
            &[
                0.5,
                -1.0 / 24.0,
                1.0 / 720.0,
                -1.0 / 40_320.0,
                1.0 / 3_628_800.0,
                -1.0 / 479_001_600.0,
                1.0 / 87_178_291_200.0,
            ],
        );
        (a, b)
    } else {
        let (s, c) = (0.5 * theta).sin_cos();
        let s_over = s / theta;
        (2.0 * c * s_over, 2.0 * s_over * s_over)
    };
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
pub fn right_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    jacobian(&-phi)
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
    Matrix3::identity() - k * 0.5 + k * k * inv_coefficient(theta)
}

// The scalar coefficients below switch to Taylor series where the closed form cancels
// catastrophically or where a series is cheaper than libm (most IMU steps have θ ≪ 1); the
// thresholds keep both the truncation and the rounding error near 1e-15 absolute (checked in tests
// against 50-digit values). Series coefficients are constants: a division by a literal is not
// folded into a multiplication and would cost more than the libm call it replaces.

/// `Σ cₖ xᵏ` by Horner's rule.
#[inline(always)]
fn horner<const N: usize>(x: f64, c: &[f64; N]) -> f64 {
    let mut acc = 0.0;
    for k in (0..N).rev() {
        acc = acc * x + c[k];
    }
    acc
}

/// `sin θ / θ = Σ (−1)ᵏ θ²ᵏ/(2k+1)!` (series below θ = 0.5, first omitted term < 5e-17).
#[inline]
fn sinc(theta: f64) -> f64 {
    const C: [f64; 7] = [
        1.0,
        -1.0 / 6.0,
        1.0 / 120.0,
        -1.0 / 5_040.0,
        1.0 / 362_880.0,
        -1.0 / 39_916_800.0,
        1.0 / 6_227_020_800.0,
    ];
    if theta < 0.5 {
        horner(theta * theta, &C)
    } else {
        theta.sin() / theta
    }
}

/// `(1 − cos θ)/θ² = ½ (sin(θ/2)/(θ/2))²`, written with the half angle to avoid cancellation.
#[inline]
fn one_minus_cos_over_sq(theta: f64) -> f64 {
    let s = sinc(0.5 * theta);
    0.5 * s * s
}

/// `(θ − sin θ)/θ³ = Σ (−1)ᵏ θ²ᵏ/(2k+3)!`.
#[inline]
fn theta_minus_sin_over_cube(theta: f64) -> f64 {
    const C: [f64; 5] = [
        1.0 / 6.0,
        -1.0 / 120.0,
        1.0 / 5_040.0,
        -1.0 / 362_880.0,
        1.0 / 39_916_800.0,
    ];
    if theta < 0.2 {
        horner(theta * theta, &C)
    } else {
        (theta - theta.sin()) / (theta * theta * theta)
    }
}

/// `(θ²/2 + cos θ − 1)/θ⁴ = (½ − (1 − cos θ)/θ²)/θ² = Σ (−1)ᵏ θ²ᵏ/(2k+4)!`.
#[inline]
fn cos_remainder(theta: f64) -> f64 {
    const C: [f64; 5] = [
        1.0 / 24.0,
        -1.0 / 720.0,
        1.0 / 40_320.0,
        -1.0 / 3_628_800.0,
        1.0 / 479_001_600.0,
    ];
    if theta < 0.2 {
        horner(theta * theta, &C)
    } else {
        (0.5 - one_minus_cos_over_sq(theta)) / (theta * theta)
    }
}

/// `(1 − (θ/2) cot(θ/2))/θ²`, equal to `1/θ² − (1 + cos θ)/(2 θ sin θ)` but finite at θ = π.
#[inline]
fn inv_coefficient(theta: f64) -> f64 {
    // (1 − x cot x)/(4x²) with x = θ/2, from x cot x = 1 − Σ 4ⁿ|B₂ₙ| x²ⁿ/(2n)!.
    const C: [f64; 5] = [
        1.0 / 12.0,
        1.0 / 720.0,
        1.0 / 30_240.0,
        1.0 / 1_209_600.0,
        1.0 / 47_900_160.0,
    ];
    if theta < 0.2 {
        horner(theta * theta, &C)
    } else {
        let half = 0.5 * theta;
        (1.0 - half * half.cos() / half.sin()) / (theta * theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values of the coefficients computed with 50-digit arithmetic (mpmath) at points
    /// on both sides of each series/closed-form switch.
    #[test]
    #[allow(clippy::excessive_precision)] // the references are quoted as computed
    fn coefficients_match_high_precision_values() {
        // (θ, (1−cosθ)/θ², (θ−sinθ)/θ³, (1−(θ/2)cot(θ/2))/θ²), 19 significant digits
        let cases = [
            (
                1e-8,
                0.4999999999999999958,
                0.1666666666666666658,
                0.08333333333333333347,
            ),
            (
                0.199_999,
                0.498335570591187701,
                0.1663336539443291972,
                0.0833889412952914013,
            ),
            (
                0.200_001,
                0.4983355373466480749,
                0.1663336472903503664,
                0.08338894240852209342,
            ),
            (
                3.0,
                0.2211102774000494953,
                0.1058844441459308436,
                0.09929197039400236965,
            ),
            (
                std::f64::consts::PI,
                0.2026423672846755429,
                0.1013211836423377714,
                0.1013211836423377714,
            ),
        ];
        for (theta, d) in [
            (1e-8, 0.041_666_666_666_666_666_53),
            (0.199_999, 0.041_611_151_330_780_503_33),
            (0.200_001, 0.041_611_150_221_255_636_03),
            (3.0, 0.030_987_746_955_550_056_08),
        ] {
            assert!((cos_remainder(theta) - d).abs() < 3e-15, "d at {theta}");
        }
        for (theta, a, b, c) in cases {
            assert!((one_minus_cos_over_sq(theta) - a).abs() < 1e-15, "a at {theta}");
            assert!((theta_minus_sin_over_cube(theta) - b).abs() < 3e-15, "b at {theta}");
            assert!((inv_coefficient(theta) - c).abs() < 3e-15, "c at {theta}");
        }
    }
}
