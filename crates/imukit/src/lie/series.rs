//! Scalar coefficients of `Exp`, `Log` and the SO(3) Jacobians, each written once.
//!
//! | function | value | series (in θ²) below | used by |
//! |---|---|---|---|
//! | [`sinc`] | `sin θ / θ` | 0.5 | Jacobians |
//! | [`rodrigues`] | `(sin θ/θ, (1 − cos θ)/θ²)` | 0.5 | `so3::exp` |
//! | [`half_angle`] | `(sin(θ/2)/θ, cos(θ/2))` from θ² | 0.5 (x = θ/2 < 0.25) | `quat::exp` |
//! | [`half_angle_small`] | the same, shorter series below θ² = 1e-4 | 1e-4, then 0.5 | the attitude filters' step |
//! | [`exp_jacobian_small`] | `(sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³)` from θ², short series below θ² = 1e-4 | 1e-4, then as [`rodrigues`] and [`theta_minus_sin_over_cube`] | `Exp` with `J_r` (preintegration, propagate) |
//! | [`one_minus_cos_over_sq`] | `(1 − cos θ)/θ² = ½ (sin(θ/2)/(θ/2))²` | via `sinc` | Jacobians |
//! | [`theta_minus_sin_over_cube`] | `(θ − sin θ)/θ³` | 0.2 | Jacobians, `Γ₂` |
//! | [`cos_remainder`] | `(θ²/2 + cos θ − 1)/θ⁴` | 0.2 | `Γ₂` |
//! | [`inv_jacobian_coefficient`] | `(1 − (θ/2) cot(θ/2))/θ²` | 0.2 | inverse Jacobians |
//! | [`atan2`] | `atan2(y, x)` | rational, not a series (Cephes) | `Robust`'s heading |
//!
//! Each switches to its Taylor series where the closed form cancels catastrophically or where a
//! series is cheaper than libm (most IMU steps have θ ≪ 1); the thresholds keep both the
//! truncation and the rounding error near 1e-15 absolute (checked in the tests against 50-digit
//! values on both sides of every switch). Series coefficients are constants: a division by a
//! literal is not folded into a multiplication and would cost more than the libm call it replaces.

/// `sin x / x = Σ (−1)ᵏ x²ᵏ/(2k+1)!` in x², through x¹².
const SINC: [f64; 7] = [
    1.0,
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
];

/// `(1 − cos x)/x² = Σ (−1)ᵏ x²ᵏ/(2k+2)!` in x², through x¹².
const ONE_MINUS_COS: [f64; 7] = [
    0.5,
    -1.0 / 24.0,
    1.0 / 720.0,
    -1.0 / 40_320.0,
    1.0 / 3_628_800.0,
    -1.0 / 479_001_600.0,
    1.0 / 87_178_291_200.0,
];

/// `cos x = Σ (−1)ᵏ x²ᵏ/(2k)!` in x², through x¹².
const COS: [f64; 7] = [
    1.0,
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
];

/// `(θ − sin θ)/θ³ = Σ (−1)ᵏ θ²ᵏ/(2k+3)!` in θ², through θ⁸.
const THETA_MINUS_SIN: [f64; 5] = [
    1.0 / 6.0,
    -1.0 / 120.0,
    1.0 / 5_040.0,
    -1.0 / 362_880.0,
    1.0 / 39_916_800.0,
];

/// `atan t = t + t³ P(t²)/Q(t²)` on `|t| ≤ 0.66`: Cephes' rational approximation (S. L. Moshier,
/// Cephes Math Library 2.8, `atan.c`; relative error ~1e-16), lowest power first; `Q` is monic.
#[allow(clippy::excessive_precision)] // quoted as published
const ATAN_P: [f64; 5] = [
    -6.485_021_904_942_025_371_773e1,
    -1.228_866_684_490_136_173_410e2,
    -7.500_855_792_314_704_667_340e1,
    -1.615_753_718_733_365_076_637e1,
    -8.750_608_600_031_904_122_785e-1,
];
#[allow(clippy::excessive_precision)] // quoted as published
const ATAN_Q: [f64; 6] = [
    1.945_506_571_482_613_964_425e2,
    4.853_903_996_359_136_964_868e2,
    4.328_810_604_912_902_668_951e2,
    1.650_270_098_316_988_542_046e2,
    2.485_846_490_142_306_297_962e1,
    1.0,
];

