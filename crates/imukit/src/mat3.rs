//! 3×3 block products for the block-structured covariance updates.
//!
//! Written out: nalgebra's generic product compiles to about twice the instructions, and these run
//! tens of times per IMU sample.

use nalgebra::Matrix3;

/// `a b` for 3×3 blocks.
#[inline(always)]
pub(crate) fn mul(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| a[(r, 0)] * b[(0, c)] + a[(r, 1)] * b[(1, c)] + a[(r, 2)] * b[(2, c)])
}

/// `a bᵀ` for 3×3 blocks.
#[inline(always)]
pub(crate) fn mul_t(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| a[(r, 0)] * b[(c, 0)] + a[(r, 1)] * b[(c, 1)] + a[(r, 2)] * b[(c, 2)])
}
