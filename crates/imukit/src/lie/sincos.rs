//! `(sin x, cos x)` of four angles at once, for the simulator's motions (three per stamp).
//!
//! | function | lanes | instructions | agreement |
//! |---|---|---|---|
//! | [`sin_cos`] | one | scalar, no call, no branch | for `|x| ≤` [`RANGE`]: within 2 ulp of libm, or 1e-22 absolute near a zero of sin or cos |
//! | [`sin_cos_x4`] | four | AVX2 on the `avx2` and `avx512` paths ([`crate::simd::path`]), else four [`sin_cos`]; libm's own for a lane beyond [`RANGE`] or NaN | the same bits as four [`sin_cos`] |
//!
//! The method (Cody & Waite, *Software Manual for the Elementary Functions*, 1980): `x` is reduced
//! by the nearest multiple `k` of π/2 to `r ∈ [−π/4, π/4]`, `π/2` split in three constants so that
//! `k · PIO2[i]` is exact; `sin r` and `cos r` are minimax polynomials in `r²` (Moshier's Cephes
//! coefficients, *Methods and Programs for Mathematical Functions*, 1989); the quadrant `k mod 4`
//! swaps and signs them. `k` is rounded half to even by adding and subtracting 2^52, whose sum's
//! low bits then hold `k` (no rounding or conversion instruction, which SSE2 lacks). Multiplies and
//! adds stay separate (no fused multiply-add) and in the same order on every path, so the vector
//! path equals the scalar one bit for bit. Beyond [`RANGE`] the constants run out of bits (more
//! than 10³ ulp by 1e9 rad): [`sin_cos_x4`] takes libm there. Each lane depends on its angle alone.

/// π/2 in three parts, the first two with 25 significant bits: `k · PIO2[i]` is exact for `k < 2^27`.
const PIO2: [f64; 3] = [
    1.570_796_310_901_641_8,
    1.589_325_471_229_585_7e-8,
    6.123_233_995_736_766e-17,
];

/// `(sin r − r)/r³` on `|r| ≤ π/4`, a polynomial in `r²` (Cephes `sin.c`).
const SIN_P: [f64; 6] = [
    -0.1666666666666663,
    0.008333333333322118,
    -0.0001984126982958954,
    2.7557313621385722e-06,
    -2.5050747762857807e-08,
    1.5896230157654656e-10,
];

/// `(cos r − 1 + r²/2)/r⁴` on `|r| ≤ π/4`, the same source.
const COS_P: [f64; 6] = [
    0.041666666666666595,
    -0.0013888888888873056,
    2.4801587288851704e-05,
    -2.755731417929674e-07,
    2.087570084197473e-09,
    -1.1358536521387682e-11,
];

/// The largest `|x|` \[rad\] [`sin_cos`] takes: 2^27 (quadrants `k < 2^27`, where `k · PIO2[i]` is
/// exact; measured, the error stays within 2 ulp of libm to 3e8 rad away from the zeros of sin
/// and cos, and within 6.6e-24 absolute near them, where ulps of the tiny value say little).
pub const RANGE: f64 = 134_217_728.0;

/// 2^52: adding it to `0 ≤ v < 2^51` rounds `v` to an integer, half to even, held in the low bits.
const ROUND: f64 = 4_503_599_627_370_496.0;

const SIGN: u64 = 1 << 63;

/// `(sin x, cos x)` for `|x| ≤` [`RANGE`], within 2 ulp of libm or 1e-22 absolute (beyond, wrong:
/// see [`RANGE`]).
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let a = x.abs();
    let shifted = a * std::f64::consts::FRAC_2_PI + ROUND;
    let k = shifted - ROUND;
    let quadrant = shifted.to_bits().wrapping_sub(ROUND.to_bits());
    let r = ((a - k * PIO2[0]) - k * PIO2[1]) - k * PIO2[2];
    let r2 = r * r;
    // A degree-5 polynomial split in three (Estrin's scheme): its multiplies do not wait on each
    // other as Horner's would.
    let estrin = |c: &[f64; 6]| {
        let z2 = r2 * r2;
        let z4 = z2 * z2;
        (c[3] * r2 + c[2]) * z2 + ((c[5] * r2 + c[4]) * z4 + (c[1] * r2 + c[0]))
    };
    let sin_r = (r * r2) * estrin(&SIN_P) + r;
    let cos_r = (r2 * r2) * estrin(&COS_P) + (1.0 - r2 * 0.5);
    let (s, c) = if quadrant & 1 == 1 {
        (cos_r, sin_r)
    } else {
        (sin_r, cos_r)
    };
    // sin changes sign with x and in quadrants 2, 3; cos in quadrants 1, 2.
    let sin = f64::from_bits(s.to_bits() ^ (((quadrant << 62) ^ x.to_bits()) & SIGN));
    let cos = f64::from_bits(c.to_bits() ^ ((quadrant.wrapping_add(1) & 2) << 62));
    (sin, cos)
}

