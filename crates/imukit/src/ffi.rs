//! Foreign-function kernels: batch maps over flat, row-major `f64` slices, the shape a binding
//! (the PyO3 glue `imukit-py`, or a C API) hands over. Not the Rust API: Rust callers use the
//! typed functions of [`so3`], [`quat`] and [`euler`]. The kernels stay in this crate, rather than
//! in the glue, so that `cargo test` (which never links libpython) tests them.
//!
//! Each function reads `n` rows of a fixed width from `input` and writes `n` rows to `out`.
//! Every input row is checked to be finite and every output row to be finite, so a batch
//! call never returns a silent NaN; errors carry the first offending row. Large batches run in
//! parallel (rayon); results do not depend on the thread count.
//!
//! Matrices are stored row-major (`m[r][c]` at `3 r + c`), quaternions as `[x, y, z, w]`.

use nalgebra::{Matrix3, Matrix4, Quaternion, Rotation3, Vector3};
use rayon::prelude::*;

use crate::{euler, quat, so3, Error, Result};

/// Rows below which a batch runs on the calling thread (thread hand-off costs more than it saves).
const PARALLEL_MIN_ROWS: usize = 8192;

/// Rows per unit of parallel work.
const BLOCK_ROWS: usize = 1024;

/// Tolerance on `max |RᵀR − I|` for a 3×3 input to count as a rotation.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// Applies `f` to each `I`-wide row of `input`, writing `O`-wide rows to `out`.
pub fn map_rows<const I: usize, const O: usize, F>(input: &[f64], out: &mut [f64], f: F) -> Result<()>
where
    F: Fn(&[f64; I]) -> Result<[f64; O]> + Sync,
{
    if !input.len().is_multiple_of(I) {
        return Err(Error::RowLength {
            len: input.len(),
            row: I,
        });
    }
    if !out.len().is_multiple_of(O) {
        return Err(Error::RowLength { len: out.len(), row: O });
    }
    let rows = input.len() / I;
    if rows != out.len() / O {
        return Err(Error::RowCount {
            input: rows,
            output: out.len() / O,
        });
    }
    // Rows `first..` of `x` into `y`, on one thread: a plain loop, so that `f` inlines into it.
    let block = |first: usize, x: &[f64], y: &mut [f64]| -> Result<()> {
        for (offset, (x, y)) in x.chunks_exact(I).zip(y.chunks_exact_mut(O)).enumerate() {
            let index = first + offset;
            let x: &[f64; I] = x.try_into().map_err(|_| Error::RowLength { len: x.len(), row: I })?;
            if x.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite { index });
            }
            let value = f(x).map_err(|e| e.at(index))?;
            if value.iter().any(|v| !v.is_finite()) {
                return Err(Error::Overflow { index });
            }
            y.copy_from_slice(&value);
        }
        Ok(())
    };
    if rows < PARALLEL_MIN_ROWS {
        return block(0, input, out);
    }
    // Rayon hands out blocks of rows, not rows: per-row splitting costs as much as a cheap row
    // (so3 exp) and leaves the inlining of `f` to the optimiser's mood.
    let parallel = input
        .par_chunks(I * BLOCK_ROWS)
        .zip(out.par_chunks_mut(O * BLOCK_ROWS))
        .enumerate()
        .try_for_each(|(b, (x, y))| block(b * BLOCK_ROWS, x, y));
    // A parallel failure may name any bad row; report the first, as the serial path does.
    parallel.or_else(|_| block(0, input, out))
}

