//! One preintegration interval, forward and reversed (its vector–Jacobian product).
//!
//! Forward, Forster, Carlone, Dellaert & Scaramuzza, "On-Manifold Preintegration for Real-Time
//! Visual-Inertial Odometry", T-RO 2017, eqs. 24–26 (deltas), 62–63 (covariance), App. B (bias
//! Jacobian), with the interval's rate `ω`, specific force `α` and step `h`:
//! `ΔR' = ΔR E`, `Δv' = Δv + ΔR α h`, `Δp' = Δp + Δv h + ½ ΔR α h²`, `E = Exp(ωh)`;
//! `P' = A P Aᵀ + B_g Σ_g B_gᵀ + B_a Σ_a B_aᵀ`, `J' = A J − [B_g B_a]` with
//! `A = [[Eᵀ, 0, 0], [−hM, I, 0], [−½h²M, hI, I]]`, `M = ΔR[α]×`, `B_g = [hJ_r; 0; 0]`,
//! `B_a = [0; hΔR; ½h²ΔR]`, `J_r = J_r(ωh)`; `Σ_g`, `Σ_a` the covariances of the interval's gyro
//! and accelerometer white noise. The midpoint scheme's deltas are the same step with
//! `α = ½(a₀ + E a₁)` (the specific forces at the interval's ends in its start frame).
//!
//! Reverse: for a scalar loss with cotangents `(ΔR̄', Δv̄', Δp̄', P̄', J̄')` after the step, the
//! chain rule through each line above gives the cotangents before it and of the inputs, e.g.
//! `P̄ = AᵀP̄'A`, `Ā += P̄'APᵀ + P̄'ᵀAP + J̄'Jᵀ`, `J̄ = AᵀJ̄'`, `Σ̄_g = B_gᵀP̄'B_g`; `Ā`, `B̄` and the
//! delta cotangents then reach `ΔR`, `E`, `J_r`, `α`, `h` through their blocks, and `E`, `J_r`
//! reach `ω` and `h` through `φ = ωh` (`so3.rs`).

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::so3::{exp_and_jacobian_pullback, vee2};
use crate::so3::{exp, hat, right_jacobian};

/// 9×9 `[δθ, δv, δp]`.
pub(super) type Mat9 = SMatrix<f64, 9, 9>;
/// 9×6: rows `[θ, v, p]`, columns `[b_g, b_a]`.
pub(super) type Mat96 = SMatrix<f64, 9, 6>;

/// The preintegration after some intervals (or a cotangent of it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct State {
    pub r: Matrix3<f64>,
    pub v: Vector3<f64>,
    pub p: Vector3<f64>,
    pub cov: Mat9,
    pub jac: Mat96,
}

impl State {
    pub const START: State = State {
        r: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        v: Vector3::new(0.0, 0.0, 0.0),
        p: Vector3::new(0.0, 0.0, 0.0),
        cov: Mat9::from_array_storage(nalgebra::ArrayStorage([[0.0; 9]; 9])),
        jac: Mat96::from_array_storage(nalgebra::ArrayStorage([[0.0; 9]; 6])),
    };

    pub fn zero() -> State {
        State {
            r: Matrix3::zeros(),
            ..Self::START
        }
    }
}

/// One interval's inputs.
#[derive(Debug, Clone, Copy)]
pub(super) struct Interval {
    pub h: f64,
    pub w: Vector3<f64>,
    pub a: Vector3<f64>,
    /// Midpoint: the specific force at the interval's end (`a` is at its start).
    pub a_end: Option<Vector3<f64>>,
    pub cov_g: Matrix3<f64>,
    pub cov_a: Matrix3<f64>,
}

/// The cotangents of an interval's inputs.
#[derive(Debug, Clone, Copy)]
pub(super) struct IntervalBar {
    pub h: f64,
    pub w: Vector3<f64>,
    pub a: Vector3<f64>,
    pub a_end: Vector3<f64>,
    pub cov_g: Matrix3<f64>,
    pub cov_a: Matrix3<f64>,
}

