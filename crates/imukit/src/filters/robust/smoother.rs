//! The acausal smoother of [`super::Robust`]: the online filter run forward and on the
//! time-reversed record, the two estimates fused sample by sample by their uncertainties.
//!
//! Time reversal: with `t' = −t` the body turns at `−ω`, so the reversed record has gyro
//! `−ω_m = −ω − b` (bias `−b`) and the same accelerometer and field; the backward pass estimates
//! the same `q_wb(t)` from the samples after `t`. Each interval is integrated with the same gyro
//! sample in both passes (the later one, as the online step does).
//!
//! Fusion (two independent Gaussian estimates, weights by inverse variance, the two-filter
//! smoother of Fraser & Potter, IEEE Trans. Automatic Control 14 (1969) 387–390): the bias per
//! axis `b = (b_f/σ_f² + b_b/σ_b²)/(1/σ_f² + 1/σ_b²)`; the attitude
//! `q = Exp(W Log(q_b ⊗ q_f⁻¹)) ⊗ q_f` with `W = diag(½, ½, w)` in the world frame:
//! - inclination (x, y) `½`: in the second stage both passes run the same filter with the same
//!   bias over the same samples, so their tilt errors have the same variance, and the low pass's
//!   lag, which trails the drift forward in one pass and backward in the other, cancels in the mean
//!   (BROAD 6D offline 0.541° → 0.530°, every group better or equal);
//! - heading (z) `w = v_f/(v_f + v_b)`, each pass's variance `v` taken as `‖σ_b‖²` (a bias error ε
//!   leaves the heading `ε τ_mag` behind; a pass that has just started has the prior σ and so little
//!   weight): the two headings differ in quality, as each pass rejects the field at other times
//!   (`½` for the heading too: 9D 2.16° → 2.38°).
//!
//! 6D: the backward heading is first aligned to the forward one by the circular mean of their
//! heading difference (each 6D heading has its own arbitrary origin).
//!
//! Flags: rest where either pass detects it (detection needs `rest_duration_s` of history, which
//! each pass has on its own side); disturbed where both passes reject the field.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::{Outputs, Robust, RobustState, Track};
use crate::filters::Inputs;
use crate::quat::{exp, log, multiply};
use crate::Result;

fn quat(x: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(Quaternion::new(x[3], x[0], x[1], x[2]))
}

/// `q_b ⊗ q_f⁻¹`: the backward estimate relative to the forward one, in the world.
fn relative(f: &[f64; 4], b: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(multiply(quat(b).quaternion(), &quat(f).quaternion().conjugate()))
}

/// The record reversed in time (see the module doc).
struct Reversed {
    t: Vec<f64>,
    gyro: Vec<[f64; 3]>,
    accel: Vec<[f64; 3]>,
    mag: Option<Vec<[f64; 3]>>,
}

impl Reversed {
    fn new(inputs: &Inputs<'_>) -> Self {
        let n = inputs.t.len();
        // The forward step over (t_k, t_k+1) integrates ω_k+1; the backward one over the same
        // interval must too (ω_k would put it one sample's rotation apart: 1° at 5 rad/s, 285 Hz).
        let gyro = (0..n)
            .map(|j| {
                let w = inputs.gyro[(n - j).min(n - 1)];
                [-w[0], -w[1], -w[2]]
            })
            .collect();
        Self {
            t: inputs.t.iter().rev().map(|t| -t).collect(),
            gyro,
            accel: inputs.accel.iter().rev().copied().collect(),
            mag: inputs.mag.map(|m| m.iter().rev().copied().collect()),
        }
    }

    fn inputs(&self) -> Inputs<'_> {
        Inputs {
            t: &self.t,
            gyro: &self.gyro,
            accel: &self.accel,
            mag: self.mag.as_deref(),
        }
    }
}

