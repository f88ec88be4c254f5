//! Two consecutive preintegrations (i → j, j → k) composed into one (i → k).
//!
//! `ΔR_ik = ΔR_ij ΔR_jk`, `Δv_ik = Δv_ij + ΔR_ij Δv_jk`, `Δp_ik = Δp_ij + Δv_ij Δt_jk + ΔR_ij Δp_jk`;
//! errors compose as `δx_ik = J_1 δx_ij + J_2 δx_jk` with
//! `δθ_ik = ΔR_jkᵀ δθ_ij + δθ_jk`, `δv_ik = δv_ij − ΔR_ij[Δv_jk]× δθ_ij + ΔR_ij δv_jk`,
//! `δp_ik = δp_ij + Δt_jk δv_ij − ΔR_ij[Δp_jk]× δθ_ij + ΔR_ij δp_jk`, so the bias Jacobians
//! compose as `J_1 J_b,ij + J_2 J_b,jk` and the covariance as `J_1 Σ_ij J_1ᵀ + J_2 Σ_jk J_2ᵀ`, plus,
//! in the midpoint scheme, the correlation through the shared sample j:
//! `Cov(δx_ij, δx_jk) = Cov(δx_ij, n_j) Cov(n_j)⁻¹ Cov(n_j, δx_jk)`. The shared sample's variance
//! is i → j's (`σ²/h` of its first interval, as one run over both gives it): j → k's share of it,
//! taken with its own first interval, is rescaled.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::blocks::{self, Cross};
use super::{Covariance9, Preintegrator, Scheme};
use crate::error::{Error, Result};
use crate::mat3::M3;
use crate::so3;

/// `diag(g, g, g, a, a, a)`: one factor per sensor of the `[gyro, accel]` noise.
fn per_axis(g: f64, a: f64) -> SMatrix<f64, 6, 6> {
    SMatrix::<f64, 6, 6>::from_diagonal(&nalgebra::Vector6::new(g, g, g, a, a, a))
}

fn mismatch(expected: &'static str, got: String) -> Error {
    Error::Parameter {
        name: "next",
        expected,
        got,
    }
}

/// `(J_1, J_2)` of the composition (module docs) after `ΔR_ij`, with the deltas `(ΔR, Δv, Δp, Δt)`
/// of j → k.
pub(super) fn composition(
    r: &Matrix3<f64>,
    (dr, dv, dp, dt_jk): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>, f64),
) -> (Covariance9, Covariance9) {
    let mut j1 = Covariance9::identity();
    j1.fixed_view_mut::<3, 3>(0, 0).copy_from(&dr.transpose());
    j1.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-r * so3::hat(dv)));
    j1.fixed_view_mut::<3, 3>(6, 0).copy_from(&(-r * so3::hat(dp)));
    j1.fixed_view_mut::<3, 3>(6, 3)
        .copy_from(&(Matrix3::identity() * dt_jk));
    let mut j2 = Covariance9::zeros();
    j2.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
    j2.fixed_view_mut::<3, 3>(3, 3).copy_from(r);
    j2.fixed_view_mut::<3, 3>(6, 6).copy_from(r);
    (j1, j2)
}

impl Preintegrator {
    /// The preintegration over i → k of this one (i → j) followed by `next` (j → k), covariance
    /// and bias Jacobians included (module docs of `merge.rs`). Both must share the scheme, bias
    /// and noise (and saturation noise factor), and in the midpoint scheme `next` must start with this one's last sample. The bias
    /// random walk is not merged (`covariance_combined` of the result is `None`). Finite
    /// preintegrations whose composition overflows are an [`Error::Overflow`] in `next`.
    pub fn merge(&self, next: &Preintegrator) -> Result<Preintegrator> {
        let merged = self.merge_unchecked(next)?;
        if !merged.is_finite() {
            return Err(Error::Overflow { index: 0 }.in_argument("next"));
        }
        Ok(merged)
    }

