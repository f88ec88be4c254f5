//! Structure-of-arrays preintegration: four windows in lockstep, one window per SIMD lane.
//!
//! The per-window kernel (`Preintegrator::integrate_euler` / `integrate_midpoint`) is a chain of dependent 3×3 products,
//! so one window leaves most of a vector register idle. Here every scalar of the state (ΔR, Δv,
//! Δp, Δt, the six covariance blocks, the five non-zero bias-Jacobian blocks) holds four values,
//! one per window, and every operation acts on the four at once:
//!
//! | path | lanes | one lane operation | `a·s + c` |
//! |---|---|---|---|
//! | `avx512`, `avx2` | [`P4`] (a `pulp` AVX2+FMA token and a 256-bit vector) | one 256-bit instruction | one fused multiply-add |
//! | `baseline` | none: the per-window kernel | | |
//!
//! Each element is computed with the same operations in the same order as the per-window kernel
//! (`preint/mod.rs`, `integrate_euler`, `BiasWalk::step`; `preint/midpoint.rs`;
//! `preint/blocks.rs`; `mat3.rs`), fused where that kernel fuses on the same path
//! (`mat3::Fused::scale_add`, the `Lanes` products, never the plain `Matrix3` ones): a lane is the
//! per-window kernel of its path bit for bit (tested on every path). The coefficients of `Exp(ω̂h)`
//! and `J_r(ω̂h)` (branches on θ) and the projection of ΔR every `PROJECT_EVERY` intervals are
//! computed per lane by the per-window functions themselves.
//!
//! What the lanes run: both schemes (`midpoint.rs` for the midpoint step) with the 9×9
//! covariance, the 9×6 bias Jacobian and, with `combined`, the bias walk (`walk.rs`), on windows
//! with no flagged (clipped) sample; `windows.rs` sends those to the per-window kernel. A bundle
//! runs in lockstep for the intervals all its windows have; each window then finishes alone on the
//! per-window kernel (the caller groups windows of near-equal length, so that tail is short).

use std::ops::{Add, Mul, Neg, Sub};

use nalgebra::{Matrix3, Vector3};

use super::blocks::Cross;
use super::windows::Span;
use super::{project_rotation, Clipped, Preintegrator, Scheme, PROJECT_EVERY};
use crate::imu::Samples;
use crate::lie::series;
use crate::mat3::{Col, M3};
use crate::simd::{self, Path};
use midpoint::Mid;
use walk::Walk;

mod midpoint;
mod walk;

/// Windows per bundle.
pub(super) const WIDTH: usize = super::windows::BUNDLE;

/// Four f64 values, one per window: element-wise arithmetic. New values come from an existing one
/// (`like`), which carries what the type needs to exist (the AVX token of [`P4`]).
pub(super) trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// Lane `i` is `f(i)`.
    fn like(self, f: impl FnMut(usize) -> f64) -> Self;
    /// Lane `i`.
    fn lane(&self, i: usize) -> f64;
    /// `self s + acc`, fused as `mat3::Lanes::scale_add` is on this path.
    fn scale_add(self, s: Self, acc: Self) -> Self;
    /// `x` in every lane.
    #[inline(always)]
    fn splat(self, x: f64) -> Self {
        self.like(|_| x)
    }
}

/// The AVX lanes: one 256-bit register, `a s + c` one fused multiply-add. The token proves the CPU
/// has AVX2 and FMA, so a `P4` exists only where its instructions run.
#[derive(Debug, Clone, Copy)]
pub(super) struct P4(pulp::x86::V3, pulp::f64x4);

impl P4 {
    /// Zero lanes, where the CPU has AVX2 and FMA.
    fn try_new() -> Option<P4> {
        pulp::x86::V3::try_new().map(|t| P4(t, t.splat_f64x4(0.0)))
    }
}

/// The lanes of this process's path: [`P4`] on the AVX paths (`crate::simd`), none on the
/// baseline, which keeps the per-window kernel (measured: lanes of plain `[f64; 4]` arrays, which
/// LLVM leaves scalar, ran at half its speed; `docs/performance.md`).
pub(super) fn lanes() -> Option<P4> {
    if simd::path() == Path::Baseline {
        None
    } else {
        P4::try_new()
    }
}

