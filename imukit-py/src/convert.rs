//! Conversion between Python objects and the core's types, and nothing else: no value checks
//! (the core makes them), no math, no defaults.
//!
//! - arrays: [`private_copy`] (a copy no other thread can write while the GIL is released),
//!   [`frozen_or_copy`] (no copy of an array nothing can write),
//!   [`contiguous`], [`rows`] (`(n, N)` as `&[[f64; N]]`), [`SampleCopies`];
//! - values by field name: [`NoiseFields`] (`imukit.ImuNoise`), [`BiasFields`]
//!   (`imukit.ImuBias`), [`NavStateFields`] (`imukit.NavState`);
//! - enums by name: [`Name`], through the core's `FromStr` ([`imukit::names::Named`]);
//! - a filter state copied ([`state_copy`]).

use imukit::filters::Inputs;
use imukit::imu::{Bias, NavState, Noise, Samples};
use imukit::names::Named;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use numpy::{PyArray, PyArrayMethods, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString, PyTuple};

use crate::{raise, to_py};

/// A copy of `x` that no other Python code can see, so its buffer may be read with the GIL
/// released: another thread could write to the caller's array meanwhile (rust-numpy issue 497).
/// numpy allocates it (and the kernels' outputs) because numpy asks for huge pages: a Rust Vec of
/// the same size costs three times as much in page faults.
pub(crate) fn private_copy<'py, D: numpy::ndarray::Dimension>(
    py: Python<'py>,
    x: &PyReadonlyArray<'py, f64, D>,
) -> PyResult<Bound<'py, PyArray<f64, D>>> {
    let _ = py;
    Ok(x.as_any().call_method0("copy")?.cast_into::<PyArray<f64, D>>()?)
}

/// `x` itself when no Python code can write to it while a kernel reads it with the GIL released:
/// C-contiguous, read-only, and owning its memory or viewing read-only arrays down to an owner
/// that is none or bytes (as `imukit.ImuData`'s arrays, pickled or not); else [`private_copy`]. Saves the copy (~5 ns/sample of
/// three streams) on the hot entry points (issue 20). A Python thread that sets such an array
/// writeable again and writes to it during the call is outside this contract.
pub(crate) fn frozen_or_copy<'py, D: numpy::ndarray::Dimension>(
    py: Python<'py>,
    x: &PyReadonlyArray<'py, f64, D>,
) -> PyResult<Bound<'py, PyArray<f64, D>>> {
    let frozen =
        |a: &Bound<'py, PyAny>| -> PyResult<bool> { Ok(!a.getattr("flags")?.getattr("writeable")?.is_truthy()?) };
    let mut owner_frozen = x.is_c_contiguous() && frozen(x.as_any())?;
    let mut base = x.as_any().getattr("base")?;
    // Read-only ndarrays are followed down to the owner, which must be none (the array owns its
    // memory) or immutable bytes (an unpickled array); any other owner (a buffer, an mmap) may
    // be written to.
    while owner_frozen && !base.is_none() && !base.is_instance_of::<pyo3::types::PyBytes>() {
        owner_frozen = base.is_instance_of::<numpy::PyUntypedArray>() && frozen(&base)?;
        if owner_frozen {
            base = base.getattr("base")?;
        }
    }
    if owner_frozen {
        return Ok(x.as_any().clone().cast_into::<PyArray<f64, D>>()?);
    }
    private_copy(py, x)
}

/// What a call's outputs need, for the message when they cannot be had: `count` items of `what`
/// taking `bytes` in all, asked for through `argument`.
pub(crate) struct Demand<'a> {
    pub(crate) argument: &'a str,
    pub(crate) what: &'static str,
    pub(crate) count: usize,
    pub(crate) bytes: u128,
}

impl<'a> Demand<'a> {
    /// The demand of one float64 array of `shape` (`shape[0]` items of `what`).
    pub(crate) fn of(argument: &'a str, what: &'static str, shape: &[usize]) -> Self {
        Demand {
            argument,
            what,
            count: shape.first().copied().unwrap_or(1),
            bytes: shape.iter().fold(8u128, |b, &d| b.saturating_mul(d as u128)),
        }
    }

