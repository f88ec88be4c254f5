//! `Robust`: an attitude filter whose accelerometer correction does not tilt under sustained or
//! short accelerations, with a Kalman estimate of the gyro bias, rest detection, a magnetometer
//! heading decoupled from inclination with disturbance rejection, and an acausal smoother.
//!
//! Design after Laidig & Seel, "VQF: Highly accurate IMU orientation estimation with bias
//! estimation and magnetic disturbance rejection", Information Fusion 91 (2023) 187–204; the
//! equations here are derived in `docs/filters_robust.md` and written from them.
//!
//! | item | convention |
//! |---|---|
//! | estimate | `q_wb = Rz(ψ) ⊗ q_incl ⊗ q_gyro` (internal ENU; NED applied at the output), Hamilton |
//! | `q_gyro` | strapdown body → almost-inertial `I`: `q_gyro ← q_gyro ⊗ Exp((ω − b̂) dt)` |
//! | specific force | `a_I = R(q_gyro) a`, low-passed by a 2nd-order Butterworth (τ = `tau_acc_s`) in `I`, where the body's accelerations average out while gravity stays put |
//! | inclination | `q_incl ← q_c ⊗ q_incl`, `q_c` the smallest rotation taking `R(q_incl) ā_I` to up: applied in full every sample, so the estimate's up is the filtered specific force |
//! | heading (9D) | `ψ ← ψ + k e`, `e` the angle of the horizontal field from north (+y) in `E'`, `k = 1 − exp(−dt/τ_mag)`: about the vertical only, so the field never tilts the estimate |
//! | magnetic disturbance | norm `|‖m‖ − m₀| ≤ f m₀` and dip `|δ − δ₀| ≤ θ` against the reference learned at the first sample; rejected at most `mag_max_rejection_s`, then used at `mag_slow_factor × τ_mag`; a homogeneous field held while turning for `mag_new_field_s` becomes the reference |
//! | bias | Kalman filter on `b` (random walk): at rest the mean gyro of the rest segment (`H = I`, noise `σ_rest²/T`) every `bias_rest_window_s` and at its end; in motion per window of `bias_window_s` the mean correction rate (`H = −Σ R dt / T`, x, y from inclination, z from heading); clipped to `±bias_clip_rad_s` |
//! | rest | `‖ω̃ − ω̄‖ < rest_gyro_rad_s`, `‖ω̄ − b̂‖² < rest_gyro_rad_s² + 9 tr P` and `‖ã − ā‖ < rest_accel` for `rest_duration_s` (first-order low passes: `ω̄`, `ā` over `rest_tau_s`, `ω̃`, `ã` over `rest_noise_tau_s`, which takes noise and vibration off); a raw sample beyond 4× the rms deviation ends it at once |
//! | first sample | initialises: tilt from the accelerometer, yaw 0 (6D) or heading from the field (9D), unless an initial attitude is given (whose heading, in 9D, the first field sample replaces); output as is |
//! | outputs per sample | `q_wb`, `b̂`, `σ_b = √diag P`, rest flag, magnetic-disturbance flag, after that sample |
//! | batch run | from 1024 samples, where rayon's pool has a second thread: each step's window half (bias-window sums, 9D heading, output rows) on it, behind the attitude half ([`pipeline`]); bit for bit the run on one thread |
//! | offline | [`Robust::smooth`]: forward and backward (time-reversed) passes' biases fused; the specific force in `I` filtered forward then backward (zero phase) for the inclination; 9D heading of both passes fused |
//!
//! Why not a [`super::Law`]: the law seam corrects one attitude with `ω_c dt`; this filter keeps
//! three factors of the attitude, a low-pass state and a bias covariance, and outputs more per
//! sample, so it is its own struct (it reuses [`super::initial_attitude`], [`super::World`],
//! [`super::Inputs`], [`super::Fields`] and [`super::check`]).

mod params;
mod pipeline;
mod smoother;
mod state;
mod step;

pub use params::RobustParams;
pub use state::RobustState;

use nalgebra::{UnitQuaternion, Vector3};

use super::{finite, row, Inputs, World};
use crate::{Cancel, Error, Result};
use step::{Coefs, CoefsCache};

