//! Attitude filters: one generic [`Filter<L>`] around a correction [`Law`]: Mahony (explicit
//! complementary filter) and Madgwick (gradient descent), each 6D (gyro + accelerometer) or 9D
//! (+ magnetometer).
//!
//! | item | convention |
//! |---|---|
//! | estimate | Hamilton `q_wb` (body → world) in [`World::Enu`] (x east, y north, z up) or [`World::Ned`] (x north, y east, z down); z is vertical in both |
//! | gyro | body rate ω [rad/s]; the estimate integrates `ω − b̂ + ω_c` by the exact exponential: `q ← q ⊗ Exp((ω − b̂ + ω_c) dt)` |
//! | accelerometer | specific force [m/s²]: at rest `R_wbᵀ (0, 0, +g)` in ENU, `R_wbᵀ (0, 0, −g)` in NED: it points **up** |
//! | magnetometer | any unit; `R_wbᵀ m_w`, north = +y (ENU) / +x (NED); only its direction is used, and its norm and dip for rejection |
//! | gains | Mahony `k_P` [1/s], `k_I` [1/s²]; Madgwick `β` [1/s] (quaternion-rate norm, rotation rate 2β) |
//! | step `k` | the correction `ω_c` is computed from the estimate after sample `k−1` and the measurements of sample `k`; then the exponential step over `dt = t_k − t_{k−1}` with `ω_k`. A step whose correction would turn past the measurement (a gap in the stamps) is capped there; a step the gyro turns by more than [`LONG_TURN_RAD`] is compared, gates included, with the estimate turned by `ω_k` ([`Step::turned`]) |
//! | first sample | initialises the attitude ([`initial_attitude`]: tilt from the accelerometer, heading from the magnetometer, else ZYX yaw 0) unless an initial state is given; it is output as is |
//! | bias output | per sample: the estimate after that sample |
//! | a field slower than the gyro | [`Filter::update`] without a field uses the last field sample turned by the gyro, for up to [`MAG_HOLD_S`] ([`FieldHold`]); [`Filter::run`] takes one field row per sample |
//! | ramp, rejection, rest | [`GainRamp`], [`AccelRejection`], [`MagRejection`], [`RestDetection`] in [`Options`]; the accept / reject / recover rule of both sensors in [`gate`] |
//! | state | [`State<L>`]: [`CommonState`] plus the law's own [`Law::Extra`], `Copy`: save by copying, restore by assigning; it records its world, and a filter of the other world turns the attitude into its own ([`CommonState::express_in`]) |
//!
//! The seam: a law is a `Copy` value (its gains) implementing [`Law`]: [`Law::validate`] its gains
//! and [`Law::correct`], which sees one gated sample ([`Step`]: the predicted and the accepted
//! directions, the ramp multiplier) and returns the correction rotation `ω_c dt`, updating the
//! bias and its own state. Initialisation, the gates, the ramp, rest detection, the exponential
//! step, the checks and the batch loop are [`Filter`]'s, compiled once per law (no dynamic
//! dispatch in the loop). A new law is a new `impl Law`; no existing law changes
//! (`crates/imukit/tests/filter_law.rs` adds a gyro-only one from outside the crate).
//!
//! Corrections (`s = a/‖a‖` measured up, `v̂_g = R̂ᵀ u_w`, `v̂_n = R̂ᵀ n_w` predicted up and north,
//! `m̂` the unit field, `ρ` the ramp factor):
//!
//! - Mahony (Mahony, Hamel & Pflimlin, IEEE TAC 2008, eq. 32): `ω_mes = s × v̂_g + v̂_g h_e/√(h_e² + h_n²)`
//!   (9D; `h_e = m̂·(v̂_n × v̂_g)`, `h_n = m̂·v̂_n`: heading only), `ω_c = k_P ρ ω_mes`,
//!   `b̂ ← b̂ − k_I ω_mes dt` (frozen during the ramp and while the accelerometer is rejected);
//!   a step with `k_P ρ dt > 1` lands on the measurement (to first order: `ω_mes` holds each gap's
//!   sine), the integral over `1/(k_P ρ)`.
//! - Madgwick (Madgwick 2010 report; ICORR 2011): the tangent-space gradient of
//!   `½‖R̂ᵀ d − s‖²` is `v̂ × s`, so `g = s × v̂_g + m̂ × (‖h_h‖ v̂_n + h_up v̂_g)` and
//!   `ω_c = 2β ρ g/‖g‖` (β is Madgwick's quaternion-rate gain; the field term only with an accepted
//!   accelerometer sample, since it is not heading-only), at most `g/n` for `n` measurements.
//!
//! ```
//! use imukit::filters::{Filter, Mahony, Options, State};
//! use nalgebra::Vector3;
//!
//! let f = Filter::new(Mahony::default(), Options::default())?;
//! let mut s = State::default();
//! // A sensor rolled +90° about x at rest reads +g on its y axis (ENU); the first sample
//! // initialises, later ones correct.
//! for _ in 0..100 {
//!     f.update(&mut s, &Vector3::zeros(), &Vector3::new(0.0, 9.81, 0.0), None, 0.01)?;
//! }
//! let up_in_body = s.common.q.inverse() * Vector3::z();
//! assert!((up_in_body - Vector3::y()).norm() < 1e-12);
//! # Ok::<(), imukit::Error>(())
//! ```
//!
//! Nothing allocates per sample; NaN or infinite input is an [`Error::NonFinite`] naming the
//! sample, wrapped in [`Error::Argument`] naming the input (`t`, `gyro`, `accel`, `mag`); finite
//! input so large that the state overflows is an [`Error::Overflow`] naming the sample (the state
//! is then unusable and should be reset).

