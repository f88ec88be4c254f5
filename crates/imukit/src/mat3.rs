//! 3×3 block products for the block-structured covariance updates.
//!
//! Written out: nalgebra's generic product compiles to about twice the instructions, and these run
//! tens of times per IMU sample. Two forms:
//!
//! - on nalgebra's `Matrix3` (`mul`), for the occasional product;
//! - on [`M3`], a 3×3 block held as three columns padded to four lanes and aligned to 32 bytes, for
//!   the per-sample kernels: a column operation is one 256-bit instruction on the AVX paths (two
//!   128-bit ones on the baseline), with no shuffles to gather 3-element columns.
//!
//! The `M3` products and axpys take their column arithmetic from a [`Lanes`] value: [`Unfused`]
//! (plain arrays) rounds each product and each sum, as the `Matrix3` forms do (`mul` and the
//! references in the tests: same bits), for the baseline path; [`Fused`] (a `pulp` AVX2+FMA
//! token) holds a column in one 256-bit register and fuses each `a·b + c` into one fused
//! multiply-add (one rounding), for the AVX paths. LLVM does not vectorise the plain arrays'
//! lanes on its own (the dispatched AVX2 step was three quarters scalar arithmetic), hence the
//! explicit vectors. Every sum runs in the same order in both, so they differ by rounding only
//! (≤ 1 ulp per fused operation). A dispatched kernel picks its lanes with `with_lanes!`.

use std::ops::{Add, AddAssign, Mul, Neg, Sub};

use nalgebra::Matrix3;

/// `a b` for 3×3 blocks.
#[inline(always)]
pub(crate) fn mul(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| a[(r, 0)] * b[(0, c)] + a[(r, 1)] * b[(1, c)] + a[(r, 2)] * b[(2, c)])
}

/// A column of [`M3`]: three values and a zero lane.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Col(pub [f64; 4]);

impl Col {
    /// The column of lanes `f(0), f(1), f(2)` and a zero fourth lane. The plain-array forms compute
    /// three lanes only: with the blocks stored padded between steps, LLVM cannot drop a computed
    /// fourth lane, and on the baseline path it is one more SSE2 instruction per column operation
    /// (the midpoint step ran 17 % more instructions with four computed lanes).
    #[inline(always)]
    fn lanes3(f: impl Fn(usize) -> f64) -> Col {
        Col([f(0), f(1), f(2), 0.0])
    }

    #[inline(always)]
    fn zip(self, other: Col, f: impl Fn(f64, f64) -> f64) -> Col {
        Col::lanes3(|i| f(self.0[i], other.0[i]))
    }

    /// `a[0] s[0] + a[1] s[1] + a[2] s[2]`, summed left to right (fused as `l` fuses).
    #[inline(always)]
    fn combine<L: Lanes>(l: L, a: &[Col; 3], s: [f64; 3]) -> Col {
        l.scale_add(a[2], s[2], l.scale_add(a[1], s[1], l.scale(a[0], s[0])))
    }
}

/// 4-lane f64 arithmetic on a [`Col`]: how the block algebra's column operations compile.
pub(crate) trait Lanes: Copy {
    /// `a s`.
    fn scale(self, a: Col, s: f64) -> Col;
    /// `a s + acc`, fused or not (the implementation's rule).
    fn scale_add(self, a: Col, s: f64, acc: Col) -> Col;
    /// `a + b`.
    fn add(self, a: Col, b: Col) -> Col;
    /// `a b` for an `a` with a zero diagonal (a skew matrix): the dense product unless the lanes
    /// can leave its zero terms out.
    #[inline(always)]
    fn zero_diagonal_mul(self, a: &M3, b: &M3) -> M3 {
        a.mul_with(self, b)
    }
}

/// Plain arrays, each product and each sum rounded: the baseline path (the `Matrix3` forms' bits).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Unfused;

impl Lanes for Unfused {
    #[inline(always)]
    fn scale(self, a: Col, s: f64) -> Col {
        a * s
    }

    #[inline(always)]
    fn scale_add(self, a: Col, s: f64, acc: Col) -> Col {
        a.zip(acc, |x, y| x * s + y)
    }

    #[inline(always)]
    fn add(self, a: Col, b: Col) -> Col {
        a + b
    }

    /// Lane by lane, the dense product's two nonzero terms in its order (the same bits: the
    /// dropped term is `0·x`, which adds an exact zero): 6 products and 3 sums a column for 9 and 6.
    #[inline(always)]
    fn zero_diagonal_mul(self, a: &M3, b: &M3) -> M3 {
        let [a0, a1, a2] = [a.0[0].0, a.0[1].0, a.0[2].0];
        M3(std::array::from_fn(|c| {
            let s = b.0[c].0;
            Col([
                a1[0] * s[1] + a2[0] * s[2],
                a0[1] * s[0] + a2[1] * s[2],
                a0[2] * s[0] + a1[2] * s[1],
                0.0,
            ])
        }))
    }
}

