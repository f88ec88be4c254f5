//! On-manifold IMU preintegration between two keyframes i and j, in two schemes: `euler`
//! (Forster, Carlone, Dellaert & Scaramuzza, "On-Manifold Preintegration for Real-Time
//! Visual-Inertial Odometry", T-RO 2017: sample k held over `[t_k, t_k+1)`, exact rotation steps)
//! and `midpoint` (VINS-Mono's formulation, Qin, Li & Shen, T-RO 2018: averaged rates,
//! specific forces rotated at both ends of each interval), each with the exact linearisation of
//! its own discrete model for the covariance and the bias Jacobians.
//!
//! | item | convention |
//! |---|---|
//! | deltas | `ΔR_ij`, `Δv_ij`, `Δp_ij` in the body frame at i, gravity-free; `Δt_ij` |
//! | bias | `b̄ = (b_g, b_a)` fixed during integration; `ω̂ = ω_m − b_g`, `â = a_m − b_a` |
//! | covariance (9) | `[δθ, δv, δp]` with `ΔR = ΔR̂ Exp(δθ)` (right), `Δv = Δv̂ + δv`, `Δp = Δp̂ + δp` (as read; held in frame i, below) |
//! | combined (15) | `[δθ, δv, δp, δb_g, δb_a]` ([`Preintegrator::with_bias_walk`]) |
//! | bias Jacobian (9×6) | rows `[θ, v, p]`, columns `[b_g, b_a]` |
//! | noise | continuous densities σ_g, σ_a; each sample's white noise has variance `σ²/h I` (h: its interval) |
//! | `integrate_measurement(a, ω, h)` | euler: the sample at the start of an interval of `h`; midpoint: the sample at its end (the window's first call only records the first sample) |
//! | saturation | a sample flagged [`Clipped`] has white-noise densities × [`Preintegrator::saturation_noise_factor`] (per sensor): euler, on the interval it starts; midpoint, its own noise, which enters both intervals it bounds. Deltas unchanged |
//!
//! One euler interval of length `h` (all right-hand sides use the values before the update):
//!
//! ```text
//! Δp ← Δp + Δv h + ½ ΔR â h²       ∂Δp/∂b_a ← ∂Δp/∂b_a + ∂Δv/∂b_a h − ½ ΔR h²
//! Δv ← Δv + ΔR â h                  ∂Δp/∂b_g ← ∂Δp/∂b_g + ∂Δv/∂b_g h − ½ ΔR [â]× ∂ΔR/∂b_g h²
//! ΔR ← ΔR Exp(ω̂ h)                  ∂Δv/∂b_a ← ∂Δv/∂b_a − ΔR h
//!                                   ∂Δv/∂b_g ← ∂Δv/∂b_g − ΔR [â]× ∂ΔR/∂b_g h
//!                                   ∂ΔR/∂b_g ← Exp(ω̂h)ᵀ ∂ΔR/∂b_g − J_r(ω̂h) h
//! Σ ← A Σ Aᵀ + B Σ_a Bᵀ + C Σ_g Cᵀ,
//! A = [[Exp(ω̂h)ᵀ, 0, 0], [−ΔR[â]× h, I, 0], [−½ΔR[â]× h², h I, I]],
//! B = [0; ΔR h; ½ ΔR h²],  C = [J_r(ω̂h) h; 0; 0]      (Forster eqs. 62–63, 69)
//! ```
//!
//! **Frame i.** Both schemes keep their blocks (covariance, bias Jacobian, bias-walk cross
//! covariance) with the rotation error as `δφ = ΔR δθ`, a left perturbation in the frame of
//! keyframe i: the state error `T δx` with `T = diag(ΔR, I, I)` (the rotation part of the
//! invariant EKF's error, Barrau & Bonnabel, "The Invariant Extended Kalman Filter as a Stable
//! Observer", IEEE TAC 2017). With `R_0 = ΔR` and `R_1 = ΔR Exp(ω̂h)` before and after the
//! interval, `R_1 Exp(ω̂h)ᵀ R_0ᵀ = I` and `R_0 [â]× R_0ᵀ = [R_0 â]×`, so Forster's step becomes
//!
//! ```text
//! δφ ← δφ + G n_g                            G = R_1 J_r(ω̂h) h
//! δv ← δv + W h δφ + R_0 h n_a               W = −[R_0 â]×
//! δp ← δp + h δv + ½ W h² δφ + ½ R_0 h² n_a
//! A' = T_1 A T_0⁻¹ = [[I, 0, 0], [W h, I, 0], [½ W h², h I, I]],  C' = [G; 0; 0],  B' = B
//! ```
//!
//! `A' Σ A'ᵀ` takes four 3×3 products (`blocks::propagate_frame_i`) where `A Σ Aᵀ` takes ten;
//! `B Σ_a Bᵀ` is a multiple of I in each block (`R_0 R_0ᵀ = I`), `C' Σ_g C'ᵀ` one product
//! (`G Gᵀ`), and `G` itself one. The bias Jacobian's θ row becomes `∂φ/∂b_g ← ∂φ/∂b_g − G` (no
//! product) and its v and p rows take `W ∂φ/∂b_g`, one product: `J ← A' J + G_b` with
//! `G_b = −[[G, 0], [0, R_0 h], [0, ½ R_0 h²]]`, which is also the bias walk's input. Every reader
//! (`covariance`, `bias_jacobian`, `covariance_combined`, windows, merge) gets the body frame's
//! blocks, `T⁻¹ (·) T⁻ᵀ` at the current `ΔR`; a projection of `ΔR` (`PROJECT_EVERY`) moves that
//! frame by rounding only.
//!
//! The midpoint step, its linearisation and its noise model: `preint/midpoint.rs`; merging two
//! windows: `preint/merge.rs`.

