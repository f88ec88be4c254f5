//! Structure-of-arrays preintegration: L euler windows in lockstep, one window per SIMD lane.
//!
//! The per-window kernel (`Preintegrator::integrate_measurement_clipped`) is a chain of dependent
//! 3×3 products, so one window leaves most of a vector register idle. Here every scalar of the
//! state (ΔR, Δv, Δp, Δt, the six covariance blocks, the five non-zero Jacobian blocks) is an
//! array of L values, one per window, and every operation acts on all L at once:
//!
//! | path | lanes L | one lane operation |
//! |---|---|---|
//! | `avx512` | 8 | one 512-bit instruction |
//! | `avx2` | 4 | one 256-bit instruction |
//! | `baseline` | 4 | two 128-bit SSE2 instructions |
//!
//! What the lanes run: the euler scheme with the 9×9 covariance and the 9×6 bias Jacobian, no
//! flagged (clipped) sample, no bias walk. `preint/windows.rs` sends everything else (midpoint,
//! `combined`, windows holding a clipped sample) to the per-window kernel.
//!
//! Each element is computed with the same operations in the same order as the per-window kernel
//! (`preint/mod.rs`, `integrate_euler`; `preint/blocks.rs`, `propagate`): a lane is that kernel,
//! bit for bit, on every path where it does not contract multiply-adds into FMA. `Exp(ω̂h)` and
//! `J_r(ω̂h)` (a norm, `sin`, `cos`: branches on θ) and the projection of ΔR every
//! `PROJECT_EVERY` intervals are computed per lane by the per-window functions themselves.
//!
//! A bundle runs in lockstep for the intervals all its windows have; each window then finishes
//! alone on the per-window kernel (the caller groups windows of near-equal length, so that tail
//! is short).

use std::marker::PhantomData;
use std::ops::{Add, Div, Mul, Neg, Sub};

use nalgebra::{Matrix3, Vector3};

use super::blocks::Cross;
use super::{project_rotation, Clipped, Preintegrator, PROJECT_EVERY};
use crate::imu::Samples;
use crate::simd::{self, Path};
use crate::so3;

/// L f64 values, one per window.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(super) struct X<const L: usize>([f64; L]);

/// What the kernel needs of a lane vector: element-wise arithmetic, a broadcast and lane access.
pub(super) trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    /// The number of lanes.
    const L: usize;
    /// `x` in every lane.
    fn splat(x: f64) -> Self;
    /// Lane `i` is `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// Lane `i`.
    fn lane(&self, i: usize) -> f64;
}

/// The element-wise binary operators of [`X`].
macro_rules! lane_op {
    ($($trait:ident $method:ident $op:tt),*) => {$(
        impl<const L: usize> $trait for X<L> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                X(std::array::from_fn(|i| self.0[i] $op o.0[i]))
            }
        }
    )*};
}
lane_op!(Add add +, Sub sub -, Mul mul *, Div div /);

impl<const L: usize> Neg for X<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut out = self;
        for v in out.0.iter_mut() {
            *v = -*v;
        }
        out
    }
}

impl<const L: usize> Lanes for X<L> {
    const L: usize = L;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        X([x; L])
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        let mut out = [0.0; L];
        for (i, v) in out.iter_mut().enumerate() {
            *v = f(i);
        }
        X(out)
    }
    #[inline(always)]
    fn lane(&self, i: usize) -> f64 {
        self.0[i]
    }
}

/// A 3×3 block of lanes, column-major (`e(r, c)` is `self.0[3c + r]`); each method is the
/// per-lane twin of `mat3::M3`'s, element for element.
#[derive(Debug, Clone, Copy)]
struct B<V>([V; 9]);

impl<V: Lanes> B<V> {
    #[inline(always)]
    fn e(&self, r: usize, c: usize) -> V {
        self.0[3 * c + r]
    }