/// One 256-bit AVX2 register per column, `a s + acc` one fused multiply-add: the AVX paths. LLVM
/// keeps the plain arrays' lanes in scalar registers (three quarters of the dispatched step's
/// arithmetic was scalar), so the vectors are spelled out; the token proves the CPU has AVX2+FMA.
#[cfg(target_arch = "x86_64")]
#[derive(Debug, Clone, Copy)]
pub(crate) struct Fused(pulp::x86::V3);

#[cfg(target_arch = "x86_64")]
impl Fused {
    /// The fused lanes, where the CPU has AVX2 and FMA.
    #[inline(always)]
    pub fn try_new() -> Option<Fused> {
        pulp::x86::V3::try_new().map(Fused)
    }

    #[inline(always)]
    fn load(a: Col) -> pulp::f64x4 {
        let [x, y, z, w] = a.0;
        pulp::f64x4(x, y, z, w)
    }

    #[inline(always)]
    fn store(v: pulp::f64x4) -> Col {
        Col([v.0, v.1, v.2, v.3])
    }
}

#[cfg(target_arch = "x86_64")]
impl Lanes for Fused {
    #[inline(always)]
    fn scale(self, a: Col, s: f64) -> Col {
        Fused::store(self.0.mul_f64x4(Fused::load(a), self.0.splat_f64x4(s)))
    }

    #[inline(always)]
    fn scale_add(self, a: Col, s: f64, acc: Col) -> Col {
        Fused::store(
            self.0
                .mul_add_f64x4(Fused::load(a), self.0.splat_f64x4(s), Fused::load(acc)),
        )
    }
    #[inline(always)]
    fn add(self, a: Col, b: Col) -> Col {
        Fused::store(self.0.add_f64x4(Fused::load(a), Fused::load(b)))
    }
}

/// Runs `body` with `l` the fused lanes when `fma` (a dispatched AVX copy, `crate::simd`) and the
/// CPU has them, [`Unfused`] otherwise.
macro_rules! with_lanes {
    ($fma:expr, |$l:ident| $body:expr) => {{
        #[cfg(target_arch = "x86_64")]
        let fused = if $fma { $crate::mat3::Fused::try_new() } else { None };
        #[cfg(not(target_arch = "x86_64"))]
        let fused: Option<$crate::mat3::Unfused> = None;
        match fused {
            Some($l) => $body,
            None => {
                let $l = $crate::mat3::Unfused;
                $body
            }
        }
    }};
}
pub(crate) use with_lanes;

impl Add for Col {
    type Output = Col;
    #[inline(always)]
    fn add(self, o: Col) -> Col {
        self.zip(o, |x, y| x + y)
    }
}

impl Sub for Col {
    type Output = Col;
    #[inline(always)]
    fn sub(self, o: Col) -> Col {
        self.zip(o, |x, y| x - y)
    }
}

impl Mul<f64> for Col {
    type Output = Col;
    #[inline(always)]
    fn mul(self, s: f64) -> Col {
        Col::lanes3(|i| self.0[i] * s)
    }
}

/// A 3×3 block as padded columns (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct M3(pub [Col; 3]);

impl M3 {
    /// The zero block.
    pub const ZERO: M3 = M3([Col([0.0; 4]); 3]);

    /// The block of `m`.
    #[inline(always)]
    pub fn of(m: &Matrix3<f64>) -> M3 {
        M3(std::array::from_fn(|c| Col([m[(0, c)], m[(1, c)], m[(2, c)], 0.0])))
    }

