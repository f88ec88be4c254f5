//! Rates between samples: the local cubic through the neighbouring samples.
//!
//! A gyro delivers samples, not a function. Integrators of order above two need the rate inside a
//! step; a straight line between the two end samples is only second-order accurate, so any scheme
//! fed by it is at most second order. The cubic through samples `k−1 … k+2` (shifted to stay
//! inside the data at the ends; lower degree when fewer than four samples exist) is fourth-order
//! accurate for smooth motion, uniform spacing or not. See `docs/attitude.md`.

use nalgebra::Vector3;

/// Lagrange interpolation of 3-vectors over a time series.
#[derive(Debug, Clone, Copy)]
pub struct Cubic<'a> {
    t: &'a [f64],
    values: &'a [f64],
}

impl<'a> Cubic<'a> {
    /// `t` (length n, strictly increasing) and `values` (flat, 3n).
    pub fn new(t: &'a [f64], values: &'a [f64]) -> Self {
        Self { t, values }
    }

    fn value(&self, j: usize) -> Vector3<f64> {
        Vector3::new(self.values[3 * j], self.values[3 * j + 1], self.values[3 * j + 2])
    }

    /// Values at `t[k] + tau[i]` for offsets inside step k (`0 ≤ tau ≤ t[k+1] − t[k]`).
    #[inline]
    pub fn at<const M: usize>(&self, k: usize, tau: [f64; M]) -> [Vector3<f64>; M] {
        let n = self.t.len();
        if n < 4 {
            return self.at_low_degree(k, tau);
        }
        // Stencil k−1 … k+2, shifted to stay inside the data; offsets from t[k] keep the
        // numbers small and well-conditioned. Plain arithmetic on purpose: this is the hot path
        // of rk4 and magnus, and iterator adaptors here cost three times the instructions.
        let s = k.saturating_sub(1).min(n - 4);
        let (t, v, tk) = (&self.t[s..s + 4], &self.values[3 * s..3 * s + 12], self.t[k]);
        let (p0, p1, p2, p3) = (t[0] - tk, t[1] - tk, t[2] - tk, t[3] - tk);
        let v0 = Vector3::new(v[0], v[1], v[2]);
        let v1 = Vector3::new(v[3], v[4], v[5]);
        let v2 = Vector3::new(v[6], v[7], v[8]);
        let v3 = Vector3::new(v[9], v[10], v[11]);
        let (d01, d02, d03) = (p0 - p1, p0 - p2, p0 - p3);
        let (d12, d13, d23) = (p1 - p2, p1 - p3, p2 - p3);
        // 1 / Π_{i≠j} (p_j − p_i)
        let inv0 = 1.0 / (d01 * d02 * d03);
        let inv1 = -1.0 / (d01 * d12 * d13);
        let inv2 = 1.0 / (d02 * d12 * d23);
        let inv3 = -1.0 / (d03 * d13 * d23);
        let mut out = [Vector3::zeros(); M];
        for (o, x) in out.iter_mut().zip(tau) {
            let (e0, e1, e2, e3) = (x - p0, x - p1, x - p2, x - p3);
            let (e01, e23) = (e0 * e1, e2 * e3);
            *o = v0 * (e1 * e23 * inv0) + v1 * (e0 * e23 * inv1) + v2 * (e01 * e3 * inv2) + v3 * (e01 * e2 * inv3);
        }
        out
    }

    /// Lagrange through all (fewer than four) samples.
    fn at_low_degree<const M: usize>(&self, k: usize, tau: [f64; M]) -> [Vector3<f64>; M] {
        let nodes: Vec<f64> = self.t.iter().map(|t| t - self.t[k]).collect();
        tau.map(|x| {
            let mut acc = Vector3::zeros();
            for (j, tj) in nodes.iter().enumerate() {
                let weight: f64 = nodes
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != j)
                    .map(|(_, ti)| (x - ti) / (tj - ti))
                    .product();
                acc += self.value(j) * weight;
            }
            acc
        })
    }
}

