//! Strapdown integration: position, velocity and attitude from IMU samples.
//!
//! | item | convention |
//! |---|---|
//! | state | `p` \[m\], `v` [m/s] in the world frame, `q = q_wb` (body to world, Hamilton) |
//! | inputs | `ω_m` [rad/s] and specific force `a_m` [m/s²] in the body frame, biases `b_g`, `b_a` |
//! | model | `ṗ = v`, `v̇ = R (a_m − b_a) + g`, `Ṙ = R [ω_m − b_g]×`; g added (default `(0, 0, −9.81)`) |
//! | output | [`StatesOut`]: `n` rows `[p (3), v (3)]` and `n` rows `q (4, xyzw)`; row 0 = the initial state |
//!
//! Schemes over step `k → k+1`, `h = t[k+1] − t[k]`, `â = a_m − b_a`, `ω̂ = ω_m − b_g`:
//!
//! | scheme | update | order |
//! |---|---|---|
//! | [`Scheme::LieEuler`] | `a = R_k â_k + g`; `p += v h + ½ a h²`; `v += a h`; `R ← R Exp(ω̂_k h)` | 1 |
//! | [`Scheme::Midpoint`] | `R⁺ = R Exp(½(ω̂_k + ω̂_{k+1}) h)`; `a = ½(R_k â_k + R⁺ â_{k+1}) + g`; then as lie_euler | 2 |
//! | [`Scheme::Rk4`] | classical RK4 on the ODE; mid-step `ω`, `a` from the local cubic | 4 |
//! | [`Scheme::Exp`] | exact for `ω̂_k`, `â_k` held over the step: `v += R Γ₁ â h + g h`, `p += v h + R Γ₂ â h² + ½ g h²` | 1 (exact for constant input) |
//!
//! `Γ₁ = J_l(ω̂ h)` and `Γ₂` = [`so3::exp_double_integral`]`(ω̂ h)`. The seed's discrete model
//! omits the ½ on the position term; with it, the lie_euler scheme is the exact solution for a
//! world-frame acceleration held over the step.
//!
//! **Rotating world** ([`Options::earth_rate`] `ω` non-zero, e.g. a [`crate::earth::LocalLevel`]
//! frame): the world turns at `ω` (in world axes), so `Ṙ = R [ω̂]× − [ω]× R` and
//! `v̇ = R â + g − 2 ω × v` (Titterton & Weston 2004, eq. 3.33, without the centrifugal change
//! across the frame). Every rotation the scheme forms is left-multiplied by `Exp(−ω τ)` for its
//! time τ into the step (exact for constant ω), and the Coriolis acceleration `−2 ω × v` is added to
//! `g`, evaluated at the step's start (lie_euler, exp) or at its mid-point estimate (midpoint) and
//! inside each stage (rk4); exp's `Γ₁`, `Γ₂` take the body rate less the world's, `ω̂ − Rᵀω`
//! (exact at rest). With `ω = 0` (the default) the loops are those without these terms.

use std::ops::Range;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::imu::{Bias, NavState, Samples};
use crate::interp::{Cubic, StepInterpolator};
use crate::{imu, quat, so3, Cancel, Error, Result};

mod chunks;
pub use chunks::CHUNK;

/// Integration scheme; see the module table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// First order, samples at the start of the step, `R Exp(ω̂_k h)`; formerly named `euler`.
    LieEuler,
    /// VINS-style midpoint: averaged rates, specific force rotated at both ends.
    Midpoint,
    /// Classical Runge–Kutta with cubic-interpolated inputs.
    Rk4,
    /// Closed form for inputs held constant over the step (zero-order hold).
    Exp,
}

crate::named_enum!(
    Scheme,
    "scheme",
    [LieEuler => "lie_euler", Midpoint => "midpoint", Rk4 => "rk4", Exp => "exp"],
    // Deprecated: `euler` means forward Euler on the ODE in attitude integration.
    aliases ["euler" => LieEuler]
);