/// The element-wise binary operators of [`P4`].
macro_rules! p4_op {
    ($($trait:ident $method:ident $simd:ident),*) => {$(
        impl $trait for P4 {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                P4(self.0, self.0.$simd(self.1, o.1))
            }
        }
    )*};
}
p4_op!(Add add add_f64x4, Sub sub sub_f64x4, Mul mul mul_f64x4);

impl Neg for P4 {
    type Output = Self;
    /// `(−1) x`: exact, and the sign of a zero flips as with `−x`.
    #[inline(always)]
    fn neg(self) -> Self {
        P4(self.0, self.0.mul_f64x4(self.1, self.0.splat_f64x4(-1.0)))
    }
}

impl Lanes for P4 {
    #[inline(always)]
    fn like(self, mut f: impl FnMut(usize) -> f64) -> Self {
        P4(self.0, pulp::f64x4(f(0), f(1), f(2), f(3)))
    }
    #[inline(always)]
    fn lane(&self, i: usize) -> f64 {
        let v = self.1;
        [v.0, v.1, v.2, v.3][i]
    }
    #[inline(always)]
    fn scale_add(self, s: Self, acc: Self) -> Self {
        P4(self.0, self.0.mul_add_f64x4(self.1, s.1, acc.1))
    }
}

/// A 3×3 block of lanes, column-major (`e(r, c)` is `self.0[3c + r]`); each method computes its
/// elements as `mat3::M3`'s twin does.
#[derive(Debug, Clone, Copy)]
struct B<V>([V; 9]);

/// The block whose element `(r, c)` is `$e`, written out nine times with `r`, `c` constants: no
/// closure calls a lane operation, since a closure is compiled without the target features of the
/// dispatched copy it is inlined into, and the AVX lane operations would stay calls.
macro_rules! block {
    (|$r:ident, $c:ident| $e:expr) => {
        B([
            block!(@ $r $c 0 0 $e),
            block!(@ $r $c 1 0 $e),
            block!(@ $r $c 2 0 $e),
            block!(@ $r $c 0 1 $e),
            block!(@ $r $c 1 1 $e),
            block!(@ $r $c 2 1 $e),
            block!(@ $r $c 0 2 $e),
            block!(@ $r $c 1 2 $e),
            block!(@ $r $c 2 2 $e),
        ])
    };
    (@ $r:ident $c:ident $rv:literal $cv:literal $e:expr) => {{
        let ($r, $c): (usize, usize) = ($rv, $cv);
        $e
    }};
}

impl<V: Lanes> B<V> {
    #[inline(always)]
    fn e(&self, r: usize, c: usize) -> V {
        self.0[3 * c + r]
    }

    /// Lane `i` as a matrix.
    fn lane(&self, i: usize) -> Matrix3<f64> {
        Matrix3::from_fn(|r, c| self.e(r, c).lane(i))
    }

    /// The padded block `m` in every lane.
    fn splat(k: V, m: &M3) -> Self {
        block!(|r, c| k.splat(m.0[c].0[r]))
    }

    /// Lane `i` as a padded block.
    fn m3(&self, i: usize) -> M3 {
        M3(std::array::from_fn(|c| {
            Col([self.e(0, c).lane(i), self.e(1, c).lane(i), self.e(2, c).lane(i), 0.0])
        }))
    }

    /// `self a`, never fused (nalgebra's `Matrix3 * Vector3`: each row summed left to right).
    #[inline(always)]
    fn apply(&self, a: &[V; 3]) -> [V; 3] {
        let mut out = *a;
        for (i, x) in out.iter_mut().enumerate() {
            *x = self.e(i, 0) * a[0] + self.e(i, 1) * a[1] + self.e(i, 2) * a[2];
        }
        out
    }

    /// Lane `i` of element `(r, c)` is `m[i][(r, c)]`.
    #[inline(always)]
    fn of_lanes(k: V, m: &[Matrix3<f64>; WIDTH]) -> Self {
        block!(|r, c| k.like(|i| m[i][(r, c)]))
    }