    // Written out: `array::from_fn` and `map` over arrays of lanes stayed out-of-line calls.
    #[inline(always)]
    fn from_fn(f: impl Fn(usize, usize) -> V) -> Self {
        B([
            f(0, 0),
            f(1, 0),
            f(2, 0),
            f(0, 1),
            f(1, 1),
            f(2, 1),
            f(0, 2),
            f(1, 2),
            f(2, 2),
        ])
    }

    /// Lane `i` of every element as a matrix.
    fn lane(&self, i: usize) -> Matrix3<f64> {
        Matrix3::from_fn(|r, c| self.e(r, c).lane(i))
    }

    /// Lane `i` of every element is `m[i]` (column-major).
    #[inline(always)]
    fn of_lanes(m: &[[f64; 9]; MAX_LANES]) -> Self {
        B::from_fn(|r, c| V::from_fn(|i| m[i][3 * c + r]))
    }

    #[inline(always)]
    fn splat(m: &Matrix3<f64>) -> Self {
        B::from_fn(|r, c| V::splat(m[(r, c)]))
    }

    /// `self b` (`M3::mul`).
    #[inline(always)]
    fn mul(&self, b: &Self) -> Self {
        B::from_fn(|r, c| self.e(r, 0) * b.e(0, c) + self.e(r, 1) * b.e(1, c) + self.e(r, 2) * b.e(2, c))
    }

    /// `self bᵀ` (`M3::mul_t`).
    #[inline(always)]
    fn mul_t(&self, b: &Self) -> Self {
        B::from_fn(|r, c| self.e(r, 0) * b.e(c, 0) + self.e(r, 1) * b.e(c, 1) + self.e(r, 2) * b.e(c, 2))
    }

    /// `self bᵀ` known to be symmetric: the upper triangle, mirrored (`M3::mul_t_symmetric`).
    #[inline(always)]
    fn mul_t_symmetric(&self, b: &Self) -> Self {
        let d = |r: usize, c: usize| self.e(r, 0) * b.e(c, 0) + self.e(r, 1) * b.e(c, 1) + self.e(r, 2) * b.e(c, 2);
        let (xy, xz, yz) = (d(0, 1), d(0, 2), d(1, 2));
        B([d(0, 0), xy, xz, xy, d(1, 1), yz, xz, yz, d(2, 2)])
    }

    #[inline(always)]
    fn transpose(&self) -> Self {
        B::from_fn(|r, c| self.e(c, r))
    }

    /// `(b + bᵀ)/2` (`M3::symmetric`).
    #[inline(always)]
    fn symmetric(&self) -> Self {
        let s = |r: usize, c: usize| (self.e(r, c) + self.e(c, r)) * V::splat(0.5);
        let (xy, xz, yz) = (s(0, 1), s(0, 2), s(1, 2));
        B([s(0, 0), xy, xz, xy, s(1, 1), yz, xz, yz, s(2, 2)])
    }

    /// `self + s I`.
    #[inline(always)]
    fn plus_identity(mut self, s: V) -> Self {
        for i in 0..3 {
            self.0[4 * i] = self.0[4 * i] + s;
        }
        self
    }

    #[inline(always)]
    fn zip(&self, o: &Self, f: impl Fn(V, V) -> V) -> Self {
        B::from_fn(|r, c| f(self.e(r, c), o.e(r, c)))
    }

    #[inline(always)]
    fn add(&self, o: &Self) -> Self {
        self.zip(o, |x, y| x + y)
    }

    #[inline(always)]
    fn sub(&self, o: &Self) -> Self {
        self.zip(o, |x, y| x - y)
    }

    #[inline(always)]
    fn scale(&self, s: V) -> Self {
        B::from_fn(|r, c| self.e(r, c) * s)
    }

    #[inline(always)]
    fn neg(&self) -> Self {
        B::from_fn(|r, c| -self.e(r, c))
    }
}

