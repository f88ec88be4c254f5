//! The covariance step of [`super::propagate_model`] when the [`Model`] has a lever arm or a frame
//! that follows the vehicle: a dense 15×15 step that carries the gyro noise of the lever-arm
//! conversion exactly.
//!
//! **Lever arm.** The readings are the body origin's, converted by [`crate::extrinsics::to_body`]:
//! `â_k = R_bs a_s − α_k × r − ω_k × (ω_k × r)`, `α_k = (ω_{k+1} − ω_{k−1}) / (t_{k+1} − t_{k−1})`.
//! With `w_j = R_bs n_j` the body-axis gyro noise of sample j (isotropic, `σ_g²/h_j` per axis,
//! `h_j` the step from sample j), the body readings carry `ω̂_k = ω_k + w_k` and
//! `â_k = f_k + R_bs m_k − D_k w_k + [r]× (w_{k+1} − w_{k−1}) / (t_{k+1} − t_{k−1})`,
//! `D_k = D(ω̂_k)` ([`crate::extrinsics::centripetal_sensitivity`]); a gyro-bias error enters
//! as `w_k` does (its α part cancels), so `∂δv⁺/∂δb_g` gains `h R D_k` and `∂δp⁺/∂δb_g`
//! `½h² R D_k` (Titterton & Weston 2004, eq. 3.48; Groves 2013, eq. 2.165). One step is then
//!
//! ```text
//! δx⁺ = F δx + G₋ w_{k−1} + G₀ w_k + G₊ w_{k+1} + (accelerometer and bias-walk impulses)
//! G₀ = [0; h R (D_k − c₀ [r]×); −h J_r(ω̂h); 0; 0],  G± = [0; −h R c± [r]×; 0; 0; 0]
//! ```
//!
//! (`c₋ = −1/Δ`, `c₊ = 1/Δ`, `c₀ = 0`; at the first sample the one-sided difference puts
//! `c₀ = −1/Δ`, `c₋ = 0`.) The noise of sample k + 1 enters step k and steps k + 1, k + 2, so the
//! state is augmented with `A = Cov(δx_k, w_{k−1})`, `B = Cov(δx_k, w_k)`, and
//!
//! ```text
//! P⁺ = F P Fᵀ + (F A G₋ᵀ + F B G₀ᵀ + sym.) + Σ G S Gᵀ + Q,   A⁺ = F B + G₀ S_k,   B⁺ = G₊ S_{k+1}
//! ```
//!
//! exactly for the linearised step (no bound, no white-noise approximation of α).
//!
//! **`F`.** In a fixed world, the exact Jacobian of the first-order step ([`super::step_jacobians`])
//! with the lever arm's `∂/∂δb_g` blocks, then the Coriolis factor of [`super`] on `P`, `A`, `B`;
//! in a frame that follows the vehicle, `Φ = I + F_c h + ½ (F_c h)²` with `F_c` the error rates of
//! [`crate::ellipsoid_errors`] (curvature, transport, gravity with latitude and height), whose
//! truncation is O(h³) per step.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::{step_jacobians, Covariance, Model};
use crate::ellipsoid_errors::error_rates;
use crate::extrinsics::centripetal_sensitivity;
use crate::imu::{Bias, NavState, Noise, Samples};
use crate::strapdown::{Options, Stepper};
use crate::{ellipsoid, so3, Result};

/// A noise input: 15×3.
type Input = SMatrix<f64, 15, 3>;

/// The propagated covariance and its cross-covariances with the gyro noise of the current and
/// previous samples (module docs).
struct State {
    p: Covariance,
    before: Input,
    current: Input,
}

/// The variance per axis of sample j's discrete gyro noise, `σ_g² / h_j`.
fn gyro_variance(samples: &Samples<'_>, noise: &Noise, j: usize) -> f64 {
    let t = samples.t;
    let h = if j + 1 < t.len() {
        t[j + 1] - t[j]
    } else {
        t[j] - t[j - 1]
    };
    noise.gyro_density * noise.gyro_density / h
}

impl State {
    /// One step with transition `f` and gyro-noise inputs `g = [G₋, G₀, G₊]`.
    fn step(&mut self, f: &Covariance, g: &[Input; 3], s: [f64; 3], q: &SMatrix<f64, 15, 1>) {
        let cross = f * (self.before * g[0].transpose() + self.current * g[1].transpose());
        let mut p = f * self.p * f.transpose() + cross + cross.transpose();
        for (gi, si) in g.iter().zip(s) {
            p += gi * gi.transpose() * si;
        }
        for (i, qi) in q.iter().enumerate() {
            p[(i, i)] += qi;
        }
        self.before = f * self.current + g[1] * s[1];
        self.current = g[2] * s[2];
        self.p = (p + p.transpose()) * 0.5;
    }