mod batch;
mod blocks;
mod continuity;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod lever;
mod merge;
mod midpoint;
mod state;
mod windows;

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::error::{Error, Result};
use crate::imu::Noise;
use crate::mat3::{mul, Lanes, Unfused, M3};
use crate::so3;
pub use batch::CHUNK;
use blocks::{CovarianceBlocks, Cross, Input, ZERO_CROSS};
pub use continuity::{End, Ends};
pub use lever::LeverNoise;
pub use midpoint::MidpointStepMatrices;
pub use windows::{
    preintegrate_windows, preintegrate_windows_cancellable, preintegrate_windows_clipped,
    preintegrate_windows_clipped_cancellable, preintegrate_windows_into, WindowsOut,
};

/// 9×9 covariance of `[δθ, δv, δp]`.
pub type Covariance9 = SMatrix<f64, 9, 9>;
/// 9×6 bias Jacobian, rows `[θ, v, p]`, columns `[b_g, b_a]`.
pub type BiasJacobian = SMatrix<f64, 9, 6>;
/// 15×15 combined covariance, order `[δθ, δv, δp, δb_g, δb_a]`.
pub type Covariance15 = SMatrix<f64, 15, 15>;

/// How the samples of an interval enter it (module docs). The default is `Midpoint`: on real
/// recordings its residuals are the smaller (docs/preintegration.md).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Scheme {
    /// Forster's: sample k held over `[t_k, t_k+1)`, exact rotation steps (named `lie_euler`).
    Euler,
    /// VINS-Mono's: averaged rates, specific forces rotated at both ends.
    #[default]
    Midpoint,
}

// `lie_euler`: R Exp(ω_k h) with v and p first order; "euler" names forward Euler on the ODE in
// `attitude`, so it stays only as a deprecated alias here (one name per update rule).
crate::named_enum!(Scheme, "scheme", [Midpoint => "midpoint", Euler => "lie_euler"], aliases ["euler" => Euler]);