/// Which linear outputs are carried.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Linear {
    pub cov: bool,
    pub jac: bool,
}

/// The quantities of an interval both directions use.
struct Parts {
    phi: Vector3<f64>,
    e: Matrix3<f64>,
    jr: Matrix3<f64>,
    alpha: Vector3<f64>,
}

fn parts(x: &Interval) -> Parts {
    let phi = x.w * x.h;
    let e = *exp(&phi).matrix();
    let alpha = x.a_end.map_or(x.a, |a1| (x.a + e * a1) * 0.5);
    Parts {
        phi,
        e,
        jr: right_jacobian(&phi),
        alpha,
    }
}

/// `A` (module docs).
fn transition(e: &Matrix3<f64>, m: &Matrix3<f64>, h: f64) -> Mat9 {
    let mut a = Mat9::identity();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(&e.transpose());
    a.fixed_view_mut::<3, 3>(3, 0).copy_from(&(m * -h));
    a.fixed_view_mut::<3, 3>(6, 0).copy_from(&(m * (-0.5 * h * h)));
    a.fixed_view_mut::<3, 3>(6, 3).copy_from(&(Matrix3::identity() * h));
    a
}

/// The state after interval `x`.
pub(super) fn forward(s: &State, x: &Interval, linear: Linear) -> State {
    let Parts { e, jr, alpha, .. } = parts(x);
    let h = x.h;
    let ra = s.r * alpha;
    let mut next = State {
        r: s.r * e,
        v: s.v + ra * h,
        p: s.p + s.v * h + ra * (0.5 * h * h),
        ..*s
    };
    if !(linear.cov || linear.jac) {
        return next;
    }
    let a = transition(&e, &(s.r * hat(&alpha)), h);
    if linear.cov {
        let mut cov = a * s.cov * a.transpose();
        let mut tt = cov.fixed_view_mut::<3, 3>(0, 0);
        tt += jr * x.cov_g * jr.transpose() * (h * h);
        let q = s.r * x.cov_a * s.r.transpose();
        for (i, j, f) in [
            (1, 1, h * h),
            (1, 2, 0.5 * h * h * h),
            (2, 1, 0.5 * h * h * h),
            (2, 2, 0.25 * h.powi(4)),
        ] {
            let mut block = cov.fixed_view_mut::<3, 3>(3 * i, 3 * j);
            block += q * f;
        }
        next.cov = cov;
    }
    if linear.jac {
        let mut jac = a * s.jac;
        let mut tg = jac.fixed_view_mut::<3, 3>(0, 0);
        tg -= jr * h;
        let mut va = jac.fixed_view_mut::<3, 3>(3, 3);
        va -= s.r * h;
        let mut pa = jac.fixed_view_mut::<3, 3>(6, 3);
        pa -= s.r * (0.5 * h * h);
        next.jac = jac;
    }
    next
}

fn block(m: &Mat9, i: usize, j: usize) -> Matrix3<f64> {
    m.fixed_view::<3, 3>(3 * i, 3 * j).into_owned()
}