// Scheme tags for the const-generic step (an enum cannot be a const parameter on stable Rust).
const EULER: u8 = 0;
const MIDPOINT: u8 = 1;
const RK4: u8 = 2;
const EXP: u8 = 3;

/// Options of [`integrate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Integration scheme.
    pub scheme: Scheme,
    /// Gravity in the world frame [m/s²], added to the rotated specific force.
    pub gravity: Vector3<f64>,
    /// Rotation rate of the world frame relative to inertial space, in world axes [rad/s] (module
    /// docs); zero for an inertial world.
    pub earth_rate: Vector3<f64>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            scheme: Scheme::Midpoint,
            gravity: imu::gravity(),
            earth_rate: Vector3::zeros(),
        }
    }
}

/// Where every state goes: two separate buffers, so that the quaternions form a contiguous
/// `(n, 4)` array that scipy can own while the `(n, 6)` positions and velocities stay read-only.
#[derive(Debug)]
pub struct StatesOut<'a> {
    /// `n` rows `[p, v]`.
    pub position_velocity: &'a mut [[f64; 6]],
    /// `n` rows `q` (`[x, y, z, w]`).
    pub rotation: &'a mut [[f64; 4]],
}

impl StatesOut<'_> {
    /// The same rows, borrowed again.
    fn reborrow(&mut self) -> StatesOut<'_> {
        StatesOut {
            position_velocity: self.position_velocity,
            rotation: self.rotation,
        }
    }

    pub(crate) fn check(&self, n: usize) -> Result<()> {
        for len in [self.position_velocity.len(), self.rotation.len()] {
            if len != n {
                return Err(Error::RowCount { input: n, output: len }.in_argument("states"));
            }
        }
        Ok(())
    }

    pub(crate) fn store(&mut self, k: usize, x: &NavState) {
        let (p, v, q) = (x.position, x.velocity, x.rotation.coords);
        self.position_velocity[k] = [p.x, p.y, p.z, v.x, v.y, v.z];
        self.rotation[k] = [q.x, q.y, q.z, q.w];
    }

    /// The state stored at row `k`.
    pub(crate) fn load(&self, k: usize) -> NavState {
        let ([px, py, pz, vx, vy, vz], [x, y, z, w]) = (self.position_velocity[k], self.rotation[k]);
        NavState {
            position: Vector3::new(px, py, pz),
            velocity: Vector3::new(vx, vy, vz),
            rotation: UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z)),
        }
    }

    /// The first stored state with a non-finite value.
    fn first_non_finite(&self) -> Option<usize> {
        let pv = self.position_velocity.iter();
        pv.zip(self.rotation.iter())
            .position(|(a, b)| a.iter().any(|v| !v.is_finite()) || !crate::quat::is_unit_coords(b))
    }
}

/// One step of the chosen scheme from sample k to k+1, biases already removed by `inputs`.
pub(crate) struct Stepper<'a> {
    samples: Samples<'a>,
    bias: Bias,
    options: Options,
    mid_gyro: StepInterpolator<'a, 1>,
    mid_accel: StepInterpolator<'a, 1>,
}

impl<'a> Stepper<'a> {
    pub(crate) fn new(samples: Samples<'a>, bias: Bias, options: Options) -> Self {
        Self {
            samples,
            bias,
            options,
            mid_gyro: StepInterpolator::new(Cubic::new(samples.t, samples.gyro.as_flattened()), [0.5]),
            mid_accel: StepInterpolator::new(Cubic::new(samples.t, samples.accel.as_flattened()), [0.5]),
        }
    }

    /// Steps from `x0` through all samples, validating each step's inputs, and calls
    /// `visit(k, state_k, state_k+1)` after each step. The scheme is matched once, outside the
    /// loop, so each loop is compiled for its scheme alone.
    pub(crate) fn run(
        &self,
        x0: NavState,
        visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
    ) -> Result<NavState> {
        self.run_steps(x0, 0..self.samples.t.len() - 1, visit)
    }

