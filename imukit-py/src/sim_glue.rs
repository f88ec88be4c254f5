//! Simulator bindings: closed-form motions into truth arrays, and the sensor error model; wrapped by
//! `imukit.sim`.

use imukit::sim::{self, Motion, MotionKind, SensorModel};
use nalgebra::{Matrix3, Rotation3, Vector3};
use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{contiguous, empty, unit_quaternion, zeros_for, Demand, Name};
use crate::{raise, threads, to_py};

fn vec3(obj: &Bound<'_, PyAny>) -> PyResult<Vector3<f64>> {
    Ok(Vector3::from(obj.extract::<[f64; 3]>()?))
}

/// `R_wb` from a scipy `Rotation` (its `[x, y, z, w]` unit quaternion).
fn rotation(obj: &Bound<'_, PyAny>) -> PyResult<Rotation3<f64>> {
    Ok(unit_quaternion(obj.call_method0("as_quat")?.extract()?).to_rotation_matrix())
}

// The attributes of the `imukit.sim` classes, read by name: one mirror per `Motion` variant.

#[derive(FromPyObject)]
struct Static {
    #[pyo3(from_py_with = vec3)]
    position: Vector3<f64>,
    #[pyo3(from_py_with = rotation)]
    rotation: Rotation3<f64>,
}

#[derive(FromPyObject)]
struct ConstantTwist {
    #[pyo3(from_py_with = vec3)]
    position: Vector3<f64>,
    #[pyo3(from_py_with = rotation)]
    rotation: Rotation3<f64>,
    #[pyo3(from_py_with = vec3)]
    body_velocity: Vector3<f64>,
    #[pyo3(from_py_with = vec3)]
    body_rate: Vector3<f64>,
}

#[derive(FromPyObject)]
struct Helix {
    #[pyo3(from_py_with = vec3)]
    center: Vector3<f64>,
    radius: f64,
    angular_rate: f64,
    climb_rate: f64,
}

#[derive(FromPyObject)]
struct FigureEight {
    #[pyo3(from_py_with = vec3)]
    center: Vector3<f64>,
    #[pyo3(from_py_with = vec3)]
    amplitude: Vector3<f64>,
    angular_rate: f64,
    roll: f64,
    pitch: f64,
}

#[derive(FromPyObject)]
struct VioEllipse {
    #[pyo3(from_py_with = vec3)]
    center: Vector3<f64>,
    #[pyo3(from_py_with = vec3)]
    amplitude: Vector3<f64>,
    angular_rate: f64,
    height_frequency: f64,
    roll: f64,
    pitch: f64,
}

/// The motion `trajectory` (an `imukit.sim` motion of kind `kind`), read by attribute name.
fn motion(kind: MotionKind, trajectory: &Bound<'_, PyAny>) -> PyResult<Motion> {
    Ok(match kind {
        MotionKind::Static => {
            let Static { position, rotation } = trajectory.extract()?;
            Motion::Static { position, rotation }
        }
        MotionKind::ConstantTwist => {
            let m: ConstantTwist = trajectory.extract()?;
            Motion::ConstantTwist {
                position: m.position,
                rotation: m.rotation,
                body_velocity: m.body_velocity,
                body_rate: m.body_rate,
            }
        }
        MotionKind::Helix => {
            let m: Helix = trajectory.extract()?;
            Motion::Helix {
                center: m.center,
                radius: m.radius,
                angular_rate: m.angular_rate,
                climb_rate: m.climb_rate,
            }
        }
        MotionKind::FigureEight => {
            let m: FigureEight = trajectory.extract()?;
            Motion::FigureEight {
                center: m.center,
                amplitude: m.amplitude,
                angular_rate: m.angular_rate,
                roll: m.roll,
                pitch: m.pitch,
            }
        }
        MotionKind::VioEllipse => {
            let m: VioEllipse = trajectory.extract()?;
            Motion::VioEllipse {
                center: m.center,
                amplitude: m.amplitude,
                angular_rate: m.angular_rate,
                height_frequency: m.height_frequency,
                roll: m.roll,
                pitch: m.pitch,
            }
        }
    })
}

type Arrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// `(position, velocity, rotation xyzw, gyro, accel)` of the closed-form motion `trajectory` (an
/// `imukit.sim` motion, its fields checked there) of kind `kind` at the times `t`, on `threads`
/// threads (None: the process-wide pool).
#[pyfunction]
#[pyo3(signature = (kind, trajectory, t, gravity, threads=None))]
pub(crate) fn sim_motion<'py>(
    py: Python<'py>,
    kind: Name<MotionKind>,
    trajectory: &Bound<'py, PyAny>,
    t: PyReadonlyArray1<'py, f64>,
    gravity: [f64; 3],
    threads: Option<usize>,
) -> PyResult<Arrays<'py>> {
    let motion = motion(kind.0, trajectory)?;
    // No private copy: imukit.sim passes an array it has just made and shares with no one.
    let t = contiguous(py, "t", &t)?;
    let n = t.len();
    let demand = Demand {
        argument: "t",
        what: "samples",
        count: n,
        bytes: n as u128 * 8 * 16,
    };
    // Every row is written (each chunk whole) or the call fails.
    let make = |w: usize| empty(py, &demand, [n, w]);
    let (p, v, q, w, a) = (make(3)?, make(3)?, make(4)?, make(3)?, make(3)?);
    {
        let (mut pg, mut vg, mut qg, mut wg, mut ag) = (
            p.readwrite(),
            v.readwrite(),
            q.readwrite(),
            w.readwrite(),
            a.readwrite(),
        );
        let out = sim::Truth {
            position: pg.as_slice_mut()?,
            velocity: vg.as_slice_mut()?,
            rotation: qg.as_slice_mut()?,
            gyro: wg.as_slice_mut()?,
            accel: ag.as_slice_mut()?,
        };
        let g = Vector3::from(gravity);
        threads::interruptible(py, n, |cancel| {
            threads::run_in_pool(threads, || sim::evaluate_cancellable(&motion, t, &g, out, cancel))
        })??
        .map_err(|e| to_py(py, "simulate", e))?;
    }
    Ok((p, v, q, w, a))
}

/// `imukit.sim.SensorErrors`, read by attribute name; also the shape of
/// [`sim_sensor_default`]'s dict.
#[derive(FromPyObject, IntoPyObject)]
pub(crate) struct SensorErrors {
    matrix: [[f64; 3]; 3],
    turn_on_sigma: f64,
    gauss_markov_sigma: f64,
    gauss_markov_tau: f64,
    range: f64,
    resolution: f64,
}

/// The fields of `imukit.sim.SensorErrors` as [`SensorModel::default`] has them (a perfect triad):
/// the Python defaults are read from here.
#[pyfunction]
pub(crate) fn sim_sensor_default(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let m = SensorModel::default();
    let errors = SensorErrors {
        matrix: m.matrix.transpose().into(),
        turn_on_sigma: m.turn_on_sigma,
        gauss_markov_sigma: m.gauss_markov_sigma,
        gauss_markov_tau: m.gauss_markov_tau,
        range: m.range,
        resolution: m.resolution,
    };
    Ok(errors.into_pyobject(py)?.cast_into::<PyDict>()?)
}