/// Default [`Preintegrator::saturation_noise_factor`]: OKVIS multiplies the white-noise densities
/// by 100 on an interval with a saturated reading (`ImuError::propagation`, `sigma_g_c *= 100`;
/// Leutenegger et al., "Keyframe-based visual–inertial odometry using nonlinear optimization",
/// IJRR 2015): a clipped reading says only that the true one is at least the range, so the factor
/// built on it should carry almost no weight.
pub const DEFAULT_SATURATION_NOISE_FACTOR: f64 = 100.0;

/// Which sensors of one sample were clipped at their full-scale range.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Clipped {
    /// Some gyro axis at its range.
    pub gyro: bool,
    /// Some accelerometer axis at its range.
    pub accel: bool,
}

impl Clipped {
    /// Nothing clipped.
    pub const NONE: Clipped = Clipped {
        gyro: false,
        accel: false,
    };
}

/// Per-sample clipping flags of a batch, one per sample (the same length as its timestamps).
#[derive(Debug, Clone, Copy)]
pub struct ClipMask<'a> {
    /// Samples whose gyro is clipped.
    pub gyro: &'a [bool],
    /// Samples whose accelerometer is clipped.
    pub accel: &'a [bool],
}

impl ClipMask<'_> {
    /// The flags of sample `k`.
    #[inline]
    pub fn at(&self, k: usize) -> Clipped {
        Clipped {
            gyro: self.gyro[k],
            accel: self.accel[k],
        }
    }

    /// Checks that there is one flag per sample.
    pub(super) fn check(&self, n: usize) -> Result<()> {
        for (name, flags) in [("gyro_saturated", self.gyro), ("accel_saturated", self.accel)] {
            if flags.len() != n {
                return Err(Error::Parameter {
                    name,
                    expected: "one flag per sample",
                    got: format!("{} flags for {n} samples", flags.len()),
                });
            }
        }
        Ok(())
    }
}

/// The flags of sample `k`, none without a mask.
#[inline]
pub(super) fn clipped_at(mask: Option<&ClipMask<'_>>, k: usize) -> Clipped {
    mask.map_or(Clipped::NONE, |m| m.at(k))
}

/// Dense `A` (9×9), `B`, `C` (9×3) of one euler interval: `Σ ← A Σ Aᵀ + B Σ_a Bᵀ + C Σ_g Cᵀ`.
#[derive(Debug, Clone, PartialEq)]
pub struct StepMatrices {
    /// Error-state transition.
    pub a: Covariance9,
    /// Accelerometer-noise input.
    pub b: SMatrix<f64, 9, 3>,
    /// Gyro-noise input.
    pub c: SMatrix<f64, 9, 3>,
}

/// The bias part of the 15×15 combined covariance `[δθ, δv, δp, δb_g, δb_a]`: the 9×6 cross
/// covariance `X` and the bias variances, which stay multiples of I (independent isotropic walks
/// starting from zero at i).
#[derive(Debug, Clone, PartialEq)]
struct BiasWalk {
    cross: Cross,
    var_gyro: f64,
    var_accel: f64,
}

impl BiasWalk {
    /// Adds the cross terms of `F Σ₁₅ Fᵀ + G Q Gᵀ` to the 9×9 blocks `cov` (already `A Σ Aᵀ + …`)
    /// and propagates the cross and bias blocks, with `F = [[A, G_b], [0, I]]` and `G_b` the step's
    /// response to a bias change (Forster 2017, the combined form); the bias is held over each
    /// interval and steps at its end; `w`, `h` the frame-i transition (`blocks.rs`). The caller
    /// adds `G_b Σ_b G_bᵀ` (`Σ_b` the bias variances before this step): the euler scheme's folds
    /// into its white noise's. Every term added to a diagonal block is exactly symmetric (`X + Xᵀ`),
    /// so no `(b + bᵀ)/2`.
    // Per sample: inlined across the crate's 4 codegen units (a new module moved the split and
    // the bias-walk loop ran 1.7× slower).
    #[inline(always)]
    fn step<L: Lanes>(&mut self, l: L, cov: &mut CovarianceBlocks, w: &M3, g_b: &Input, noise: &Noise) {
        let h = 2.0 * g_b.half_h;
        let y = blocks::transition(l, &self.cross, w, h);
        g_b.add_cross(l, cov, &y);
        self.cross = blocks::add(&y, &g_b.scaled(self.var_gyro, self.var_accel));
        self.var_gyro += noise.gyro_random_walk * noise.gyro_random_walk * h;
        self.var_accel += noise.accel_random_walk * noise.accel_random_walk * h;
    }
}

