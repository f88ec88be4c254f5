//! PyO3 glue for imukit: conversion only. Each binding copies its arrays, converts its values
//! by field name and its enums by name (module `convert`), releases the GIL, calls the core, and maps
//! a core error to the `imukit` exception hierarchy with its argument and index as fields
//! (module `errors`). No value checks, no math, no defaults: those live in the core (`crates/imukit`).
//! The public Python API (shapes, broadcasting, scipy interop) lives in `python/imukit`; nothing
//! here is meant to be called directly.

mod adjoint_glue;
mod allan_glue;
mod attitude_glue;
mod convert;
mod earth_glue;
mod errors;
mod filters_glue;
mod math_glue;
mod preint_glue;
mod robust_glue;
mod sim_glue;
mod strapdown_glue;
mod text_glue;
mod threads;

// The helpers the domain files import from the crate root.
pub(crate) use convert::{contiguous, private_copy, state_copy, SampleCopies};
pub(crate) use errors::{class_name, raise, to_py};

use imukit::{attitude, ffi, strapdown};
use pyo3::prelude::*;

/// Compiled core of imukit. Use the `imukit` package, not this module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    use math_glue as g;
    for f in [
        wrap_pyfunction!(g::so3_hat, m)?,
        wrap_pyfunction!(g::so3_vee, m)?,
        wrap_pyfunction!(g::so3_exp, m)?,
        wrap_pyfunction!(g::so3_exp_double_integral, m)?,
        wrap_pyfunction!(g::so3_log, m)?,
        wrap_pyfunction!(g::so3_jacobian, m)?,
        wrap_pyfunction!(g::quat_multiply, m)?,
        wrap_pyfunction!(g::quat_conjugate, m)?,
        wrap_pyfunction!(g::quat_inverse, m)?,
        wrap_pyfunction!(g::quat_normalize, m)?,
        wrap_pyfunction!(g::quat_rotate, m)?,
        wrap_pyfunction!(g::quat_product_matrix, m)?,
        wrap_pyfunction!(g::quat_omega_matrix, m)?,
        wrap_pyfunction!(g::quat_exp, m)?,
        wrap_pyfunction!(g::quat_log, m)?,
        wrap_pyfunction!(g::euler_to_matrix, m)?,
        wrap_pyfunction!(g::euler_from_matrix, m)?,
        wrap_pyfunction!(g::euler_rate_matrix, m)?,
        wrap_pyfunction!(g::euler_rate_matrix_inv, m)?,
        wrap_pyfunction!(attitude_glue::attitude_integrate, m)?,
        wrap_pyfunction!(strapdown_glue::strapdown_integrate, m)?,
        wrap_pyfunction!(strapdown_glue::body_readings, m)?,
        wrap_pyfunction!(strapdown_glue::strapdown_propagate, m)?,
        wrap_pyfunction!(adjoint_glue::preint_adjoint, m)?,
        wrap_pyfunction!(threads::set_num_threads, m)?,
        wrap_pyfunction!(threads::after_fork_in_child, m)?,
        wrap_pyfunction!(threads::get_num_threads, m)?,
        wrap_pyfunction!(threads::simd_path, m)?,
    ] {
        m.add_function(f)?;
    }
    convert::add_names::<attitude::Scheme>(m, "ATTITUDE_SCHEMES", Some("ATTITUDE_SCHEME_ALIASES"))?;
    convert::add_names::<attitude::Representation>(m, "ATTITUDE_REPRESENTATIONS", None)?;
    m.add("ATTITUDE_DEFAULT_SCHEME", attitude::Options::default().scheme.name())?;
    convert::add_names::<strapdown::Scheme>(m, "STRAPDOWN_SCHEMES", Some("STRAPDOWN_SCHEME_ALIASES"))?;
    m.add("STRAPDOWN_DEFAULT_SCHEME", strapdown::Options::default().scheme.name())?;
    convert::add_names::<ffi::Convention>(m, "QUAT_CONVENTIONS", None)?;
    convert::add_names::<imukit::filters::World>(m, "FILTER_WORLDS", None)?;
    m.add_class::<preint_glue::PyPreintegrator>()?;
    m.add_class::<preint_glue::PyLeverNoise>()?;
    m.add_class::<filters_glue::PyGainRamp>()?;
    m.add_class::<filters_glue::PyAccelLowPass>()?;
    m.add_class::<filters_glue::PyAccelRejection>()?;
    m.add_class::<filters_glue::PyMagRejection>()?;
    m.add_class::<filters_glue::PyRestDetection>()?;
    m.add_class::<filters_glue::PyFilterOptions>()?;
    m.add_class::<filters_glue::PyFilterState>()?;
    m.add_class::<filters_glue::PyMahonyGains>()?;
    m.add_class::<filters_glue::PyMadgwickGains>()?;
    m.add_class::<filters_glue::PyMahonyFilter>()?;
    m.add_class::<filters_glue::PyMadgwickFilter>()?;
    robust_glue::register(m)?;
    m.add_function(wrap_pyfunction!(preint_glue::preint_windows, m)?)?;
    m.add_function(wrap_pyfunction!(preint_glue::lever_noise, m)?)?;
    m.add_function(wrap_pyfunction!(preint_glue::preint_windows_record, m)?)?;
    convert::add_names::<imukit::preint::Scheme>(m, "PREINT_SCHEMES", Some("PREINT_SCHEME_ALIASES"))?;
    m.add("PREINT_DEFAULT_SCHEME", imukit::preint::Scheme::default().name())?;
    m.add(
        "DEFAULT_SATURATION_NOISE_FACTOR",
        imukit::preint::DEFAULT_SATURATION_NOISE_FACTOR,
    )?;
    m.add_function(wrap_pyfunction!(allan_glue::allan_variance, m)?)?;
    m.add_function(wrap_pyfunction!(sim_glue::sim_motion, m)?)?;
    m.add_function(wrap_pyfunction!(sim_glue::sim_rotating_world, m)?)?;
    m.add_function(wrap_pyfunction!(sim_glue::sim_sensor_pose, m)?)?;
    m.add_function(wrap_pyfunction!(earth_glue::local_level, m)?)?;
    m.add_function(wrap_pyfunction!(earth_glue::ellipsoid_integrate, m)?)?;
    m.add_function(wrap_pyfunction!(earth_glue::sim_ellipsoid, m)?)?;
    convert::add_names::<imukit::earth::Axes>(m, "LOCAL_LEVEL_AXES", None)?;
    m.add_function(wrap_pyfunction!(sim_glue::sim_measure, m)?)?;
    m.add_function(wrap_pyfunction!(sim_glue::sim_sensor_default, m)?)?;
    m.add_function(wrap_pyfunction!(text_glue::text_parse_block, m)?)?;
    let [gx, gy, gz] = imukit::imu::GRAVITY;
    m.add("GRAVITY", (gx, gy, gz))?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