fn vec3(x: &[f64]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

fn quaternion(x: &[f64]) -> Quaternion<f64> {
    Quaternion::new(x[3], x[0], x[1], x[2])
}

fn matrix3(x: &[f64; 9]) -> Matrix3<f64> {
    Matrix3::from_row_slice(x)
}

fn flat3(v: Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn flat4(q: Quaternion<f64>) -> [f64; 4] {
    [q.i, q.j, q.k, q.w]
}

fn flat9(m: &Matrix3<f64>) -> [f64; 9] {
    let mut out = [0.0; 9];
    for (r, chunk) in out.chunks_exact_mut(3).enumerate() {
        for (c, v) in chunk.iter_mut().enumerate() {
            *v = m[(r, c)];
        }
    }
    out
}

fn flat16(m: &Matrix4<f64>) -> [f64; 16] {
    let mut out = [0.0; 16];
    for (r, chunk) in out.chunks_exact_mut(4).enumerate() {
        for (c, v) in chunk.iter_mut().enumerate() {
            *v = m[(r, c)];
        }
    }
    out
}

/// A checked rotation from 9 row-major numbers.
fn rotation(x: &[f64; 9]) -> Result<Rotation3<f64>> {
    let m = matrix3(x);
    let orthogonality = (m.transpose() * m - Matrix3::identity()).abs().max();
    let det = m.determinant();
    if orthogonality > ROTATION_TOLERANCE || det <= 0.0 {
        return Err(Error::NotRotation {
            index: 0,
            orthogonality,
            det,
            tolerance: ROTATION_TOLERANCE,
        });
    }
    Ok(Rotation3::from_matrix_unchecked(m))
}

/// `(n, 3)` → `(n, 3, 3)`: [`so3::hat`].
pub fn so3_hat(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<3, 9, _>(input, out, |x| Ok(flat9(&so3::hat(&vec3(x)))))
}

/// `(n, 3, 3)` → `(n, 3)`: [`so3::vee`].
pub fn so3_vee(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<9, 3, _>(input, out, |x| Ok(flat3(so3::vee(&matrix3(x)))))
}

/// `(n, 3)` → `(n, 3, 3)`: [`so3::exp`].
pub fn so3_exp(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<3, 9, _>(input, out, |x| Ok(flat9(so3::exp(&vec3(x)).matrix())))
}

/// `(n, 3)` → `(n, 3, 3)`: [`so3::exp_double_integral`] (`Γ₂`).
pub fn so3_exp_double_integral(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<3, 9, _>(input, out, |x| Ok(flat9(&so3::exp_double_integral(&vec3(x)))))
}

/// `(n, 3, 3)` → `(n, 3)`: [`so3::log`]; rows must be rotations within [`ROTATION_TOLERANCE`].
pub fn so3_log(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<9, 3, _>(input, out, |x| Ok(flat3(so3::log(&rotation(x)?))))
}

/// Which Jacobian of `Exp` a batch call computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Jacobian {
    /// [`so3::right_jacobian`]
    Right,
    /// [`so3::right_jacobian_inv`]
    RightInv,
    /// [`so3::left_jacobian`]
    Left,
    /// [`so3::left_jacobian_inv`]
    LeftInv,
}

crate::named_enum!(
    Jacobian,
    "kind",
    [Right => "right", RightInv => "right_inv", Left => "left", LeftInv => "left_inv"]
);

/// `(n, 3)` → `(n, 3, 3)`: one of the Jacobians of `Exp`.
pub fn so3_jacobian(kind: Jacobian, input: &[f64], out: &mut [f64]) -> Result<()> {
    let f = match kind {
        Jacobian::Right => so3::right_jacobian,
        Jacobian::RightInv => so3::right_jacobian_inv,
        Jacobian::Left => so3::left_jacobian,
        Jacobian::LeftInv => so3::left_jacobian_inv,
    };
    map_rows::<3, 9, _>(input, out, |x| Ok(flat9(&f(&vec3(x)))))
}

/// Quaternion product convention.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Convention {
    /// Hamilton, `i j = k`.
    Hamilton,
    /// JPL, `i j = −k`.
    Jpl,
}

crate::named_enum!(Convention, "convention", [Hamilton => "hamilton", Jpl => "jpl"]);

/// `(n, 8)` rows `[q, p]` → `(n, 4)`: `q ⊗ p` in the given convention.
pub fn quat_multiply(convention: Convention, input: &[f64], out: &mut [f64]) -> Result<()> {
    let f = match convention {
        Convention::Hamilton => quat::multiply,
        Convention::Jpl => quat::multiply_jpl,
    };
    map_rows::<8, 4, _>(input, out, |x| Ok(flat4(f(&quaternion(&x[..4]), &quaternion(&x[4..])))))
}

/// `(n, 4)` → `(n, 4)`: [`quat::conjugate`].
pub fn quat_conjugate(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<4, 4, _>(input, out, |x| Ok(flat4(quat::conjugate(&quaternion(x)))))
}