/// Streaming preintegrator: one sample at a time, no allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct Preintegrator {
    /// Integration scheme.
    pub scheme: Scheme,
    /// Gyro bias used for integration [rad/s].
    pub bias_gyro: Vector3<f64>,
    /// Accelerometer bias used for integration [m/s²].
    pub bias_accel: Vector3<f64>,
    /// Noise densities.
    pub noise: Noise,
    /// Multiplier of the white-noise densities of a clipped sample ([`Clipped`]; module docs),
    /// [`DEFAULT_SATURATION_NOISE_FACTOR`] unless set.
    pub saturation_noise_factor: f64,
    /// `ΔR_ij`.
    pub delta_rotation: Matrix3<f64>,
    /// `Δv_ij` [m/s].
    pub delta_velocity: Vector3<f64>,
    /// `Δp_ij` \[m\].
    pub delta_position: Vector3<f64>,
    /// `Δt_ij` \[s\].
    pub delta_t: f64,
    covariance: CovarianceBlocks,
    /// The bias Jacobian; it evolves as `J ← A J + G_b` (`∂ΔR/∂b_a` stays 0).
    jac: Cross,
    /// Bias random walk during the interval, when tracked (see [`Preintegrator::with_bias_walk`]).
    bias_walk: Option<BiasWalk>,
    /// The midpoint scheme's memory of the samples at the window's ends.
    ends: midpoint::Ends,
    /// The samples it starts and ends with, for the continuity rule (`continuity.rs`).
    boundary: Ends,
    /// Intervals since ΔR was last projected onto SO(3) (see [`PROJECT_EVERY`]).
    since_projection: u32,
}

crate::simd_dispatch! {
    /// One step of `p` ([`Preintegrator::integrate_measurement_clipped`]) per instruction-set path,
    /// its block algebra fused on the AVX paths (`mat3`'s module docs).
    fn step<const FMA: bool>(p: &mut Preintegrator, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64, clipped: Clipped) -> () {
        crate::mat3::with_lanes!(FMA, |l| p.step_with(l, accel, gyro, h, clipped))
    }
}

/// ΔR is a product of exact rotations, so it leaves SO(3) by rounding only, about 1e-16 an
/// interval, but without a projection that adds up (‖ΔRᵀΔR − I‖ reached 1.3e-12 to 4.6e-12 after
/// 10^7 intervals, `tests/stability.rs`). One Björck–Bowie step every 16 intervals keeps it at
/// rounding level for a few 3×3 products per 16 samples.
const PROJECT_EVERY: u32 = 16;

/// One Björck–Bowie step towards the nearest rotation, `R (3I − RᵀR)/2`: from `‖RᵀR − I‖ = ε` it
/// leaves `O(ε²)`.
pub(super) fn project_rotation(r: &Matrix3<f64>) -> Matrix3<f64> {
    let gram = r.transpose() * r;
    mul(r, &(Matrix3::identity() * 3.0 - gram)) * 0.5
}

