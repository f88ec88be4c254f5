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
//! `c₀ = −1/Δ`, `c₋ = 0`.) That is the first-order step, which reads sample k; the midpoint scheme
//! reads half of sample k (rotated by `R_k`) and half of k + 1 (by `R_{k+1}`), in the velocity and
//! in the attitude, so its step has inputs from `w_{k−1} … w_{k+2}` (the readings' weights matter
//! at a record's ends, where the tangential noise does not telescope). The state is augmented with
//! the cross-covariances `C_i = Cov(δx_k, w_{k−1+i})`, i = 0, 1, 2, and with inputs `G_0 … G_3`
//!
//! ```text
//! P⁺ = F P Fᵀ + (F Σ C_i G_iᵀ + transpose) + Σ G_i S_i G_iᵀ + Q
//! C_0⁺ = F C_1 + G_1 S_k,  C_1⁺ = F C_2 + G_2 S_{k+1},  C_2⁺ = G_3 S_{k+2}
//! ```
//!
//! exactly for the linearised step (no bound, no white-noise approximation of α). `rk4` takes the
//! midpoint's weights (its Simpson rule to within the cubic's outer taps), `exp` the first-order
//! step's.
//!
//! **`F`.** In a fixed world, the exact Jacobian of the first-order step ([`super::step_jacobians`])
//! with the lever arm's `∂/∂δb_g` blocks (`h Σ c_j R_j D_j`, the readings' weights), then the
//! Coriolis factor of [`super`] on `P` and the `C_i`;
//! in a frame that follows the vehicle, `Φ = I + F_c h + ½ (F_c h)²` with `F_c` the error rates of
//! [`crate::ellipsoid_errors`] (curvature, transport, gravity with latitude and height), whose
//! truncation is O(h³) per step.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::{step_jacobians, Covariance, Model};
use crate::ellipsoid_errors::error_rates;
use crate::extrinsics::{alpha_weights, centripetal_sensitivity};
use crate::imu::{Bias, NavState, Noise, Samples};
use crate::strapdown::{Options, Scheme, Stepper};
use crate::{ellipsoid, so3, Result};

/// A noise input: 15×3.
type Input = SMatrix<f64, 15, 3>;

/// The propagated covariance and its cross-covariances with the gyro noise of samples
/// `k − 1, k, k + 1` (module docs).
struct State {
    p: Covariance,
    cross: [Input; 3],
}

/// The variance per axis of sample j's discrete gyro noise, `σ_g² / h_j` (zero past the end,
/// where no input reads it).
fn gyro_variance(samples: &Samples<'_>, noise: &Noise, j: usize) -> f64 {
    let t = samples.t;
    let h = match j {
        j if j + 1 < t.len() => t[j + 1] - t[j],
        j if j + 1 == t.len() => t[j] - t[j - 1],
        _ => return 0.0,
    };
    noise.gyro_density * noise.gyro_density / h
}

impl State {
    /// One step with transition `f` and the inputs `g` of the gyro noise of samples
    /// `k − 1 … k + 2`, variances `s`.
    fn step(&mut self, f: &Covariance, g: &[Input; 4], s: [f64; 4], q: &SMatrix<f64, 15, 1>) {
        let mixed: Covariance = (0..3).map(|i| self.cross[i] * g[i].transpose()).sum();
        let cross = f * mixed;
        let mut p = f * self.p * f.transpose() + cross + cross.transpose();
        for (gi, si) in g.iter().zip(s) {
            p += gi * gi.transpose() * si;
        }
        for (i, qi) in q.iter().enumerate() {
            p[(i, i)] += qi;
        }
        self.cross = [
            f * self.cross[1] + g[1] * s[1],
            f * self.cross[2] + g[2] * s[2],
            g[3] * s[3],
        ];
        self.p = (p + p.transpose()) * 0.5;
    }

