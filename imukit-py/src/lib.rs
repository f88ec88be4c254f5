//! PyO3 glue for imukit: thin functions over `(n, k)` float64 arrays that copy the input, release
//! the GIL, run an [`imukit::batch`] kernel and map its error to the `imukit` exception
//! hierarchy. The public Python API (shapes, broadcasting, scipy interop) lives in
//! `python/imukit`; nothing here is meant to be called directly.

use imukit::attitude::{self, Representation, Scheme};
use imukit::batch::{self, Convention, Jacobian, ProductMatrix};
use imukit::imu::{Bias, NavState, Noise, Samples};
use imukit::{propagate, strapdown};

mod allan_glue;
mod errors;
mod filters_glue;
mod preint_glue;
mod sim_glue;
mod threads;
pub(crate) use errors::{class_name, raise, to_py};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use numpy::{
    PyArray, PyArray2, PyArrayMethods, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

/// Runs `kernel` over the rows of `x` (shape `(n, width_in)`) into a new `(n, width_out)` array.
fn run<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    name: &str,
    width_in: usize,
    width_out: usize,
    kernel: impl FnOnce(&[f64], &mut [f64]) -> imukit::Result<()> + Send,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let shape = x.shape();
    if shape[1] != width_in {
        let got = format!("{shape:?}");
        return Err(raise(
            py,
            "ShapeError",
            name,
            format!("expected shape (n, {width_in}), got {got}"),
        ));
    }
    let rows = shape[0];
    let input = private_copy(py, &x)?;
    let input = input.readonly();
    let input = contiguous(py, name, &input)?;
    let out = PyArray2::<f64>::zeros(py, [rows, width_out], false);
    {
        let mut guard = out.readwrite();
        let out_slice = guard.as_slice_mut()?;
        py.detach(|| threads::run_in_pool(None, || kernel(input, out_slice)))?
            .map_err(|e| to_py(py, name, e))?;
    }
    Ok(out)
}

/// A copy of `x` that no other Python code can see, so its buffer may be read with the GIL
/// released: another thread could write to the caller's array meanwhile (rust-numpy issue 497).
/// numpy allocates it (and [`run`]'s outputs) because numpy asks for huge pages: a Rust Vec of the
/// same size costs three times as much in page faults.
pub(crate) fn private_copy<'py, D: numpy::ndarray::Dimension>(
    py: Python<'py>,
    x: &PyReadonlyArray<'py, f64, D>,
) -> PyResult<Bound<'py, PyArray<f64, D>>> {
    let _ = py;
    Ok(x.as_any().call_method0("copy")?.cast_into::<PyArray<f64, D>>()?)
}

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

fn parse_convention(py: Python<'_>, convention: &str) -> PyResult<Convention> {
    match convention {
        "hamilton" => Ok(Convention::Hamilton),
        "jpl" => Ok(Convention::Jpl),
        other => Err(raise(
            py,
            "ParameterError",
            "convention",
            format!("expected 'hamilton' or 'jpl', got {other:?}"),
        )),
    }
}

/// A `#[pyfunction] name(x, name)` running `batch::kernel` from `(n, in)` to `(n, out)`.
macro_rules! unary {
    ($func:ident, $kernel:path, $width_in:expr, $width_out:expr) => {
        #[pyfunction]
        fn $func<'py>(
            py: Python<'py>,
            x: PyReadonlyArray2<'py, f64>,
            name: &str,
        ) -> PyResult<Bound<'py, PyArray2<f64>>> {
            run(py, x, name, $width_in, $width_out, $kernel)
        }
    };
}

unary!(so3_hat, batch::so3_hat, 3, 9);
unary!(so3_vee, batch::so3_vee, 9, 3);
unary!(so3_exp, batch::so3_exp, 3, 9);
unary!(so3_log, batch::so3_log, 9, 3);
unary!(quat_conjugate, batch::quat_conjugate, 4, 4);
unary!(quat_inverse, batch::quat_inverse, 4, 4);
unary!(quat_normalize, batch::quat_normalize, 4, 4);
unary!(quat_rotate, batch::quat_rotate, 7, 3);
unary!(quat_exp, batch::quat_exp, 3, 4);
unary!(quat_log, batch::quat_log, 4, 3);
unary!(euler_to_matrix, batch::euler_to_matrix, 3, 9);
unary!(euler_from_matrix, batch::euler_from_matrix, 9, 3);
unary!(euler_rate_matrix_inv, batch::euler_rate_matrix_inv, 3, 9);

