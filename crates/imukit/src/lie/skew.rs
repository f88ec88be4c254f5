//! The skew map of so(3): `hat(φ) = [φ]×` with `[φ]× v = φ × v`, and its inverse `vee`.

use nalgebra::{Matrix3, Vector3};

/// `[φ]×`, the skew-symmetric matrix with `[φ]× v = φ × v`.
pub fn hat(phi: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(
        0.0, -phi.z, phi.y, //
        phi.z, 0.0, -phi.x, //
        -phi.y, phi.x, 0.0,
    )
}

/// Inverse of [`hat`]. For a matrix that is not exactly skew it returns the vector of its skew
/// part `(M − Mᵀ)/2`, the nearest element of so(3) in the Frobenius norm.
pub fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    // Halve before subtracting: entries near f64::MAX must not overflow.
    Vector3::new(
        0.5 * m[(2, 1)] - 0.5 * m[(1, 2)],
        0.5 * m[(0, 2)] - 0.5 * m[(2, 0)],
        0.5 * m[(1, 0)] - 0.5 * m[(0, 1)],
    )
}
