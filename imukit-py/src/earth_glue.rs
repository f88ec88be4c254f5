//! `local_level`: the Earth rate and gravity of an `imukit.LocalLevel` (read by field name) from
//! [`imukit::earth::LocalLevel`], which checks the values; `ellipsoid_integrate` and
//! `sim_ellipsoid`: `integrate` and `simulate` with a frame that follows the vehicle
//! ([`imukit::ellipsoid`]).

use imukit::earth::{Axes, LocalLevel};
use imukit::ellipsoid::{self, Track};
use imukit::imu::{Bias, NavState};
use imukit::strapdown::Scheme;
use nalgebra::Vector3;
use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::convert::{contiguous, rows, zeros, BiasFields, Demand, Name, NavStateFields};
use crate::strapdown_glue::{integrate_states, States};
use crate::to_py;

/// `imukit.LocalLevel`'s fields.
#[derive(FromPyObject)]
pub(crate) struct LocalLevelFields {
    latitude: f64,
    height: f64,
    // A name, parsed below: a failed parse inside the derive would surface as a TypeError.
    axes: String,
    transport: bool,
}

impl LocalLevelFields {
    /// The core's frame, its values checked there.
    pub(crate) fn frame(&self, py: Python<'_>) -> PyResult<LocalLevel> {
        let axes = self.axes.parse::<Axes>().map_err(|e| to_py(py, "axes", e))?;
        let frame = LocalLevel::new(self.latitude, self.height, axes).map_err(|e| to_py(py, "frame", e))?;
        if self.transport {
            ellipsoid::check_origin(self.latitude).map_err(|e| to_py(py, "frame", e))?;
        }
        Ok(frame)
    }
}

/// `(earth_rate, gravity)` of the frame, in its axes.
#[pyfunction]
pub(crate) fn local_level(py: Python<'_>, frame: LocalLevelFields) -> PyResult<([f64; 3], [f64; 3])> {
    let f = frame.frame(py)?;
    Ok((f.earth_rate().into(), f.gravity().into()))
}

/// `(N, 6)` rows `[φ, λ, h, v]` and `(N, 4)` quaternions of [`ellipsoid::integrate`].
#[pyfunction]
#[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.integrate
pub(crate) fn ellipsoid_integrate<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    initial: NavStateFields,
    bias: BiasFields,
    frame: LocalLevelFields,
    scheme: Name<Scheme>,
) -> PyResult<States<'py>> {
    let (initial, bias, start) = (NavState::from(initial), Bias::from(bias), frame.frame(py)?);
    integrate_states(py, (&t, &gyro, &accel), |samples, out, cancel| {
        Ok(ellipsoid::integrate(
            samples,
            &initial,
            &bias,
            &start,
            scheme.0,
            Some(out),
            cancel,
        ))
    })
}

/// [`ellipsoid::sensor_readings`] on `simulate`'s own fresh `gyro` and `accel` arrays, in place;
/// returns the `(N, 3)` geodetic track.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // the track's arrays, each by name
pub(crate) fn sim_ellipsoid<'py>(
    py: Python<'py>,
    axes: Name<Axes>,
    start: [f64; 3],
    t: PyReadonlyArray1<'py, f64>,
    position: PyReadonlyArray2<'py, f64>,
    velocity: PyReadonlyArray2<'py, f64>,
    mid_position: PyReadonlyArray2<'py, f64>,
    mid_velocity: PyReadonlyArray2<'py, f64>,
    rotation: PyReadonlyArray2<'py, f64>,
    gyro: &Bound<'py, PyArray2<f64>>,
    accel: &Bound<'py, PyArray2<f64>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let track = Track {
        t: contiguous(py, "t", &t)?,
        position: rows::<3>(py, "position", &position)?,
        velocity: rows::<3>(py, "velocity", &velocity)?,
        mid_position: rows::<3>(py, "mid_position", &mid_position)?,
        mid_velocity: rows::<3>(py, "mid_velocity", &mid_velocity)?,
        rotation: rows::<4>(py, "rotation", &rotation)?,
    };
    let n = track.t.len();
    let demand = Demand {
        argument: "duration",
        what: "positions",
        count: n,
        bytes: n as u128 * 24,
    };
    let geodetic = zeros(py, &demand, [n, 3])?;
    {
        let (mut wg, mut ag, mut pg) = (gyro.readwrite(), accel.readwrite(), geodetic.readwrite());
        let (w, a, p) = (wg.as_slice_mut()?, ag.as_slice_mut()?, pg.as_slice_mut()?);
        let start = Vector3::from(start);
        py.detach(|| {
            ellipsoid::sensor_readings(
                axes.0,
                &start,
                &track,
                w.as_chunks_mut().0,
                a.as_chunks_mut().0,
                p.as_chunks_mut().0,
            )
        })
        .map_err(|e| to_py(py, "simulate", e))?;
    }
    Ok(geodetic)
}
