//! Attitude filters: Mahony (explicit complementary filter) and Madgwick (gradient descent),
//! each 6D (gyro + accelerometer) or 9D (+ magnetometer).
//!
//! | item | convention |
//! |---|---|
//! | estimate | Hamilton `q_wb` (body → world) in [`World::Enu`] (x east, y north, z up) or [`World::Ned`] (x north, y east, z down); z is vertical in both |
//! | gyro | body rate ω [rad/s]; the estimate integrates `ω − b̂ + ω_c` by the exact exponential: `q ← q ⊗ Exp((ω − b̂ + ω_c) dt)` |
//! | accelerometer | specific force [m/s²]: at rest `R_wbᵀ (0, 0, +g)` in ENU, `R_wbᵀ (0, 0, −g)` in NED: it points **up** |
//! | magnetometer | any unit; `R_wbᵀ m_w`, north = +y (ENU) / +x (NED); only its direction is used, and its norm and dip for rejection |
//! | gains | Mahony `k_P` [1/s], `k_I` [1/s²]; Madgwick `β` [1/s] (quaternion-rate norm, rotation rate 2β) |
//! | step `k` | the correction `ω_c` is computed from the estimate after sample `k−1` and the measurements of sample `k`; then the exponential step over `dt = t_k − t_{k−1}` with `ω_k` |
//! | first sample | initialises the attitude ([`initial_attitude`]: tilt from the accelerometer, heading from the magnetometer, else ZYX yaw 0) unless an initial state is given; it is output as is |
//! | bias output | per sample: the estimate after that sample |
//! | ramp, rejection, rest | [`GainRamp`], [`AccelRejection`], [`MagRejection`], [`RestDetection`] |
//! | state | [`State`], `Copy`: save by copying, restore by assigning |
//!
//! Corrections (`s = a/‖a‖` measured up, `v̂_g = R̂ᵀ u_w`, `v̂_n = R̂ᵀ n_w` predicted up and north,
//! `m̂` the unit field, `ρ` the ramp factor):
//!
//! - Mahony (Mahony, Hamel & Pflimlin, IEEE TAC 2008, eq. 32): `ω_mes = s × v̂_g + v̂_g h_e/√(h_e² + h_n²)`
//!   (9D; `h_e = m̂·(v̂_n × v̂_g)`, `h_n = m̂·v̂_n`: heading only), `ω_c = k_P ρ ω_mes`,
//!   `b̂ ← b̂ − k_I ω_mes dt` (frozen during the ramp and while the accelerometer is rejected).
//! - Madgwick (Madgwick 2010 report; ICORR 2011): the tangent-space gradient of
//!   `½‖R̂ᵀ d − s‖²` is `v̂ × s`, so `g = s × v̂_g + m̂ × (‖h_h‖ v̂_n + h_up v̂_g)` and
//!   `ω_c = 2β ρ g/‖g‖` (β is Madgwick's quaternion-rate gain; the field term only with an accepted
//!   accelerometer sample, since it is not heading-only).
//!
//! ```
//! use imukit::filters::{Algorithm, Common, Filter, Mahony, State};
//! use nalgebra::Vector3;
//!
//! let f = Filter::new(Algorithm::Mahony(Mahony::default()), Common::default())?;
//! let mut s = State::default();
//! // A sensor rolled +90° about x at rest reads +g on its y axis (ENU); the first sample
//! // initialises, later ones correct.
//! for _ in 0..100 {
//!     f.update(&mut s, &Vector3::zeros(), &Vector3::new(0.0, 9.81, 0.0), None, 0.01)?;
//! }
//! let up_in_body = s.q.inverse() * Vector3::z();
//! assert!((up_in_body - Vector3::y()).norm() < 1e-12);
//! # Ok::<(), imukit::Error>(())
//! ```
//!
//! Nothing allocates per sample; NaN or infinite input is an [`Error::NonFinite`] naming the
//! sample, wrapped in [`Error::Argument`] naming the input (`t`, `gyro`, `accel`, `mag`); finite
//! input so large that the state overflows is an [`Error::Overflow`] naming the sample (the state
//! is then unusable and should be reset).

mod common;
mod madgwick;
mod mahony;

pub use common::{
    initial_attitude, AccelRejection, Common, GainRamp, MagRejection, RestDetection, State, World, STATE_LEN,
};
pub use madgwick::Madgwick;
pub use mahony::Mahony;

use nalgebra::Vector3;

use crate::quat::{exp, multiply};
use crate::{Error, Result};

/// The correction law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Algorithm {
    /// Mahony et al. 2008.
    Mahony(Mahony),
    /// Madgwick 2010.
    Madgwick(Madgwick),
}

