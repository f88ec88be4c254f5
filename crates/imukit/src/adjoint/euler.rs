//! The lie_euler window with noise densities, covariance, final record only (the common case of
//! `imukit.torch.preintegrate`), forward and reversed, with the covariance's rotation error
//! expressed in the window's start frame.
//!
//! Forster et al.'s covariance (`step.rs`) has `δθ` in the body frame at the current sample, so
//! its `A = [[Eᵀ, 0, 0], [−hΔR[α]×, I, 0], [−½h²ΔR[α]×, hI, I]]` rotates the `θ` block by a
//! general 3×3 every interval. With `δθ̃ = ΔR δθ` (the start frame, `P̃ = G P Gᵀ`,
//! `G = diag(ΔR, I, I)`) the same recursion is `P̃' = ÃP̃Ãᵀ + Q̃` with the unipotent
//! `Ã = G' A G⁻¹ = [[I, 0, 0], [C, I, 0], [½hC, hI, I]]`, `C = [g]×`, `g = −hΔRα` (since
//! `ΔR[α]×ΔRᵀ = [ΔRα]×` and `ΔR' = ΔR E`), and the noise
//! `Q̃ = diag(hσ_g² WWᵀ, σ_a²[[hI, ½h²I], [½h²I, ¼h³I]])`, `W = ΔR' J_r` (Forster's
//! `B₁ diag(σ_g²/h, σ_a²/h) B₁ᵀ` rotated, `ΔRΔRᵀ = I`; no noise on a step `h = 0`, as `mod.rs`).
//! `P̃` is symmetric, kept as its six upper 3×3 blocks, and `ÃP̃Ãᵀ` is five 3×3 products; the
//! output is `P = G⁻¹P̃G⁻ᵀ` with the window's final `ΔR` (the same numbers as `step.rs` up to
//! rounding: tested against it).
//!
//! Reverse, with `V` the symmetric cotangent of `P̃` (`dL = ⟨V, dP̃⟩`): from the output's
//! `P̄`, `V_out = ½(P̄ + P̄ᵀ)`, `V = G V_out Gᵀ` (`P = G⁻¹P̃G⁻ᵀ`, `G` at the window's end) and
//! `ΔR̄ += 2ΔR (P V_out)_θθ`; per interval `V ← ÃᵀV'Ã`, `Ā = 2V'ÃP̃` read on `Ã`'s variable
//! blocks (`C̄ = Ā_vθ + ½hĀ_pθ`, `h̄ += ½⟨Ā_pθ, C⟩ + tr Ā_pv`, `ḡ = vee₂(C̄)`), `W̄ = 2hσ_g² V'_θθ W`,
//! `σ̄_g² = h⟨V'_θθ, WWᵀ⟩`, `σ̄_a² = h tr V'_vv + h² tr V'_vp + ¼h³ tr V'_pp`, then through
//! `g = −hΔRα`, `ΔR' = ΔR E`, the deltas and `Exp`, `J_r` (`so3.rs`) to `ω`, `α` and `h`. The tape
//! keeps per interval `ΔR`, `Δv` and the five blocks of `P̃` the reverse reads (57 numbers).

use nalgebra::{Matrix3, Vector3};

use super::so3::{exp_and_jacobian_pullback, vee2};
use super::step::{Mat9, State};
use super::{read, write, Outputs, Windows};
use crate::so3::{exp, hat, right_jacobian};

/// A symmetric 9×9 `[θ, v, p]` by its upper 3×3 blocks.
#[derive(Debug, Clone, Copy)]
struct Sym {
    tt: Matrix3<f64>,
    tv: Matrix3<f64>,
    tp: Matrix3<f64>,
    vv: Matrix3<f64>,
    vp: Matrix3<f64>,
    pp: Matrix3<f64>,
}

impl Sym {
    fn zero() -> Sym {
        let z = Matrix3::zeros();
        Sym {
            tt: z,
            tv: z,
            tp: z,
            vv: z,
            vp: z,
            pp: z,
        }
    }

    /// From a full matrix (its upper blocks).
    fn from_full(m: &Mat9) -> Sym {
        let b = |i: usize, j: usize| m.fixed_view::<3, 3>(3 * i, 3 * j).into_owned();
        Sym {
            tt: b(0, 0),
            tv: b(0, 1),
            tp: b(0, 2),
            vv: b(1, 1),
            vp: b(1, 2),
            pp: b(2, 2),
        }
    }

    /// The full matrix with the `θ` rows and columns taken into the frame `rᵀ` (`G⁻¹ · G⁻ᵀ`,
    /// `G = diag(r, I, I)`); `r = I`: as is.
    fn rotated_full(&self, r: &Matrix3<f64>) -> Mat9 {
        let (tt, tv, tp) = (r.tr_mul(&(self.tt * r)), r.tr_mul(&self.tv), r.tr_mul(&self.tp));
        let mut m = Mat9::zeros();
        for (i, j, b) in [
            (0, 0, tt),
            (0, 1, tv),
            (0, 2, tp),
            (1, 1, self.vv),
            (1, 2, self.vp),
            (2, 2, self.pp),
        ] {
            m.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&b);
            m.fixed_view_mut::<3, 3>(3 * j, 3 * i).copy_from(&b.transpose());
        }
        m
    }
}

