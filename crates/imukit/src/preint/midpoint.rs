//! The midpoint scheme: VINS-Mono's `midPointIntegration` (Qin, Li & Shen, T-RO 2018) with an
//! exact rotation step in place of its first-order quaternion update. Between the samples 0 and 1
//! of an interval of `h`:
//!
//! ```text
//! ω̂ = ½(ω_0 + ω_1) − b_g,   R_1 = R_0 Exp(ω̂h),   ā = ½(R_0 â_0 + R_1 â_1)
//! Δp ← Δp + Δv h + ½ ā h²,   Δv ← Δv + ā h,   ΔR ← R_1
//! ```
//!
//! Linearised with the right perturbation (`Φ = Exp(ω̂h)`, `J = J_r(ω̂h)`, `n` white noise):
//!
//! ```text
//! δθ_1 = Φᵀ δθ_0 − J h (δb_g + ½(n_g0 + n_g1))
//! δā   = M δθ_0 + K (2 δb_g + n_g0 + n_g1) − ½(R_0 + R_1) δb_a − ½ R_0 n_a0 − ½ R_1 n_a1
//! M = −½(R_0[â_0]× + R_1[â_1]× Φᵀ),   K = ¼ h R_1[â_1]× J
//! ```
//!
//! so the transition `A` has the euler form with this `M`; sample s enters through
//! `B_s = [[−½hJ, 0], [hK, −½hR_s], [½h²K, −¼h²R_s]]` (columns `[gyro, accel]`) and a bias
//! change through `G_b = B_0 + B_1`, which is also the bias Jacobian's step: `J_b ← A J_b + G_b`.
//!
//! Consecutive intervals share a sample, so its white noise enters two steps. VINS-Mono treats
//! `n_0` and `n_1` of every interval as fresh noise, which halves the white-noise part:
//! `Δv ≈ h Σ ½(n_k + n_k+1)` has variance `≈ N h² σ²`, its model `½ N h² σ²`. Here the error
//! splits as `δx = δx̃ + P n_last`, `δx̃` independent of `n_last` (`P` the last interval's `B_1`);
//! an interval then gives `δx̃_1 = A δx̃_0 + D n_0` with `D = A P + B_0`, and `P ← B_1`, so the
//! stored covariance `Cov(δx̃)` takes `A Σ̃ Aᵀ + D q_0 Dᵀ` and the covariance is `Σ̃ + P q Pᵀ`, an
//! exact account of that correlation (tested against a dense augmented-state propagation and a
//! Monte Carlo) with no cross term to carry through `A`.
//!
//! **Frame i.** The per-sample blocks hold the rotation error as `δφ = ΔR δθ` (a left
//! perturbation, in the frame of keyframe i), i.e. the state error `T δx` with `T = diag(ΔR, I, I)`.
//! Since `R_1 Φᵀ R_0ᵀ = I` and `M R_0ᵀ = −½[R_0 â_0 + R_1 â_1]× = −[ā]×` (`R[a]×Rᵀ = [Ra]×`), the
//! transition becomes `A' = [[I, 0, 0], [W h, I, 0], [½ W h², h I, I]]` with `W = −[ā]×`, and the
//! inputs `B'_s` have θ rows `−½h G`, `G = R_1 J`, and v rows `h K = ¼h² [R_1 â_1]× G`: no `Φ`
//! product anywhere, four 3×3 products for `A' Σ A'ᵀ` instead of ten (the rotation part of the
//! invariant EKF's error, Barrau & Bonnabel, "The Invariant Extended Kalman Filter as a Stable
//! Observer", IEEE TAC 2017). The body
//! frame's blocks, which every reader gets, are `T⁻¹ (·) T⁻ᵀ` at the current `ΔR`; a projection of
//! `ΔR` (`mod.rs`) moves that frame by rounding only.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::blocks::{self, Cross, Input, ZERO_CROSS};
use super::{Covariance9, Preintegrator};
use crate::mat3::{mul, Lanes, M3};
use crate::so3;