/// `Exp(diag(½, ½, w_k) Log(q_b,k ⊗ q_f,k⁻¹)) ⊗ q_f,k` into `out` (`weights` the `w_k` of the
/// heading), the backward heading first aligned in 6D.
fn fuse_attitudes(fwd: &[[f64; 4]], bwd: &[[f64; 4]], weights: &[f64], nine: bool, out: &mut [[f64; 4]]) {
    // 6D: the backward heading origin moved onto the forward one (circular mean of the twist
    // about the vertical z, which both worlds share).
    let align = if nine {
        UnitQuaternion::identity()
    } else {
        let (mut s, mut c) = (0.0, 0.0);
        for (f, b) in fwd.iter().zip(bwd) {
            let d = relative(f, b);
            let psi = 2.0 * d.k.atan2(d.w);
            (s, c) = (s + psi.sin(), c + psi.cos());
        }
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), -s.atan2(c))
    };
    for (k, o) in out.iter_mut().enumerate() {
        let qb = align * quat(&bwd[k]);
        let d = log(&relative(&fwd[k], &qb.coords.into()));
        let w = Vector3::new(0.5, 0.5, weights[k]);
        *o = (exp(&d.component_mul(&w)) * quat(&fwd[k])).coords.into();
    }
}

impl Robust {
    /// The smoothed estimate of a whole record (one row of `out` per sample): `state` starts
    /// the forward pass (uninitialised, or at an initial attitude) and ends as the first forward
    /// pass's final state. Deterministic; errors as [`Robust::run`].
    ///
    /// Two stages: forward and backward passes estimate the bias, fused; then both passes again
    /// with the fused bias in every step, their attitudes fused.
    pub fn smooth(&self, state: &mut RobustState, inputs: &Inputs<'_>, out: &mut Outputs<'_>) -> Result<()> {
        let n = inputs.t.len();
        if !out.len_ok(n) {
            return Err(crate::Error::RowCount {
                input: n,
                output: out.q.len(),
            });
        }
        let start = *state;
        let mut fwd = Track::new(n);
        if n == 0 {
            return self.run(state, inputs, false, &mut fwd.outputs());
        }
        // The two passes of each stage are independent: one thread each (every pass is the same
        // sequential loop, so the result does not depend on the threads; errors are the forward
        // pass's first, as in sequence).
        let (forward, backward) = rayon::join(
            || self.run(state, inputs, false, &mut fwd.outputs()),
            || {
                let rev = Reversed::new(inputs);
                let mut bwd = Track::new(n);
                let done = self.run(&mut RobustState::default(), &rev.inputs(), false, &mut bwd.outputs());
                bwd.reverse();
                done.map(|()| (rev, bwd))
            },
        );
        forward?;
        let (rev, mut bwd) = backward?;

        let mut weights = vec![0.5; n];
        for (k, weight) in weights.iter_mut().enumerate() {
            let (sf, sb) = (Vector3::from(fwd.bias_sigma[k]), Vector3::from(bwd.bias_sigma[k]));
            let (vf, vb) = (sf.norm_squared(), sb.norm_squared());
            if vf + vb > 0.0 {
                *weight = vf / (vf + vb);
            }
            for i in 0..3 {
                let (bf, bb) = (fwd.bias[k][i], -bwd.bias[k][i]);
                let (pf, pb) = (sf[i] * sf[i], sb[i] * sb[i]);
                let (fused, var) = if pf + pb > 0.0 {
                    ((bf * pb + bb * pf) / (pf + pb), pf * pb / (pf + pb))
                } else {
                    (0.5 * (bf + bb), 0.0)
                };
                out.bias[k][i] = fused;
                out.bias_sigma[k][i] = var.sqrt();
            }
            out.rest[k] = fwd.rest[k] || bwd.rest[k];
            out.mag_disturbed[k] = fwd.mag_disturbed[k] && bwd.mag_disturbed[k];
        }

        // Second stage: the fused bias in every step of both passes.
        let bias_rev: Vec<[f64; 3]> = out.bias.iter().rev().map(|b| [-b[0], -b[1], -b[2]]).collect();
        let mut s = start;
        let fused_bias: &[[f64; 3]] = out.bias;
        let (forward, backward) = rayon::join(
            || self.run_with((&mut s, inputs), (0, false), &mut fwd.outputs(), Some(fused_bias)),
            || {
                let back = (&mut RobustState::default(), &rev.inputs());
                let done = self.run_with(back, (0, false), &mut bwd.outputs(), Some(&bias_rev));
                bwd.q.reverse();
                done
            },
        );
        forward?;
        backward?;
        fuse_attitudes(&fwd.q, &bwd.q, &weights, inputs.mag.is_some(), out.q);
        Ok(())
    }
}