/// `(sin x, cos x)` of four angles: [`sin_cos`] in each lane, in one AVX2 sequence where the
/// dispatched path has it (the same bits as four calls), and libm's own value in a lane beyond
/// [`RANGE`] or NaN.
#[inline]
pub fn sin_cos_x4(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    #[cfg(target_arch = "x86_64")]
    let vector = matches!(crate::simd::path(), crate::simd::Path::Avx2 | crate::simd::Path::Avx512);
    #[cfg(not(target_arch = "x86_64"))]
    let vector = false;
    let (mut s, mut c, outside) = if vector {
        // SAFETY: `path()` is `Avx2` or `Avx512` only where the CPU has AVX2 (never off x86-64).
        #[allow(unsafe_code)]
        unsafe {
            avx2::sin_cos_x4(x)
        }
    } else {
        let (mut s, mut c, mut outside) = ([0.0; 4], [0.0; 4], 0);
        for k in 0..4 {
            (s[k], c[k]) = sin_cos(x[k]);
            outside |= i32::from(x[k].is_nan() || x[k].abs() > RANGE) << k;
        }
        (s, c, outside)
    };
    if outside != 0 {
        for (k, v) in x.iter().enumerate() {
            if outside >> k & 1 == 1 {
                (s[k], c[k]) = v.sin_cos();
            }
        }
    }
    (s, c)
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::{COS_P, PIO2, RANGE, ROUND, SIGN, SIN_P};

    #[inline]
    #[target_feature(enable = "avx2")]
    fn splat(v: f64) -> __m256d {
        _mm256_set1_pd(v)
    }

    /// `c₀ + c₁z + … + c₅z⁵`, as [`super::sin_cos`] groups it.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn estrin(z: __m256d, c: &[f64; 6]) -> __m256d {
        let (mul, add) = (_mm256_mul_pd, _mm256_add_pd);
        let z2 = mul(z, z);
        let z4 = mul(z2, z2);
        let low = add(mul(splat(c[1]), z), splat(c[0]));
        let high = add(mul(splat(c[5]), z), splat(c[4]));
        add(mul(add(mul(splat(c[3]), z), splat(c[2])), z2), add(mul(high, z4), low))
    }

    /// [`super::sin_cos`] in the four lanes of a 256-bit register, operation for operation, and
    /// the lanes beyond [`RANGE`] or NaN as bits of a mask.
    #[target_feature(enable = "avx2")]
    pub(super) fn sin_cos_x4(x: [f64; 4]) -> ([f64; 4], [f64; 4], i32) {
        let (mul, add, sub) = (_mm256_mul_pd, _mm256_add_pd, _mm256_sub_pd);
        // SAFETY: `x` holds four f64, which `loadu` reads unaligned.
        #[allow(unsafe_code)]
        let x = unsafe { _mm256_loadu_pd(x.as_ptr()) };
        let sign = _mm256_castsi256_pd(_mm256_set1_epi64x(SIGN as i64));
        let a = _mm256_andnot_pd(sign, x);
        let outside = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_NLE_UQ>(a, splat(RANGE)));
        let round = splat(ROUND);
        let shifted = add(mul(a, splat(std::f64::consts::FRAC_2_PI)), round);
        let k = sub(shifted, round);
        let quadrant = _mm256_sub_epi64(_mm256_castpd_si256(shifted), _mm256_castpd_si256(round));
        let r = sub(
            sub(sub(a, mul(k, splat(PIO2[0]))), mul(k, splat(PIO2[1]))),
            mul(k, splat(PIO2[2])),
        );
        let r2 = mul(r, r);
        let sin_r = add(mul(mul(r, r2), estrin(r2, &SIN_P)), r);
        let cos_r = add(
            mul(mul(r2, r2), estrin(r2, &COS_P)),
            sub(splat(1.0), mul(r2, splat(0.5))),
        );
        // Odd quadrants swap: `blendv` picks by each lane's top bit, so bit 0 goes up to it.
        let odd = _mm256_castsi256_pd(_mm256_slli_epi64::<63>(quadrant));
        let s = _mm256_blendv_pd(sin_r, cos_r, odd);
        let c = _mm256_blendv_pd(cos_r, sin_r, odd);
        let sin_sign = _mm256_and_pd(
            _mm256_xor_pd(_mm256_castsi256_pd(_mm256_slli_epi64::<62>(quadrant)), x),
            sign,
        );
        let cos_sign = _mm256_slli_epi64::<62>(_mm256_and_si256(
            _mm256_add_epi64(quadrant, _mm256_set1_epi64x(1)),
            _mm256_set1_epi64x(2),
        ));
        let (mut sin, mut cos) = ([0.0; 4], [0.0; 4]);
        // SAFETY: `sin` and `cos` hold four f64 each, which `storeu` writes unaligned.
        #[allow(unsafe_code)]
        unsafe {
            _mm256_storeu_pd(sin.as_mut_ptr(), _mm256_xor_pd(s, sin_sign));
            _mm256_storeu_pd(cos.as_mut_ptr(), _mm256_xor_pd(c, _mm256_castsi256_pd(cos_sign)));
        }
        (sin, cos, outside)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One unit in the last place of `x` (the spacing above `|x|`).
    fn ulp(x: f64) -> f64 {
        let a = x.abs();
        a.next_up() - a
    }

    /// Four-lane angles: subnormal to tiny, small, a few turns, the stamps of long records, up to
    /// the range's end.
    fn angles(seed: u64) -> Vec<[f64; 4]> {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut draws = Vec::new();
        for scale in [1e-310, 1e-6, 1.0, 10.0, 1e5, RANGE] {
            for _ in 0..10_000 {
                draws.push(std::array::from_fn(|_| scale * (2.0 * rng.random::<f64>() - 1.0)));
            }
        }
        draws
    }

    #[test]
    fn within_two_ulp_of_libm_up_to_the_range() {
        let mut worst = 0.0_f64;
        for x in angles(7) {
            let (s, c) = sin_cos_x4(x);
            for k in 0..4 {
                let (rs, rc) = x[k].sin_cos();
                worst = worst.max((s[k] - rs).abs() / ulp(rs)).max((c[k] - rc).abs() / ulp(rc));
            }
        }
        assert!(worst <= 2.0, "{worst} ulp");
        // Not libm bit for bit (else this test would not see the polynomials).
        let x = [0.1, 1.0, 2.5, 1e3];
        assert_ne!(sin_cos_x4(x).0, x.map(f64::sin));
        // Signed zeros and the quadrant edges, exactly.
        assert_eq!(sin_cos(0.0).0.to_bits(), 0.0_f64.to_bits());
        assert_eq!(sin_cos(-0.0).0.to_bits(), (-0.0_f64).to_bits());
        assert_eq!(sin_cos(0.0).1, 1.0);
        assert_eq!(sin_cos(std::f64::consts::PI).1, -1.0);
        assert_eq!(sin_cos(-std::f64::consts::FRAC_PI_2).0, -1.0);
    }

    #[test]
    fn near_the_zeros_of_sin_and_cos_within_an_absolute_bound() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(17);
        let (mut worst_abs, mut worst_ulp) = (0.0_f64, 0.0_f64);
        for _ in 0..200_000 {
            // k π/2 rounded to f64 and its neighbours, up to the range's end.
            let k = f64::from(rng.random_range(1..85_000_000_u32));
            let mut x = k * std::f64::consts::FRAC_PI_2;
            for _ in 0..rng.random_range(0..4) {
                x = if rng.random::<bool>() {
                    x.next_up()
                } else {
                    x.next_down()
                };
            }
            let ((s, c), (rs, rc)) = (sin_cos(x), x.sin_cos());
            worst_abs = worst_abs.max((s - rs).abs()).max((c - rc).abs());
            worst_ulp = worst_ulp.max((s - rs).abs() / ulp(rs)).max((c - rc).abs() / ulp(rc));
        }
        assert!(worst_abs < 1e-22, "{worst_abs}");
        // Relative to the tiny value there, the error is far beyond 2 ulp (why the bound is absolute).
        assert!(worst_ulp > 2.0, "{worst_ulp}");
    }

    #[test]
    fn beyond_the_range_the_polynomials_fail_and_libm_takes_the_lane_alone() {
        let worst = (0..1000)
            .map(|i| 1e9 + 7.3 * f64::from(i))
            .map(|x| (sin_cos(x).0 - x.sin()).abs() / ulp(x.sin()))
            .fold(0.0, f64::max);
        assert!(worst > 1e3, "{worst} ulp");
        let big = 1e12;
        let (s, c) = sin_cos_x4([0.5, big, f64::INFINITY, f64::NAN]);
        assert_eq!((s[0], c[0]), sin_cos(0.5));
        assert_eq!((s[1], c[1]), big.sin_cos());
        assert!(s[2].is_nan() && c[2].is_nan() && s[3].is_nan() && c[3].is_nan());
        let edge = [RANGE, -RANGE, RANGE.next_up(), -RANGE.next_up()];
        let (s, _) = sin_cos_x4(edge);
        assert_eq!([s[0], s[1]], [sin_cos(RANGE).0, sin_cos(-RANGE).0]);
        assert_eq!([s[2], s[3]], [edge[2].sin(), edge[3].sin()]);
    }

    #[test]
    fn four_lanes_equal_four_scalar_calls_bit_for_bit_on_every_path() {
        let same = |x: [f64; 4], (s, c): ([f64; 4], [f64; 4])| {
            for k in 0..4 {
                let (rs, rc) = sin_cos(x[k]);
                assert_eq!(
                    (s[k].to_bits(), c[k].to_bits()),
                    (rs.to_bits(), rc.to_bits()),
                    "{}",
                    x[k]
                );
            }
        };
        for x in angles(11) {
            same(x, sin_cos_x4(x));
        }
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            for x in angles(13) {
                // SAFETY: the CPU has AVX2 (checked above).
                #[allow(unsafe_code)]
                let (s, c, outside) = unsafe { avx2::sin_cos_x4(x) };
                assert_eq!(outside, 0);
                same(x, (s, c));
            }
        }
    }
}