impl Preintegrator {
    /// An empty euler preintegration with the given bias estimate and noise.
    pub fn new(bias_gyro: Vector3<f64>, bias_accel: Vector3<f64>, noise: Noise) -> Self {
        Self {
            scheme: Scheme::Euler,
            bias_gyro,
            bias_accel,
            noise,
            saturation_noise_factor: DEFAULT_SATURATION_NOISE_FACTOR,
            delta_rotation: Matrix3::identity(),
            delta_velocity: Vector3::zeros(),
            delta_position: Vector3::zeros(),
            delta_t: 0.0,
            covariance: [M3::ZERO; 6],
            jac: ZERO_CROSS,
            bias_walk: None,
            ends: midpoint::Ends::default(),
            boundary: Ends::default(),
            since_projection: 0,
        }
    }

    /// The same, integrating with `scheme`.
    pub fn with_scheme(mut self, scheme: Scheme) -> Self {
        self.scheme = scheme;
        self
    }

    /// Also track the bias random walk between i and j, for [`Preintegrator::covariance_combined`]
    /// (about twice the work per sample, as GTSAM's combined factor).
    pub fn with_bias_walk(mut self) -> Self {
        self.bias_walk = Some(BiasWalk {
            cross: ZERO_CROSS,
            var_gyro: 0.0,
            var_accel: 0.0,
        });
        self
    }

    /// The same, with `factor` multiplying the white-noise densities of clipped samples (it must
    /// be finite and at least 1: a clipped reading is never better than a measured one).
    pub fn with_saturation_noise_factor(mut self, factor: f64) -> Result<Self> {
        if !(factor.is_finite() && factor >= 1.0) {
            return Err(Error::Parameter {
                name: "saturation_noise_factor",
                expected: "a finite factor ≥ 1",
                got: format!("{factor}"),
            });
        }
        self.saturation_noise_factor = factor;
        Ok(self)
    }

    /// Adds one interval of `dt` seconds with the measurements `accel` [m/s²] and `gyro` [rad/s]
    /// (flagged by `clipped`), as [`Preintegrator::integrate_measurement_clipped`], after checking
    /// them: finite readings (errors name `accel` or `gyro`); in the midpoint scheme the window's
    /// first sample comes with `dt == 0` (it has no interval before it), every other step with a
    /// positive, finite `dt` (errors name `dt`). Transactional: the step runs on a copy that is
    /// committed only when every delta, covariance and Jacobian stayed finite (readings or a `dt`
    /// near f64's limits overflow them: [`Error::Overflow`] under `accel / gyro / dt`); on any
    /// error the preintegration is unchanged.
    pub fn try_integrate_measurement(
        &mut self,
        accel: &Vector3<f64>,
        gyro: &Vector3<f64>,
        dt: f64,
        clipped: Clipped,
    ) -> Result<()> {
        for (name, v) in [("accel", accel), ("gyro", gyro)] {
            if let Some(index) = v.iter().position(|x| !x.is_finite()) {
                return Err(Error::NonFinite { index }.in_argument(name));
            }
        }
        let starts = self.scheme == Scheme::Midpoint && self.last_sample().is_none();
        if starts && dt != 0.0 {
            // Named as the rule, so that the message reads "dt: the first sample of a midpoint
            // window must be …".
            let rule = Error::Parameter {
                name: "the first sample of a midpoint window",
                expected: "given with dt = 0 (it has no interval before it)",
                got: format!("dt = {dt}"),
            };
            return Err(rule.in_argument("dt"));
        }
        let positive = dt > 0.0 && dt.is_finite();
        if !(starts || positive) {
            return Err(Error::Parameter {
                name: "dt",
                expected: "a positive, finite step",
                got: format!("{dt}"),
            });
        }
        // The sample starts this interval (euler: held over it) or ends it (midpoint).
        let sample = End {
            t: None,
            accel: *accel,
            gyro: *gyro,
        };
        if self.scheme == Scheme::Euler {
            self.boundary
                .check_next(&sample, "the sample")
                .map_err(|e| e.in_argument("accel / gyro"))?;
        }
        let mut next = self.clone();
        next.integrate_measurement_clipped(accel, gyro, dt, clipped);
        if !next.is_finite() {
            return Err(Error::Overflow { index: 0 }.in_argument("accel / gyro / dt"));
        }
        let (first, last) = match self.scheme {
            // The end of a held interval is open: any sample may be held next.
            Scheme::Euler => (sample, None),
            Scheme::Midpoint => (sample, Some(sample)),
        };
        next.boundary = self.boundary.then(&Ends {
            first: Some(first),
            last,
        });
        *self = next;
        Ok(())
    }