/// One euler window as a sequence of intervals: interval j holds sample `k0 + j` from `T(j)` to
/// `T(j + 1)`, with `T(0) = lo`, `T(steps) = hi` and `T(j) = t[k0 + j]` between.
#[derive(Debug, Clone, Copy)]
pub(super) struct Span {
    /// The sample held at `lo` (the last one at or before it).
    pub k0: usize,
    /// The number of intervals.
    pub steps: usize,
    /// Start time.
    pub lo: f64,
    /// End time.
    pub hi: f64,
}

impl Span {
    /// `T(j)`.
    #[inline(always)]
    fn time(&self, t: &[f64], j: usize) -> f64 {
        if j == 0 {
            self.lo
        } else if j == self.steps {
            self.hi
        } else {
            t[self.k0 + j]
        }
    }

    /// `(accel, gyro, h)` of interval j.
    #[inline(always)]
    pub fn interval(&self, samples: &Samples<'_>, j: usize) -> (Vector3<f64>, Vector3<f64>, f64) {
        let k = self.k0 + j;
        let h = self.time(samples.t, j + 1) - self.time(samples.t, j);
        (samples.accel_at(k), samples.gyro_at(k), h)
    }
}

/// The lockstep state: the per-window fields, one window per lane.
struct State<V> {
    rotation: B<V>,
    velocity: [V; 3],
    position: [V; 3],
    t: V,
    /// `[θθ, θv, θp, vv, vp, pp]`.
    cov: [B<V>; 6],
    /// `[θg, vg, va, pg, pa]` (the θa block stays zero).
    jac: [B<V>; 5],
}

/// `A Σ Aᵀ + B Σ_a Bᵀ + C Σ_g Cᵀ`: `blocks::propagate`, lane-wise.
#[inline(always)]
fn propagate<V: Lanes>(cov: &[B<V>; 6], phi: &B<V>, m: &B<V>, jr: &B<V>, h: V, var_a: V, var_g: V) -> [B<V>; 6] {
    let [tt, tv, tp, vv, vp, pp] = cov;
    let (vt, pt, pv) = (tv.transpose(), tp.transpose(), vp.transpose());
    let half_h2 = V::splat(0.5) * h * h;
    let phi_tt = phi.mul(tt);
    let m_tt = m.mul(tt);
    let (m_tv, m_tp) = (m.mul(tv), m.mul(tp));
    let a_vt = m_tt.scale(h).add(&vt);
    let a_vv = m_tv.scale(h).add(vv);
    let a_vp = m_tp.scale(h).add(vp);
    let a_pt = m_tt.scale(half_h2).add(&vt.scale(h)).add(&pt);
    let a_pv = m_tv.scale(half_h2).add(&vv.scale(h)).add(&pv);
    let a_pp = m_tp.scale(half_h2).add(&vp.scale(h)).add(pp);
    let phi_tt_mt = phi_tt.mul_t(m);
    let new_tt = phi_tt
        .mul_t_symmetric(phi)
        .add(&jr.mul_t_symmetric(jr).scale(var_g * h * h));
    let phi_tv = phi.mul(tv);
    let new_tv = phi_tt_mt.scale(h).add(&phi_tv);
    let new_tp = phi_tt_mt.scale(half_h2).add(&phi_tv.scale(h)).add(&phi.mul(tp));
    let a_vt_mt = a_vt.mul_t(m);
    let new_vv = a_vt_mt.scale(h).add(&a_vv).plus_identity(var_a * h * h);
    let new_vp = a_vt_mt
        .scale(half_h2)
        .add(&a_vv.scale(h))
        .add(&a_vp)
        .plus_identity(var_a * h * half_h2);
    let new_pp = a_pt
        .mul_t(m)
        .scale(half_h2)
        .add(&a_pv.scale(h))
        .add(&a_pp)
        .plus_identity(var_a * half_h2 * half_h2);
    [new_tt, new_tv, new_tp, new_vv.symmetric(), new_vp, new_pp.symmetric()]
}

