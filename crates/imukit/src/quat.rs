//! Quaternion algebra: Hamilton (default) and JPL products, product matrices, Ω(ω), exp/log.
//!
//! | item | convention |
//! |---|---|
//! | storage | nalgebra [`Quaternion`]: `coords = [x, y, z, w]`, scalar last (`Quaternion::new` takes `w` first) |
//! | product | Hamilton, `i j = k`: [`multiply`]; JPL (Trawny & Roumeliotis 2005), `i j = −k`: [`multiply_jpl`] |
//! | meaning | active: `v_w = q_wb ⊗ [v_b, 0] ⊗ q_wb*` (see [`rotate`]) |
//! | 4×4 matrices | act on `[x, y, z, w]` column vectors: `q ⊗ p = L(q) p = R(p) q` |
//! | body rate | `q̇ = ½ q ⊗ [ω, 0] = ½ Ω(ω) q` with `Ω(ω) = R([ω, 0])` |
//!
//! The JPL product satisfies `q ⊗_J p = p ⊗_H q` component-wise, so `L_J = R_H` and `R_J = L_H`.
//! A JPL quaternion of the world-to-body rotation `ᴮC_W` stores the same four numbers as the
//! Hamilton quaternion of `R_wb`; its kinematics `q̇ = ½ Ω(ω) q` (Trawny & Roumeliotis 2005,
//! eq. 108) therefore use the very same matrix as the Hamilton `½ q ⊗ [ω, 0]`. See
//! `docs/conventions.md`.

use nalgebra::{Matrix3, Matrix4, Quaternion, UnitQuaternion, Vector3};

use crate::lie::series;
use crate::lie::skew::hat;
use crate::{Error, Result};

/// Below this norm a quaternion is treated as zero: it encodes no rotation.
pub const ZERO_NORM: f64 = 1e-12;

/// Hamilton product `q ⊗ p = [q_w p_v + p_w q_v + q_v × p_v, q_w p_w − q_v·p_v]`.
///
/// Written out (nalgebra's generic product compiles to about twice the instructions), with the
/// `w w` and `x x` terms first so each sum pairs into two independent halves.
#[inline]
pub fn multiply(q: &Quaternion<f64>, p: &Quaternion<f64>) -> Quaternion<f64> {
    let (a, b) = (&q.coords, &p.coords); // [x, y, z, w]
    Quaternion::new(
        (a[3] * b[3] - a[0] * b[0]) - (a[1] * b[1] + a[2] * b[2]),
        (a[3] * b[0] + a[0] * b[3]) + (a[1] * b[2] - a[2] * b[1]),
        (a[3] * b[1] + a[1] * b[3]) + (a[2] * b[0] - a[0] * b[2]),
        (a[3] * b[2] + a[2] * b[3]) + (a[0] * b[1] - a[1] * b[0]),
    )
}

/// JPL product `q ⊗_J p` (`i j = −k`), equal to the Hamilton product `p ⊗ q`.
pub fn multiply_jpl(q: &Quaternion<f64>, p: &Quaternion<f64>) -> Quaternion<f64> {
    multiply(p, q)
}

/// Conjugate `q* = [−x, −y, −z, w]`.
pub fn conjugate(q: &Quaternion<f64>) -> Quaternion<f64> {
    q.conjugate()
}

/// `(q / m, m)` with `m = max |q_i|`, so that norms of finite quaternions never overflow
/// (`|q|²` does beyond 1.3e154); errors on a zero quaternion.
fn scaled(q: &Quaternion<f64>) -> Result<(Quaternion<f64>, f64)> {
    let m = q.coords.amax();
    let unit_scale = if m > 0.0 { q / m } else { *q };
    let norm = m * unit_scale.norm();
    if norm < ZERO_NORM {
        return Err(Error::ZeroQuaternion { index: 0, norm });
    }
    Ok((unit_scale, m))
}

/// Inverse `q⁻¹ = q* / |q|²`; errors on a zero quaternion.
pub fn inverse(q: &Quaternion<f64>) -> Result<Quaternion<f64>> {
    let (s, m) = scaled(q)?;
    Ok(s.conjugate() / (s.norm_squared() * m))
}

/// `q / |q|`; errors on a zero quaternion.
pub fn normalize(q: &Quaternion<f64>) -> Result<UnitQuaternion<f64>> {
    Ok(UnitQuaternion::new_normalize(scaled(q)?.0))
}

/// Rotates `v` by the (normalised) rotation `q`: `q ⊗ [v, 0] ⊗ q*`.
pub fn rotate(q: &Quaternion<f64>, v: &Vector3<f64>) -> Result<Vector3<f64>> {
    Ok(normalize(q)? * v)
}

/// `q ⊗ [v, 0] ⊗ q*` for a unit `q`: `v + w t + u × t` with `t = 2 u × v` (18 multiplications,
/// no normalisation; the hot path of strapdown integration).
#[inline]
pub fn rotate_unit(q: &UnitQuaternion<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    let u = q.imag();
    let t = u.cross(v) * 2.0;
    v + t * q.w + u.cross(&t)
}

/// Left product matrix `L(q)`: `q ⊗ p = L(q) p` on `[x, y, z, w]` vectors (Hamilton).
pub fn left_matrix(q: &Quaternion<f64>) -> Matrix4<f64> {
    // q ⊗ p = [q_w p_v + p_w q_v + q_v × p_v ; q_w p_w − q_v·p_v]  (Solà 2017, eq. 12)
    product_matrix(q, &hat(&q.imag()))
}

