//! One preintegration interval, forward and reversed (its vector–Jacobian product).
//!
//! Deltas, Forster, Carlone, Dellaert & Scaramuzza, "On-Manifold Preintegration for Real-Time
//! Visual-Inertial Odometry", T-RO 2017, eqs. 24–26, with the interval's rate `ω`, step `h`:
//! `ΔR' = ΔR E`, `Δv' = Δv + ΔR α h`, `Δp' = Δp + Δv h + ½ ΔR α h²`, `E = Exp(ωh)`, `α` the
//! specific force (midpoint: `½(a₀ + E a₁)` from the interval's two samples, as
//! `preint/midpoint.rs`).
//!
//! Linear parts, both schemes in one form (`python/imukit/torch/_steps.py` writes out the blocks):
//! `A = [[Eᵀ, 0, 0], [hM, I, 0], [½h²M, hI, I]]` and the noise inputs `B₀` (the interval's start
//! sample) and `B₁` (its end sample): euler `M = −ΔR[α]×`, `B₀ = 0`,
//! `B₁ = −[[hJ_r, 0], [0, hΔR], [0, ½h²ΔR]]` (Forster eqs. 62–63, App. B); midpoint
//! `M = −½(R₀[a₀]× + R₁[a₁]×Eᵀ)`, `B_s = [[−½hJ_r, 0], [hK, −½hR_s], [½h²K, −¼h²R_s]]`,
//! `K = ¼h R₁[a₁]× J_r`, `R₀ = ΔR`, `R₁ = ΔR E`. A sample's noise enters both intervals it
//! bounds, so the state carries `X = Cov(δx, n_last)` and `S = Σ_last`:
//! `P' = APAᵀ + AXB₀ᵀ + B₀XᵀAᵀ + B₀SB₀ᵀ + B₁ΣB₁ᵀ`, `X' = B₁Σ`, `S' = Σ` (Σ the end sample's noise
//! covariance, block-diagonal `[Σ_g, Σ_a]`), and the bias Jacobian `J' = AJ + B₀ + B₁`.
//!
//! Reverse: for a scalar loss with cotangents `(ΔR̄', Δv̄', Δp̄', P̄', J̄', X̄', S̄')` after the step,
//! the chain rule through each line above gives those before it and of the inputs, e.g.
//! `P̄ = AᵀP̄'A`, `Ā += P̄'APᵀ + P̄'ᵀAP + UB₀Xᵀ + J̄'Jᵀ` (`U = P̄' + P̄'ᵀ`), `X̄ = AᵀUB₀`,
//! `S̄ = B₀ᵀP̄'B₀`, `J̄ = AᵀJ̄'`, `Σ̄ = B₁ᵀP̄'B₁ + B₁ᵀX̄' + S̄'`; `Ā`, `B̄_s` then reach `ΔR`, `E`,
//! `J_r`, the specific forces and `h` through their blocks, and `E`, `J_r` reach `ω` and `h`
//! through `φ = ωh` (`so3.rs`). With symmetric noise (densities) `P` is symmetric, so
//! `P̄'APᵀ + P̄'ᵀAP = UAP`, `B̄₁ = UB₁Σ` and `Σ̄`'s symmetric part is `½B₁ᵀUB₁`: one product each
//! instead of two; and since only `P̄`'s symmetric part then reaches any input, `P̄ = ½AᵀUA`
//! reuses `UA`. Euler's `B₁` is block-diagonal by row groups (`θ` ← gyro, `v, p` ← accel) and
//! `Σ` block-diagonal, so `B₁ΣB₁ᵀ`, `B̄₁` and `Σ̄` take only `P`'s and `P̄`'s diagonal blocks.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::so3::{exp_and_jacobian_pullback, vee2};
use crate::so3::{exp, hat, right_jacobian};

/// 9×9 `[δθ, δv, δp]`.
pub(super) type Mat9 = SMatrix<f64, 9, 9>;
/// 9×6: rows `[θ, v, p]`, columns `[gyro, accel]`.
pub(super) type Mat96 = SMatrix<f64, 9, 6>;
/// 6×6 `[gyro, accel]`.
pub(super) type Mat6 = SMatrix<f64, 6, 6>;

