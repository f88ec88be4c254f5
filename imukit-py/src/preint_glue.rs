//! Preintegration bindings: the streaming `Preintegrator` state and keyframe windows, wrapped by
//! `imukit.PreintegratedImu` and `imukit.preintegrate_windows`.

use imukit::imu::{Bias, Samples};
use imukit::preint::{self, ClipMask, Clipped, Scheme};
use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::convert::{zeros, BiasFields, Demand, Name, NoiseFields};
use crate::{raise, to_py, SampleCopies};

/// What `__reduce__` returns for a state class: `(Class.from_state, (words,))`.
type Reduced<'py> = (Bound<'py, PyAny>, (Vec<f64>,));

/// `(T.from_state, (words,))`: pickles (and `copy.deepcopy`s) a state class exactly.
fn reduced<T: pyo3::PyTypeInfo>(py: Python<'_>, words: Vec<f64>) -> PyResult<Reduced<'_>> {
    Ok((py.get_type::<T>().getattr("from_state")?, (words,)))
}

/// Streaming preintegration state; wrapped by `imukit.PreintegratedImu`.
#[pyclass(name = "Preintegrator", module = "imukit._core")]
pub(crate) struct PyPreintegrator {
    inner: preint::Preintegrator,
}

/// Private copies of the per-sample saturation flags `(gyro, accel)`: the run releases the GIL.
/// None are made when no sample is flagged (the common case): the run then reads no flag.
struct FlagCopies {
    gyro: Vec<bool>,
    accel: Vec<bool>,
}

impl FlagCopies {
    fn new(py: Python<'_>, gyro: &PyReadonlyArray1<'_, bool>, accel: &PyReadonlyArray1<'_, bool>) -> PyResult<Self> {
        let (gyro, accel) = (gyro.as_array(), accel.as_array());
        if !gyro.iter().chain(accel.iter()).any(|&f| f) {
            return Ok(Self {
                gyro: Vec::new(),
                accel: Vec::new(),
            });
        }
        let copy = |name: &'static str, flags: &numpy::ndarray::ArrayView1<'_, bool>| {
            let mut out = imukit::try_vec(flags.len(), "flags").map_err(|e| to_py(py, name, e))?;
            out.extend(flags.iter().copied());
            Ok::<_, PyErr>(out)
        };
        Ok(Self {
            gyro: copy("gyro_saturated", &gyro)?,
            accel: copy("accel_saturated", &accel)?,
        })
    }

    /// The mask, or None when nothing is flagged (the unflagged path, bit for bit): the copies
    /// exist only when a flag is set.
    fn mask(&self) -> Option<ClipMask<'_>> {
        (!self.gyro.is_empty()).then_some(ClipMask {
            gyro: &self.gyro,
            accel: &self.accel,
        })
    }
}

/// The options of an `imukit.PreintParams`, by attribute name (gravity is Python's: the core's
/// deltas are gravity-free).
#[derive(FromPyObject)]
pub(crate) struct Params {
    #[pyo3(attribute)]
    noise: NoiseFields,
    #[pyo3(attribute)]
    bias: BiasFields,
    #[pyo3(attribute)]
    scheme: Name<Scheme>,
    #[pyo3(attribute)]
    combined: bool,
    #[pyo3(attribute)]
    saturation_noise_factor: f64,
}

impl Params {
    /// The empty preintegrator these options describe.
    fn template(&self, py: Python<'_>) -> PyResult<preint::Preintegrator> {
        let bias = Bias::from(self.bias);
        let inner = preint::Preintegrator::new(bias.gyro, bias.accel, self.noise.into())
            .with_scheme(self.scheme.0)
            .with_saturation_noise_factor(self.saturation_noise_factor)
            .map_err(|e| to_py(py, "saturation_noise_factor", e))?;
        Ok(if self.combined { inner.with_bias_walk() } else { inner })
    }
}

/// `e` raised under the Python argument `argument` that carried the core's input (`imu` for the
/// core's `samples`, `other` for `next`) when it is a [`imukit::Error::Parameter`] (as "expected …,
/// got …"), else as [`to_py`] does with `fallback`.
fn as_argument(py: Python<'_>, argument: &str, fallback: &str, e: imukit::Error) -> PyErr {
    match e {
        imukit::Error::Parameter { expected, got, .. } => raise(
            py,
            "ParameterError",
            argument,
            format!("expected {expected}, got {got}"),
        ),
        other => to_py(py, fallback, other),
    }
}

