//! Intrinsic ZYX Euler angles (yaw ψ, pitch θ, roll φ) and their rate map.
//!
//! | item | convention |
//! |---|---|
//! | angle vector | `χ = [ψ, θ, φ]` = `[yaw, pitch, roll]`, radians, the order of scipy's `as_euler("ZYX")` |
//! | rotation | intrinsic z–y′–x″: `R_wb = Rz(ψ) Ry(θ) Rx(φ)` |
//! | ranges from [`from_rotation`] | `ψ, φ ∈ (−π, π]`, `θ ∈ [−π/2, π/2]`; roll 0 at gimbal lock |
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
    EulerSines::of(chi).rotation()
}

/// `(R(χ), E⁻¹(χ) χ̇)`: the attitude and the body rate of Euler angles moving at `χ̇`, from one
/// evaluation of the sines (a simulator evaluates both at every sample).
pub fn to_rotation_with_body_rate(chi: &Vector3<f64>, chi_dot: &Vector3<f64>) -> (Rotation3<f64>, Vector3<f64>) {
    let s = EulerSines::of(chi);
    (s.rotation(), s.body_rate(chi_dot))
}

/// Sines and cosines `(sin, cos)` of yaw ψ, pitch θ and roll φ: callers that know them without the
/// angles (a heading from a velocity direction) skip the trigonometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EulerSines {
    /// `(sin ψ, cos ψ)`.
    pub yaw: (f64, f64),
    /// `(sin θ, cos θ)`.
    pub pitch: (f64, f64),
    /// `(sin φ, cos φ)`.
    pub roll: (f64, f64),
}

impl EulerSines {
    /// The sines of `χ = [ψ, θ, φ]`.
    pub fn of(chi: &Vector3<f64>) -> Self {
        Self {
            yaw: chi.x.sin_cos(),
            pitch: chi.y.sin_cos(),
            roll: chi.z.sin_cos(),
        }
    }

    /// `R = Rz(ψ) Ry(θ) Rx(φ)`.
    pub fn rotation(&self) -> Rotation3<f64> {
        let ((sy, cy), (sp, cp), (sr, cr)) = (self.yaw, self.pitch, self.roll);
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

    /// `ω_b = E⁻¹(χ) χ̇ = [φ̇ − ψ̇ sθ, θ̇ cφ + ψ̇ cθ sφ, ψ̇ cθ cφ − θ̇ sφ]`.
    pub fn body_rate(&self, chi_dot: &Vector3<f64>) -> Vector3<f64> {
        let ((sp, cp), (sr, cr)) = (self.pitch, self.roll);
        let (yaw_dot, pitch_dot, roll_dot) = (chi_dot.x, chi_dot.y, chi_dot.z);
        Vector3::new(
            roll_dot - yaw_dot * sp,
            pitch_dot * cr + yaw_dot * cp * sr,
            yaw_dot * cp * cr - pitch_dot * sr,
        )
    }
}

/// `χ = [ψ, θ, φ]` of R; `to_rotation(χ)` reproduces R to rounding, except within
/// [`GIMBAL_LOCK_COS`] of gimbal lock, where setting roll to 0 moves R by at most `2 cos θ`
/// (≤ 2e-12).
///
/// Pitch uses `atan2(−R₂₀, √(R₀₀² + R₁₀²))`, accurate near ±π/2 where `asin` loses half its
/// digits. Roll is solved from `Rx(φ) = Ry(θ)ᵀ Rz(ψ)ᵀ R` given the yaw actually chosen, so yaw
/// noise near the singularity moves into roll instead of breaking `to_rotation(χ) = R`. Within
/// [`GIMBAL_LOCK_COS`] of the singularity yaw takes the whole rotation about the vertical and
/// roll comes out 0 (only ψ ∓ φ is observable there).
pub fn from_rotation(r: &Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    let cos_pitch = m[(0, 0)].hypot(m[(1, 0)]);
    let pitch = (-m[(2, 0)]).atan2(cos_pitch);
    let yaw = if cos_pitch < GIMBAL_LOCK_COS {
        // R = Rz(ψ ∓ φ) Ry(±π/2): the second column is [−sin, cos, 0] of the yaw with roll 0.
        (-m[(0, 1)]).atan2(m[(1, 1)])
    } else {
        m[(1, 0)].atan2(m[(0, 0)])
    };
    let (sy, cy) = yaw.sin_cos();
    // Row 1 of Rz(ψ)ᵀ R is [0, cos φ, −sin φ]; Ry(θ)ᵀ leaves row 1 unchanged.
    let roll = (sy * m[(0, 2)] - cy * m[(1, 2)]).atan2(cy * m[(1, 1)] - sy * m[(0, 1)]);
    Vector3::new(half_open(yaw), pitch, half_open(roll))
}

/// Maps atan2's `−π` (returned for a `−0.0` numerator) to `π`, so angles lie in `(−π, π]`.
fn half_open(angle: f64) -> f64 {
    if angle <= -std::f64::consts::PI {
        std::f64::consts::PI
    } else {
        angle
    }
}

/// `cos θ` below which [`from_rotation`] treats the pitch as ±π/2 (yaw and roll are then no longer
/// separately determined to better than `ε / cos θ`).
pub const GIMBAL_LOCK_COS: f64 = 1e-12;

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

/// Errors when the pitch is within `tolerance` of ±π/2, is not finite, or the tolerance itself
/// is invalid.
pub fn check_pitch(pitch: f64, tolerance: f64) -> Result<()> {
    if !pitch.is_finite() {
        return Err(Error::NonFinite { index: 0 });
    }
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