/// A configured filter: gains and options. It holds no state; every call takes a [`State`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filter {
    algorithm: Algorithm,
    common: Common,
    cos_angle: f64,
    cos_dip: f64,
}

/// Samples of a batch run: flat row-major slices, `t` (n), `gyro`, `accel`, `mag` (3n).
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    /// Timestamps [s], strictly increasing.
    pub t: &'a [f64],
    /// Body rates [rad/s].
    pub gyro: &'a [f64],
    /// Specific force [m/s²].
    pub accel: &'a [f64],
    /// Magnetometer (9D), or None (6D).
    pub mag: Option<&'a [f64]>,
}

#[inline]
fn row(x: &[f64], k: usize) -> Vector3<f64> {
    Vector3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2])
}

#[inline]
fn finite(v: &Vector3<f64>) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// Finite input so large that the state overflowed (e.g. a gyro of 1e300 rad/s).
#[inline]
fn check_overflow(s: &State, index: usize) -> Result<()> {
    let sum = s.q.coords.sum() + s.bias.sum();
    if sum.is_finite() {
        Ok(())
    } else {
        Err(Error::Overflow { index })
    }
}

impl Filter {
    /// A filter with `algorithm`'s gains and the `common` options; errors on an option outside
    /// its domain.
    pub fn new(algorithm: Algorithm, common: Common) -> Result<Self> {
        match algorithm {
            Algorithm::Mahony(m) => {
                common::check("kp", m.kp, "finite and ≥ 0", |x| x >= 0.0)?;
                common::check("ki", m.ki, "finite and ≥ 0", |x| x >= 0.0)?;
            }
            Algorithm::Madgwick(m) => common::check("beta", m.beta, "finite and ≥ 0", |x| x >= 0.0)?,
        }
        common.validate()?;
        let cos_angle = common.accel_rejection.map_or(-1.0, |r| r.angle.cos());
        // cos is decreasing on [0, π], where |δ − δ₀| lies; a threshold beyond π rejects nothing.
        let cos_dip = common
            .mag_rejection
            .map_or(-1.0, |r| r.dip.min(std::f64::consts::PI).cos());
        Ok(Self {
            algorithm,
            common,
            cos_angle,
            cos_dip,
        })
    }

    /// The correction law.
    pub fn algorithm(&self) -> Algorithm {
        self.algorithm
    }

    /// The shared options.
    pub fn common(&self) -> &Common {
        &self.common
    }

    /// One sample. An uninitialised `state` is initialised from `accel` (and `mag`) and `dt` is
    /// ignored; otherwise `dt` [s] must be positive and finite. Errors name the argument.
    pub fn update(
        &self,
        state: &mut State,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        dt: f64,
    ) -> Result<()> {
        if !finite(gyro) {
            return Err(Error::NonFinite { index: 0 }.in_argument("gyro"));
        }
        if !finite(accel) {
            return Err(Error::NonFinite { index: 0 }.in_argument("accel"));
        }
        if mag.is_some_and(|m| !finite(m)) {
            return Err(Error::NonFinite { index: 0 }.in_argument("mag"));
        }
        if state.initialized && !(dt > 0.0 && dt.is_finite()) {
            return Err(Error::Parameter {
                name: "dt",
                expected: "a positive finite step [s]",
                got: format!("{dt}"),
            });
        }
        self.step(state, gyro, accel, mag, dt);
        check_overflow(state, 0)
    }

    /// The update proper, on validated input.
    fn step(&self, s: &mut State, gyro: &Vector3<f64>, accel: &Vector3<f64>, mag: Option<&Vector3<f64>>, dt: f64) {
        match self.algorithm {
            Algorithm::Mahony(m) => self.step_impl::<true>(s, gyro, accel, mag, dt, [m.kp, m.ki]),
            Algorithm::Madgwick(m) => self.step_impl::<false>(s, gyro, accel, mag, dt, [m.beta, 0.0]),
        }
    }

