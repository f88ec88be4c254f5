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

/// `a bᵀ` for 3×3 blocks whose product is known to be symmetric (as `X S Xᵀ` with `a = X S`):
/// the upper triangle, mirrored, so the result is exactly symmetric at two thirds of the cost.
#[inline(always)]
pub(crate) fn mul_t_symmetric(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    let d = |r: usize, c: usize| a[(r, 0)] * b[(c, 0)] + a[(r, 1)] * b[(c, 1)] + a[(r, 2)] * b[(c, 2)];
    let (xy, xz, yz) = (d(0, 1), d(0, 2), d(1, 2));
    Matrix3::new(d(0, 0), xy, xz, xy, d(1, 1), yz, xz, yz, d(2, 2))
}