/// `Σ cₖ xᵏ` by Horner's rule (N ≥ 1). Started at the last coefficient, not at `0·x + c`: the
/// compiler may not fold `0·x` (it is NaN for an infinite x), and that step was a multiply and
/// an add on every series' dependency chain.
#[inline(always)]
fn horner<const N: usize>(x: f64, c: &[f64; N]) -> f64 {
    let mut acc = c[N - 1];
    for k in (0..N - 1).rev() {
        acc = acc * x + c[k];
    }
    acc
}

/// [`horner`] on the first `K` coefficients of `c` (all of them if `K > N`).
#[inline(always)]
fn horner_head<const K: usize, const N: usize>(x: f64, c: &[f64; N]) -> f64 {
    match c.first_chunk::<K>() {
        Some(head) => horner(x, head),
        None => horner(x, c),
    }
}

/// The Taylor series `c` (in θ²) below `switch`, else the closed form.
#[inline(always)]
fn taylor_below<const N: usize>(theta: f64, switch: f64, c: &[f64; N], closed: impl FnOnce() -> f64) -> f64 {
    if theta < switch {
        horner(theta * theta, c)
    } else {
        closed()
    }
}

/// `sin θ / θ` (series below θ = 0.5, first omitted term < 5e-17).
#[inline]
pub fn sinc(theta: f64) -> f64 {
    taylor_below(theta, 0.5, &SINC, || theta.sin() / theta)
}

/// `(sin θ/θ, (1 − cos θ)/θ²)`, the Rodrigues coefficients of `Exp(φ) = I + a [φ]× + b [φ]×²`.
/// Series below θ = 0.5 (first omitted terms below 5e-17); above, one `sin_cos` of θ/2 gives
/// both: `sin θ = 2 s c`, `1 − cos θ = 2 s²`.
#[inline]
pub fn rodrigues(theta: f64) -> (f64, f64) {
    if theta < 0.5 {
        let t = theta * theta;
        (horner(t, &SINC), horner(t, &ONE_MINUS_COS))
    } else {
        let (s, c) = (0.5 * theta).sin_cos();
        let s_over = s / theta;
        (2.0 * c * s_over, 2.0 * s_over * s_over)
    }
}

/// `(sin(θ/2)/θ, cos(θ/2))` from `θ²`: the quaternion `Exp(φ) = [φ sin(θ/2)/θ, cos(θ/2)]`. Below
/// θ² = 0.25 a series in `x² = θ²/4` (sin x/x through x¹⁰, cos x through x¹²; the first omitted
/// terms are below 1e-17 relative), which needs neither a square root nor a libm call.
#[inline]
pub fn half_angle(theta_sq: f64) -> (f64, f64) {
    if theta_sq < 0.25 {
        let x2 = 0.25 * theta_sq;
        (0.5 * horner_head::<6, 7>(x2, &SINC), horner(x2, &COS))
    } else {
        let theta = theta_sq.sqrt();
        let (s, c) = (0.5 * theta).sin_cos();
        (s / theta, c)
    }
}

/// [`half_angle`] with shorter series below θ² = 1e-4 (θ < 0.01 rad, an attitude filter's gyro
/// step at 100 Hz up to 1 rad/s): in `x² = θ²/4 < 2.5e-5`, sin x/x through x⁴ and cos x through
/// x⁶, whose first omitted terms are below 4e-18 and 1e-23, a quarter of the last bit at most;
/// two and three multiply-adds on the dependency chain instead of five and six. Above, [`half_angle`].
#[inline(always)]
pub fn half_angle_small(theta_sq: f64) -> (f64, f64) {
    if theta_sq < 1e-4 {
        let x2 = 0.25 * theta_sq;
        (0.5 * horner_head::<3, 7>(x2, &SINC), horner_head::<4, 7>(x2, &COS))
    } else {
        half_angle(theta_sq)
    }
}