pub mod gate;
mod madgwick;
mod mahony;
mod options;
mod robust;
mod state;
mod world;

pub use madgwick::Madgwick;
pub use mahony::Mahony;
pub use options::{check, AccelLowPass, AccelRejection, GainRamp, MagRejection, Options, RestDetection};
pub use robust::{Outputs as RobustOutputs, Robust, RobustParams, RobustState, Track as RobustTrack};
pub use state::{CommonState, FieldHold, Fields, State};
pub use world::{initial_attitude, World};

use nalgebra::{UnitQuaternion, Vector3};

use crate::quat::{exp_step, multiply_exp_step};

/// The default of [`Options::mag_hold_s`] and [`RobustParams::mag_hold_s`]: seconds a streamed
/// field sample stands for the samples after it that have none ([`FieldHold`]). A field at 1 Hz
/// or faster corrects the heading at its full gain; the gyro's turn over a second moves the held
/// field by the bias error times a second.
pub const MAG_HOLD_S: f64 = 1.0;
use crate::{Cancel, Error, Result};
use gate::Gates;

/// A correction law: its gains (a `Copy` value) and how one gated sample corrects the estimate.
pub trait Law: Copy + std::fmt::Debug + PartialEq + Send + Sync {
    /// The law's own state, beyond [`CommonState`] (`()` for none).
    type Extra: Copy + Default + std::fmt::Debug + PartialEq + Send + Sync + Fields;

    /// Checks the gains ([`check`] names each one); [`Filter::new`] calls it.
    fn validate(&self) -> Result<()>;

    /// The correction rotation `ω_c dt` \[rad\] of one step. May update the gyro-bias estimate
    /// `bias` (subtracted from the gyro in this step's exponential) and the law's own state.
    fn correct(&self, step: &Step<'_>, bias: &mut Vector3<f64>, extra: &mut Self::Extra) -> Vector3<f64>;
}

/// One sample as a law sees it, after the gates.
#[derive(Debug, Clone, Copy)]
pub struct Step<'a> {
    /// The estimate after the previous sample.
    pub q: &'a UnitQuaternion<f64>,
    /// World north in body axes, `R̂ᵀ n_w`.
    pub north_pred: Vector3<f64>,
    /// World east in body axes, `R̂ᵀ e_w` (`north_pred × up_pred`).
    pub east_pred: Vector3<f64>,
    /// World up in body axes, `R̂ᵀ u_w`.
    pub up_pred: Vector3<f64>,
    /// The raw gyro sample [rad/s].
    pub gyro: &'a Vector3<f64>,
    /// The raw accelerometer sample [m/s²].
    pub accel: &'a Vector3<f64>,
    /// The raw magnetometer sample (9D).
    pub mag: Option<&'a Vector3<f64>>,
    /// The unit accelerometer direction if the gate accepted it (or recovered).
    pub accel_dir: Option<Vector3<f64>>,
    /// The unit field direction if the gate accepted it (or recovered).
    pub mag_dir: Option<Vector3<f64>>,
    /// Whether the gain ramp is running (the gates are open meanwhile).
    pub ramping: bool,
    /// Whether the accelerometer sample passed only by the drift rule ([`AccelRejection`]): its
    /// angle is beyond the gate's, so it may hold an acceleration; a law should correct with it
    /// but not learn a bias from it.
    pub drifting: bool,
    /// The ramp multiplier `ρ` of the correction gain (1 after the ramp).
    pub gain: f64,
    /// The step \[s\].
    pub dt: f64,
    /// The gyro's turn over the step, `Exp((ω − b̂) dt)`, where it exceeds [`LONG_TURN_RAD`]: the
    /// predictions (and the gates) are then the turned estimate's, and a law returns its
    /// correction through [`Step::from_predictions`].
    pub turned: Option<UnitQuaternion<f64>>,
}

