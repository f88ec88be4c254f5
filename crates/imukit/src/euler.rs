//! Intrinsic ZYX Euler angles (yaw ψ, pitch θ, roll φ) and their rate map.
//!
//! | item | convention |
//! |---|---|
//! | angle vector | `χ = [ψ, θ, φ]` = `[yaw, pitch, roll]`, radians, the order of scipy's `as_euler("ZYX")` |
//! | rotation | intrinsic z–y′–x″: `R_wb = Rz(ψ) Ry(θ) Rx(φ)` |
//! | ranges from [`from_rotation`] | `ψ, φ ∈ (−π, π]`, `θ ∈ [−π/2, π/2]` |
//! | rate map | `χ̇ = E(χ) ω_b` for the body rate ω_b of `Ṙ = R [ω_b]×` ([`rate_matrix`]) |
//! | singularity | `cos θ = 0`: E is undefined; [`rate_matrix`] returns [`Error::GimbalLock`] |
//!
//! Derivation: `ω_b = Rx(φ)ᵀ Ry(θ)ᵀ [0, 0, ψ̇] + Rx(φ)ᵀ [0, θ̇, 0] + [φ̇, 0, 0]`
//! gives `ω_b = E⁻¹(χ) χ̇` ([`rate_matrix_inv`], always defined); inverting it gives E.

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::{Error, Result};

/// Default gimbal-lock tolerance: |pitch| within this many radians of π/2 is refused.
pub const GIMBAL_TOLERANCE: f64 = 1e-6;

/// `R = Rz(ψ) Ry(θ) Rx(φ)` for `χ = [ψ, θ, φ]`.
pub fn to_rotation(chi: &Vector3<f64>) -> Rotation3<f64> {
    let (sy, cy) = chi.x.sin_cos();
    let (sp, cp) = chi.y.sin_cos();
    let (sr, cr) = chi.z.sin_cos();
    Rotation3::from_matrix_unchecked(Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    ))
}

/// `χ = [ψ, θ, φ]` of R. Pitch uses `atan2(−R₂₀, √(R₀₀² + R₁₀²))`, accurate near ±π/2 where
/// `asin` loses half its digits. At exact gimbal lock (`R₀₀ = R₁₀ = 0`) roll is set to 0 and
/// the whole rotation about the vertical is reported as yaw.
pub fn from_rotation(r: &Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    let pitch = (-m[(2, 0)]).atan2(m[(0, 0)].hypot(m[(1, 0)]));
    if m[(0, 0)] == 0.0 && m[(1, 0)] == 0.0 {
        // R = Rz(ψ ∓ φ) Ry(±π/2): only the difference (or sum) is observable.
        let yaw = (-m[(0, 1)]).atan2(m[(1, 1)]);
        return Vector3::new(yaw, pitch, 0.0);
    }
    Vector3::new(m[(1, 0)].atan2(m[(0, 0)]), pitch, m[(2, 1)].atan2(m[(2, 2)]))
}

/// `E(χ)` with `χ̇ = E(χ) ω_b`:
///
/// ```text
/// ⎡ 0   sin φ / cos θ   cos φ / cos θ ⎤
/// ⎢ 0   cos φ           −sin φ        ⎥
/// ⎣ 1   sin φ tan θ     cos φ tan θ   ⎦
/// ```
///
/// Errors with [`Error::GimbalLock`] when `|θ|` is within `tolerance` radians of π/2.
pub fn rate_matrix(chi: &Vector3<f64>, tolerance: f64) -> Result<Matrix3<f64>> {
    check_pitch(chi.y, tolerance)?;
    let (sp, cp) = chi.y.sin_cos();
    let (sr, cr) = chi.z.sin_cos();
    Ok(Matrix3::new(
        0.0,
        sr / cp,
        cr / cp,
        0.0,
        cr,
        -sr,
        1.0,
        sr * sp / cp,
        cr * sp / cp,
    ))
}

/// `E⁻¹(χ)` with `ω_b = E⁻¹(χ) χ̇`; defined everywhere.
pub fn rate_matrix_inv(chi: &Vector3<f64>) -> Matrix3<f64> {
    let (sp, cp) = chi.y.sin_cos();
    let (sr, cr) = chi.z.sin_cos();
    Matrix3::new(
        -sp,
        0.0,
        1.0, //
        sr * cp,
        cr,
        0.0, //
        cr * cp,
        -sr,
        0.0,
    )
}

/// Errors when the pitch is within `tolerance` of ±π/2 (or the tolerance itself is invalid).
pub fn check_pitch(pitch: f64, tolerance: f64) -> Result<()> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::Parameter {
            name: "tolerance",
            expected: "a finite, non-negative number of radians",
            got: format!("{tolerance}"),
        });
    }
    // Distance to the nearest odd multiple of π/2, so that pitch values outside [−π/2, π/2]
    // (e.g. integrated angles) are judged by where they really are.
    let to_pole = (pitch.cos()).abs().asin();
    if to_pole <= tolerance {
        return Err(Error::GimbalLock {
            index: 0,
            pitch_deg: pitch.to_degrees(),
            tolerance_deg: tolerance.to_degrees(),
        });
    }
    Ok(())
}