/// The cotangents before interval `x` (state `s`) and of its inputs, given `bar`, those after it.
pub(super) fn reverse(s: &State, x: &Interval, bar: &State, linear: Linear) -> (State, IntervalBar) {
    let Parts { phi, e, jr, alpha } = parts(x);
    let h = x.h;
    let ra = s.r * alpha;
    let mut r_bar = bar.r * e.transpose();
    let mut e_bar = s.r.transpose() * bar.r;
    let mut jr_bar = Matrix3::zeros();
    let mut a_bar = Mat9::zeros();
    let mut h_bar = 0.0;
    let mut prev = State {
        r: Matrix3::zeros(),
        v: bar.v + bar.p * h,
        p: bar.p,
        cov: Mat9::zeros(),
        jac: Mat96::zeros(),
    };
    let mut out = IntervalBar {
        h: 0.0,
        w: Vector3::zeros(),
        a: Vector3::zeros(),
        a_end: Vector3::zeros(),
        cov_g: Matrix3::zeros(),
        cov_a: Matrix3::zeros(),
    };
    let m = s.r * hat(&alpha);
    let a = transition(&e, &m, h);
    if linear.cov {
        let pb = &bar.cov;
        prev.cov = a.transpose() * pb * a;
        a_bar += pb * a * s.cov.transpose() + pb.transpose() * a * s.cov;
        // θθ += h² J_r Σ_g J_rᵀ.
        let tt = block(pb, 0, 0);
        let g = jr * x.cov_g * jr.transpose();
        jr_bar += (tt * jr * x.cov_g.transpose() + tt.transpose() * jr * x.cov_g) * (h * h);
        out.cov_g = jr.transpose() * tt * jr * (h * h);
        h_bar += 2.0 * h * tt.dot(&g);
        // vv, vp, pv, pp += (h², ½h³, ½h³, ¼h⁴) ΔR Σ_a ΔRᵀ.
        let q = s.r * x.cov_a * s.r.transpose();
        let (vv, cross, pp) = (block(pb, 1, 1), block(pb, 1, 2) + block(pb, 2, 1), block(pb, 2, 2));
        let q_bar = vv * (h * h) + cross * (0.5 * h * h * h) + pp * (0.25 * h.powi(4));
        h_bar += 2.0 * h * vv.dot(&q) + 1.5 * h * h * cross.dot(&q) + h.powi(3) * pp.dot(&q);
        r_bar += q_bar * s.r * x.cov_a.transpose() + q_bar.transpose() * s.r * x.cov_a;
        out.cov_a = s.r.transpose() * q_bar * s.r;
    }
    if linear.jac {
        let jb = &bar.jac;
        prev.jac = a.transpose() * jb;
        a_bar += jb * s.jac.transpose();
        // G = −[[hJ_r, 0], [0, hΔR], [0, ½h²ΔR]].
        let tg = jb.fixed_view::<3, 3>(0, 0).into_owned();
        let (va, pa) = (
            jb.fixed_view::<3, 3>(3, 3).into_owned(),
            jb.fixed_view::<3, 3>(6, 3).into_owned(),
        );
        jr_bar -= tg * h;
        h_bar -= tg.dot(&jr) + va.dot(&s.r) + h * pa.dot(&s.r);
        r_bar -= va * h + pa * (0.5 * h * h);
    }
    let mut alpha_bar = Vector3::zeros();
    if linear.cov || linear.jac {
        e_bar += block(&a_bar, 0, 0).transpose();
        let (a10, a20) = (block(&a_bar, 1, 0), block(&a_bar, 2, 0));
        let m_bar = a10 * -h + a20 * (-0.5 * h * h);
        h_bar += -a10.dot(&m) - h * a20.dot(&m) + block(&a_bar, 2, 1).trace();
        // M = ΔR[α]×.
        r_bar += m_bar * hat(&alpha).transpose();
        alpha_bar += vee2(&(s.r.transpose() * m_bar));
    }
    // Deltas: ΔR α enters Δv with h and Δp with ½h².
    let ra_bar = bar.v * h + bar.p * (0.5 * h * h);
    r_bar += ra_bar * alpha.transpose();
    alpha_bar += s.r.transpose() * ra_bar;
    h_bar += bar.v.dot(&ra) + bar.p.dot(&s.v) + h * bar.p.dot(&ra);
    match x.a_end {
        Some(a1) => {
            out.a = alpha_bar * 0.5;
            out.a_end = e.transpose() * alpha_bar * 0.5;
            e_bar += alpha_bar * a1.transpose() * 0.5;
        }
        None => out.a = alpha_bar,
    }
    let phi_bar = exp_and_jacobian_pullback(&phi, &e_bar, &jr_bar);
    out.w = phi_bar * h;
    out.h = h_bar + x.w.dot(&phi_bar);
    prev.r = r_bar;
    (prev, out)
}