/// Column-major nalgebra storage as a row-major `(r, c)` array.
fn rows<'py>(py: Python<'py>, m: &[f64], r: usize, c: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let data: Vec<f64> = (0..r * c).map(|i| m[(i % c) * r + i / c]).collect();
    PyArray1::from_vec(py, data).reshape([r, c])
}

#[pymethods]
impl PyPreintegrator {
    /// An empty preintegrator with the options of `params` (an `imukit.PreintParams`).
    #[new]
    fn new(py: Python<'_>, params: Params) -> PyResult<Self> {
        Ok(Self {
            inner: params.template(py)?,
        })
    }

    /// The preintegrator of `words` (from `__reduce__`: the complete core state).
    #[staticmethod]
    fn from_state(py: Python<'_>, words: Vec<f64>) -> PyResult<Self> {
        let inner = preint::Preintegrator::from_state_words(&words).map_err(|e| to_py(py, "words", e))?;
        Ok(Self { inner })
    }

    /// Pickles (and `copy.deepcopy`s) as `Preintegrator.from_state(words)`: exact, every part of
    /// the state included.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Reduced<'py>> {
        reduced::<Self>(py, self.inner.state_words())
    }

    /// This preintegration followed by `next`, as one.
    fn merge(&self, py: Python<'_>, next: PyRef<'_, PyPreintegrator>) -> PyResult<PyPreintegrator> {
        let inner = self
            .inner
            .merge(&next.inner)
            .map_err(|e| as_argument(py, "other", "other", e))?;
        Ok(PyPreintegrator { inner })
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
        let clipped = Clipped {
            gyro: gyro_saturated,
            accel: accel_saturated,
        };
        self.inner
            .try_integrate_measurement(&Vector3::from(accel), &Vector3::from(gyro), dt, clipped)
            .map_err(|e| to_py(py, "accel / gyro / dt", e))
    }

    /// The N − 1 intervals of the samples (euler: sample k held over `[t_k, t_k+1)`; midpoint:
    /// between samples k and k+1), continuing from the last sample, which must be sample 0 (the
    /// same time on the caller's `clock`, the first and last sample's times, and readings). On
    /// `threads` threads (None: the process-wide pool): long lie_euler batches run in chunks.
    #[pyo3(signature = (t, gyro, accel, gyro_saturated, accel_saturated, clock, threads=None))]
    #[allow(clippy::too_many_arguments)] // the sample arrays, their flags and the thread count
    fn integrate(
        &mut self,
        py: Python<'_>,
        t: PyReadonlyArray1<'_, f64>,
        gyro: PyReadonlyArray2<'_, f64>,
        accel: PyReadonlyArray2<'_, f64>,
        gyro_saturated: PyReadonlyArray1<'_, bool>,
        accel_saturated: PyReadonlyArray1<'_, bool>,
        clock: [f64; 2],
        threads: Option<usize>,
    ) -> PyResult<()> {
        let copies = SampleCopies::new(py, &t, &gyro, &accel)?;
        let samples = copies.samples(py)?;
        let flags = FlagCopies::new(py, &gyro_saturated, &accel_saturated)?;
        let inner = &mut self.inner;
        let mask = flags.mask();
        crate::threads::interruptible(py, samples.t().len(), |cancel| {
            crate::threads::run_in_pool(threads, || {
                inner.integrate_samples_cancellable(&samples, mask.as_ref(), clock, cancel)
            })
        })??
        .map_err(|e| as_argument(py, "imu", "imu / bias", e))
    }

    /// `(ΔR (3, 3), Δv (3,), Δp (3,), Δt, covariance (9, 9), bias Jacobian (9, 6), combined
    /// covariance (15, 15) or None)`: everything `PreintegratedImu.snapshot` reads, in one call.
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
        Option<Bound<'py, PyArray2<f64>>>,
    )> {
        let p = &self.inner;
        // Symmetric: column-major storage reads the same as row-major.
        let combined = p
            .covariance_combined()
            .map(|c| PyArray1::from_slice(py, c.as_slice()).reshape([15, 15]));
        Ok((
            rows(py, p.delta_rotation.as_slice(), 3, 3)?,
            PyArray1::from_slice(py, p.delta_velocity.as_slice()),
            PyArray1::from_slice(py, p.delta_position.as_slice()),
            p.delta_t,
            rows(py, p.covariance().as_slice(), 9, 9)?,
            rows(py, p.bias_jacobian().as_slice(), 9, 6)?,
            combined.transpose()?,
        ))
    }
}

