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
    pub fn at<const M: usize>(&self, k: usize, tau: [f64; M]) -> [Vector3<f64>; M] {
        let n = self.t.len();
        let m = n.min(4);
        // Stencil start: k−1, clamped so the stencil [s, s+m) stays inside the data.
        let s = k.saturating_sub(1).min(n - m);
        let mut nodes = [0.0; 4];
        for (j, node) in nodes.iter_mut().enumerate().take(m) {
            // Offsets from t[k] keep the numbers small and well-conditioned.
            *node = self.t[s + j] - self.t[k];
        }
        let nodes = &nodes[..m];
        let mut inv_denominators = [0.0; 4];
        for (j, (inv, tj)) in inv_denominators.iter_mut().zip(nodes).enumerate() {
            let product: f64 = nodes
                .iter()
                .enumerate()
                .filter(|&(i, _)| i != j)
                .map(|(_, ti)| tj - ti)
                .product();
            *inv = 1.0 / product;
        }
        tau.map(|x| {
            let mut acc = Vector3::zeros();
            for (j, inv) in inv_denominators.iter().take(m).enumerate() {
                let numerator: f64 = nodes
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != j)
                    .map(|(_, ti)| x - ti)
                    .product();
                acc += self.value(s + j) * (numerator * inv);
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

    /// With two samples the interpolant is the straight line.
    #[test]
    fn two_samples_give_a_line() {
        let t = [1.0, 3.0];
        let values = [0.0, 2.0, 4.0, 2.0, 2.0, 2.0];
        let [mid] = Cubic::new(&t, &values).at(0, [1.0]);
        assert!((mid - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-15);
    }
}
