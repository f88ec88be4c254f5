//! Reverse-mode derivatives of `Exp(φ)` and `J_r(φ)`.
//!
//! Both are `f(φ) = I + c₁(t) K + c₂(t) K²` with `K = [φ]×`, `t = θ² = |φ|²` (Solà, Deray &
//! Atchuthan 2018, eqs. 143 and 183): `Exp` with `(c₁, c₂) = (A, B)`, `J_r` with `(−B, C)`,
//! `A = sin θ/θ`, `B = (1 − cos θ)/θ²`, `C = (θ − sin θ)/θ³`. For a cotangent `M̄` (the gradient of
//! a scalar loss with respect to the matrix), differentiating each term gives
//! `φ̄ = 2φ (c₁'⟨M̄, K⟩ + c₂'⟨M̄, K²⟩) + c₁ vee₂(M̄) − c₂ vee₂(M̄K + KM̄)`, with `'` = d/dt,
//! `⟨·,·⟩` the Frobenius product and `vee₂(M) = vee(M − Mᵀ)` (so that `⟨M, [u]×⟩ = u·vee₂(M)`).
//! Below θ = 0.5 the coefficients and their derivatives come from their Taylor series in t (the
//! closed forms cancel there), so φ = 0 (a padded step) is exact.

use nalgebra::{Matrix3, Vector3};

use crate::so3::hat;

/// Where the closed forms' cancellation (≈ 10⁻¹⁷/t² relative in `C'`, from `θ − sin θ`) meets the
/// truncation of [`SERIES_TERMS`] terms (< 10⁻¹⁵ relative): θ = 0.5.
const SERIES_BELOW: f64 = 0.25;
const SERIES_TERMS: usize = 10;

/// `(−1)ᵏ/(2k + m)!` for k < [`SERIES_TERMS`], at compile time (the series are evaluated once
/// per interval and way: no factorial or power at run time).
const fn series_coefficients(m: usize) -> [f64; SERIES_TERMS] {
    let mut c = [0.0; SERIES_TERMS];
    let mut inv_factorial = 1.0;
    let mut i = 2;
    while i <= m {
        inv_factorial /= i as f64;
        i += 1;
    }
    let mut k = 0;
    while k < SERIES_TERMS {
        c[k] = if k % 2 == 0 { inv_factorial } else { -inv_factorial };
        inv_factorial /= ((2 * k + m + 1) * (2 * k + m + 2)) as f64;
        k += 1;
    }
    c
}

/// The series of A (m = 1), B (m = 2), C (m = 3).
const SERIES: [[f64; SERIES_TERMS]; 3] = [series_coefficients(1), series_coefficients(2), series_coefficients(3)];

/// `Σₖ cₖtᵏ` and its derivative in t, by Horner's rule.
fn series(t: f64, c: &[f64; SERIES_TERMS]) -> (f64, f64) {
    let (mut value, mut slope) = (0.0, 0.0);
    for (k, &ck) in c.iter().enumerate().rev() {
        value = value * t + ck;
        if k > 0 {
            slope = slope * t + k as f64 * ck;
        }
    }
    (value, slope)
}

/// `A, B, C` and their derivatives in `t = θ²`.
#[derive(Debug, Clone, Copy)]
struct Coefficients {
    a: f64,
    b: f64,
    c: f64,
    a_t: f64,
    b_t: f64,
    c_t: f64,
}

fn coefficients(t: f64) -> Coefficients {
    if t < SERIES_BELOW {
        let ((a, a_t), (b, b_t), (c, c_t)) = (series(t, &SERIES[0]), series(t, &SERIES[1]), series(t, &SERIES[2]));
        return Coefficients { a, b, c, a_t, b_t, c_t };
    }
    let th = t.sqrt();
    let (s, co) = th.sin_cos();
    // 1 − cos θ = 2 sin²(θ/2): no cancellation.
    let half = (0.5 * th).sin();
    let (one_minus_cos, th_minus_sin) = (2.0 * half * half, th - s);
    Coefficients {
        a: s / th,
        b: one_minus_cos / t,
        c: th_minus_sin / (t * th),
        a_t: (th * co - s) / (2.0 * t * th),
        b_t: (th * s - 2.0 * one_minus_cos) / (2.0 * t * t),
        c_t: one_minus_cos / (2.0 * t * t) - 3.0 * th_minus_sin / (2.0 * t * t * th),
    }
}

