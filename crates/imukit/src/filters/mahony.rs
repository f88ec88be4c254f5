//! Mahony's explicit complementary filter on SO(3) (Mahony, Hamel & Pflimlin, "Nonlinear
//! complementary filters on the special orthogonal group", IEEE TAC 53(5), 2008, §V eq. 32):
//!
//! `ω_mes = Σ k_i v_i × v̂_i`, `Ṙ̂ = R̂ [ω_y − b̂ + k_P ω_mes]×`, `ḃ̂ = −k_I ω_mes`,
//!
//! with `v_i` the measured and `v̂_i = R̂ᵀ v₀ᵢ` the predicted body directions (unit vectors).
//! imukit uses `k_a = 1` for gravity; the magnetometer (9D) enters only about the vertical: its
//! world-frame horizontal direction `ĥ` is compared with north, `e = R̂ᵀ (ĥ × n_w)`, so a magnetic
//! disturbance can never tilt the estimate (the same `v × v̂` form, written in world axes with the
//! field's vertical part removed).
//!
//! **Long steps**: the proportional law decays a gap at the rate `k_P ρ`, so a step with
//! `k_P ρ dt > 1` (a gap in the stamps) would turn the estimate past the measurement. Such a step
//! lands on the measurement instead (to first order: `ω_mes` holds each gap's sine), the integral
//! stepping over the decay's time `1/(k_P ρ)`. A step with `k_P ρ dt > 0.1` levels before it takes
//! the field's heading error; a step the gyro turns by more than [`super::LONG_TURN_RAD`] is seen
//! from the estimate turned by the gyro. At a normal rate the law is the textbook one, bit for bit.

use nalgebra::{UnitQuaternion, Vector3};

use super::{check, over_norm, turned_predictions, Law, Step};
use crate::Result;

/// Gains of the Mahony filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mahony {
    /// Proportional gain `k_P` [1/s] (rad/s of correction per unit of `v × v̂`).
    pub kp: f64,
    /// Integral gain `k_I` [1/s²] of the gyro-bias estimate; 0 disables it.
    pub ki: f64,
}

impl Default for Mahony {
    /// `k_P = 0.3`, `k_I = 0.01`: tuned on the 12 BROAD trials with the default options
    /// (`bench/tune_filters.py`, leave-one-group-out scores in `docs/filters_accuracy.md`): a
    /// crossover near 0.3 rad/s and a bias time constant `k_P / k_I = 30` s.
    fn default() -> Self {
        Self { kp: 0.3, ki: 0.01 }
    }
}

/// `sin²` of the heading error (5°) beyond which the integral takes it for a step of the field
/// rather than a bias: a vertical bias `b` holds the heading `b / k_P` off, so at the default
/// `k_P = 0.3` the integral learns vertical biases up to 0.026 rad/s from the field; a larger one
/// only at rest ([`super::RestDetection`]).
const HEADING_STEP_SIN2: f64 = 0.007_596_123_493_895_969;

/// The gain per step `k = k_P ρ dt` beyond which a step levels before it takes the field's heading
/// error ([`Mahony::long_step`]): taken together, the tilt's leak into the heading error,
/// `k tan(dip)` per radian of tilt, turns the heading past its measurement once it exceeds
/// `(1 − k)` times the heading's gap; at a normal rate (`k` ≈ 1e-3) a transient the next steps
/// absorb, and the textbook law is kept there bit for bit.
const LONG_K: f64 = 0.1;

impl Law for Mahony {
    type Extra = ();

    fn validate(&self) -> Result<()> {
        check("kp", self.kp, "finite and ≥ 0", |x| x >= 0.0)?;
        check("ki", self.ki, "finite and ≥ 0", |x| x >= 0.0)
    }

    /// `ω_c dt = k_P ρ ω_mes dt`, and `b̂ ← b̂ − k_I ω_mes dt`; where `k_P ρ dt > 0.1`, the long
    /// step (module docs).
    #[inline(always)]
    fn correct(&self, step: &Step<'_>, bias: &mut Vector3<f64>, _: &mut ()) -> Vector3<f64> {
        let k = self.kp * step.gain * step.dt;
        if k > LONG_K || step.turned.is_some() {
            return self.long_step(step, bias, k);
        }
        let (e_acc, e_mag) = errors(
            &step.north_pred,
            &step.east_pred,
            &step.up_pred,
            step.accel_dir.as_ref(),
            step.mag_dir.as_ref(),
        );
        self.integrate(step, bias, &e_acc, &e_mag, step.dt);
        (e_acc + e_mag) * k
    }
}