/// The samples of an `imukit.ImuData`, read by attribute name.
#[derive(FromPyObject)]
pub(crate) struct ImuArrays<'py> {
    #[pyo3(attribute("seconds"))]
    t: PyReadonlyArray1<'py, f64>,
    #[pyo3(attribute)]
    gyro: PyReadonlyArray2<'py, f64>,
    #[pyo3(attribute)]
    accel: PyReadonlyArray2<'py, f64>,
    #[pyo3(attribute)]
    gyro_saturated: PyReadonlyArray1<'py, bool>,
    #[pyo3(attribute)]
    accel_saturated: PyReadonlyArray1<'py, bool>,
}

/// `kernel` over private copies of `imu` and `boundaries` (the run releases the GIL and stops at
/// Ctrl-C where the kernel polls its cancel flag), on `threads` threads (None: the process-wide pool).
fn run_windows<'py, R: Send>(
    py: Python<'py>,
    imu: &ImuArrays<'py>,
    boundaries: &PyReadonlyArray1<'py, f64>,
    threads: Option<usize>,
    kernel: impl FnOnce(&Samples<'_>, Option<&ClipMask<'_>>, &[f64], &imukit::Cancel) -> imukit::Result<R> + Send,
) -> PyResult<R> {
    let copies = SampleCopies::new(py, &imu.t, &imu.gyro, &imu.accel)?;
    let samples = copies.samples(py)?;
    let flags = FlagCopies::new(py, &imu.gyro_saturated, &imu.accel_saturated)?;
    let mask = flags.mask();
    let boundaries = crate::private_copy(py, boundaries)?.readonly();
    let boundaries = crate::contiguous(py, "boundaries", &boundaries)?;
    crate::threads::interruptible(py, samples.t().len(), |cancel| {
        crate::threads::run_in_pool(threads, || kernel(&samples, mask.as_ref(), boundaries, cancel))
    })??
    .map_err(|e| to_py(py, "imu / bias", e))
}

/// One preintegration per window `[boundaries[m], boundaries[m + 1]]` of the `ImuData` `imu`,
/// each starting from a copy of the empty `template` (scheme, bias, noise, saturation factor, bias
/// walk), in parallel on `threads` threads (None: the process-wide pool), GIL released.
#[pyfunction]
pub(crate) fn preint_windows<'py>(
    py: Python<'py>,
    imu: ImuArrays<'py>,
    boundaries: PyReadonlyArray1<'py, f64>,
    template: PyRef<'py, PyPreintegrator>,
    threads: Option<usize>,
) -> PyResult<Vec<PyPreintegrator>> {
    let template = template.inner.clone();
    let windows = run_windows(py, &imu, &boundaries, threads, |samples, mask, b, cancel| {
        preint::preintegrate_windows_clipped_cancellable(samples, mask, (b, &template), cancel)
    })?;
    Ok(windows.into_iter().map(|inner| PyPreintegrator { inner }).collect())
}

/// The arrays of a `Preintegration` record: `(ΔR (M, 3, 3), Δv (M, 3), Δp (M, 3), Δt (M,),
/// covariance (M, 9, 9), bias Jacobian (M, 9, 6), combined covariance (M, 15, 15) or None)`.
pub(crate) type Record<'py> = (
    Bound<'py, PyArray3<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray3<f64>>,
    Bound<'py, PyArray3<f64>>,
    Option<Bound<'py, PyArray3<f64>>>,
);

