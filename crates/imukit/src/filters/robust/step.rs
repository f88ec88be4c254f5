//! One online step of [`super::Robust`] (internal ENU frame; the equations are in `super`'s
//! module doc and `docs/filters_robust.md`).

use std::ops::{Add, AddAssign, Mul, Sub};

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector2, Vector3};

use super::params::RobustParams;
use super::state::RobustState;
use crate::filters::gate::dip_z_up;
use crate::filters::{initial_attitude, World};
use crate::lie::series::{atan2, half_angle_small};
use crate::quat::{exp_step, multiply};

/// The coefficients that depend on the step `dt` only, recomputed when it changes by more than
/// the rounding of timestamps: they are computed from `dt` with its 20 lowest mantissa bits
/// cleared (relative change < 2.4e-10), so that steps differing only in the last bits, as
/// differences of `k / rate` do, share one computation (a tangent, four exponentials and a cosine,
/// a tenth of a step) in a batch run and in streaming alike; the batch loops keep the last four
/// keys' ([`CoefsCache`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Coefs {
    /// The step \[s\], exactly (the others are computed from its key).
    pub(super) dt: f64,
    key: f64,
    // Butterworth, direct form II transposed: y = b0 x + s1; s1 ← b1 x − a1 y + s2; s2 ← b2 x − a2 y.
    b0: f64,
    b1: f64,
    a1: f64,
    a2: f64,
    rest: f64,
    rest_noise: f64,
    mag: f64,
    mag_slow: f64,
    /// `cos θ` of the dip threshold θ = `mag_dip_rad` (−∞ for θ ≥ π, where every dip is near).
    cos_dip: f64,
}

impl Coefs {
    /// For step `dt` \[s\] (a non-positive step, the first sample's, gives inert coefficients).
    pub(super) fn new(p: &RobustParams, dt: f64) -> Self {
        let exact = dt;
        let key = Self::key(dt);
        let dt = key;
        // Bilinear transform of the analogue 2nd-order Butterworth with cut-off 1/(2π τ), prewarped
        // (Oppenheim & Schafer, Discrete-Time Signal Processing, 3rd ed., §7.1.2). The prewarp's
        // tangent grows without bound as the step nears π τ, where the poles reach z = −1, and
        // wraps past it (unstable: a 30 s gap at τ = 2 s left the estimate 60° off); a step
        // beyond π τ / 2 (the cut-off past a quarter of the step's rate, the poles at ±0.41 i)
        // is filtered as one of π τ / 2.
        let k = (dt / (2.0 * p.tau_acc_s)).min(std::f64::consts::FRAC_PI_4).tan();
        let n = 1.0 / (1.0 + std::f64::consts::SQRT_2 * k + k * k);
        let b0 = k * k * n;
        let first_order = |tau: f64| 1.0 - (-dt / tau).exp();
        Self {
            dt: exact,
            key,
            b0,
            b1: 2.0 * b0,
            a1: 2.0 * (k * k - 1.0) * n,
            a2: (1.0 - std::f64::consts::SQRT_2 * k + k * k) * n,
            rest: first_order(p.rest_tau_s),
            rest_noise: first_order(p.rest_noise_tau_s),
            mag: first_order(p.tau_mag_s),
            mag_slow: first_order(p.tau_mag_s * p.mag_slow_factor),
            cos_dip: if p.mag_dip_rad < std::f64::consts::PI {
                p.mag_dip_rad.cos()
            } else {
                f64::NEG_INFINITY
            },
        }
    }

    /// `dt` with its 20 lowest mantissa bits cleared: what the coefficients are computed from.
    #[inline(always)]
    fn key(dt: f64) -> f64 {
        f64::from_bits(dt.to_bits() & !0xf_ffff)
    }
}

/// [`Coefs`] of the last four keys. Stamps in float seconds make steps that differ in their last
/// bits, and once the stamps' own rounding reaches the key's resolution (at 200 Hz, from about
/// 1000 s on) consecutive steps alternate between two or three keys: 44% of the steps of
/// `bench/_timing.synthetic_imu`'s 10^6 samples computed the tangent and exponentials again with
/// one remembered key. Each key's coefficients are the same whenever they are computed, so the
/// results do not depend on what the cache holds.
#[derive(Debug, Clone, Copy)]
pub(super) struct CoefsCache {
    slots: [Coefs; 4],
    next: usize,
}

impl CoefsCache {
    /// A cache holding `first`'s key.
    pub(super) fn new(first: Coefs) -> Self {
        Self {
            slots: [first; 4],
            next: 0,
        }
    }

    /// The coefficients for step `dt`: a remembered key's, else new ones, which replace the
    /// oldest remembered.
    #[inline(always)]
    pub(super) fn for_dt(&mut self, p: &RobustParams, dt: f64) -> Coefs {
        let key = Coefs::key(dt);
        if let Some(c) = self.slots.iter().find(|c| c.key == key) {
            return Coefs { dt, ..*c };
        }
        let c = Coefs::new(p, dt);
        self.slots[self.next] = c;
        self.next = (self.next + 1) % self.slots.len();
        c
    }
}

impl Coefs {
    /// One Butterworth step of input `x` with delay elements `s1`, `s2` (per element).
    #[inline(always)]
    pub(super) fn butter<T>(&self, x: T, s1: &mut T, s2: &mut T) -> T
    where
        T: Copy + Add<Output = T> + Sub<Output = T> + Mul<f64, Output = T>,
    {
        let y = x * self.b0 + *s1;
        *s1 = x * self.b1 - y * self.a1 + *s2;
        *s2 = x * self.b0 - y * self.a2;
        y
    }