/// The gyro's turn over one step \[rad\] beyond which a law compares the measurements with the
/// estimate turned by the gyro ([`Step::turned`]), not with the estimate at the step's
/// start. Compared with the latter, the correction holds the step's turn `g` as a gap, `k g` of it
/// for a gain `k` per step: negligible at a normal rate (10 rad/s at 200 Hz turns 0.05 rad in a
/// step, of which Mahony takes 4e-4), not across a gap in the stamps in motion (Madgwick after the
/// ramp: 8° after a 2 s gap at 0.19 rad/s, 20° after 5 s). Below it the laws keep their one-sample
/// lag, bit for bit and without the second rotation.
pub const LONG_TURN_RAD: f64 = 0.1;

impl Step<'_> {
    /// The law's return value for `correction`, a rotation of the estimate the step's predictions
    /// are of, with the bias `before` the law's update and the bias it leaves: the correction
    /// beside the gyro's `(ω − b̂) dt` in the step's exponential that turns the estimate by
    /// `(ω − b̂_before) dt` (as [`Step::turned`], if the step is seen from the turned estimate),
    /// then by `Exp(correction)`: the bias the law changed does not turn the estimate over this
    /// step (after a 5 s step Mahony's integral took a sixth of the gap that way).
    #[inline(always)]
    pub fn from_predictions(
        &self,
        correction: Vector3<f64>,
        before: &Vector3<f64>,
        bias: &Vector3<f64>,
    ) -> Vector3<f64> {
        match self.turned {
            Some(turn) => after_turn(&turn, &correction, &((self.gyro - bias) * self.dt)),
            None => correction + (bias - before) * self.dt,
        }
    }
}

/// `Log(turn Exp(correction)) − g`.
#[cold]
#[inline(never)]
fn after_turn(turn: &UnitQuaternion<f64>, correction: &Vector3<f64>, g: &Vector3<f64>) -> Vector3<f64> {
    (turn * UnitQuaternion::from_scaled_axis(*correction)).scaled_axis() - g
}

/// World north, east and up in body axes.
type Predictions = (Vector3<f64>, Vector3<f64>, Vector3<f64>);

/// The turn `Exp(g)` and the predictions (world north, east, up in body axes) of the estimate so
/// turned.
pub(crate) fn turned_predictions(
    g: &Vector3<f64>,
    (north, east, up): (&Vector3<f64>, &Vector3<f64>, &Vector3<f64>),
) -> (UnitQuaternion<f64>, Predictions) {
    let turn = UnitQuaternion::from_scaled_axis(*g);
    let back = |v: &Vector3<f64>| turn.inverse_transform_vector(v);
    (turn, (back(north), back(east), back(up)))
}

/// A configured filter: a law's gains and the shared options. It holds no state; every call
/// takes a [`State`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filter<L: Law> {
    law: L,
    options: Options,
    gates: Gates,
    /// `τ` of the low pass and of rest detection, 1 for one that is off ([`Rates::at`]).
    taus: [f64; 2],
}

/// Samples of a batch run, one row per sample.
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    /// Timestamps \[s\], strictly increasing.
    pub t: &'a [f64],
    /// Body rates [rad/s].
    pub gyro: &'a [[f64; 3]],
    /// Specific force [m/s²].
    pub accel: &'a [[f64; 3]],
    /// Magnetometer (9D), or None (6D).
    pub mag: Option<&'a [[f64; 3]]>,
}

