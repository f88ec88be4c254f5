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

use crate::mat3::{mul, mul_t};
use crate::propagate::Noise;
use crate::so3;

/// 9×9 covariance of `[δθ, δv, δp]`.
pub type Covariance9 = SMatrix<f64, 9, 9>;
/// 9×6 bias Jacobian, rows `[θ, v, p]`, columns `[b_g, b_a]`.
pub type BiasJacobian = SMatrix<f64, 9, 6>;

/// Dense `A` (9×9), `B`, `C` (9×3) of one interval: `Σ ← A Σ Aᵀ + B Σ_a Bᵀ + C Σ_g Cᵀ`.
#[derive(Debug, Clone, PartialEq)]
pub struct StepMatrices {
    /// Error-state transition.
    pub a: Covariance9,
    /// Accelerometer-noise input.
    pub b: SMatrix<f64, 9, 3>,
    /// Gyro-noise input.
    pub c: SMatrix<f64, 9, 3>,
}

/// `A Σ Aᵀ + B Σ_a Bᵀ + C Σ_g Cᵀ` on the six unique 3×3 blocks of Σ, with
/// `A = [[Φ, 0, 0], [M h, I, 0], [½ M h², h I, I]]` (`Φ = Exp(ω̂h)ᵀ`, `M = −ΔR[â]×`), about a dozen
/// 3×3 products instead of two dense 9×9 ones. `B Σ_a Bᵀ` reduces to multiples of I because ΔR
/// is orthonormal.
fn propagate_blocks(
    cov: &CovarianceBlocks,
    phi: &Matrix3<f64>,
    m: &Matrix3<f64>,
    jr: &Matrix3<f64>,
    h: f64,
    var_a: f64,
    var_g: f64,
) -> CovarianceBlocks {
    let [tt, tv, tp, vv, vp, pp] = *cov;
    let (vt, pt, pv) = (tv.transpose(), tp.transpose(), vp.transpose());
    let half_h2 = 0.5 * h * h;
    // Rows of A Σ.
    let phi_tt = mul(phi, &tt);
    let m_tt = mul(m, &tt);
    let (m_tv, m_tp) = (mul(m, &tv), mul(m, &tp));
    let a_vt = m_tt * h + vt;
    let a_vv = m_tv * h + vv;
    let a_vp = m_tp * h + vp;
    let a_pt = m_tt * half_h2 + vt * h + pt;
    let a_pv = m_tv * half_h2 + vv * h + pv;
    let a_pp = m_tp * half_h2 + vp * h + pp;
    // (A Σ) Aᵀ, upper blocks.
    let phi_tt_mt = mul_t(&phi_tt, m);
    let new_tt = mul_t(&phi_tt, phi) + mul_t(jr, jr) * (var_g * h * h);
    let phi_tv = mul(phi, &tv);
    let new_tv = phi_tt_mt * h + phi_tv;
    let new_tp = phi_tt_mt * half_h2 + phi_tv * h + mul(phi, &tp);
    let a_vt_mt = mul_t(&a_vt, m);
    let new_vv = a_vt_mt * h + a_vv + Matrix3::identity() * (var_a * h * h);
    let new_vp = a_vt_mt * half_h2 + a_vv * h + a_vp + Matrix3::identity() * (var_a * h * half_h2);
    let new_pp = mul_t(&a_pt, m) * half_h2 + a_pv * h + a_pp + Matrix3::identity() * (var_a * half_h2 * half_h2);
    let symmetric = |b: Matrix3<f64>| (b + b.transpose()) * 0.5;
    [
        symmetric(new_tt),
        new_tv,
        new_tp,
        symmetric(new_vv),
        new_vp,
        symmetric(new_pp),
    ]
}

/// The unique blocks `[θθ, θv, θp, vv, vp, pp]` of the 9×9 covariance.
type CovarianceBlocks = [Matrix3<f64>; 6];