    /// One zero-input step of [`Coefs::butter`] applied to a state given as a linear map `m` of
    /// some earlier state (rows: `s1`, `s2`; columns: the earlier `s1`, `s2`): with no input,
    /// `s1 ← −a1 s1 + s2`, `s2 ← −a2 s1` (and the output is `s1`).
    ///
    /// The map decays (the poles are inside the unit circle); it is set to zero once every entry
    /// is below 1e-150 (its share of the state is then below the state's rounding by 130 orders),
    /// before it reaches the subnormal numbers, on which each multiply takes about a hundred
    /// cycles on x86.
    #[inline(always)]
    pub(super) fn free_step(&self, m: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
        let next = [
            [m[1][0] - self.a1 * m[0][0], m[1][1] - self.a1 * m[0][1]],
            [-self.a2 * m[0][0], -self.a2 * m[0][1]],
        ];
        let largest = next[0][0]
            .abs()
            .max(next[0][1].abs())
            .max(next[1][0].abs().max(next[1][1].abs()));
        if largest < 1e-150 {
            [[0.0; 2]; 2]
        } else {
            next
        }
    }

    /// The map of the delay elements `(s1, s2)` from coefficients `from` to these, for a step that
    /// changed by more than a factor of 1.5 (a gap in the stamps, a new rate, a dropped sample;
    /// [`carry`] decides).
    ///
    /// The direct form's elements depend on the coefficients: a 2 s gap at τ = 2 s left elements
    /// that, read with the gap's coefficients, gave −6.6 times the input (the estimate upside down
    /// for 7 s). The elements are read as what they are in the steady response to a ramp, its level
    /// `X` at the last sample and its slope `S` per second ([`Coefs::ramp`]), and written back as
    /// the same ramp's under the new coefficients: `(s1, s2) ← R′ R⁻¹ (s1, s2)`, exact for any
    /// ramp. Restarting at the level alone (the slope dropped, until 2026-12-07) lost the low
    /// pass's memory of the motion at every dropped sample: 0.5 % of BROAD trial 08's samples
    /// dropped took its online 6D inclination from 1.3° to 2.5°. Linear in `(s1, s2)`, so it
    /// applies to the smoother's maps of the state as well.
    fn carry_from(&self, from: &Coefs) -> Carry {
        let (to, old) = (self.ramp(), from.ramp());
        let det = old[0][0] * old[1][1] - old[0][1] * old[1][0];
        let inv = [[old[1][1] / det, -old[0][1] / det], [-old[1][0] / det, old[0][0] / det]];
        Carry {
            m: [0, 1].map(|r| [0, 1].map(|c| to[r][0] * inv[0][c] + to[r][1] * inv[1][c])),
        }
    }

    /// The delay elements after a sample in the steady response to the ramp `x_j = X + S (t_j −
    /// t_k)` as a matrix on `(X, S)`: the output lags by `ℓ` steps, `y_j = x_j − S ℓ dt`, and
    /// `s2 = b0 X − a2 Y`, `s1 = b1 X − a1 Y + b0 (X − S dt) − a2 (Y − S dt)` with `Y = X − S ℓ dt`
    /// (`b2 = b0`). `ℓ = (b1 + 2 b0 − a1 − 2 a2) / (2 b0 + b1)` from `y_k = Σ b x − Σ a y` on
    /// the ramp, the DC gain `(2 b0 + b1)/(1 + a1 + a2)` being 1.
    fn ramp(&self) -> [[f64; 2]; 2] {
        let (b0, b1, a1, a2, h) = (self.b0, self.b1, self.a1, self.a2, self.dt);
        let lag = (b1 + 2.0 * b0 - a1 - 2.0 * a2) / (2.0 * b0 + b1);
        [
            [b1 + b0 - a1 - a2, ((a1 + a2) * lag + a2 - b0) * h],
            [b0 - a2, a2 * lag * h],
        ]
    }

    /// The delay elements `(s1, s2)` of [`Coefs::butter`] in steady state for the constant input
    /// `x` (its output is then `x`: the DC gain is 1).
    pub(super) fn steady<T>(&self, x: T) -> (T, T)
    where
        T: Copy + Add<Output = T> + Mul<f64, Output = T>,
    {
        let s2 = x * (self.b0 - self.a2);
        (x * (self.b1 - self.a1) + s2, s2)
    }
}

/// [`Coefs::carry_from`]'s map: `(s1, s2) ← m (s1, s2)`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Carry {
    m: [[f64; 2]; 2],
}

impl Carry {
    /// Maps the delay elements in place.
    pub(super) fn apply<T>(&self, s1: &mut T, s2: &mut T)
    where
        T: Copy + Add<Output = T> + Mul<f64, Output = T>,
    {
        let (a, b, m) = (*s1, *s2, &self.m);
        *s1 = a * m[0][0] + b * m[0][1];
        *s2 = a * m[1][0] + b * m[1][1];
    }

    /// A linear map of some earlier state (rows `s1`, `s2`, as [`Coefs::free_step`]'s) mapped.
    pub(super) fn apply_map(&self, map: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
        let m = &self.m;
        [0, 1].map(|r| [0, 1].map(|c| m[r][0] * map[0][c] + m[r][1] * map[1][c]))
    }
}

/// The map of the delay elements to coefficients `c` from the step `from_dt` \[s\] they were
/// last advanced with, [`Coefs::carry_from`], when the step changed by more than a factor of
/// 1.5; none otherwise (0: never advanced; jitter and the rounding of float stamps: the elements
/// carry over as they are). The threshold is away from the ratios a dropped sample makes (2, 3,
/// … and their inverses): at 2 the rounding of the stamps mapped the step into a two-step gap and
/// not the one out of it (or back), and the unmatched map took BROAD trial 08 offline 10° off
/// over 10 s of dropped samples. The steps are compared before the old coefficients, a tangent
/// and four exponentials, are built.
#[inline(always)]
pub(super) fn carry(p: &RobustParams, c: &Coefs, from_dt: f64) -> Option<Carry> {
    if from_dt > 0.0 && (c.dt > 1.5 * from_dt || from_dt > 1.5 * c.dt) {
        Some(c.carry_from(&Coefs::new(p, from_dt)))
    } else {
        None
    }
}

