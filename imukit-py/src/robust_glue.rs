//! `Robust` filter bindings. Values cross by field name:
//!
//! | Python (`imukit._core`) | Rust (`imukit::filters`) |
//! |---|---|
//! | `RobustParams(**fields)` (omitted fields take the Rust `Default`; `.fields()` by name) | `RobustParams` |
//! | `RobustState(**fields)` (named getters, pickles by name) | `RobustState` by its `Fields` names |
//! | `RobustFilter(params, world)` | `Robust` |
//!
//! Converts only: values are checked by the core, Python types by `imukit._robust`.

use imukit::filters::{Fields, Robust, RobustOutputs, RobustParams, RobustState, World};
use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::convert::{real_number, state_copy, unit_quaternion, FilterRecord, Name, SampleCopies};
use crate::threads::{interruptible, prefaulting, run_in_pool, Fresh};
use crate::{raise, to_py};

/// `T`'s fields from a dict of name → float: unknown names are a `ParameterError`, missing ones
/// take `base`'s value.
fn from_fields<T: Fields>(py: Python<'_>, base: &T, fields: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<f64>> {
    let mut values = base.values();
    for (key, value) in fields.into_iter().flat_map(|d| d.iter()) {
        let name: String = key.extract()?;
        let Some(i) = T::NAMES.iter().position(|n| *n == name) else {
            return Err(raise(py, "ParameterError", &name, "unknown field"));
        };
        values[i] = real_number(py, &name, &value)?;
    }
    Ok(values)
}

fn to_dict<'py, T: Fields>(py: Python<'py>, x: &T) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, value) in T::NAMES.iter().zip(x.values()) {
        d.set_item(name, value)?;
    }
    Ok(d)
}

/// The parameters of `Robust` (frozen; compared by value; pickles by name).
#[pyclass(name = "RobustParams", module = "imukit._core", frozen, eq, from_py_object)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PyRobustParams(RobustParams);

#[pymethods]
impl PyRobustParams {
    #[new]
    #[pyo3(signature = (**fields))]
    fn new(py: Python<'_>, fields: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let values = from_fields(py, &RobustParams::default(), fields)?;
        let params = RobustParams::from_values(&values).ok_or_else(|| raise(py, "ParameterError", "params", "?"))?;
        params.validate().map_err(|e| to_py(py, "params", e))?;
        Ok(Self(params))
    }

    /// The fields by name (the constructor's keywords).
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        to_dict(py, &self.0)
    }

    fn __repr__(&self) -> String {
        let fields: Vec<String> = RobustParams::NAMES
            .iter()
            .zip(self.0.values())
            .map(|(n, v)| format!("{n}={v:?}"))
            .collect();
        format!("RobustParams({})", fields.join(", "))
    }

    fn __getnewargs_ex__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        Ok((PyTuple::empty(py), self.fields(py)?))
    }
}

/// The state of a `Robust` filter, by field name.
#[pyclass(name = "RobustState", module = "imukit._core", frozen, subclass, eq)]
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PyRobustState(RobustState);

#[pymethods]
impl PyRobustState {
    /// A state from its fields by name (what pickling stores), checked by the core; or a copy of
    /// `state`, which the core has checked already (what `Robust.update` makes of each sample's
    /// state: through the ~80 fields by name it took 80–90 µs).
    #[new]
    #[pyo3(signature = (state=None, /, **fields))]
    fn new(
        py: Python<'_>,
        state: Option<PyRef<'_, PyRobustState>>,
        fields: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        if let Some(state) = state {
            return state_copy(py, &*state, fields.is_some_and(|f| !f.is_empty()));
        }
        let values = from_fields(py, &RobustState::default(), fields)?;
        RobustState::restored(&values)
            .map(Self)
            .map_err(|e| to_py(py, "state", e))
    }

    /// The fields by name.
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        to_dict(py, &self.0)
    }

    fn __getnewargs_ex__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        Ok((PyTuple::empty(py), self.fields(py)?))
    }

    /// This state with its clock at `time` [s].
    #[pyo3(name = "_at_time")]
    fn at_time(&self, time: f64) -> Self {
        let mut s = self.0;
        s.time = time;
        Self(s)
    }

    /// Attitude `q_wb` as `[x, y, z, w]`.
    #[getter]
    fn quaternion<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.0.q.coords.as_slice())
    }

    /// Gyro-bias estimate [rad/s].
    #[getter]
    fn gyro_bias<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.0.bias.as_slice())
    }

    /// Standard deviation of the bias estimate per axis [rad/s].
    #[getter]
    fn gyro_bias_sigma<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let p = &self.0.bias_cov;
        PyArray1::from_slice(py, &[p[(0, 0)].sqrt(), p[(1, 1)].sqrt(), p[(2, 2)].sqrt()])
    }

    /// Whether the attitude has been initialised.
    #[getter]
    fn initialized(&self) -> bool {
        self.0.initialized
    }

    /// Time of the last sample [s].
    #[getter]
    fn time(&self) -> f64 {
        self.0.time
    }
}

/// The batch outputs: `(q xyzw, bias, bias sigma, rest, mag_disturbed, final state)`.
type Outputs<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<bool>>,
    PyRobustState,
);

/// A configured `imukit::filters::Robust` (no state).
#[pyclass(name = "RobustFilter", module = "imukit._core", frozen)]
pub(crate) struct PyRobustFilter {
    inner: Robust,
    params: PyRobustParams,
}

#[pymethods]
impl PyRobustFilter {
    #[new]
    fn new(py: Python<'_>, params: PyRobustParams, world: Name<World>) -> PyResult<Self> {
        let inner = Robust::new(params.0, world.0).map_err(|e| to_py(py, "params", e))?;
        Ok(Self { inner, params })
    }