    /// Adds one interval of `h` seconds with the measurements `accel` [m/s²] and `gyro` [rad/s]:
    /// in the euler scheme, held over the interval; in the midpoint scheme, sampled at its end (the
    /// first call of a window records its first sample and ignores `h`). Unchecked: the hot path
    /// of the batch kernels, whose callers validated the samples;
    /// [`Preintegrator::try_integrate_measurement`] checks and refuses transactionally.
    pub fn integrate_measurement(&mut self, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64) {
        self.integrate_measurement_clipped(accel, gyro, h, Clipped::NONE);
    }

    /// [`Preintegrator::integrate_measurement`] of a sample whose sensors `clipped` flags as
    /// saturated: its white-noise densities are multiplied by
    /// [`Preintegrator::saturation_noise_factor`] (module docs); the deltas are the same.
    // Inlined into the batch loops; the step itself is dispatched here, per sample, so that every
    // caller (batch, windows, streaming) runs the same path's rounding (`step` below).
    #[inline(always)]
    pub fn integrate_measurement_clipped(
        &mut self,
        accel: &Vector3<f64>,
        gyro: &Vector3<f64>,
        h: f64,
        clipped: Clipped,
    ) {
        step(self, accel, gyro, h, clipped);
    }

    /// One step with the block algebra in `l`'s lanes, fused or not (`mat3`'s module docs).
    #[inline(always)]
    fn step_with<L: Lanes>(&mut self, l: L, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64, clipped: Clipped) {
        let scale = self.variance_scale(clipped);
        match self.scheme {
            Scheme::Euler => self.integrate_euler(l, accel, gyro, h, scale),
            Scheme::Midpoint => self.integrate_midpoint(l, accel, gyro, h, scale),
        }
    }

    /// Multipliers `[gyro, accel]` of a sample's white-noise variances: the factor squared for a
    /// clipped sensor, else exactly 1 (so unflagged samples give bit-identical results).
    #[inline]
    fn variance_scale(&self, clipped: Clipped) -> [f64; 2] {
        let f2 = self.saturation_noise_factor * self.saturation_noise_factor;
        [
            if clipped.gyro { f2 } else { 1.0 },
            if clipped.accel { f2 } else { 1.0 },
        ]
    }

    #[inline(always)]
    fn integrate_euler<L: Lanes>(&mut self, l: L, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64, scale: [f64; 2]) {
        let a = accel - self.bias_accel;
        let w = gyro - self.bias_gyro;
        let r = self.delta_rotation;
        let (step, jr) = so3::exp_and_right_jacobian(&(w * h));
        let r1 = mul(&r, &step);
        let ra = r * a;

        // Frame i (module docs): W = −[ΔR â]×, G = ΔR_k+1 J_r h; A, B, G use the state before the
        // update.
        let var_a = self.noise.accel_density * self.noise.accel_density / h * scale[1];
        let var_g = self.noise.gyro_density * self.noise.gyro_density / h * scale[0];
        let w_m = M3::of(&so3::hat(&-ra));
        let g = M3::of(&r1).mul_with(l, &M3::of(&(jr * h)));
        let g_b = Input {
            tg: -g,
            vg: M3::ZERO,
            va: M3::of(&r).scale_with(l, -h),
            half_h: 0.5 * h,
        };
        let mut cov = blocks::propagate_frame_i(l, &self.covariance, &w_m, h);
        // The bias step enters through `G_b = −[C, B]`, the white noise's own inputs: one quadratic
        // for both (`x + 0.0` is `x`: no walk, the same bits).
        let [walk_g, walk_a] = self.bias_walk.as_ref().map_or([0.0; 2], |b| [b.var_gyro, b.var_accel]);
        blocks::add_held_noise(l, &mut cov, &g, var_g + walk_g, var_a + walk_a, h);
        if let Some(walk) = self.bias_walk.as_mut() {
            walk.step(l, &mut cov, &w_m, &g_b, &self.noise);
        }
        self.covariance = cov;
        self.jac = g_b.added_to(l, &blocks::transition(l, &self.jac, &w_m, h));

        // Deltas.
        self.delta_position += self.delta_velocity * h + ra * (0.5 * h * h);
        self.delta_velocity += ra * h;
        self.delta_rotation = r1;
        self.delta_t += h;
        self.count_interval();
    }