/// The attitude in `world` from the internal ENU one.
#[inline(always)]
pub(super) fn to_world(world: World, q: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    world.attitude_in(World::Enu, q)
}

/// The internal ENU attitude from one in `world`.
pub(super) fn from_world(world: World, q: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    World::Enu.attitude_in(world, q)
}

/// `q ⊗ r` renormalised by one Newton step (both unit: the product is unit to rounding, this
/// stops the rounding from accumulating without a square root).
#[inline(always)]
pub(super) fn compose(q: &UnitQuaternion<f64>, r: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    let p = multiply(q.quaternion(), r.quaternion());
    UnitQuaternion::new_unchecked(p * (0.5 * (3.0 - p.norm_squared())))
}

/// Sets the heading to `psi` \[rad\] ∈ [−π, π]: its angle and `Rz(ψ)` as the pair
/// `(cos ψ/2, sin ψ/2)` (the w, z of its quaternion).
pub(super) fn set_heading(s: &mut RobustState, psi: f64) {
    let (sin, cos) = (0.5 * psi).sin_cos();
    s.heading = Vector2::new(cos, sin);
    s.heading_angle = psi;
}

/// The first sample's heading: the one that turns the field `m_e` (frame `E'`) to north, when it
/// has a horizontal part.
pub(super) fn start_heading(s: &mut RobustState, m_e: &Vector3<f64>) {
    if m_e.x != 0.0 || m_e.y != 0.0 {
        set_heading(s, m_e.x.atan2(m_e.y));
        s.heading_pending = false;
    }
}

/// `x` ∈ [−2π, 2π] wrapped into [−π, π].
#[inline(always)]
pub(super) fn wrap(x: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if x > PI {
        x - TAU
    } else if x < -PI {
        x + TAU
    } else {
        x
    }
}

/// The heading turned by `angle` \[rad\] (`k e`, |angle| ≤ π): the pair by [`turn`], the angle by
/// a wrapped addition. The two are kept side by side so that the filter's loop-carried chain
/// (angle → error → angle) has no `atan2`; they stay equal to rounding (each turn adds an
/// error of about an ulp to each, independently: ~1e-13 rad after 10^6 samples).
#[inline(always)]
pub(super) fn turn_heading(s: &mut RobustState, angle: f64) {
    s.heading = turn(&s.heading, angle);
    s.heading_angle = wrap(s.heading_angle + angle);
}

/// The heading pair `h` turned by `angle` \[rad\] about the vertical, `Rz(angle) ⊗ h`: the half-angle
/// rotation by `series::half_angle_small` (exact to rounding, no libm call below 0.5 rad), whose
/// short series holds below 0.01 rad: the heading loop's `k e` is there whenever the field's gain
/// `k = 1 − exp(−dt/τ_mag)` is below 0.01/π (|e| ≤ π; dt/τ_mag < 0.0032, every rate above 16 Hz
/// at the default τ_mag = 20 s), and a larger angle takes the longer series. Renormalised by one
/// Newton step and with `w ≥ 0`, i.e. `ψ ∈ [−π, π]` (the angle's wrap).
#[inline(always)]
pub(super) fn turn(h: &Vector2<f64>, angle: f64) -> Vector2<f64> {
    let (k, c) = half_angle_small(angle * angle);
    let s = angle * k;
    let p = Vector2::new(h.x * c - h.y * s, h.y * c + h.x * s);
    let p = p * (0.5 * (3.0 - p.norm_squared()));
    if p.x < 0.0 {
        -p
    } else {
        p
    }
}

/// `Rz(ψ) ⊗ q` for the heading pair `h` (both unit: the product is, to rounding).
#[inline(always)]
pub(super) fn yawed(h: &Vector2<f64>, q: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    let (c, s) = (h.x, h.y);
    UnitQuaternion::new_unchecked(Quaternion::new(
        c * q.w - s * q.k,
        c * q.i - s * q.j,
        c * q.j + s * q.i,
        c * q.k + s * q.w,
    ))
}

/// Sets up `s` at the first sample: attitude from `initial` (internal ENU) or from the
/// accelerometer (yaw 0 in `world`, as Mahony's and Madgwick's); the first field sample gives the
/// heading, an initial attitude's too: in 9D north is the field's, and an initial heading from
/// another frame (motion capture's), left to the heading loop, took a minute to converge and its
/// corrections were learned as a vertical bias meanwhile (30° off: 1.4° at 60 s).
pub(super) fn initialise(
    p: &RobustParams,
    world: World,
    s: &mut RobustState,
    initial: Option<UnitQuaternion<f64>>,
    gyro: &Vector3<f64>,
    accel: &Vector3<f64>,
) {
    s.q_gyro = initial.unwrap_or_else(|| from_world(world, &initial_attitude(world, accel, None)));
    s.q_incl = UnitQuaternion::identity();
    set_heading(s, 0.0);
    s.heading_pending = true;
    s.bias_cov = Matrix3::identity() * p.bias_sigma_init_rad_s.powi(2);
    (s.rest_gyro, s.rest_gyro_smooth) = (*gyro, *gyro);
    (s.rest_accel, s.rest_accel_smooth) = (*accel, *accel);
    s.initialized = true;
}

