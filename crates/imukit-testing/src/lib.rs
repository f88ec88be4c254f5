//! Test helpers shared by imukit's test suites: central differences on vectors and on SO(3),
//! proptest strategies for the four regimes every Jacobian is checked in, and rotation
//! comparison that reports the angle between two rotations.

use nalgebra::{Matrix3, Rotation3, SMatrix, SVector, Vector3};
use proptest::prelude::*;

use imukit::so3;

/// Central-difference step for first derivatives in f64 (≈ ε^(1/3)).
pub const STEP: f64 = 6e-6;

/// Jacobian of `f: Rⁿ → Rᵐ` at `x` by central differences.
pub fn numeric_jacobian<const N: usize, const M: usize>(
    f: impl Fn(&SVector<f64, N>) -> SVector<f64, M>,
    x: &SVector<f64, N>,
) -> SMatrix<f64, M, N> {
    let mut j = SMatrix::<f64, M, N>::zeros();
    for k in 0..N {
        let mut dx = SVector::<f64, N>::zeros();
        dx[k] = STEP;
        j.set_column(k, &((f(&(x + dx)) - f(&(x - dx))) / (2.0 * STEP)));
    }
    j
}

/// Angle (rad) of `aᵀ b`: zero exactly when the rotations agree.
pub fn rotation_distance(a: &Rotation3<f64>, b: &Rotation3<f64>) -> f64 {
    so3::log(&(a.inverse() * b)).norm()
}

/// Panics with both rotations printed unless they agree to `tol` radians.
pub fn assert_rot_close(a: &Rotation3<f64>, b: &Rotation3<f64>, tol: f64) {
    let d = rotation_distance(a, b);
    assert!(d <= tol, "rotations differ by {d:e} rad > {tol:e}:\n{a}\n{b}");
}

/// Largest absolute entry of `a − b`.
pub fn max_abs_diff<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>, b: &SMatrix<f64, R, C>) -> f64 {
    (a - b).abs().max()
}

/// A uniformly random unit vector.
pub fn unit_vector() -> impl Strategy<Value = Vector3<f64>> {
    (-1.0..1.0f64, 0.0..std::f64::consts::TAU).prop_map(|(z, az): (f64, f64)| {
        let r = (1.0 - z * z).sqrt();
        Vector3::new(r * az.cos(), r * az.sin(), z)
    })
}

/// The regimes where SO(3) formulas break: identity, tiny angles, near π, and anywhere.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// θ = 0 exactly.
    Identity,
    /// θ ≈ 1e-8.
    Tiny,
    /// θ ≈ π − 1e-6.
    NearPi,
    /// θ uniform in (0, π).
    Random,
}

/// Every regime, for tests that loop over them.
pub const REGIMES: [Regime; 4] = [Regime::Identity, Regime::Tiny, Regime::NearPi, Regime::Random];

/// Rotation vectors in a given regime, with a random axis.
pub fn rotation_vector(regime: Regime) -> BoxedStrategy<Vector3<f64>> {
    let angle: BoxedStrategy<f64> = match regime {
        Regime::Identity => Just(0.0).boxed(),
        Regime::Tiny => (0.5e-8..2e-8f64).boxed(),
        Regime::NearPi => (std::f64::consts::PI - 2e-6..std::f64::consts::PI - 0.5e-6).boxed(),
        Regime::Random => (1e-3..std::f64::consts::PI - 1e-3).boxed(),
    };
    (unit_vector(), angle).prop_map(|(u, a)| u * a).boxed()
}

/// Rotation vectors drawn from all four regimes.
pub fn any_rotation_vector() -> BoxedStrategy<Vector3<f64>> {
    prop_oneof![
        rotation_vector(Regime::Identity),
        rotation_vector(Regime::Tiny),
        rotation_vector(Regime::NearPi),
        rotation_vector(Regime::Random),
    ]
    .boxed()
}

/// A small perturbation for first-order checks (|δ| ≤ 1e-5 per component).
pub fn small_vector() -> impl Strategy<Value = Vector3<f64>> {
    (-1e-5..1e-5f64, -1e-5..1e-5f64, -1e-5..1e-5f64).prop_map(|(x, y, z)| Vector3::new(x, y, z))
}

/// The identity 3×3 matrix, for readability in assertions.
pub fn identity3() -> Matrix3<f64> {
    Matrix3::identity()
}
