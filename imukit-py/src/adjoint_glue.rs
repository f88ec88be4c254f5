//! `preint_adjoint`: `imukit.torch`'s CPU path over
//! [`imukit::adjoint`]. Unlike the other bindings, the inputs are read in place, not copied: they
//! are the buffers of contiguous torch tensors that autograd holds for the call (the issue's
//! zero-copy contract); the GIL is released while the kernels run.

use imukit::adjoint::{self, Noise, Outputs, Windows};
use numpy::{PyArray3, PyArrayMethods, PyReadonlyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::convert::{contiguous, zeros_for};
use crate::{threads, to_py};

/// The buffers of one call, borrowed from the arrays.
struct Buffers<'a, 'py> {
    h: &'a PyReadonlyArray2<'py, f64>,
    w: &'a PyReadonlyArrayDyn<'py, f64>,
    a: &'a PyReadonlyArrayDyn<'py, f64>,
    a_end: &'a Option<PyReadonlyArrayDyn<'py, f64>>,
    cov: &'a Option<(PyReadonlyArrayDyn<'py, f64>, PyReadonlyArrayDyn<'py, f64>)>,
    densities: &'a Option<PyReadonlyArray2<'py, f64>>,
}

impl<'a> Buffers<'a, '_> {
    fn windows(&self, py: Python<'a>) -> PyResult<(usize, Windows<'a>)> {
        let noise = match (self.cov, self.densities) {
            (Some((g, a)), _) => Some(Noise::Samples(
                contiguous(py, "gyro_cov", g)?,
                contiguous(py, "accel_cov", a)?,
            )),
            (None, Some(q)) => Some(Noise::Densities(contiguous(py, "noise", q)?)),
            (None, None) => None,
        };
        let a_end = match self.a_end {
            Some(a) => Some(contiguous(py, "accel", a)?),
            None => None,
        };
        let windows = Windows {
            n: self.h.shape()[1],
            h: contiguous(py, "dt", self.h)?,
            w: contiguous(py, "gyro", self.w)?,
            a: contiguous(py, "accel", self.a)?,
            a_end,
            noise,
        };
        Ok((self.h.shape()[0], windows))
    }
}

/// Without `bar`: the records `(windows, n or 1, width)` of `imukit::adjoint::forward`; with
/// `bar` (their cotangents): the input cotangents `(windows, n, grad_width)` of
/// `imukit::adjoint::backward`. The noise: `gyro_cov` and `accel_cov` per sample, else
/// `noise_density` `(windows, 2)` variance densities.
#[pyfunction]
#[pyo3(signature = (h, w, a, *, bar, a_end, gyro_cov, accel_cov, noise_density, per_step, covariance, jacobian))]
#[allow(clippy::too_many_arguments)] // the kernel's buffers and output switches, by keyword
pub(crate) fn preint_adjoint<'py>(
    py: Python<'py>,
    h: PyReadonlyArray2<'py, f64>,
    w: PyReadonlyArrayDyn<'py, f64>,
    a: PyReadonlyArrayDyn<'py, f64>,
    bar: Option<PyReadonlyArrayDyn<'py, f64>>,
    a_end: Option<PyReadonlyArrayDyn<'py, f64>>,
    gyro_cov: Option<PyReadonlyArrayDyn<'py, f64>>,
    accel_cov: Option<PyReadonlyArrayDyn<'py, f64>>,
    noise_density: Option<PyReadonlyArray2<'py, f64>>,
    per_step: bool,
    covariance: bool,
    jacobian: bool,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let cov = gyro_cov.zip(accel_cov);
    let buffers = Buffers {
        h: &h,
        w: &w,
        a: &a,
        a_end: &a_end,
        cov: &cov,
        densities: &noise_density,
    };
    let (count, x) = buffers.windows(py)?;
    let outputs = Outputs {
        per_step,
        covariance,
        jacobian,
    };
    let bar = match &bar {
        Some(b) => Some(contiguous(py, "bar", b)?),
        None => None,
    };
    let shape = match bar {
        Some(_) => [count, x.n, x.grad_width()],
        None => [count, if per_step { x.n } else { 1 }, outputs.width()],
    };
    let out = zeros_for(py, "gyro", "preintegration records", shape)?;
    {
        let mut guard = out.readwrite();
        let slice = guard.as_slice_mut()?;
        let run = || match bar {
            Some(bar) => adjoint::backward(&x, &outputs, bar, slice),
            None => adjoint::forward(&x, &outputs, slice),
        };
        py.detach(|| threads::run_in_pool(None, run))?
            .map_err(|e| to_py(py, "gyro", e))?;
    }
    Ok(out)
}