/// One sample on validated input with coefficients `c` for its step `c.dt` (0 on the first
/// sample of an uninitialised state, which only initialises). Updates `s.q` (in `world`).
///
/// A step is an attitude half ([`attitude_half`], [`window_due`], [`update_bias`]) and a window
/// half ([`window_half`]) that write disjoint fields of `s`; the attitude half reads the window
/// half's sums only where a bias window ends. [`super::pipeline`] runs the halves on two threads
/// on exactly these functions.
#[inline(always)]
pub(super) fn step(
    p: &RobustParams,
    world: World,
    c: &Coefs,
    s: &mut RobustState,
    gyro: &Vector3<f64>,
    accel: &Vector3<f64>,
    mag: Option<&Vector3<f64>>,
) {
    if !s.initialized {
        initialise(p, world, s, None, gyro, accel);
        if let Some(m) = mag {
            start_heading(s, &(s.q_gyro * m));
        }
    }
    let (corr, q6) = attitude_half(p, c, s, gyro, accel);
    window_half(p, world, c, s, (&q6, &corr), mag, gyro);
    if let Some(update) = window_due(p, c, s, gyro) {
        update_bias(p, s, update);
    }
}

/// Rest detection, the gyro strapdown and the inclination loop of one sample: returns the
/// inclination correction (x, y \[rad\]) and the attitude up to heading `q6`.
#[inline(always)]
pub(super) fn attitude_half(
    p: &RobustParams,
    c: &Coefs,
    s: &mut RobustState,
    gyro: &Vector3<f64>,
    accel: &Vector3<f64>,
) -> (Vector2<f64>, UnitQuaternion<f64>) {
    if c.dt > 0.0 {
        rest_detection(p, c, s, gyro, accel);
        s.q_gyro = compose(&s.q_gyro, &exp_step(&((gyro - s.bias) * c.dt)));
    }
    let a_i = s.q_gyro * accel;
    if c.dt > 0.0 {
        if s.lp_dt == 0.0 && s.lp_ready && s.lp_s2 == -s.lp_s1 {
            // Started on the first sample, whose coefficients are inert (no step yet): its
            // steady state `(x, −x)` is not this step's, and read with this step's coefficients
            // it was a transient that took the output 28% below the input over the first second
            // (the direction kept, all axes alike), and that a ramp carry then extrapolated: a
            // 2 s gap 0.5 s in turned the estimate upside down. (A state from before `lp_dt` was
            // recorded restores it as 0 with elements that are not `(x, −x)`: carried as is.)
            (s.lp_s1, s.lp_s2) = c.steady(s.lp_s1);
        } else if let Some(m) = carry(p, c, s.lp_dt) {
            m.apply(&mut s.lp_s1, &mut s.lp_s2);
        }
        s.lp_dt = c.dt;
    }
    let starting = !s.lp_ready;
    if starting {
        // Steady state for a constant input: the low pass starts at its first sample.
        s.lp_s2 = a_i * (c.b0 - c.a2);
        s.lp_s1 = a_i * (c.b1 - c.a1) + s.lp_s2;
        s.lp_ready = true;
    }
    let corr = inclination(c, s, &a_i);
    // The first sample's turn aligns a given initial attitude with the accelerometer (from the
    // sensors it is zero): no bias turned it, and counted in the bias window it was learned as one
    // (an initial attitude 5° off gave 0.063 rad/s and a 9.4° tilt later).
    let corr = if starting { Vector2::zeros() } else { corr };
    (corr, compose(&s.q_incl, &s.q_gyro))
}

/// The window half of a step, from the attitude half's `q6` and inclination correction `corr`:
/// (9D) the field's gate and heading loop, the bias window's sums, and the output attitude `s.q`.
/// It reads and writes only the fields [`super::pipeline`] gives its second thread, and the bias
/// `s.bias`, which only [`update_bias`] changes.
#[inline(always)]
pub(super) fn window_half(
    p: &RobustParams,
    world: World,
    c: &Coefs,
    s: &mut RobustState,
    (q6, corr): (&UnitQuaternion<f64>, &Vector2<f64>),
    mag: Option<&Vector3<f64>>,
    gyro: &Vector3<f64>,
) {
    let r6 = *q6.to_rotation_matrix().matrix();
    let rb = r6 * s.bias;
    let mut correction = None;
    if let Some(m) = mag {
        if s.heading_pending {
            // A field that starts after the gyro (streaming): its first sample gives the heading,
            // as the first sample's would have (the loop alone took minutes and its corrections
            // drove the vertical bias to its clip).
            start_heading(s, &(r6 * m));
        }
        if let Some((gain, err)) = magnetometer(p, c, s, &(r6 * m), gyro) {
            turn_heading(s, gain * err);
            correction = Some((gain, gain * err));
        }
    }
    if c.dt > 0.0 {
        window_sums(p, c, s, corr, &r6, &rb);
        if mag.is_some() {
            heading_window(c, s, &r6, rb.z, correction);
        }
    }
    // The heading stays applied on a sample without a field (streaming with a slower
    // magnetometer); before any field it is zero, `yawed` the identity, skipped.
    let q = if s.heading.y == 0.0 { *q6 } else { yawed(&s.heading, q6) };
    s.q = to_world(world, &q);
}

/// Feeds `a_i` (specific force in `I`) to the low pass and rotates `E'` so that its output points
/// up; returns the correction's x, y \[rad\].
#[inline(always)]
fn inclination(c: &Coefs, s: &mut RobustState, a_i: &Vector3<f64>) -> Vector2<f64> {
    let a_f = c.butter(*a_i, &mut s.lp_s1, &mut s.lp_s2);
    // ‖a_f‖ rather than the rotated vector's (equal to rounding): the square root and the
    // division by it depend on the input alone and leave `q_incl`'s loop-carried chain.
    match to_up_norm(&(s.q_incl * a_f), a_f.norm()) {
        Some(qc) => {
            s.q_incl = compose(&qc, &s.q_incl);
            Vector2::new(2.0 * qc.i, 2.0 * qc.j)
        }
        None => Vector2::zeros(),
    }
}

/// The smallest rotation taking the direction of `a` to up (z), none for a zero or overflowing
/// (finite but huge) `a`, which has no direction; 180° about x for `a` pointing down.
#[inline(always)]
pub(super) fn to_up(a: &Vector3<f64>) -> Option<UnitQuaternion<f64>> {
    to_up_norm(a, a.norm())
}