/// Per-sample outputs of a run, one row per sample.
#[derive(Debug)]
pub struct Outputs<'a> {
    /// `q_wb` as `[x, y, z, w]`.
    pub q: &'a mut [[f64; 4]],
    /// Gyro-bias estimate [rad/s].
    pub bias: &'a mut [[f64; 3]],
    /// Its standard deviation per axis [rad/s].
    pub bias_sigma: &'a mut [[f64; 3]],
    /// Rest detected.
    pub rest: &'a mut [bool],
    /// Magnetometer sample rejected as disturbed (always false in 6D).
    pub mag_disturbed: &'a mut [bool],
}

impl Outputs<'_> {
    /// Every row count `n`, the attitude's `0` where the run writes none (`attitude` false).
    fn len_ok(&self, n: usize, attitude: bool) -> bool {
        self.q.len() == if attitude { n } else { 0 }
            && [
                self.bias.len(),
                self.bias_sigma.len(),
                self.rest.len(),
                self.mag_disturbed.len(),
            ]
            .iter()
            .all(|&l| l == n)
    }

    /// The rows before `m` and those from `m` (the smoother's fusions run the halves of the
    /// record on two threads).
    fn split_at(&mut self, m: usize) -> (Outputs<'_>, Outputs<'_>) {
        let (q, q_) = self.q.split_at_mut(m);
        let (bias, bias_) = self.bias.split_at_mut(m);
        let (bias_sigma, bias_sigma_) = self.bias_sigma.split_at_mut(m);
        let (rest, rest_) = self.rest.split_at_mut(m);
        let (mag_disturbed, mag_disturbed_) = self.mag_disturbed.split_at_mut(m);
        (
            Outputs {
                q,
                bias,
                bias_sigma,
                rest,
                mag_disturbed,
            },
            Outputs {
                q: q_,
                bias: bias_,
                bias_sigma: bias_sigma_,
                rest: rest_,
                mag_disturbed: mag_disturbed_,
            },
        )
    }
}

/// `√diag P` of the bias covariance, recomputed only when the diagonal changes (at a Kalman
/// update or a window's process noise, once per window): three square roots per sample were a
/// tenth of a 6D step.
#[derive(Debug, Default)]
struct Sigma {
    /// The diagonal's bits the roots are of.
    diag: [u64; 3],
    roots: [f64; 3],
}

impl Sigma {
    #[inline(always)]
    fn of(&mut self, p: &nalgebra::Matrix3<f64>) -> [f64; 3] {
        // Compared one element at a time: comparing the arrays gathered the diagonal's three
        // 8-byte rows on the stack and read them back as one 16-byte load, which the store buffer
        // cannot forward (a stall on every sample; 3% of a 9D run's profile).
        let diag = [p[(0, 0)].to_bits(), p[(1, 1)].to_bits(), p[(2, 2)].to_bits()];
        if diag[0] != self.diag[0] || diag[1] != self.diag[1] || diag[2] != self.diag[2] {
            self.diag = diag;
            self.roots = diag.map(|d| f64::from_bits(d).sqrt());
        }
        self.roots
    }
}

/// Owned per-sample outputs (what [`Outputs`] views).
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// `q_wb` as `[x, y, z, w]`.
    pub q: Vec<[f64; 4]>,
    /// Gyro-bias estimate [rad/s].
    pub bias: Vec<[f64; 3]>,
    /// Its standard deviation per axis [rad/s].
    pub bias_sigma: Vec<[f64; 3]>,
    /// Rest detected.
    pub rest: Vec<bool>,
    /// Magnetometer sample rejected as disturbed.
    pub mag_disturbed: Vec<bool>,
}

impl Track {
    /// `n` rows of zeros.
    pub fn new(n: usize) -> Self {
        Self {
            q: vec![[0.0; 4]; n],
            bias: vec![[0.0; 3]; n],
            bias_sigma: vec![[0.0; 3]; n],
            rest: vec![false; n],
            mag_disturbed: vec![false; n],
        }
    }

    /// The rows as outputs of a run.
    pub fn outputs(&mut self) -> Outputs<'_> {
        Outputs {
            q: &mut self.q,
            bias: &mut self.bias,
            bias_sigma: &mut self.bias_sigma,
            rest: &mut self.rest,
            mag_disturbed: &mut self.mag_disturbed,
        }
    }
}

/// A configured robust filter (no state: every call takes a [`RobustState`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Robust {
    params: RobustParams,
    world: World,
}

impl Robust {
    /// A filter with `params` in `world`; errors on a parameter outside its domain.
    pub fn new(params: RobustParams, world: World) -> Result<Self> {
        params.validate()?;
        Ok(Self { params, world })
    }