    /// [`Stepper::run`] compiled into its caller instead of dispatched: for a caller that is
    /// itself one instruction-set copy (`propagate`'s block loops, whose AVX-512 path runs their
    /// AVX2 copy). Dispatched, the AVX-512 copy of the loop ran under that caller and passed the
    /// state on through overlapping 64-byte copies, which the next step's 32-byte load could not
    /// forward from (16% of a propagate run in `perf annotate` on one instruction).
    #[inline(always)]
    pub(crate) fn run_here(
        &self,
        x0: NavState,
        visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
    ) -> Result<NavState> {
        let steps = 0..self.samples.t.len() - 1;
        if self.options.earth_rate == Vector3::zeros() {
            self.drive_scheme::<false>(x0, steps, visit)
        } else {
            self.drive_scheme::<true>(x0, steps, visit)
        }
    }

    /// [`Stepper::run`] over the steps `k → k+1` for `k` in `steps`, from `x0` at sample
    /// `steps.start` (a chunk of a longer run, `chunks.rs`).
    pub(crate) fn run_steps(
        &self,
        x0: NavState,
        steps: Range<usize>,
        visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
    ) -> Result<NavState> {
        if self.options.earth_rate == Vector3::zeros() {
            drive_inertial(self, x0, steps, visit)
        } else {
            drive_rotating(self, x0, steps, visit)
        }
    }

    /// The loop of this stepper's scheme, matched once outside the loop.
    #[inline(always)]
    fn drive_scheme<const E: bool>(
        &self,
        x0: NavState,
        steps: Range<usize>,
        visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
    ) -> Result<NavState> {
        match self.options.scheme {
            Scheme::LieEuler => self.drive::<EULER, E>(x0, steps, visit),
            Scheme::Midpoint => self.drive::<MIDPOINT, E>(x0, steps, visit),
            Scheme::Rk4 => self.drive::<RK4, E>(x0, steps, visit),
            Scheme::Exp => self.drive::<EXP, E>(x0, steps, visit),
        }
    }

    #[inline(always)]
    fn drive<const S: u8, const E: bool>(
        &self,
        x0: NavState,
        steps: Range<usize>,
        mut visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
    ) -> Result<NavState> {
        let samples = &self.samples;
        if steps.start == 0 && !samples.first_ok() {
            return Err(samples.value_error());
        }
        let mut x = x0;
        let mut rotated = None;
        for k in steps {
            if !samples.step_ok(k) {
                return Err(samples.value_error());
            }
            let mut next = self.step::<S, E>(&x, k, &mut rotated);
            if (k + 1).is_multiple_of(RENORMALIZE_EVERY) {
                // One Newton step on 1/|q| (|q| is 1 to rounding): no square root needed.
                let q = next.rotation.quaternion();
                next.rotation = UnitQuaternion::new_unchecked(q * (1.5 - 0.5 * q.norm_squared()));
            }
            visit(k, &x, &next)?;
            x = next;
        }
        Ok(x)
    }