    /// The `ResourceError` refusing it ("boundaries: 20,000,000 windows need 24.2 GB").
    fn refuse(&self, py: Python<'_>) -> PyErr {
        let e = imukit::Error::Allocation {
            count: self.count,
            what: self.what,
            bytes: self.bytes,
        };
        to_py(py, self.argument, e)
    }
}

/// A zeroed float64 array of `shape`, allocated by numpy (see [`private_copy`]), part of
/// `demand`. Memory that cannot be had is a `ResourceError` naming the argument and the size,
/// never a panic: rust-numpy's own constructors panic on the null array numpy returns then.
pub(crate) fn zeros<'py, const K: usize>(
    py: Python<'py>,
    demand: &Demand<'_>,
    shape: [usize; K],
) -> PyResult<Bound<'py, PyArray<f64, numpy::ndarray::Dim<[usize; K]>>>>
where
    numpy::ndarray::Dim<[usize; K]>: numpy::ndarray::Dimension,
{
    allocate(py, "zeros", demand, shape)
}

/// [`zeros`] without the zeros, for an output the kernel writes whole before it is returned (an
/// error drops it): memory reused from numpy's heap is then written once, not cleared first
/// (a 16 MB `memset` per call of `integrate` on 2·10^5 samples, 8 ns a sample).
pub(crate) fn empty<'py, const K: usize>(
    py: Python<'py>,
    demand: &Demand<'_>,
    shape: [usize; K],
) -> PyResult<Bound<'py, PyArray<f64, numpy::ndarray::Dim<[usize; K]>>>>
where
    numpy::ndarray::Dim<[usize; K]>: numpy::ndarray::Dimension,
{
    allocate(py, "empty", demand, shape)
}

/// `numpy.<constructor>(shape)` as float64, part of `demand` ([`zeros`]).
fn allocate<'py, const K: usize>(
    py: Python<'py>,
    constructor: &str,
    demand: &Demand<'_>,
    shape: [usize; K],
) -> PyResult<Bound<'py, PyArray<f64, numpy::ndarray::Dim<[usize; K]>>>>
where
    numpy::ndarray::Dim<[usize; K]>: numpy::ndarray::Dimension,
{
    if demand.bytes > isize::MAX as u128 || Demand::of("", "", &shape).bytes > isize::MAX as u128 {
        return Err(demand.refuse(py));
    }
    let array = py
        .import("numpy")?
        .getattr(constructor)?
        .call1((PyTuple::new(py, shape)?,))
        .map_err(|e| {
            if e.is_instance_of::<PyMemoryError>(py) {
                demand.refuse(py)
            } else {
                e
            }
        })?;
    Ok(array.cast_into()?)
}

/// [`zeros`] of one array, the whole demand.
pub(crate) fn zeros_for<'py, const K: usize>(
    py: Python<'py>,
    argument: &str,
    what: &'static str,
    shape: [usize; K],
) -> PyResult<Bound<'py, PyArray<f64, numpy::ndarray::Dim<[usize; K]>>>>
where
    numpy::ndarray::Dim<[usize; K]>: numpy::ndarray::Dimension,
{
    zeros(py, &Demand::of(argument, what, &shape), shape)
}

/// The buffer of a C-contiguous array.
pub(crate) fn contiguous<'a, 'py, D: numpy::ndarray::Dimension>(
    py: Python<'py>,
    name: &str,
    x: &'a PyReadonlyArray<'py, f64, D>,
) -> PyResult<&'a [f64]> {
    x.as_slice()
        .map_err(|_| raise(py, "ShapeError", name, "expected a C-contiguous float64 array"))
}

/// The rows of a C-contiguous `(n, N)` array.
pub(crate) fn rows<'a, 'py, const N: usize>(
    py: Python<'py>,
    name: &str,
    x: &'a PyReadonlyArray2<'py, f64>,
) -> PyResult<&'a [[f64; N]]> {
    match contiguous(py, name, x)?.as_chunks::<N>() {
        (rows, []) if x.shape()[1] == N => Ok(rows),
        _ => Err(raise(
            py,
            "ShapeError",
            name,
            format!("expected shape (n, {N}), got {:?}", x.shape()),
        )),
    }
}