    /// The parameters.
    pub fn params(&self) -> &RobustParams {
        &self.params
    }

    /// The world frame.
    pub fn world(&self) -> World {
        self.world
    }

    /// A state initialised at attitude `q` (`q_wb` in this filter's world) at `time`, zero bias
    /// with the prior covariance; in 9D the first field sample replaces its heading.
    pub fn state_at(&self, q: &UnitQuaternion<f64>, time: f64) -> RobustState {
        let mut s = RobustState::default();
        step::initialise(
            &self.params,
            self.world,
            &mut s,
            Some(step::from_world(self.world, q)),
            &Vector3::zeros(),
            &Vector3::zeros(),
        );
        s.q = *q;
        s.time = time;
        s
    }

    /// One streaming sample: an uninitialised `state` is initialised (and `dt` ignored);
    /// otherwise `dt` \[s\] must be positive and finite. Without `mag`, the last field sample
    /// turned by the gyro stands in for up to [`RobustParams::mag_hold_s`]
    /// ([`crate::filters::FieldHold`]). Errors name the argument.
    pub fn update(
        &self,
        state: &mut RobustState,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
        dt: f64,
    ) -> Result<()> {
        for (name, v) in [("gyro", Some(gyro)), ("accel", Some(accel)), ("mag", mag)] {
            if v.is_some_and(|v| !finite(v)) {
                return Err(Error::NonFinite { index: 0 }.in_argument(name));
            }
        }
        // As `Filter::update`: a field whose squared norm overflows would be held as it is.
        if mag.is_some_and(|m| !m.norm_squared().is_finite()) {
            return Err(Error::Overflow { index: 0 }.in_argument("mag"));
        }
        let dt = if state.initialized {
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(Error::Parameter {
                    name: "dt",
                    expected: "a positive finite step [s]",
                    got: format!("{dt}"),
                });
            }
            dt
        } else {
            0.0
        };
        let turn = (gyro - state.bias) * dt;
        let field = state
            .mag_hold
            .for_sample(mag, state.initialized, &turn, dt, self.params.mag_hold_s);
        step::step(
            &self.params,
            self.world,
            &Coefs::new(&self.params, dt),
            state,
            gyro,
            accel,
            field.as_ref(),
        );
        state.time += dt;
        check_overflow(state, 0)
    }

    /// Runs over `inputs`, writing one row of `out` per sample. With `continued` false the first
    /// sample initialises an uninitialised `state` or, for an initialised one, is a step of
    /// length 0 (output as the state has it, time set); with `continued` true the first sample
    /// is a step over `t[0] − state.time`. `state` ends as the state after the last sample.
    /// An error at row `k` leaves the rows before it written and `state` after row `k − 1`; an
    /// overflow (finite input so large that the state overflowed) leaves row `k` written too and
    /// `state` after the step that overflowed. From 1024 samples the run may take two threads of
    /// rayon's pool (`pipeline`), with the same result.
    pub fn run(
        &self,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        continued: bool,
        out: &mut Outputs<'_>,
    ) -> Result<()> {
        self.run_part(state, inputs, 0, continued, out)
    }

    /// [`Robust::run`] on a part of a longer record whose first row is row `first` of the whole
    /// (a caller feeding the record part by part, `continued` after the first part): errors name
    /// the row in the whole record. Parts give the same result as one run, bit for bit.
    pub fn run_part(
        &self,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        first: usize,
        continued: bool,
        out: &mut Outputs<'_>,
    ) -> Result<()> {
        self.run_part_cancellable(state, inputs, (first, continued), out, &Cancel::new())
    }

    /// [`Robust::run_part`] with `start = (first, continued)`, stopping with
    /// [`Error::Interrupted`] (naming the row in the whole record) when `cancel` is set (polled
    /// every [`Cancel::EVERY`] samples); the rows before it are written and `state` is part-way
    /// through, as after an error.
    pub fn run_part_cancellable(
        &self,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        start: (usize, bool),
        out: &mut Outputs<'_>,
        cancel: &Cancel,
    ) -> Result<()> {
        self.run_checked(state, inputs, start, true, out, cancel)
    }

    /// [`Robust::run_part`] with `start = (first, continued)`, writing the attitude only where
    /// `attitude` (`out.q` empty otherwise): the smoother's first stage reads none, and its two
    /// passes' attitude tracks were 32 B per sample of fresh pages each.
    fn run_checked(
        &self,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        (first, continued): (usize, bool),
        attitude: bool,
        out: &mut Outputs<'_>,
        cancel: &Cancel,
    ) -> Result<()> {
        let n = inputs.t.len();
        check_lengths(inputs)?;
        if !out.len_ok(n, attitude) {
            return Err(Error::RowCount {
                input: n,
                output: out.q.len(),
            });
        }
        if continued && !state.initialized {
            return Err(Error::Parameter {
                name: "initial",
                expected: "an initialised state to continue from",
                got: "an uninitialised state".into(),
            });
        }
        let result = if attitude && n >= pipeline::FROM && rayon::current_num_threads() > 1 {
            pipeline::run(self, state, inputs, (first, continued), out, cancel)
        } else {
            run_any(self, state, inputs, (first, continued), attitude, out, cancel)
        };
        state.mag_hold.after_run(inputs.mag, n, first, &result);
        result
    }

    /// The loop of [`Robust::run_part`]: `NINE` with the field `mags`, each checked sample
    /// given to `stepper`; `start` is `(first, continued)`.
    #[inline(always)]
    fn run_loop<const NINE: bool, S: Stepper>(
        &self,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        mags: &[[f64; 3]],
        (first, continued): (usize, bool),
        stepper: &mut S,
        cancel: &Cancel,
    ) -> Result<()> {
        let p = &self.params;
        let mut cache = CoefsCache::new(Coefs::new(p, 0.0));
        let mut previous = state.time;
        for (k, &t) in inputs.t.iter().enumerate() {
            cancel.check(k).map_err(|_| Error::Interrupted { index: first + k })?;
            let gyro = row(&inputs.gyro[k]);
            let accel = row(&inputs.accel[k]);
            let mag = if NINE { Some(row(&mags[k])) } else { None };
            let sum = t + gyro.sum() + accel.sum() + mag.map_or(0.0, |m| m.sum());
            if !sum.is_finite() {
                non_finite(first + k, t, &gyro, &accel, mag.as_ref())?;
            }
            let dt = if k == 0 && !continued {
                0.0
            } else {
                let dt = t - previous;
                if dt.is_nan() || dt <= 0.0 {
                    return Err(Error::NonIncreasingTime { index: first + k, dt }.in_argument("t"));
                }
                dt
            };
            let stepped = dt > 0.0 || !state.initialized;
            if stepped {
                let coefs = cache.for_dt(p, dt);
                stepper.step(k, &coefs, state, &gyro, &accel, mag.as_ref());
            } else {
                stepper.skip(k, state);
            }
            // Row k is written before the overflow check: on two threads the second may have
            // written it already.
            stepper.write(k, state);
            if stepped && stepper.overflowed(state) {
                return Err(Error::Overflow { index: first + k });
            }
            state.time = t;
            previous = t;
        }
        Ok(())
    }
}