    /// The state at sample k+1 from the state at sample k. `rotated` carries `R_k â_k` from the
    /// previous midpoint step (its `R⁺ â_{k+1}`), so each specific force is rotated once. `E`: the
    /// rotating-world terms (module docs).
    #[inline(always)]
    fn step<const S: u8, const E: bool>(&self, x: &NavState, k: usize, rotated: &mut Option<Vector3<f64>>) -> NavState {
        let s = &self.samples;
        let h = s.t[k + 1] - s.t[k];
        let omega = self.options.earth_rate;
        // The world's turn over τ, applied on the left of a body attitude.
        let turn = |q: UnitQuaternion<f64>, tau: f64| {
            if E {
                UnitQuaternion::new_unchecked(quat::multiply(quat::exp(&(omega * -tau)).quaternion(), q.quaternion()))
            } else {
                q
            }
        };
        // Gravity plus the Coriolis acceleration at velocity `v`.
        let g_at = |v: &Vector3<f64>| {
            if E {
                self.options.gravity - omega.cross(v) * 2.0
            } else {
                self.options.gravity
            }
        };
        let g = g_at(&x.velocity);
        let w0 = s.gyro_at(k) - self.bias.gyro;
        let a0 = s.accel_at(k) - self.bias.accel;
        let (p, v, q) = (x.position, x.velocity, x.rotation);
        match S {
            EULER => {
                let acc = quat::rotate_unit(&q, &a0) + g;
                NavState {
                    position: p + v * h + acc * (0.5 * h * h),
                    velocity: v + acc * h,
                    rotation: turn(compose(&q, &(w0 * h)), h),
                }
            }
            MIDPOINT => {
                let w1 = s.gyro_at(k + 1) - self.bias.gyro;
                let a1 = s.accel_at(k + 1) - self.bias.accel;
                let q1 = turn(compose(&q, &((w0 + w1) * (0.5 * h))), h);
                let r0 = rotated.unwrap_or_else(|| quat::rotate_unit(&q, &a0));
                let r1 = quat::rotate_unit(&q1, &a1);
                *rotated = Some(r1);
                let force = (r0 + r1) * 0.5;
                // Coriolis at the step's mid-point velocity, so the scheme stays second order.
                let acc = if E {
                    force + g_at(&(v + (force + g) * (0.5 * h)))
                } else {
                    force + g
                };
                NavState {
                    position: p + v * h + acc * (0.5 * h * h),
                    velocity: v + acc * h,
                    rotation: q1,
                }
            }
            EXP => {
                let phi = w0 * h;
                // The specific force turns in the world at the body rate less the world's own
                // (`Exp(−ωτ) R Exp(ω̂τ) = R Exp((ω̂ − Rᵀω)τ)` to O(τ² |ω| |ω̂|)): with `ω̂` alone a sensor
                // at rest on the Earth read a spurious `½ h ω × f` (113 m in 1 h at 10 Hz, 60° N).
                let relative = if E {
                    (w0 - quat::rotate_unit(&q.inverse(), &omega)) * h
                } else {
                    phi
                };
                let dv = quat::rotate_unit(&q, &(so3::left_jacobian(&relative) * a0)) * h;
                let dp = quat::rotate_unit(&q, &(so3::exp_double_integral(&relative) * a0)) * (h * h);
                NavState {
                    position: p + v * h + dp + g * (0.5 * h * h),
                    velocity: v + dv + g * h,
                    rotation: turn(compose(&q, &phi), h),
                }
            }
            _ => {
                let [wm] = self.mid_gyro.at(k);
                let [am] = self.mid_accel.at(k);
                let wm = wm - self.bias.gyro;
                let am = am - self.bias.accel;
                let w1 = s.gyro_at(k + 1) - self.bias.gyro;
                let a1 = s.accel_at(k + 1) - self.bias.accel;
                // y = (p, v, q) with q unnormalised inside the step; R(q) uses q/|q|.
                let f = |v: &Vector3<f64>, q: &Quaternion<f64>, w: &Vector3<f64>, a: &Vector3<f64>| {
                    let rot = UnitQuaternion::new_normalize(*q);
                    let mut dq = quat::multiply(q, &Quaternion::from_imag(*w)) * 0.5;
                    if E {
                        dq -= quat::multiply(&Quaternion::from_imag(omega), q) * 0.5;
                    }
                    (*v, quat::rotate_unit(&rot, a) + g_at(v), dq)
                };
                let q0 = q.into_inner();
                let (dp1, dv1, dq1) = f(&v, &q0, &w0, &a0);
                let (dp2, dv2, dq2) = f(&(v + dv1 * (0.5 * h)), &(q0 + dq1 * (0.5 * h)), &wm, &am);
                let (dp3, dv3, dq3) = f(&(v + dv2 * (0.5 * h)), &(q0 + dq2 * (0.5 * h)), &wm, &am);
                let (dp4, dv4, dq4) = f(&(v + dv3 * h), &(q0 + dq3 * h), &w1, &a1);
                let c = h / 6.0;
                NavState {
                    position: p + (dp1 + dp2 * 2.0 + dp3 * 2.0 + dp4) * c,
                    velocity: v + (dv1 + dv2 * 2.0 + dv3 * 2.0 + dv4) * c,
                    rotation: UnitQuaternion::new_normalize(q0 + (dq1 + dq2 * 2.0 + dq3 * 2.0 + dq4) * c),
                }
            }
        }
    }
}