    fn __getnewargs__(&self) -> (PyRobustParams, Name<World>) {
        (self.params, Name(self.inner.world()))
    }

    /// The uninitialised state, or one at `q` (xyzw, in this filter's world) and `time`.
    #[pyo3(signature = (q=None, time=0.0))]
    fn initial_state(&self, q: Option<[f64; 4]>, time: f64) -> PyRobustState {
        PyRobustState(match q {
            None => RobustState::default(),
            Some(q) => self.inner.state_at(&unit_quaternion(q), time),
        })
    }

    /// One streaming sample; returns the new state.
    #[pyo3(signature = (state, gyro, accel, dt, mag=None))]
    fn update(
        &self,
        py: Python<'_>,
        state: PyRef<'_, PyRobustState>,
        gyro: [f64; 3],
        accel: [f64; 3],
        dt: f64,
        mag: Option<[f64; 3]>,
    ) -> PyResult<PyRobustState> {
        let mut s = state.0;
        let mag = mag.map(Vector3::from);
        self.inner
            .update(&mut s, &Vector3::from(gyro), &Vector3::from(accel), mag.as_ref(), dt)
            .map_err(|e| to_py(py, "gyro / accel / dt / state", e))?;
        Ok(PyRobustState(s))
    }

    /// Batch run (or the smoother with `offline`), GIL released.
    #[pyo3(signature = (t, gyro, accel, mag, state, continued, offline, threads))]
    #[allow(clippy::too_many_arguments)] // the arrays of a run, the start state and how to run
    fn run<'py>(
        &self,
        py: Python<'py>,
        t: PyReadonlyArray1<'py, f64>,
        gyro: PyReadonlyArray2<'py, f64>,
        accel: PyReadonlyArray2<'py, f64>,
        mag: Option<PyReadonlyArray2<'py, f64>>,
        state: PyRef<'py, PyRobustState>,
        continued: bool,
        offline: bool,
        threads: Option<usize>,
    ) -> PyResult<Outputs<'py>> {
        let mut s = state.0;
        let n = t.shape()[0];
        let out_q = PyArray2::<f64>::zeros(py, [n, 4], false);
        let out_b = PyArray2::<f64>::zeros(py, [n, 3], false);
        let out_s = PyArray2::<f64>::zeros(py, [n, 3], false);
        let out_rest = PyArray1::<bool>::zeros(py, [n], false);
        let out_mag = PyArray1::<bool>::zeros(py, [n], false);
        {
            let (mut gq, mut gb, mut gs) = (out_q.readwrite(), out_b.readwrite(), out_s.readwrite());
            let (mut gr, mut gm) = (out_rest.readwrite(), out_mag.readwrite());
            let mut out = RobustOutputs {
                q: gq.as_slice_mut()?.as_chunks_mut().0,
                bias: gb.as_slice_mut()?.as_chunks_mut().0,
                bias_sigma: gs.as_slice_mut()?.as_chunks_mut().0,
                rest: gr.as_slice_mut()?,
                mag_disturbed: gm.as_slice_mut()?,
            };
            let arrays = (&t, &gyro, &accel, mag.as_ref());
            run_whole(py, &self.inner, &mut s, arrays, (continued, offline), threads, &mut out)?;
        }
        Ok((out_q, out_b, out_s, out_rest, out_mag, PyRobustState(s)))
    }
}

/// The input arrays of a run as the caller passed them: `t`, `gyro`, `accel`, `mag`.
type Arrays<'a, 'py> = (
    &'a PyReadonlyArray1<'py, f64>,
    &'a PyReadonlyArray2<'py, f64>,
    &'a PyReadonlyArray2<'py, f64>,
    Option<&'a PyReadonlyArray2<'py, f64>>,
);

/// The online filter (its window halves on a second thread) or, `offline`, the smoother (its
/// passes side by side) over the whole record in one core call, on `threads`, else the process's
/// pool (`set_num_threads`, or a fresh one in a forked child), interruptible by Ctrl-C. The record
/// is read in place where no Python code can write to it meanwhile, else copied
/// ([`FilterRecord`]). The online run went part by part (4096 rows copied with the GIL held, then
/// filtered) until 2026-12-07: each part started the second thread anew, which woke too late for
/// the part's first bias window, so the calling thread ran ~700 of each part's 4096 window halves
/// itself (a 9D run 15 % slower).
fn run_whole(
    py: Python<'_>,
    f: &Robust,
    s: &mut RobustState,
    (t, gyro, accel, mag): Arrays<'_, '_>,
    (continued, offline): (bool, bool),
    threads: Option<usize>,
    out: &mut RobustOutputs<'_>,
) -> PyResult<()> {
    let record = FilterRecord::new(py, SampleCopies::new(py, t, gyro, accel)?, mag)?;
    let inputs = record.inputs(py)?;
    let n = inputs.t.len();
    // The smoother writes its outputs last, after its tracks: a helper faulting them in ahead
    // would run while nothing writes them.
    let fresh = [
        Fresh::of(out.q),
        Fresh::of(out.bias),
        Fresh::of(out.bias_sigma),
        Fresh::of(out.rest),
        Fresh::of(out.mag_disturbed),
    ];
    let mut run = move || {
        interruptible(py, n, |cancel| {
            run_in_pool(threads, || match offline {
                true => f.smooth_cancellable(s, &inputs, out, cancel),
                false => f.run_part_cancellable(s, &inputs, (0, continued), out, cancel),
            })
        })
    };
    let result = if offline { run() } else { prefaulting(n, &fresh, run) };
    result??.map_err(|e| to_py(py, "imu / params", e))
}

/// Registers the classes.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRobustParams>()?;
    m.add_class::<PyRobustState>()?;
    m.add_class::<PyRobustFilter>()
}
