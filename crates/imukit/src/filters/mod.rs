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
//! | step `k` | the correction `ω_c` is computed from the estimate after sample `k−1` and the measurements of sample `k`; then the exponential step over `dt = t_k − t_{k−1}` with `ω_k` |
//! | first sample | initialises the attitude ([`initial_attitude`]: tilt from the accelerometer, heading from the magnetometer, else ZYX yaw 0) unless an initial state is given; it is output as is |
//! | bias output | per sample: the estimate after that sample |
//! | ramp, rejection, rest | [`GainRamp`], [`AccelRejection`], [`MagRejection`], [`RestDetection`] in [`Options`]; the accept / reject / recover rule of both sensors in [`gate`] |
//! | state | [`State<L>`]: [`CommonState`] plus the law's own [`Law::Extra`], `Copy`: save by copying, restore by assigning |
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
//!   `b̂ ← b̂ − k_I ω_mes dt` (frozen during the ramp and while the accelerometer is rejected).
//! - Madgwick (Madgwick 2010 report; ICORR 2011): the tangent-space gradient of
//!   `½‖R̂ᵀ d − s‖²` is `v̂ × s`, so `g = s × v̂_g + m̂ × (‖h_h‖ v̂_n + h_up v̂_g)` and
//!   `ω_c = 2β ρ g/‖g‖` (β is Madgwick's quaternion-rate gain; the field term only with an accepted
//!   accelerometer sample, since it is not heading-only).
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
pub use state::{CommonState, Fields, State};
pub use world::{initial_attitude, World};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::lie::series;
use crate::quat::multiply;
use crate::{Cancel, Error, Result};
use gate::{Field, Gates};

/// A correction law: its gains (a `Copy` value) and how one gated sample corrects the estimate.
pub trait Law: Copy + std::fmt::Debug + PartialEq + Send + Sync {
    /// The law's own state, beyond [`CommonState`] (`()` for none).
    type Extra: Copy + Default + std::fmt::Debug + PartialEq + Send + Sync + Fields;

    /// Checks the gains ([`check`] names each one); [`Filter::new`] calls it.
    fn validate(&self) -> Result<()>;

    /// The correction rotation `ω_c dt` [rad] of one step. May update the gyro-bias estimate
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
    /// The step [s].
    pub dt: f64,
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
    /// Timestamps [s], strictly increasing.
    pub t: &'a [f64],
    /// Body rates [rad/s].
    pub gyro: &'a [[f64; 3]],
    /// Specific force [m/s²].
    pub accel: &'a [[f64; 3]],
    /// Magnetometer (9D), or None (6D).
    pub mag: Option<&'a [[f64; 3]]>,
}