    /// `X ← D X` for `P` (both sides), `A`, `B`, with the Coriolis factor `D` of [`super`].
    fn coriolis(&mut self, omega: &Vector3<f64>, h: f64) {
        let mut d = Covariance::identity();
        let w = so3::hat(omega);
        d.fixed_view_mut::<3, 3>(0, 3).copy_from(&(w * (-h * h)));
        d.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() - w * (2.0 * h)));
        self.p = d * self.p * d.transpose();
        self.before = d * self.before;
        self.current = d * self.current;
    }
}

/// Integrates the mean (strapdown's stepper, or [`ellipsoid::run`] for a frame that follows the
/// vehicle) and propagates `p0` with the steps of the module docs, calling `visit(k, state_{k+1},
/// P_{k+1})` after each step.
#[allow(clippy::too_many_arguments)] // propagate's inputs
pub(super) fn run(
    samples: &Samples<'_>,
    initial: &NavState,
    p0: &Covariance,
    bias: &Bias,
    noise: &Noise,
    options: &Options,
    model: &Model,
    mut visit: impl FnMut(usize, &NavState, &Covariance) -> Result<()>,
) -> Result<(NavState, Covariance)> {
    let mut state = State {
        p: *p0,
        before: Input::zeros(),
        current: Input::zeros(),
    };
    let d = |x: f64| x * x;
    let q_of = |h: f64| {
        let mut q = SMatrix::<f64, 15, 1>::zeros();
        for (block, density) in [
            (1, noise.accel_density),
            (3, noise.accel_random_walk),
            (4, noise.gyro_random_walk),
        ] {
            q.fixed_rows_mut::<3>(3 * block).fill(d(density) * h);
        }
        q
    };
    let arm = so3::hat(&model.lever_arm);
    let rotating = options.earth_rate != Vector3::zeros();
    let mut step = |k: usize, x: &NavState, next: &NavState| {
        let t = samples.t;
        let h = t[k + 1] - t[k];
        let w_hat = samples.gyro_at(k) - bias.gyro;
        let a_hat = samples.accel_at(k) - bias.accel;
        let centripetal = centripetal_sensitivity(&w_hat, &model.lever_arm);
        let r = *x.rotation.to_rotation_matrix().matrix();
        let f = if let Some(frame) = model.transport {
            let fc = error_rates(frame.axes, x, &w_hat, &a_hat, &centripetal) * h;
            Covariance::identity() + fc + fc * fc * 0.5
        } else {
            let mut f = step_jacobians(x, &w_hat, &a_hat, h).f_x;
            let rd = r * centripetal;
            f.fixed_view_mut::<3, 3>(0, 12).copy_from(&(rd * (0.5 * h * h)));
            f.fixed_view_mut::<3, 3>(3, 12).copy_from(&(rd * h));
            f
        };
        // α's coefficients on w_{k−1}, w_k, w_{k+1} (one-sided at the first sample).
        let lo = k.saturating_sub(1);
        let span = t[k + 1] - t[lo];
        let (c_prev, c_cur) = if lo == k {
            (0.0, -1.0 / span)
        } else {
            (-1.0 / span, 0.0)
        };
        let tangential = |c: f64| -(r * arm) * (c * h);
        let mut g = [Input::zeros(); 3];
        g[0].fixed_view_mut::<3, 3>(3, 0).copy_from(&tangential(c_prev));
        g[1].fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(r * centripetal * h + tangential(c_cur)));
        g[1].fixed_view_mut::<3, 3>(6, 0)
            .copy_from(&(-so3::right_jacobian(&(w_hat * h)) * h));
        g[2].fixed_view_mut::<3, 3>(3, 0).copy_from(&tangential(1.0 / span));
        let s = [lo, k, k + 1].map(|j| gyro_variance(samples, noise, j));
        state.step(&f, &g, s, &q_of(h));
        if rotating && model.transport.is_none() {
            state.coriolis(&options.earth_rate, h);
        }
        visit(k, next, &state.p)
    };
    let x = match model.transport {
        Some(frame) => ellipsoid::run(samples, initial, bias, &frame, options.scheme, &mut step)?,
        None => Stepper::new(*samples, *bias, *options).run(*initial, &mut step)?,
    };
    Ok((x, state.p))
}