    /// Whether every delta, covariance, cross covariance and Jacobian is finite: finite input can
    /// still overflow them (a noise density of 1e200 squares to inf).
    pub(super) fn is_finite(&self) -> bool {
        let finite = |m: &Matrix3<f64>| m.iter().all(|v| v.is_finite());
        let block_finite = |b: &M3| finite(&b.matrix());
        let cross_finite = |c: &Cross| c.iter().flatten().all(block_finite);
        let walk_finite = self
            .bias_walk
            .as_ref()
            .is_none_or(|w| cross_finite(&w.cross) && w.var_gyro.is_finite() && w.var_accel.is_finite());
        finite(&self.delta_rotation)
            && self
                .delta_velocity
                .iter()
                .chain(self.delta_position.iter())
                .all(|v| v.is_finite())
            && self.delta_t.is_finite()
            // The covariance as `covariance()` gives it, with the midpoint's pending term of the
            // last sample: that term's Gram products can overflow while the stored blocks do not
            // (an accelerometer bias of 2e265 m/s² with zero noise gave `0 · inf`, NaN, behind an
            // `Ok`; fuzz/artifacts/preint/crash-7386d8e0…).
            && self.covariance_blocks(true).iter().all(block_finite)
            && cross_finite(&self.jac)
            && cross_finite(&self.ends.start_cross)
            && cross_finite(&self.ends.pending.cross())
            && walk_finite
    }

    /// Counts one interval; every [`PROJECT_EVERY`] intervals, projects ΔR back onto SO(3).
    #[inline]
    pub(super) fn count_interval(&mut self) {
        self.since_projection += 1;
        if self.since_projection >= PROJECT_EVERY {
            self.since_projection = 0;
            self.delta_rotation = project_rotation(&self.delta_rotation);
        }
    }