/// `vee(M − Mᵀ)`: `⟨M, [u]×⟩ = u · vee₂(M)`.
pub(super) fn vee2(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(m[(2, 1)] - m[(1, 2)], m[(0, 2)] - m[(2, 0)], m[(1, 0)] - m[(0, 1)])
}

/// `φ̄` of `f(φ) = I + c₁K + c₂K²` (module docs).
fn pullback(phi: &Vector3<f64>, k: &Matrix3<f64>, c: [f64; 4], bar: &Matrix3<f64>) -> Vector3<f64> {
    let [c1, c2, c1_t, c2_t] = c;
    let k2 = k * k;
    phi * (2.0 * (c1_t * bar.dot(k) + c2_t * bar.dot(&k2))) + vee2(bar) * c1 - vee2(&(bar * k + k * bar)) * c2
}

/// `φ̄` given the cotangents of `Exp(φ)` and of `J_r(φ)`.
pub(super) fn exp_and_jacobian_pullback(
    phi: &Vector3<f64>,
    exp_bar: &Matrix3<f64>,
    jr_bar: &Matrix3<f64>,
) -> Vector3<f64> {
    let co = coefficients(phi.norm_squared());
    let k = hat(phi);
    pullback(phi, &k, [co.a, co.b, co.a_t, co.b_t], exp_bar) + pullback(phi, &k, [-co.b, co.c, -co.b_t, co.c_t], jr_bar)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3::{exp, right_jacobian};

    /// Central differences of `⟨M̄, f(φ)⟩` against the pullback, at small, medium and large angles
    /// (both sides of the series switch).
    #[test]
    fn pullback_matches_central_differences() {
        let exp_bar = Matrix3::new(0.3, -1.2, 0.5, 0.7, 0.1, -0.4, 1.1, 0.2, -0.9);
        let jr_bar = Matrix3::new(-0.6, 0.8, 0.2, 0.4, -1.3, 0.9, 0.05, 0.6, 0.3);
        for scale in [0.0, 1e-4, 0.02, 0.0317, 0.5, 2.5] {
            let phi = Vector3::new(0.3, -0.8, 0.52) * scale;
            let loss = |p: &Vector3<f64>| exp_bar.dot(exp(p).matrix()) + jr_bar.dot(&right_jacobian(p));
            let got = exp_and_jacobian_pullback(&phi, &exp_bar, &jr_bar);
            let eps = 1e-6;
            for i in 0..3 {
                let mut d = Vector3::zeros();
                d[i] = eps;
                let numeric = (loss(&(phi + d)) - loss(&(phi - d))) / (2.0 * eps);
                assert!(
                    (numeric - got[i]).abs() < 1e-8,
                    "scale {scale} axis {i}: {numeric} vs {}",
                    got[i]
                );
            }
        }
    }

    /// The coefficients' series and closed forms agree at the switch.
    #[test]
    fn series_meets_closed_form() {
        let below = coefficients(SERIES_BELOW * (1.0 - 1e-12));
        let above = coefficients(SERIES_BELOW * (1.0 + 1e-12));
        let pairs = [
            (below.a, above.a),
            (below.b, above.b),
            (below.c, above.c),
            (below.a_t, above.a_t),
            (below.b_t, above.b_t),
            (below.c_t, above.c_t),
        ];
        for (s, c) in pairs {
            assert!((s - c).abs() < 1e-11 * c.abs(), "{s} vs {c}");
        }
    }
}