/// `q ⊗ Exp(θ)`, not renormalised: [`Stepper::run`] does that every [`RENORMALIZE_EVERY`] steps.
#[inline]
fn compose(q: &UnitQuaternion<f64>, theta: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(quat::multiply(q.quaternion(), quat::exp_step(theta).quaternion()))
}

/// A product of unit quaternions drifts from unit norm by rounding only (≈ 1e-16 per step);
/// renormalising every 16 steps keeps |q| within ~1e-15 of 1 and takes the renormalisation, a
/// dependent chain as long as the product itself, off most steps (it cost 18 ns a sample).
const RENORMALIZE_EVERY: usize = 16;

/// Integrates the samples from `initial`, writing every state to `out` when given; returns the
/// final state. No allocation per sample.
pub fn integrate(
    samples: &Samples<'_>,
    initial: &NavState,
    bias: &Bias,
    options: &Options,
    out: Option<StatesOut<'_>>,
) -> Result<NavState> {
    integrate_cancellable(samples, initial, bias, options, out, &Cancel::new())
}

/// [`integrate`], stopping with [`Error::Interrupted`] when `cancel` is set (polled every
/// [`Cancel::EVERY`] samples).
pub fn integrate_cancellable(
    samples: &Samples<'_>,
    initial: &NavState,
    bias: &Bias,
    options: &Options,
    mut out: Option<StatesOut<'_>>,
    cancel: &Cancel,
) -> Result<NavState> {
    let n = samples.t.len();
    if let Some(out) = out.as_ref() {
        out.check(n)?;
    }
    check_parameters(initial, bias, options)?;
    if let Some(out) = out.as_mut() {
        out.store(0, initial);
    }
    let stepper = Stepper::new(*samples, *bias, *options);
    if chunks::chunked(n, options) {
        let without_gravity = Stepper::new(
            *samples,
            *bias,
            Options {
                gravity: Vector3::zeros(),
                ..*options
            },
        );
        let x = chunks::integrate(
            samples,
            initial,
            (&stepper, &without_gravity),
            out.as_mut().map(StatesOut::reborrow),
            cancel,
        )?;
        check_finite_result(&x, out.as_ref(), (samples, initial, bias, options))?;
        return Ok(x);
    }
    let x = stepper.run(*initial, |k, _, next| {
        if let Some(out) = out.as_mut() {
            out.store(k + 1, next);
        }
        cancel.check(k)
    })?;
    check_finite_result(&x, out.as_ref(), (samples, initial, bias, options))?;
    Ok(x)
}