    /// Element `(r, c)` of `self b`, fused as `M3::mul_with` (`Col::combine`: the first product,
    /// then two multiply-adds).
    #[inline(always)]
    fn dot(&self, r: usize, b: &Self, c: usize) -> V {
        let acc = self.e(r, 0) * b.e(0, c);
        self.e(r, 2)
            .scale_add(b.e(2, c), self.e(r, 1).scale_add(b.e(1, c), acc))
    }

    /// `self b` (`M3::mul_with`).
    #[inline(always)]
    fn mul(&self, b: &Self) -> Self {
        block!(|r, c| self.dot(r, b, c))
    }

    /// `self b`, never fused (`mat3::mul` on `Matrix3`).
    #[inline(always)]
    fn mul_plain(&self, b: &Self) -> Self {
        block!(|r, c| self.e(r, 0) * b.e(0, c) + self.e(r, 1) * b.e(1, c) + self.e(r, 2) * b.e(2, c))
    }

    /// `self b` for a `self` with a zero diagonal: each element's two nonzero terms, the second
    /// as a multiply-add on the first (`Unfused::zero_diagonal_mul`; on the fused path the dense
    /// product, whose zero terms add exact zeros, gives the same bits).
    #[inline(always)]
    fn zero_diagonal_mul(&self, b: &Self) -> Self {
        block!(|r, c| {
            let (j, k) = [(1, 2), (0, 2), (0, 1)][r];
            self.e(r, k).scale_add(b.e(k, c), self.e(r, j) * b.e(j, c))
        })
    }

    /// `self bᵀ` (`M3::mul_t_with`).
    #[inline(always)]
    fn mul_t(&self, b: &Self) -> Self {
        let bt = b.transpose();
        block!(|r, c| self.dot(r, &bt, c))
    }

    /// `self bᵀ` known to be symmetric: the upper triangle, mirrored (`M3::mul_t_symmetric_with`).
    #[inline(always)]
    fn mul_t_symmetric(&self, b: &Self) -> Self {
        let bt = b.transpose();
        let (xy, xz, yz) = (self.dot(0, &bt, 1), self.dot(0, &bt, 2), self.dot(1, &bt, 2));
        B([
            self.dot(0, &bt, 0),
            xy,
            xz,
            xy,
            self.dot(1, &bt, 1),
            yz,
            xz,
            yz,
            self.dot(2, &bt, 2),
        ])
    }

    #[inline(always)]
    fn transpose(&self) -> Self {
        block!(|r, c| self.e(c, r))
    }

    /// `self s + acc` (`M3::mul_add`).
    #[inline(always)]
    fn mul_add(&self, s: V, acc: &Self) -> Self {
        block!(|r, c| self.e(r, c).scale_add(s, acc.e(r, c)))
    }

    #[inline(always)]
    fn scale(&self, s: V) -> Self {
        block!(|r, c| self.e(r, c) * s)
    }

    #[inline(always)]
    fn add(&self, o: &Self) -> Self {
        block!(|r, c| self.e(r, c) + o.e(r, c))
    }

    #[inline(always)]
    fn neg(&self) -> Self {
        block!(|r, c| -self.e(r, c))
    }

    /// `self + s I`.
    #[inline(always)]
    fn plus_identity(mut self, s: V) -> Self {
        for i in 0..3 {
            self.0[4 * i] = self.0[4 * i] + s;
        }
        self
    }
}

/// The lockstep state: the per-window fields, one window per lane.
struct State<V> {
    rotation: B<V>,
    velocity: [V; 3],
    position: [V; 3],
    t: V,
    /// `[θθ, θv, θp, vv, vp, pp]` in frame i (`blocks.rs`).
    cov: [B<V>; 6],
    /// `[θg, vg, va, pg, pa]` (the θa block stays zero).
    jac: [B<V>; 5],
    /// The bias random walk, when tracked (`combined`).
    walk: Option<Walk<V>>,
}

