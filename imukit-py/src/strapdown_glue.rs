//! `strapdown_integrate`, `strapdown_propagate`: `imukit.integrate` and `imukit.propagate` over
//! [`imukit::strapdown::integrate`] and [`imukit::propagate::propagate`]. The initial state, the
//! biases and the noise cross by field name ([`NavStateFields`], [`BiasFields`],
//! [`NoiseFields`]).

use imukit::extrinsics::{self, SensorPose};
use imukit::imu::{Bias, NavState, Noise};
use imukit::strapdown::{Options, Scheme, StatesOut};
use imukit::{propagate, strapdown};
use nalgebra::{Matrix3, Vector3};
use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::convert::{contiguous, empty, zeros, BiasFields, Demand, Name, NavStateFields, NoiseFields, SampleCopies};
use crate::earth_glue::LocalLevelFields;
use crate::threads::Fresh;
use crate::{raise, to_py};

/// `(N, 6)` rows `[p, v]` and `(N, 4)` quaternions.
pub(crate) type States<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);
/// `(N, 3)` gyro and accelerometer readings.
type Readings<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);
/// States and `(M, 225)` covariances.
type StatesAndCovariances<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// Zeroed `(n, 6)` and `(n, 4)` state arrays, part of `demand`.
fn state_arrays<'py>(py: Python<'py>, demand: &Demand<'_>, n: usize) -> PyResult<States<'py>> {
    Ok((zeros(py, demand, [n, 6])?, zeros(py, demand, [n, 4])?))
}

/// Bytes of one stored state (`[p, v]` and a quaternion).
const STATE_BYTES: u128 = 8 * 10;

#[pyfunction]
#[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.integrate
pub(crate) fn strapdown_integrate<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    initial: NavStateFields,
    bias: BiasFields,
    gravity: [f64; 3],
    scheme: Name<Scheme>,
    earth_rate: [f64; 3],
    threads: Option<usize>,
) -> PyResult<States<'py>> {
    let options = Options {
        scheme: scheme.0,
        gravity: Vector3::from(gravity),
        earth_rate: Vector3::from(earth_rate),
    };
    let (initial, bias) = (NavState::from(initial), Bias::from(bias));
    integrate_states(py, (&t, &gyro, &accel), |samples, out, cancel| {
        // Long records in an inertial world run in parallel chunks (`strapdown/chunks.rs`).
        crate::threads::run_in_pool(threads, || {
            strapdown::integrate_cancellable(samples, &initial, &bias, &options, Some(out), cancel)
        })
    })
}

/// The `(N, 6)` and `(N, 4)` states of the integrator `run` over the samples `(t, gyro, accel)`
/// (private copies, GIL released, interruptible).
pub(crate) fn integrate_states<'py>(
    py: Python<'py>,
    (t, gyro, accel): (
        &PyReadonlyArray1<'py, f64>,
        &PyReadonlyArray2<'py, f64>,
        &PyReadonlyArray2<'py, f64>,
    ),
    run: impl FnOnce(&imukit::imu::Samples<'_>, StatesOut<'_>, &imukit::Cancel) -> PyResult<imukit::Result<NavState>> + Send,
) -> PyResult<States<'py>> {
    let copies = SampleCopies::new(py, t, gyro, accel)?;
    let samples = copies.samples(py)?;
    let n = samples.len();
    let demand = Demand {
        argument: "imu",
        what: "states",
        count: n,
        bytes: n as u128 * STATE_BYTES,
    };
    // Every row is written (the initial state, then one per step) or the call fails.
    let (pv, rot) = (empty(py, &demand, [n, 6])?, empty(py, &demand, [n, 4])?);
    {
        let (mut pv_guard, mut rot_guard) = (pv.readwrite(), rot.readwrite());
        let out = StatesOut {
            position_velocity: pv_guard.as_slice_mut()?.as_chunks_mut().0,
            rotation: rot_guard.as_slice_mut()?.as_chunks_mut().0,
        };
        crate::threads::interruptible(py, n, |cancel| run(&samples, out, cancel))??
            .map_err(|e| to_py(py, "imu / bias", e))?;
    }
    Ok((pv, rot))
}