    /// [`Filter::step`] for one law, so that a batch loop is compiled per law without branches
    /// on it: `gains` is `[k_P, k_I]` (Mahony) or `[β, 0]` (Madgwick).
    #[inline(always)]
    fn step_impl<const MAHONY: bool>(
        &self,
        s: &mut State,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        dt: f64,
        gains: [f64; 2],
    ) {
        let c = &self.common;
        if !s.initialized {
            s.q = initial_attitude(c.world, accel, mag);
            s.initialized = true;
            if let Some(m) = mag {
                let mn = m.norm();
                if mn > 0.0 {
                    let up_pred = c.world.predicted(&s.q).1;
                    s.mag_norm = mn;
                    (s.mag_dip_sin, s.mag_dip_cos) = common::dip(m, mn, &up_pred);
                }
            }
            return;
        }
        let ramping = s.ramp_elapsed < c.ramp.duration;
        let gain = c.ramp_gain(s.ramp_elapsed);
        let (north_pred, up_pred) = c.world.predicted(&s.q);

        // Accelerometer: accept, reject, or recover (restart the ramp).
        let an = accel.norm();
        let mut accel_dir = None;
        if an > 1e-9 {
            let dir = accel * (1.0 / an);
            let accept = ramping
                || match c.accel_rejection {
                    None => true,
                    Some(r) => (an - c.gravity).abs() <= r.norm && dir.dot(&up_pred) >= self.cos_angle,
                };
            if accept {
                s.accel_rejected = 0.0;
                accel_dir = Some(dir);
            } else {
                s.accel_rejected += dt;
                if let Some(r) = c.accel_rejection {
                    if s.accel_rejected >= r.recovery {
                        s.accel_rejected = 0.0;
                        s.ramp_elapsed = 0.0;
                        accel_dir = Some(dir);
                    }
                }
            }
        }

        // Magnetometer: learn the reference once, then accept, reject, or re-learn.
        let mut mag_dir = None;
        if let Some(m) = mag {
            let mn = m.norm();
            if mn > 0.0 {
                let (dip_sin, dip_cos) = common::dip(m, mn, &up_pred);
                if s.mag_norm <= 0.0 {
                    s.mag_norm = mn;
                    (s.mag_dip_sin, s.mag_dip_cos) = (dip_sin, dip_cos);
                }
                let accept = ramping
                    || match c.mag_rejection {
                        None => true,
                        Some(r) => {
                            (mn - s.mag_norm).abs() <= r.norm * s.mag_norm
                                && dip_cos * s.mag_dip_cos + dip_sin * s.mag_dip_sin >= self.cos_dip
                        }
                    };
                if accept {
                    s.mag_rejected = 0.0;
                    mag_dir = Some(m * (1.0 / mn));
                } else {
                    s.mag_rejected += dt;
                    if let Some(r) = c.mag_rejection {
                        if s.mag_rejected >= r.recovery {
                            s.mag_rejected = 0.0;
                            s.mag_norm = mn;
                            (s.mag_dip_sin, s.mag_dip_cos) = (dip_sin, dip_cos);
                            mag_dir = Some(m * (1.0 / mn));
                        }
                    }
                }
            }
        }

        // Rest detection: bias low pass towards the raw gyro.
        if let Some(r) = c.rest {
            if gyro.norm() < r.gyro && (an - c.gravity).abs() < r.accel {
                s.rest += dt;
            } else {
                s.rest = 0.0;
            }
            if s.rest >= r.duration {
                s.bias += (gyro - s.bias) * (dt / r.tau).min(1.0);
            }
        }

        // Correction as a rotation over the step, ω_c dt (scalars folded off the critical path).
        let correction_dt = if MAHONY {
            let e = mahony::error(&north_pred, &up_pred, accel_dir.as_ref(), mag_dir.as_ref());
            // The integral only learns while gravity is observed: the magnetometer alone measures
            // heading about the estimated vertical, and integrating that (in body axes, while the
            // body turns) into the bias would tilt the estimate.
            if !ramping && accel_dir.is_some() {
                s.bias -= e * (gains[1] * dt);
            }
            e * (gains[0] * gain * dt)
        } else {
            // The field's gradient is not heading-only (it also turns the estimate's tilt): without
            // the gravity term it would tilt the estimate at the full 2β rate, so the magnetometer
            // is used only together with an accepted accelerometer sample.
            let mag_dir = if accel_dir.is_some() { mag_dir } else { None };
            madgwick::direction(&north_pred, &up_pred, accel_dir.as_ref(), mag_dir.as_ref())
                * (2.0 * gains[0] * gain * dt)
        };

        // One Newton step towards |q| = 1 without a square root, computed from q_k (|q_k ⊗ E| =
        // |q_k| for a unit E), so it stays off the dependency chain: the exact exponential keeps
        // the norm to rounding, this only stops the rounding from accumulating.
        let renorm = 0.5 * (3.0 - s.q.norm_squared());
        let q = multiply(
            s.q.quaternion(),
            exp(&((gyro - s.bias) * dt + correction_dt)).quaternion(),
        );
        s.q = nalgebra::UnitQuaternion::new_unchecked(q * renorm);
        s.time += dt;
        if ramping {
            s.ramp_elapsed += dt;
        }
    }