/// What a run does with each checked sample `k`: the whole step on this thread ([`Whole`]), or
/// its attitude half with the window half sent to another thread ([`pipeline`]).
trait Stepper {
    /// Steps `s` over sample `k` with coefficients `c` (the step is `c.dt`).
    fn step(
        &mut self,
        k: usize,
        c: &Coefs,
        s: &mut RobustState,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
    );
    /// Sample `k` is a step of length 0 (the first of a run on an initialised state `s`).
    fn skip(&mut self, k: usize, s: &RobustState);
    /// Writes row `k` of the outputs from `s`, after the sample.
    fn write(&mut self, k: usize, s: &RobustState);
    /// Whether the step overflowed the state (finite input so large that it did), as far as
    /// this thread's fields tell.
    fn overflowed(&self, s: &RobustState) -> bool;
}

/// Every step whole, on the calling thread; the attitude written where `ATTITUDE`.
struct Whole<'r, 'o, const ATTITUDE: bool> {
    filter: &'r Robust,
    out: &'r mut Outputs<'o>,
    sigma: Sigma,
}

impl<'r, 'o, const ATTITUDE: bool> Whole<'r, 'o, ATTITUDE> {
    fn new(filter: &'r Robust, out: &'r mut Outputs<'o>) -> Self {
        // Bits of 0.0: the cache starts valid for a zero diagonal, whose roots are 0.0.
        let sigma = Sigma::default();
        Self { filter, out, sigma }
    }
}

