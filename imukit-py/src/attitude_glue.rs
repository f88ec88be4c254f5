//! `attitude_integrate`: `imukit.integrate_attitude` over [`imukit::attitude::integrate`].

use imukit::attitude::{self, Representation, Scheme};
use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::convert::{contiguous, empty, frozen_or_copy, rows, unit_quaternion, Demand, Name};
use crate::{threads, to_py};

/// `(n, 4)` attitudes `[x, y, z, w]`, or `(1, 4)` with `final_only`; on `threads` threads (None: the
/// process-wide pool).
#[pyfunction]
#[pyo3(signature = (t, gyro, initial, scheme, representation, gimbal_tolerance, final_only, threads=None))]
#[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.integrate_attitude
pub(crate) fn attitude_integrate<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    initial: [f64; 4],
    scheme: Name<Scheme>,
    representation: Name<Representation>,
    gimbal_tolerance: f64,
    final_only: bool,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let options = attitude::Options {
        scheme: scheme.0,
        representation: representation.0,
        gimbal_tolerance,
    };
    let initial = unit_quaternion(initial);
    let (t, gyro) = (frozen_or_copy(py, &t)?, frozen_or_copy(py, &gyro)?);
    let (t, gyro) = (t.readonly(), gyro.readonly());
    let (t, gyro) = (contiguous(py, "t", &t)?, rows::<3>(py, "gyro", &gyro)?);
    let n = if final_only { 1 } else { t.len() };
    // Every row is written (`attitude::integrate` stores all, or the final one is copied in) or
    // the call fails.
    let out = empty(py, &Demand::of("t", "attitudes", &[n, 4]), [n, 4])?;
    {
        let mut guard = out.readwrite();
        let out_slice = guard.as_slice_mut()?;
        let store = (!final_only).then_some(out_slice.as_chunks_mut::<4>().0);
        let last = threads::interruptible(py, t.len(), |cancel| {
            threads::run_in_pool(threads, || {
                attitude::integrate_cancellable(t, gyro, &initial, &options, store, cancel)
            })
        })??;
        // Errors that name no argument (gimbal lock, overflow) are about the rates.
        let last = last.map_err(|e| to_py(py, "gyro", e))?;
        if final_only {
            out_slice.copy_from_slice(&[last.i, last.j, last.k, last.w]);
        }
    }
    Ok(out)
}