/// `(sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³)` from `θ²`, the coefficients `Exp` and `J_r` share
/// (`so3::exp_and_right_jacobian`). Below θ² = 1e-4 (θ < 0.01 rad, a preintegration step at
/// 200 Hz up to 2 rad/s) short series in θ², through θ⁶, θ⁴ and θ⁴: the first omitted terms,
/// θ⁸/9!, θ⁶/8! and θ⁶/9!, are below 3e-22, 3e-17 and 3e-18, a quarter of the last bit of each
/// coefficient at most. No square root is taken there (the closed forms need θ itself), and each
/// chain is three multiply-adds at most where [`rodrigues`] and [`theta_minus_sin_over_cube`] take
/// a square root and six. Above, those two.
#[inline(always)]
pub fn exp_jacobian_small(theta_sq: f64) -> (f64, f64, f64) {
    if theta_sq < 1e-4 {
        (
            horner_head::<4, 7>(theta_sq, &SINC),
            horner_head::<3, 7>(theta_sq, &ONE_MINUS_COS),
            horner_head::<3, 5>(theta_sq, &THETA_MINUS_SIN),
        )
    } else {
        let theta = theta_sq.sqrt();
        let (a, b) = rodrigues(theta);
        (a, b, theta_minus_sin_over_cube(theta))
    }
}

/// `(1 − cos θ)/θ² = ½ (sin(θ/2)/(θ/2))²`, written with the half angle to avoid cancellation.
#[inline]
pub fn one_minus_cos_over_sq(theta: f64) -> f64 {
    let s = sinc(0.5 * theta);
    0.5 * s * s
}

/// `(θ − sin θ)/θ³ = Σ (−1)ᵏ θ²ᵏ/(2k+3)!`.
#[inline]
pub fn theta_minus_sin_over_cube(theta: f64) -> f64 {
    taylor_below(theta, 0.2, &THETA_MINUS_SIN, || {
        (theta - theta.sin()) / (theta * theta * theta)
    })
}

/// `(θ²/2 + cos θ − 1)/θ⁴ = (½ − (1 − cos θ)/θ²)/θ² = Σ (−1)ᵏ θ²ᵏ/(2k+4)!`.
#[inline]
pub fn cos_remainder(theta: f64) -> f64 {
    const C: [f64; 5] = [
        1.0 / 24.0,
        -1.0 / 720.0,
        1.0 / 40_320.0,
        -1.0 / 3_628_800.0,
        1.0 / 479_001_600.0,
    ];
    taylor_below(theta, 0.2, &C, || {
        (0.5 - one_minus_cos_over_sq(theta)) / (theta * theta)
    })
}

/// `atan2(y, x)` within about 1 ulp, in ~40 instructions where libm's takes ~140 (the 9D
/// `Robust` step's costliest call). `|y|, |x|` are reduced to `t ∈ [−0.66, 0.66]` as Cephes does
/// (`t = a/b`; up to `a/b = tan 3π/8` `(a − b)/(a + b)` plus π/4, above `−b/a` plus π/2, the
/// constants' low bits added to the small part), then `ATAN_P`/`ATAN_Q`, then the quadrant.
/// Both zero, infinities and NaN go to libm (its special cases).
#[inline(always)]
pub fn atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    /// π/2 − `FRAC_PI_2`: the low bits of π/2.
    const PI_2_LOW: f64 = 6.123_233_995_736_766e-17;
    const TAN_3PI_8: f64 = 2.414_213_562_373_095;
    let (a, b) = (y.abs(), x.abs());
    if !(a.is_finite() && b.is_finite() && (a > 0.0 || b > 0.0)) {
        return y.atan2(x);
    }
    let (base, low, t) = if a > TAN_3PI_8 * b {
        (FRAC_PI_2, PI_2_LOW, -b / a)
    } else if a <= 0.66 * b {
        (0.0, 0.0, a / b)
    } else {
        (FRAC_PI_4, 0.5 * PI_2_LOW, (a - b) / (a + b))
    };
    let z = t * t;
    let angle = base + (t + t * (z * horner(z, &ATAN_P) / horner(z, &ATAN_Q)) + low);
    let angle = if x < 0.0 { PI - angle } else { angle };
    angle.copysign(y)
}