    /// Runs over `inputs`, writing `q_wb` (`[x, y, z, w]`, 4n) and the bias after each sample (3n).
    ///
    /// With `continued` false the first sample initialises an uninitialised `state`, or, for an
    /// initialised one (an initial attitude), is output as is and sets `state.time`; with
    /// `continued` true the state is the end of an earlier run and the first sample is a step
    /// over `t[0] − state.time`. `state` ends as the state after the last sample.
    pub fn run(
        &self,
        state: &mut State,
        inputs: &Inputs<'_>,
        continued: bool,
        out_q: &mut [f64],
        out_bias: &mut [f64],
    ) -> Result<()> {
        let n = inputs.t.len();
        for (name, x, width) in [
            ("gyro", inputs.gyro, 3),
            ("accel", inputs.accel, 3),
            ("mag", inputs.mag.unwrap_or(&[]), 3),
        ] {
            if name == "mag" && inputs.mag.is_none() {
                continue;
            }
            if x.len() != n * width {
                return Err(Error::RowCount {
                    input: n,
                    output: x.len() / width,
                }
                .in_argument(name));
            }
        }
        if out_q.len() != 4 * n || out_bias.len() != 3 * n {
            return Err(Error::RowCount {
                input: n,
                output: out_q.len() / 4,
            });
        }
        if continued && !state.initialized {
            return Err(Error::Parameter {
                name: "initial",
                expected: "an initialised state to continue from",
                got: "an uninitialised state".into(),
            });
        }
        match (self.algorithm, inputs.mag.is_some()) {
            (Algorithm::Mahony(m), false) => {
                self.run_loop::<true, false>(state, inputs, continued, out_q, out_bias, [m.kp, m.ki])
            }
            (Algorithm::Mahony(m), true) => {
                self.run_loop::<true, true>(state, inputs, continued, out_q, out_bias, [m.kp, m.ki])
            }
            (Algorithm::Madgwick(m), false) => {
                self.run_loop::<false, false>(state, inputs, continued, out_q, out_bias, [m.beta, 0.0])
            }
            (Algorithm::Madgwick(m), true) => {
                self.run_loop::<false, true>(state, inputs, continued, out_q, out_bias, [m.beta, 0.0])
            }
        }
    }

    /// The batch loop for one law and one sensor set (checked inputs).
    fn run_loop<const MAHONY: bool, const NINE: bool>(
        &self,
        state: &mut State,
        inputs: &Inputs<'_>,
        continued: bool,
        out_q: &mut [f64],
        out_bias: &mut [f64],
        gains: [f64; 2],
    ) -> Result<()> {
        let n = inputs.t.len();
        let mags = inputs.mag.unwrap_or(&[]);
        let mut previous = state.time;
        for k in 0..n {
            let t = inputs.t[k];
            let gyro = row(inputs.gyro, k);
            let accel = row(inputs.accel, k);
            let mag = if NINE { Some(row(mags, k)) } else { None };
            // One test on the sum (NaN and ±inf propagate); only when it fails, find the culprit
            // (a finite sum overflowing to inf is no error).
            let sum = t + gyro.sum() + accel.sum() + mag.map_or(0.0, |m| m.sum());
            if !sum.is_finite() {
                if !t.is_finite() {
                    return Err(Error::NonFinite { index: k }.in_argument("t"));
                }
                if !finite(&gyro) {
                    return Err(Error::NonFinite { index: k }.in_argument("gyro"));
                }
                if !finite(&accel) {
                    return Err(Error::NonFinite { index: k }.in_argument("accel"));
                }
                if mag.as_ref().is_some_and(|m| !finite(m)) {
                    return Err(Error::NonFinite { index: k }.in_argument("mag"));
                }
            }
            if k == 0 && !continued {
                if state.initialized {
                    state.time = t;
                } else {
                    self.step_impl::<MAHONY>(state, &gyro, &accel, mag.as_ref(), 0.0, gains);
                    state.time = t;
                }
            } else {
                let dt = t - previous;
                if dt.is_nan() || dt <= 0.0 {
                    return Err(Error::NonIncreasingTime { index: k, dt }.in_argument("t"));
                }
                self.step_impl::<MAHONY>(state, &gyro, &accel, mag.as_ref(), dt, gains);
                check_overflow(state, k)?;
                // Keep the stamp itself (summing the steps would drift from it by rounding).
                state.time = t;
            }
            previous = t;
            out_q[4 * k..4 * k + 4].copy_from_slice(state.q.coords.as_slice());
            out_bias[3 * k..3 * k + 3].copy_from_slice(state.bias.as_slice());
        }
        Ok(())
    }
}