/// The 9×9 matrix of the blocks.
fn assemble(blocks: &CovarianceBlocks) -> Covariance9 {
    let mut out = Covariance9::zeros();
    let places = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    for ((i, j), b) in places.into_iter().zip(blocks) {
        out.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(b);
        out.fixed_view_mut::<3, 3>(3 * j, 3 * i).copy_from(&b.transpose());
    }
    out
}

/// 15×15 combined covariance, order `[δθ, δv, δp, δb_g, δb_a]`.
pub type Covariance15 = SMatrix<f64, 15, 15>;

impl BiasWalk {
    /// Adds the bias terms of `F Σ₁₅ Fᵀ + G Q Gᵀ` to the 9×9 blocks `cov` (already `A Σ Aᵀ + …`)
    /// and propagates the cross and bias blocks, with `F = [[A, G_b], [0, I]]`,
    /// `G_b = [[−J_r h, 0], [0, −ΔR h], [0, −½ ΔR h²]]` (Forster 2017, the combined form).
    #[allow(clippy::too_many_arguments)] // the step's shared blocks, passed as computed
    fn step(
        &mut self,
        cov: &mut CovarianceBlocks,
        phi: &Matrix3<f64>,
        m: &Matrix3<f64>,
        jr: &Matrix3<f64>,
        r: &Matrix3<f64>,
        h: f64,
        noise: &Noise,
    ) {
        let half_h2 = 0.5 * h * h;
        let [[xtg, xta], [xvg, xva], [xpg, xpa]] = self.cross;
        // Y = A X.
        let (m_tg, m_ta) = (mul(m, &xtg), mul(m, &xta));
        let y = [
            [mul(phi, &xtg), mul(phi, &xta)],
            [m_tg * h + xvg, m_ta * h + xva],
            [m_tg * half_h2 + xvg * h + xpg, m_ta * half_h2 + xva * h + xpa],
        ];
        // Y G_bᵀ + G_b Yᵀ + G_b S_b G_bᵀ on the upper blocks [θθ, θv, θp, vv, vp, pp].
        let (jsj, rsr) = (mul_t(&mul(jr, &self.gyro), jr), mul_t(&mul(r, &self.accel), r));
        let y_tg_jt = mul_t(&y[0][0], jr);
        let y_ta_rt = mul_t(&y[0][1], r);
        let y_va_rt = mul_t(&y[1][1], r);
        let y_pa_rt = mul_t(&y[2][1], r);
        cov[0] += -(y_tg_jt + y_tg_jt.transpose()) * h + jsj * (h * h);
        cov[1] += -y_ta_rt * h - mul_t(jr, &y[1][0]) * h;
        cov[2] += -y_ta_rt * half_h2 - mul_t(jr, &y[2][0]) * h;
        cov[3] += -(y_va_rt + y_va_rt.transpose()) * h + rsr * (h * h);
        cov[4] += -y_va_rt * half_h2 - y_pa_rt.transpose() * h + rsr * (h * half_h2);
        cov[5] += -(y_pa_rt + y_pa_rt.transpose()) * half_h2 + rsr * (half_h2 * half_h2);
        for d in [0, 3, 5] {
            cov[d] = (cov[d] + cov[d].transpose()) * 0.5;
        }
        // X' = A X + G_b S_b, then S_b' = S_b + Q_b.
        let (jg, ra) = (mul(jr, &self.gyro) * h, mul(r, &self.accel));
        self.cross = [
            [y[0][0] - jg, y[0][1]],
            [y[1][0], y[1][1] - ra * h],
            [y[2][0], y[2][1] - ra * half_h2],
        ];
        self.gyro += Matrix3::identity() * (noise.gyro_random_walk * noise.gyro_random_walk * h);
        self.accel += Matrix3::identity() * (noise.accel_random_walk * noise.accel_random_walk * h);
    }
}

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
    covariance: CovarianceBlocks,
    d_rot_d_bg: Matrix3<f64>,
    d_vel_d_bg: Matrix3<f64>,
    d_vel_d_ba: Matrix3<f64>,
    d_pos_d_bg: Matrix3<f64>,
    d_pos_d_ba: Matrix3<f64>,
    /// Bias random walk during the interval, when tracked (see [`Preintegrator::with_bias_walk`]).
    bias_walk: Option<BiasWalk>,
}

