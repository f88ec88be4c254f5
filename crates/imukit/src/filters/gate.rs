//! The accept / reject / recover gate, written once and used for the accelerometer and the
//! magnetometer.
//!
//! | step | rule |
//! |---|---|
//! | accept | during the gain ramp, with no rejection configured, or when the sample passes its test; the rejection clock restarts |
//! | reject | otherwise: the rejection clock advances by `dt` and the sample is not used |
//! | recover | once the clock reaches `recovery_s`: the clock restarts and the sample is used; the caller resets what the gate protects (the accelerometer restarts the gain ramp, the magnetometer re-learns its reference field) |
//!
//! Tests: accelerometer, `|‖a‖ − g| ≤ norm` on the raw sample and `∠(a, up_pred) ≤ angle_rad` on
//! the vector the law uses (the filtered one with [`super::AccelLowPass`]); magnetometer,
//! `|‖m‖ − m₀| ≤ norm_fraction · m₀` and `|δ − δ₀| ≤ dip_rad` against the reference `m₀`, `δ₀`
//! learned from the first field sample.

use nalgebra::Vector3;

use super::options::{AccelRejection, MagRejection};
use super::state::CommonState;

/// What a gate decided about one sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Verdict {
    Accept,
    Reject,
    Recover,
}

/// The gate proper: `rejected` is its clock \[s\], `recovery_s` None when no rejection is
/// configured, `passes` the sample's test given the clock (only evaluated when it matters).
#[inline(always)]
fn decide(
    rejected: &mut f64,
    recovery_s: Option<f64>,
    ramping: bool,
    dt: f64,
    passes: impl FnOnce(f64) -> bool,
) -> Verdict {
    let Some(recovery_s) = recovery_s else {
        *rejected = 0.0;
        return Verdict::Accept;
    };
    if ramping || passes(*rejected) {
        *rejected = 0.0;
        Verdict::Accept
    } else {
        *rejected += dt;
        if *rejected >= recovery_s {
            *rejected = 0.0;
            Verdict::Recover
        } else {
            Verdict::Reject
        }
    }
}

/// Thresholds of both gates, with their cosines computed once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Gates {
    accel: Option<AccelRejection>,
    mag: Option<MagRejection>,
    gravity: f64,
    cos_angle: f64,
    cos_dip: f64,
    /// `|‖a‖ − g| ≤ norm` as `raw_lo² ≤ ‖a‖² ≤ raw_hi²` (no square root of the raw sample).
    raw_lo2: f64,
    raw_hi2: f64,
}

impl Gates {
    pub(crate) fn new(accel: Option<AccelRejection>, mag: Option<MagRejection>, gravity: f64) -> Self {
        Self {
            accel,
            mag,
            gravity,
            cos_angle: accel.map_or(-1.0, |r| r.angle_rad.cos()),
            // cos is decreasing on [0, π], where |δ − δ₀| lies; a threshold beyond π rejects nothing.
            cos_dip: mag.map_or(-1.0, |r| r.dip_rad.min(std::f64::consts::PI).cos()),
            raw_lo2: accel.map_or(0.0, |r| (gravity - r.norm).max(0.0).powi(2)),
            raw_hi2: accel.map_or(0.0, |r| (gravity + r.norm).powi(2)),
        }
    }