#[pyfunction]
fn so3_jacobian<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    name: &str,
    kind: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let kind = match kind {
        "right" => Jacobian::Right,
        "right_inv" => Jacobian::RightInv,
        "left" => Jacobian::Left,
        "left_inv" => Jacobian::LeftInv,
        other => {
            let message = format!("expected 'right', 'right_inv', 'left' or 'left_inv', got {other:?}");
            return Err(raise(py, "ParameterError", "kind", message));
        }
    };
    run(py, x, name, 3, 9, move |i, o| batch::so3_jacobian(kind, i, o))
}

#[pyfunction]
fn quat_multiply<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    name: &str,
    convention: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let convention = parse_convention(py, convention)?;
    run(py, x, name, 8, 4, move |i, o| batch::quat_multiply(convention, i, o))
}

#[pyfunction]
fn quat_product_matrix<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    name: &str,
    side: &str,
    convention: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let convention = parse_convention(py, convention)?;
    let side = match side {
        "left" => ProductMatrix::Left,
        "right" => ProductMatrix::Right,
        other => {
            return Err(raise(
                py,
                "ParameterError",
                "side",
                format!("expected 'left' or 'right', got {other:?}"),
            ))
        }
    };
    run(py, x, name, 4, 16, move |i, o| {
        batch::quat_product_matrix(side, convention, i, o)
    })
}

#[pyfunction]
fn quat_omega_matrix<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    name: &str,
    convention: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let convention = parse_convention(py, convention)?;
    run(py, x, name, 3, 16, move |i, o| {
        batch::quat_omega_matrix(convention, i, o)
    })
}

#[pyfunction]
fn euler_rate_matrix<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    name: &str,
    tolerance: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    run(py, x, name, 3, 9, move |i, o| batch::euler_rate_matrix(tolerance, i, o))
}

#[pyfunction]
#[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.integrate_attitude
fn attitude_integrate<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    initial: [f64; 4],
    scheme: &str,
    representation: &str,
    gimbal_tolerance: f64,
    final_only: bool,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    // Errors that name no argument (gimbal lock, overflow) are about the rates.
    let name = "gyro";
    let scheme = match scheme {
        "euler" => Scheme::Euler,
        "exp" => Scheme::Exp,
        "midpoint" => Scheme::Midpoint,
        "rk4" => Scheme::Rk4,
        "magnus" => Scheme::Magnus,
        other => {
            let message = format!("expected 'euler', 'exp', 'midpoint', 'rk4' or 'magnus', got {other:?}");
            return Err(raise(py, "ParameterError", "scheme", message));
        }
    };
    let representation = match representation {
        "quaternion" => Representation::Quaternion,
        "matrix" => Representation::Matrix,
        "euler" => Representation::Euler,
        other => {
            let message = format!("expected 'quaternion', 'matrix' or 'euler', got {other:?}");
            return Err(raise(py, "ParameterError", "representation", message));
        }
    };
    let options = attitude::Options {
        scheme,
        representation,
        gimbal_tolerance,
    };
    let [x, y, z, w] = initial;
    // Python passes a scipy Rotation's quaternion: unit already, renormalised here regardless.
    let initial = UnitQuaternion::new_normalize(Quaternion::new(w, x, y, z));
    let (t, gyro) = (private_copy(py, &t)?, private_copy(py, &gyro)?);
    let (t, gyro) = (t.readonly(), gyro.readonly());
    let (t, gyro) = (contiguous(py, "t", &t)?, contiguous(py, "gyro", &gyro)?);
    let rows = if final_only { 1 } else { t.len() };
    let out = PyArray2::<f64>::zeros(py, [rows, 4], false);
    {
        let mut guard = out.readwrite();
        let out_slice = guard.as_slice_mut()?;
        py.detach(|| {
            threads::run_in_pool(None, || {
                let last = attitude::integrate(t, gyro, &initial, &options, (!final_only).then_some(&mut *out_slice))?;
                if final_only {
                    out_slice.copy_from_slice(&[last.i, last.j, last.k, last.w]);
                }
                Ok(())
            })
        })?
        .map_err(|e| to_py(py, name, e))?;
    }
    Ok(out)
}