impl<V: Lanes> State<V> {
    /// Every lane at `p`'s state.
    fn of(p: &Preintegrator) -> Self {
        let splat3 = |v: &Vector3<f64>| [V::splat(v.x), V::splat(v.y), V::splat(v.z)];
        let [[tg, _], [vg, va], [pg, pa]] = &p.jac;
        State {
            rotation: B::splat(&p.delta_rotation),
            velocity: splat3(&p.delta_velocity),
            position: splat3(&p.delta_position),
            t: V::splat(p.delta_t),
            cov: p.covariance.each_ref().map(B::splat),
            jac: [tg, vg, va, pg, pa].map(B::splat),
        }
    }

    /// Lane `i` written into `p` (a copy of the template the lanes started from).
    fn write_lane(&self, i: usize, p: &mut Preintegrator) {
        let vector = |v: &[V; 3]| Vector3::new(v[0].lane(i), v[1].lane(i), v[2].lane(i));
        p.delta_rotation = self.rotation.lane(i);
        p.delta_velocity = vector(&self.velocity);
        p.delta_position = vector(&self.position);
        p.delta_t = self.t.lane(i);
        p.covariance = self.cov.each_ref().map(|b| b.lane(i));
        let [tg, vg, va, pg, pa] = self.jac.each_ref().map(|b| b.lane(i));
        let jac: Cross = [[tg, Matrix3::zeros()], [vg, va], [pg, pa]];
        p.jac = jac;
    }

    /// One euler interval in every lane (`integrate_euler`, element for element).
    #[inline(always)]
    fn step(&mut self, accel: &[V; 3], gyro: &[V; 3], h: V, p: &Preintegrator) {
        let (ba, bg) = (&p.bias_accel, &p.bias_gyro);
        let a = [
            accel[0] - V::splat(ba.x),
            accel[1] - V::splat(ba.y),
            accel[2] - V::splat(ba.z),
        ];
        let w = [
            gyro[0] - V::splat(bg.x),
            gyro[1] - V::splat(bg.y),
            gyro[2] - V::splat(bg.z),
        ];
        let r = self.rotation;
        // `blocks::times_hat`: column j is `R (a × e_j)`.
        let r_a_cross = B::from_fn(|i, c| match c {
            0 => r.e(i, 1) * a[2] - r.e(i, 2) * a[1],
            1 => r.e(i, 2) * a[0] - r.e(i, 0) * a[2],
            _ => r.e(i, 0) * a[1] - r.e(i, 1) * a[0],
        });
        let wh = [w[0] * h, w[1] * h, w[2] * h];
        let (mut exp_l, mut jr_l) = ([[0.0; 9]; MAX_LANES], [[0.0; 9]; MAX_LANES]);
        for i in 0..V::L {
            let (e, j) = so3::exp_and_right_jacobian(&Vector3::new(wh[0].lane(i), wh[1].lane(i), wh[2].lane(i)));
            exp_l[i].copy_from_slice(e.as_slice());
            jr_l[i].copy_from_slice(j.as_slice());
        }
        let step = B::<V>::of_lanes(&exp_l);
        let jr = B::<V>::of_lanes(&jr_l);
        let half_h2 = V::splat(0.5) * h * h;
        let var_a = V::splat(p.noise.accel_density * p.noise.accel_density) / h;
        let var_g = V::splat(p.noise.gyro_density * p.noise.gyro_density) / h;
        let phi = step.transpose();
        let m = r_a_cross.neg();
        self.cov = propagate(&self.cov, &phi, &m, &jr, h, var_a, var_g);

        let [jtg, jvg, jva, jpg, jpa] = self.jac;
        let jr_h = jr.scale(h);
        let ra_drot = r_a_cross.mul(&jtg);
        self.jac = [
            phi.mul(&jtg).sub(&jr_h),
            jvg.sub(&ra_drot.scale(h)),
            jva.sub(&r.scale(h)),
            jpg.add(&jvg.scale(h)).sub(&ra_drot.scale(half_h2)),
            jpa.add(&jva.scale(h)).sub(&r.scale(half_h2)),
        ];

        let ra_row = |i: usize| r.e(i, 0) * a[0] + r.e(i, 1) * a[1] + r.e(i, 2) * a[2];
        let ra = [ra_row(0), ra_row(1), ra_row(2)];
        for ((p, v), ra) in self.position.iter_mut().zip(self.velocity.iter_mut()).zip(ra) {
            *p = *p + (*v * h + ra * half_h2);
            *v = *v + ra * h;
        }
        self.rotation = r.mul(&step);
        self.t = self.t + h;
    }