/// One interval's quantities both directions use.
struct Step {
    h: f64,
    w: Vector3<f64>,
    a: Vector3<f64>,
    phi: Vector3<f64>,
    e: Matrix3<f64>,
    jr: Matrix3<f64>,
    /// `ΔRα`, the specific force in the start frame.
    f: Vector3<f64>,
    /// `C = [−hΔRα]×`.
    c: Matrix3<f64>,
}

#[inline(always)]
fn step(x: &Windows<'_>, k: usize, r: &Matrix3<f64>) -> Step {
    let v = |s: &[f64]| Vector3::new(s[3 * k], s[3 * k + 1], s[3 * k + 2]);
    let (h, w, a) = (x.h[k], v(x.w), v(x.a));
    let phi = w * h;
    let f = r * a;
    Step {
        h,
        w,
        a,
        phi,
        e: *exp(&phi).matrix(),
        jr: right_jacobian(&phi),
        f,
        c: hat(&(f * -h)),
    }
}

/// `ÃPÃᵀ + Q̃` (module docs), `r1` the rotation after the step, `q = [σ_g², σ_a²]`.
#[inline(always)]
fn propagate(p: &Sym, s: &Step, r1: &Matrix3<f64>, q: &[f64]) -> Sym {
    let (c, h) = (&s.c, s.h);
    let hh = 0.5 * h;
    // C P_θj; rows v and p, column θ, of ÃP.
    let (ct, cv, cp) = (c * p.tt, c * p.tv, c * p.tp);
    let yv_t = ct + p.tv.transpose();
    let yp_t = ct * hh + p.tv.transpose() * h + p.tp.transpose();
    let yvc = yv_t * c.transpose();
    // P_θθCᵀ = (CP_θθ)ᵀ.
    let mut n = Sym {
        tt: p.tt,
        tv: ct.transpose() + p.tv,
        tp: ct.transpose() * hh + p.tv * h + p.tp,
        vv: yvc + cv + p.vv,
        vp: yvc * hh + (cv + p.vv) * h + cp + p.vp,
        pp: yp_t * c.transpose() * hh + (cv * hh + p.vv * h + p.vp.transpose()) * h + cp * hh + p.vp * h + p.pp,
    };
    if h > 0.0 {
        let wm = r1 * s.jr;
        n.tt += wm * wm.transpose() * (h * q[0]);
        let d = Matrix3::identity() * q[1];
        n.vv += d * h;
        n.vp += d * (hh * h);
        n.pp += d * (hh * hh * h);
    }
    n
}

/// The window's deltas and `P̃`, the tape of the states before each interval when given.
#[inline(always)]
fn run(x: &Windows<'_>, q: &[f64], mut tape: Option<&mut Vec<f64>>) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>, Sym) {
    let (mut r, mut v, mut p, mut cov) = (Matrix3::identity(), Vector3::zeros(), Vector3::zeros(), Sym::zero());
    for k in 0..x.n {
        if let Some(t) = tape.as_deref_mut() {
            t.extend_from_slice(r.as_slice());
            t.extend_from_slice(v.as_slice());
            for b in [&cov.tt, &cov.tv, &cov.tp, &cov.vv, &cov.vp] {
                t.extend_from_slice(b.as_slice());
            }
        }
        let s = step(x, k, &r);
        let r1 = r * s.e;
        cov = propagate(&cov, &s, &r1, q);
        p += v * s.h + s.f * (0.5 * s.h * s.h);
        v += s.f * s.h;
        r = r1;
    }
    (r, v, p, cov)
}

/// Numbers per interval of the tape.
const TAPE: usize = 57;

/// One window's record (`mod.rs`'s layout, covariance, no Jacobian).
pub(super) fn forward(x: &Windows<'_>, q: &[f64], outputs: &Outputs, o: &mut [f64]) {
    let (r, v, p, cov) = run(x, q, None);
    let s = State {
        r,
        v,
        p,
        cov: cov.rotated_full(&r),
        ..State::zero()
    };
    write(&s, outputs, o);
}