/// Right product matrix `R(p)`: `q ⊗ p = R(p) q` on `[x, y, z, w]` vectors (Hamilton).
pub fn right_matrix(p: &Quaternion<f64>) -> Matrix4<f64> {
    product_matrix(p, &-hat(&p.imag()))
}

/// JPL left product matrix: `q ⊗_J p = L_J(q) p`; equals the Hamilton [`right_matrix`].
pub fn left_matrix_jpl(q: &Quaternion<f64>) -> Matrix4<f64> {
    right_matrix(q)
}

/// JPL right product matrix: `q ⊗_J p = R_J(p) q`; equals the Hamilton [`left_matrix`].
pub fn right_matrix_jpl(p: &Quaternion<f64>) -> Matrix4<f64> {
    left_matrix(p)
}

/// `[[w I + S, v], [−vᵀ, w]]`: the shape shared by both product matrices, `S = ±[v]×`.
fn product_matrix(q: &Quaternion<f64>, cross: &Matrix3<f64>) -> Matrix4<f64> {
    let v = q.imag();
    let mut m = Matrix4::identity() * q.w;
    let mut block = m.fixed_view_mut::<3, 3>(0, 0);
    block += cross;
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&v);
    m.fixed_view_mut::<1, 3>(3, 0).copy_from(&(-v.transpose()));
    m
}

/// `Ω(ω)` with `q̇ = ½ Ω(ω) q = ½ q ⊗ [ω, 0]` for a body rate ω (Hamilton, `q = q_wb`):
/// `[[−[ω]×, ω], [−ωᵀ, 0]]` on `[x, y, z, w]`, the right product matrix of the pure quaternion ω.
pub fn omega_matrix(omega: &Vector3<f64>) -> Matrix4<f64> {
    right_matrix(&pure(omega))
}

/// JPL `Ω(ω)`: `q̇ = ½ Ω(ω) q = ½ [ω, 0] ⊗_J q` for the JPL quaternion of `ᴮC_W` (Trawny &
/// Roumeliotis 2005, eq. 108). Numerically equal to [`omega_matrix`]; kept so that ported JPL
/// formulas read as written.
pub fn omega_matrix_jpl(omega: &Vector3<f64>) -> Matrix4<f64> {
    left_matrix_jpl(&pure(omega))
}

/// The pure quaternion `[v, 0]`.
pub fn pure(v: &Vector3<f64>) -> Quaternion<f64> {
    Quaternion::from_imag(*v)
}

/// `Exp(φ) = [sin(θ/2) φ/θ, cos(θ/2)]`, θ = |φ|, exact to rounding at θ → 0.
///
/// For θ < 0.5 (every gyro step of a sane IMU) both coefficients come from their Taylor series
/// in θ², which needs neither a square root nor a libm call and is accurate to 1e-17 there;
/// this is what makes gyro integration cost a few nanoseconds per sample.
#[inline]
pub fn exp(phi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let (k, w) = series::half_angle(phi.norm_squared());
    UnitQuaternion::new_unchecked(Quaternion::from_parts(w, phi * k))
}

/// [`exp`] of one integration step: below θ = 0.01 rad the shorter series of
/// [`series::half_angle_small`] (the same rotation to the last bit or so; a step is a chain of
/// dependent operations, and this takes three multiply-adds off it).
#[inline(always)]
pub fn exp_step(phi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let (k, w) = series::half_angle_small(phi.norm_squared());
    UnitQuaternion::new_unchecked(Quaternion::from_parts(w, phi * k))
}

/// `q ⊗ Exp(φ)` of one integration step, as `w q + k (q ⊗ [φ, 0])` with `(k, w)` of
/// [`exp_step`] (`Exp(φ) = [k φ, w]`, and the product is linear in its right factor): the pure
/// product runs beside the series instead of after it, which takes the scaling `k φ` and one
/// product level off a filter step's dependency chain. The same rotation to rounding.
#[inline(always)]
pub fn multiply_exp_step(q: &Quaternion<f64>, phi: &Vector3<f64>) -> Quaternion<f64> {
    let (k, w) = series::half_angle_small(phi.norm_squared());
    let (v, s) = (q.imag(), q.w);
    let pure = Quaternion::from_parts(-v.dot(phi), phi * s + v.cross(phi));
    q * w + pure * k
}

/// `Log(q)`: the rotation vector with angle in `[0, π]` of the rotation `q` (either sign of `q`).
///
/// Uses `θ = 2 atan2(|v|, |w|)`, accurate at 0 and at π, unlike `acos(w)`. Not nalgebra's
/// `UnitQuaternion::ln` (nalgebra issue 1363).
pub fn log(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    // q and −q are the same rotation; the one with w ≥ 0 has its angle in [0, π].
    let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    let w = sign * q.w;
    let v = q.imag() * sign;
    let n = v.norm();
    // 2 atan(n / w) / n by its Taylor series for small n / w (then w ≈ 1).
    let k = if n < 1e-6 * w {
        let r2 = (n / w) * (n / w);
        (2.0 / w) * (1.0 - r2 / 3.0)
    } else {
        2.0 * n.atan2(w) / n
    };
    v * k
}

/// Whether `[x, y, z, w]` is a unit quaternion up to far more than rounding: every state an
/// integrator keeps is unit to ~1e-15, while an overflowed one is zero, NaN or ±inf. The kernels use
/// it to refuse a result whose norm overflowed (`q/|q|` with `|q|² = inf` is the zero quaternion).
pub(crate) fn is_unit_coords(q: &[f64]) -> bool {
    let norm_squared: f64 = q.iter().map(|v| v * v).sum();
    (norm_squared - 1.0).abs() < 1e-6
}
