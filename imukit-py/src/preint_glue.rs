//! Preintegration bindings: the streaming `Preintegrator` state and keyframe windows, wrapped by
//! `imukit.PreintegratedImu` and `imukit.preintegrate_windows`.

use imukit::preint::{self, ClipMask, Clipped, Scheme};
use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::{bias, noise_of, raise, to_py, SampleCopies};

/// Streaming preintegration state; wrapped by `imukit.PreintegratedImu`.
#[pyclass(name = "Preintegrator", module = "imukit._core")]
pub(crate) struct PyPreintegrator {
    inner: preint::Preintegrator,
}

fn scheme_of(py: Python<'_>, name: &str) -> PyResult<Scheme> {
    match name {
        "euler" => Ok(Scheme::Euler),
        "midpoint" => Ok(Scheme::Midpoint),
        other => Err(raise(
            py,
            "ParameterError",
            "scheme",
            format!("expected one of 'euler', 'midpoint', got {other:?}"),
        )),
    }
}

/// Private copies of the per-sample saturation flags `(gyro, accel)`: the run releases the GIL.
struct FlagCopies {
    gyro: Vec<bool>,
    accel: Vec<bool>,
}

impl FlagCopies {
    fn new(gyro: &PyReadonlyArray1<'_, bool>, accel: &PyReadonlyArray1<'_, bool>) -> Self {
        Self {
            gyro: gyro.as_array().to_vec(),
            accel: accel.as_array().to_vec(),
        }
    }

    /// The mask, or None when nothing is flagged (the unflagged path, bit for bit).
    fn mask(&self) -> Option<ClipMask<'_>> {
        let any = self.gyro.iter().chain(&self.accel).any(|&f| f);
        any.then_some(ClipMask {
            gyro: &self.gyro,
            accel: &self.accel,
        })
    }

    /// Refuses flags whose count is not the number of samples, naming the flag array.
    fn check(&self, py: Python<'_>, n: usize) -> PyResult<()> {
        for (name, flags) in [("gyro_saturated", &self.gyro), ("accel_saturated", &self.accel)] {
            if flags.len() != n {
                return Err(raise(
                    py,
                    "ShapeError",
                    name,
                    format!("expected one flag per sample ({n}), got {}", flags.len()),
                ));
            }
        }
        Ok(())
    }
}

fn finite3(py: Python<'_>, name: &str, v: [f64; 3]) -> PyResult<Vector3<f64>> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(raise(
            py,
            "NonFiniteError",
            name,
            format!("expected finite values, got {v:?}"),
        ))
    }
}

/// Whether every delta, covariance and Jacobian entry is finite: one streaming step with finite
/// readings near f64's limits (or a subnormal step) can overflow them, and the core's streaming
/// step leaves that check to its caller (its batch paths make it themselves).
fn all_finite(p: &preint::Preintegrator) -> bool {
    let (covariance, jacobian, combined) = (p.covariance(), p.bias_jacobian(), p.covariance_combined());
    [
        p.delta_rotation.as_slice(),
        p.delta_velocity.as_slice(),
        p.delta_position.as_slice(),
        covariance.as_slice(),
        jacobian.as_slice(),
        combined.as_ref().map_or(&[][..], |c| c.as_slice()),
    ]
    .iter()
    .all(|part| part.iter().all(|x| x.is_finite()))
}

/// Column-major nalgebra storage as a row-major `(r, c)` array.
fn rows<'py>(py: Python<'py>, m: &[f64], r: usize, c: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let data: Vec<f64> = (0..r * c).map(|i| m[(i % c) * r + i / c]).collect();
    PyArray1::from_vec(py, data).reshape([r, c])
}

#[pymethods]
impl PyPreintegrator {
    #[new]
    fn new(
        py: Python<'_>,
        bias_values: [f64; 6],
        noise: [f64; 4],
        combined: bool,
        scheme: &str,
        saturation_noise_factor: f64,
    ) -> PyResult<Self> {
        let b = bias(bias_values);
        let inner = preint::Preintegrator::new(b.gyro, b.accel, noise_of(noise))
            .with_scheme(scheme_of(py, scheme)?)
            .with_saturation_noise_factor(saturation_noise_factor)
            .map_err(|e| to_py(py, "saturation_noise_factor", e))?;
        Ok(Self {
            inner: if combined { inner.with_bias_walk() } else { inner },
        })
    }

    /// This preintegration followed by `next`, as one.
    fn merge(&self, py: Python<'_>, next: PyRef<'_, PyPreintegrator>) -> PyResult<PyPreintegrator> {
        match self.inner.merge(&next.inner) {
            Ok(inner) => Ok(PyPreintegrator { inner }),
            Err(imukit::Error::Parameter { expected, got, .. }) => Err(raise(
                py,
                "ParameterError",
                "other",
                format!("expected {expected}, got {got}"),
            )),
            Err(e) => Err(to_py(py, "other", e)),
        }
    }