/// The bias part of the 15×15 combined covariance `[δθ, δv, δp, δb_g, δb_a]`: the 9×6 cross
/// covariance `X` as 3×2 blocks (rows θ, v, p; columns b_g, b_a) and the bias covariances, which
/// stay block-diagonal (independent walks, starting from zero at i).
#[derive(Debug, Clone, PartialEq)]
struct BiasWalk {
    cross: [[Matrix3<f64>; 2]; 3],
    gyro: Matrix3<f64>,
    accel: Matrix3<f64>,
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
            covariance: [Matrix3::zeros(); 6],
            d_rot_d_bg: Matrix3::zeros(),
            d_vel_d_bg: Matrix3::zeros(),
            d_vel_d_ba: Matrix3::zeros(),
            d_pos_d_bg: Matrix3::zeros(),
            d_pos_d_ba: Matrix3::zeros(),
            bias_walk: None,
        }
    }

    /// Also track the bias random walk between i and j, for [`Preintegrator::covariance_combined`]
    /// (about twice the work per sample, as GTSAM's combined factor).
    pub fn with_bias_walk(mut self) -> Self {
        self.bias_walk = Some(BiasWalk {
            cross: [[Matrix3::zeros(); 2]; 3],
            gyro: Matrix3::zeros(),
            accel: Matrix3::zeros(),
        });
        self
    }

    /// Adds one interval of `h` seconds with the measurements `accel` [m/s²] and `gyro` [rad/s]
    /// held over it (the caller validates finiteness and `h > 0`).
    pub fn integrate_measurement(&mut self, accel: &Vector3<f64>, gyro: &Vector3<f64>, h: f64) {
        let a = accel - self.bias_accel;
        let w = gyro - self.bias_gyro;
        let r = self.delta_rotation;
        let a_cross = so3::hat(&a);
        let r_a_cross = mul(&r, &a_cross);
        let step = so3::exp(&(w * h));
        let step_t = step.matrix().transpose();
        let jr = so3::right_jacobian(&(w * h));
        let half_h2 = 0.5 * h * h;

        // Covariance first: A, B, C use the state before the update.
        let var_a = self.noise.accel_density * self.noise.accel_density / h;
        let var_g = self.noise.gyro_density * self.noise.gyro_density / h;
        let old = self.covariance;
        self.covariance = propagate_blocks(&old, &step_t, &(-r_a_cross), &jr, h, var_a, var_g);
        if let Some(walk) = self.bias_walk.as_mut() {
            walk.step(&mut self.covariance, &step_t, &(-r_a_cross), &jr, &r, h, &self.noise);
        }

        // Bias Jacobians, position before velocity before rotation.
        let ra_drot = mul(&r_a_cross, &self.d_rot_d_bg);
        self.d_pos_d_ba += self.d_vel_d_ba * h - r * half_h2;
        self.d_pos_d_bg += self.d_vel_d_bg * h - ra_drot * half_h2;
        self.d_vel_d_ba -= r * h;
        self.d_vel_d_bg -= ra_drot * h;
        self.d_rot_d_bg = mul(&step_t, &self.d_rot_d_bg) - jr * h;

        // Deltas.
        let ra = r * a;
        self.delta_position += self.delta_velocity * h + ra * half_h2;
        self.delta_velocity += ra * h;
        self.delta_rotation = mul(&r, step.matrix());
        self.delta_t += h;
    }

    /// `A`, `B`, `C` of the next interval (module docs) as dense matrices: the reference the
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
        out.fixed_view_mut::<9, 9>(0, 0).copy_from(&assemble(&self.covariance));
        for (i, row) in walk.cross.iter().enumerate() {
            for (j, b) in row.iter().enumerate() {
                out.fixed_view_mut::<3, 3>(3 * i, 9 + 3 * j).copy_from(b);
                out.fixed_view_mut::<3, 3>(9 + 3 * j, 3 * i).copy_from(&b.transpose());
            }
        }
        out.fixed_view_mut::<3, 3>(9, 9).copy_from(&walk.gyro);
        out.fixed_view_mut::<3, 3>(12, 12).copy_from(&walk.accel);
        Some(out)
    }

    /// The preintegration over i → k of this one (i → j) followed by `next` (j → k), covariance
    /// and bias Jacobians included: `ΔR_ik = ΔR_ij ΔR_jk`, `Δv_ik = Δv_ij + ΔR_ij Δv_jk`,
    /// `Δp_ik = Δp_ij + Δv_ij Δt_jk + ΔR_ij Δp_jk`; errors compose through
    /// `δθ_ik = ΔR_jkᵀ δθ_ij + δθ_jk`, `δv_ik = δv_ij − ΔR_ij[Δv_jk]× δθ_ij + ΔR_ij δv_jk`,
    /// `δp_ik = δp_ij + Δt_jk δv_ij − ΔR_ij[Δp_jk]× δθ_ij + ΔR_ij δp_jk`. Both must share the bias
    /// and noise (`None` otherwise); the bias random walk is not merged (`covariance_combined` of the
    /// result is `None`).
    pub fn merge(&self, next: &Preintegrator) -> Option<Preintegrator> {
        if self.bias_gyro != next.bias_gyro || self.bias_accel != next.bias_accel || self.noise != next.noise {
            return None;
        }
        let r = self.delta_rotation;
        let r_jk_t = next.delta_rotation.transpose();
        let dt_jk = next.delta_t;
        let rv = -mul(&r, &so3::hat(&next.delta_velocity));
        let rp = -mul(&r, &so3::hat(&next.delta_position));
        // J1 (w.r.t. the first segment's errors) and J2 (the second's), dense 9×9: merging is rare.
        let mut j1 = Covariance9::identity();
        j1.fixed_view_mut::<3, 3>(0, 0).copy_from(&r_jk_t);
        j1.fixed_view_mut::<3, 3>(3, 0).copy_from(&rv);
        j1.fixed_view_mut::<3, 3>(6, 0).copy_from(&rp);
        j1.fixed_view_mut::<3, 3>(6, 3)
            .copy_from(&(Matrix3::identity() * dt_jk));
        let mut j2 = Covariance9::zeros();
        j2.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
        j2.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
        j2.fixed_view_mut::<3, 3>(6, 6).copy_from(&r);
        let cov = j1 * self.covariance() * j1.transpose() + j2 * next.covariance() * j2.transpose();
        let block = |i: usize, j: usize| cov.fixed_view::<3, 3>(3 * i, 3 * j).into_owned();
        Some(Preintegrator {
            bias_gyro: self.bias_gyro,
            bias_accel: self.bias_accel,
            noise: self.noise,
            delta_rotation: mul(&r, &next.delta_rotation),
            delta_velocity: self.delta_velocity + r * next.delta_velocity,
            delta_position: self.delta_position + self.delta_velocity * dt_jk + r * next.delta_position,
            delta_t: self.delta_t + dt_jk,
            covariance: [
                block(0, 0),
                block(0, 1),
                block(0, 2),
                block(1, 1),
                block(1, 2),
                block(2, 2),
            ],
            d_rot_d_bg: mul(&r_jk_t, &self.d_rot_d_bg) + next.d_rot_d_bg,
            d_vel_d_bg: self.d_vel_d_bg + mul(&rv, &self.d_rot_d_bg) + mul(&r, &next.d_vel_d_bg),
            d_vel_d_ba: self.d_vel_d_ba + mul(&r, &next.d_vel_d_ba),
            d_pos_d_bg: self.d_pos_d_bg
                + self.d_vel_d_bg * dt_jk
                + mul(&rp, &self.d_rot_d_bg)
                + mul(&r, &next.d_pos_d_bg),
            d_pos_d_ba: self.d_pos_d_ba + self.d_vel_d_ba * dt_jk + mul(&r, &next.d_pos_d_ba),
            bias_walk: None,
        })
    }

    /// Covariance of `[δθ, δv, δp]` (9×9).
    pub fn covariance(&self) -> Covariance9 {
        assemble(&self.covariance)
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