/// One sample's row as a vector, element by element: copying the array whole went through the
/// stack in a way that stalled store-to-load forwarding (+20% per Madgwick 6D sample, measured).
#[inline(always)]
fn row(x: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

#[inline]
fn finite(v: &Vector3<f64>) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// Finite input so large that the state overflowed (e.g. a gyro of 1e300 rad/s).
#[inline]
fn check_overflow(s: &CommonState, index: usize) -> Result<()> {
    let sum = s.q.coords.sum() + s.bias.sum();
    if sum.is_finite() {
        Ok(())
    } else {
        Err(Error::Overflow { index })
    }
}

/// The factors of one step that depend only on `dt` and the options: the low pass's and rest
/// detection's `dt / (τ + dt)` and the bias follower's `min(dt / τ, 1)`, divided every sample
/// (off the step's dependency chain: `dt` comes from the stamps). A cache keyed on `dt` (divide
/// only when it changes) missed its branch on 43 % of the bench's samples (callgrind's branch
/// simulation): stamps `k · 0.005` differ by rounding from one step to the next on 48 % of
/// samples, BROAD's `k / 285.714` on 14 %; each miss cost more than the divisions. Each factor is
/// the same number either way.
#[derive(Debug, Clone, Copy)]
struct Rates {
    low_pass: f64,
    rest: f64,
    follow: f64,
}

impl Rates {
    /// The factors for `dt` (> 0); `taus` are the low pass's and rest detection's `τ` (1 for an
    /// option that is off, whose factor is then unused).
    #[inline(always)]
    fn at(taus: [f64; 2], dt: f64) -> Self {
        Self {
            low_pass: dt / (taus[0] + dt),
            rest: dt / (taus[1] + dt),
            follow: (dt / taus[1]).min(1.0),
        }
    }
}

/// `v / √n2` (`n2 > 0`, a squared norm) as `(v / n2) √n2`: the division and the square root
/// both start from `n2` and run side by side, where `v / √n2` waits for the root before dividing
/// (20 + 13 cycles on this host's Zen 5, docs/performance.md); one rounding more. The laws
/// normalise on the attitude's dependency chain (Madgwick's direction, Mahony's heading error), and
/// the accelerometer gate on Mahony's bias (the low pass → direction → bias → gyro turn cycle).
#[inline(always)]
fn over_norm(v: &Vector3<f64>, n2: f64) -> Vector3<f64> {
    v * (1.0 / n2) * n2.sqrt()
}

/// Both stages of the accelerometer low pass ([`AccelLowPass`]) one step towards `accel`
/// (`alpha = dt / (τ + dt)`); the filtered vector. A state without one (zero: an `initial`
/// attitude, a restored older state) starts it at this sample.
#[inline(always)]
fn low_pass(s: &mut CommonState, accel: &Vector3<f64>, alpha: f64) -> Vector3<f64> {
    if s.acc_lp2 == Vector3::zeros() {
        (s.acc_lp1, s.acc_lp2) = (*accel, *accel);
    }
    s.acc_lp1 += (accel - s.acc_lp1) * alpha;
    s.acc_lp2 += (s.acc_lp1 - s.acc_lp2) * alpha;
    s.acc_lp2
}

impl<L: Law> Filter<L> {
    /// A filter with `law`'s gains and the shared `options`; errors on a gain or an option
    /// outside its domain.
    pub fn new(law: L, options: Options) -> Result<Self> {
        law.validate()?;
        options.validate()?;
        Ok(Self {
            law,
            options,
            gates: Gates::new(options.acc_rejection, options.mag_rejection, options.gravity),
            taus: [
                options.acc_lowpass.map_or(1.0, |lp| lp.tau_s),
                options.rest_detection.map_or(1.0, |r| r.tau_s),
            ],
        })
    }

    /// The law (its gains).
    pub fn law(&self) -> &L {
        &self.law
    }

    /// The shared options.
    pub fn options(&self) -> &Options {
        &self.options
    }

    /// One sample. An uninitialised `state` is initialised from `accel` (and `mag`) and `dt` is
    /// ignored; otherwise `dt` \[s\] must be positive and finite. Without `mag`, the last field
    /// sample turned by the gyro stands in for up to [`Options::mag_hold_s`] ([`FieldHold`]).
    /// Errors name the argument.
    pub fn update(
        &self,
        state: &mut State<L>,
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
        if let Some(m) = mag {
            if !finite(m) {
                return Err(Error::NonFinite { index: 0 }.in_argument("mag"));
            }
            if !m.norm_squared().is_finite() {
                return Err(Error::Overflow { index: 0 }.in_argument("mag"));
            }
        }
        if state.common.initialized && !(dt > 0.0 && dt.is_finite()) {
            return Err(Error::Parameter {
                name: "dt",
                expected: "a positive finite step [s]",
                got: format!("{dt}"),
            });
        }
        state.common.express_in(self.options.world);
        let c = &mut state.common;
        let field = c
            .mag_hold
            .for_sample(mag, c.initialized, &((gyro - c.bias) * dt), dt, self.options.mag_hold_s);
        // The clock is advanced here, not in the step: the batch loop sets it to each stamp.
        let stepping = state.common.initialized;
        self.step(state, gyro, accel, field.as_ref(), dt, self.options.world);
        if stepping {
            state.common.time += dt;
        }
        check_overflow(&state.common, 0)
    }

    /// The update proper, on validated input: initialise, or gate, correct and integrate.
    /// `world` is the options' (the batch loop passes it as a constant of its copy: read from
    /// the options, both frames' predictions were computed and one selected every sample).
    #[inline(always)]
    fn step(
        &self,
        state: &mut State<L>,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        dt: f64,
        world: World,
    ) {
        let s = &mut state.common;
        if !s.initialized {
            s.q = initial_attitude(world, accel, mag);
            s.initialized = true;
            (s.acc_lp1, s.acc_lp2, s.gyro_lp, s.rest_accel_lp) = (*accel, *accel, *gyro, *accel);
            if let Some(m) = mag {
                let norm = m.norm();
                if norm > 0.0 {
                    let (sin, cos) = gate::dip(m, norm, &world.predicted(&s.q).2);
                    gate::learn(s, norm, sin, cos);
                }
            }
            return;
        }
        if ((gyro - s.bias) * dt).norm_squared() > LONG_TURN_RAD * LONG_TURN_RAD {
            self.step_turned(state, gyro, accel, mag, dt, world);
        } else {
            self.advance::<false>(state, gyro, accel, mag, dt, world);
        }
    }

    /// [`Filter::advance`] for a step the gyro turns by more than [`LONG_TURN_RAD`]: out of line,
    /// so that the hot loop keeps only the test.
    #[cold]
    #[inline(never)]
    fn step_turned(
        &self,
        state: &mut State<L>,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        dt: f64,
        world: World,
    ) {
        self.advance::<true>(state, gyro, accel, mag, dt, world);
    }

    /// A step of an initialised state: gate, correct and integrate; with `TURNED`, every
    /// prediction (the gates' and the law's) is the estimate's turned by the gyro over the step.
    #[inline(always)]
    fn advance<const TURNED: bool>(
        &self,
        state: &mut State<L>,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        dt: f64,
        world: World,
    ) {
        let o = &self.options;
        let s = &mut state.common;
        let rates = Rates::at(self.taus, dt);
        let ramping = s.ramp_elapsed < o.gain_ramp.duration_s;
        let gain = o.ramp_gain(s.ramp_elapsed);
        let predicted = world.predicted(&s.q);
        let (turned, (north_pred, east_pred, up_pred)) = if TURNED {
            let (turn, p) = turned_predictions(&((gyro - s.bias) * dt), (&predicted.0, &predicted.1, &predicted.2));
            (Some(turn), p)
        } else {
            (None, predicted)
        };
        let raw_sq = accel.norm_squared();
        let accel_dir = if o.acc_lowpass.is_some() {
            let f = low_pass(s, accel, rates.low_pass);
            self.gates
                .accelerometer(s, &f, f.norm_squared(), raw_sq, &up_pred, ramping, dt)
        } else {
            self.gates
                .accelerometer(s, accel, raw_sq, raw_sq, &up_pred, ramping, dt)
        };
        let mag_dir = mag.and_then(|m| self.gates.magnetometer(s, m, &up_pred, ramping, dt));

        if let Some(r) = o.rest_detection {
            let alpha = rates.rest;
            s.gyro_lp += (gyro - s.gyro_lp) * alpha;
            s.rest_accel_lp += (accel - s.rest_accel_lp) * alpha;
            // Capped: a finite 1e300 m/s² sample must not make the state infinite.
            let gyro_dev = (gyro - s.gyro_lp).norm_squared().min(f64::MAX);
            let accel_dev = (accel - s.rest_accel_lp).norm_squared().min(f64::MAX);
            let (g2, a2) = (r.gyro * r.gyro, r.accel * r.accel);
            // The means lag the start of a motion by about tau_s: one sample beyond 4× the rms
            // deviation seen so far (floored at a tenth of the threshold) ends the rest at once,
            // before the bias learns the motion.
            // `f64::max` by a compare, without the NaN blend `max` compiles to: the same value for
            // a threshold that is a number (validated), a NaN `ms` included; zeros' signs do not
            // matter to the `<` below.
            let floor = |ms: f64, threshold: f64| if ms > threshold { ms } else { threshold };
            let still = gyro_dev < 16.0 * floor(s.rest_gyro_ms, g2 / 100.0)
                && accel_dev < 16.0 * floor(s.rest_accel_ms, a2 / 100.0);
            s.rest_gyro_ms += (gyro_dev - s.rest_gyro_ms) * alpha;
            s.rest_accel_ms += (accel_dev - s.rest_accel_ms) * alpha;
            let steady = s.rest_gyro_ms < g2 && s.rest_accel_ms < a2;
            if still && steady && s.gyro_lp.norm_squared() < r.max_bias * r.max_bias {
                s.rest += dt;
            } else {
                s.rest = 0.0;
            }
            if s.rest >= r.duration_s {
                s.bias += (gyro - s.bias) * rates.follow;
            }
        }

        // The low pass's turn into the new body axes, by the gyro alone with the bias before the
        // law's update (what [`AccelLowPass`] specifies): it depends on the inputs and the last
        // step's bias only, so the low pass's loop-carried chain is its two stages and this turn,
        // without the norm, the division and the correction of the attitude's chain.
        let gyro_turn = o.acc_lowpass.is_some().then(|| exp_step(&((gyro - s.bias) * dt)));
        let step = Step {
            q: &s.q,
            north_pred,
            east_pred,
            up_pred,
            gyro,
            accel,
            mag,
            accel_dir,
            mag_dir,
            ramping,
            drifting: s.accel_drift,
            gain,
            dt,
            turned,
        };
        let mut bias = s.bias;
        let correction_dt = self.law.correct(&step, &mut bias, &mut state.extra);
        s.bias = bias;

        // One Newton step towards |q| = 1 without a square root, computed from q_k (|q_k ⊗ E| =
        // |q_k| for a unit E), so it stays off the dependency chain: the exact exponential keeps
        // the norm to rounding, this only stops the rounding from accumulating.
        let renorm = 0.5 * (3.0 - s.q.norm_squared());
        let q = multiply_exp_step(&(s.q.quaternion() * renorm), &((gyro - s.bias) * dt + correction_dt));
        s.q = UnitQuaternion::new_unchecked(q);
        if let Some(gyro_turn) = gyro_turn {
            for f in [&mut s.acc_lp1, &mut s.acc_lp2] {
                *f = gyro_turn.inverse_transform_vector(f);
            }
        }
        if ramping {
            s.ramp_elapsed += dt;
        }
    }

    /// Runs over `inputs`, writing `q_wb` (`[x, y, z, w]`) and the bias after each sample.
    ///
    /// With `continued` false the first sample initialises an uninitialised `state`, or, for an
    /// initialised one (an initial attitude), is output as is and sets its time; with
    /// `continued` true the state is the end of an earlier run and the first sample is a step
    /// over `t[0] − time`. `state` ends as the state after the last sample.
    pub fn run(
        &self,
        state: &mut State<L>,
        inputs: &Inputs<'_>,
        continued: bool,
        out_q: &mut [[f64; 4]],
        out_bias: &mut [[f64; 3]],
    ) -> Result<()> {
        self.run_cancellable(state, inputs, continued, (out_q, out_bias), &Cancel::new())
    }

    /// [`Filter::run`] into `(out_q, out_bias)`, stopping with [`Error::Interrupted`] when `cancel`
    /// is set (polled every [`Cancel::EVERY`] samples); `state` is then part-way through: run on a
    /// copy to keep it.
    pub fn run_cancellable(
        &self,
        state: &mut State<L>,
        inputs: &Inputs<'_>,
        continued: bool,
        (out_q, out_bias): (&mut [[f64; 4]], &mut [[f64; 3]]),
        cancel: &Cancel,
    ) -> Result<()> {
        let n = inputs.t.len();
        let rows = [
            ("gyro", Some(inputs.gyro)),
            ("accel", Some(inputs.accel)),
            ("mag", inputs.mag),
        ];
        for (name, x) in rows {
            if let Some(x) = x.filter(|x| x.len() != n) {
                return Err(Error::RowCount {
                    input: n,
                    output: x.len(),
                }
                .in_argument(name));
            }
        }
        if out_q.len() != n || out_bias.len() != n {
            return Err(Error::RowCount {
                input: n,
                output: out_q.len(),
            });
        }
        if continued && !state.common.initialized {
            return Err(Error::Parameter {
                name: "initial",
                expected: "an initialised state to continue from",
                got: "an uninitialised state".into(),
            });
        }
        state.common.express_in(self.options.world);
        let result = run_batch(self, state, inputs, continued, (out_q, out_bias), cancel);
        state.common.mag_hold.after_run(inputs.mag, n, 0, &result);
        result
    }

    /// The batch loop for one sensor set (checked inputs), compiled per law.
    #[inline(always)]
    fn run_loop<const NINE: bool, const ENU: bool>(
        &self,
        state: &mut State<L>,
        inputs: &Inputs<'_>,
        mags: &[[f64; 3]],
        continued: bool,
        (out_q, out_bias): (&mut [[f64; 4]], &mut [[f64; 3]]),
        cancel: &Cancel,
    ) -> Result<()> {
        let world = if ENU { World::Enu } else { World::Ned };
        let mut previous = state.common.time;
        for (k, (&t, (q_out, b_out))) in inputs
            .t
            .iter()
            .zip(out_q.iter_mut().zip(out_bias.iter_mut()))
            .enumerate()
        {
            cancel.check(k)?;
            let gyro = row(&inputs.gyro[k]);
            let accel = row(&inputs.accel[k]);
            let mag = if NINE { Some(row(&mags[k])) } else { None };
            // One test on a sum of everything (NaN and ±inf propagate through any order of the
            // additions; this one pairs the rows lane by lane); only when it fails, find the
            // culprit (a finite sum overflowing to inf is no error, but a field whose squared norm
            // overflows is: the gate keeps its first norm as the reference).
            let lanes = gyro + accel;
            let sum = (lanes.x + lanes.y) + (lanes.z + (t + mag.map_or(0.0, |m| m.norm_squared())));
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
                if let Some(m) = mag.filter(|m| !finite(m) || !m.norm_squared().is_finite()) {
                    let index = k;
                    return Err(if finite(&m) {
                        Error::Overflow { index }
                    } else {
                        Error::NonFinite { index }
                    }
                    .in_argument("mag"));
                }
            }
            if k == 0 && !continued {
                if !state.common.initialized {
                    self.step(state, &gyro, &accel, mag.as_ref(), 0.0, world);
                }
            } else {
                let dt = t - previous;
                if dt.is_nan() || dt <= 0.0 {
                    return Err(Error::NonIncreasingTime { index: k, dt }.in_argument("t"));
                }
                self.step(state, &gyro, &accel, mag.as_ref(), dt, world);
                check_overflow(&state.common, k)?;
            }
            // Keep the stamp itself (summing the steps would drift from it by rounding).
            state.common.time = t;
            previous = t;
            *q_out = state.common.q.coords.into();
            *b_out = state.common.bias.into();
        }
        Ok(())
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// [`Filter::run_cancellable`] on checked inputs: the loop of its sensor set, per
    /// instruction-set path.
    fn run_batch<L: Law>(
        filter: &Filter<L>,
        state: &mut State<L>,
        inputs: &Inputs<'_>,
        continued: bool,
        out: (&mut [[f64; 4]], &mut [[f64; 3]]),
        cancel: &Cancel,
    ) -> Result<()> {
        let mag = inputs.mag.unwrap_or(&[]);
        match (inputs.mag.is_some(), filter.options.world) {
            (true, World::Enu) => filter.run_loop::<true, true>(state, inputs, mag, continued, out, cancel),
            (true, World::Ned) => filter.run_loop::<true, false>(state, inputs, mag, continued, out, cancel),
            (false, World::Enu) => filter.run_loop::<false, true>(state, inputs, mag, continued, out, cancel),
            (false, World::Ned) => filter.run_loop::<false, false>(state, inputs, mag, continued, out, cancel),
        }
    }
}
