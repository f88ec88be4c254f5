//! # imukit
//!
//! IMU kinematics in Rust: quaternion and SO(3) math, Euler-angle rate maps, and (in later
//! modules) integration, preintegration and filters. No Python and no I/O here; the Python
//! bindings live in the `imukit-py` crate.
//!
//! Conventions (the full table with worked numbers is `docs/conventions.md`): Hamilton
//! quaternions, active rotations `R_wb` mapping body to world, body angular velocity
//! right-multiplied (`Ṙ = R [ω]×`), right (local) perturbations `R Exp(δ)`, intrinsic ZYX Euler
//! angles, SI units.
//!
//! ```
//! use imukit::{so3, quat};
//! use nalgebra::Vector3;
//!
//! // A quarter turn about z maps the body x axis onto the world y axis.
//! let phi = Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2);
//! let r = so3::exp(&phi);
//! assert!((r * Vector3::x() - Vector3::y()).norm() < 1e-15);
//! // Log inverts Exp, and the quaternion route agrees with the matrix route.
//! assert!((so3::log(&r) - phi).norm() < 1e-15);
//! assert!((quat::exp(&phi) * Vector3::x() - Vector3::y()).norm() < 1e-15);
//! ```

pub mod adjoint;
pub mod allan;
pub mod attitude;
pub mod earth;
pub mod ellipsoid;
pub mod ellipsoid_errors;
mod error;
pub mod euler;
pub mod extrinsics;
pub mod ffi;
pub mod filters;
pub mod imu;
pub mod interp;
pub mod lie;
mod mat3;
pub mod names;
pub mod pages;
pub mod preint;
pub mod propagate;
pub mod quat;
pub mod sim;
pub mod simd;
pub mod so3;
pub mod strapdown;
pub mod text;
pub mod time;

pub use error::{try_vec, Cancel, Error, Result};