/// `(Exp(φ), J_r(φ))` in every lane: `so3::exp_and_right_jacobian`'s elements, lane-wise, with its
/// coefficients from θ² computed per lane (the series below θ² = 1e-4, else a square root and
/// `sin`, `cos`: a branch per lane).
#[inline(always)]
fn exp_and_right_jacobian<V: Lanes>(k: V, phi: &[V; 3]) -> (B<V>, B<V>) {
    // A loop, not `array::from_fn`, which stayed an out-of-line call.
    let mut coef = [(0.0, 0.0, 0.0); WIDTH];
    for (i, c) in coef.iter_mut().enumerate() {
        let phi = Vector3::new(phi[0].lane(i), phi[1].lane(i), phi[2].lane(i));
        *c = series::exp_jacobian_small(phi.norm_squared());
    }
    let (a, b, c) = (k.like(|i| coef[i].0), k.like(|i| coef[i].1), k.like(|i| coef[i].2));
    let [x, y, z] = *phi;
    let (xy, xz, yz) = (x * y, x * z, y * z);
    let (d0, d1, d2) = (y * y + z * z, x * x + z * z, x * x + y * y);
    let one = k.splat(1.0);
    let exp = B([
        one - b * d0,
        b * xy + a * z,
        b * xz - a * y,
        b * xy - a * z,
        one - b * d1,
        b * yz + a * x,
        b * xz + a * y,
        b * yz - a * x,
        one - b * d2,
    ]);
    let jr = B([
        one - c * d0,
        c * xy - b * z,
        c * xz + b * y,
        c * xy + b * z,
        one - c * d1,
        c * yz - b * x,
        c * xz - b * y,
        c * yz + b * x,
        one - c * d2,
    ]);
    (exp, jr)
}

/// `A Σ Aᵀ` for the frame-i transition of `w`, `h`: `blocks::propagate_frame_i`, lane-wise.
#[inline(always)]
fn propagate<V: Lanes>(cov: &[B<V>; 6], w: &B<V>, h: V, half_h2: V) -> [B<V>; 6] {
    let [tt, tv, tp, vv, vp, pp] = cov;
    let h2 = h * h;
    let (w_tt, w_tv, w_tp) = (
        w.zero_diagonal_mul(tt),
        w.zero_diagonal_mul(tv),
        w.zero_diagonal_mul(tp),
    );
    let (w_tt_t, w_tv_t) = (w_tt.transpose(), w_tv.transpose());
    let w_tt_wt = w_tt.mul_t_symmetric(w);
    let sym_v = w_tv.add(&w_tv_t);
    let sym_p = w_tp.add(&w_tp.transpose());
    let sym_vp = vp.add(&vp.transpose());
    let new_vv = w_tt_wt.mul_add(h, &sym_v).mul_add(h, vv);
    let new_vp = w_tt_wt
        .mul_add(h, &w_tv_t)
        .mul_add(half_h2, &w_tv.mul_add(h2, &vv.mul_add(h, &w_tp.mul_add(h, vp))));
    let new_pp = w_tt_wt
        .mul_add(half_h2, &sym_v.mul_add(h, &sym_p))
        .mul_add(half_h2, &vv.mul_add(h2, &sym_vp.mul_add(h, pp)));
    [
        *tt,
        w_tt_t.mul_add(h, tv),
        w_tt_t.mul_add(half_h2, &tv.mul_add(h, tp)),
        new_vv,
        new_vp,
        new_pp,
    ]
}

/// `W` = `[−v]×` for the vector `v` (`so3::hat(&−v)`, zero diagonal).
#[inline(always)]
fn hat_neg<V: Lanes>(v: &[V; 3]) -> B<V> {
    let zero = v[0].splat(0.0);
    B([zero, -v[2], v[1], v[2], zero, -v[0], -v[1], v[0], zero])
}

/// `A X` for a 9×6 cross covariance `X = [θg, vg, va, pg, pa]` (its θa block zero):
/// `blocks::transition`, lane-wise.
#[inline(always)]
fn transition<V: Lanes>(x: &[B<V>; 5], w: &B<V>, h: V, half_h2: V) -> [B<V>; 5] {
    let [xtg, xvg, xva, xpg, xpa] = x;
    let w_tg = w.zero_diagonal_mul(xtg);
    [
        *xtg,
        w_tg.mul_add(h, xvg),
        *xva,
        xvg.mul_add(h, &w_tg.scale(half_h2)).add(xpg),
        xva.mul_add(h, xpa),
    ]
}

/// A step's 9×6 input `G = [[tg, 0], [vg, va], [h/2 vg, h/2 va]]` in lanes (`blocks::Input`).
#[derive(Debug, Clone, Copy)]
struct In<V> {
    tg: B<V>,
    vg: B<V>,
    va: B<V>,
    half_h: V,
}