fn parse_strapdown_scheme(py: Python<'_>, scheme: &str) -> PyResult<strapdown::Scheme> {
    use strapdown::Scheme as S;
    match scheme {
        "euler" => Ok(S::Euler),
        "midpoint" => Ok(S::Midpoint),
        "rk4" => Ok(S::Rk4),
        "exp" => Ok(S::Exp),
        other => {
            let message = format!("expected 'euler', 'midpoint', 'rk4' or 'exp', got {other:?}");
            Err(raise(py, "ParameterError", "scheme", message))
        }
    }
}

/// `[p, v, q(xyzw)]` and `[b_g, b_a]` as the core's types.
fn nav_state(initial: [f64; 10]) -> NavState {
    let [px, py_, pz, vx, vy, vz, x, y, z, w] = initial;
    NavState {
        position: Vector3::new(px, py_, pz),
        velocity: Vector3::new(vx, vy, vz),
        rotation: UnitQuaternion::new_normalize(Quaternion::new(w, x, y, z)),
    }
}

fn strapdown_options(py: Python<'_>, scheme: &str, gravity: [f64; 3]) -> PyResult<strapdown::Options> {
    Ok(strapdown::Options {
        scheme: parse_strapdown_scheme(py, scheme)?,
        gravity: Vector3::from(gravity),
    })
}

/// Private copies of a sample set ([`private_copy`]), alive while a kernel borrows them
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
            t: private_copy(py, t)?.readonly(),
            gyro: private_copy(py, gyro)?.readonly(),
            accel: private_copy(py, accel)?.readonly(),
        })
    }

    pub(crate) fn samples<'s>(&'s self, py: Python<'py>) -> PyResult<Samples<'s>> {
        let t = contiguous(py, "t", &self.t)?;
        let (gyro, accel) = (rows(py, "gyro", &self.gyro)?, rows(py, "accel", &self.accel)?);
        Samples::new(t, gyro, accel).map_err(|e| to_py(py, "imu", e))
    }
}

/// `[σ_g, σ_a, σ_bg, σ_ba]` as the core's noise densities.
pub(crate) fn noise_of(values: [f64; 4]) -> Noise {
    let [gyro_density, accel_density, gyro_random_walk, accel_random_walk] = values;
    Noise {
        gyro_density,
        accel_density,
        gyro_random_walk,
        accel_random_walk,
    }
}

pub(crate) fn bias(values: [f64; 6]) -> Bias {
    let [gx, gy, gz, ax, ay, az] = values;
    Bias {
        gyro: Vector3::new(gx, gy, gz),
        accel: Vector3::new(ax, ay, az),
    }
}

/// `(N, 6)` rows `[p, v]` and `(N, 4)` quaternions.
type States<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);
/// States and `(M, 225)` covariances.
type StatesAndCovariances<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

#[pyfunction]
#[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.integrate
fn strapdown_integrate<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    initial: [f64; 10],
    bias_values: [f64; 6],
    gravity: [f64; 3],
    scheme: &str,
) -> PyResult<States<'py>> {
    let options = strapdown_options(py, scheme, gravity)?;
    let copies = SampleCopies::new(py, &t, &gyro, &accel)?;
    let samples = copies.samples(py)?;
    let n = samples.len();
    let (pv, rot) = (
        PyArray2::<f64>::zeros(py, [n, 6], false),
        PyArray2::<f64>::zeros(py, [n, 4], false),
    );
    {
        let (mut pv_guard, mut rot_guard) = (pv.readwrite(), rot.readwrite());
        let out = strapdown::StatesOut {
            position_velocity: pv_guard.as_slice_mut()?,
            rotation: rot_guard.as_slice_mut()?,
        };
        let (initial, bias) = (nav_state(initial), bias(bias_values));
        py.detach(|| strapdown::integrate(&samples, &initial, &bias, &options, Some(out)))
            .map_err(|e| to_py(py, "imu / bias", e))?;
    }
    Ok((pv, rot))
}