/// [`to_up`] with `an = ‖a‖` given by the caller.
///
/// The rotation taking the unit n to z is ∝ (1 + n_z, n × z) = (1 + n_z, n_y, −n_x, 0)
/// (half-angle identity, no trigonometry), scaled by `1/√(2(1 + n_z))`. With `d = 1 − n_z`
/// that is `½ (1 − d/2)^(−1/2)`, whose binomial series to `d⁴` is exact to rounding for
/// `d < 10⁻³` (the next term is `63/8192 d⁵`, < 8e-18 relative), i.e. every tilt below 2.5°,
/// where the online step's per-sample corrections are: no square root and no division on the
/// inclination loop's chain there.
#[inline(always)]
pub(super) fn to_up_norm(a: &Vector3<f64>, an: f64) -> Option<UnitQuaternion<f64>> {
    if !(an > 1e-9 && an.is_finite()) {
        return None;
    }
    let n = a * (1.0 / an);
    let d = 1.0 - n.z;
    let w = 1.0 + n.z;
    let k = if d < 1e-3 {
        0.5 * (1.0 + d * (0.25 + d * (3.0 / 32.0 + d * (5.0 / 128.0 + d * (35.0 / 2048.0)))))
    } else if w > 1e-9 {
        1.0 / (2.0 * w).sqrt()
    } else {
        return Some(UnitQuaternion::new_unchecked(Quaternion::new(0.0, 1.0, 0.0, 0.0)));
    };
    Some(UnitQuaternion::new_unchecked(Quaternion::new(
        w * k,
        n.y * k,
        -n.x * k,
        0.0,
    )))
}

/// Rest: the gyro and accelerometer, low-passed over `rest_noise_tau_s` (`ω̃`, `ã`), stay
/// close to their window means (`ω̄`, `ā`, low-passed over `rest_tau_s`) and the mean gyro is a
/// bias the estimate allows, for `rest_duration_s`.
///
/// The samples are low-passed before the comparison because the raw deviation `‖ω − ω̄‖` is
/// mostly sensor noise and vibration: a drone's rotors on the ground give 2 °/s per sample (EuRoC
/// V1_02) and a raw test never finds rest; `ω̃` keeps `√(α/(2 − α))` of white noise (α = the
/// step's gain; 0.45 °/s there), passes motion below its 3.2 Hz cut-off and makes the thresholds
/// act on the noise density, whatever the sample rate.
///
/// The mean test is `‖ω̄ − b̂‖² < rest_gyro² + 9 tr P` (P the bias covariance): a sensor at rest
/// reads its bias, which is within 3σ of the estimate. Taken as `‖ω̄ − b̂‖ < rest_gyro` alone it
/// never held before the bias was known when the bias exceeds the threshold (EuRoC: 4.45 °/s);
/// once a rest has measured the bias, P is small and the test is the plain one. The bias is taken
/// off `ω̄` because the raw `‖ω̄‖` of a sensor at rest is `‖b‖` (`docs/filters_robust.md`, bias).
///
/// `ω̃` lags the start of a motion by about `rest_noise_tau_s`, and the rest mean would take in
/// those samples (BROAD 6D heading 2.46° → 2.56°): as in Mahony's rest detection, one raw sample
/// beyond 4× the rms deviation seen so far (floored at a tenth of the threshold) ends the rest at
/// once. Vibration raises the rms with it, so it does not end a rest under vibration.
#[inline(always)]
fn rest_detection(p: &RobustParams, c: &Coefs, s: &mut RobustState, gyro: &Vector3<f64>, accel: &Vector3<f64>) {
    s.rest_gyro += (gyro - s.rest_gyro) * c.rest;
    s.rest_accel += (accel - s.rest_accel) * c.rest;
    s.rest_gyro_smooth += (gyro - s.rest_gyro_smooth) * c.rest_noise;
    s.rest_accel_smooth += (accel - s.rest_accel_smooth) * c.rest_noise;
    let th = p.rest_gyro_rad_s * p.rest_gyro_rad_s;
    let a2 = p.rest_accel * p.rest_accel;
    // Capped: a finite 1e300 m/s² sample must not make the state infinite.
    let dev = Vector2::new(
        (gyro - s.rest_gyro).norm_squared(),
        (accel - s.rest_accel).norm_squared(),
    )
    .map(|x| x.min(f64::MAX));
    let onset = dev.x >= 16.0 * s.rest_ms.x.max(th / 100.0) || dev.y >= 16.0 * s.rest_ms.y.max(a2 / 100.0);
    s.rest_ms += (dev - s.rest_ms) * c.rest;
    let still = !onset
        && (s.rest_gyro_smooth - s.rest_gyro).norm_squared() < th
        && (s.rest_gyro - s.bias).norm_squared() < th + 9.0 * s.bias_cov.trace()
        && (s.rest_accel_smooth - s.rest_accel).norm_squared() < a2;
    s.rest_time = if still { s.rest_time + c.dt } else { 0.0 };
    s.rest = s.rest_time >= p.rest_duration_s;
}

/// What the heading loop needs of one field sample `m_e` (frame E'), computed from the sample and
/// the gyro alone: none of it depends on the filter's state, so a pass over a record
/// ([`super::smoother`]'s heading passes) computes a block of them apart from the loop-carried
/// gate and heading, where the square roots, divisions and `atan2` of successive samples overlap.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Field {
    /// `‖m_e‖`; NaN or ≤ 0 for a sample with no field, which the gate skips.
    norm: f64,
    /// Dip δ below the horizontal (E' vertical being z) as (sin δ, cos δ).
    dip: Vector2<f64>,
    /// Whether the sensor turns faster than `mag_new_field_gyro_rad_s`.
    turning: bool,
    /// The field's angle φ from north (+y), `atan2(m_x, m_y)`; NaN without a horizontal part.
    phi: f64,
}

