//! Tests of `imukit::ffi`: shape errors, the first bad row reported on both the serial and the
//! parallel (> 8192 rows) path, overflow and non-rotation detection, and bit-for-bit agreement
//! of every kernel with the single-element function it wraps.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![allow(missing_docs)]

use imukit::ffi::{self, Convention, Jacobian, ProductMatrix};
use imukit::{euler, quat, so3, Error, Result};
use nalgebra::{Matrix3, Matrix4, Quaternion, Vector3};

/// Above `PARALLEL_MIN_ROWS` (8192): the rayon path.
const LARGE: usize = 30_000;
const SMALL: usize = 100;

/// xorshift64*: deterministic inputs without a dependency.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        lo + (hi - lo) * (bits as f64 / (1u64 << 53) as f64)
    }

    fn rows(&mut self, n: usize, width: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n * width).map(|_| self.uniform(lo, hi)).collect()
    }
}

fn rotation_rows(rng: &mut Rng, n: usize) -> Vec<f64> {
    (0..n)
        .flat_map(|_| {
            let phi = Vector3::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0));
            row9(so3::exp(&phi).matrix())
        })
        .collect()
}

fn row9(m: &Matrix3<f64>) -> [f64; 9] {
    let mut out = [0.0; 9];
    for r in 0..3 {
        for c in 0..3 {
            out[3 * r + c] = m[(r, c)];
        }
    }
    out
}

fn row16(m: &Matrix4<f64>) -> [f64; 16] {
    let mut out = [0.0; 16];
    for r in 0..4 {
        for c in 0..4 {
            out[4 * r + c] = m[(r, c)];
        }
    }
    out
}