/// The sample arrays themselves when frozen, else private copies ([`frozen_or_copy`]), alive while a kernel borrows them
/// without the GIL.
pub(crate) struct SampleCopies<'py> {
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
}

impl<'py> SampleCopies<'py> {
    pub(crate) fn new(
        py: Python<'py>,
        t: &PyReadonlyArray1<'py, f64>,
        gyro: &PyReadonlyArray2<'py, f64>,
        accel: &PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Self> {
        Ok(Self {
            t: frozen_or_copy(py, t)?.readonly(),
            gyro: frozen_or_copy(py, gyro)?.readonly(),
            accel: frozen_or_copy(py, accel)?.readonly(),
        })
    }

    pub(crate) fn samples<'s>(&'s self, py: Python<'py>) -> PyResult<Samples<'s>> {
        let t = contiguous(py, "t", &self.t)?;
        let (gyro, accel) = (rows(py, "gyro", &self.gyro)?, rows(py, "accel", &self.accel)?);
        Samples::new(t, gyro, accel).map_err(|e| to_py(py, "imu", e))
    }
}

/// A filter's record: [`SampleCopies`] and the optional field `mag`, each array in place where no
/// Python code can write to it meanwhile, else a private copy.
pub(crate) struct FilterRecord<'py> {
    samples: SampleCopies<'py>,
    mag: Option<PyReadonlyArray2<'py, f64>>,
}

impl<'py> FilterRecord<'py> {
    /// `samples` with the field `mag` beside them.
    pub(crate) fn new(
        py: Python<'py>,
        samples: SampleCopies<'py>,
        mag: Option<&PyReadonlyArray2<'py, f64>>,
    ) -> PyResult<Self> {
        let mag = mag
            .map(|m| Ok::<_, PyErr>(frozen_or_copy(py, m)?.readonly()))
            .transpose()?;
        Ok(Self { samples, mag })
    }

    /// The record as the filters' inputs; an array of the wrong layout is a `ShapeError` naming it.
    pub(crate) fn inputs(&self, py: Python<'py>) -> PyResult<Inputs<'_>> {
        let s = &self.samples;
        Ok(Inputs {
            t: contiguous(py, "t", &s.t)?,
            gyro: rows(py, "gyro", &s.gyro)?,
            accel: rows(py, "accel", &s.accel)?,
            mag: self.mag.as_ref().map(|m| rows(py, "mag", m)).transpose()?,
        })
    }
}

/// A string argument parsed as the core enum `T`; an unknown name raises `ParameterError` for
/// the argument `T::ARGUMENT`, listing the names.
/// Back in Python it is the canonical name (a `#[pyclass]` field of this type reads as a `str`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Name<T>(pub(crate) T);

impl<'a, 'py, T: Named> FromPyObject<'a, 'py> for Name<T> {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let text: String = obj.extract()?;
        text.parse::<T>().map(Name).map_err(|e| to_py(obj.py(), T::ARGUMENT, e))
    }
}

impl<'py, T: Named> IntoPyObject<'py> for Name<T> {
    type Target = PyString;
    type Output = Bound<'py, PyString>;
    type Error = std::convert::Infallible;

    fn into_pyobject(self, py: Python<'py>) -> Result<Self::Output, Self::Error> {
        Ok(PyString::new(py, self.0.name()))
    }
}