/// Finite inputs can still overflow (e.g. 1e200 rad/s): refuse a non-finite result, naming the
/// first non-finite stored state when there is a store, else the last sample, under the input
/// whose term of the sum dominates ([`overflow_culprit`]). An RK4 step can also overflow only the
/// quaternion's norm: `q/|q|` with `|q|² = inf` is the zero quaternion, finite but no rotation, so
/// an attitude off the unit sphere is refused the same way (a rate's fault: `imu` or `bias`).
pub(crate) fn check_finite_result(
    x: &NavState,
    out: Option<&StatesOut<'_>>,
    run: (&Samples<'_>, &NavState, &Bias, &Options),
) -> Result<()> {
    let finite = x.position.iter().chain(x.velocity.iter()).all(|v| v.is_finite());
    let unit = crate::quat::is_unit_coords(x.rotation.coords.as_slice());
    if finite && unit {
        return Ok(());
    }
    let (samples, initial, bias, options) = run;
    let n = samples.t.len();
    let index = out.and_then(StatesOut::first_non_finite).unwrap_or(n - 1);
    Err(Error::Overflow { index }.in_argument(overflow_culprit(samples, initial, bias, options, unit)))
}

/// The input to blame for an overflow of the mean: when the attitude left the unit sphere (a
/// rotation overflowed by `|ω − b_g|`, which then spoils position and velocity too) the rates or the
/// gyro bias, whichever is larger; else the largest term of `p = p₀ + v₀T + ½(R(a − b_a) + g)T²`
/// over the span T. Errors in Python then name the argument the user can change (`initial`, `imu`,
/// `bias`, `gravity`), not "imu / bias".
fn overflow_culprit(
    samples: &Samples<'_>,
    initial: &NavState,
    bias: &Bias,
    options: &Options,
    unit: bool,
) -> &'static str {
    if unit {
        let n = samples.t.len();
        let span = (samples.t[n - 1] - samples.t[0]).max(f64::MIN_POSITIVE);
        let reach = span.max(span * span);
        let terms = [
            (
                "initial",
                initial.position.amax().max(initial.velocity.amax() * span.max(1.0)),
            ),
            ("imu", largest(samples.accel) * reach),
            ("bias", bias.accel.amax() * reach),
            ("gravity", options.gravity.amax() * reach),
        ];
        return terms.iter().fold(terms[0], |m, t| if t.1 > m.1 { *t } else { m }).0;
    }
    if bias.gyro.amax() > largest(samples.gyro) {
        "bias"
    } else {
        "imu"
    }
}

crate::simd_dispatch! {
    /// [`Stepper::run`] in an inertial world: the loop of the scheme of `stepper` (matched once,
    /// outside the loop, so each loop is compiled for its scheme alone), per instruction-set path.
    /// The rotating-world loops are a function of their own ([`drive_rotating`]), so the default
    /// loops are the four they were before those terms (issue 20's regression hunt).
    fn drive_inertial(
        stepper: &Stepper<'_>,
        x0: NavState,
        steps: Range<usize>,
        visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
    ) -> Result<NavState> {
        stepper.drive_scheme::<false>(x0, steps, visit)
    }
}

crate::simd_dispatch! {
    /// [`drive_inertial`] with the rotating-world terms (module docs).
    fn drive_rotating(
        stepper: &Stepper<'_>,
        x0: NavState,
        steps: Range<usize>,
        visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
    ) -> Result<NavState> {
        stepper.drive_scheme::<true>(x0, steps, visit)
    }
}

/// The largest magnitude in `rows` (0 for none): the size of a reading stream in the overflow blame.
pub(crate) fn largest(rows: &[[f64; 3]]) -> f64 {
    rows.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()))
}

/// Finite initial state, biases and gravity.
pub(crate) fn check_parameters(initial: &NavState, bias: &Bias, options: &Options) -> Result<()> {
    let finite = |name: &'static str, values: &[f64]| {
        if values.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(Error::NonFinite { index: 0 }.in_argument(name))
        }
    };
    finite("initial.position", initial.position.as_slice())?;
    finite("initial.velocity", initial.velocity.as_slice())?;
    finite("initial.rotation", initial.rotation.coords.as_slice())?;
    finite("bias.gyro", bias.gyro.as_slice())?;
    finite("bias.accel", bias.accel.as_slice())?;
    finite("gravity", options.gravity.as_slice())
}