    /// The unit direction of `accel` (the vector the law uses, `norm_sq` its squared norm; a zero
    /// one is never used) if the sample is used. With a low pass, `raw_sq` is the unfiltered
    /// sample's squared norm and the norm test is on it: a sustained acceleration changes the raw norm at
    /// once, while the filtered vector turns slowly and a law whose correction rate does not
    /// shrink with the error (Madgwick's) would follow it below any angle threshold; the angle
    /// test stays on the filtered vector, since the raw direction swings with every movement of
    /// the hand. A recovery restarts the gain ramp.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // the vector, both norms, the prediction and the clock
    pub(crate) fn accelerometer(
        &self,
        s: &mut CommonState,
        accel: &Vector3<f64>,
        norm_sq: f64,
        raw_sq: f64,
        up_pred: &Vector3<f64>,
        ramping: bool,
        dt: f64,
    ) -> Option<Vector3<f64>> {
        let accel_norm = norm_sq.sqrt();
        // Written as `>` so that a NaN norm, like a zero one, is never used.
        let usable = accel_norm > 1e-9;
        if !usable {
            return None;
        }
        // A finite sample whose squared norm overflows (1e300 m/s²) keeps `a / ‖a‖ = 0` (unused
        // by the law), where `(a / ‖a‖²) ‖a‖` would be `0 · ∞`.
        let dir = if norm_sq.is_finite() {
            super::over_norm(accel, norm_sq)
        } else {
            accel * (1.0 / accel_norm)
        };
        let verdict = decide(
            &mut s.accel_rejected,
            self.accel.map(|r| r.recovery_s),
            ramping,
            dt,
            |rejected| {
                self.accel.is_some_and(|r| {
                    let calm = (accel_norm - self.gravity).abs() <= r.filtered_norm;
                    s.accel_calm = if calm { s.accel_calm + dt } else { 0.0 };
                    if dir.dot(up_pred) >= self.cos_angle {
                        s.accel_drift = false;
                    } else if rejected >= r.drift_s && s.accel_calm >= r.drift_s {
                        s.accel_drift = true;
                    }
                    let angle = s.accel_drift || dir.dot(up_pred) >= self.cos_angle;
                    (self.raw_lo2..=self.raw_hi2).contains(&raw_sq) && calm && angle
                })
            },
        );
        match verdict {
            Verdict::Accept => Some(dir),
            Verdict::Reject => None,
            Verdict::Recover => {
                s.ramp_elapsed = 0.0;
                Some(dir)
            }
        }
    }

    /// The unit field direction if the sample is used. The reference (norm, dip) is learned from
    /// the first usable sample and re-learned on a recovery.
    #[inline(always)]
    pub(crate) fn magnetometer(
        &self,
        s: &mut CommonState,
        mag: &Vector3<f64>,
        up_pred: &Vector3<f64>,
        ramping: bool,
        dt: f64,
    ) -> Option<Vector3<f64>> {
        let norm = mag.norm();
        let usable = norm > 0.0;
        if !usable {
            return None;
        }
        let inv = 1.0 / norm;
        let (dip_sin, dip_cos) = dip_scaled(mag, inv, up_pred);
        if s.mag_norm <= 0.0 {
            learn(s, norm, dip_sin, dip_cos);
        }
        let (reference, ref_sin, ref_cos) = (s.mag_norm, s.mag_dip_sin, s.mag_dip_cos);
        let verdict = decide(&mut s.mag_rejected, self.mag.map(|r| r.recovery_s), ramping, dt, |_| {
            self.mag.is_some_and(|r| {
                (norm - reference).abs() <= r.norm_fraction * reference
                    && dip_cos * ref_cos + dip_sin * ref_sin >= self.cos_dip
            })
        });
        match verdict {
            Verdict::Accept => Some(mag * inv),
            Verdict::Reject => None,
            Verdict::Recover => {
                learn(s, norm, dip_sin, dip_cos);
                Some(mag * inv)
            }
        }
    }
}

/// Takes the field of this sample as the magnetometer's reference.
#[inline(always)]
pub(crate) fn learn(s: &mut CommonState, norm: f64, dip_sin: f64, dip_cos: f64) {
    s.mag_norm = norm;
    (s.mag_dip_sin, s.mag_dip_cos) = (dip_sin, dip_cos);
}

/// `(sin δ, cos δ)` of the dip angle δ of `m` (body) below the horizontal, given the body
/// direction of up (δ ∈ [−π/2, π/2], so cos δ ≥ 0).
#[inline]
pub(crate) fn dip(m: &Vector3<f64>, m_norm: f64, up_b: &Vector3<f64>) -> (f64, f64) {
    dip_scaled(m, 1.0 / m_norm, up_b)
}

/// [`dip`] for a field already in a frame whose up is z: the dot with up is `m.z` (the same
/// value; the two products by 0 were a quarter of the dip's instructions in the robust 9D step).
#[inline(always)]
pub(crate) fn dip_z_up(m: &Vector3<f64>, m_norm: f64) -> (f64, f64) {
    dip_of(m.z, 1.0 / m_norm)
}

/// [`dip`] given `1/‖m‖` (the gate divides once for the dip and the direction).
#[inline(always)]
fn dip_scaled(m: &Vector3<f64>, inv_norm: f64, up_b: &Vector3<f64>) -> (f64, f64) {
    dip_of(m.dot(up_b), inv_norm)
}

/// `(sin δ, cos δ)` from the field's component along up and `1/‖m‖`.
#[inline(always)]
fn dip_of(m_up: f64, inv_norm: f64) -> (f64, f64) {
    let s = (-m_up * inv_norm).clamp(-1.0, 1.0);
    (s, (1.0 - s * s).sqrt())
}