    /// `X ← D X` for `P` (both sides) and the cross-covariances, with the Coriolis factor `D` of
    /// [`super`].
    fn coriolis(&mut self, omega: &Vector3<f64>, h: f64) {
        let mut d = Covariance::identity();
        let w = so3::hat(omega);
        d.fixed_view_mut::<3, 3>(0, 3).copy_from(&(w * (-h * h)));
        d.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() - w * (2.0 * h)));
        self.p = d * self.p * d.transpose();
        for c in &mut self.cross {
            *c = d * *c;
        }
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
        cross: [Input::zeros(); 3],
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
    // The weights of the readings at k and k + 1 in the step's velocity and attitude: the
    // midpoint averages both ends; so does rk4 to within its cubic's outer taps (Simpson over
    // the interval with the cubic's mid value weighs k−1, k, k+1, k+2 as −1, 13, 13, −1 over 24);
    // lie_euler and exp read sample k.
    let weights = if matches!(options.scheme, Scheme::Midpoint | Scheme::Rk4) {
        [0.5, 0.5]
    } else {
        [1.0, 0.0]
    };
    let mut step = |k: usize, x: &NavState, next: &NavState| {
        let t = samples.t;
        let h = t[k + 1] - t[k];
        let w_hat = samples.gyro_at(k) - bias.gyro;
        let a_hat = samples.accel_at(k) - bias.accel;
        // Per reading j ∈ {k, k + 1}: its weight, `R_j D(ω̂_j)`, `R_j [r]×`.
        let reading = |j: usize, x: &NavState| {
            let r = *x.rotation.to_rotation_matrix().matrix();
            let rate = samples.gyro_at(j) - bias.gyro;
            (r * centripetal_sensitivity(&rate, &model.lever_arm), r * arm)
        };
        let ends = [(k, reading(k, x)), (k + 1, reading(k + 1, next))];
        let bias_force: Matrix3<f64> = ends.iter().zip(weights).map(|((_, (rd, _)), c)| rd * c).sum();
        let f = if let Some(frame) = model.transport {
            // `F_c` takes `R_k D`: the readings' weighted `R_j D_j` brought back by `R_kᵀ`.
            let centripetal = x.rotation.to_rotation_matrix().matrix().transpose() * bias_force;
            let fc = error_rates(frame.axes, x, &w_hat, &a_hat, &centripetal) * h;
            Covariance::identity() + fc + fc * fc * 0.5
        } else {
            let mut f = step_jacobians(x, &w_hat, &a_hat, h).f_x;
            f.fixed_view_mut::<3, 3>(0, 12).copy_from(&(bias_force * (0.5 * h * h)));
            f.fixed_view_mut::<3, 3>(3, 12).copy_from(&(bias_force * h));
            f
        };
        // Slot i holds sample k − 1 + i; a reading's noise enters δv as −h c R_j ε_j, with
        // ε_j = −D_j w_j + [r]× α̃_j, and δθ as −h c J_r w_j.
        let mut g = [Input::zeros(); 4];
        let jr = so3::right_jacobian(&(w_hat * h)) * h;
        for ((j, (rd, ra)), c) in ends.iter().zip(weights) {
            if c == 0.0 {
                continue;
            }
            let slot = |i: usize| i + 1 - k;
            let mut v = |i: usize, m: Matrix3<f64>| {
                let mut block = g[slot(i)].fixed_view_mut::<3, 3>(3, 0);
                block += m * (h * c);
            };
            v(*j, *rd);
            let (lo, hi, inv) = alpha_weights(t, *j);
            v(lo, ra * inv);
            v(hi, -ra * inv);
            let mut theta = g[slot(*j)].fixed_view_mut::<3, 3>(6, 0);
            theta -= jr * c;
        }
        let s = [k as isize - 1, k as isize, k as isize + 1, k as isize + 2]
            .map(|j| usize::try_from(j).map_or(0.0, |j| gyro_variance(samples, noise, j)));
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