/// The preintegration after some intervals (or a cotangent of it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct State {
    pub r: Matrix3<f64>,
    pub v: Vector3<f64>,
    pub p: Vector3<f64>,
    pub cov: Mat9,
    pub jac: Mat96,
    /// `Cov(δx, n_last)`, the midpoint scheme's correlation with the last sample's noise.
    pub cross: Mat96,
    /// `Σ_last`.
    pub last: Mat6,
}

impl State {
    /// The empty preintegration.
    pub fn start() -> State {
        State {
            r: Matrix3::identity(),
            ..Self::zero()
        }
    }

    /// The zero cotangent.
    pub fn zero() -> State {
        State {
            r: Matrix3::zeros(),
            v: Vector3::zeros(),
            p: Vector3::zeros(),
            cov: Mat9::zeros(),
            jac: Mat96::zeros(),
            cross: Mat96::zeros(),
            last: Mat6::zeros(),
        }
    }
}

/// What [`reverse`] reads of the state before its interval: `ΔR`, `Δv` and, of the linear parts,
/// only what the cotangents of `A`'s variable blocks and of `B₀` need (a window's backward keeps
/// one per interval, `mod.rs`'s tape, so it stays small). Parts a call does not carry are zero.
#[derive(Debug, Clone, Copy)]
pub(super) struct Before {
    pub r: Matrix3<f64>,
    pub v: Vector3<f64>,
    /// `P`'s first six columns.
    pub cov_cols: Mat96,
    /// `P`'s first six rows, transposed (non-symmetric noise only).
    pub cov_rows: Mat96,
    /// `J`'s first six rows.
    pub jac: Mat6,
    /// Midpoint: `X` and `S`.
    pub cross: Mat96,
    pub last: Mat6,
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
    /// The noise covariances are symmetric (from densities), hence every `P`: the reverse sweep
    /// folds `P̄'` and `P̄'ᵀ` into `U = P̄' + P̄'ᵀ` and returns `Σ̄`'s symmetric part.
    pub symmetric: bool,
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

/// `A`, `B₀`, `B₁` of an interval (module docs); `b0` is None for euler. `A` is kept as its
/// two non-trivial blocks `E` and `hM`: products with it skip its identity and zero blocks.
struct Lin {
    m: Matrix3<f64>,
    e: Matrix3<f64>,
    hm: Matrix3<f64>,
    h: f64,
    b0: Option<Mat96>,
    b1: Mat96,
}

impl Lin {
    /// `A X`, with `A = [[Eᵀ, 0, 0], [hM, I, 0], [½h²M, hI, I]]`.
    fn a_mul<const C: usize>(&self, x: &SMatrix<f64, 9, C>) -> SMatrix<f64, 9, C> {
        let (x0, x1, x2) = (x.fixed_rows::<3>(0), x.fixed_rows::<3>(3), x.fixed_rows::<3>(6));
        let mx = self.hm * x0;
        let mut y = SMatrix::<f64, 9, C>::zeros();
        y.fixed_rows_mut::<3>(0).copy_from(&self.e.tr_mul(&x0));
        y.fixed_rows_mut::<3>(3).copy_from(&(mx + x1));
        y.fixed_rows_mut::<3>(6)
            .copy_from(&(mx * (0.5 * self.h) + x1 * self.h + x2));
        y
    }

    /// `Aᵀ X`.
    fn at_mul<const C: usize>(&self, x: &SMatrix<f64, 9, C>) -> SMatrix<f64, 9, C> {
        let (x0, x1, x2) = (x.fixed_rows::<3>(0), x.fixed_rows::<3>(3), x.fixed_rows::<3>(6));
        let mut y = SMatrix::<f64, 9, C>::zeros();
        y.fixed_rows_mut::<3>(0)
            .copy_from(&(self.e * x0 + self.hm.tr_mul(&(x1 + x2 * (0.5 * self.h)))));
        y.fixed_rows_mut::<3>(3).copy_from(&(x1 + x2 * self.h));
        y.fixed_rows_mut::<3>(6).copy_from(&x2);
        y
    }

    /// `A X Aᵀ`.
    fn sandwich(&self, x: &Mat9) -> Mat9 {
        self.a_mul(&self.a_mul(x).transpose()).transpose()
    }

