//! Test helpers shared by imukit's test suites: central differences on vectors and on SO(3),
//! proptest strategies for the four regimes every Jacobian is checked in, and rotation
//! comparison that reports the angle between two rotations.

pub mod preint;

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

/// Runs `test` on `cases` values drawn from `strategy(regime)` in every regime of [`REGIMES`],
/// one proptest run per regime; a failure names the regime and the shrunk input.
pub fn check_regimes<S, F>(cases: u32, strategy: impl Fn(Regime) -> S, test: F)
where
    S: Strategy,
    F: Fn(Regime, S::Value) -> Result<(), TestCaseError>,
{
    for regime in REGIMES {
        check(&format!("{regime:?}"), cases, strategy(regime), |value| {
            test(regime, value)
        });
    }
}

/// Runs `test` on `cases` values drawn from `strategy` (one proptest run, no regression files);
/// a failure names `label` and the shrunk input.
pub fn check<S, F>(label: &str, cases: u32, strategy: S, test: F)
where
    S: Strategy,
    F: Fn(S::Value) -> Result<(), TestCaseError>,
{
    let config = ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    };
    let outcome = proptest::test_runner::TestRunner::new(config).run(&strategy, test);
    let message = outcome.as_ref().err().map(ToString::to_string).unwrap_or_default();
    assert!(outcome.is_ok(), "[{label}] {message}");
}

/// Rotation vectors whose angle lies within ±2 % of a point where imukit switches between a
/// Taylor series and a closed form (θ = 2e-6 for the quaternion log, 1e-4 for sinc, 2e-4 for
/// (1 − cos θ)/θ², 0.2 for the Jacobian coefficients, 0.5 for the quaternion exp): a wrong series
/// term shows up here, where it is largest, and not at θ ≈ 1e-8, where every series term past
/// the first is below rounding. Extend the list when a new switch point appears.
pub fn series_switch_vector() -> BoxedStrategy<Vector3<f64>> {
    let angle = prop_oneof![
        (1.96e-6..2.04e-6f64),
        (0.98e-4..1.02e-4f64),
        (1.96e-4..2.04e-4f64),
        (0.196..0.204f64),
        (0.49..0.51f64),
    ];
    (unit_vector(), angle).prop_map(|(u, a)| u * a).boxed()
}

/// Uniformly random rotations, built with nalgebra (not with imukit) so that they can serve as an
/// independent reference.
pub fn random_rotation() -> BoxedStrategy<Rotation3<f64>> {
    (unit_vector(), 0.0..std::f64::consts::PI)
        .prop_map(|(u, a)| Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(u), a))
        .boxed()
}

/// Quaternions (not normalised) with norm between 0.1 and about 3.5, for algebra checks.
pub fn any_quaternion() -> BoxedStrategy<nalgebra::Quaternion<f64>> {
    (-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64)
        .prop_map(|(w, x, y, z)| nalgebra::Quaternion::new(w, x, y, z))
        .prop_filter("norm at least 0.1", |q| q.norm() >= 0.1)
        .boxed()
}

/// `exp(A)` of any 3×3 matrix by its Taylor series Σ Aᵏ/k! (30 terms) after scaling A by 2⁻ˢ
/// to ‖A‖∞ ≤ ½, then squaring s times: a dense reference that shares no code or formula with
/// Rodrigues' closed form. Truncation error ≤ 0.5³¹/31! ≈ 5e-44; rounding a few ulp per squaring.
pub fn series_expm(a: &Matrix3<f64>) -> Matrix3<f64> {
    let norm = (0..3).map(|r| a.row(r).abs().sum()).fold(0.0, f64::max);
    let mut squarings = 0;
    let mut scale = 1.0;
    while norm * scale > 0.5 {
        squarings += 1;
        scale *= 0.5;
    }
    let scaled = a * scale;
    let mut term = Matrix3::identity();
    let mut sum = Matrix3::identity();
    for k in 1..=30 {
        term = term * scaled / f64::from(k);
        sum += term;
    }
    for _ in 0..squarings {
        sum = sum * sum;
    }
    sum
}

/// Left Jacobian by its defining series `J_l(φ) = Σₖ [φ]×ᵏ/(k+1)! = ∫₀¹ Exp(sφ) ds` (Chirikjian
/// 2011, eq. 10.86), 40 terms: truncation below 1e-30 for θ ≤ π, rounding about 1e-15 there.
pub fn series_left_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    let k = so3::hat(phi);
    let mut term = Matrix3::identity();
    let mut sum = Matrix3::identity();
    for n in 1..=40 {
        term = term * k / f64::from(n + 1);
        sum += term;
    }
    sum
}

/// The rotation vector of `r` nearest to `reference`: `Log(r) + 2πk u` over k. This unwraps
/// Log across its cut at θ = π, so that central differences through π stay smooth.
pub fn log_near(r: &Rotation3<f64>, reference: &Vector3<f64>) -> Vector3<f64> {
    let v = so3::log(r);
    let theta = v.norm();
    if theta == 0.0 {
        return v;
    }
    let u = v / theta;
    (-2..=2)
        .map(|k| v + u * (f64::from(k) * std::f64::consts::TAU))
        .fold(v, |best, c| {
            if (c - reference).norm() < (best - reference).norm() {
                c
            } else {
                best
            }
        })
}

/// A unit vector perpendicular to `v` (any one, chosen stably).
pub fn perpendicular(v: &Vector3<f64>) -> Vector3<f64> {
    let helper = if v.x.abs() < 0.6 { Vector3::x() } else { Vector3::y() };
    v.cross(&helper).normalize()
}

/// Runs `test` on `cases` rotation vectors from each of the four [`REGIMES`] and from
/// [`series_switch_vector`]: the set every SO(3) formula is checked on.
pub fn check_rotation_vectors<F>(cases: u32, test: F)
where
    F: Fn(Vector3<f64>) -> Result<(), TestCaseError>,
{
    check_regimes(cases, rotation_vector, |_, phi| test(phi));
    check("series switch", cases, series_switch_vector(), test);
}

/// Vectors with components uniform in `(-bound, bound)`.
pub fn vector3(bound: f64) -> BoxedStrategy<Vector3<f64>> {
    let c = -bound..bound;
    (c.clone(), c.clone(), c)
        .prop_map(|(x, y, z)| Vector3::new(x, y, z))
        .boxed()
}