impl Mahony {
    /// A step with `k_P ρ dt > 0.1` ([`LONG_K`]; a gap in the stamps, a slow stream), or one the
    /// gyro turns far ([`Step::turned`]: its predictions are then the turned estimate's). The
    /// proportional law decays a gap at the rate `k_P ρ`, so a step of `k = k_P ρ dt > 1` would
    /// turn the estimate past the measurement (`ω_mes` is each gap's sine); capped at `k = 1` it
    /// lands on the measurement to first order. The step levels by `k e_acc`, then turns in
    /// heading by `k` times the field's error seen from the levelled estimate (from the tilted one
    /// the field's vertical part leaks into the heading error, `tan(dip)` per radian of tilt,
    /// which a full step would take as heading). The integral sees the time the decay takes,
    /// `1/(k_P ρ)`, not the gap's length (`∫ gap dt` over the decay). A 5 s gap at rest on BROAD
    /// 01 (9D) left the estimate 13.6° off the uninterrupted run in the gain ramp and 7.8° after
    /// it with the step unbounded; landing on one sample leaves that sample's noise (2.5° and
    /// 4.4°: BROAD's field is noisy in heading, the filter's averaging then resumes).
    #[cold]
    #[inline(never)]
    fn long_step(&self, step: &Step<'_>, bias: &mut Vector3<f64>, k: f64) -> Vector3<f64> {
        let (k, dt) = if k > 1.0 {
            (1.0, 1.0 / (self.kp * step.gain))
        } else {
            (k, step.dt)
        };
        let (n, e, u) = (&step.north_pred, &step.east_pred, &step.up_pred);
        let (e_acc, _) = errors(n, e, u, step.accel_dir.as_ref(), None);
        let (level, (n, e, u)) = turned_predictions(&(e_acc * k), (n, e, u));
        let (_, e_mag) = errors(&n, &e, &u, None, step.mag_dir.as_ref());
        let before = *bias;
        self.integrate(step, bias, &e_acc, &e_mag, dt);
        step.from_predictions(
            (level * UnitQuaternion::from_scaled_axis(e_mag * k)).scaled_axis(),
            &before,
            bias,
        )
    }

    /// The integral's step over `dt` from the accelerometer's and the field's errors.
    #[inline(always)]
    fn integrate(&self, step: &Step<'_>, bias: &mut Vector3<f64>, e_acc: &Vector3<f64>, e_mag: &Vector3<f64>, dt: f64) {
        // The integral only learns while gravity is observed: the magnetometer alone measures
        // heading about the estimated vertical, and integrating that (in body axes, while the
        // body turns) into the bias would tilt the estimate. Nor from a sample let through by the
        // drift rule: handheld accelerations keep the filtered vector beyond the angle gate for
        // seconds with its norm near g (the integral wound up to 7e-3 rad/s on `handheld`).
        // Nor from a heading error beyond 5°:
        // that is a step of the field (a re-learned reference after a disturbance), not a bias,
        // and integrated at k_I it wound the vertical bias up to 0.044 rad/s on the x-io handheld
        // example ([`HEADING_STEP_SIN2`]).
        if !step.ramping && !step.drifting && step.accel_dir.is_some() {
            let e = if e_mag.norm_squared() > HEADING_STEP_SIN2 {
                *e_acc
            } else {
                e_acc + e_mag
            };
            *bias -= e * (self.ki * dt);
        }
    }
}

/// `v × v̂` of the accepted accelerometer and magnetometer samples (body frame), zero for one not
/// accepted. `north_pred`, `east_pred`, `up_pred` are the world north, east and up in body axes
/// (`R̂ᵀ n_w`, `R̂ᵀ e_w`, `R̂ᵀ u_w`).
///
/// Magnetometer: with `h = R̂ m̂`, its east and north parts are `m̂·e_pred`, `m̂·n_pred`, and `ĥ_horizontal × n_w = u_w h_e / √(h_e² + h_n²)`; in body axes `u_pred h_e/…`.
#[inline(always)]
fn errors(
    north_pred: &Vector3<f64>,
    east_pred: &Vector3<f64>,
    up_pred: &Vector3<f64>,
    accel_dir: Option<&Vector3<f64>>,
    mag_dir: Option<&Vector3<f64>>,
) -> (Vector3<f64>, Vector3<f64>) {
    let e_acc = accel_dir.map_or_else(Vector3::zeros, |s| s.cross(up_pred));
    let mut e_mag = Vector3::zeros();
    if let Some(m) = mag_dir {
        let h_north = m.dot(north_pred);
        let h_east = m.dot(east_pred);
        let r2 = h_north * h_north + h_east * h_east;
        if r2 > 1e-18 {
            e_mag = over_norm(&(up_pred * h_east), r2);
        }
    }
    (e_acc, e_mag)
}