impl<V: Lanes> In<V> {
    /// `x + G` (`Input::added_to`).
    #[inline(always)]
    fn added_to(&self, x: &[B<V>; 5]) -> [B<V>; 5] {
        [
            x[0].add(&self.tg),
            x[1].add(&self.vg),
            x[2].add(&self.va),
            self.vg.mul_add(self.half_h, &x[3]),
            self.va.mul_add(self.half_h, &x[4]),
        ]
    }
}

impl<V: Lanes> State<V> {
    /// Every lane at `p`'s state.
    fn of(k: V, p: &Preintegrator) -> Self {
        let block = |m: &M3| B::splat(k, m);
        let splat3 = |v: &Vector3<f64>| [k.splat(v.x), k.splat(v.y), k.splat(v.z)];
        let [[tg, _], [vg, va], [pg, pa]] = &p.jac;
        State {
            rotation: block!(|r, c| k.splat(p.delta_rotation[(r, c)])),
            velocity: splat3(&p.delta_velocity),
            position: splat3(&p.delta_position),
            t: k.splat(p.delta_t),
            cov: p.covariance.each_ref().map(block),
            jac: [tg, vg, va, pg, pa].map(block),
            walk: p.bias_walk.as_ref().map(|w| Walk::of(k, w)),
        }
    }

    /// Lane `i` written into `p` (a copy of the template the lanes started from).
    fn write_lane(&self, i: usize, p: &mut Preintegrator) {
        let vector = |v: &[V; 3]| Vector3::new(v[0].lane(i), v[1].lane(i), v[2].lane(i));
        let block = |b: &B<V>| b.m3(i);
        p.delta_rotation = self.rotation.lane(i);
        p.delta_velocity = vector(&self.velocity);
        p.delta_position = vector(&self.position);
        p.delta_t = self.t.lane(i);
        p.covariance = self.cov.each_ref().map(block);
        let [tg, vg, va, pg, pa] = self.jac.each_ref().map(block);
        let jac: Cross = [[tg, M3::ZERO], [vg, va], [pg, pa]];
        p.jac = jac;
        p.bias_walk = self.walk.as_ref().map(|w| w.lane(i));
    }

    /// One euler interval in every lane (`integrate_euler` with unit variance scales, element for
    /// element).
    #[inline(always)]
    fn step_euler(&mut self, accel: &[V; 3], gyro: &[V; 3], h: V, p: &Preintegrator) {
        let k = h;
        let (ba, bg) = (&p.bias_accel, &p.bias_gyro);
        let a = [
            accel[0] - k.splat(ba.x),
            accel[1] - k.splat(ba.y),
            accel[2] - k.splat(ba.z),
        ];
        let w = [
            gyro[0] - k.splat(bg.x),
            gyro[1] - k.splat(bg.y),
            gyro[2] - k.splat(bg.z),
        ];
        let r = self.rotation;
        let wh = [w[0] * h, w[1] * h, w[2] * h];
        let (step, jr) = exp_and_right_jacobian(k, &wh);
        let jr_h = jr.scale(h);
        let r1 = r.mul_plain(&step);
        let ra = r.apply(&a);

        let (d_a, d_g) = (p.noise.accel_density, p.noise.gyro_density);
        let var_a = k.like(|i| d_a * d_a / h.lane(i));
        let var_g = k.like(|i| d_g * d_g / h.lane(i));
        let w_m = hat_neg(&ra);
        let g = r1.mul(&jr_h);
        let half_h = k.splat(0.5) * h;
        let g_b = In {
            tg: g.neg(),
            vg: B([k.splat(0.0); 9]),
            va: r.scale(-h),
            half_h,
        };
        let half_h2 = half_h * h;
        let mut cov = propagate(&self.cov, &w_m, h, half_h2);
        // `blocks::add_held_noise`, the bias step folded into the white noise's quadratic.
        let [q_g, q_a] = match &self.walk {
            Some(walk) => [var_g + walk.var[0], var_a + walk.var[1]],
            None => [var_g, var_a],
        };
        cov[0] = g.mul_t_symmetric(&g).mul_add(q_g, &cov[0]);
        let q_a_h = q_a * h;
        cov[3] = cov[3].plus_identity(q_a_h * h);
        cov[4] = cov[4].plus_identity(q_a_h * half_h2);
        cov[5] = cov[5].plus_identity(q_a * half_h2 * half_h2);
        if let Some(walk) = &mut self.walk {
            walk.step(&mut cov, &w_m, &g_b, &p.noise);
        }
        self.cov = cov;

        self.jac = g_b.added_to(&transition(&self.jac, &w_m, h, half_h2));

        for ((p, v), ra) in self.position.iter_mut().zip(self.velocity.iter_mut()).zip(ra) {
            *p = *p + (*v * h + ra * half_h2);
            *v = *v + ra * h;
        }
        self.rotation = r1;
        self.t = self.t + h;
    }