    /// Back to nalgebra.
    #[inline(always)]
    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|r, c| self.0[c].0[r])
    }

    #[inline(always)]
    fn map_cols(&self, f: impl Fn(usize, Col) -> Col) -> M3 {
        M3(std::array::from_fn(|c| f(c, self.0[c])))
    }

    /// `self b`.
    #[inline(always)]
    pub fn mul(&self, b: &M3) -> M3 {
        self.mul_with(Unfused, b)
    }

    /// `self b` in `l`'s lanes (module docs). No closure calls a lane operation: a closure is
    /// compiled without the dispatched copy's target features.
    #[inline(always)]
    pub fn mul_with<L: Lanes>(&self, l: L, b: &M3) -> M3 {
        let col = |c: usize| -> [f64; 3] { [b.0[c].0[0], b.0[c].0[1], b.0[c].0[2]] };
        let (c0, c1, c2) = (col(0), col(1), col(2));
        M3([
            Col::combine(l, &self.0, c0),
            Col::combine(l, &self.0, c1),
            Col::combine(l, &self.0, c2),
        ])
    }

    /// `self b` for a `self` with a zero diagonal (a skew matrix), in `l`'s lanes
    /// ([`Lanes::zero_diagonal_mul`]).
    #[inline(always)]
    pub fn zero_diagonal_mul_with<L: Lanes>(&self, l: L, b: &M3) -> M3 {
        l.zero_diagonal_mul(self, b)
    }

    /// `self bᵀ`.
    #[inline(always)]
    pub fn mul_t(&self, b: &M3) -> M3 {
        self.mul_t_with(Unfused, b)
    }

    /// `self bᵀ` in `l`'s lanes.
    #[inline(always)]
    pub fn mul_t_with<L: Lanes>(&self, l: L, b: &M3) -> M3 {
        let [b0, b1, b2] = b.0;
        let row = |c: usize| -> [f64; 3] { [b0.0[c], b1.0[c], b2.0[c]] };
        let (r0, r1, r2) = (row(0), row(1), row(2));
        M3([
            Col::combine(l, &self.0, r0),
            Col::combine(l, &self.0, r1),
            Col::combine(l, &self.0, r2),
        ])
    }

    /// `self bᵀ` known to be symmetric: the upper triangle, mirrored (as the `Matrix3` form in the
    /// tests), in `l`'s lanes.
    #[inline(always)]
    pub fn mul_t_symmetric_with<L: Lanes>(&self, l: L, b: &M3) -> M3 {
        self.mul_t_with(l, b).mirror_upper()
    }

    /// `self s + acc` in `l`'s lanes.
    #[inline(always)]
    pub fn mul_add<L: Lanes>(&self, l: L, s: f64, acc: &M3) -> M3 {
        M3([
            l.scale_add(self.0[0], s, acc.0[0]),
            l.scale_add(self.0[1], s, acc.0[1]),
            l.scale_add(self.0[2], s, acc.0[2]),
        ])
    }

    /// `self s` in `l`'s lanes.
    #[inline(always)]
    pub fn scale_with<L: Lanes>(&self, l: L, s: f64) -> M3 {
        M3([l.scale(self.0[0], s), l.scale(self.0[1], s), l.scale(self.0[2], s)])
    }

    /// `self + o` in `l`'s lanes.
    #[inline(always)]
    pub fn add_with<L: Lanes>(&self, l: L, o: &M3) -> M3 {
        M3([
            l.add(self.0[0], o.0[0]),
            l.add(self.0[1], o.0[1]),
            l.add(self.0[2], o.0[2]),
        ])
    }

    /// The transpose.
    #[inline(always)]
    pub fn transpose(&self) -> M3 {
        M3(std::array::from_fn(|c| {
            Col([self.0[0].0[c], self.0[1].0[c], self.0[2].0[c], 0.0])
        }))
    }

    /// The upper triangle copied onto the lower one.
    #[inline(always)]
    fn mirror_upper(mut self) -> M3 {
        self.0[0].0[1] = self.0[1].0[0];
        self.0[0].0[2] = self.0[2].0[0];
        self.0[1].0[2] = self.0[2].0[1];
        self
    }

    /// `(b + bᵀ)/2`, exactly symmetric.
    #[inline(always)]
    pub fn symmetric(self) -> M3 {
        let s = |r: usize, c: usize| (self.0[c].0[r] + self.0[r].0[c]) * 0.5;
        let (xy, xz, yz) = (s(0, 1), s(0, 2), s(1, 2));
        let mut out = self;
        for i in 0..3 {
            out.0[i].0[i] = s(i, i);
        }
        (out.0[1].0[0], out.0[2].0[0], out.0[2].0[1]) = (xy, xz, yz);
        out.mirror_upper()
    }

    /// `self + s I`.
    #[inline(always)]
    pub fn plus_identity(mut self, s: f64) -> M3 {
        for i in 0..3 {
            self.0[i].0[i] += s;
        }
        self
    }
}

impl Add for M3 {
    type Output = M3;
    #[inline(always)]
    fn add(self, o: M3) -> M3 {
        self.map_cols(|c, x| x + o.0[c])
    }
}

impl AddAssign for M3 {
    #[inline(always)]
    fn add_assign(&mut self, o: M3) {
        *self = *self + o;
    }
}

impl Sub for M3 {
    type Output = M3;
    #[inline(always)]
    fn sub(self, o: M3) -> M3 {
        self.map_cols(|c, x| x - o.0[c])
    }
}

impl Mul<f64> for M3 {
    type Output = M3;
    #[inline(always)]
    fn mul(self, s: f64) -> M3 {
        self.map_cols(|_, x| x * s)
    }
}