    /// `A`, `B`, `C` of the next euler interval (module docs) as dense matrices: the reference the
    /// block-structured update is tested against.
    pub fn step_matrices(&self, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64) -> StepMatrices {
        let a = accel - self.bias_accel;
        let w = gyro - self.bias_gyro;
        let r = self.delta_rotation;
        let r_a_cross = r * so3::hat(&a);
        let mut a_m = Covariance9::identity();
        a_m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&so3::exp(&(w * h)).matrix().transpose());
        a_m.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-r_a_cross * h));
        a_m.fixed_view_mut::<3, 3>(6, 0)
            .copy_from(&(-r_a_cross * (0.5 * h * h)));
        a_m.fixed_view_mut::<3, 3>(6, 3).copy_from(&(Matrix3::identity() * h));
        let mut b_m = SMatrix::<f64, 9, 3>::zeros();
        b_m.fixed_view_mut::<3, 3>(3, 0).copy_from(&(r * h));
        b_m.fixed_view_mut::<3, 3>(6, 0).copy_from(&(r * (0.5 * h * h)));
        let mut c_m = SMatrix::<f64, 9, 3>::zeros();
        c_m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(so3::right_jacobian(&(w * h)) * h));
        StepMatrices { a: a_m, b: b_m, c: c_m }
    }

    /// Covariance of `[δθ, δv, δp, δb_g, δb_a]` (15×15) including the bias random walk between i
    /// and j; `None` unless built [`Preintegrator::with_bias_walk`].
    pub fn covariance_combined(&self) -> Option<Covariance15> {
        let walk = self.bias_walk.as_ref()?;
        let mut out = Covariance15::zeros();
        out.fixed_view_mut::<9, 9>(0, 0).copy_from(&self.covariance());
        let cross = blocks::cross_matrix(&self.body_rows(&walk.cross));
        out.fixed_view_mut::<9, 6>(0, 9).copy_from(&cross);
        out.fixed_view_mut::<6, 9>(9, 0).copy_from(&cross.transpose());
        out.fixed_view_mut::<3, 3>(9, 9)
            .copy_from(&(Matrix3::identity() * walk.var_gyro));
        out.fixed_view_mut::<3, 3>(12, 12)
            .copy_from(&(Matrix3::identity() * walk.var_accel));
        Some(out)
    }

    /// Covariance of `[δθ, δv, δp]` (9×9).
    pub fn covariance(&self) -> Covariance9 {
        blocks::assemble(&self.covariance_blocks(true))
    }

    /// The bias Jacobian `∂(θ, v, p)/∂(b_g, b_a)`.
    pub fn bias_jacobian(&self) -> BiasJacobian {
        blocks::cross_matrix(&self.body_rows(&self.jac))
    }

    /// `ΔRᵀ` as a block: from frame i to the body frame at j.
    fn to_body(&self) -> M3 {
        M3::of(&self.delta_rotation.transpose())
    }

    /// `x` with its θ row in the body frame at j (the right perturbation of the readers), where
    /// both schemes keep it in frame i (module docs).
    pub(super) fn body_rows(&self, x: &Cross) -> Cross {
        blocks::rotate_rows(x, &self.to_body())
    }

    /// The covariance blocks in the body frame at j: with the midpoint scheme's last sample's
    /// noise (the covariance), or without it (`pending = false`: the part a merge composes on its
    /// own); the euler scheme has none pending.
    pub(super) fn covariance_blocks(&self, pending: bool) -> CovarianceBlocks {
        let mut cov = self.covariance;
        if let (true, Some([q_g, q_a])) = (pending, self.ends.last.and_then(|s| s.var)) {
            let p = &self.ends.pending;
            // `va` is −½h R_1: `va vaᵀ = (h/2)² I`.
            p.add_quadratic(Unfused, &mut cov, q_g, q_a, Some(p.half_h * p.half_h));
        }
        blocks::rotate_covariance(&cov, &self.to_body())
    }

    /// `Cov(δx, n_last)` in the body frame at j (zero before the first interval and in the euler
    /// scheme).
    pub(super) fn end_cross(&self) -> Cross {
        let [q_g, q_a] = self.ends.last.and_then(|s| s.var).unwrap_or([0.0; 2]);
        self.body_rows(&self.ends.pending.scaled(q_g, q_a))
    }

    /// This preintegration with its blocks (covariance, bias Jacobian, start cross covariance, bias
    /// walk cross) given in the body frame at j, as a merge composes them and earlier euler states
    /// hold them (`state.rs`), taken to frame i.
    pub(super) fn in_own_frame(mut self) -> Self {
        let r = M3::of(&self.delta_rotation);
        self.covariance = blocks::rotate_covariance(&self.covariance, &r);
        self.jac = blocks::rotate_rows(&self.jac, &r);
        self.ends.start_cross = blocks::rotate_rows(&self.ends.start_cross, &r);
        if let Some(walk) = self.bias_walk.as_mut() {
            walk.cross = blocks::rotate_rows(&walk.cross, &r);
        }
        self
    }
}