    /// `Preintegrator::count_interval` for every lane (they share the counter).
    #[inline(always)]
    fn count_interval(&mut self, since_projection: &mut u32) {
        *since_projection += 1;
        if *since_projection >= PROJECT_EVERY {
            *since_projection = 0;
            let projected: [Matrix3<f64>; WIDTH] = std::array::from_fn(|i| project_rotation(&self.rotation.lane(i)));
            self.rotation = B::of_lanes(self.t, &projected);
        }
    }
}

crate::simd_dispatch! {
    /// `template` run over each of `spans` (at most [`WIDTH`]) without clipping
    /// flags, in lockstep for the intervals they all have, then each alone (module docs); lanes
    /// beyond `spans` repeat its first window and are dropped. `k`: any lane value (from
    /// [`lanes`]). The boundary samples are left as in `template` (the caller sets them).
    pub(super) fn run<V: Lanes>(samples: &Samples<'_>, spans: &[Span], template: &Preintegrator, k: V) -> Vec<Preintegrator> {
        let lane_span = |i: usize| spans[if i < spans.len() { i } else { 0 }];
        let common = spans.iter().map(|s| s.steps).min().unwrap_or(0);
        let mut state = State::of(k, template);
        let mut since_projection = template.since_projection;
        // Each lane's `(accel, gyro, h)` of interval j: euler's held sample, midpoint's end point.
        let gather = |lanes: &[(Vector3<f64>, Vector3<f64>, f64); WIDTH]| {
            let accel = [k.like(|i| lanes[i].0.x), k.like(|i| lanes[i].0.y), k.like(|i| lanes[i].0.z)];
            let gyro = [k.like(|i| lanes[i].1.x), k.like(|i| lanes[i].1.y), k.like(|i| lanes[i].1.z)];
            ([accel, gyro], k.like(|i| lanes[i].2))
        };
        let mut lanes = [(Vector3::zeros(), Vector3::zeros(), 0.0); WIDTH];
        let mut mid = None;
        if template.scheme == Scheme::Midpoint {
            for (i, lane) in lanes.iter_mut().enumerate() {
                *lane = lane_span(i).start_point(samples);
            }
            mid = Some(Mid::start(gather(&lanes).0));
        }
        for j in 0..common {
            match &mut mid {
                None => {
                    for (i, lane) in lanes.iter_mut().enumerate() {
                        *lane = lane_span(i).interval(samples, j);
                    }
                    let ([accel, gyro], h) = gather(&lanes);
                    state.step_euler(&accel, &gyro, h, template);
                }
                Some(mid) => {
                    for (i, lane) in lanes.iter_mut().enumerate() {
                        *lane = lane_span(i).end_point(samples, j);
                    }
                    let (point, h) = gather(&lanes);
                    state.step_midpoint(mid, &point, h, j == 0, template);
                }
            }
            state.count_interval(&mut since_projection);
        }
        spans
            .iter()
            .enumerate()
            .map(|(i, span)| {
                let mut p = template.clone();
                state.write_lane(i, &mut p);
                p.since_projection = since_projection;
                if let Some(mid) = &mid {
                    mid.write_lane(i, &mut p);
                }
                for j in common..span.steps {
                    let (a, w, h) = match mid {
                        None => span.interval(samples, j),
                        Some(_) => span.end_point(samples, j),
                    };
                    p.integrate_measurement_clipped(&a, &w, h, Clipped::NONE);
                }
                p
            })
            .collect()
    }
}