#[pyfunction]
#[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.propagate
pub(crate) fn strapdown_propagate<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    initial: NavStateFields,
    covariance: PyReadonlyArray2<'py, f64>,
    bias: BiasFields,
    noise: NoiseFields,
    gravity: [f64; 3],
    scheme: Name<Scheme>,
    every: usize,
    earth_rate: [f64; 3],
    lever_arm: [f64; 3],
    transport: Option<LocalLevelFields>,
) -> PyResult<StatesAndCovariances<'py>> {
    let options = Options {
        scheme: scheme.0,
        gravity: Vector3::from(gravity),
        earth_rate: Vector3::from(earth_rate),
    };
    let model = propagate::Model {
        lever_arm: Vector3::from(lever_arm),
        transport: transport.map(|f| f.frame(py)).transpose()?,
    };
    let (initial, bias, noise) = (NavState::from(initial), Bias::from(bias), Noise::from(noise));
    if covariance.shape() != [15, 15] {
        let message = format!("expected shape (15, 15), got {:?}", covariance.shape());
        return Err(raise(py, "ShapeError", "covariance", message));
    }
    let p0 = propagate::Covariance::from_row_slice(contiguous(py, "covariance", &covariance)?);
    let copies = SampleCopies::new(py, &t, &gyro, &accel)?;
    let samples = copies.samples(py)?;
    let n = samples.len();
    // The covariances dominate: 15,000,000 of them (the default stride 1) need 27 GB.
    let count = propagate::covariance_count(n, every);
    let demand = Demand {
        argument: "covariance_every",
        what: "covariances",
        count,
        bytes: n as u128 * STATE_BYTES + count as u128 * 8 * 225,
    };
    let (pv, rot) = state_arrays(py, &demand, n)?;
    let covariances = zeros(py, &demand, [count, 225])?;
    {
        let (mut pv_guard, mut rot_guard, mut c_guard) = (pv.readwrite(), rot.readwrite(), covariances.readwrite());
        let fresh = [pv_guard.as_slice()?, rot_guard.as_slice()?, c_guard.as_slice()?].map(Fresh::of);
        let outputs = propagate::Outputs {
            states: Some(StatesOut {
                position_velocity: pv_guard.as_slice_mut()?.as_chunks_mut().0,
                rotation: rot_guard.as_slice_mut()?.as_chunks_mut().0,
            }),
            covariances: c_guard.as_slice_mut()?.as_chunks_mut().0,
            every,
        };
        crate::threads::prefaulting(n, &fresh, || {
            crate::threads::interruptible(py, n, |cancel| {
                let setup = propagate::Setup {
                    bias: &bias,
                    noise: &noise,
                    options: &options,
                    model: &model,
                };
                propagate::propagate_model(&samples, &initial, &p0, setup, outputs, cancel)
            })
        })?
        .map_err(|e| to_py(py, "imu / bias", e))?;
    }
    Ok((pv, rot, covariances))
}

/// `(gyro, accel)` `(N, 3)` at the body origin from the readings of a sensor at
/// `(rotation R_bs, lever_arm)` in the body frame, biases removed ([`imukit::extrinsics`]).
#[pyfunction]
pub(crate) fn body_readings<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    bias: BiasFields,
    rotation: [[f64; 3]; 3],
    lever_arm: [f64; 3],
) -> PyResult<Readings<'py>> {
    let pose = SensorPose::new(Matrix3::from(rotation).transpose(), Vector3::from(lever_arm))
        .map_err(|e| to_py(py, "body_from_sensor", e))?;
    let bias = Bias::from(bias);
    let copies = SampleCopies::new(py, &t, &gyro, &accel)?;
    let samples = copies.samples(py)?;
    let n = samples.len();
    let demand = Demand {
        argument: "imu",
        what: "samples",
        count: n,
        bytes: n as u128 * 48,
    };
    let (w, a) = (zeros(py, &demand, [n, 3])?, zeros(py, &demand, [n, 3])?);
    {
        let (mut wg, mut ag) = (w.readwrite(), a.readwrite());
        let (wo, ao) = (
            wg.as_slice_mut()?.as_chunks_mut().0,
            ag.as_slice_mut()?.as_chunks_mut().0,
        );
        py.detach(|| extrinsics::to_body(&samples, &bias, &pose, wo, ao))
            .map_err(|e| to_py(py, "imu", e))?;
    }
    Ok((w, a))
}