/// `Exp(φ)` of one filter step: [`crate::quat::exp`] with the shorter series of
/// [`series::half_angle_small`] below θ = 0.01 rad (the same rotation to the last bit or so;
/// the step is a chain of dependent operations, and this shortens it by three multiply-adds).
#[inline(always)]
fn exp_step(phi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let (k, w) = series::half_angle_small(phi.norm_squared());
    UnitQuaternion::new_unchecked(Quaternion::from_parts(w, phi * k))
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

/// What rest detection ([`RestDetection`]) tracks: the means and mean squares of its tests and
/// the time they have held (the fields `gyro_lp`, `rest_gyro_ms`, `rest_accel_lp`,
/// `rest_accel_ms`, `rest` of [`CommonState`]). They follow the samples alone, never the
/// estimate, so the batch loop runs them for a block of rows ahead of the steps ([`Block`]).
#[derive(Debug, Clone, Copy)]
struct Rest {
    gyro_lp: Vector3<f64>,
    gyro_ms: f64,
    accel_lp: Vector3<f64>,
    accel_ms: f64,
    held: f64,
}

impl Rest {
    #[inline(always)]
    fn of(s: &CommonState) -> Self {
        Self {
            gyro_lp: s.gyro_lp,
            gyro_ms: s.rest_gyro_ms,
            accel_lp: s.rest_accel_lp,
            accel_ms: s.rest_accel_ms,
            held: s.rest,
        }
    }

    #[inline(always)]
    fn store(&self, s: &mut CommonState) {
        (s.gyro_lp, s.rest_gyro_ms, s.rest_accel_lp, s.rest_accel_ms, s.rest) =
            (self.gyro_lp, self.gyro_ms, self.accel_lp, self.accel_ms, self.held);
    }

    /// One sample over `dt` (`alpha = dt / (τ + dt)`); whether the sensor is at rest after it
    /// (the bias then follows the gyro).
    #[inline(always)]
    fn update(&mut self, r: &RestDetection, gyro: &Vector3<f64>, accel: &Vector3<f64>, alpha: f64, dt: f64) -> bool {
        self.gyro_lp += (gyro - self.gyro_lp) * alpha;
        self.accel_lp += (accel - self.accel_lp) * alpha;
        // Capped: a finite 1e300 m/s² sample must not make the state infinite.
        let gyro_dev = (gyro - self.gyro_lp).norm_squared().min(f64::MAX);
        let accel_dev = (accel - self.accel_lp).norm_squared().min(f64::MAX);
        let (g2, a2) = (r.gyro * r.gyro, r.accel * r.accel);
        // The means lag the start of a motion by about tau_s: one sample beyond 4× the rms
        // deviation seen so far (floored at a tenth of the threshold) ends the rest at once,
        // before the bias learns the motion.
        // `f64::max` by a compare, without the NaN blend `max` compiles to: the same value for
        // a threshold that is a number (validated), a NaN `ms` included; zeros' signs do not
        // matter to the `<` below.
        let floor = |ms: f64, threshold: f64| if ms > threshold { ms } else { threshold };
        let still =
            gyro_dev < 16.0 * floor(self.gyro_ms, g2 / 100.0) && accel_dev < 16.0 * floor(self.accel_ms, a2 / 100.0);
        self.gyro_ms += (gyro_dev - self.gyro_ms) * alpha;
        self.accel_ms += (accel_dev - self.accel_ms) * alpha;
        let steady = self.gyro_ms < g2 && self.accel_ms < a2;
        if still && steady && self.gyro_lp.norm_squared() < r.max_bias * r.max_bias {
            self.held += dt;
        } else {
            self.held = 0.0;
        }
        self.held >= r.duration_s
    }
}

/// One step's values that depend on its samples alone, not on the estimate: the step, the low
/// pass's and the bias follower's factors ([`Rates`]), the accelerometer's squared norm (its raw
/// norm test) and rest detection's verdict ([`Rest`]). [`Filter::update`] computes them inline,
/// the batch loop for a block of rows ahead of the steps ([`Block`]).
#[derive(Debug, Clone, Copy)]
struct Given {
    dt: f64,
    low_pass: f64,
    follow: f64,
    accel_sq: f64,
    at_rest: bool,
}

/// Rows per block of the batch loop ([`Block`]): a power of two dividing [`Cancel::EVERY`], so
/// that the blocks start at its polling points.
const BLOCK: usize = 256;
const _: () = assert!(Cancel::EVERY.is_multiple_of(BLOCK));

/// A block of rows' [`Given`] and [`Field`] values as a structure of arrays, on the stack. The
/// batch loop's first pass fills them ([`Block::fill`]): everything but rest detection is
/// independent from row to row, so it vectorises across rows (the divisions of [`Rates`] and of
/// `1/‖m‖`, the square root of `‖m‖`, the finiteness and time tests); the second pass runs the
/// steps, which then hold only the estimate's chain and its gates.
struct Block {
    dt: [f64; BLOCK],
    low_pass: [f64; BLOCK],
    rest: [f64; BLOCK],
    follow: [f64; BLOCK],
    accel_sq: [f64; BLOCK],
    at_rest: [bool; BLOCK],
    mag_norm: [f64; BLOCK],
    mag_inv: [f64; BLOCK],
    mag_dir: [Vector3<f64>; BLOCK],
}

/// Zero when every value of `x` is finite, NaN otherwise (`v · 0` is NaN exactly for ±inf and
/// NaN), summed in four lanes so that it vectorises.
#[inline(always)]
fn poison(x: &[f64]) -> f64 {
    let mut lanes = [0.0; 4];
    let (chunks, tail) = x.as_chunks::<4>();
    for c in chunks {
        for (lane, v) in lanes.iter_mut().zip(c) {
            *lane += v * 0.0;
        }
    }
    for v in tail {
        lanes[0] += v * 0.0;
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// The input checks of one sample's rows: [`Error::NonFinite`] naming the first non-finite one,
/// or [`Error::Overflow`] for a field whose squared norm overflows (the gate keeps its first norm
/// as the reference).
fn check_rows(gyro: &Vector3<f64>, accel: &Vector3<f64>, mag: Option<&Vector3<f64>>, index: usize) -> Result<()> {
    if !finite(gyro) {
        return Err(Error::NonFinite { index }.in_argument("gyro"));
    }
    if !finite(accel) {
        return Err(Error::NonFinite { index }.in_argument("accel"));
    }
    if let Some(m) = mag {
        if !finite(m) {
            return Err(Error::NonFinite { index }.in_argument("mag"));
        }
        if !m.norm_squared().is_finite() {
            return Err(Error::Overflow { index }.in_argument("mag"));
        }
    }
    Ok(())
}

/// The rows of one block of a batch run: stamps, gyro, accelerometer, magnetometer (empty in 6D).
#[derive(Clone, Copy)]
struct Rows<'a> {
    t: &'a [f64],
    gyro: &'a [[f64; 3]],
    accel: &'a [[f64; 3]],
    mag: &'a [[f64; 3]],
}

impl Rows<'_> {
    /// The first row that fails the input checks (non-finite, or a step `dt` that is not
    /// positive), with its error; `k0` is the block's first index. Only called after a block's
    /// vectorised tests failed.
    #[cold]
    #[inline(never)]
    fn first_bad(&self, dt: &[f64], k0: usize) -> Option<(usize, Error)> {
        (0..self.t.len()).find_map(|i| {
            let index = k0 + i;
            let mag = self.mag.get(i).map(row);
            let checked = if self.t[i].is_finite() {
                check_rows(&row(&self.gyro[i]), &row(&self.accel[i]), mag.as_ref(), index)
            } else {
                Err(Error::NonFinite { index }.in_argument("t"))
            };
            let checked = checked.and_then(|()| match dt[i] {
                dt if dt.is_nan() || dt <= 0.0 => Err(Error::NonIncreasingTime { index, dt }.in_argument("t")),
                _ => Ok(()),
            });
            checked.err().map(|e| (i, e))
        })
    }
}

impl Block {
    fn new() -> Self {
        Self {
            dt: [0.0; BLOCK],
            low_pass: [0.0; BLOCK],
            rest: [0.0; BLOCK],
            follow: [0.0; BLOCK],
            accel_sq: [0.0; BLOCK],
            at_rest: [false; BLOCK],
            mag_norm: [0.0; BLOCK],
            mag_inv: [0.0; BLOCK],
            mag_dir: [Vector3::zeros(); BLOCK],
        }
    }

    /// The first pass over `rows` (at most [`BLOCK`], the first at index `k0`, after the stamp
    /// `previous`): every row's values, then rest detection from `rest` on. Returns how many
    /// rows passed the input checks, and the error of the first that did not.
    #[inline(always)]
    fn fill<const NINE: bool>(
        &mut self,
        taus: [f64; 2],
        rest_detection: Option<&RestDetection>,
        rest: &mut Rest,
        rows: &Rows<'_>,
        previous: f64,
        k0: usize,
    ) -> (usize, Option<Error>) {
        let n = rows.t.len();
        let dt = &mut self.dt[..n];
        dt[0] = rows.t[0] - previous;
        for (d, (t, before)) in dt[1..].iter_mut().zip(rows.t[1..].iter().zip(rows.t)) {
            *d = t - before;
        }
        let increasing = dt.iter().fold(true, |ok, &d| ok & (d > 0.0));
        for (i, &dt) in dt.iter().enumerate() {
            let r = Rates::at(taus, dt);
            (self.low_pass[i], self.rest[i], self.follow[i]) = (r.low_pass, r.rest, r.follow);
        }
        for (sq, a) in self.accel_sq[..n].iter_mut().zip(rows.accel) {
            *sq = row(a).norm_squared();
        }
        let mut sum = (poison(rows.t) + poison(rows.gyro.as_flattened())) + poison(rows.accel.as_flattened());
        if NINE {
            for (i, m) in rows.mag.iter().enumerate() {
                let f = Field::of(&row(m));
                (self.mag_norm[i], self.mag_inv[i], self.mag_dir[i]) = (f.norm, f.inv, f.dir);
            }
            // The norm is finite exactly when the field is and its squared norm did not overflow.
            sum += poison(&self.mag_norm[..n]);
        }
        let (valid, error) = if sum == 0.0 && increasing {
            (n, None)
        } else {
            rows.first_bad(&self.dt[..n], k0)
                .map_or((n, None), |(i, e)| (i, Some(e)))
        };
        if let Some(r) = rest_detection {
            self.rest_pass(r, rest, rows, valid);
        }
        (valid, error)
    }

    /// Rest detection over the first `n` rows, from `rest` on.
    #[inline(always)]
    fn rest_pass(&mut self, r: &RestDetection, rest: &mut Rest, rows: &Rows<'_>, n: usize) {
        for i in 0..n {
            self.at_rest[i] = rest.update(r, &row(&rows.gyro[i]), &row(&rows.accel[i]), self.rest[i], self.dt[i]);
        }
    }

    /// Row `i`'s values.
    #[inline(always)]
    fn given(&self, i: usize) -> Given {
        Given {
            dt: self.dt[i],
            low_pass: self.low_pass[i],
            follow: self.follow[i],
            accel_sq: self.accel_sq[i],
            at_rest: self.at_rest[i],
        }
    }

    /// Row `i`'s field values.
    #[inline(always)]
    fn field(&self, i: usize) -> Field {
        Field {
            norm: self.mag_norm[i],
            inv: self.mag_inv[i],
            dir: self.mag_dir[i],
        }
    }
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
    /// ignored; otherwise `dt` [s] must be positive and finite. Errors name the argument.
    pub fn update(
        &self,
        state: &mut State<L>,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        dt: f64,
    ) -> Result<()> {
        check_rows(gyro, accel, mag, 0)?;
        let world = self.options.world;
        if !state.common.initialized {
            self.initialise(&mut state.common, gyro, accel, mag, world);
            return check_overflow(&state.common, 0);
        }
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(Error::Parameter {
                name: "dt",
                expected: "a positive finite step [s]",
                got: format!("{dt}"),
            });
        }
        let s = &mut state.common;
        let rates = Rates::at(self.taus, dt);
        let at_rest = self.options.rest_detection.is_some_and(|r| {
            let mut rest = Rest::of(s);
            let at_rest = rest.update(&r, gyro, accel, rates.rest, dt);
            rest.store(s);
            at_rest
        });
        let given = Given {
            dt,
            low_pass: rates.low_pass,
            follow: rates.follow,
            accel_sq: accel.norm_squared(),
            at_rest,
        };
        let field = mag.map(Field::of);
        self.step(state, gyro, accel, mag.zip(field.as_ref()), &given, world);
        // The clock is advanced here, not in the step: the batch loop sets it to each stamp.
        state.common.time += dt;
        check_overflow(&state.common, 0)
    }

    /// The first sample of an uninitialised state: the attitude from `accel` (and `mag`), every
    /// low pass started at this sample, the field's reference learned from it.
    fn initialise(
        &self,
        s: &mut CommonState,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        world: World,
    ) {
        s.q = initial_attitude(world, accel, mag);
        s.initialized = true;
        (s.acc_lp1, s.acc_lp2, s.gyro_lp, s.rest_accel_lp) = (*accel, *accel, *gyro, *accel);
        if let Some(m) = mag {
            let norm = m.norm();
            if norm > 0.0 {
                let (sin, cos) = gate::dip(m, norm, &world.predicted(&s.q).1);
                gate::learn(s, norm, sin, cos);
            }
        }
    }

    /// The step proper of an initialised state, on validated input: gate, correct and
    /// integrate. `mag` is the field sample with its [`Field`] values, `given` the sample's
    /// values that do not depend on the estimate (rest detection's state already advanced);
    /// `world` is the options' (the batch loop passes it as a constant of its copy: read from
    /// the options, both frames' predictions were computed and one selected every sample).
    #[inline(always)]
    fn step(
        &self,
        state: &mut State<L>,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<(&Vector3<f64>, &Field)>,
        given: &Given,
        world: World,
    ) {
        let o = &self.options;
        let s = &mut state.common;
        let dt = given.dt;
        let ramping = s.ramp_elapsed < o.gain_ramp.duration_s;
        let gain = o.ramp_gain(s.ramp_elapsed);
        let (north_pred, up_pred) = world.predicted(&s.q);
        let raw_sq = given.accel_sq;
        let accel_dir = if o.acc_lowpass.is_some() {
            let f = low_pass(s, accel, given.low_pass);
            self.gates.accelerometer(s, &f, f.norm(), raw_sq, &up_pred, ramping, dt)
        } else {
            self.gates
                .accelerometer(s, accel, raw_sq.sqrt(), raw_sq, &up_pred, ramping, dt)
        };
        let mag_dir = mag.and_then(|(m, field)| self.gates.magnetometer(s, m, field, &up_pred, ramping, dt));
        if given.at_rest {
            s.bias += (gyro - s.bias) * given.follow;
        }

        let step = Step {
            q: &s.q,
            north_pred,
            up_pred,
            gyro,
            accel,
            mag: mag.map(|(m, _)| m),
            accel_dir,
            mag_dir,
            ramping,
            drifting: s.accel_drift,
            gain,
            dt,
        };
        let mut bias = s.bias;
        let correction_dt = self.law.correct(&step, &mut bias, &mut state.extra);
        s.bias = bias;

        // One Newton step towards |q| = 1 without a square root, computed from q_k (|q_k ⊗ E| =
        // |q_k| for a unit E), so it stays off the dependency chain: the exact exponential keeps
        // the norm to rounding, this only stops the rounding from accumulating.
        let renorm = 0.5 * (3.0 - s.q.norm_squared());
        let turn = exp_step(&((gyro - s.bias) * dt + correction_dt));
        let q = multiply(s.q.quaternion(), turn.quaternion());
        s.q = UnitQuaternion::new_unchecked(q * renorm);
        if o.acc_lowpass.is_some() {
            // Into the new body axes by the gyro turn alone: `Exp(θ)ᵀ = Exp(c) Exp(θ + c)ᵀ` to
            // first order in the small correction `c`, i.e. one cross product after the full turn.
            for f in [&mut s.acc_lp1, &mut s.acc_lp2] {
                let w = turn.inverse_transform_vector(f);
                *f = w + correction_dt.cross(&w);
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
        run_batch(self, state, inputs, continued, (out_q, out_bias), cancel)
    }

    /// The batch loop for one sensor set (checked inputs), compiled per law: the first row
    /// (initialisation) on its own, then blocks of [`BLOCK`] rows, each filled by its first pass
    /// ([`Block::fill`]) and then stepped.
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
        let n = inputs.t.len();
        let mut k0 = 0;
        if !continued && n > 0 {
            cancel.check(0)?;
            let (gyro, accel) = (row(&inputs.gyro[0]), row(&inputs.accel[0]));
            let mag = NINE.then(|| row(&mags[0]));
            if !inputs.t[0].is_finite() {
                return Err(Error::NonFinite { index: 0 }.in_argument("t"));
            }
            check_rows(&gyro, &accel, mag.as_ref(), 0)?;
            if !state.common.initialized {
                self.initialise(&mut state.common, &gyro, &accel, mag.as_ref(), world);
            }
            state.common.time = inputs.t[0];
            out_q[0] = state.common.q.coords.into();
            out_bias[0] = state.common.bias.into();
            k0 = 1;
        }
        let mut block = Block::new();
        let rest_detection = self.options.rest_detection.as_ref();
        while k0 < n {
            cancel.check(k0)?;
            let end = ((k0 / BLOCK + 1) * BLOCK).min(n);
            let rows = Rows {
                t: &inputs.t[k0..end],
                gyro: &inputs.gyro[k0..end],
                accel: &inputs.accel[k0..end],
                mag: if NINE { &mags[k0..end] } else { &[] },
            };
            // Rest detection's state at the block's start stays in `state` until the block is
            // stepped: an overflow part-way re-runs it to the failing row from there.
            let mut rest = Rest::of(&state.common);
            let (valid, error) = block.fill::<NINE>(self.taus, rest_detection, &mut rest, &rows, state.common.time, k0);
            let outputs = out_q[k0..k0 + valid].iter_mut().zip(&mut out_bias[k0..k0 + valid]);
            for (i, (q_out, b_out)) in outputs.enumerate() {
                let gyro = row(&rows.gyro[i]);
                let accel = row(&rows.accel[i]);
                let mag = NINE.then(|| (row(&rows.mag[i]), block.field(i)));
                self.step(
                    state,
                    &gyro,
                    &accel,
                    mag.as_ref().map(|(m, f)| (m, f)),
                    &block.given(i),
                    world,
                );
                if let Err(e) = check_overflow(&state.common, k0 + i) {
                    if let Some(r) = rest_detection {
                        let mut rest = Rest::of(&state.common);
                        block.rest_pass(r, &mut rest, &rows, i + 1);
                        rest.store(&mut state.common);
                    }
                    if i > 0 {
                        state.common.time = rows.t[i - 1];
                    }
                    return Err(e);
                }
                *q_out = state.common.q.coords.into();
                *b_out = state.common.bias.into();
            }
            rest.store(&mut state.common);
            if valid > 0 {
                // The stamp itself (summing the steps would drift from it by rounding).
                state.common.time = rows.t[valid - 1];
            }
            if let Some(e) = error {
                return Err(e);
            }
            k0 = end;
        }
        Ok(())
    }
}

crate::simd_dispatch! {
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
