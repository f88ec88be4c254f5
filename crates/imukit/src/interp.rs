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