/// Spacing irregularity below which a stencil counts as uniform: with nodes off by at most
/// `1e-9 h`, the interpolated rate moves by about `1e-9 h |ω̇|`, five orders of magnitude below the
/// cubic's own `O(h⁴)` error at IMU rates, while float timestamps like `k · 0.005` (whose steps
/// differ in the last bits) still take the fast path.
const UNIFORM_TOLERANCE: f64 = 1e-9;

/// Spacing ratio (longest over shortest step of a stencil) above which a step takes the straight
/// line between its own two samples instead of the cubic: across a gap the cubic's nodes come in
/// far-apart pairs, its weights grow to ±25 and it amplifies sensor noise tenfold. Jittered
/// sampling (ratios up to ~3) keeps the cubic.
const MAX_SPACING_RATIO: f64 = 4.0;

/// The cubic evaluated at fixed fractions `u` of every step (`t[k] + u h_k`), with the Lagrange
/// weights of uniformly spaced stencils computed once instead of once per step.
#[derive(Debug, Clone)]
pub struct StepInterpolator<'a, const M: usize> {
    cubic: Cubic<'a>,
    fractions: [f64; M],
    /// `weights[o][i][j]`: weight of node j at fraction i for the stencil starting at `k − o`
    /// (o = 0 first step, 1 interior, 2 last step), on unit spacing.
    weights: [[[f64; 4]; M]; 3],
}

impl<'a, const M: usize> StepInterpolator<'a, M> {
    /// Interpolates `cubic` at `t[k] + fractions[i] (t[k+1] − t[k])`.
    pub fn new(cubic: Cubic<'a>, fractions: [f64; M]) -> Self {
        let weights = [0usize, 1, 2].map(|o| {
            fractions.map(|u| {
                let node = |j: usize| j as f64 - o as f64;
                std::array::from_fn(|j| {
                    (0..4)
                        .filter(|&i| i != j)
                        .map(|i| (u - node(i)) / (node(j) - node(i)))
                        .product()
                })
            })
        });
        Self {
            cubic,
            fractions,
            weights,
        }
    }