/// One sample as the midpoint scheme remembers it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Sample {
    pub accel: Vector3<f64>,
    pub gyro: Vector3<f64>,
    /// Variances `[gyro, accel]` of its white noise, `σ²/h` with `h` its (first) interval, times
    /// `scale`; `None` until that interval arrives.
    pub var: Option<[f64; 2]>,
    /// Its variance multipliers `[gyro, accel]` (the saturation factor squared where clipped).
    pub scale: [f64; 2],
}

/// The samples at the window's ends and how their noise enters the state error (frame i, module
/// docs).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Ends {
    pub first: Option<Sample>,
    pub last: Option<Sample>,
    /// `Cov(δx, n_first)`, for merging this window after another.
    pub start_cross: Cross,
    /// `P`, the response of `δx` to the last sample's noise, whose share `P q Pᵀ` the stored
    /// covariance leaves out (zero before the first interval).
    pub pending: Input,
}

impl Default for Ends {
    fn default() -> Self {
        Self {
            first: None,
            last: None,
            start_cross: ZERO_CROSS,
            pending: Input::ZERO,
        }
    }
}

/// Dense matrices of one midpoint interval, the reference for the block update:
/// `δx_1 = A δx_0 + B_0 n_0 + B_1 n_1 + G_b δb` (noise and bias columns `[gyro, accel]`).
#[derive(Debug, Clone, PartialEq)]
pub struct MidpointStepMatrices {
    /// Error-state transition.
    pub a: Covariance9,
    /// Input of the interval's first sample's noise.
    pub b0: SMatrix<f64, 9, 6>,
    /// Input of its last sample's noise.
    pub b1: SMatrix<f64, 9, 6>,
}

/// The quantities one interval's update and its linearisation share.
struct Step {
    a0: Vector3<f64>,
    a1: Vector3<f64>,
    r0: Matrix3<f64>,
    r1: Matrix3<f64>,
    /// `Exp(ω̂h)`.
    exp: Matrix3<f64>,
    jr: Matrix3<f64>,
}

impl Preintegrator {
    #[inline(always)]
    fn midpoint_step(&self, prev: &Sample, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64) -> Step {
        let w = (prev.gyro + gyro) * 0.5 - self.bias_gyro;
        let r0 = self.delta_rotation;
        let (exp, jr) = so3::exp_and_right_jacobian(&(w * h));
        Step {
            a0: prev.accel - self.bias_accel,
            a1: accel - self.bias_accel,
            r0,
            r1: mul(&r0, &exp),
            exp,
            jr,
        }
    }