/// `(n, 4)` → `(n, 4)`: [`quat::inverse`].
pub fn quat_inverse(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<4, 4, _>(input, out, |x| Ok(flat4(quat::inverse(&quaternion(x))?)))
}

/// `(n, 4)` → `(n, 4)`: [`quat::normalize`].
pub fn quat_normalize(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<4, 4, _>(input, out, |x| Ok(flat4(quat::normalize(&quaternion(x))?.into_inner())))
}

/// `(n, 7)` rows `[q, v]` → `(n, 3)`: [`quat::rotate`].
pub fn quat_rotate(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<7, 3, _>(input, out, |x| {
        Ok(flat3(quat::rotate(&quaternion(&x[..4]), &vec3(&x[4..]))?))
    })
}

/// Which 4×4 product matrix a batch call computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProductMatrix {
    /// `L(q)`: `q ⊗ p = L(q) p`.
    Left,
    /// `R(p)`: `q ⊗ p = R(p) q`.
    Right,
}

crate::named_enum!(ProductMatrix, "side", [Left => "left", Right => "right"]);

/// `(n, 4)` → `(n, 4, 4)`: left or right product matrix, `[x, y, z, w]` layout.
pub fn quat_product_matrix(kind: ProductMatrix, convention: Convention, input: &[f64], out: &mut [f64]) -> Result<()> {
    let f = match (kind, convention) {
        (ProductMatrix::Left, Convention::Hamilton) => quat::left_matrix,
        (ProductMatrix::Right, Convention::Hamilton) => quat::right_matrix,
        (ProductMatrix::Left, Convention::Jpl) => quat::left_matrix_jpl,
        (ProductMatrix::Right, Convention::Jpl) => quat::right_matrix_jpl,
    };
    map_rows::<4, 16, _>(input, out, |x| Ok(flat16(&f(&quaternion(x)))))
}

/// `(n, 3)` → `(n, 4, 4)`: Ω(ω), `[x, y, z, w]` layout.
pub fn quat_omega_matrix(convention: Convention, input: &[f64], out: &mut [f64]) -> Result<()> {
    let f = match convention {
        Convention::Hamilton => quat::omega_matrix,
        Convention::Jpl => quat::omega_matrix_jpl,
    };
    map_rows::<3, 16, _>(input, out, |x| Ok(flat16(&f(&vec3(x)))))
}

/// `(n, 3)` → `(n, 4)`: [`quat::exp`].
pub fn quat_exp(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<3, 4, _>(input, out, |x| Ok(flat4(quat::exp(&vec3(x)).into_inner())))
}

/// `(n, 4)` → `(n, 3)`: [`quat::log`] of the normalised quaternion.
pub fn quat_log(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<4, 3, _>(input, out, |x| Ok(flat3(quat::log(&quat::normalize(&quaternion(x))?))))
}

/// `(n, 3)` `[ψ, θ, φ]` → `(n, 3, 3)`: [`euler::to_rotation`].
pub fn euler_to_matrix(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<3, 9, _>(input, out, |x| Ok(flat9(euler::to_rotation(&vec3(x)).matrix())))
}

/// `(n, 3, 3)` → `(n, 3)`: [`euler::from_rotation`]; rows must be rotations.
pub fn euler_from_matrix(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<9, 3, _>(input, out, |x| Ok(flat3(euler::from_rotation(&rotation(x)?))))
}

/// `(n, 3)` → `(n, 3, 3)`: [`euler::rate_matrix`] with the given gimbal tolerance.
pub fn euler_rate_matrix(tolerance: f64, input: &[f64], out: &mut [f64]) -> Result<()> {
    euler::check_pitch(0.0, tolerance)?;
    map_rows::<3, 9, _>(input, out, |x| Ok(flat9(&euler::rate_matrix(&vec3(x), tolerance)?)))
}

/// `(n, 3)` → `(n, 3, 3)`: [`euler::rate_matrix_inv`].
pub fn euler_rate_matrix_inv(input: &[f64], out: &mut [f64]) -> Result<()> {
    map_rows::<3, 9, _>(input, out, |x| Ok(flat9(&euler::rate_matrix_inv(&vec3(x)))))
}
