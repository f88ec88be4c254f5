//! On-manifold IMU preintegration (Forster, Carlone, Dellaert & Scaramuzza, "On-Manifold
//! Preintegration for Real-Time Visual-Inertial Odometry", T-RO 2017), the `euler` scheme:
//! samples held constant over each interval, exact rotation steps.
//!
//! | item | convention |
//! |---|---|
//! | deltas | `ΔR_ij`, `Δv_ij`, `Δp_ij` in the body frame at i, gravity-free; `Δt_ij` |
//! | bias | `b̄ = (b_g, b_a)` fixed during integration; `ω̂ = ω_m − b_g`, `â = a_m − b_a` |
//! | covariance (9) | `[δθ, δv, δp]` with `ΔR = ΔR̂ Exp(δθ)` (right), `Δv = Δv̂ + δv`, `Δp = Δp̂ + δp` |
//! | bias Jacobian (9×6) | rows `[θ, v, p]`, columns `[b_g, b_a]` |
//! | noise | continuous densities σ_g, σ_a; per interval `Σ_g = σ_g²/Δt I`, `Σ_a = σ_a²/Δt I` |
//!
//! One interval of length `h` (all right-hand sides use the values before the update):
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

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::propagate::Noise;
use crate::so3;

/// 9×9 covariance of `[δθ, δv, δp]`.
pub type Covariance9 = SMatrix<f64, 9, 9>;
/// 9×6 bias Jacobian, rows `[θ, v, p]`, columns `[b_g, b_a]`.
pub type BiasJacobian = SMatrix<f64, 9, 6>;

/// Streaming preintegrator: one sample interval at a time, no allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct Preintegrator {
    /// Gyro bias used for integration [rad/s].
    pub bias_gyro: Vector3<f64>,
    /// Accelerometer bias used for integration [m/s²].
    pub bias_accel: Vector3<f64>,
    /// Noise densities.
    pub noise: Noise,
    /// `ΔR_ij`.
    pub delta_rotation: Matrix3<f64>,
    /// `Δv_ij` [m/s].
    pub delta_velocity: Vector3<f64>,
    /// `Δp_ij` [m].
    pub delta_position: Vector3<f64>,
    /// `Δt_ij` [s].
    pub delta_t: f64,
    /// Covariance of `[δθ, δv, δp]`.
    pub covariance: Covariance9,
    d_rot_d_bg: Matrix3<f64>,
    d_vel_d_bg: Matrix3<f64>,
    d_vel_d_ba: Matrix3<f64>,
    d_pos_d_bg: Matrix3<f64>,
    d_pos_d_ba: Matrix3<f64>,
}

impl Preintegrator {
    /// An empty preintegration with the given bias estimate and noise.
    pub fn new(bias_gyro: Vector3<f64>, bias_accel: Vector3<f64>, noise: Noise) -> Self {
        Self {
            bias_gyro,
            bias_accel,
            noise,
            delta_rotation: Matrix3::identity(),
            delta_velocity: Vector3::zeros(),
            delta_position: Vector3::zeros(),
            delta_t: 0.0,
            covariance: Covariance9::zeros(),
            d_rot_d_bg: Matrix3::zeros(),
            d_vel_d_bg: Matrix3::zeros(),
            d_vel_d_ba: Matrix3::zeros(),
            d_pos_d_bg: Matrix3::zeros(),
            d_pos_d_ba: Matrix3::zeros(),
        }
    }

    /// Adds one interval of `h` seconds with the measurements `accel` [m/s²] and `gyro` [rad/s]
    /// held over it (the caller validates finiteness and `h > 0`).
    pub fn integrate_measurement(&mut self, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64) {
        let a = accel - self.bias_accel;
        let w = gyro - self.bias_gyro;
        let r = self.delta_rotation;
        let a_cross = so3::hat(&a);
        let r_a_cross = r * a_cross;
        let step = so3::exp(&(w * h));
        let step_t = step.matrix().transpose();
        let jr = so3::right_jacobian(&(w * h));
        let half_h2 = 0.5 * h * h;

        // Covariance first: A, B, C use the state before the update.
        let mut a_m = Covariance9::identity();
        a_m.fixed_view_mut::<3, 3>(0, 0).copy_from(&step_t);
        a_m.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-r_a_cross * h));
        a_m.fixed_view_mut::<3, 3>(6, 0).copy_from(&(-r_a_cross * half_h2));
        a_m.fixed_view_mut::<3, 3>(6, 3).copy_from(&(Matrix3::identity() * h));
        let mut b_m = SMatrix::<f64, 9, 3>::zeros();
        b_m.fixed_view_mut::<3, 3>(3, 0).copy_from(&(r * h));
        b_m.fixed_view_mut::<3, 3>(6, 0).copy_from(&(r * half_h2));
        let c_block = jr * h;
        let var_a = self.noise.accel_density * self.noise.accel_density / h;
        let var_g = self.noise.gyro_density * self.noise.gyro_density / h;
        let mut cov = a_m * self.covariance * a_m.transpose() + b_m * b_m.transpose() * var_a;
        let mut top = cov.fixed_view_mut::<3, 3>(0, 0);
        top += c_block * c_block.transpose() * var_g;
        self.covariance = (cov + cov.transpose()) * 0.5;

        // Bias Jacobians, position before velocity before rotation.
        self.d_pos_d_ba += self.d_vel_d_ba * h - r * half_h2;
        self.d_pos_d_bg += self.d_vel_d_bg * h - r_a_cross * self.d_rot_d_bg * half_h2;
        self.d_vel_d_ba -= r * h;
        self.d_vel_d_bg -= r_a_cross * self.d_rot_d_bg * h;
        self.d_rot_d_bg = step_t * self.d_rot_d_bg - jr * h;

        // Deltas.
        self.delta_position += self.delta_velocity * h + r * a * half_h2;
        self.delta_velocity += r * a * h;
        self.delta_rotation = r * step.matrix();
        self.delta_t += h;
    }

    /// The bias Jacobian `∂(θ, v, p)/∂(b_g, b_a)`.
    pub fn bias_jacobian(&self) -> BiasJacobian {
        let mut j = BiasJacobian::zeros();
        j.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.d_rot_d_bg);
        j.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.d_vel_d_bg);
        j.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.d_vel_d_ba);
        j.fixed_view_mut::<3, 3>(6, 0).copy_from(&self.d_pos_d_bg);
        j.fixed_view_mut::<3, 3>(6, 3).copy_from(&self.d_pos_d_ba);
        j
    }

    /// First-order bias update: the deltas for biases `b̄ + (δb_g, δb_a)` without
    /// re-integration, `ΔR Exp(∂ΔR/∂b_g δb_g)` (right-applied), `Δv + ∂Δv/∂b δb`, `Δp + ∂Δp/∂b δb`.
    pub fn corrected(
        &self,
        bias_gyro: &Vector3<f64>,
        bias_accel: &Vector3<f64>,
    ) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
        let dbg = bias_gyro - self.bias_gyro;
        let dba = bias_accel - self.bias_accel;
        (
            self.delta_rotation * so3::exp(&(self.d_rot_d_bg * dbg)).matrix(),
            self.delta_velocity + self.d_vel_d_bg * dbg + self.d_vel_d_ba * dba,
            self.delta_position + self.d_pos_d_bg * dbg + self.d_pos_d_ba * dba,
        )
    }
}