    /// `Preintegrator::count_interval` for every lane (they share the counter).
    #[inline(always)]
    fn count_interval(&mut self, since_projection: &mut u32) {
        *since_projection += 1;
        if *since_projection >= PROJECT_EVERY {
            *since_projection = 0;
            let mut projected = [[0.0; 9]; MAX_LANES];
            for (i, lane) in projected.iter_mut().enumerate().take(V::L) {
                lane.copy_from_slice(project_rotation(&self.rotation.lane(i)).as_slice());
            }
            self.rotation = B::of_lanes(&projected);
        }
    }
}

/// The widest lane count supported (the AVX-512 path's).
const MAX_LANES: usize = 8;

/// Windows per bundle on the path in use.
pub(super) fn width() -> usize {
    match simd::path() {
        Path::Avx512 => 8,
        _ => 4,
    }
}

/// `template` (euler, no bias walk) run over each of `spans` (at most [`width`]), without
/// clipping flags; the boundary samples are left as in `template` (the caller sets them).
pub(super) fn run(samples: &Samples<'_>, spans: &[Span], template: &Preintegrator) -> Vec<Preintegrator> {
    match simd::path() {
        Path::Avx512 => bundle::<X<8>>(samples, spans, template, PhantomData),
        _ => bundle::<X<4>>(samples, spans, template, PhantomData),
    }
}

crate::simd_dispatch! {
    /// Up to `V::L` windows in lockstep for the intervals they all have, then each alone (module
    /// docs); lanes beyond `spans` repeat its first window and are dropped.
    fn bundle<V: Lanes>(
        samples: &Samples<'_>,
        spans: &[Span],
        template: &Preintegrator,
        _lanes: PhantomData<V>,
    ) -> Vec<Preintegrator> {
        let lane_span = |i: usize| spans[if i < spans.len() { i } else { 0 }];
        let common = spans.iter().map(|s| s.steps).min().unwrap_or(0);
        let mut state = State::<V>::of(template);
        let mut since_projection = template.since_projection;
        for j in 0..common {
            let mut hs = [0.0; MAX_LANES];
            let mut lanes = [[0.0; 6]; MAX_LANES];
            for (i, (lane, h)) in lanes.iter_mut().zip(hs.iter_mut()).enumerate().take(V::L) {
                let (a, w, dt) = lane_span(i).interval(samples, j);
                *lane = [a.x, a.y, a.z, w.x, w.y, w.z];
                *h = dt;
            }
            let value = |k: usize| V::from_fn(|i| lanes[i][k]);
            let accel = [value(0), value(1), value(2)];
            let gyro = [value(3), value(4), value(5)];
            state.step(&accel, &gyro, V::from_fn(|i| hs[i]), template);
            state.count_interval(&mut since_projection);
        }
        spans
            .iter()
            .enumerate()
            .map(|(i, span)| {
                let mut p = template.clone();
                state.write_lane(i, &mut p);
                p.since_projection = since_projection;
                for j in common..span.steps {
                    let (a, w, h) = span.interval(samples, j);
                    p.integrate_measurement_clipped(&a, &w, h, Clipped::NONE);
                }
                p
            })
            .collect()
    }
}