    #[inline(always)]
    pub(super) fn integrate_midpoint<L: Lanes>(
        &mut self,
        l: L,
        accel: &Vector3<f64>,
        gyro: &Vector3<f64>,
        h: f64,
        scale: [f64; 2],
    ) {
        let Some(prev) = self.ends.last else {
            let first = Sample {
                accel: *accel,
                gyro: *gyro,
                var: None,
                scale,
            };
            (self.ends.first, self.ends.last) = (Some(first), Some(first));
            return;
        };
        let s = self.midpoint_step(&prev, accel, gyro, h);
        let q = [
            self.noise.gyro_density * self.noise.gyro_density / h,
            self.noise.accel_density * self.noise.accel_density / h,
        ];
        let q1 = [q[0] * scale[0], q[1] * scale[1]];
        let q0 = prev.var.unwrap_or([q[0] * prev.scale[0], q[1] * prev.scale[1]]);
        let half_h = 0.5 * h;
        let (u0, u1) = (s.r0 * s.a0, s.r1 * s.a1);
        let acc = (u0 + u1) * 0.5;

        // Frame i (module docs): W = −[ā]×, G = R_1 J_r, each B_s's v row h K = ¼h² [R_1 â_1]× G.
        let (r0, r1) = (M3::of(&s.r0), M3::of(&s.r1));
        let w = M3::of(&so3::hat(&-acc));
        let g = r1.mul_with(l, &M3::of(&s.jr));
        let vg = M3::of(&so3::hat(&(u1 * (0.25 * h * h)))).mul_with(l, &g);
        let tg = g.scale_with(l, -half_h);
        let (va0, va1) = (r0.scale_with(l, -half_h), r1.scale_with(l, -half_h));
        let b0 = Input {
            tg,
            vg,
            va: va0,
            half_h,
        };
        let g_b = Input {
            tg: tg.add_with(l, &tg),
            vg: vg.add_with(l, &vg),
            va: va0.add_with(l, &va1),
            half_h,
        };

        // Covariance: the last sample's noise enters now through D = A P + B_0 (module docs), whose
        // accelerometer blocks are −½(h' + h) R_0 and −¼(h' + h)² R_0.
        let pending = self.ends.pending;
        let d = pending.through(l, &w, h, &b0);
        let mut cov = blocks::propagate_frame_i(l, &self.covariance, &w, h);
        let c_v = -(pending.half_h + half_h);
        blocks::add_noise(l, &mut cov, &d, q0[0], q0[1], [c_v, -c_v * c_v]);
        if let Some(walk) = self.bias_walk.as_mut() {
            g_b.add_quadratic(l, &mut cov, walk.var_gyro, walk.var_accel, None);
            walk.step(l, &mut cov, &w, &g_b, &self.noise);
        }
        self.covariance = cov;
        self.ends.pending = Input { va: va1, ..b0 };
        self.ends.start_cross = match prev.var {
            // The window's first interval: its first sample's noise enters through B_0 alone.
            None => b0.scaled(q0[0], q0[1]),
            Some(_) => blocks::transition(l, &self.ends.start_cross, &w, h),
        };
        self.jac = g_b.added_to(l, &blocks::transition(l, &self.jac, &w, h));

        // Deltas.
        self.delta_position += self.delta_velocity * h + acc * (half_h * h);
        self.delta_velocity += acc * h;
        self.delta_rotation = s.r1;
        self.delta_t += h;
        self.count_interval();
        if prev.var.is_none() {
            self.ends.first = Some(Sample { var: Some(q0), ..prev });
        }
        self.ends.last = Some(Sample {
            accel: *accel,
            gyro: *gyro,
            var: Some(q1),
            scale,
        });
    }

    /// The midpoint window's last sample `(accel, gyro)`, which the next interval starts from;
    /// `None` before the first sample and in the euler scheme.
    pub fn last_sample(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        self.ends.last.map(|s| (s.accel, s.gyro))
    }

    /// Dense `A`, `B_0`, `B_1` of the next midpoint interval (module docs of `midpoint.rs`), ending
    /// with the sample `accel`, `gyro`; `None` before the window's first sample.
    pub fn midpoint_step_matrices(
        &self,
        accel: &Vector3<f64>,
        gyro: &Vector3<f64>,
        h: f64,
    ) -> Option<MidpointStepMatrices> {
        let s = self.midpoint_step(self.ends.last.as_ref()?, accel, gyro, h);
        let phi = s.exp.transpose();
        let m = -blocks::times_hat(&s.r0, &(s.a0 + s.exp * s.a1)) * 0.5;
        let k = mul(&blocks::times_hat(&s.r1, &s.a1), &s.jr) * (0.25 * h);
        let mut a = Covariance9::identity();
        a.fixed_view_mut::<3, 3>(0, 0).copy_from(&phi);
        a.fixed_view_mut::<3, 3>(3, 0).copy_from(&(m * h));
        a.fixed_view_mut::<3, 3>(6, 0).copy_from(&(m * (0.5 * h * h)));
        a.fixed_view_mut::<3, 3>(6, 3).copy_from(&(Matrix3::identity() * h));
        let input = |r_s: &Matrix3<f64>| {
            let mut b = SMatrix::<f64, 9, 6>::zeros();
            b.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-s.jr * (0.5 * h)));
            b.fixed_view_mut::<3, 3>(3, 0).copy_from(&(k * h));
            b.fixed_view_mut::<3, 3>(6, 0).copy_from(&(k * (0.5 * h * h)));
            b.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-r_s * (0.5 * h)));
            b.fixed_view_mut::<3, 3>(6, 3).copy_from(&(-r_s * (0.25 * h * h)));
            b
        };
        Some(MidpointStepMatrices {
            a,
            b0: input(&s.r0),
            b1: input(&s.r1),
        })
    }
}