impl Field {
    #[inline(always)]
    pub(super) fn new(p: &RobustParams, m_e: &Vector3<f64>, gyro: &Vector3<f64>) -> Self {
        let norm = m_e.norm();
        // With δ, δ₀ ∈ [−π/2, π/2], |δ − δ₀| ≤ θ exactly when cos(δ − δ₀) = cos δ cos δ₀ +
        // sin δ sin δ₀ ≥ cos θ (cos decreases on [0, π]), which needs no asin.
        let (dip_sin, dip_cos) = dip_z_up(m_e, norm);
        // North is +y: the heading error is the angle from it of the horizontal field turned by
        // the heading, `Rz(ψ) m`, i.e. the field's own angle φ less ψ, wrapped; φ depends on the
        // field alone, so its `atan2` stays off the heading's loop-carried chain.
        let horizontal = m_e.x != 0.0 || m_e.y != 0.0;
        Self {
            norm,
            dip: Vector2::new(dip_sin, dip_cos),
            turning: gyro.norm_squared() > p.mag_new_field_gyro_rad_s * p.mag_new_field_gyro_rad_s,
            phi: if horizontal { atan2(m_e.x, m_e.y) } else { f64::NAN },
        }
    }
}

/// Disturbance detection and the heading error of field `m_e` (frame E'): `Some((gain, error))`
/// when the field is used. The reference (norm, dip) is learned from the first sample; a field
/// that stays homogeneous while the sensor turns for `mag_new_field_s` becomes the reference.
#[inline(always)]
pub(super) fn magnetometer(
    p: &RobustParams,
    c: &Coefs,
    s: &mut RobustState,
    m_e: &Vector3<f64>,
    gyro: &Vector3<f64>,
) -> Option<(f64, f64)> {
    heading_error(p, c, s, &Field::new(p, m_e, gyro))
}

/// [`magnetometer`] for a field sample already reduced to its [`Field`].
#[inline(always)]
pub(super) fn heading_error(p: &RobustParams, c: &Coefs, s: &mut RobustState, f: &Field) -> Option<(f64, f64)> {
    let (norm, dip) = (f.norm, f.dip);
    if norm.is_nan() || norm <= 0.0 {
        return None;
    }
    let near = |n0: f64, d0: &Vector2<f64>| (norm - n0).abs() <= p.mag_norm_fraction * n0 && dip.dot(d0) >= c.cos_dip;
    if !s.mag_ready {
        (s.mag_norm, s.mag_dip, s.mag_ready) = (norm, dip, true);
        (s.cand_norm, s.cand_dip, s.cand_time) = (norm, dip, 0.0);
    }
    if near(s.cand_norm, &s.cand_dip) {
        if f.turning {
            s.cand_time += c.dt;
        }
    } else {
        (s.cand_norm, s.cand_dip, s.cand_time) = (norm, dip, 0.0);
    }
    let mut accepted = near(s.mag_norm, &s.mag_dip);
    if !accepted && s.cand_time >= p.mag_new_field_s {
        (s.mag_norm, s.mag_dip) = (s.cand_norm, s.cand_dip);
        accepted = true;
    }
    s.mag_disturbed = !accepted;
    let gain = if accepted {
        s.mag_rejected = 0.0;
        c.mag
    } else {
        s.mag_rejected += c.dt;
        if s.mag_rejected < p.mag_max_rejection_s {
            return None;
        }
        c.mag_slow
    };
    if f.phi.is_nan() {
        return None;
    }
    Some((gain, wrap(f.phi - s.heading_angle)))
}

/// The bias window's sums of one sample (the inclination loop's; [`heading_window`] adds the
/// heading loop's), from which [`update_bias`] measures the bias in motion.
///
/// In motion (derivation in `docs/filters_robust.md`): with `ε = b − b̂` the estimate turns at
/// `R ε` in the world; the inclination loop answers with corrections `c = −L∗(R ε)` (`L` the
/// Butterworth, for small angles, x and y) and the heading loop with `c_z = −F∗(R ε)_z` (`F` its
/// first-order loop, while the field is used). Running the same loops on `R` and on `R b̂` gives
/// `S = Σ L∗R dt` and `O = Σ L∗(R b̂) dt`, and `C = Σ c = −S b + O`: a measurement of `b` itself
/// whose lag is modelled, `y = C − O`, `H = −S` (divided by the window length). `r6` is this
/// sample's `R_E'b`, `rb = r6 b̂`.
#[inline(always)]
fn window_sums(
    p: &RobustParams,
    c: &Coefs,
    s: &mut RobustState,
    corr: &Vector2<f64>,
    r6: &Matrix3<f64>,
    rb: &Vector3<f64>,
) {
    let dt = c.dt;
    // The loop's model is mapped as the loop's own low pass is (`attitude_half`).
    if let Some(m) = carry(p, c, s.loop_dt) {
        m.apply(&mut s.loop_rot1, &mut s.loop_rot2);
        m.apply(&mut s.loop_bias1, &mut s.loop_bias2);
    }
    s.loop_dt = dt;
    let rot_xy = r6.fixed_rows::<2>(0).into_owned();
    let lr = c.butter(rot_xy, &mut s.loop_rot1, &mut s.loop_rot2);
    let lb = c.butter(Vector2::new(rb.x, rb.y), &mut s.loop_bias1, &mut s.loop_bias2);
    s.win_rot.fixed_rows_mut::<2>(0).add_assign(lr * dt);
    s.win_off.x += lb.x * dt;
    s.win_off.y += lb.y * dt;
    s.win_corr.x += corr.x;
    s.win_corr.y += corr.y;
}

/// A bias update that is due ([`window_due`]).
#[derive(Debug, Clone, Copy)]
pub(super) enum Update {
    /// The mean gyro of the rest segment so far.
    Rest,
    /// The motion window's mean correction rate.
    Motion,
}