    /// The 15×15 combined covariance `[δθ, δv, δp, δb_g, δb_a]`, or None when not tracked.
    fn covariance_combined<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        let Some(c) = self.inner.covariance_combined() else {
            return Ok(None);
        };
        // Symmetric: column-major storage reads the same as row-major.
        Ok(Some(PyArray1::from_slice(py, c.as_slice()).reshape([15, 15])?))
    }

    /// One interval of `dt` seconds: euler, `accel`, `gyro` held over it; midpoint, sampled at its
    /// end (the window's first sample comes with `dt = 0`); the flags mark clipped sensors.
    fn integrate_measurement(
        &mut self,
        py: Python<'_>,
        accel: [f64; 3],
        gyro: [f64; 3],
        dt: f64,
        gyro_saturated: bool,
        accel_saturated: bool,
    ) -> PyResult<()> {
        let (a, w) = (finite3(py, "accel", accel)?, finite3(py, "gyro", gyro)?);
        let starts = self.inner.scheme == Scheme::Midpoint && self.inner.last_sample().is_none();
        if starts && dt != 0.0 {
            return Err(raise(
                py,
                "ParameterError",
                "dt",
                format!("the first sample of a midpoint window has no interval before it: expected 0, got {dt}"),
            ));
        }
        let positive = dt > 0.0 && dt.is_finite();
        if !starts && !positive {
            return Err(raise(
                py,
                "ParameterError",
                "dt",
                format!("expected a positive, finite step, got {dt}"),
            ));
        }
        // On a copy: a step that overflows (dt or a reading near f64's limits) must leave the
        // preintegration as it was, not poisoned with NaN.
        let mut next = self.inner.clone();
        let clipped = Clipped {
            gyro: gyro_saturated,
            accel: accel_saturated,
        };
        next.integrate_measurement_clipped(&a, &w, dt, clipped);
        if !all_finite(&next) {
            return Err(raise(
                py,
                "NonFiniteError",
                "accel / gyro / dt",
                format!("too large (or dt too small) to compute with: the step of {dt} s overflows"),
            ));
        }
        self.inner = next;
        Ok(())
    }

    /// The N − 1 intervals of the samples (euler: sample k held over `[t_k, t_k+1)`; midpoint:
    /// between samples k and k+1, continuing from the last sample, which must be sample 0).
    fn integrate(
        &mut self,
        py: Python<'_>,
        t: PyReadonlyArray1<'_, f64>,
        gyro: PyReadonlyArray2<'_, f64>,
        accel: PyReadonlyArray2<'_, f64>,
        gyro_saturated: PyReadonlyArray1<'_, bool>,
        accel_saturated: PyReadonlyArray1<'_, bool>,
    ) -> PyResult<()> {
        let copies = SampleCopies::new(py, &t, &gyro, &accel)?;
        let samples = copies.samples(py)?;
        let flags = FlagCopies::new(&gyro_saturated, &accel_saturated);
        flags.check(py, t.len())?;
        let inner = &mut self.inner;
        match py.detach(|| inner.integrate_samples_clipped(&samples, flags.mask().as_ref())) {
            Err(imukit::Error::Parameter {
                name: "samples",
                expected,
                got,
            }) => Err(raise(
                py,
                "ParameterError",
                "imu",
                format!("expected {expected}, got {got}"),
            )),
            // The core refuses (adding nothing) finite samples that overflow the deltas or covariance.
            other => other.map_err(|e| to_py(py, "imu / bias", e)),
        }
    }

    /// `(ΔR (3, 3), Δv (3,), Δp (3,), Δt, covariance (9, 9), bias Jacobian (9, 6))`.
    #[allow(clippy::type_complexity)] // a plain tuple is the simplest thing to unpack in Python
    fn state<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        f64,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
    )> {
        let p = &self.inner;
        Ok((
            rows(py, p.delta_rotation.as_slice(), 3, 3)?,
            PyArray1::from_slice(py, p.delta_velocity.as_slice()),
            PyArray1::from_slice(py, p.delta_position.as_slice()),
            p.delta_t,
            rows(py, p.covariance().as_slice(), 9, 9)?,
            rows(py, p.bias_jacobian().as_slice(), 9, 6)?,
        ))
    }
}

/// One preintegration per window `[boundaries[m], boundaries[m + 1]]`, each starting from a copy
/// of the empty `template` (scheme, bias, noise, saturation factor, bias walk), in parallel on
/// `threads` threads (0: all cores), GIL released.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // the samples, their flags, the boundaries and the run's options
pub(crate) fn preint_windows(
    py: Python<'_>,
    t: PyReadonlyArray1<'_, f64>,
    gyro: PyReadonlyArray2<'_, f64>,
    accel: PyReadonlyArray2<'_, f64>,
    gyro_saturated: PyReadonlyArray1<'_, bool>,
    accel_saturated: PyReadonlyArray1<'_, bool>,
    boundaries: PyReadonlyArray1<'_, f64>,
    template: PyRef<'_, PyPreintegrator>,
    threads: usize,
) -> PyResult<Vec<PyPreintegrator>> {
    let template = template.inner.clone();
    let copies = SampleCopies::new(py, &t, &gyro, &accel)?;
    let samples = copies.samples(py)?;
    let flags = FlagCopies::new(&gyro_saturated, &accel_saturated);
    flags.check(py, t.len())?;
    let mask = flags.mask();
    let boundaries = crate::private_copy(py, &boundaries)?.readonly();
    let boundaries = crate::contiguous(py, "boundaries", &boundaries)?;
    let run = || preint::preintegrate_windows_clipped(&samples, mask.as_ref(), boundaries, &template);
    let windows = py.detach(|| {
        if threads == 0 {
            return Ok(run());
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map(|pool| pool.install(run))
    });
    let windows = windows
        .map_err(|e| raise(py, "ParameterError", "threads", e))?
        .map_err(|e| to_py(py, "imu / bias", e))?;
    Ok(windows.into_iter().map(|inner| PyPreintegrator { inner }).collect())
}
