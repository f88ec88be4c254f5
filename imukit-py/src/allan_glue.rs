//! Allan-variance binding, wrapped by `imukit.noise.allan_deviation`.

use imukit::allan::{self, Estimator};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::convert::frozen_or_copy;
use crate::{contiguous, raise, threads, to_py};

/// `(M, C)` variances and `(M,)` term counts.
type VarianceAndTerms<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<i64>>);

/// `(M, C)` Allan variances and `(M,)` term counts of the `(N, C)` rate samples `y` at `rate`
/// Hz for the cluster sizes `clusters` (`τ = m / rate`), on `threads` threads (None: the
/// process-wide pool).
#[pyfunction]
#[pyo3(signature = (y, name, rate, clusters, overlapping, threads=None))]
pub(crate) fn allan_variance<'py>(
    py: Python<'py>,
    y: PyReadonlyArray2<'py, f64>,
    name: &str,
    rate: f64,
    clusters: Vec<usize>,
    overlapping: bool,
    threads: Option<usize>,
) -> PyResult<VarianceAndTerms<'py>> {
    let columns = y.shape()[1];
    let copy = frozen_or_copy(py, &y)?.readonly();
    let samples = contiguous(py, name, &copy)?;
    let estimator = if overlapping {
        Estimator::Overlapping
    } else {
        Estimator::NonOverlapping
    };
    let result = py
        .detach(|| {
            threads::run_in_pool(threads, || {
                allan::allan_variance(samples, columns, rate, &clusters, estimator)
            })
        })?
        .map_err(|e| match e {
            imukit::Error::Parameter {
                name: param,
                expected,
                got,
            } => {
                let (class, param) = if param == "y" {
                    ("ShapeError", name)
                } else {
                    ("ParameterError", param)
                };
                raise(py, class, param, format!("expected {expected}, got {got}"))
            }
            imukit::Error::RowLength { .. } => {
                let got = format!("{:?}", y.shape());
                raise(
                    py,
                    "ShapeError",
                    name,
                    format!("expected shape (N, C) with C ≥ 1, got {got}"),
                )
            }
            other => to_py(py, name, other),
        })?;
    let terms: Vec<i64> = result.terms.iter().map(|&t| t as i64).collect();
    let variance = PyArray1::from_vec(py, result.variance).reshape([clusters.len(), columns])?;
    Ok((variance, PyArray1::from_vec(py, terms)))
}