/// One window's input cotangents (`mod.rs`'s rows `[h̄, w̄, ā, σ̄_g², σ̄_a²]`) given its record's
/// cotangent `bar`.
pub(super) fn backward(x: &Windows<'_>, q: &[f64], outputs: &Outputs, bar: &[f64], g: &mut [f64]) {
    let gw = x.grad_width();
    let mut tape = Vec::with_capacity(x.n * TAPE);
    let (r_end, _, _, cov_end) = run(x, q, Some(&mut tape));
    let cot = read(bar, outputs);
    let v_out = (cot.cov + cot.cov.transpose()) * 0.5;
    // ΔR̄ += 2ΔR (P V_out)_θθ, P the output (body frame).
    let pv = cov_end.rotated_full(&r_end) * v_out;
    let mut r_bar = cot.r + r_end * pv.fixed_view::<3, 3>(0, 0) * 2.0;
    let (mut v_bar, p_bar) = (cot.v, cot.p);
    // V = G V_out Gᵀ, G = diag(ΔR, I, I): `rotated_full` with r = ΔRᵀ.
    let mut vs = Sym::from_full(&Sym::from_full(&v_out).rotated_full(&r_end.transpose()));
    for k in (0..x.n).rev() {
        let t = &tape[k * TAPE..(k + 1) * TAPE];
        let m = |i: usize| Matrix3::from_column_slice(&t[12 + 9 * i..21 + 9 * i]);
        let r = Matrix3::from_column_slice(&t[..9]);
        let v = Vector3::from_column_slice(&t[9..12]);
        let (tt, tv, tp, vv, vp) = (m(0), m(1), m(2), m(3), m(4));
        let s = step(x, k, &r);
        let (h, hh, c) = (s.h, 0.5 * s.h, &s.c);
        let r1 = r * s.e;
        // Deltas: ΔRα enters Δv with h and Δp with ½h².
        let mut f_bar = v_bar * h + p_bar * (hh * h);
        let mut h_bar = s.f.dot(&v_bar) + v.dot(&p_bar) + h * s.f.dot(&p_bar);
        let mut jr_bar = Matrix3::zeros();
        let row = &mut g[k * gw..(k + 1) * gw];
        let vt = &vs;
        if h > 0.0 {
            let wm = r1 * s.jr;
            let vw = vt.tt * wm;
            let st = vw.dot(&wm);
            let w_bar = vw * (2.0 * h * q[0]);
            r_bar += w_bar * s.jr.transpose();
            jr_bar = r1.tr_mul(&w_bar);
            let (t_vv, t_vp, t_pp) = (vt.vv.trace(), vt.vp.trace(), vt.pp.trace());
            row[7] = h * st;
            row[8] = h * t_vv + h * h * t_vp + 0.25 * h * h * h * t_pp;
            h_bar += q[0] * st + q[1] * (t_vv + 2.0 * h * t_vp + 0.75 * h * h * t_pp);
        }
        // Z = ÃᵀV' (its blocks Z_ij), D_j = V'_vj + ½hV'_pj.
        let ct = c.transpose();
        let (d_t, d_v, d_p) = (
            vt.tv.transpose() + vt.tp.transpose() * hh,
            vt.vv + vt.vp.transpose() * hh,
            vt.vp + vt.pp * hh,
        );
        let z_tt = vt.tt + ct * d_t;
        let z_tv = vt.tv + ct * d_v;
        let z_tp = vt.tp + ct * d_p;
        let z_vv = vt.vv + vt.vp.transpose() * h;
        let z_vp = vt.vp + vt.pp * h;
        let z_pp = vt.pp;
        // G_j = Z_jv + ½hZ_jp; C̄ = 2Σ_j G_jᵀP_jθ, ½Ā_pθ = Σ_j Z_jpᵀP_jθ (P_vθ = P_θvᵀ, …).
        let g_t = z_tv + z_tp * hh;
        let g_v = z_vv + z_vp * hh;
        let g_p = vt.vp.transpose() + z_pp * hh;
        let c_bar = (g_t.tr_mul(&tt) + g_v.tr_mul(&tv.transpose()) + g_p.tr_mul(&tp.transpose())) * 2.0;
        let a_pt = z_tp.tr_mul(&tt) + z_vp.tr_mul(&tv.transpose()) + z_pp.tr_mul(&tp.transpose());
        let tr_pv = 2.0 * (z_tp.dot(&tv) + z_vp.dot(&vv) + z_pp.dot(&vp.transpose()));
        h_bar += a_pt.dot(c) + tr_pv;
        // C = [g]×, g = −hf.
        let gb = vee2(&c_bar);
        f_bar -= gb * h;
        h_bar -= s.f.dot(&gb);
        // V = ZÃ, upper blocks.
        vs = Sym {
            tt: z_tt + g_t * c,
            tv: z_tv + z_tp * h,
            tp: z_tp,
            vv: z_vv + z_vp * h,
            vp: z_vp,
            pp: z_pp,
        };
        // ΔR' = ΔR E, f = ΔRα.
        let e_bar = r.tr_mul(&r_bar);
        r_bar = r_bar * s.e.transpose() + f_bar * s.a.transpose();
        let phi_bar = exp_and_jacobian_pullback(&s.phi, &e_bar, &jr_bar);
        row[0] = h_bar + s.w.dot(&phi_bar);
        row[1..4].copy_from_slice((phi_bar * h).as_slice());
        row[4..7].copy_from_slice(r.tr_mul(&f_bar).as_slice());
        v_bar += p_bar * h;
    }
}