impl<const ATTITUDE: bool> Stepper for Whole<'_, '_, ATTITUDE> {
    #[inline(always)]
    fn step(
        &mut self,
        _: usize,
        c: &Coefs,
        s: &mut RobustState,
        gyro: &Vector3<f64>,
        accel: &Vector3<f64>,
        mag: Option<&Vector3<f64>>,
    ) {
        step::step(&self.filter.params, self.filter.world, c, s, gyro, accel, mag);
    }

    #[inline(always)]
    fn skip(&mut self, _: usize, _: &RobustState) {}

    #[inline(always)]
    fn write(&mut self, k: usize, s: &RobustState) {
        if ATTITUDE {
            self.out.q[k] = s.q.coords.into();
        }
        self.out.mag_disturbed[k] = s.mag_disturbed;
        self.out.rest[k] = s.rest;
        write_bias(self.out.bias, self.out.bias_sigma, &mut self.sigma, k, s);
    }

    #[inline(always)]
    fn overflowed(&self, s: &RobustState) -> bool {
        !(attitude_half_sum(s) + window_half_sum(s)).is_finite()
    }
}

/// The attitude half's state, summed: non-finite once it overflowed.
#[inline(always)]
fn attitude_half_sum(s: &RobustState) -> f64 {
    s.bias.sum() + s.lp_s1.sum()
}

/// The window half's state (the output attitude and the heading pair), summed: non-finite once
/// it overflowed; both are unit, so the sum of the two halves overflows only with one of them.
#[inline(always)]
fn window_half_sum(s: &RobustState) -> f64 {
    s.q.coords.sum() + s.heading.sum()
}

/// Row `k` of the bias and its σ from `s`.
#[inline(always)]
fn write_bias(bias: &mut [[f64; 3]], bias_sigma: &mut [[f64; 3]], sigma: &mut Sigma, k: usize, s: &RobustState) {
    bias[k] = s.bias.into();
    bias_sigma[k] = sigma.of(&s.bias_cov);
}

crate::simd_dispatch! {
    widest = avx2;
    /// [`Robust::run_part`] on checked inputs: the loop of its sensor set, per instruction-set
    /// path.
    fn run_any(
        f: &Robust,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        start: (usize, bool),
        attitude: bool,
        out: &mut Outputs<'_>,
        cancel: &Cancel
    ) -> Result<()> {
        match (inputs.mag, attitude) {
            (Some(m), true) => f.run_loop::<true, _>(state, inputs, m, start, &mut Whole::<true>::new(f, out), cancel),
            (Some(m), false) => f.run_loop::<true, _>(state, inputs, m, start, &mut Whole::<false>::new(f, out), cancel),
            (None, true) => f.run_loop::<false, _>(state, inputs, &[], start, &mut Whole::<true>::new(f, out), cancel),
            (None, false) => f.run_loop::<false, _>(state, inputs, &[], start, &mut Whole::<false>::new(f, out), cancel),
        }
    }
}

/// Every input row count equal to `t`'s.
fn check_lengths(inputs: &Inputs<'_>) -> Result<()> {
    let n = inputs.t.len();
    for (name, x) in [
        ("gyro", Some(inputs.gyro)),
        ("accel", Some(inputs.accel)),
        ("mag", inputs.mag),
    ] {
        if let Some(x) = x.filter(|x| x.len() != n) {
            return Err(Error::RowCount {
                input: n,
                output: x.len(),
            }
            .in_argument(name));
        }
    }
    Ok(())
}

/// The error naming the first non-finite input of sample `k` (a finite sum overflowing is none).
fn non_finite(k: usize, t: f64, gyro: &Vector3<f64>, accel: &Vector3<f64>, mag: Option<&Vector3<f64>>) -> Result<()> {
    let bad = [
        ("t", !t.is_finite()),
        ("gyro", !finite(gyro)),
        ("accel", !finite(accel)),
        ("mag", mag.is_some_and(|m| !finite(m))),
    ];
    match bad.iter().find(|(_, b)| *b) {
        Some((name, _)) => Err(Error::NonFinite { index: k }.in_argument(name)),
        None => Ok(()),
    }
}

/// Finite input so large that the state overflowed.
fn check_overflow(s: &RobustState, index: usize) -> Result<()> {
    if (attitude_half_sum(s) + window_half_sum(s)).is_finite() {
        Ok(())
    } else {
        Err(Error::Overflow { index })
    }
}
