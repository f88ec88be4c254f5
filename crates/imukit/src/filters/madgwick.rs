//! Madgwick's gradient-descent filter (Madgwick, "An efficient orientation filter for inertial
//! and inertial/magnetic sensor arrays", report, 2010, §3; Madgwick, Harrison & Vaidyanathan,
//! ICORR 2011): `q̇ = ½ q ⊗ ω − β ∇f/‖∇f‖`, `f = q* ⊗ d ⊗ q − s` stacked over gravity and the
//! earth field `b = [‖h_horizontal‖ north + h_vertical up]`, `h = q ⊗ m ⊗ q*` (his eq. 45–46).
//!
//! For `f = ½‖R̂ᵀ d − s‖²` and a right perturbation `R̂ Exp(δ)`, the gradient is `v̂ × s`
//! (`v̂ = R̂ᵀ d`), so the descent direction on the tangent space is `s × v̂`, summed over the
//! measurements and normalised. `β` keeps Madgwick's meaning, the norm of the correction's
//! quaternion rate, hence a correction rate of `2β` rad/s about `Σ s × v̂ / ‖Σ s × v̂‖`. The radial
//! part of his 4-vector gradient (which his renormalisation removes) is left out of the norm.
//!
//! **Floor on the normalisation** (`full_rate_angle_rad`, `θ₀`): the step is
//! `2β d/max(‖d‖, θ₀)`, `d = Σ s × v̂`. The normalised step turns the estimate at `2β` whatever the
//! gap, so a slowly growing gap (the low-passed specific force leaning under a sustained
//! acceleration) is followed at full rate until the acceleration gate's angle is reached, the
//! estimate by then ≈ 5° over (docs/filters.md, Limits). Below `θ₀` the step is proportional
//! (`2β/θ₀` per radian, as Mahony's `k_P`), so the gap grows to the gate while the estimate has
//! moved less; above it Madgwick's law is unchanged. The floor applies when the step has no field
//! term: the field's heading gap ψ enters `‖d‖` as `cos δ sin ψ` (dip δ, 67° on BROAD), so a shared
//! floor slowed the heading correction (9D mean 2.62° → 2.98° on BROAD).
//!
//! **Never past the measurements**: the step is at most `d/n` for `n` measurements (1 or 2): the
//! normalised law, integrated over the step, stops at the gap, and `d/n` is at most the gap (to
//! first order; one measurement: its sine). A step the gyro turns by more than
//! [`super::LONG_TURN_RAD`] is compared with the estimate turned by the gyro. Without the cap a gap in the stamps turned the
//! estimate by `2βρ` per second of it whatever the gap (a 5 s gap at rest on BROAD 01, 9D: 141°
//! off in the gain ramp, 20.8° after it; now 1.2° and 0.98°), and a gap below the step chattered about the measurement.

use nalgebra::Vector3;

use super::{check, over_norm, Law, Step};
use crate::Result;

/// Gain of the Madgwick filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Madgwick {
    /// `β` [1/s]: norm of the correction's quaternion rate (rotation rate `2β` rad/s).
    pub beta: f64,
    /// `θ₀` \[rad\]: the floor on the norm of the descent direction `‖Σ s × v̂‖` (the sine of the
    /// gap, for one measurement), so that below a gap of about `θ₀` the step is proportional,
    /// `2β ‖Σ s × v̂‖ / θ₀`, and above it Madgwick's full rate `2β`; 0 is his normalised step at
    /// every gap.
    pub full_rate_angle_rad: f64,
}

impl Default for Madgwick {
    /// `β = 0.035`, `θ₀ = 0.08` rad: the best point of `bench/tune_filters.py`'s grid on the 12 BROAD
    /// trials among those that hold a simulated 5 m/s² for 10 s and a 3 m/s² figure-eight below 2°
    /// of tilt (the textbook `θ₀ = 0` does not: 4.6° / 5.3° at this `β`); leave-one-group-out picks
    /// the same point in three folds of four (docs/filters_accuracy.md).
    fn default() -> Self {
        Self {
            beta: 0.035,
            full_rate_angle_rad: 0.08,
        }
    }
}

impl Law for Madgwick {
    type Extra = ();

    fn validate(&self) -> Result<()> {
        check("beta", self.beta, "finite and ≥ 0", |x| x >= 0.0)?;
        check(
            "full_rate_angle_rad",
            self.full_rate_angle_rad,
            "finite, in [0, 1]",
            |x| (0.0..=1.0).contains(&x),
        )
    }