    /// [`Preintegrator::merge`] without the overflow check (the batch path checks once, at its end).
    pub(super) fn merge_unchecked(&self, next: &Preintegrator) -> Result<Preintegrator> {
        if self.scheme != next.scheme {
            let got = format!("{:?} after {:?}", next.scheme, self.scheme);
            return Err(mismatch("a preintegration with the same scheme", got));
        }
        if self.bias_gyro != next.bias_gyro || self.bias_accel != next.bias_accel || self.noise != next.noise {
            return Err(mismatch(
                "a preintegration with the same bias and noise",
                "a different bias or noise".into(),
            ));
        }
        if self.saturation_noise_factor != next.saturation_noise_factor {
            let got = format!(
                "{} after {}",
                next.saturation_noise_factor, self.saturation_noise_factor
            );
            return Err(mismatch("a preintegration with the same saturation noise factor", got));
        }
        if let Some(first) = &next.boundary.first {
            self.boundary.check_next(first, "next")?;
        }
        if self.scheme == Scheme::Midpoint {
            match (&self.ends.last, &next.ends.first) {
                (None, _) => {
                    return Ok(Preintegrator {
                        bias_walk: None,
                        ..next.clone()
                    })
                }
                (_, None) => {
                    return Ok(Preintegrator {
                        bias_walk: None,
                        ..self.clone()
                    })
                }
                (Some(last), Some(first)) if (last.accel, last.gyro) != (first.accel, first.gyro) => {
                    return Err(mismatch(
                        "a midpoint preintegration starting with this one's last sample",
                        format!("first sample accel {:?}, gyro {:?}", first.accel, first.gyro),
                    ))
                }
                _ => {}
            }
            if next.ends.last.is_some_and(|s| s.var.is_none()) {
                // `next` holds only its first sample, this one's last: nothing to compose.
                return Ok(Preintegrator {
                    bias_walk: None,
                    ..self.clone()
                });
            }
            if self.ends.last.is_some_and(|s| s.var.is_none()) {
                // This one holds only `next`'s first sample, whose variance `next` set.
                return Ok(Preintegrator {
                    bias_walk: None,
                    ..next.clone()
                });
            }
        }
        let r = self.delta_rotation;
        let dt_jk = next.delta_t;
        let (j1, j2) = composition(
            &r,
            (&next.delta_rotation, &next.delta_velocity, &next.delta_position, dt_jk),
        );
        // Dense 9×9 products: merging is rare.
        // `next`'s covariance without its last sample's noise: the merged window holds that apart too.
        let mut cov_jk = blocks::assemble(&next.covariance_blocks(false));
        let transport = |m: &Covariance9, x: &Cross| blocks::cross_of(&(m * blocks::cross_matrix(x)));
        let mut ends = next.ends.clone();
        let mut between = None;
        if let (Scheme::Midpoint, Some(first)) = (self.scheme, &next.ends.first) {
            // Cov(δx_jk, n_j) Cov(n_j)⁻¹ is n_j's sensitivity D; Cov(δx_ij, δx_jk) = Cov(δx_ij, n_j) Dᵀ.
            let [q_g, q_a] = first.var.unwrap_or([0.0; 2]);
            let inv = |q: f64| if q > 0.0 { 1.0 / q } else { 0.0 };
            let cross_jk = blocks::cross_matrix(&next.body_rows(&next.ends.start_cross));
            let d = cross_jk * per_axis(inv(q_g), inv(q_a));
            // n_j's variance is σ²/h of its first interval, which is this one's last; `next` gave
            // it its own first interval's (`q'`): its share `D q' Dᵀ` becomes `D q Dᵀ`, so that a
            // merge over jittered stamps equals one run over all the samples.
            if let Some([q_g_ij, q_a_ij]) = self.ends.last.and_then(|s| s.var).filter(|&q| q != [q_g, q_a]) {
                let rescale = |q_ij: f64, q_jk: f64| (q_ij - q_jk) * inv(q_jk) * inv(q_jk);
                let s = per_axis(rescale(q_g_ij, q_g), rescale(q_a_ij, q_a));
                cov_jk += cross_jk * s * cross_jk.transpose();
            }
            between = Some(j1 * blocks::cross_matrix(&self.end_cross()) * d.transpose() * j2.transpose());
            ends.first = self.ends.first;
            ends.start_cross = transport(&j1, &self.body_rows(&self.ends.start_cross));
            // In frame i: J_2 = diag(I, ΔR_ij, ΔR_ij) between body frames, ΔR_ij on every row.
            ends.pending = next.ends.pending.rotated(&M3::of(&r));
        }
        let mut cov = j1 * self.covariance() * j1.transpose() + j2 * cov_jk * j2.transpose();
        if let Some(b) = between {
            cov += b + b.transpose();
        }
        let body_jac = |p: &Preintegrator| blocks::cross_matrix(&p.body_rows(&p.jac));
        let jac = j1 * body_jac(self) + j2 * body_jac(next);
        Ok(Preintegrator {
            scheme: self.scheme,
            bias_gyro: self.bias_gyro,
            bias_accel: self.bias_accel,
            noise: self.noise,
            saturation_noise_factor: self.saturation_noise_factor,
            // Merged products would accumulate rounding as sample products do (mod.rs).
            delta_rotation: super::project_rotation(&(r * next.delta_rotation)),
            delta_velocity: self.delta_velocity + r * next.delta_velocity,
            delta_position: self.delta_position + self.delta_velocity * dt_jk + r * next.delta_position,
            delta_t: self.delta_t + dt_jk,
            covariance: blocks::blocks_of(&((cov + cov.transpose()) * 0.5)),
            jac: blocks::cross_of(&jac),
            bias_walk: None,
            ends,
            boundary: self.boundary.then(&next.boundary),
            since_projection: 0,
        }
        .in_own_frame())
    }
}