/// Counts one sample (step `c.dt` > 0) into the window and the rest segment and says whether a
/// bias update is due.
///
/// At rest: the mean gyro over each rest segment (`H = I`), updated every `bias_rest_window_s` and
/// when the rest ends, its variance `σ_rest² / T` (white noise averaged over `T` seconds);
/// a rest update restarts the motion window (no sample counts twice).
#[inline(always)]
pub(super) fn window_due(p: &RobustParams, c: &Coefs, s: &mut RobustState, gyro: &Vector3<f64>) -> Option<Update> {
    let dt = c.dt;
    if dt <= 0.0 {
        return None;
    }
    s.win_time += dt;
    // The still samples before rest is declared are rest too: they count once it is.
    let still = s.rest_time > 0.0;
    if still {
        s.rest_sum += gyro * dt;
        s.rest_sum_time += dt;
    } else if !s.rest_segment {
        s.rest_sum = Vector3::zeros();
        s.rest_sum_time = 0.0;
    }
    let ended = !still && s.rest_segment && s.rest_sum_time > 0.0;
    s.rest_segment = s.rest || (still && s.rest_segment);
    if (s.rest && s.rest_sum_time >= p.bias_rest_window_s) || ended {
        Some(Update::Rest)
    } else if s.win_time >= p.bias_window_s {
        Some(Update::Motion)
    } else {
        None
    }
}

/// Makes the Kalman update `u` of the bias and restarts the window (a motion update reads the
/// window's sums, which must then be in `s`).
pub(super) fn update_bias(p: &RobustParams, s: &mut RobustState, u: Update) {
    match u {
        Update::Rest => {
            let t_rest = s.rest_sum_time;
            let r = p.bias_sigma_rest_rad_s.powi(2) / t_rest;
            let innovation = s.rest_sum / t_rest - s.bias;
            kalman(p, s, &Matrix3::identity(), &innovation, r, s.win_time);
            s.rest_sum = Vector3::zeros();
            s.rest_sum_time = 0.0;
        }
        Update::Motion => {
            let t = s.win_time;
            let mut h = -s.win_rot / t;
            let mut innovation = (s.win_corr - s.win_off) / t - h * s.bias;
            if s.win_mag_time < 0.5 * t {
                h.row_mut(2).fill(0.0);
                innovation.z = 0.0;
            }
            kalman(p, s, &h, &innovation, p.bias_sigma_motion_rad_s.powi(2), t);
        }
    }
    restart_window(s);
}

/// The heading loop's share of the bias window (9D): its responses to row z of `r6` and to
/// `(r6 b̂)_z` (`rb_z`), and, where the field is used, the loop's output and the correction
/// `(gain, k e)` applied: the sums [`update_bias`] reads beside [`window_sums`]'.
#[inline(always)]
fn heading_window(c: &Coefs, s: &mut RobustState, r6: &Matrix3<f64>, rb_z: f64, correction: Option<(f64, f64)>) {
    let dt = c.dt;
    s.loop_head_rot += r6.row(2).transpose() * dt;
    s.loop_head_bias += rb_z * dt;
    let mut corr_z = 0.0;
    if let Some((k, applied)) = correction {
        let (out_r, out_b) = (s.loop_head_rot * k, s.loop_head_bias * k);
        s.loop_head_rot -= out_r;
        s.loop_head_bias -= out_b;
        s.win_rot.row_mut(2).add_assign(out_r.transpose());
        s.win_off.z += out_b;
        s.win_mag_time += dt;
        corr_z = applied;
    }
    s.win_corr.z += corr_z;
}

/// One Kalman update of the bias with measurement matrix `h`, innovation and noise variance `r`
/// per component, after `t` seconds of random walk; the estimate clipped to `±bias_clip_rad_s`.
fn kalman(p: &RobustParams, s: &mut RobustState, h: &Matrix3<f64>, innovation: &Vector3<f64>, r: f64, t: f64) {
    s.bias_cov += Matrix3::identity() * (p.bias_sigma_init_rad_s.powi(2) / p.bias_forgetting_s * t);
    let pm = s.bias_cov;
    let innovation_cov = h * pm * h.transpose() + Matrix3::identity() * r;
    if let Some(inv) = innovation_cov.try_inverse() {
        let k = pm * h.transpose() * inv;
        let clip = p.bias_clip_rad_s;
        s.bias = (s.bias + k * innovation).map(|b| b.clamp(-clip, clip));
        let pn = (Matrix3::identity() - k * h) * pm;
        s.bias_cov = (pn + pn.transpose()) * 0.5;
    }
}