/// Every window `[boundaries[m], boundaries[m + 1]]` preintegrated with the options `params` (an
/// `imukit.PreintParams`), written into fresh arrays in one call (`imukit.preint.Preintegration`'s fields), in
/// parallel on `threads` threads (None: the process-wide pool), GIL released.
#[pyfunction]
pub(crate) fn preint_windows_record<'py>(
    py: Python<'py>,
    imu: ImuArrays<'py>,
    boundaries: PyReadonlyArray1<'py, f64>,
    params: Params,
    threads: Option<usize>,
) -> PyResult<Record<'py>> {
    let template = params.template(py)?;
    let m = boundaries.as_array().len().saturating_sub(1);
    let combined = template.covariance_combined().is_some();
    // 1.2 kB a window (2 kB with the combined covariance): all of it or a ResourceError.
    let per_window = 8 * (9 + 3 + 3 + 1 + 81 + 54 + if combined { 225 } else { 0 });
    let demand = Demand {
        argument: "boundaries",
        what: "windows",
        count: m,
        bytes: m as u128 * per_window,
    };
    let record: Record<'py> = (
        zeros(py, &demand, [m, 3, 3])?,
        zeros(py, &demand, [m, 3])?,
        zeros(py, &demand, [m, 3])?,
        zeros(py, &demand, [m])?,
        zeros(py, &demand, [m, 9, 9])?,
        zeros(py, &demand, [m, 9, 6])?,
        combined.then(|| zeros(py, &demand, [m, 15, 15])).transpose()?,
    );
    {
        let (mut r, mut v, mut p) = (record.0.readwrite(), record.1.readwrite(), record.2.readwrite());
        let (mut dt, mut cov, mut jac) = (record.3.readwrite(), record.4.readwrite(), record.5.readwrite());
        let mut c15 = record.6.as_ref().map(|c| c.readwrite());
        let c15 = match c15.as_mut() {
            Some(c) => Some(c.as_slice_mut()?.as_chunks_mut().0.as_chunks_mut().0),
            None => None,
        };
        let out = preint::WindowsOut {
            delta_rotation: r.as_slice_mut()?.as_chunks_mut().0.as_chunks_mut().0,
            delta_velocity: v.as_slice_mut()?.as_chunks_mut().0,
            delta_position: p.as_slice_mut()?.as_chunks_mut().0,
            delta_t: dt.as_slice_mut()?,
            covariance: cov.as_slice_mut()?.as_chunks_mut().0.as_chunks_mut().0,
            bias_jacobian: jac.as_slice_mut()?.as_chunks_mut().0.as_chunks_mut().0,
            covariance_combined: c15,
        };
        run_windows(py, &imu, &boundaries, threads, |samples, mask, b, cancel| {
            preint::preintegrate_windows_cancellable(samples, mask, (b, &template), out, cancel)
        })?;
    }
    Ok(record)
}

/// The lever-arm-complete covariance of one window (`imukit::preint::LeverNoise`); held by
/// `imukit.PreintegratedImu` and read by `preintegrate_windows` with a lever arm.
#[pyclass(name = "LeverNoise", module = "imukit._core")]
pub(crate) struct PyLeverNoise {
    inner: preint::LeverNoise,
}

#[pymethods]
impl PyLeverNoise {
    /// The window of `words` (from `__reduce__`).
    #[staticmethod]
    fn from_state(py: Python<'_>, words: Vec<f64>) -> PyResult<Self> {
        preint::LeverNoise::from_state_words(&words)
            .map(|inner| Self { inner })
            .map_err(|e| to_py(py, "words", e))
    }

    /// Pickles as `LeverNoise.from_state(words)`: exact.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Reduced<'py>> {
        reduced::<Self>(py, self.inner.state_words())
    }

    /// This window followed by `next`, as one.
    fn merge(&self, py: Python<'_>, next: PyRef<'_, PyLeverNoise>) -> PyResult<PyLeverNoise> {
        let merged = self.inner.merge(&next.inner);
        merged
            .map(|inner| PyLeverNoise { inner })
            .map_err(|e| as_argument(py, "other", "other", e))
    }

    /// `(covariance (9, 9), bias Jacobian (9, 6), combined covariance (15, 15) or None)`.
    #[allow(clippy::type_complexity)]
    fn state<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
        Option<Bound<'py, PyArray2<f64>>>,
    )> {
        let p = &self.inner;
        let (cov, jac) = (p.covariance(), p.bias_jacobian());
        let combined = p.covariance_combined();
        // Symmetric: column-major storage reads the same as row-major.
        let combined = combined.map(|c| PyArray1::from_slice(py, c.as_slice()).reshape([15, 15]));
        Ok((
            rows(py, cov.as_slice(), 9, 9)?,
            rows(py, jac.as_slice(), 9, 6)?,
            combined.transpose()?,
        ))
    }
}

/// The lever-arm-complete covariance of each window `[boundaries[m], boundaries[m + 1]]` (sample
/// stamps of `imu.seconds`) of the body origin's readings `imu` of a sensor at
/// `(rotation R_bs, lever_arm)`, preintegrated with `params` (zero bias), GIL released.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lever_noise<'py>(
    py: Python<'py>,
    imu: ImuArrays<'py>,
    rotation: [[f64; 3]; 3],
    lever_arm: [f64; 3],
    boundaries: PyReadonlyArray1<'py, f64>,
    params: Params,
    threads: Option<usize>,
) -> PyResult<Vec<PyLeverNoise>> {
    let pose =
        imukit::extrinsics::SensorPose::new(nalgebra::Matrix3::from(rotation).transpose(), Vector3::from(lever_arm))
            .map_err(|e| to_py(py, "body_from_sensor", e))?;
    let template = params.template(py)?;
    let windows = run_windows(py, &imu, &boundaries, threads, |samples, mask, b, _| {
        preint::LeverNoise::windows(samples, mask, &pose, b, &template)
    })?;
    Ok(windows.into_iter().map(|inner| PyLeverNoise { inner }).collect())
}