/// Registers `T`'s canonical names as the tuple `_core.<names>` and, when it has any, its
/// deprecated aliases as the dict `_core.<aliases>` (`{"old": "canonical"}`).
/// A real number given as a Python object for a field `name`: a `ParameterError` for anything that
/// is not one, Python's and numpy's bools included (PyO3 reads a bool as 1.0 / 0.0; issue 17, item 16).
pub(crate) fn real_number(py: Python<'_>, name: &str, v: &Bound<'_, PyAny>) -> PyResult<f64> {
    let shown = || v.repr().map_or_else(|_| "?".to_owned(), |r| r.to_string());
    // numpy's bool scalar (type name "bool" in numpy 2, "bool_" before) converts to float too.
    let numpy_bool = v.get_type().name().is_ok_and(|n| n == "bool" || n == "bool_");
    if v.is_instance_of::<PyBool>() || numpy_bool {
        return Err(raise(
            py,
            "ParameterError",
            name,
            format!("expected a real number, got the bool {}", shown()),
        ));
    }
    v.extract::<f64>().map_err(|_| {
        raise(
            py,
            "ParameterError",
            name,
            format!("expected a real number, got {}", shown()),
        )
    })
}

pub(crate) fn add_names<T: Named>(m: &Bound<'_, PyModule>, names: &str, aliases: Option<&str>) -> PyResult<()> {
    m.add(names, PyTuple::new(m.py(), T::names())?)?;
    if let Some(aliases) = aliases {
        let dict = PyDict::new(m.py());
        for (alias, variant) in T::ALIASES {
            dict.set_item(alias, variant.name())?;
        }
        m.add(aliases, dict)?;
    }
    Ok(())
}

/// `imukit.ImuNoise` by field name.
#[derive(FromPyObject, Clone, Copy)]
pub(crate) struct NoiseFields {
    #[pyo3(attribute)]
    gyro_density: f64,
    #[pyo3(attribute)]
    accel_density: f64,
    #[pyo3(attribute)]
    gyro_random_walk: f64,
    #[pyo3(attribute)]
    accel_random_walk: f64,
}

impl From<NoiseFields> for Noise {
    fn from(n: NoiseFields) -> Self {
        Noise {
            gyro_density: n.gyro_density,
            accel_density: n.accel_density,
            gyro_random_walk: n.gyro_random_walk,
            accel_random_walk: n.accel_random_walk,
        }
    }
}

/// `imukit.ImuBias` by field name.
#[derive(FromPyObject, Clone, Copy)]
pub(crate) struct BiasFields {
    #[pyo3(attribute)]
    gyro: [f64; 3],
    #[pyo3(attribute)]
    accel: [f64; 3],
}

impl From<BiasFields> for Bias {
    fn from(b: BiasFields) -> Self {
        Bias {
            gyro: Vector3::from(b.gyro),
            accel: Vector3::from(b.accel),
        }
    }
}

/// `imukit.NavState` by field name; `rotation` is a scipy `Rotation`.
#[derive(FromPyObject)]
pub(crate) struct NavStateFields {
    #[pyo3(attribute)]
    position: [f64; 3],
    #[pyo3(attribute)]
    velocity: [f64; 3],
    #[pyo3(attribute, from_py_with = xyzw)]
    rotation: [f64; 4],
}

/// A scipy `Rotation`'s quaternion, `[x, y, z, w]`.
fn xyzw(rotation: &Bound<'_, PyAny>) -> PyResult<[f64; 4]> {
    rotation.call_method0("as_quat")?.extract()
}

/// An `[x, y, z, w]` quaternion as a rotation; Python passes a scipy `Rotation`'s quaternion
/// (unit already), renormalised here regardless.
pub(crate) fn unit_quaternion([x, y, z, w]: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_normalize(Quaternion::new(w, x, y, z))
}

impl From<NavStateFields> for NavState {
    fn from(s: NavStateFields) -> Self {
        NavState {
            position: Vector3::from(s.position),
            velocity: Vector3::from(s.velocity),
            rotation: unit_quaternion(s.rotation),
        }
    }
}

/// A copy of a filter's `state` object (the core checked it when it was made), for a constructor
/// that takes a state or its fields: fields beside it are a `ParameterError` naming `state`.
pub(crate) fn state_copy<T: Clone>(py: Python<'_>, state: &T, with_fields: bool) -> PyResult<T> {
    if with_fields {
        return Err(raise(
            py,
            "ParameterError",
            "state",
            "expected a state or its fields, not both",
        ));
    }
    Ok(state.clone())
}