    /// `ω_c dt = 2β ρ dt · d/max(‖d‖, θ₀)`, at most `d/n` (module docs); the bias is left to rest
    /// detection.
    #[inline(always)]
    fn correct(&self, step: &Step<'_>, bias: &mut Vector3<f64>, _: &mut ()) -> Vector3<f64> {
        // The field's gradient is not heading-only (it also turns the estimate's tilt): without
        // the gravity term it would tilt the estimate at the full 2β rate, so the magnetometer
        // is used only together with an accepted accelerometer sample.
        let mag_dir = if step.accel_dir.is_some() { step.mag_dir } else { None };
        let floor2 = if mag_dir.is_some() {
            0.0
        } else {
            self.full_rate_angle_rad * self.full_rate_angle_rad
        };
        let angle = 2.0 * self.beta * step.gain * step.dt;
        let (accel_dir, mag_dir) = (step.accel_dir.as_ref(), mag_dir.as_ref());
        let correction = match descent(&step.north_pred, &step.up_pred, accel_dir, mag_dir, floor2, angle) {
            Descent::Within(c) => c,
            Descent::Capped => capped(step, accel_dir, mag_dir),
        };
        if step.turned.is_some() {
            step.from_predictions(correction, bias, bias)
        } else {
            correction
        }
    }
}

/// A step of [`descent`].
enum Descent {
    /// The step, within the cap.
    Within(Vector3<f64>),
    /// The step reaches the cap: [`capped`] is it.
    Capped,
}

/// The correction `angle · d / max(‖d‖, θ₀)` along the descent direction `d` ([`direction`]), or
/// zero; [`Descent::Capped`] where it would turn past the measurements.
///
/// The cap (module docs): for a small gap `δ`, `d ≈ J δ` with `J` symmetric and positive
/// semi-definite, gravity's term `I − ŝ ŝᵀ` and the field's (its reference rebuilt from the
/// estimate) `p pᵀ` with `p ⊥ m̂` a unit vector, so `J`'s largest eigenvalue is at most the number
/// `n` of measurements (with both, `1 + sin(dip)` about an axis in the north–up plane, tight as the
/// dip nears 90°) and a step of `d / n` does not overshoot (one measurement: `d` is the
/// sine of the gap).
#[inline(always)]
fn descent(
    north_pred: &Vector3<f64>,
    up_pred: &Vector3<f64>,
    accel_dir: Option<&Vector3<f64>>,
    mag_dir: Option<&Vector3<f64>>,
    floor2: f64,
    angle: f64,
) -> Descent {
    let d = direction(north_pred, up_pred, accel_dir, mag_dir);
    let n2 = d.norm_squared().max(floor2);
    let n = measurements(accel_dir, mag_dir);
    if angle * angle * (n * n) > n2 {
        Descent::Capped
    } else if n2 > 1e-24 {
        Descent::Within(over_norm(&d, n2) * angle)
    } else {
        Descent::Within(Vector3::zeros())
    }
}

/// The descent direction `d = Σ s × v̂` (body frame). `north_pred`, `up_pred`: the world north and
/// up in body axes. The field reference `b = n_w ‖h_horizontal‖ + u_w h_up` seen from the body is
/// `v̂_m = n_pred ‖h_horizontal‖ + u_pred h_up`, with `h_up = m̂·u_pred`.
#[inline(always)]
fn direction(
    north_pred: &Vector3<f64>,
    up_pred: &Vector3<f64>,
    accel_dir: Option<&Vector3<f64>>,
    mag_dir: Option<&Vector3<f64>>,
) -> Vector3<f64> {
    let mut d = Vector3::zeros();
    if let Some(s) = accel_dir {
        d += s.cross(up_pred);
    }
    if let Some(m) = mag_dir {
        let vertical = m.dot(up_pred);
        let horizontal = (1.0 - vertical * vertical).max(0.0).sqrt();
        // `m × v̂_m` as `‖h_h‖ (m × n_pred) + h_up (m × u_pred)`: both products run beside the
        // square root instead of after it (the step's dependency chain; the same to rounding).
        d += m.cross(north_pred) * horizontal + m.cross(up_pred) * vertical;
    }
    d
}

/// The step at the cap, `d / n`, seen from `step`'s predictions.
#[cold]
#[inline(never)]
fn capped(step: &Step<'_>, accel_dir: Option<&Vector3<f64>>, mag_dir: Option<&Vector3<f64>>) -> Vector3<f64> {
    direction(&step.north_pred, &step.up_pred, accel_dir, mag_dir) / measurements(accel_dir, mag_dir)
}

/// The number of measurements in the step (the cap's `n`).
#[inline(always)]
fn measurements(accel_dir: Option<&Vector3<f64>>, mag_dir: Option<&Vector3<f64>>) -> f64 {
    f64::from(u8::from(accel_dir.is_some()) + u8::from(mag_dir.is_some()))
}
