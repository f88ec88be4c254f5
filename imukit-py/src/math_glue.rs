//! so3, quat and euler: row maps from `(n, k)` float64 arrays to new `(n, m)` arrays over the
//! core's [`imukit::ffi`] kernels, GIL released, on `threads` threads (None: the process-wide
//! pool).

use imukit::ffi::{self, Convention, Jacobian, ProductMatrix};
use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::convert::{contiguous, private_copy, zeros_for, Name};
use crate::{raise, threads, to_py};

/// Runs `kernel` over the rows of `x` (shape `(n, width_in)`) into a new `(n, width_out)` array.
fn run<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    name: &str,
    width_in: usize,
    width_out: usize,
    threads: Option<usize>,
    kernel: impl FnOnce(&[f64], &mut [f64]) -> imukit::Result<()> + Send,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let shape = x.shape();
    if shape[1] != width_in {
        let message = format!("expected shape (n, {width_in}), got {shape:?}");
        return Err(raise(py, "ShapeError", name, message));
    }
    let input = private_copy(py, &x)?;
    let input = input.readonly();
    let input = contiguous(py, name, &input)?;
    let out = zeros_for(py, name, "rows", [shape[0], width_out])?;
    {
        let mut guard = out.readwrite();
        let out_slice = guard.as_slice_mut()?;
        py.detach(|| threads::run_in_pool(threads, || kernel(input, out_slice)))?
            .map_err(|e| to_py(py, name, e))?;
    }
    Ok(out)
}

/// A `#[pyfunction] name(x, name, options…, threads=None)` running `kernel` from `(n, in)` to `(n, out)`.
macro_rules! kernel {
    ($func:ident, $width_in:expr, $width_out:expr, $kernel:expr $(, $arg:ident: $ty:ty)*) => {
        #[pyfunction]
        #[pyo3(signature = (x, name, $($arg,)* threads=None))]
        pub(crate) fn $func<'py>(
            py: Python<'py>,
            x: PyReadonlyArray2<'py, f64>,
            name: &str,
            $($arg: $ty,)*
            threads: Option<usize>,
        ) -> PyResult<Bound<'py, PyArray2<f64>>> {
            run(py, x, name, $width_in, $width_out, threads, $kernel)
        }
    };
}

kernel!(so3_hat, 3, 9, ffi::so3_hat);
kernel!(so3_vee, 9, 3, ffi::so3_vee);
kernel!(so3_exp, 3, 9, ffi::so3_exp);
kernel!(so3_exp_double_integral, 3, 9, ffi::so3_exp_double_integral);
kernel!(so3_log, 9, 3, ffi::so3_log);
kernel!(so3_jacobian, 3, 9, move |i, o| ffi::so3_jacobian(kind.0, i, o), kind: Name<Jacobian>);
kernel!(quat_conjugate, 4, 4, ffi::quat_conjugate);
kernel!(quat_inverse, 4, 4, ffi::quat_inverse);
kernel!(quat_normalize, 4, 4, ffi::quat_normalize);
kernel!(quat_rotate, 7, 3, ffi::quat_rotate);
kernel!(quat_exp, 3, 4, ffi::quat_exp);
kernel!(quat_log, 4, 3, ffi::quat_log);
kernel!(
    quat_multiply, 8, 4,
    move |i, o| ffi::quat_multiply(convention.0, i, o),
    convention: Name<Convention>
);
kernel!(
    quat_product_matrix, 4, 16,
    move |i, o| ffi::quat_product_matrix(side.0, convention.0, i, o),
    side: Name<ProductMatrix>, convention: Name<Convention>
);
kernel!(
    quat_omega_matrix, 3, 16,
    move |i, o| ffi::quat_omega_matrix(convention.0, i, o),
    convention: Name<Convention>
);
kernel!(euler_to_matrix, 3, 9, ffi::euler_to_matrix);
kernel!(euler_from_matrix, 9, 3, ffi::euler_from_matrix);
kernel!(euler_rate_matrix_inv, 3, 9, ffi::euler_rate_matrix_inv);
kernel!(
    euler_rate_matrix, 3, 9,
    move |i, o| ffi::euler_rate_matrix(tolerance, i, o),
    tolerance: f64
);
