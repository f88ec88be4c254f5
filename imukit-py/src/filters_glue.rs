//! Attitude-filter bindings: `AttitudeFilter` (gains and options, no state) wrapped by
//! `imukit.filters.Mahony` / `Madgwick`. The state travels as a flat `(16,)` array
//! (`imukit::filters::State::to_array`), so Python can copy, store and restore it freely.

use imukit::filters::{
    AccelRejection, Algorithm, Common, Filter, GainRamp, Inputs, Madgwick, MagRejection, Mahony, RestDetection, State,
    World, STATE_LEN,
};
use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::{contiguous, private_copy, raise, to_py};

fn state_of(py: Python<'_>, values: [f64; STATE_LEN]) -> PyResult<State> {
    State::from_array(&values).map_err(|e| to_py(py, "state", e))
}

/// Gains and options of a Mahony or Madgwick filter.
#[pyclass(name = "AttitudeFilter", module = "imukit._core", frozen)]
pub(crate) struct PyAttitudeFilter {
    inner: Filter,
}

#[pymethods]
impl PyAttitudeFilter {
    /// `algorithm` "mahony" (`gains = [kp, ki]`) or "madgwick" (`gains = [beta, _]`); `world`
    /// "ENU" / "NED"; `ramp = [duration, factor]`; rejections `[norm, angle, recovery]`;
    /// `rest = [gyro, accel, duration, tau]`.
    #[new]
    #[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.filters
    fn new(
        py: Python<'_>,
        algorithm: &str,
        gains: [f64; 2],
        world: &str,
        gravity: f64,
        ramp: [f64; 2],
        accel_rejection: Option<[f64; 3]>,
        mag_rejection: Option<[f64; 3]>,
        rest: Option<[f64; 4]>,
    ) -> PyResult<Self> {
        let algorithm = match algorithm {
            "mahony" => Algorithm::Mahony(Mahony {
                kp: gains[0],
                ki: gains[1],
            }),
            "madgwick" => Algorithm::Madgwick(Madgwick { beta: gains[0] }),
            other => {
                return Err(raise(
                    py,
                    "ParameterError",
                    "algorithm",
                    format!("expected 'mahony' or 'madgwick', got {other:?}"),
                ))
            }
        };
        let world = match world {
            "ENU" => World::Enu,
            "NED" => World::Ned,
            other => {
                return Err(raise(
                    py,
                    "ParameterError",
                    "world",
                    format!("expected 'ENU' or 'NED', got {other:?}"),
                ))
            }
        };
        let common = Common {
            world,
            gravity,
            ramp: GainRamp {
                duration: ramp[0],
                factor: ramp[1],
            },
            accel_rejection: accel_rejection.map(|[norm, angle, recovery]| AccelRejection { norm, angle, recovery }),
            mag_rejection: mag_rejection.map(|[norm, dip, recovery]| MagRejection { norm, dip, recovery }),
            rest: rest.map(|[gyro, accel, duration, tau]| RestDetection {
                gyro,
                accel,
                duration,
                tau,
            }),
        };
        let inner = Filter::new(algorithm, common).map_err(|e| to_py(py, "options", e))?;
        Ok(Self { inner })
    }

    /// The uninitialised state, or one initialised at quaternion `q` (xyzw) with zero bias.
    #[staticmethod]
    #[pyo3(signature = (q=None))]
    fn initial_state<'py>(py: Python<'py>, q: Option<[f64; 4]>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let state = match q {
            None => State::default(),
            Some([x, y, z, w]) => {
                let q = imukit::quat::normalize(&nalgebra::Quaternion::new(w, x, y, z))
                    .map_err(|e| to_py(py, "initial", e))?;
                State::at(q, Vector3::zeros(), 0.0)
            }
        };
        Ok(PyArray1::from_slice(py, &state.to_array()))
    }

    /// One streaming sample; returns the new state.
    #[pyo3(signature = (state, gyro, accel, dt, mag=None))]
    fn update<'py>(
        &self,
        py: Python<'py>,
        state: [f64; STATE_LEN],
        gyro: [f64; 3],
        accel: [f64; 3],
        dt: f64,
        mag: Option<[f64; 3]>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let mut s = state_of(py, state)?;
        let mag = mag.map(Vector3::from);
        self.inner
            .update(&mut s, &Vector3::from(gyro), &Vector3::from(accel), mag.as_ref(), dt)
            .map_err(|e| to_py(py, "gyro / accel / dt / state", e))?;
        Ok(PyArray1::from_slice(py, &s.to_array()))
    }

    /// Batch run, GIL released: `(q (n, 4) xyzw, bias (n, 3), final state (16,))`.
    #[allow(clippy::type_complexity, clippy::too_many_arguments)] // flat arguments and a plain tuple are the simplest across the boundary
    #[pyo3(signature = (t, gyro, accel, mag, state, continued))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        t: PyReadonlyArray1<'py, f64>,
        gyro: PyReadonlyArray2<'py, f64>,
        accel: PyReadonlyArray2<'py, f64>,
        mag: Option<PyReadonlyArray2<'py, f64>>,
        state: [f64; STATE_LEN],
        continued: bool,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let mut s = state_of(py, state)?;
        let n = t.shape()[0];
        let t = private_copy(py, &t)?.readonly();
        let gyro = private_copy(py, &gyro)?.readonly();
        let accel = private_copy(py, &accel)?.readonly();
        let mag = match mag {
            Some(m) => Some(private_copy(py, &m)?.readonly()),
            None => None,
        };
        let inputs = Inputs {
            t: contiguous(py, "t", &t)?,
            gyro: contiguous(py, "gyro", &gyro)?,
            accel: contiguous(py, "accel", &accel)?,
            mag: match &mag {
                Some(m) => Some(contiguous(py, "mag", m)?),
                None => None,
            },
        };
        let out_q = PyArray2::<f64>::zeros(py, [n, 4], false);
        let out_b = PyArray2::<f64>::zeros(py, [n, 3], false);
        {
            let mut gq = out_q.readwrite();
            let mut gb = out_b.readwrite();
            let (sq, sb) = (gq.as_slice_mut()?, gb.as_slice_mut()?);
            let filter = &self.inner;
            let state = &mut s;
            py.detach(|| filter.run(state, &inputs, continued, sq, sb))
                .map_err(|e| to_py(py, "imu / gains", e))?;
        }
        Ok((out_q, out_b, PyArray1::from_slice(py, &s.to_array())))
    }
}