    /// Values at the fractions of step k.
    #[inline]
    pub fn at(&self, k: usize) -> [Vector3<f64>; M] {
        let t = self.cubic.t;
        let n = t.len();
        let h = t[k + 1] - t[k];
        if n >= 4 {
            let s = k.saturating_sub(1).min(n - 4);
            let g = &t[s..s + 4];
            let tol = UNIFORM_TOLERANCE * h;
            if ((g[1] - g[0]) - h).abs() <= tol && ((g[2] - g[1]) - h).abs() <= tol && ((g[3] - g[2]) - h).abs() <= tol
            {
                let v = &self.cubic.values[3 * s..3 * s + 12];
                let mut out = [Vector3::zeros(); M];
                // A plain loop: `array::from_fn` here compiled to three times the instructions.
                for (o, w) in out.iter_mut().zip(&self.weights[k - s]) {
                    *o = Vector3::new(
                        w[0] * v[0] + w[1] * v[3] + w[2] * v[6] + w[3] * v[9],
                        w[0] * v[1] + w[1] * v[4] + w[2] * v[7] + w[3] * v[10],
                        w[0] * v[2] + w[1] * v[5] + w[2] * v[8] + w[3] * v[11],
                    );
                }
                return out;
            }
        }
        if n >= 4 {
            let s = k.saturating_sub(1).min(n - 4);
            let g = &t[s..s + 4];
            let steps = [g[1] - g[0], g[2] - g[1], g[3] - g[2]];
            let (lo, hi) = steps
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), d| (lo.min(*d), hi.max(*d)));
            if hi > MAX_SPACING_RATIO * lo {
                let (v0, v1) = (self.cubic.value(k), self.cubic.value(k + 1));
                return self.fractions.map(|u| v0 + (v1 - v0) * u);
            }
        }
        let mut tau = self.fractions;
        tau.iter_mut().for_each(|u| *u *= h);
        self.cubic.at(k, tau)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cubic reproduces any cubic polynomial exactly, on non-uniform times, at both ends.
    #[test]
    fn reproduces_cubics() {
        let t = [0.0, 0.3, 0.45, 1.0, 1.2, 1.9];
        let f = |x: f64| Vector3::new(1.0 + 2.0 * x - x * x * x, x * x, -3.0 * x * x * x + 0.5);
        let values: Vec<f64> = t
            .iter()
            .flat_map(|&x| f(x).iter().copied().collect::<Vec<_>>())
            .collect();
        let cubic = Cubic::new(&t, &values);
        for k in 0..t.len() - 1 {
            let h = t[k + 1] - t[k];
            let [a, b] = cubic.at(k, [0.25 * h, 0.8 * h]);
            assert!((a - f(t[k] + 0.25 * h)).norm() < 1e-13, "k={k}");
            assert!((b - f(t[k] + 0.8 * h)).norm() < 1e-13, "k={k}");
        }
    }

    /// The step interpolator matches the general cubic on uniform, nearly uniform and irregular
    /// spacing, at interior and end steps.
    #[test]
    fn step_interpolator_matches_the_cubic() {
        let f = |x: f64| Vector3::new((1.3 * x).sin(), (0.7 * x).cos(), x * x * x - x);
        for jitter in [0.0, 1e-12, 0.3] {
            // (spacing ratios stay below MAX_SPACING_RATIO here, so the cubic is used throughout)
            let t: Vec<f64> = (0..12)
                .map(|k| k as f64 * 0.01 + jitter * 0.01 * ((k * k) as f64).sin())
                .collect();
            let values: Vec<f64> = t
                .iter()
                .flat_map(|&x| f(x).iter().copied().collect::<Vec<_>>())
                .collect();
            let cubic = Cubic::new(&t, &values);
            let fractions = [0.2113, 0.5, 0.7887];
            let fast = StepInterpolator::new(cubic, fractions);
            for k in 0..t.len() - 1 {
                let h = t[k + 1] - t[k];
                let expected = cubic.at(k, fractions.map(|u| u * h));
                for (a, b) in fast.at(k).iter().zip(expected.iter()) {
                    assert!((a - b).norm() < 1e-13, "jitter {jitter}, k {k}: {a} vs {b}");
                }
            }
        }
    }

    /// Across a gap (spacing ratio above 4) a step uses the straight line between its samples.
    #[test]
    fn gaps_fall_back_to_the_line() {
        let t = [0.0, 0.01, 0.02, 1.0, 1.01, 1.02];
        let values: Vec<f64> = t.iter().flat_map(|&x| [x * x, 1.0, -x]).collect();
        let fast = StepInterpolator::new(Cubic::new(&t, &values), [0.5]);
        for k in [1, 2, 3] {
            let [mid] = fast.at(k);
            let (a, b) = (
                Vector3::new(t[k] * t[k], 1.0, -t[k]),
                Vector3::new(t[k + 1] * t[k + 1], 1.0, -t[k + 1]),
            );
            assert!((mid - (a + b) * 0.5).norm() < 1e-15, "k = {k}");
        }
    }

    /// With two samples the interpolant is the straight line, with three the parabola.
    #[test]
    fn two_samples_give_a_line() {
        let t = [1.0, 3.0];
        let values = [0.0, 2.0, 4.0, 2.0, 2.0, 2.0];
        let [mid] = Cubic::new(&t, &values).at(0, [1.0]);
        assert!((mid - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-15);
        let t = [0.0, 1.0, 3.0];
        let values = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 9.0, 9.0, 9.0]; // x²
        let [a] = Cubic::new(&t, &values).at(1, [0.5]);
        assert!((a - Vector3::repeat(2.25)).norm() < 1e-14);
    }
}
