//! The acausal smoother of [`super::Robust`]: the online filter run forward and on the
//! time-reversed record, the two estimates fused sample by sample by their uncertainties.
//!
//! Time reversal: with `t' = −t` the body turns at `−ω`, so the reversed record has gyro
//! `−ω_m = −ω − b` (bias `−b`) and the same accelerometer and field; the backward pass estimates
//! the same `q_wb(t)` from the samples after `t`.
//!
//! Fusion (two independent Gaussian estimates, weights by inverse variance): the bias per axis
//! `b = (b_f/σ_f² + b_b/σ_b²)/(1/σ_f² + 1/σ_b²)`; the attitude `q = Exp(w Log(q_b ⊗ q_f⁻¹)) ⊗ q_f`,
//! `w = v_f/(v_f + v_b)`, each pass's attitude variance `v` taken as `‖σ_b‖²` (a bias error ε
//! leaves the low-passed inclination `ε τ` behind and the heading `ε τ_mag`, the same `τ` for both
//! passes; a pass that has just started has the prior σ and so little weight). 6D: the backward
//! heading is first aligned to the forward one by the circular mean of their heading difference
//! (each 6D heading has its own arbitrary origin).
//!
//! Flags: rest where either pass detects it (detection needs `rest_duration_s` of history, which
//! each pass has on its own side); disturbed where both passes reject the field.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::{Outputs, Robust, RobustState};
use crate::filters::Inputs;
use crate::quat::{exp, log, multiply};
use crate::Result;

/// One pass's outputs, owned.
struct Pass {
    q: Vec<[f64; 4]>,
    bias: Vec<[f64; 3]>,
    sigma: Vec<[f64; 3]>,
    rest: Vec<bool>,
    disturbed: Vec<bool>,
}

impl Pass {
    fn new(n: usize) -> Self {
        Self {
            q: vec![[0.0; 4]; n],
            bias: vec![[0.0; 3]; n],
            sigma: vec![[0.0; 3]; n],
            rest: vec![false; n],
            disturbed: vec![false; n],
        }
    }

    fn outputs(&mut self) -> Outputs<'_> {
        Outputs {
            q: &mut self.q,
            bias: &mut self.bias,
            bias_sigma: &mut self.sigma,
            rest: &mut self.rest,
            mag_disturbed: &mut self.disturbed,
        }
    }
}

fn quat(x: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(Quaternion::new(x[3], x[0], x[1], x[2]))
}

/// `q_b ⊗ q_f⁻¹`: the backward estimate relative to the forward one, in the world.
fn relative(f: &[f64; 4], b: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(multiply(quat(b).quaternion(), &quat(f).quaternion().conjugate()))
}

impl Robust {
    /// The smoothed estimate of a whole record (one row of `out` per sample): `state` starts
    /// the forward pass (uninitialised, or at an initial attitude) and ends as the forward
    /// pass's final state. Deterministic; errors as [`Robust::run`].
    pub fn smooth(&self, state: &mut RobustState, inputs: &Inputs<'_>, out: &mut Outputs<'_>) -> Result<()> {
        let n = inputs.t.len();
        if !out.len_ok(n) {
            return Err(crate::Error::RowCount {
                input: n,
                output: out.q.len(),
            });
        }
        let mut fwd = Pass::new(n);
        self.run(state, inputs, false, &mut fwd.outputs())?;
        if n == 0 {
            return Ok(());
        }
        let t: Vec<f64> = inputs.t.iter().rev().map(|t| -t).collect();
        let gyro: Vec<[f64; 3]> = inputs.gyro.iter().rev().map(|w| [-w[0], -w[1], -w[2]]).collect();
        let accel: Vec<[f64; 3]> = inputs.accel.iter().rev().copied().collect();
        let mag: Option<Vec<[f64; 3]>> = inputs.mag.map(|m| m.iter().rev().copied().collect());
        let reversed = Inputs {
            t: &t,
            gyro: &gyro,
            accel: &accel,
            mag: mag.as_deref(),
        };
        let mut bwd = Pass::new(n);
        self.run(&mut RobustState::default(), &reversed, false, &mut bwd.outputs())?;
        bwd.q.reverse();
        bwd.bias.reverse();
        bwd.sigma.reverse();
        bwd.rest.reverse();
        bwd.disturbed.reverse();

        // 6D: the backward heading origin moved onto the forward one (circular mean of the
        // twist about the vertical z, which both worlds share).
        let align = if inputs.mag.is_some() {
            UnitQuaternion::identity()
        } else {
            let (mut s, mut c) = (0.0, 0.0);
            for (f, b) in fwd.q.iter().zip(&bwd.q) {
                let d = relative(f, b);
                let psi = 2.0 * d.k.atan2(d.w);
                (s, c) = (s + psi.sin(), c + psi.cos());
            }
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), -s.atan2(c))
        };
        for k in 0..n {
            let (sf, sb) = (Vector3::from(fwd.sigma[k]), Vector3::from(bwd.sigma[k]));
            let (vf, vb) = (sf.norm_squared(), sb.norm_squared());
            let w = if vf + vb > 0.0 { vf / (vf + vb) } else { 0.5 };
            let qb = align * quat(&bwd.q[k]);
            let qf = quat(&fwd.q[k]);
            let d = log(&relative(&fwd.q[k], &qb.coords.into()));
            let q = exp(&(d * w)) * qf;
            out.q[k] = q.coords.into();
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
            out.mag_disturbed[k] = fwd.disturbed[k] && bwd.disturbed[k];
        }
        Ok(())
    }
}