impl Neg for M3 {
    type Output = M3;
    #[inline(always)]
    fn neg(self) -> M3 {
        self.map_cols(|_, x| Col::lanes3(|i| -x.0[i]))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;

    use super::M3;

    /// `a bᵀ` for 3×3 blocks.
    fn mul_t(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
        Matrix3::from_fn(|r, c| a[(r, 0)] * b[(c, 0)] + a[(r, 1)] * b[(c, 1)] + a[(r, 2)] * b[(c, 2)])
    }

    /// `a bᵀ` for 3×3 blocks whose product is known to be symmetric (as `X S Xᵀ` with `a = X S`):
    /// the upper triangle, mirrored, so the result is exactly symmetric at two thirds of the cost.
    fn mul_t_symmetric(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
        let d = |r: usize, c: usize| a[(r, 0)] * b[(c, 0)] + a[(r, 1)] * b[(c, 1)] + a[(r, 2)] * b[(c, 2)];
        let (xy, xz, yz) = (d(0, 1), d(0, 2), d(1, 2));
        Matrix3::new(d(0, 0), xy, xz, xy, d(1, 1), yz, xz, yz, d(2, 2))
    }

    /// The padded form gives the `Matrix3` form's bits (same operations, same order).
    #[test]
    fn padded_blocks_match_the_matrix_forms_bit_for_bit() {
        let a = Matrix3::new(0.3, -1.2, 2.5, 0.7, 0.1, -0.4, -2.2, 1.9, 0.6);
        let b = Matrix3::new(1.1, 0.2, -0.3, 0.45, -0.9, 1.7, 0.05, 2.2, -1.4);
        let (pa, pb) = (M3::of(&a), M3::of(&b));
        assert_eq!(pa.mul(&pb).matrix(), super::mul(&a, &b));
        assert_eq!(pa.mul_t(&pb).matrix(), mul_t(&a, &b));
        assert_eq!(
            pa.mul_t_symmetric_with(super::Unfused, &pa).matrix(),
            mul_t_symmetric(&a, &a)
        );
        let w = crate::so3::hat(&nalgebra::Vector3::new(0.8, -9.7, 0.35));
        assert_eq!(
            M3::of(&w).zero_diagonal_mul_with(super::Unfused, &pb).matrix(),
            super::mul(&w, &b)
        );
        assert_eq!(pa.transpose().matrix(), a.transpose());
        assert_eq!(pa.symmetric().matrix(), (a + a.transpose()) * 0.5);
        assert_eq!(pa.plus_identity(0.7).matrix(), a + Matrix3::identity() * 0.7);
        assert_eq!((pa * 1.3 - pb + -pa).matrix(), a * 1.3 - b + -a);
        assert_eq!(
            pa.scale_with(super::Unfused, 1.3)
                .add_with(super::Unfused, &pb)
                .matrix(),
            a * 1.3 + b
        );
        let mut acc = pa;
        acc += pb;
        assert_eq!(acc.matrix(), a + b);
    }

    /// The fused forms round each `a·b + c` once, in the unfused form's order: equal to a scalar
    /// `mul_add` chain bit for bit, and within rounding of the unfused product.
    #[test]
    fn fused_blocks_are_scalar_fma_chains_in_the_same_order() {
        let a = Matrix3::new(0.3, -1.2, 2.5, 0.7, 0.1, -0.4, -2.2, 1.9, 0.6);
        let b = Matrix3::new(1.1, 0.2, -0.3, 0.45, -0.9, 1.7, 0.05, 2.2, -1.4);
        let (pa, pb) = (M3::of(&a), M3::of(&b));
        let chain = |r: usize, x: [f64; 3]| a[(r, 2)].mul_add(x[2], a[(r, 1)].mul_add(x[1], a[(r, 0)] * x[0]));
        let ab = Matrix3::from_fn(|r, c| chain(r, [b[(0, c)], b[(1, c)], b[(2, c)]]));
        let abt = Matrix3::from_fn(|r, c| chain(r, [b[(c, 0)], b[(c, 1)], b[(c, 2)]]));
        let Some(l) = super::Fused::try_new() else {
            return; // no AVX2+FMA on this CPU: the fused lanes never run here
        };
        assert_eq!(pa.mul_with(l, &pb).matrix(), ab);
        assert_eq!(pa.mul_t_with(l, &pb).matrix(), abt);
        assert_eq!(
            pa.mul_add(l, 0.3, &pb).matrix(),
            a.zip_map(&b, |x, y| x.mul_add(0.3, y))
        );
        // Sums and scalings have one rounding either way: the unfused bits.
        assert_eq!(pa.add_with(l, &pb).matrix(), a + b);
        assert_eq!(pa.scale_with(l, -1.3).matrix(), a * -1.3);
        let gap = (pa.mul_with(l, &pb).matrix() - a * b).amax();
        assert!(gap < 1e-14 * (a.abs() * b.abs()).amax(), "{gap:e}");
    }
}