/// Measures one triad in place: `ideal` (the caller's fresh `(N, 3)` array) becomes the readings;
/// returns the true biases. The model is `errors` (an `imukit.sim.SensorErrors`, read by name) with
/// the constant `bias` and the white-noise `density` and bias `random_walk` of this triad.
/// Private to `imukit.sim`, which passes arrays it has just made and shares with no one, so nothing
/// is copied. On `threads` threads (None: the process-wide pool).
#[pyfunction]
#[pyo3(signature = (t, ideal, errors, bias, density, random_walk, seed, triad, threads=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sim_measure<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    mut ideal: PyReadwriteArray2<'py, f64>,
    errors: SensorErrors,
    bias: [f64; 3],
    density: f64,
    random_walk: f64,
    seed: u64,
    triad: u64,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let model = SensorModel {
        matrix: Matrix3::from(errors.matrix).transpose(),
        bias: Vector3::from(bias),
        turn_on_sigma: errors.turn_on_sigma,
        density,
        random_walk,
        gauss_markov_sigma: errors.gauss_markov_sigma,
        gauss_markov_tau: errors.gauss_markov_tau,
        range: errors.range,
        resolution: errors.resolution,
    };
    let t = contiguous(py, "t", &t)?;
    let n = t.len();
    let bias = zeros_for(py, "t", "samples", [n, 3])?;
    {
        let mut bg = bias.readwrite();
        let b = bg.as_slice_mut()?;
        let values = ideal
            .as_slice_mut()
            .map_err(|_| raise(py, "ShapeError", "ideal", "expected a C-contiguous float64 array"))?;
        let errors = if triad == 0 { "gyro_errors" } else { "accel_errors" };
        // The core names the model's field; simulate's argument holding it is this one.
        let argument = |e: &imukit::Error| match e.argument() {
            Some("density" | "random_walk") => "noise",
            Some("bias") => "bias",
            _ => errors,
        };
        threads::interruptible(py, n, |cancel| {
            threads::run_in_pool(threads, || {
                sim::measure_in_place_cancellable(t, values, &model, (seed, triad), b, cancel)
            })
        })??
        .map_err(|e| raise(py, crate::class_name(&e), argument(&e), e.root()))?;
    }
    Ok(bias)
}

/// [`sim::in_rotating_world`] on `simulate`'s own fresh `gyro` and `accel` arrays, in place.
#[pyfunction]
pub(crate) fn sim_rotating_world<'py>(
    py: Python<'py>,
    earth_rate: [f64; 3],
    rotation: PyReadonlyArray2<'py, f64>,
    velocity: PyReadonlyArray2<'py, f64>,
    gyro: &Bound<'py, PyArray2<f64>>,
    accel: &Bound<'py, PyArray2<f64>>,
) -> PyResult<()> {
    let (q, v) = (
        contiguous(py, "rotation", &rotation)?,
        contiguous(py, "velocity", &velocity)?,
    );
    let (mut wg, mut ag) = (gyro.readwrite(), accel.readwrite());
    let (w, a) = (wg.as_slice_mut()?, ag.as_slice_mut()?);
    let w_rate = Vector3::from(earth_rate);
    // In parallel, on the process's pool (`simulate`'s `threads=` is not passed down here).
    py.detach(|| {
        threads::run_in_pool(None, || {
            sim::in_rotating_world(
                &w_rate,
                q.as_chunks().0,
                v.as_chunks().0,
                w.as_chunks_mut().0,
                a.as_chunks_mut().0,
            )
        })
    })?
    .map_err(|e| to_py(py, "simulate", e))
}

/// [`imukit::extrinsics::to_sensor`] on `simulate`'s own fresh `gyro` and `accel` arrays, in place:
/// the readings of a sensor at `(rotation R_bs rows, lever_arm)` on the simulated body.
#[pyfunction]
pub(crate) fn sim_sensor_pose<'py>(
    py: Python<'py>,
    rotation: [[f64; 3]; 3],
    lever_arm: [f64; 3],
    alpha: PyReadonlyArray2<'py, f64>,
    gyro: &Bound<'py, PyArray2<f64>>,
    accel: &Bound<'py, PyArray2<f64>>,
) -> PyResult<()> {
    use imukit::extrinsics::{to_sensor, SensorPose};
    let pose = SensorPose::new(Matrix3::from(rotation).transpose(), Vector3::from(lever_arm))
        .map_err(|e| to_py(py, "body_from_sensor", e))?;
    let alpha = crate::convert::rows::<3>(py, "alpha", &alpha)?;
    let (mut wg, mut ag) = (gyro.readwrite(), accel.readwrite());
    let (w, a) = (wg.as_slice_mut()?, ag.as_slice_mut()?);
    py.detach(|| to_sensor(&pose, alpha, w.as_chunks_mut().0, a.as_chunks_mut().0))
        .map_err(|e| to_py(py, "simulate", e))
}
