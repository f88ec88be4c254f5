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
//! Consecutive intervals share a sample, so its white noise enters two steps. The covariance
//! carries `C = Cov(δx, n_last)` and adds `A C B_0ᵀ + B_0 Cᵀ Aᵀ`, an exact account of that
//! correlation (tested against a dense augmented-state propagation and a Monte Carlo). VINS-Mono
//! treats `n_0` and `n_1` of every interval as fresh noise, which halves the white-noise part:
//! `Δv ≈ h Σ ½(n_k + n_k+1)` has variance `≈ N h² σ²`, its model `½ N h² σ²`.

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

/// The samples at the window's ends and the covariances of the state error with their noise.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Ends {
    pub first: Option<Sample>,
    pub last: Option<Sample>,
    /// `Cov(δx, n_first)`, for merging this window after another.
    pub start_cross: Cross,
    /// `Cov(δx, n_last)`.
    pub end_cross: Cross,
}

impl Default for Ends {
    fn default() -> Self {
        Self {
            first: None,
            last: None,
            start_cross: ZERO_CROSS,
            end_cross: ZERO_CROSS,
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
    phi: Matrix3<f64>,
    jr: Matrix3<f64>,
    m: Matrix3<f64>,
    k: Matrix3<f64>,
}

impl Preintegrator {
    #[inline(always)]
    fn midpoint_step(&self, prev: &Sample, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64) -> Step {
        let a0 = prev.accel - self.bias_accel;
        let a1 = accel - self.bias_accel;
        let w = (prev.gyro + gyro) * 0.5 - self.bias_gyro;
        let r0 = self.delta_rotation;
        let (step, jr) = so3::exp_and_right_jacobian(&(w * h));
        let phi = step.transpose();
        let r1 = mul(&r0, &step);
        let r1a = blocks::times_hat(&r1, &a1);
        Step {
            // R_1[â_1]× Φᵀ = R_0 Exp(ω̂h) [â_1]× Exp(ω̂h)ᵀ = R_0 [Exp(ω̂h) â_1]× (the adjoint), so
            // M = −½ R_0 [â_0 + Exp(ω̂h) â_1]×: one product instead of three.
            m: -blocks::times_hat(&r0, &(a0 + step * a1)) * 0.5,
            k: mul(&r1a, &jr) * (0.25 * h),
            a0,
            a1,
            r0,
            r1,
            phi,
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
        // In padded blocks (`mat3::M3`), the form the blocks are stored in.
        let (phi, m, jr, k, r0, r1) = (
            M3::of(&s.phi),
            M3::of(&s.m),
            M3::of(&s.jr),
            M3::of(&s.k),
            M3::of(&s.r0),
            M3::of(&s.r1),
        );
        let input = |r_s: &M3| Input {
            tg: -jr * half_h,
            vg: k * h,
            va: -*r_s * half_h,
            half_h,
        };
        let (b0, b1) = (input(&r0), input(&r1));
        let g_b = Input {
            tg: -jr * h,
            vg: k * (2.0 * h),
            va: -(r0 + r1) * half_h,
            half_h,
        };

        // Covariance, with the shared sample's correlation (module docs).
        let y_end = blocks::transition(l, &self.ends.end_cross, &phi, &m, h);
        let mut cov = blocks::propagate(l, &self.covariance, &phi, &m, h, 0.0, None);
        // B_0 q_0 B_0ᵀ + B_1 q_1 B_1ᵀ in one: the gyro columns are equal, and each accelerometer
        // block (−½h R_s) has the Gram matrix ¼h² I.
        b0.add_quadratic(l, &mut cov, q0[0] + q1[0], q0[1] + q1[1], Some(half_h * half_h));
        b0.add_cross(l, &mut cov, &y_end);
        blocks::symmetric_diagonal(&mut cov);
        if let Some(walk) = self.bias_walk.as_mut() {
            walk.step(l, &mut cov, &phi, &m, &g_b, None, &self.noise);
        }
        self.covariance = cov;
        let moved_start = blocks::transition(l, &self.ends.start_cross, &phi, &m, h);
        self.ends.start_cross = match prev.var {
            None => blocks::add(&moved_start, &b0.scaled(q0[0], q0[1])),
            Some(_) => moved_start,
        };
        self.ends.end_cross = b1.scaled(q1[0], q1[1]);
        let jac = blocks::transition(l, &self.jac, &phi, &m, h);
        self.jac = blocks::add(&jac, &g_b.cross());

        // Deltas.
        let acc = (s.r0 * s.a0 + s.r1 * s.a1) * 0.5;
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
        let mut a = Covariance9::identity();
        a.fixed_view_mut::<3, 3>(0, 0).copy_from(&s.phi);
        a.fixed_view_mut::<3, 3>(3, 0).copy_from(&(s.m * h));
        a.fixed_view_mut::<3, 3>(6, 0).copy_from(&(s.m * (0.5 * h * h)));
        a.fixed_view_mut::<3, 3>(6, 3).copy_from(&(Matrix3::identity() * h));
        let input = |r_s: &Matrix3<f64>| {
            let mut b = SMatrix::<f64, 9, 6>::zeros();
            b.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-s.jr * (0.5 * h)));
            b.fixed_view_mut::<3, 3>(3, 0).copy_from(&(s.k * h));
            b.fixed_view_mut::<3, 3>(6, 0).copy_from(&(s.k * (0.5 * h * h)));
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