fn v3(x: &[f64]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

fn q4(x: &[f64]) -> Quaternion<f64> {
    Quaternion::new(x[3], x[0], x[1], x[2])
}

fn xyzw(q: &Quaternion<f64>) -> [f64; 4] {
    [q.i, q.j, q.k, q.w]
}

fn m9(x: &[f64]) -> Matrix3<f64> {
    Matrix3::from_row_slice(x)
}

fn run(
    kernel: impl Fn(&[f64], &mut [f64]) -> Result<()>,
    input: &[f64],
    out_width: usize,
    in_width: usize,
) -> Vec<f64> {
    let mut out = vec![f64::NAN; input.len() / in_width * out_width];
    kernel(input, &mut out).unwrap();
    out
}

/// Asserts `batch` equals the concatenation of `single` over the rows, bit for bit.
fn assert_bitwise(name: &str, batch: &[f64], input: &[f64], in_width: usize, single: impl Fn(&[f64]) -> Vec<f64>) {
    let expected: Vec<f64> = input.chunks_exact(in_width).flat_map(single).collect();
    assert_eq!(batch.len(), expected.len(), "{name}: length");
    for (i, (a, b)) in batch.iter().zip(&expected).enumerate() {
        assert!(
            a.to_bits() == b.to_bits(),
            "{name}: element {i} of the output: batch {a:e} vs single {b:e}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// map_rows: shapes and row indices
// ---------------------------------------------------------------------------------------------

type Vec3Fn<T> = fn(&Vector3<f64>) -> T;
type QuatFn<T> = fn(&Quaternion<f64>) -> T;
type QuatProduct = fn(&Quaternion<f64>, &Quaternion<f64>) -> Quaternion<f64>;

fn copy3(x: &[f64; 3]) -> Result<[f64; 3]> {
    Ok(*x)
}

#[test]
fn map_rows_shape_errors() {
    let mut out = [0.0; 9];
    assert_eq!(
        ffi::map_rows::<3, 3, _>(&[0.0; 7], &mut out, copy3),
        Err(Error::RowLength { len: 7, row: 3 })
    );
    let mut short = [0.0; 5];
    assert_eq!(
        ffi::map_rows::<3, 3, _>(&[0.0; 6], &mut short, copy3),
        Err(Error::RowLength { len: 5, row: 3 })
    );
    assert_eq!(
        ffi::map_rows::<3, 3, _>(&[0.0; 6], &mut out, copy3),
        Err(Error::RowCount { input: 2, output: 3 })
    );
    let mut empty: [f64; 0] = [];
    assert_eq!(ffi::map_rows::<3, 3, _>(&[], &mut empty, copy3), Ok(()));
    // The kernels check shapes the same way, with their own widths.
    let mut out9 = [0.0; 18];
    assert_eq!(
        ffi::so3_exp(&[0.0; 6], &mut out9[..17]),
        Err(Error::RowLength { len: 17, row: 9 })
    );
    assert_eq!(
        ffi::so3_exp(&[0.0; 3], &mut out9),
        Err(Error::RowCount { input: 1, output: 2 })
    );
    assert_eq!(
        ffi::quat_multiply(Convention::Hamilton, &[0.0; 12], &mut [0.0; 8]),
        Err(Error::RowLength { len: 12, row: 8 })
    );
    // Output rows are written.
    let mut out = [0.0; 6];
    ffi::map_rows::<3, 3, _>(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], &mut out, copy3).unwrap();
    assert_eq!(out, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
}

#[test]
fn non_finite_input_reports_the_first_bad_row() {
    for (n, bad) in [
        (SMALL, [37, 80]),
        (SMALL, [0, 99]),
        (LARGE, [9_000, 20_000]),
        (LARGE, [8_191, 29_999]),
        (LARGE, [0, 15_000]),
    ] {
        for poison in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut input = Rng(7).rows(n, 3, -1.0, 1.0);
            // Later bad row first in memory order of writing, so order of insertion does not matter.
            input[3 * bad[1] + 2] = poison;
            input[3 * bad[0] + 1] = poison;
            let mut out = vec![0.0; 9 * n];
            assert_eq!(
                ffi::so3_exp(&input, &mut out),
                Err(Error::NonFinite { index: bad[0] }),
                "n = {n}, bad rows {bad:?}, {poison}"
            );
        }
    }
}

#[test]
fn first_error_wins_whatever_its_kind() {
    // A row the kernel refuses (index a) before a non-finite row (index b), and the reverse: the
    // error of the lower row comes back, on the serial and on the parallel path.
    let refuse_negative = |x: &[f64; 3]| -> Result<[f64; 3]> {
        if x[0] < 0.0 {
            Err(Error::ZeroQuaternion { index: 0, norm: 0.0 })
        } else {
            Ok(*x)
        }
    };
    for n in [SMALL, LARGE] {
        let (a, b) = (n / 3, 2 * n / 3);
        let mut input = vec![1.0; 3 * n];
        input[3 * a] = -1.0;
        input[3 * b] = f64::NAN;
        let mut out = vec![0.0; 3 * n];
        assert_eq!(
            ffi::map_rows::<3, 3, _>(&input, &mut out, refuse_negative),
            Err(Error::ZeroQuaternion { index: a, norm: 0.0 })
        );
        let mut input = vec![1.0; 3 * n];
        input[3 * a] = f64::NAN;
        input[3 * b] = -1.0;
        assert_eq!(
            ffi::map_rows::<3, 3, _>(&input, &mut out, refuse_negative),
            Err(Error::NonFinite { index: a })
        );
    }
}

#[test]
fn huge_finite_input_overflows() {
    // |φ|² = 3e400 overflows, θ = inf, sin θ/θ = NaN: a finite input that cannot be computed.
    // The kernel must say so (Overflow) and not return NaN rows.
    let mut out = [0.0; 9];
    assert_eq!(
        ffi::so3_exp(&[1e200, 1e200, 1e200], &mut out),
        Err(Error::Overflow { index: 0 })
    );
    let mut out4 = [0.0; 4];
    assert_eq!(
        ffi::quat_exp(&[1e200, 1e200, 1e200], &mut out4),
        Err(Error::Overflow { index: 0 })
    );
    // vee of a finite skew matrix with entries ±1e308 is representable: halving comes first.
    let mut out3 = [0.0; 3];
    let vee_in = [0.0, -1e308, 0.0, 1e308, 0.0, 0.0, 0.0, 0.0, 0.0];
    ffi::so3_vee(&vee_in, &mut out3).unwrap();
    assert_eq!(out3, [0.0, 0.0, 1e308]);
    for (n, bad) in [(SMALL, 42), (LARGE, 12_345)] {
        let mut input = Rng(3).rows(n, 3, -3.0, 3.0);
        input[3 * bad..3 * bad + 3].copy_from_slice(&[1e200, -1e200, 1e200]);
        let mut out = vec![0.0; 9 * n];
        assert_eq!(
            ffi::so3_exp(&input, &mut out),
            Err(Error::Overflow { index: bad }),
            "n = {n}"
        );
    }
    // Large but squarable magnitudes are fine (and still rotations).
    ffi::so3_exp(&[1e150, 0.0, 0.0], &mut out).unwrap();
    let m = m9(&out);
    assert!((m.transpose() * m - Matrix3::identity()).abs().max() < 1e-12);
}

#[test]
fn huge_quaternion_rows_are_not_silently_wrong() {
    // [1e200, 0, 0, 0] (xyzw) is a valid rotation: π about x. Any Ok result must be right.
    let q = [1e200, 0.0, 0.0, 0.0];
    let mut out4 = [0.0; 4];
    if ffi::quat_normalize(&q, &mut out4).is_ok() {
        assert_eq!(out4, [1.0, 0.0, 0.0, 0.0], "quat_normalize");
    }
    let mut out3 = [0.0; 3];
    if ffi::quat_rotate(&[1e200, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0], &mut out3).is_ok() {
        assert_eq!(out3, [1.0, -2.0, -3.0], "quat_rotate");
    }
    if ffi::quat_inverse(&q, &mut out4).is_ok() {
        assert!(out4[0] < 0.0, "quat_inverse: {out4:?}");
    }
}

#[test]
fn non_rotations_are_refused() {
    let mut out = [0.0; 3];
    let scaled = [2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0];
    assert_eq!(
        ffi::so3_log(&scaled, &mut out),
        Err(Error::NotRotation {
            index: 0,
            orthogonality: 3.0,
            det: 8.0,
            tolerance: ffi::ROTATION_TOLERANCE
        })
    );
    // Orthonormal but improper: −I and a reflection.
    for (m, det) in [
        ([-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0], -1.0),
        ([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0], -1.0),
    ] {
        match ffi::so3_log(&m, &mut out) {
            Err(Error::NotRotation {
                index: 0,
                orthogonality,
                det: d,
                ..
            }) => {
                assert_eq!(orthogonality, 0.0);
                assert_eq!(d, det);
            }
            other => panic!("{m:?}: {other:?}"),
        }
        assert!(matches!(
            ffi::euler_from_matrix(&m, &mut out),
            Err(Error::NotRotation { .. })
        ));
    }
    // The tolerance on max |RᵀR − I| (1e-6): a rotation scaled by (1 + 1e-7) passes, by
    // (1 + 1e-5) it does not; the offending row is named on both paths.
    for (n, bad) in [(SMALL, 63), (LARGE, 17_001)] {
        let mut input = rotation_rows(&mut Rng(11), n);
        let mut out = vec![0.0; 3 * n];
        for x in &mut input[9 * 5..9 * 6] {
            *x *= 1.0 + 1e-7;
        }
        ffi::so3_log(&input, &mut out).unwrap();
        for x in &mut input[9 * bad..9 * bad + 9] {
            *x *= 1.0 + 1e-5;
        }
        assert!(
            matches!(ffi::so3_log(&input, &mut out), Err(Error::NotRotation { index, .. }) if index == bad),
            "n = {n}"
        );
        assert!(
            matches!(ffi::euler_from_matrix(&input, &mut out), Err(Error::NotRotation { index, .. }) if index == bad)
        );
    }
}

#[test]
fn zero_quaternions_and_gimbal_lock_are_located() {
    for (n, bad) in [(SMALL, 13), (LARGE, 9_999)] {
        let mut q = Rng(5).rows(n, 4, -1.0, 1.0);
        q[4 * bad..4 * bad + 4].copy_from_slice(&[0.0; 4]);
        let mut out4 = vec![0.0; 4 * n];
        let mut out3 = vec![0.0; 3 * n];
        let zero = Err(Error::ZeroQuaternion { index: bad, norm: 0.0 });
        assert_eq!(ffi::quat_inverse(&q, &mut out4), zero);
        assert_eq!(ffi::quat_normalize(&q, &mut out4), zero);
        assert_eq!(ffi::quat_log(&q, &mut out3), zero);
        let qv: Vec<f64> = q
            .chunks_exact(4)
            .flat_map(|x| [x[0], x[1], x[2], x[3], 1.0, 2.0, 3.0])
            .collect();
        assert_eq!(ffi::quat_rotate(&qv, &mut out3), zero);

        let mut chi = Rng(9).rows(n, 3, -1.0, 1.0);
        chi[3 * bad + 1] = -std::f64::consts::FRAC_PI_2;
        let mut out9 = vec![0.0; 9 * n];
        assert!(matches!(
            ffi::euler_rate_matrix(1e-6, &chi, &mut out9),
            Err(Error::GimbalLock { index, tolerance_deg, .. }) if index == bad && tolerance_deg == 1e-6f64.to_degrees()
        ));
    }
    // A bad tolerance is a parameter error even with no rows.
    let mut empty: [f64; 0] = [];
    assert!(matches!(
        ffi::euler_rate_matrix(-1.0, &[], &mut empty),
        Err(Error::Parameter { name: "tolerance", .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// bit-for-bit agreement with the single-element functions
// ---------------------------------------------------------------------------------------------

#[test]
fn batch_results_equal_single_element_functions_bit_for_bit() {
    for n in [SMALL, LARGE] {
        let rng = &mut Rng(0x5eed + n as u64);
        let vecs = rng.rows(n, 3, -3.0, 3.0);
        let quats = rng.rows(n, 4, -1.0, 1.0);
        let pairs = rng.rows(n, 8, -1.0, 1.0);
        let qv = rng.rows(n, 7, -1.0, 1.0);
        let rots = rotation_rows(rng, n);
        let chis: Vec<f64> = rng.rows(n, 3, -1.5, 1.5);
        let mats = rng.rows(n, 9, -2.0, 2.0);

        let out = run(ffi::so3_hat, &vecs, 9, 3);
        assert_bitwise("so3_hat", &out, &vecs, 3, |x| row9(&so3::hat(&v3(x))).to_vec());
        let out = run(ffi::so3_vee, &mats, 3, 9);
        assert_bitwise("so3_vee", &out, &mats, 9, |x| so3::vee(&m9(x)).as_slice().to_vec());
        let out = run(ffi::so3_exp, &vecs, 9, 3);
        assert_bitwise("so3_exp", &out, &vecs, 3, |x| row9(so3::exp(&v3(x)).matrix()).to_vec());
        let out = run(ffi::so3_log, &rots, 3, 9);
        assert_bitwise("so3_log", &out, &rots, 9, |x| {
            so3::log(&nalgebra::Rotation3::from_matrix_unchecked(m9(x)))
                .as_slice()
                .to_vec()
        });
        let jacobians: [(Jacobian, Vec3Fn<Matrix3<f64>>); 4] = [
            (Jacobian::Right, so3::right_jacobian),
            (Jacobian::RightInv, so3::right_jacobian_inv),
            (Jacobian::Left, so3::left_jacobian),
            (Jacobian::LeftInv, so3::left_jacobian_inv),
        ];
        for (kind, f) in jacobians {
            let out = run(|i, o| ffi::so3_jacobian(kind, i, o), &vecs, 9, 3);
            assert_bitwise(&format!("{kind:?}"), &out, &vecs, 3, |x| row9(&f(&v3(x))).to_vec());
        }
        let products: [(Convention, QuatProduct); 2] = [
            (Convention::Hamilton, quat::multiply),
            (Convention::Jpl, quat::multiply_jpl),
        ];
        for (convention, f) in products {
            let out = run(|i, o| ffi::quat_multiply(convention, i, o), &pairs, 4, 8);
            assert_bitwise(&format!("{convention:?}"), &out, &pairs, 8, |x| {
                xyzw(&f(&q4(&x[..4]), &q4(&x[4..]))).to_vec()
            });
        }
        let out = run(ffi::quat_conjugate, &quats, 4, 4);
        assert_bitwise("conjugate", &out, &quats, 4, |x| {
            xyzw(&quat::conjugate(&q4(x))).to_vec()
        });
        let out = run(ffi::quat_inverse, &quats, 4, 4);
        assert_bitwise("inverse", &out, &quats, 4, |x| {
            xyzw(&quat::inverse(&q4(x)).unwrap()).to_vec()
        });
        let out = run(ffi::quat_normalize, &quats, 4, 4);
        assert_bitwise("normalize", &out, &quats, 4, |x| {
            xyzw(quat::normalize(&q4(x)).unwrap().quaternion()).to_vec()
        });
        let out = run(ffi::quat_rotate, &qv, 3, 7);
        assert_bitwise("rotate", &out, &qv, 7, |x| {
            quat::rotate(&q4(&x[..4]), &v3(&x[4..])).unwrap().as_slice().to_vec()
        });
        let matrices: [(ProductMatrix, Convention, QuatFn<Matrix4<f64>>); 4] = [
            (ProductMatrix::Left, Convention::Hamilton, quat::left_matrix),
            (ProductMatrix::Right, Convention::Hamilton, quat::right_matrix),
            (ProductMatrix::Left, Convention::Jpl, quat::left_matrix_jpl),
            (ProductMatrix::Right, Convention::Jpl, quat::right_matrix_jpl),
        ];
        for (kind, convention, f) in matrices {
            let out = run(|i, o| ffi::quat_product_matrix(kind, convention, i, o), &quats, 16, 4);
            assert_bitwise(&format!("{kind:?} {convention:?}"), &out, &quats, 4, |x| {
                row16(&f(&q4(x))).to_vec()
            });
        }
        let omegas: [(Convention, Vec3Fn<Matrix4<f64>>); 2] = [
            (Convention::Hamilton, quat::omega_matrix),
            (Convention::Jpl, quat::omega_matrix_jpl),
        ];
        for (convention, f) in omegas {
            let out = run(|i, o| ffi::quat_omega_matrix(convention, i, o), &vecs, 16, 3);
            assert_bitwise(&format!("Ω {convention:?}"), &out, &vecs, 3, |x| {
                row16(&f(&v3(x))).to_vec()
            });
        }
        let out = run(ffi::quat_exp, &vecs, 4, 3);
        assert_bitwise("quat_exp", &out, &vecs, 3, |x| {
            xyzw(quat::exp(&v3(x)).quaternion()).to_vec()
        });
        let out = run(ffi::quat_log, &quats, 3, 4);
        assert_bitwise("quat_log", &out, &quats, 4, |x| {
            quat::log(&quat::normalize(&q4(x)).unwrap()).as_slice().to_vec()
        });
        let out = run(ffi::euler_to_matrix, &chis, 9, 3);
        assert_bitwise("euler_to_matrix", &out, &chis, 3, |x| {
            row9(euler::to_rotation(&v3(x)).matrix()).to_vec()
        });
        let out = run(ffi::euler_from_matrix, &rots, 3, 9);
        assert_bitwise("euler_from_matrix", &out, &rots, 9, |x| {
            euler::from_rotation(&nalgebra::Rotation3::from_matrix_unchecked(m9(x)))
                .as_slice()
                .to_vec()
        });
        let out = run(|i, o| ffi::euler_rate_matrix(1e-6, i, o), &chis, 9, 3);
        assert_bitwise("euler_rate_matrix", &out, &chis, 3, |x| {
            row9(&euler::rate_matrix(&v3(x), 1e-6).unwrap()).to_vec()
        });
        let out = run(ffi::euler_rate_matrix_inv, &chis, 9, 3);
        assert_bitwise("euler_rate_matrix_inv", &out, &chis, 3, |x| {
            row9(&euler::rate_matrix_inv(&v3(x))).to_vec()
        });
    }
}

#[test]
fn batch_layout_is_row_major_and_xyzw() {
    // One hand-checked row per layout convention, so that a transposed or reordered output
    // cannot pass just because the single-element comparison used the same helper.
    let mut out9 = [0.0; 9];
    ffi::so3_hat(&[1.0, 2.0, 3.0], &mut out9).unwrap();
    assert_eq!(out9, [0.0, -3.0, 2.0, 3.0, 0.0, -1.0, -2.0, 1.0, 0.0]);
    let mut out4 = [0.0; 4];
    // i ⊗ j = k in [x, y, z, w]
    ffi::quat_multiply(
        Convention::Hamilton,
        &[1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        &mut out4,
    )
    .unwrap();
    assert_eq!(out4, [0.0, 0.0, 1.0, 0.0]);
    ffi::quat_multiply(Convention::Jpl, &[1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0], &mut out4).unwrap();
    assert_eq!(out4, [0.0, 0.0, -1.0, 0.0]);
    // Exp of a quarter turn about z: w = cos(π/4) last.
    ffi::quat_exp(&[0.0, 0.0, std::f64::consts::FRAC_PI_2], &mut out4).unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!((out4[2] - h).abs() <= 2e-16 && (out4[3] - h).abs() <= 2e-16, "{out4:?}");
    // Ω(ω) row 0 = [0, ω_z, −ω_y, ω_x]
    let mut out16 = [0.0; 16];
    ffi::quat_omega_matrix(Convention::Hamilton, &[1.0, 2.0, 3.0], &mut out16).unwrap();
    assert_eq!(out16[..4], [0.0, 3.0, -2.0, 1.0]);
}