/// Empties the motion window.
fn restart_window(s: &mut RobustState) {
    s.win_time = 0.0;
    s.win_corr = Vector3::zeros();
    s.win_rot = Matrix3::zeros();
    s.win_off = Vector3::zeros();
    s.win_mag_time = 0.0;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Butterworth of any step is stable (Jury: `|a2| < 1`, `|a1| < 1 + a2` for the poles of
    /// `z² + a1 z + a2`) with a DC gain of 1. The prewarp's `tan(dt / 2τ)` wrapped past `π τ`
    /// (6.28 s at the default τ = 2 s): `a2` = 1.09 at 6.4 s, poles outside the unit circle.
    #[test]
    fn every_step_gives_a_stable_low_pass() {
        let p = RobustParams::default();
        for dt in [1e-4, 0.01, 1.0, 3.0, 3.2, 6.2, 6.4, 10.0, 100.0, 1e6] {
            let c = Coefs::new(&p, dt);
            assert!(
                c.a2.abs() < 1.0 && c.a1.abs() < 1.0 + c.a2,
                "{dt} s: a1 {}, a2 {}",
                c.a1,
                c.a2
            );
            // 1e-6: `1 + a1 + a2` cancels to about `4 k²` at small steps
            let dc = (2.0 * c.b0 + c.b1) / (1.0 + c.a1 + c.a2);
            assert!((dc - 1.0).abs() < 1e-6, "{dt} s: DC gain {dc}");
        }
    }

    /// Steps as float-second stamps make them: three keys alternating, two more evicting the
    /// oldest, returns to evicted and kept ones, and steps that share a key but not their last
    /// bits. Each step's coefficients equal fresh ones, its own exact `dt` included.
    #[test]
    fn cached_coefficients_equal_fresh_ones_in_any_order_of_keys() {
        let p = RobustParams::default();
        let mut cache = CoefsCache::new(Coefs::new(&p, 0.0));
        let mut keys = Vec::new();
        for (j, bits) in [
            (0, 0),
            (1, 0),
            (2, 0),
            (1, 3),
            (0, 5),
            (2, 1),
            (3, 0),
            (4, 0),
            (0, 2),
            (1, 0),
            (5, 0),
            (4, 7),
        ] {
            // 1e-9 apart: distinct keys (their resolution is 2.4e-10); a few ulps: the same key.
            let dt = f64::from_bits((0.005 * (1.0 + 1e-9 * f64::from(j))).to_bits() + bits);
            let got = cache.for_dt(&p, dt);
            assert_eq!(got, Coefs::new(&p, dt), "key {j}, +{bits} ulp");
            assert_eq!(got.dt, dt);
            keys.push(got.key);
        }
        keys.dedup();
        assert_eq!(keys.len(), 12, "every step a key of its own: {keys:?}");
    }

    /// The series branch of `to_up_norm` against the closed form `(1 + n_z, n_y, −n_x, 0) /
    /// √(2(1 + n_z))` on both sides of its switch at `1 − n_z = 10⁻³` (tilts 0 to 2.6°): within
    /// 4 ulp per component, and the result takes `a`'s direction to up.
    #[test]
    fn to_up_series_matches_the_closed_form() {
        for i in 0..=400 {
            let tilt = 0.045 * f64::from(i) / 400.0 + 1e-12;
            let az = 0.3 + 0.01 * f64::from(i);
            let a = Vector3::new(tilt.sin() * az.cos(), tilt.sin() * az.sin(), tilt.cos()) * 9.81;
            let q = to_up(&a);
            assert!(q.is_some(), "tilt {tilt}: no rotation for a finite a");
            let q = q.unwrap_or_else(UnitQuaternion::identity);
            let n = a / a.norm();
            let k = 1.0 / (2.0 * (1.0 + n.z)).sqrt();
            let want = [(1.0 + n.z) * k, n.y * k, -n.x * k];
            for (got, want) in [q.w, q.i, q.j].into_iter().zip(want) {
                assert!(
                    (got - want).abs() <= 4.0 * f64::EPSILON * want.abs().max(1e-300),
                    "tilt {tilt}: {got} vs {want}"
                );
            }
            let up = q * n;
            assert!(up.x.abs() < 1e-15 && up.y.abs() < 1e-15, "tilt {tilt}: {up:?}");
        }
    }

    /// A ramp through the Butterworth at 200 Hz, then the step doubled or halved (a dropped
    /// sample, a rate change) or 2 s long (a gap): carried by the ramp map, the output stays the
    /// ramp's steady response `x − S ℓ dt` to 1e-8 m/s² (ramp 0.5 m/s² per second from 9.8, 80 s).
    /// The level-only map it replaced dropped the slope: off by about the lag times the slope.
    #[test]
    fn the_carry_keeps_a_ramp_on_its_steady_response() {
        let p = RobustParams::default();
        let slope = 0.5;
        let x = |t: f64| 9.8 + slope * t;
        for new_dt in [0.01, 0.0025, 0.015, 2.0] {
            let old = Coefs::new(&p, 0.005);
            let mut t = 0.0;
            let (mut s1, mut s2) = old.steady(x(0.0));
            for _ in 0..16_000 {
                t += 0.005;
                old.butter(x(t), &mut s1, &mut s2);
            }
            let new = Coefs::new(&p, new_dt);
            let m = carry(&p, &new, old.dt);
            assert!(m.is_some(), "no carry from 0.005 to {new_dt}");
            let Some(m) = m else { return };
            // The ramp matrix is the steady state the pass reached (old coefficients).
            let r = old.ramp();
            let (e1, e2) = (r[0][0] * x(t) + r[0][1] * slope, r[1][0] * x(t) + r[1][1] * slope);
            assert!(
                (e1 - s1).abs() < 1e-8 && (e2 - s2).abs() < 1e-8,
                "{e1} {e2} against {s1} {s2}"
            );
            // Mapped, then 2 s at the new step: still the steady response. Dropping the slope
            // (the former map) leaves the output behind by about S × lag.
            let level = s2 / (old.b0 - old.a2);
            let (mut c1, mut c2) = (s1, s2);
            m.apply(&mut c1, &mut c2);
            let (mut d1, mut d2) = new.steady(level);
            let (mut y, mut dropped) = (0.0, 0.0);
            for _ in 0..((2.0 / new_dt).round() as usize).max(1) {
                t += new_dt;
                y = new.butter(x(t), &mut c1, &mut c2);
                dropped = new.butter(x(t), &mut d1, &mut d2);
            }
            let lag = (new.b1 + 2.0 * new.b0 - new.a1 - 2.0 * new.a2) / (2.0 * new.b0 + new.b1) * new.dt;
            let want = x(t) - slope * lag;
            assert!((y - want).abs() < 1e-8, "to {new_dt} s: {y} against {want}");
            assert!(
                (dropped - want).abs() > 0.1,
                "to {new_dt} s: the level map is {dropped}, {want} wanted"
            );
        }
        // Jitter below the threshold carries nothing.
        assert!(carry(&p, &Coefs::new(&p, 0.0074), 0.005).is_none());
        assert!(carry(&p, &Coefs::new(&p, 0.0034), 0.005).is_none());
    }
}