/// `(1 − (θ/2) cot(θ/2))/θ²`, equal to `1/θ² − (1 + cos θ)/(2 θ sin θ)` but finite at θ = π.
#[inline]
pub fn inv_jacobian_coefficient(theta: f64) -> f64 {
    // (1 − x cot x)/(4x²) with x = θ/2, from x cot x = 1 − Σ 4ⁿ|B₂ₙ| x²ⁿ/(2n)!.
    const C: [f64; 5] = [
        1.0 / 12.0,
        1.0 / 720.0,
        1.0 / 30_240.0,
        1.0 / 1_209_600.0,
        1.0 / 47_900_160.0,
    ];
    taylor_below(theta, 0.2, &C, || {
        let half = 0.5 * theta;
        (1.0 - half * half.cos() / half.sin()) / (theta * theta)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values of the coefficients computed with 50-digit arithmetic (mpmath) at points
    /// on both sides of each series/closed-form switch.
    #[test]
    #[allow(clippy::excessive_precision)] // the references are quoted as computed
    fn coefficients_match_high_precision_values() {
        // (θ, (1−cosθ)/θ², (θ−sinθ)/θ³, (1−(θ/2)cot(θ/2))/θ²), 19 significant digits
        let cases = [
            (
                1e-8,
                0.4999999999999999958,
                0.1666666666666666658,
                0.08333333333333333347,
            ),
            (
                0.199_999,
                0.498335570591187701,
                0.1663336539443291972,
                0.0833889412952914013,
            ),
            (
                0.200_001,
                0.4983355373466480749,
                0.1663336472903503664,
                0.08338894240852209342,
            ),
            (
                3.0,
                0.2211102774000494953,
                0.1058844441459308436,
                0.09929197039400236965,
            ),
            (
                std::f64::consts::PI,
                0.2026423672846755429,
                0.1013211836423377714,
                0.1013211836423377714,
            ),
        ];
        for (theta, d) in [
            (1e-8, 0.041_666_666_666_666_666_53),
            (0.199_999, 0.041_611_151_330_780_503_33),
            (0.200_001, 0.041_611_150_221_255_636_03),
            (3.0, 0.030_987_746_955_550_056_08),
        ] {
            assert!((cos_remainder(theta) - d).abs() < 3e-15, "d at {theta}");
        }
        for (theta, a, b, c) in cases {
            assert!((one_minus_cos_over_sq(theta) - a).abs() < 1e-15, "a at {theta}");
            assert!((theta_minus_sin_over_cube(theta) - b).abs() < 3e-15, "b at {theta}");
            assert!((inv_jacobian_coefficient(theta) - c).abs() < 3e-15, "c at {theta}");
        }
    }

    /// `atan2` against 50-digit values (mpmath) on both sides of each reduction's switch
    /// (`|y/x|` = 0.66 and tan 3π/8) and in every quadrant, within 1 ulp; and against libm (an
    /// independent implementation) within 2 ulp on a sweep of 20,001 directions of all sizes.
    #[test]
    #[allow(clippy::excessive_precision)] // the references are quoted as computed
    fn atan2_matches_high_precision_values() {
        for (y, x, angle) in [
            (1e-8, 1.0, 9.9999999999999998759e-9),
            (0.6599999, 1.0, 0.58337293733656656591),
            (0.6600001, 1.0, 0.58337307665113887418),
            (2.4142134, 1.0, 1.1780972213171818638),
            (2.4142137, 1.0, 1.1780972652511650633),
            (3.0, -1.0, 1.8925468811915388126),
            (-0.2, -3.1, -3.0771658141642396861),
            (-1.0, 0.5, -1.107148717794090503),
            (1.0, 0.0, std::f64::consts::FRAC_PI_2),
            (0.0, -2.0, std::f64::consts::PI),
            (1e300, 1e-300, std::f64::consts::FRAC_PI_2),
        ] {
            let got = atan2(y, x);
            assert!(
                (got - angle).abs() <= f64::EPSILON * angle.abs(),
                "atan2({y}, {x}) = {got}"
            );
        }
        assert_eq!(atan2(-0.0, 1.0).to_bits(), (-0.0f64).to_bits());
        assert!(atan2(f64::NAN, 1.0).is_nan());
        for k in -10_000..=10_000 {
            let phi = f64::from(k) * 3.0 / 10_000.0;
            let scale = 10f64.powi(k % 7 * 40);
            let (y, x) = (phi.sin() * scale, phi.cos() * scale);
            let want = y.atan2(x);
            let got = atan2(y, x);
            assert!(
                (got - want).abs() <= 2.0 * f64::EPSILON * want.abs(),
                "atan2({y}, {x}) = {got}, libm {want}"
            );
        }
    }

    /// Both branches of the half-angle coefficients, and the short series of `half_angle_small`
    /// on both sides of its switch (θ = 0.01), against 50-digit values (mpmath): within the last
    /// bit of the values.
    #[test]
    #[allow(clippy::excessive_precision)] // the references are quoted as computed
    fn half_angle_matches_high_precision_values() {
        // (θ, sin(θ/2)/θ, cos(θ/2))
        let cases = [
            (1e-8, 0.4999999999999999979167, 0.9999999999999999875),
            (0.003, 0.4999998125000210937489, 0.9999988750002109374842),
            (0.0099999, 0.4999979167109371859516, 0.9999875002760393533155),
            (0.0100001, 0.4999979166276040609514, 0.9999874997760414366463),
            (0.1, 0.4997916927067832879487, 0.9987502603949662465629),
            (0.4999, 0.4948099886461344949577, 0.9689247906974618291559),
            (0.5001, 0.4948058479630740395059, 0.9689000503015466853613),
            (3.0, 0.3324983288680181436472, 0.07073720166770291008819),
        ];
        for f in [half_angle, half_angle_small] {
            for (theta, k, w) in cases {
                let (k_ours, w_ours) = f(theta * theta);
                assert!((k_ours - k).abs() < 2e-16, "sin(θ/2)/θ at {theta}: {k_ours} vs {k}");
                assert!((w_ours - w).abs() < 2e-16, "cos(θ/2) at {theta}: {w_ours} vs {w}");
            }
        }
    }

    /// `exp_jacobian_small` on both sides of its switch (θ = 0.01) and of the closed forms' own
    /// (θ = 0.2 and 0.5), against 50-digit values (mpmath): within the last bit of the values.
    #[test]
    #[allow(clippy::excessive_precision)] // the references are quoted as computed
    fn exp_jacobian_small_matches_high_precision_values() {
        // (θ, sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³)
        let cases = [
            (
                1e-8,
                0.9999999999999999833333,
                0.4999999999999999958333,
                0.1666666666666666658333,
            ),
            (
                0.003,
                0.9999985000006749998554,
                0.4999996250001124999819,
                0.1666665916666827380932,
            ),
            (
                0.0099999,
                0.9999833337499948016495,
                0.4999958334305545585416,
                0.1666658333519839615313,
            ),
            (
                0.0100001,
                0.9999833330833348016257,
                0.4999958332638890029831,
                0.1666658333186507869278,
            ),
            (
                0.1,
                0.9983341664682815230681,
                0.4995834721974233904438,
                0.1665833531718476931858,
            ),
            (
                0.199_999,
                0.993346720375522076189,
                0.498335570591187701,
                0.1663336539443291972,
            ),
            (
                0.200_001,
                0.9933465875747607355578,
                0.4983355373466480749,
                0.1663336472903503664,
            ),
            (
                0.4999,
                0.9588673293679386592089,
                0.4896738497279754956206,
                0.1645965145502048631016,
            ),
            (
                0.5001,
                0.9588348219618437967631,
                0.4896656543569134832207,
                0.164594867621781395518,
            ),
            (
                3.0,
                0.04704000268662240736691,
                0.2211102774000494952524,
                0.1058844441459308436259,
            ),
        ];
        for (theta, a, b, c) in cases {
            let (a_ours, b_ours, c_ours) = exp_jacobian_small(theta * theta);
            assert!((a_ours - a).abs() < 2.3e-16, "sin θ/θ at {theta}: {a_ours} vs {a}");
            assert!(
                (b_ours - b).abs() < 1.2e-16,
                "(1 − cos θ)/θ² at {theta}: {b_ours} vs {b}"
            );
            assert!((c_ours - c).abs() < 3e-15, "(θ − sin θ)/θ³ at {theta}: {c_ours} vs {c}");
        }
    }

    /// The Rodrigues pair on both sides of its switch, against the half-angle forms (which
    /// agree with the 50-digit values above) and the Jacobians' `(1 − cos θ)/θ²`.
    #[test]
    fn rodrigues_agrees_with_the_other_forms_on_both_sides_of_its_switch() {
        for theta in [1e-8, 0.1, 0.499_999, 0.500_001, 2.0, std::f64::consts::PI] {
            let (a, b) = rodrigues(theta);
            let (k, w) = half_angle(theta * theta);
            assert!((a - 2.0 * k * w).abs() < 1e-15, "sin θ/θ at {theta}");
            assert!((a - sinc(theta)).abs() < 1e-15, "sinc at {theta}");
            assert!((b - one_minus_cos_over_sq(theta)).abs() < 1e-15, "b at {theta}");
        }
    }
}