    /// `Aᵀ X A`.
    fn sandwich_t(&self, x: &Mat9) -> Mat9 {
        self.at_mul(&self.at_mul(&x.transpose()).transpose())
    }
}

fn put(m: &mut Mat96, i: usize, j: usize, b: &Matrix3<f64>) {
    m.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(b);
}

/// `m[i.., j..] += b`.
fn add_block<const R: usize, const C: usize, const RM: usize, const CM: usize>(
    m: &mut SMatrix<f64, RM, CM>,
    i: usize,
    j: usize,
    b: &SMatrix<f64, R, C>,
) {
    let mut v = m.fixed_view_mut::<R, C>(i, j);
    v += b;
}

fn sub96(m: &Mat96, i: usize, j: usize) -> Matrix3<f64> {
    m.fixed_view::<3, 3>(3 * i, 3 * j).into_owned()
}

/// `K = ¼h R₁[a₁]× J_r` of the midpoint scheme.
fn midpoint_k(r1: &Matrix3<f64>, a1: &Vector3<f64>, jr: &Matrix3<f64>, h: f64) -> Matrix3<f64> {
    r1 * hat(a1) * jr * (0.25 * h)
}

/// The midpoint `B_s` for the sample frame `r` (module docs).
fn midpoint_input(jr: &Matrix3<f64>, k: &Matrix3<f64>, r: &Matrix3<f64>, h: f64) -> Mat96 {
    let mut b = Mat96::zeros();
    put(&mut b, 0, 0, &(jr * (-0.5 * h)));
    put(&mut b, 1, 0, &(k * h));
    put(&mut b, 2, 0, &(k * (0.5 * h * h)));
    put(&mut b, 1, 1, &(r * (-0.5 * h)));
    put(&mut b, 2, 1, &(r * (-0.25 * h * h)));
    b
}

fn linearize(r0: &Matrix3<f64>, x: &Interval, p: &Parts) -> Lin {
    let h = x.h;
    let (m, b0, b1) = match x.a_end {
        None => {
            let mut b1 = Mat96::zeros();
            put(&mut b1, 0, 0, &(p.jr * -h));
            put(&mut b1, 1, 1, &(r0 * -h));
            put(&mut b1, 2, 1, &(r0 * (-0.5 * h * h)));
            (-(r0 * hat(&p.alpha)), None, b1)
        }
        Some(a1) => {
            let r1 = r0 * p.e;
            let k = midpoint_k(&r1, &a1, &p.jr, h);
            let m = (r0 * hat(&x.a) + r1 * hat(&a1) * p.e.transpose()) * -0.5;
            (
                m,
                Some(midpoint_input(&p.jr, &k, r0, h)),
                midpoint_input(&p.jr, &k, &r1, h),
            )
        }
    };
    Lin {
        m,
        e: p.e,
        hm: m * h,
        h,
        b0,
        b1,
    }
}

/// Euler's `B₁` by row groups, `diag(B_θ, B_vp)`: `B_θ = −hJ_r` (gyro → θ, 3×3) and
/// `B_vp = −h[R₀; ½hR₀]` (accel → v, p, 6×3); its other blocks are zero.
fn euler_blocks(b1: &Mat96) -> (Matrix3<f64>, SMatrix<f64, 6, 3>) {
    (
        b1.fixed_view::<3, 3>(0, 0).into_owned(),
        b1.fixed_view::<6, 3>(3, 3).into_owned(),
    )
}

/// The cotangents of one diagonal block `B` of a block-diagonal `B₁` and of its noise `Σ`, from
/// `P̄`'s matching diagonal block: `B̄ = P̄BΣᵀ + P̄ᵀBΣ`, `Σ̄ = BᵀP̄B` (symmetric: `UBΣ` and
/// `½BᵀUB`, `U = P̄ + P̄ᵀ`, module docs).
fn noise_input_reverse<const R: usize>(
    pb: &SMatrix<f64, R, R>,
    b: &SMatrix<f64, R, 3>,
    q: &Matrix3<f64>,
    symmetric: bool,
) -> (SMatrix<f64, R, 3>, Matrix3<f64>) {
    if symmetric {
        let ub = (pb + pb.transpose()) * b;
        (ub * q, b.tr_mul(&ub) * 0.5)
    } else {
        let (pbb, pbtb) = (pb * b, pb.tr_mul(b));
        (pbb * q.transpose() + pbtb * q, b.tr_mul(&pbb))
    }
}

fn noise(x: &Interval) -> Mat6 {
    let mut q = Mat6::zeros();
    q.fixed_view_mut::<3, 3>(0, 0).copy_from(&x.cov_g);
    q.fixed_view_mut::<3, 3>(3, 3).copy_from(&x.cov_a);
    q
}

/// The state after interval `x`.
pub(super) fn forward(s: &State, x: &Interval, linear: Linear) -> State {
    let p = parts(x);
    let h = x.h;
    let ra = s.r * p.alpha;
    let mut next = State {
        r: s.r * p.e,
        v: s.v + ra * h,
        p: s.p + s.v * h + ra * (0.5 * h * h),
        ..*s
    };
    if !(linear.cov || linear.jac) {
        return next;
    }
    let l = linearize(&s.r, x, &p);
    if linear.cov {
        let q = noise(x);
        let mut cov = l.sandwich(&s.cov);
        match &l.b0 {
            None => {
                // Euler's B₁ is block-diagonal (module docs): B₁ΣB₁ᵀ = diag(B_θΣ_gB_θᵀ, B_vpΣ_aB_vpᵀ).
                let (th, vp) = euler_blocks(&l.b1);
                add_block(&mut cov, 0, 0, &(th * x.cov_g * th.transpose()));
                add_block(&mut cov, 3, 3, &(vp * x.cov_a * vp.transpose()));
            }
            Some(_) => cov += l.b1 * q * l.b1.transpose(),
        }
        if let Some(b0) = &l.b0 {
            let axb = l.a_mul(&s.cross) * b0.transpose();
            cov += axb + axb.transpose() + b0 * s.last * b0.transpose();
            next.cross = l.b1 * q;
            next.last = q;
        }
        next.cov = cov;
    }
    if linear.jac {
        next.jac = l.a_mul(&s.jac) + l.b1 + l.b0.unwrap_or_else(Mat96::zeros);
    }
    next
}

/// Cotangents of `A` (its first six columns, where its variable blocks are; only those blocks
/// [`linearization_reverse`] reads are filled, [`add_a_bar`]), `B₀`, `B₁`.
struct LinBar {
    a: Mat96,
    b0: Mat96,
    b1: Mat96,
}

/// Adds the cotangents of `R₀`, `E`, `J_r`, the specific forces and `h` that `A`, `B₀`, `B₁`
/// carry (module docs) to `acc`.
fn linearization_reverse(r0: &Matrix3<f64>, x: &Interval, p: &Parts, l: &Lin, bar: &LinBar, acc: &mut Reverse) {
    let h = x.h;
    let ab = &bar.a;
    acc.e += sub96(ab, 0, 0).transpose();
    let (a10, a20) = (sub96(ab, 1, 0), sub96(ab, 2, 0));
    let m_bar = a10 * h + a20 * (0.5 * h * h);
    acc.h += a10.dot(&l.m) + h * a20.dot(&l.m) + sub96(ab, 2, 1).trace();
    match x.a_end {
        None => {
            // M = −R₀[α]×; B₁ blocks −hJ_r, −hR₀, −½h²R₀.
            acc.r += m_bar * hat(&p.alpha);
            acc.alpha -= vee2(&(r0.transpose() * m_bar));
            let (tg, va, pa) = (sub96(&bar.b1, 0, 0), sub96(&bar.b1, 1, 1), sub96(&bar.b1, 2, 1));
            acc.jr -= tg * h;
            acc.r -= va * h + pa * (0.5 * h * h);
            acc.h -= tg.dot(&p.jr) + va.dot(r0) + h * pa.dot(r0);
        }
        Some(a1) => {
            let r1 = r0 * p.e;
            let (k0, k1) = (hat(&x.a), hat(&a1));
            let mut r1_bar = Matrix3::zeros();
            // M = −½(R₀[a₀]× + R₁[a₁]×Eᵀ).
            let n_bar = m_bar * -0.5;
            acc.r += n_bar * k0.transpose();
            acc.a0 += vee2(&(r0.transpose() * n_bar));
            r1_bar += n_bar * p.e * k1.transpose();
            acc.a1 += vee2(&(r1.transpose() * n_bar * p.e));
            acc.e += n_bar.transpose() * r1 * k1;
            // B_s: θg −½hJ_r, vg hK, pg ½h²K, va −½hR_s, pa −¼h²R_s.
            let k = midpoint_k(&r1, &a1, &p.jr, h);
            let mut k_bar = Matrix3::zeros();
            for (b, r_s, is_end) in [(&bar.b0, r0, false), (&bar.b1, &r1, true)] {
                let (tg, vg, pg) = (sub96(b, 0, 0), sub96(b, 1, 0), sub96(b, 2, 0));
                let (va, pa) = (sub96(b, 1, 1), sub96(b, 2, 1));
                acc.jr -= tg * (0.5 * h);
                k_bar += vg * h + pg * (0.5 * h * h);
                let rs_bar = va * (-0.5 * h) + pa * (-0.25 * h * h);
                if is_end {
                    r1_bar += rs_bar;
                } else {
                    acc.r += rs_bar;
                }
                acc.h += -0.5 * tg.dot(&p.jr) + vg.dot(&k) + h * pg.dot(&k) - 0.5 * va.dot(r_s) - 0.5 * h * pa.dot(r_s);
            }
            // K = ¼h L, L = R₁[a₁]×J_r.
            let l_mat = r1 * k1 * p.jr;
            acc.h += 0.25 * k_bar.dot(&l_mat);
            let l_bar = k_bar * (0.25 * h);
            r1_bar += l_bar * (k1 * p.jr).transpose();
            acc.jr += (r1 * k1).transpose() * l_bar;
            acc.a1 += vee2(&(r1.transpose() * l_bar * p.jr.transpose()));
            // R₁ = R₀E.
            acc.r += r1_bar * p.e.transpose();
            acc.e += r0.transpose() * r1_bar;
        }
    }
}

/// `Ā += X Y` on the blocks of `Ā` that [`linearization_reverse`] reads: the first block column
/// (`E`, `hM`, `½h²M`) and the `(p, v)` block `hI` (its trace).
fn add_a_bar<const C: usize>(a: &mut Mat96, x: &SMatrix<f64, 9, C>, y: &SMatrix<f64, C, 6>) {
    let mut first = a.fixed_columns_mut::<3>(0);
    first += x * y.fixed_columns::<3>(0);
    let mut pv = a.fixed_view_mut::<3, 3>(6, 3);
    pv += x.fixed_rows::<3>(6) * y.fixed_columns::<3>(3);
}

/// Cotangents gathered while reversing one interval.
struct Reverse {
    r: Matrix3<f64>,
    e: Matrix3<f64>,
    jr: Matrix3<f64>,
    alpha: Vector3<f64>,
    a0: Vector3<f64>,
    a1: Vector3<f64>,
    h: f64,
}

/// The cotangents before interval `x` (state `s`) and of its inputs, given `bar`, those after it.
pub(super) fn reverse(s: &Before, x: &Interval, bar: &State, linear: Linear) -> (State, IntervalBar) {
    let p = parts(x);
    let h = x.h;
    let ra = s.r * p.alpha;
    let mut acc = Reverse {
        r: bar.r * p.e.transpose(),
        e: s.r.transpose() * bar.r,
        jr: Matrix3::zeros(),
        alpha: Vector3::zeros(),
        a0: Vector3::zeros(),
        a1: Vector3::zeros(),
        h: 0.0,
    };
    let mut prev = State {
        v: bar.v + bar.p * h,
        p: bar.p,
        ..State::zero()
    };
    let mut q_bar = Mat6::zeros();
    if linear.cov || linear.jac {
        let l = linearize(&s.r, x, &p);
        let mut lb = LinBar {
            a: Mat96::zeros(),
            b0: Mat96::zeros(),
            b1: Mat96::zeros(),
        };
        if linear.cov {
            let (pb, q) = (&bar.cov, noise(x));
            let u = pb + pb.transpose();
            // U is symmetric: UA = (AᵀU)ᵀ.
            let ua = l.at_mul(&u).transpose();
            // Symmetric noise: every P is symmetric, so only P̄'s symmetric part ½U reaches the
            // inputs, and P̄ = ½AᵀUA reuses UA (module docs).
            prev.cov = match linear.symmetric {
                true => l.at_mul(&ua) * 0.5,
                false => l.sandwich_t(pb),
            };
            if linear.symmetric {
                // P = Pᵀ, Σ = Σᵀ: P̄'APᵀ + P̄'ᵀAP = UAP, P̄'B₁Σᵀ + P̄'ᵀB₁Σ = UB₁Σ, and the
                // symmetric part of B₁ᵀP̄'B₁ is ½B₁ᵀUB₁.
                add_a_bar(&mut lb.a, &ua, &s.cov_cols);
            } else {
                // P̄'APᵀ + P̄'ᵀAP, first six columns.
                let (pba, pbta) = (l.at_mul(&pb.transpose()).transpose(), l.at_mul(pb).transpose());
                add_a_bar(&mut lb.a, &pba, &s.cov_rows);
                add_a_bar(&mut lb.a, &pbta, &s.cov_cols);
            }
            match &l.b0 {
                None => {
                    // Euler: only B₁'s diagonal blocks and Σ̄'s are read, and they see only P̄'s
                    // diagonal blocks (P̄_θθ, P̄_vp,vp).
                    let (th, vp) = euler_blocks(&l.b1);
                    let (tg, qg) = noise_input_reverse(
                        &pb.fixed_view::<3, 3>(0, 0).into_owned(),
                        &th,
                        &x.cov_g,
                        linear.symmetric,
                    );
                    let (ta, qa) = noise_input_reverse(
                        &pb.fixed_view::<6, 6>(3, 3).into_owned(),
                        &vp,
                        &x.cov_a,
                        linear.symmetric,
                    );
                    add_block(&mut lb.b1, 0, 0, &tg);
                    add_block(&mut lb.b1, 3, 3, &ta);
                    add_block(&mut q_bar, 0, 0, &qg);
                    add_block(&mut q_bar, 3, 3, &qa);
                }
                Some(_) if linear.symmetric => {
                    let ub1 = u * l.b1;
                    lb.b1 += ub1 * q;
                    q_bar += l.b1.tr_mul(&ub1) * 0.5;
                }
                Some(_) => {
                    lb.b1 += pb * l.b1 * q.transpose() + pb.transpose() * l.b1 * q;
                    q_bar += l.b1.transpose() * pb * l.b1;
                }
            }
            if let Some(b0) = &l.b0 {
                let ub0 = u * b0;
                add_a_bar(&mut lb.a, &ub0, &s.cross.fixed_rows::<6>(0).transpose());
                prev.cross = l.at_mul(&ub0);
                lb.b0 += ua * s.cross
                    + match linear.symmetric {
                        true => ub0 * s.last,
                        false => pb * b0 * s.last.transpose() + pb.transpose() * b0 * s.last,
                    };
                prev.last = b0.transpose() * pb * b0;
                // X' = B₁Σ, S' = Σ.
                lb.b1 += bar.cross * q.transpose();
                q_bar += l.b1.transpose() * bar.cross + bar.last;
            }
        }
        if linear.jac {
            prev.jac = l.at_mul(&bar.jac);
            add_a_bar(&mut lb.a, &bar.jac, &s.jac.transpose());
            lb.b1 += bar.jac;
            lb.b0 += bar.jac;
        }
        linearization_reverse(&s.r, x, &p, &l, &lb, &mut acc);
    }
    // Deltas: ΔR α enters Δv with h and Δp with ½h².
    let ra_bar = bar.v * h + bar.p * (0.5 * h * h);
    acc.r += ra_bar * p.alpha.transpose();
    acc.alpha += s.r.transpose() * ra_bar;
    acc.h += bar.v.dot(&ra) + bar.p.dot(&s.v) + h * bar.p.dot(&ra);
    let (a, a_end) = match x.a_end {
        Some(a1) => {
            acc.e += acc.alpha * a1.transpose() * 0.5;
            (acc.a0 + acc.alpha * 0.5, acc.a1 + p.e.transpose() * acc.alpha * 0.5)
        }
        None => (acc.alpha, Vector3::zeros()),
    };
    let phi_bar = exp_and_jacobian_pullback(&p.phi, &acc.e, &acc.jr);
    prev.r = acc.r;
    let out = IntervalBar {
        h: acc.h + x.w.dot(&phi_bar),
        w: phi_bar * h,
        a,
        a_end,
        cov_g: q_bar.fixed_view::<3, 3>(0, 0).into_owned(),
        cov_a: q_bar.fixed_view::<3, 3>(3, 3).into_owned(),
    };
    (prev, out)
}