#[pyfunction]
#[allow(clippy::too_many_arguments)] // mirrors the keyword options of imukit.propagate
fn strapdown_propagate<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    initial: [f64; 10],
    covariance: PyReadonlyArray2<'py, f64>,
    bias_values: [f64; 6],
    noise: [f64; 4],
    gravity: [f64; 3],
    scheme: &str,
    every: usize,
) -> PyResult<StatesAndCovariances<'py>> {
    let options = strapdown_options(py, scheme, gravity)?;
    let noise = noise_of(noise);
    if covariance.shape() != [15, 15] {
        let got = format!("{:?}", covariance.shape());
        return Err(raise(
            py,
            "ShapeError",
            "covariance",
            format!("expected shape (15, 15), got {got}"),
        ));
    }
    let p0 = propagate::Covariance::from_row_slice(contiguous(py, "covariance", &covariance)?);
    let copies = SampleCopies::new(py, &t, &gyro, &accel)?;
    let samples = copies.samples(py)?;
    let n = samples.len();
    let (pv, rot) = (
        PyArray2::<f64>::zeros(py, [n, 6], false),
        PyArray2::<f64>::zeros(py, [n, 4], false),
    );
    let covariances = PyArray2::<f64>::zeros(py, [propagate::covariance_count(n, every), 225], false);
    {
        let (mut pv_guard, mut rot_guard, mut c_guard) = (pv.readwrite(), rot.readwrite(), covariances.readwrite());
        let outputs = propagate::Outputs {
            states: Some(strapdown::StatesOut {
                position_velocity: pv_guard.as_slice_mut()?,
                rotation: rot_guard.as_slice_mut()?,
            }),
            covariances: c_guard.as_slice_mut()?,
            every,
        };
        let (initial, bias) = (nav_state(initial), bias(bias_values));
        py.detach(|| propagate::propagate(&samples, &initial, &p0, &bias, &noise, &options, outputs))
            .map_err(|e| to_py(py, "imu / bias", e))?;
    }
    Ok((pv, rot, covariances))
}

/// Compiled core of imukit. Use the `imukit` package, not this module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(so3_hat, m)?)?;
    m.add_function(wrap_pyfunction!(so3_vee, m)?)?;
    m.add_function(wrap_pyfunction!(so3_exp, m)?)?;
    m.add_function(wrap_pyfunction!(so3_log, m)?)?;
    m.add_function(wrap_pyfunction!(so3_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(quat_multiply, m)?)?;
    m.add_function(wrap_pyfunction!(quat_conjugate, m)?)?;
    m.add_function(wrap_pyfunction!(quat_inverse, m)?)?;
    m.add_function(wrap_pyfunction!(quat_normalize, m)?)?;
    m.add_function(wrap_pyfunction!(quat_rotate, m)?)?;
    m.add_function(wrap_pyfunction!(quat_product_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(quat_omega_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(quat_exp, m)?)?;
    m.add_function(wrap_pyfunction!(quat_log, m)?)?;
    m.add_function(wrap_pyfunction!(euler_to_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(euler_from_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(euler_rate_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(euler_rate_matrix_inv, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_integrate, m)?)?;
    m.add_function(wrap_pyfunction!(strapdown_integrate, m)?)?;
    m.add_function(wrap_pyfunction!(strapdown_propagate, m)?)?;
    m.add_class::<preint_glue::PyPreintegrator>()?;
    m.add_class::<filters_glue::PyAttitudeFilter>()?;
    m.add_function(wrap_pyfunction!(preint_glue::preint_windows, m)?)?;
    m.add_function(wrap_pyfunction!(preint_glue::preint_windows_record, m)?)?;
    m.add(
        "PREINT_SCHEMES",
        <imukit::preint::Scheme as imukit::names::Named>::names(),
    )?;
    m.add(
        "PREINT_SCHEME_ALIASES",
        preint_glue::scheme_aliases()
            .into_iter()
            .collect::<std::collections::HashMap<_, _>>(),
    )?;
    m.add(
        "DEFAULT_SATURATION_NOISE_FACTOR",
        imukit::preint::DEFAULT_SATURATION_NOISE_FACTOR,
    )?;
    m.add_function(wrap_pyfunction!(allan_glue::allan_variance, m)?)?;
    m.add_function(wrap_pyfunction!(sim_glue::sim_motion, m)?)?;
    m.add_function(wrap_pyfunction!(sim_glue::sim_measure, m)?)?;
    m.add_function(wrap_pyfunction!(threads::set_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(threads::get_num_threads, m)?)?;
    let [gx, gy, gz] = imukit::imu::GRAVITY;
    m.add("GRAVITY", (gx, gy, gz))?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
